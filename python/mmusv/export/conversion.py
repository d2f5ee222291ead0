"""``convert``: recordings → a dataset folder in one of the formats of :data:`~mmusv.export.common.TARGETS`,
optionally split by sequence.

One job for every format: it reads and validates every recording (:mod:`mmusv.recording.info`,
:mod:`mmusv.recording.stream`), splits them by sequence (:mod:`mmusv.export.splits`), selects the complete frames,
reports progress and skipped frames, and hands each complete frame to the format's
:class:`~mmusv.export.writer.DatasetWriter`. Output root ``out_dir``:
``{train,validate,test}/<scenario>/...`` (or ``<scenario>/...`` with ``splits=None``) for the formats with one
folder per recording (OPV2V, KITTI, MaSTr; ROS 2 bags, never split), the format's own layout for the others (COCO,
YOLO, SemanticKITTI, MOT, KITTI tracking: see their modules), plus ``conversion.yaml`` (options, sources, split of
every recording, frames converted and skipped; no times or absolute paths, so two conversions of the same input are
byte-identical). ``conversion.yaml`` is written first with ``status: in_progress`` and rewritten at the end
(``complete``; ``failed`` with the error, or ``interrupted``, when it stops halfway in a new folder); an
existing ``out_dir`` is replaced only with ``overwrite`` and only when it is empty or holds a previous conversion
(its ``conversion.yaml``), and then only once the new one is complete (written beside it, then swapped in).

Its parts: the checks made before anything is written (:mod:`~mmusv.export.convert_checks`), the output folder
(:mod:`~mmusv.export.convert_output`) and the report (:mod:`~mmusv.export.convert_report`).
"""

from __future__ import annotations

import contextlib
import shutil
import time
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from pathlib import Path

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.export.common import (
    DEFAULT_EXTRAS,
    TARGETS,
    Options,
    Sink,
    dump_yaml,
    naming,
    parse_box,
    parse_extras,
)
from mmusv.export.convert_checks import (
    DEFAULT_RANGE_M,
    agent_selection,
    as_list,
    box_filter,
    box_options,
    check_agents,
    contrast_filter,
    extras_option,
    frame_selection,
    kitti_type,
    outside_frames,
    oxts_origin_of,
    target_options,
)
from mmusv.export.convert_output import contents, prepare_out, reported, staged
from mmusv.export.convert_report import REPORT_NAME, ConvertReport, RecordingReport
from mmusv.export.convert_report import load_report as load_report  # importable from here as before
from mmusv.export.splits import DEFAULT_RATIOS, SPLIT_NAMES, assign_splits, parse_ratios
from mmusv.export.writer import DatasetWriter
from mmusv.held_signals import is_stop, raise_noted_stop, stops_unwrapped
from mmusv.recording.info import RecordingInfo, read_info
from mmusv.recording.stream import FrameStream, held_text
from mmusv.text import counted, given, named

__all__ = ["REPORT_NAME", "ConvertReport", "RecordingReport", "convert", "writer_class"]

_contrast_filter = contrast_filter
""":func:`~mmusv.export.convert_checks.contrast_filter` by its name here before the split (tests import it)."""


_BOX_FORMATS = ("coco", "yolo", "mot")
"""The formats whose 2D boxes the options ``box``, ``min_box_px``, ``max_occlusion`` and ``min_contrast`` choose
(recorded in ``conversion.yaml``'s ``options``)."""


def _clear(out: Path, *, remove: bool) -> None:
    """Empties ``out`` of what a conversion that converted nothing wrote there (it was empty, or emptied for it),
    and removes it when the conversion created it."""
    for child in sorted(out.iterdir()):
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child, ignore_errors=True)
        else:
            child.unlink(missing_ok=True)
    if remove:
        with contextlib.suppress(OSError):
            out.rmdir()


