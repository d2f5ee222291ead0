"""``convert``: recordings → a dataset folder in one of the formats of :data:`~mmusv.export.common.TARGETS`,
optionally split by sequence.

One job for every format: it reads and validates every recording (:mod:`mmusv.recording.info`,
:mod:`mmusv.recording.stream`), splits them by sequence (:mod:`mmusv.export.splits`), selects the complete frames,
reports progress and skipped frames, and hands each complete frame to the format's
:class:`~mmusv.export.writer.DatasetWriter`. Output root ``out_dir``:
``{train,validate,test}/<scenario>/...`` (or ``<scenario>/...`` with ``splits=None``) for the formats with one
folder per recording (OPV2V, KITTI, MaSTr; ROS 2 bags, never split), the format's own layout for the others (COCO,
YOLO, SemanticKITTI: see their modules), plus ``conversion.yaml`` (options, sources, split of every recording,
frames converted and skipped; no times or absolute paths, so two conversions of the same input are
byte-identical). ``conversion.yaml`` is written first with ``status: in_progress`` and rewritten at the end; an
existing ``out_dir`` is replaced only with ``overwrite`` and only when it is empty or holds a previous conversion
(its ``conversion.yaml``), and then only once the new one is complete (written beside it, then swapped in).
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.export.common import DEFAULT_EXTRAS, TARGETS, Options, Sink, dump_yaml, parse_box, parse_extras
from mmusv.export.contrast import MAX_CONTRAST
from mmusv.export.splits import DEFAULT_RATIOS, SPLIT_NAMES, assign_splits, parse_ratios
from mmusv.export.writer import DatasetWriter
from mmusv.recording.guard import FolderLock
from mmusv.recording.info import RecordingInfo, read_info
from mmusv.recording.stream import FrameStream

__all__ = ["REPORT_NAME", "ConvertReport", "RecordingReport", "convert", "writer_class"]

REPORT_NAME = "conversion.yaml"


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
    raise ConfigError(f"unknown target {to!r}; allowed: {', '.join(TARGETS)}")


@dataclass
class RecordingReport:
    """One recording's conversion: where it went and which frames were converted or skipped (``skipped``:
    ``{"frames": [first, last], "reason": ...}`` ranges)."""

    path: Path
    scenario: str
    folder: str
    split: str | None
    frames_converted: int = 0
    first_frame: int | None = None
    last_frame: int | None = None
    skipped: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    status: str = ""

    def as_dict(self) -> dict[str, Any]:
        """The recording's entry of ``conversion.yaml``."""
        return {
            "source": self.path.name,
            "scenario": self.scenario,
            "folder": self.folder,
            "split": self.split,
            "run_status": self.status,
            "frames_converted": self.frames_converted,
            "frames": None if self.first_frame is None else [self.first_frame, self.last_frame],
            "skipped": self.skipped,
            "notes": self.notes,
        }


@dataclass
class ConvertReport:
    """What a conversion wrote: per recording, totals, seconds (wall) and bytes on disk."""

    out_dir: Path
    target: str
    recordings: list[RecordingReport]
    agent_frames: int = 0
    files: int = 0
    bytes: int = 0
    seconds: float = 0.0

    @property
    def frames(self) -> int:
        """Frames converted (each one for every agent of its recording)."""
        return sum(r.frames_converted for r in self.recordings)

    @property
    def skipped(self) -> list[dict[str, Any]]:
        """Every skipped range, with its recording's file name."""
        return [{"recording": r.path.name, **s} for r in self.recordings for s in r.skipped]

    def lines(self) -> list[str]:
        """A human summary, one line per recording and a total."""
        out = []
        for r in self.recordings:
            where = f"{r.split}/{r.folder}" if r.split else r.folder
            out.append(f"{r.path.name} -> {where}: {r.frames_converted} frames")
            out += [f"  skipped frames {s['frames'][0]}..{s['frames'][1]}: {s['reason']}" for s in r.skipped]
            out += [f"  note: {n}" for n in r.notes]
        out.append(
            f"{self.frames} frames ({self.agent_frames} agent-frames), {self.files} files, {self.bytes / 1e6:.1f} MB "
            f"in {self.seconds:.1f} s -> {self.out_dir}"
        )
        return out


def _as_list(recordings: str | Path | Iterable[str | Path]) -> list[Path]:
    """The recordings given: files (``.mcap``, parts manifests) as they are, a folder holding a ``dataset.json``
    (a batch run's output) as its complete recordings."""
    from mmusv.batch.index import dataset_recordings, find_index

    if isinstance(recordings, (str, os.PathLike)):
        given = [arguments.path(recordings, name="recordings")]
    elif isinstance(recordings, (bytes, Mapping)) or not isinstance(recordings, Iterable):
        raise ConfigError(
            f"recordings = {arguments.shown(recordings)}: must be a path (str or pathlib.Path) or a list of paths"
        )
    else:
        given = [arguments.path(r, name=f"recordings[{i}]") for i, r in enumerate(recordings)]
    out: list[Path] = []
    for p in given:
        if p.is_dir():
            index = find_index(p)
            if index is None:
                raise IoError(
                    f"{p} is not a file but a folder without a dataset.json; give recordings (.mcap, .parts.json) "
                    "or a batch output folder"
                )
            found = dataset_recordings(index)
            if not found:
                raise ConfigError(f"{index} lists no complete recording")
            out.extend(found)
        else:
            out.append(p)
    if not out:
        raise ConfigError("no recordings given")
    return out


def _prepare_out(out: Path, overwrite: bool, inputs: list[Path]) -> tuple[Path, FolderLock]:
    """Checks ``out``, locks it (:class:`~mmusv.recording.guard.FolderLock`: a second conversion into it, from
    another process or thread, is refused instead of mixing its files with this one's) and returns the folder to
    write into, with the lock to release when done: ``out`` itself (created), or, when ``overwrite`` replaces a
    previous conversion there, a staging folder beside it that :func:`_staged` swaps in once the new conversion is
    complete, so that one failing halfway (a full disk) leaves the previous one as it was. Where ``out`` cannot be
    swapped (it is, or holds, the working folder, e.g. ``-o .``; it is a link; its parent takes no new folder) the
    previous conversion is emptied in place instead."""
    if out.exists() and not out.is_dir():
        raise IoError(f"output {out} exists and is not a folder")
    # The output folder is replaced on --overwrite: it may not hold a recording being converted.
    home = out.resolve()
    for p in inputs:
        where = p.resolve()
        if where == home or home in where.parents:
            raise IoError(
                f"output folder {out} holds {p}, which is being converted; write the conversion to another folder"
            )
    lock = FolderLock.create(out, what="mmusv convert")
    try:
        return _prepare_locked(out, home, overwrite), lock
    except BaseException:
        lock.release()
        raise


def _prepare_locked(out: Path, home: Path, overwrite: bool) -> Path:
    """:func:`_prepare_out` once ``out`` exists and is locked."""
    if any(out.iterdir()):
        if not overwrite:
            raise IoError(
                f"output folder {out} already exists and is not empty; pass overwrite=True (--overwrite) to replace it"
            )
        if not (out / REPORT_NAME).is_file():
            raise IoError(
                f"output folder {out} is not empty and holds no {REPORT_NAME} from a previous conversion; "
                "refusing to delete it, choose another folder"
            )
        here = Path.cwd().resolve()
        if not out.is_symlink() and home != here and home not in here.parents:
            _remove_stale_stages(out)
            stage = out.parent / f".{out.name}.converting-{os.getpid()}"
            try:
                if stage.exists():
                    shutil.rmtree(stage)
                stage.mkdir()
                return stage
            except OSError:
                pass  # the parent takes no new folder: replaced in place
        for child in sorted(out.iterdir()):
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
    return out


def _remove_stale_stages(out: Path) -> None:
    """Removes the staging and replaced folders beside ``out`` left by conversions that were killed (their process
    no longer runs): ``.<name>.converting-<pid>`` and ``.<name>.replaced-<pid>``."""
    for kind in ("converting", "replaced"):
        for left in out.parent.glob(f".{out.name}.{kind}-*"):
            pid = left.name.rpartition("-")[2]
            if not pid.isdigit() or not left.is_dir() or left.is_symlink():
                continue
            try:
                os.kill(int(pid), 0)
            except ProcessLookupError:
                shutil.rmtree(left, ignore_errors=True)
            except (PermissionError, OverflowError, ValueError):
                continue