@contextlib.contextmanager
def _write_failures(out: Path) -> Iterator[None]:
    """Names a file in the ``OSError`` of a write of the conversion that names none (a full disk): the write to an
    open file names no file (only opening one does), so the command line said only "No space left on device". The
    writes through :class:`~mmusv.export.common.Sink` name their file; the others (a library's: rosbags') are named
    by the output folder ``out``."""
    try:
        yield
    except OSError as exc:
        raise naming(exc, out) from exc


def _why_nothing(reports: list[RecordingReport]) -> str:
    """Why the recordings of a conversion gave no complete frame, for its error (empty when none says): each one's
    skipped frames with their reasons (damage, a cut, missing topics), else its notes; the error said only "no complete
    frame in X", and these went with the report that is not written then."""
    parts = []
    for r in reports:
        why = [f"{held_text(range(s['frames'][0], s['frames'][1] + 1))} {s['reason']}" for s in r.skipped]
        why = why or [n for n in r.notes if not n.startswith("no complete frame")]
        if why:
            parts.append(f"{r.path}: {'; '.join(dict.fromkeys(why))}")
    return f" ({'; '.join(parts)})" if parts else ""


def _beyond(frames: tuple[int, int | None] | None, first: int, end: int) -> str | None:
    """What of ``frames`` (``[start, stop)``, the ``--frames`` asked for) lies outside the acquisition indices
    ``first..end - 1`` a recording's run set out to write, said as a note (``None``: nothing): a range that reaches
    past the recording would otherwise convert fewer frames than asked without a word."""
    if frames is None or end <= first:
        return None
    start, stop = frames
    before = (start, first if stop is None else min(stop, first))
    after = (max(start, end), end if stop is None else stop)
    out = [f"{a}" if b == a + 1 else f"{a}..{b - 1}" for a, b in (before, after) if a < b]
    if not out:
        return None
    asked = f"{start}:{'' if stop is None else stop}"
    return (
        f"frames {asked} reach past the recording, which holds frames {first}..{end - 1}: {' and '.join(out)} not in it"
    )


def writer_class(to: str) -> type[DatasetWriter]:
    """The writer of format ``to`` (one of :data:`~mmusv.export.common.TARGETS`)."""
    if to == "opv2v":
        from mmusv.export.opv2v import Opv2vWriter

        return Opv2vWriter
    if to == "kitti":
        from mmusv.export.kitti import KittiWriter

        return KittiWriter
    if to == "ros2":
        from mmusv.export.ros2 import Ros2Writer

        return Ros2Writer
    if to == "coco":
        from mmusv.export.coco import CocoWriter

        return CocoWriter
    if to == "yolo":
        from mmusv.export.yolo import YoloWriter

        return YoloWriter
    if to == "mastr":
        from mmusv.export.mastr import MastrWriter

        return MastrWriter
    if to == "semantickitti":
        from mmusv.export.semantickitti import SemanticKittiWriter

        return SemanticKittiWriter
    if to == "mot":
        from mmusv.export.mot import MotWriter

        return MotWriter
    if to == "kitti_tracking":
        from mmusv.export.kitti_tracking import KittiTrackingWriter

        return KittiTrackingWriter
    raise ConfigError(f"unknown target {to!r}; allowed: {', '.join(TARGETS)}")


def _ranges(frames: list[int]) -> list[tuple[int, int]]:
    out: list[tuple[int, int]] = []
    for k in sorted(frames):
        if out and k == out[-1][1] + 1:
            out[-1] = (out[-1][0], k)
        else:
            out.append((k, k))
    return out


def _folders(infos: list[RecordingInfo], from_folders: Collection[Path] = ()) -> list[str]:
    """Scenario folder names: the scenario name, or ``<name>_<hash8>`` when names repeat. ``from_folders``: the
    recordings that a batch folder given listed (the others were given one by one)."""
    names = [i.scenario_name for i in infos]
    keys = [f"{i.scenario_name}_{i.config_hash[:8]}" for i in infos]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        same = [i.path for i, k in zip(infos, keys, strict=True) if k in dup]
        # the folder's hint only where a batch folder listed one of them: given as files, there is no folder
        how = (
            "pass the recordings to convert instead of their folder, leaving one of these out"
            if any(p in from_folders for p in same)
            else "leave one of these out"
        )
        raise ConfigError(
            f"recordings {', '.join(map(str, same))} are runs of the same scenario configuration (the same scenario "
            "and seed give the same data: converted together, every frame would be in the dataset twice, or in two "
            f"of its splits); give each only once: {how}"
        )
    return [n if names.count(n) == 1 else k for n, k in zip(names, keys, strict=True)]


def _frames_to_read(info: RecordingInfo, options: Options) -> int:
    """How many frames of ``info`` the conversion reads (for its progress): those written, in ``options.frames``."""
    first = int(info.run.get("first_frame", 0) or 0)
    written = int(info.run.get("frames_written", info.frames_configured) or 0)
    start, stop = options.frames if options.frames is not None else (first, None)
    end = first + written if stop is None else min(first + written, stop)
    return max(0, end - max(first, start))


def convert(
    recordings: str | Path | Iterable[str | Path],
    *,
    to: str = "opv2v",
    out_dir: str | Path,
    splits: Sequence[float] | str | None = DEFAULT_RATIOS,
    seed: int = 0,
    eval_range_m: float = DEFAULT_RANGE_M,
    include_usvs: bool = False,
    extras: Iterable[str] | str | None = DEFAULT_EXTRAS,
    min_box_px: float = 0.0,
    max_occlusion: float = 1.0,
    min_contrast: float | None = None,
    box: str = "visible",
    overwrite: bool = False,
    agents: Iterable[str] | str | None = None,
    frames: Sequence[int | None] | str | None = None,
    kitti_class: str | None = None,
    oxts_origin: Sequence[float] | str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ConvertReport:
    """Converts one or many recordings into a dataset folder (see the module docstring).

    Args:
        recordings: ``.mcap`` files written by ``mmusv run`` (also ``.mcap.partial`` or truncated ones: their
            complete frames are converted, the rest reported as skipped), parts manifests of recordings split
            into frame ranges (read as one sequence), or folders holding a ``dataset.json`` (their complete
            recordings).
        to: one of :data:`~mmusv.export.common.TARGETS`: ``"opv2v"``, ``"kitti"``, ``"ros2"`` (a rosbag2 folder
            per recording), ``"coco"``, ``"yolo"``, ``"mastr"``, ``"semantickitti"``, ``"mot"`` (MOTChallenge
            sequences), ``"kitti_tracking"`` (KITTI tracking sequences; ``docs/exports.md``).
        splits: ``(train, validate, test)`` fractions (split per recording, shuffled with ``seed``, a whole number
            >= 0) or ``None``
            for one folder of scenarios. ROS 2 bags are never split: with ``to="ros2"`` only the default or
            ``None`` is accepted.
        eval_range_m: OPV2V, KITTI and KITTI tracking: targets are vessels whose box centre lies within
            ``eval_range_m`` of the agent's LiDAR in bird's-eye view (:func:`mmusv.boxes3d.in_target_range`). The
            other formats refuse a value other than the default (they label every vessel they hold).
        include_usvs: OPV2V, KITTI and KITTI tracking: list the other USVs as targets too (default: only
            non-instrumented vessels); the other formats refuse ``True``.
        extras: any of ``depth``, ``semantic``, ``instance``, ``radar``, ``top_view`` (OPV2V and KITTI: extra
            files stock loaders skip).
        min_box_px: COCO, YOLO and MOT (and ROS 2, see ``max_occlusion``): leave out 2D boxes whose shorter side is
            under this many pixels. This option, ``max_occlusion``, ``min_contrast`` and ``box`` other than their
            defaults are refused for the other formats, which would ignore them.
        max_occlusion: COCO, YOLO and MOT: leave out 2D boxes hidden by more than this fraction (0..1); ROS 2 too
            (and ``min_box_px``), from its ``Detection2DArray`` messages, on the recorded box and occlusion.
        min_contrast: COCO, YOLO and MOT: leave out 2D boxes whose apparent contrast in the recorded RGB image (the
            vessel's Weber contrast against the background around it, :mod:`mmusv.export.contrast`; 0.05 is the
            WMO's visibility threshold) is under this; ``None`` (the default) keeps every box. It needs the cameras'
            instance images (also with ``box="projected"``).
        box: COCO, YOLO and MOT: the 2D box written, ``"visible"`` (the default: the tight box of the vessel's
            pixels in the instance image, COCO's convention for ``bbox``; YOLO and MOT then need cameras recording
            instance images)
            or ``"projected"`` (the recording's box: the vessel's projected 3D box clipped to the image, reaching
            down to the keel and over what hides it). ``min_box_px`` applies to the box written. Other formats
            keep their boxes (KITTI and ROS 2: the recorded box).
        overwrite: replace a previous conversion in ``out_dir`` (``include_usvs`` and ``overwrite`` are ``bool``).
        agents: the agents (USV ids, a list or ``"usv_1,usv_2"``) to convert; every recording must hold one of
            them. ``None``: all.
        frames: the acquisition indices to convert, ``(start, stop)`` or ``"start:stop"`` (``stop`` excluded; left
            out or ``None``: to the end). The others are neither converted nor reported missing. ``None``: all.
        kitti_class: ``to="kitti_tracking"`` only: the type its labels give every target, one word (``"Car"``: what
            stock TrackEval's ``Kitti2DBox`` and the KITTI devkit score); ``None`` (the default): each target's class
            name (``Vessel``, ``Usv``).
        oxts_origin: ``to="kitti_tracking"`` only: the geodetic point ``(lat, lon)`` (degrees, ``|lat| <= 85``,
            ``|lon| <= 180``; or ``"LAT,LON"``) of the world origin in its ``oxts`` files; ``None`` (the default):
            :data:`mmusv.export.kitti_oxts.DEFAULT_ORIGIN`.
        progress: called with (frames done, frames expected) after every frame (a callable of two arguments).

    Raises:
        ConfigError: bad options. IoError: missing, unreadable or non-MCAP recordings; an existing output.
    """
    t0 = time.perf_counter()
    cls = writer_class(to)
    rng = arguments.real(eval_range_m, name=named("eval_range_m"), unit="metres", above=0.0)
    seed = arguments.whole(seed, name=named("seed"), lo=0)
    include_usvs = arguments.flag(include_usvs, name="include_usvs")
    overwrite = arguments.flag(overwrite, name="overwrite")
    progress = arguments.callback(progress, name="progress", nargs=2)
    out = arguments.path(out_dir, name="out_dir")
    ratios = None if splits is None else parse_ratios(splits, name="splits")
    if not cls.splits and ratios is not None:
        if ratios != parse_ratios(DEFAULT_RATIOS):
            raise ConfigError(
                f"{given('splits', splits)}: {given('to', to)} writes one folder per recording and is never split"
            )
        ratios = None
    box_px, max_occ = box_filter(min_box_px, max_occlusion)
    min_c = contrast_filter(min_contrast)
    box = parse_box(box)
    box_options(to, min_box_px=box_px, max_occlusion=max_occ, min_contrast=min_c, box=box)
    target_options(to, eval_range_m=rng, include_usvs=include_usvs)
    extras_given = parse_extras(extras)
    extras_option(to, extras_given)
    kind = kitti_type(kitti_class, to)
    origin = oxts_origin_of(oxts_origin, to)
    options = Options(
        to=to,
        eval_range_m=rng,
        include_usvs=include_usvs,
        extras=extras_given,
        min_box_px=box_px,
        max_occlusion=max_occ,
        min_contrast=min_c,
        box=box,
        agents=agent_selection(agents),
        frames=frame_selection(frames),
        kitti_class=kind,
        oxts_origin=origin,
    )
    cls = cls.for_options(options)
    from_folders: set[Path] = set()
    paths = as_list(recordings, from_folders=from_folders)
    infos = [read_info(p) for p in paths]  # validates every input before anything is written
    for i in infos:
        cls.check(i)
    if options.agents is not None:
        check_agents(cls, infos, options.agents)
    outside = outside_frames(infos, options.frames)
    folders = _folders(infos, from_folders)
    split_of: dict[str, str | None] = dict.fromkeys(folders)
    if ratios is not None:
        split_of = dict(assign_splits(folders, ratios=ratios, seed=seed))
    created = not out.exists()
    work, lock = prepare_out(out, overwrite, [Path(i.path) for i in infos])
    nothing = False
    try:
        reports = [
            RecordingReport(path=i.path, scenario=i.scenario_name, folder=f, split=split_of[f])
            for i, f in zip(infos, folders, strict=True)
        ]
        header = {
            "format": to,
            "format_version": cls.format_version,
            "options": {
                "eval_range_m": rng,
                "include_usvs": options.include_usvs,
                "extras": list(options.extras),
                **({"min_box_px": box_px, "max_occlusion": max_occ, "box": box} if to in _BOX_FORMATS else {}),
                **({"min_box_px": box_px, "max_occlusion": max_occ} if to == "ros2" else {}),
                **({"min_contrast": min_c} if to in _BOX_FORMATS and min_c is not None else {}),
                "splits": None
                if ratios is None
                else dict(zip(SPLIT_NAMES, [round(r, 9) for r in ratios], strict=True)),
                "seed": seed,
                **({"agents": list(options.agents)} if options.agents is not None else {}),
                **({"frames": list(options.frames)} if options.frames is not None else {}),
                **({"kitti_class": kind} if kind is not None else {}),
                **({"oxts_origin": list(origin)} if origin is not None else {}),
            },
        }
        # an error a library made of a stop's KeyboardInterrupt leaves as the stop (held_signals): conversion.yaml
        # says interrupted, as for a plain Ctrl-C, not failed with the library's error
        with staged(work, out), reported(work / REPORT_NAME, header), _write_failures(out), stops_unwrapped():
            sink = Sink()
            shared = cls.start(work, options, sink)
            report = ConvertReport(out_dir=out, target=to, recordings=reports)
            expected = sum(_frames_to_read(i, options) for i in infos)
            done = 0
            order = sorted(
                range(len(infos)),
                key=lambda j: (SPLIT_NAMES.index(reports[j].split) if reports[j].split else 0, folders[j]),
            )
            for j in order:
                info, rep = infos[j], reports[j]
                if j in outside:  # none of its frames is in --frames (another recording's are)
                    rep.status = info.run.get("status", "unfinished (no run metadata)")
                    rep.notes.append(f"{outside[j]}: nothing converted")
                    continue
                folder = work / rep.split / rep.folder if rep.split else work / rep.folder
                if cls.owns_folder:
                    sink.mkdir(folder)
                writer = cls(info, folder, options, sink, split=rep.split, shared=shared)
                try:
                    wanted = writer.topic_filter()
                    stream = FrameStream(info, wanted.__contains__, frames=options.frames)
                    converted: set[int] = set()
                    incomplete: dict[int, str] = {}
                    for fr in stream:
                        raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
                        missing = writer.missing(fr)
                        if not options.wants_frame(fr.index):
                            pass  # outside --frames: neither converted nor missing
                        elif fr.index in converted:
                            # a frame recorded again: its first complete copy stands (handed to the writer again, COCO
                            # listed the image twice, SemanticKITTI added a scan and a bag held every message twice)
                            pass
                        elif fr.world is None or missing or not writer.agents:
                            why = (
                                writer.no_agent_reason
                                if not writer.agents
                                else f"incomplete: missing {', '.join(missing[:4])}"
                                + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
                            )
                            incomplete.setdefault(fr.index, why)
                        else:
                            writer.write_frame(fr)
                            converted.add(fr.index)
                            report.agent_frames += len(writer.agents)
                        done += 1
                        if progress is not None:
                            progress(done, max(expected, done))
                    rep.status = stream.run.get("status", "unfinished (no run metadata)")
                    for k, why in incomplete.items():
                        if k not in converted:  # an incomplete copy of a frame converted from another copy is no loss
                            rep.skipped.append({"frames": [k, k], "reason": why})
                    seen = converted | set(incomplete)
                    # the frames the run set out to write (its run metadata, or for one that did not finish its
                    # manifest's): --frames N cuts a run short on purpose, those after N are not missing; one part of a
                    # split recording given alone starts at its first frame
                    span = stream.set_out()
                    first, configured = span.start, len(span)
                    absent = [k for k in span if k not in seen and options.wants_frame(k)]
                    if not stream.truncated:  # whole bytes: a frame the reader left out is there, but incomplete
                        hollow: dict[int, str] = {}
                        for k, why in stream.incomplete:
                            hollow.setdefault(k, why)
                        rep.skipped += [
                            {"frames": [k, k], "reason": f"in the recording but incomplete: {hollow[k]}"}
                            for k in absent
                            if k in hollow
                        ]
                        absent = [k for k in absent if k not in hollow]
                    if absent:
                        written = stream.run.get("frames_written")
                        # every frame written, yet some not read: lost to damage or a cut (it said "not in the recording
                        # (run complete: 6 of 6 frames written)")
                        lost = written is not None and str(written).isdigit() and int(written) >= configured
                        why = (
                            f"{'lost from' if lost else 'not in'} the recording (run {rep.status}: {written} of "
                            f"{counted(configured, 'frame')} written)"
                            if written is not None
                            else "not in the recording (the run did not finish; it set out to write "
                            f"{counted(configured, 'frame')})"
                        )
                        if stream.truncated:
                            why += "; " + stream.truncated
                        rep.skipped += [{"frames": [a, b], "reason": why} for a, b in _ranges(absent)]
                    elif stream.truncated:
                        rep.notes.append(stream.truncated)
                    beyond = _beyond(options.frames, first, first + configured)
                    if beyond:
                        rep.notes.append(beyond)
                    if stream.out_of_order:
                        again = sorted(set(stream.out_of_order))
                        rep.notes.append(f"frames {again} appear more than once; the first complete copy was converted")
                    rep.skipped.sort(key=lambda s: s["frames"][0])
                    writer.finish(sorted(converted), rep.skipped)
                except BaseException as exc:  # a stop, or an error: a file the writer holds open is closed
                    with contextlib.suppress(Exception):
                        writer.stop(interrupted=is_stop(exc))  # (an error a library made of a stop: the stop)
                    raise
                rep.notes += writer.notes
                rep.frames_converted = len(converted)
                if converted:
                    rep.first_frame, rep.last_frame = min(converted), max(converted)
                else:
                    rep.notes.append("no complete frame: nothing written for this recording")
                    if cls.owns_folder:
                        shutil.rmtree(folder, ignore_errors=True)
            if report.frames == 0:
                # nothing to show for it: --overwrite keeps the previous conversion (the staging folder goes), a new
                # folder is left as it was (a report saying "complete" over no frame looked like a dataset)
                nothing = True
                raise IoError(
                    f"nothing converted: no complete frame in {', '.join(str(r.path) for r in reports)}; "
                    + (f"{out} keeps its previous conversion" if work != out else "nothing written")
                    + _why_nothing(reports)
                )
            cls.finish_all(shared, work, sink)
            doc = {
                **header,
                "status": "complete",
                "frames_converted": report.frames,
                "agent_frames": report.agent_frames,
                "recordings": [r.as_dict() for r in sorted(reports, key=lambda r: (r.split or "", r.folder))],
                "contents": contents(work),
            }
            data = dump_yaml(doc)
            (work / REPORT_NAME).write_bytes(data)
            report.files = sink.files + 1
            report.bytes = sink.bytes + len(data)
    except IoError:
        if nothing and work == out:
            _clear(out, remove=created)
        raise
    except OSError:
        if created and work == out:  # a new folder where not even the report could be written (a full disk)
            with contextlib.suppress(OSError):
                out.rmdir()  # only when empty
        raise
    finally:
        lock.release()
    report.seconds = time.perf_counter() - t0
    return report