@contextlib.contextmanager
def _staged(work: Path, out: Path) -> Iterator[None]:
    """Around a conversion written into ``work`` (:func:`_prepare_out`): when that is a staging folder, swaps it in
    for ``out`` on success (the previous conversion is removed only then) and removes it on failure (the previous
    conversion stays)."""
    if work == out:
        yield
        return
    try:
        yield
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    old = out.parent / f".{out.name}.replaced-{os.getpid()}"
    try:
        os.replace(out, old)
        try:
            os.replace(work, out)
        except OSError:
            os.replace(old, out)
            raise
    except OSError as exc:
        shutil.rmtree(work, ignore_errors=True)
        raise IoError(f"cannot replace {out} with the new conversion: {exc.strerror or exc}") from None
    shutil.rmtree(old, ignore_errors=True)


def _ranges(frames: list[int]) -> list[tuple[int, int]]:
    out: list[tuple[int, int]] = []
    for k in sorted(frames):
        if out and k == out[-1][1] + 1:
            out[-1] = (out[-1][0], k)
        else:
            out.append((k, k))
    return out


def _folders(infos: list[RecordingInfo]) -> list[str]:
    """Scenario folder names: the scenario name, or ``<name>_<hash8>`` when names repeat."""
    names = [i.scenario_name for i in infos]
    keys = [f"{i.scenario_name}_{i.config_hash[:8]}" for i in infos]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        a = [str(i.path) for i, k in zip(infos, keys, strict=True) if k in dup]
        raise ConfigError(f"recordings {', '.join(a)} are runs of the same scenario configuration; give each only once")
    return [n if names.count(n) == 1 else k for n, k in zip(names, keys, strict=True)]


def _box_filter(min_box_px: Any, max_occlusion: Any) -> tuple[float, float]:
    px = arguments.real(min_box_px, name="min_box_px", unit="pixels", finite=False)
    occ = arguments.real(max_occlusion, name="max_occlusion", finite=False)
    if not (math.isfinite(px) and px >= 0):
        raise ConfigError(f"min_box_px = {min_box_px!r}: must be a finite number of pixels >= 0")
    if not (math.isfinite(occ) and 0 <= occ <= 1):
        raise ConfigError(f"max_occlusion = {max_occlusion!r}: must be a fraction in [0, 1]")
    return px, occ


def _contrast_filter(min_contrast: Any) -> float | None:
    """``min_contrast`` as a float in ``[0, MAX_CONTRAST]``, or ``None``; :class:`~mmusv.errors.ConfigError` naming it
    otherwise."""
    if min_contrast is None:
        return None
    allowed = (
        f"must be a Weber contrast >= 0 and <= {MAX_CONTRAST:.1f} (the largest an 8-bit image holds; 0.05 is the "
        "WMO's visibility threshold), or None to keep every box"
    )
    c = arguments.real(min_contrast, name="min_contrast", finite=False)
    if not (math.isfinite(c) and 0 <= c <= MAX_CONTRAST):
        raise ConfigError(f"min_contrast = {arguments.shown(min_contrast)}: {allowed}")
    return c


def _agent_selection(agents: Iterable[str] | str | None) -> tuple[str, ...] | None:
    """``agents`` (a list of ids or ``"usv_1,usv_2"``) as sorted unique ids, or ``None``; an empty selection or an
    id that is not a string is a :class:`~mmusv.errors.ConfigError` naming ``agents``."""
    if agents is None:
        return None
    if isinstance(agents, str):
        items = [a.strip() for a in agents.split(",")]
    elif isinstance(agents, Iterable):
        items = list(agents)
    else:
        raise ConfigError(f"agents = {arguments.shown(agents)}: must be agent ids (a list or 'usv_1,usv_2')")
    if not all(isinstance(a, str) and a for a in items) or not items:
        raise ConfigError(
            f"agents = {arguments.shown(agents)}: must be one or more agent ids (non-empty strings, comma-separated)"
        )
    return tuple(sorted(set(items)))


def _outside_frames(infos: list[RecordingInfo], frames: tuple[int, int | None] | None) -> dict[int, str]:
    """Per recording (index in ``infos``) that holds none of ``frames`` by its run's own account, why; a
    :class:`~mmusv.errors.ConfigError` before anything is written when no recording holds one."""
    if frames is None:
        return {}
    out: dict[int, str] = {}
    for j, info in enumerate(infos):
        try:
            FrameStream(info, lambda _t: False, frames=frames)  # refuses a range outside what the run wrote
        except ConfigError as exc:
            out[j] = str(exc).split(": ", 1)[1]
    if out and len(out) == len(infos):
        stop = "" if frames[1] is None else frames[1]
        raise ConfigError(f"frames = {frames[0]}:{stop}: " + "; ".join(out[j] for j in sorted(out)))
    return out


def _frames_to_read(info: RecordingInfo, options: Options) -> int:
    """How many frames of ``info`` the conversion reads (for its progress): those written, in ``options.frames``."""
    first = int(info.run.get("first_frame", 0) or 0)
    written = int(info.run.get("frames_written", info.frames_configured) or 0)
    start, stop = options.frames if options.frames is not None else (first, None)
    end = first + written if stop is None else min(first + written, stop)
    return max(0, end - max(first, start))


def _frame_selection(frames: Sequence[int | None] | str | None) -> tuple[int, int | None] | None:
    """``frames`` (``(start, stop)`` or ``"start:stop"``, ``stop`` excluded and optional) as ``(start, stop)``, or
    ``None``; :class:`~mmusv.errors.ConfigError` naming ``frames`` unless ``0 <= start < stop``."""
    if frames is None:
        return None
    shown = arguments.shown(frames)
    if isinstance(frames, str):
        head, sep, tail = frames.partition(":")
        if not sep or not head.strip().isdigit() or not (tail.strip().isdigit() or tail.strip() == ""):
            raise ConfigError(f"frames = {shown}: must be START:STOP (acquisition indices, STOP excluded or empty)")
        pair: list[Any] = [int(head), int(tail) if tail.strip() else None]
    elif isinstance(frames, Sequence) and len(frames) == 2:
        pair = [frames[0], frames[1]]
    else:
        raise ConfigError(f"frames = {shown}: must be (start, stop) or 'START:STOP'")
    start = arguments.whole(pair[0], name="frames start", lo=0)
    stop = None if pair[1] is None else arguments.whole(pair[1], name="frames stop", lo=start + 1)
    return start, stop


def _check_agents(cls: type[DatasetWriter], infos: list[RecordingInfo], agents: tuple[str, ...]) -> None:
    """Every selected agent is an agent of some recording, and every recording holds a selected agent the format
    uses (:class:`~mmusv.errors.ConfigError` naming the ids or the recording otherwise)."""
    known = sorted({a.id for i in infos for a in i.agents})
    unknown = [a for a in agents if a not in known]
    if unknown:
        raise ConfigError(
            f"agents: {', '.join(unknown)} {'is not an agent' if len(unknown) == 1 else 'are not agents'} of the "
            f"recordings (their agents: {', '.join(known)})"
        )
    for i in infos:
        if not any(a.id in agents and cls.uses_agent(a) is None for a in i.agents):
            unusable = [f"{a.id} {cls.uses_agent(a)}" for a in i.agents if a.id in agents]
            raise ConfigError(
                f"{i.path}: no selected agent ({', '.join(agents)}) to convert to {cls.format_name()}: "
                + (f"{'; '.join(unusable)}" if unusable else f"its agents are {', '.join(a.id for a in i.agents)}")
            )


def convert(
    recordings: str | Path | Iterable[str | Path],
    *,
    to: str = "opv2v",
    out_dir: str | Path,
    splits: Sequence[float] | str | None = DEFAULT_RATIOS,
    seed: int = 0,
    eval_range_m: float = 200.0,
    include_usvs: bool = False,
    extras: Iterable[str] | str | None = DEFAULT_EXTRAS,
    min_box_px: float = 0.0,
    max_occlusion: float = 1.0,
    min_contrast: float | None = None,
    box: str = "visible",
    overwrite: bool = False,
    agents: Iterable[str] | str | None = None,
    frames: Sequence[int | None] | str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ConvertReport:
    """Converts one or many recordings into a dataset folder (see the module docstring).

    Args:
        recordings: ``.mcap`` files written by ``mmusv run`` (also ``.mcap.partial`` or truncated ones: their
            complete frames are converted, the rest reported as skipped), parts manifests of recordings split
            into frame ranges (read as one sequence), or folders holding a ``dataset.json`` (their complete
            recordings).
        to: one of :data:`~mmusv.export.common.TARGETS`: ``"opv2v"``, ``"kitti"``, ``"ros2"`` (a rosbag2 folder
            per recording), ``"coco"``, ``"yolo"``, ``"mastr"``, ``"semantickitti"`` (``docs/exports.md``).
        splits: ``(train, validate, test)`` fractions (split per recording, shuffled with ``seed``, a whole number
            >= 0) or ``None``
            for one folder of scenarios. ROS 2 bags are never split: with ``to="ros2"`` only the default or
            ``None`` is accepted.
        eval_range_m: targets are vessels whose box centre lies within ``eval_range_m`` of the agent's LiDAR in
            bird's-eye view (:func:`mmusv.annotate.in_target_range`).
        include_usvs: list the other USVs as targets too (default: only non-instrumented vessels).
        extras: any of ``depth``, ``semantic``, ``instance``, ``radar``, ``top_view`` (OPV2V and KITTI: extra
            files stock loaders skip).
        min_box_px: COCO and YOLO: leave out 2D boxes whose shorter side is under this many pixels.
        max_occlusion: COCO and YOLO: leave out 2D boxes hidden by more than this fraction (0..1).
        min_contrast: COCO and YOLO: leave out 2D boxes whose apparent contrast in the recorded RGB image (the
            vessel's Weber contrast against the background around it, :mod:`mmusv.export.contrast`; 0.05 is the
            WMO's visibility threshold) is under this; ``None`` (the default) keeps every box. It needs the cameras'
            instance images (also with ``box="projected"``).
        box: COCO and YOLO: the 2D box written, ``"visible"`` (the default: the tight box of the vessel's pixels in
            the instance image, COCO's convention for ``bbox``; YOLO then needs cameras recording instance images)
            or ``"projected"`` (the recording's box: the vessel's projected 3D box clipped to the image, reaching
            down to the keel and over what hides it). ``min_box_px`` applies to the box written. Other formats
            keep their boxes (KITTI and ROS 2: the recorded box).
        overwrite: replace a previous conversion in ``out_dir`` (``include_usvs`` and ``overwrite`` are ``bool``).
        agents: the agents (USV ids, a list or ``"usv_1,usv_2"``) to convert; every recording must hold one of
            them. ``None``: all.
        frames: the acquisition indices to convert, ``(start, stop)`` or ``"start:stop"`` (``stop`` excluded; left
            out or ``None``: to the end). The others are neither converted nor reported missing. ``None``: all.
        progress: called with (frames done, frames expected) after every frame (a callable of two arguments).

    Raises:
        ConfigError: bad options. IoError: missing, unreadable or non-MCAP recordings; an existing output.
    """
    t0 = time.perf_counter()
    cls = writer_class(to)
    rng = arguments.real(eval_range_m, name="eval_range_m", unit="metres", above=0.0)
    seed = arguments.whole(seed, name="seed", lo=0)
    include_usvs = arguments.flag(include_usvs, name="include_usvs")
    overwrite = arguments.flag(overwrite, name="overwrite")
    progress = arguments.callback(progress, name="progress", nargs=2)
    out = arguments.path(out_dir, name="out_dir")
    ratios = None if splits is None else parse_ratios(splits)
    if not cls.splits and ratios is not None:
        if ratios != parse_ratios(DEFAULT_RATIOS):
            raise ConfigError(f"split {splits!r}: --to {to} writes one folder per recording and is never split")
        ratios = None
    box_px, max_occ = _box_filter(min_box_px, max_occlusion)
    min_c = _contrast_filter(min_contrast)
    box = parse_box(box)
    options = Options(
        to=to,
        eval_range_m=rng,
        include_usvs=include_usvs,
        extras=parse_extras(extras),
        min_box_px=box_px,
        max_occlusion=max_occ,
        min_contrast=min_c,
        box=box,
        agents=_agent_selection(agents),
        frames=_frame_selection(frames),
    )
    cls = cls.for_options(options)
    paths = _as_list(recordings)
    infos = [read_info(p) for p in paths]  # validates every input before anything is written
    for i in infos:
        cls.check(i)
    if options.agents is not None:
        _check_agents(cls, infos, options.agents)
    outside = _outside_frames(infos, options.frames)
    folders = _folders(infos)
    split_of: dict[str, str | None] = dict.fromkeys(folders)
    if ratios is not None:
        split_of = dict(assign_splits(folders, ratios, seed))
    work, lock = _prepare_out(out, overwrite, [Path(i.path) for i in infos])
    try:
        reports = [
            RecordingReport(path=i.path, scenario=i.scenario_name, folder=f, split=split_of[f])
            for i, f in zip(infos, folders, strict=True)
        ]
        header = {
            "format": to,
            "options": {
                "eval_range_m": rng,
                "include_usvs": options.include_usvs,
                "extras": list(options.extras),
                **({"min_box_px": box_px, "max_occlusion": max_occ, "box": box} if to in ("coco", "yolo") else {}),
                **({"min_contrast": min_c} if to in ("coco", "yolo") and min_c is not None else {}),
                "splits": None
                if ratios is None
                else dict(zip(SPLIT_NAMES, [round(r, 9) for r in ratios], strict=True)),
                "seed": seed,
                **({"agents": list(options.agents)} if options.agents is not None else {}),
                **({"frames": list(options.frames)} if options.frames is not None else {}),
            },
        }
        with _staged(work, out):
            (work / REPORT_NAME).write_bytes(dump_yaml({**header, "status": "in_progress"}))
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
                wanted = writer.topic_filter()
                stream = FrameStream(info, wanted.__contains__, frames=options.frames)
                converted: list[int] = []
                incomplete: list[tuple[int, str]] = []
                for fr in stream:
                    missing = writer.missing(fr)
                    if not options.wants_frame(fr.index):
                        pass  # outside --frames: neither converted nor missing
                    elif fr.world is None or missing or not writer.agents:
                        why = (
                            writer.no_agent_reason
                            if not writer.agents
                            else f"incomplete: missing {', '.join(missing[:4])}"
                            + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
                        )
                        incomplete.append((fr.index, why))
                    else:
                        writer.write_frame(fr)
                        converted.append(fr.index)
                        report.agent_frames += len(writer.agents)
                    done += 1
                    if progress is not None:
                        progress(done, max(expected, done))
                rep.status = stream.run.get("status", "unfinished (no run metadata)")
                for k, why in incomplete:
                    rep.skipped.append({"frames": [k, k], "reason": why})
                seen = set(converted) | {k for k, _ in incomplete}
                # the frames the run set out to write: --frames N cuts a run short on purpose, those after N are
                # not missing
                configured = int(
                    stream.run.get("frames_requested", stream.run.get("frames_configured", info.frames_configured)) or 0
                )
                first = int(stream.run.get("first_frame", 0) or 0)  # one part of a split recording given alone
                absent = [k for k in range(first, first + configured) if k not in seen and options.wants_frame(k)]
                if absent:
                    written = stream.run.get("frames_written")
                    why = (
                        f"not in the recording (run {rep.status}: {written} of {configured} frames written)"
                        if written is not None
                        else f"not in the recording (the run did not finish; {configured} frames configured)"
                    )
                    if stream.truncated:
                        why += "; " + stream.truncated
                    rep.skipped += [{"frames": [a, b], "reason": why} for a, b in _ranges(absent)]
                elif stream.truncated:
                    rep.notes.append(stream.truncated)
                if stream.out_of_order:
                    again = sorted(set(stream.out_of_order))
                    rep.notes.append(f"frames {again} appear more than once; the last copy was kept")
                rep.skipped.sort(key=lambda s: s["frames"][0])
                writer.finish(sorted(converted), rep.skipped)
                rep.notes += writer.notes
                rep.frames_converted = len(converted)
                if converted:
                    rep.first_frame, rep.last_frame = min(converted), max(converted)
                else:
                    rep.notes.append("no complete frame: nothing written for this recording")
                    if cls.owns_folder:
                        shutil.rmtree(folder, ignore_errors=True)
            if report.frames == 0 and work != out:
                # --overwrite with nothing to show for it: the previous conversion stays (the staging folder goes)
                raise IoError(
                    f"nothing converted: no complete frame in {', '.join(str(r.path) for r in reports)}; "
                    f"{out} keeps its previous conversion"
                )
            cls.finish_all(shared, work, sink)
            doc = {
                **header,
                "status": "complete",
                "frames_converted": report.frames,
                "agent_frames": report.agent_frames,
                "recordings": [r.as_dict() for r in sorted(reports, key=lambda r: (r.split or "", r.folder))],
            }
            data = dump_yaml(doc)
            (work / REPORT_NAME).write_bytes(data)
            report.files = sink.files + 1
            report.bytes = sink.bytes + len(data)
    finally:
        lock.release()
    report.seconds = time.perf_counter() - t0
    return report


def load_report(out_dir: str | Path) -> dict[str, Any]:
    """The ``conversion.yaml`` of a converted folder."""
    doc: dict[str, Any] = yaml.safe_load((Path(out_dir) / REPORT_NAME).read_text(encoding="utf-8"))
    return doc
