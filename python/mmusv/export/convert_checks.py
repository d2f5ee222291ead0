"""What a conversion (:func:`mmusv.export.convert`) checks before it writes anything: its options (the 2D box and
contrast filters, the agents and frames selected) and the recordings given (files, or batch output folders as their
complete recordings; the selected agents and frames in them), each refused with a
:class:`~mmusv.errors.ConfigError` or :class:`~mmusv.errors.IoError` naming the argument."""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.export.contrast import MAX_CONTRAST
from mmusv.export.writer import DatasetWriter
from mmusv.recording.info import RecordingInfo
from mmusv.recording.stream import FrameStream
from mmusv.text import given, named

__all__ = [
    "agent_selection",
    "as_list",
    "box_filter",
    "box_options",
    "check_agents",
    "contrast_filter",
    "frame_selection",
    "kitti_type",
    "outside_frames",
    "oxts_origin_of",
]


def as_list(recordings: str | Path | Iterable[str | Path], *, from_folders: set[Path] | None = None) -> list[Path]:
    """The recordings given: files (``.mcap``, parts manifests) as they are, a folder holding a ``dataset.json``
    (a batch run's output) as its complete recordings (also added to ``from_folders``, when given: what a message
    about them can tell apart from the files given one by one)."""
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
                from mmusv.recording.folders import folder_hint

                raise IoError(
                    f"{p} is not a file but a folder without a dataset.json; give recordings (.mcap, .parts.json) "
                    f"or a batch output folder{folder_hint(p)}"
                )
            found = dataset_recordings(index)
            if not found:
                raise ConfigError(f"{index} lists no complete recording")
            out.extend(found)
            if from_folders is not None:
                from_folders.update(found)
        else:
            out.append(p)
    if not out:
        raise ConfigError("no recordings given")
    return out


def box_filter(min_box_px: Any, max_occlusion: Any) -> tuple[float, float]:
    px = arguments.real(min_box_px, name=named("min_box_px"), unit="pixels", finite=False)
    occ = arguments.real(max_occlusion, name=named("max_occlusion"), finite=False)
    if not (math.isfinite(px) and px >= 0):
        raise ConfigError(f"{given('min_box_px', min_box_px)}: must be a finite number of pixels >= 0")
    if not (math.isfinite(occ) and 0 <= occ <= 1):
        raise ConfigError(f"{given('max_occlusion', max_occlusion)}: must be a fraction in [0, 1]")
    return px, occ


BOX_FORMATS = ("coco", "yolo", "mot")
"""The formats whose 2D boxes the options ``box``, ``min_box_px``, ``max_occlusion`` and ``min_contrast`` choose."""


FILTER_FORMATS = (*BOX_FORMATS, "ros2")
"""The formats whose 2D boxes ``min_box_px`` and ``max_occlusion`` filter: :data:`BOX_FORMATS` and ROS 2 (its
``Detection2DArray`` messages, on the recorded box: ``Detection2D`` has no field for occlusion)."""


def box_options(to: str, *, min_box_px: float, max_occlusion: float, min_contrast: float | None, box: str) -> None:
    """Refuses (:class:`~mmusv.errors.ConfigError` naming the option) a 2D box option other than its default for a
    format ``to`` that writes no such boxes (``min_box_px`` and ``max_occlusion``: not in :data:`FILTER_FORMATS`;
    ``min_contrast`` and ``box``: not in :data:`BOX_FORMATS`): it would change nothing, silently."""
    filters = [
        given("min_box_px", float(min_box_px)) if min_box_px != 0.0 else "",
        given("max_occlusion", float(max_occlusion)) if max_occlusion != 1.0 else "",
    ]
    filters = [g for g in filters if g]
    if to not in FILTER_FORMATS and filters:
        raise ConfigError(
            f"{', '.join(filters)}: only the COCO, YOLO, MOT and ROS 2 exports ({_formats(FILTER_FORMATS)}) "
            f"filter their 2D boxes with it, not {given('to', to)}, which would ignore it; leave it out"
        )
    chosen = [
        given("min_contrast", float(min_contrast)) if min_contrast is not None else "",
        given("box", box) if box != "visible" else "",
    ]
    chosen = [g for g in chosen if g]
    if to not in BOX_FORMATS and chosen:
        raise ConfigError(
            f"{', '.join(chosen)}: only the COCO, YOLO and MOT exports ({_formats(BOX_FORMATS)}) choose their 2D "
            f"boxes with it, not {given('to', to)}, which would ignore it; leave it out"
        )


def _formats(formats: Sequence[str]) -> str:
    """``to = 'coco', 'yolo' or 'mot'`` (Python), ``--to coco, yolo or mot`` (the command line)."""
    flag = named("to")
    lead, values = (f"{flag} ", list(formats)) if flag != "to" else ("to = ", [repr(f) for f in formats])
    return lead + (values[0] if len(values) == 1 else ", ".join(values[:-1]) + f" or {values[-1]}")


EXTRAS_FORMATS = ("opv2v", "kitti", "kitti_tracking")
"""The formats that write the extra files ``extras`` (``--extras``) names."""


def extras_option(to: str, extras: tuple[str, ...]) -> None:
    """Refuses (:class:`~mmusv.errors.ConfigError`) ``extras`` other than the default or none for a format ``to`` that
    writes no extra files (not in :data:`EXTRAS_FORMATS`): ``--to coco --extras depth`` wrote no depth, and said
    nothing of it."""
    from mmusv.export.common import DEFAULT_EXTRAS

    if to not in EXTRAS_FORMATS and extras not in ((), DEFAULT_EXTRAS):  # none: what it writes anyway
        raise ConfigError(
            f"{given('extras', ','.join(extras))}: only the OPV2V, KITTI and KITTI tracking exports "
            f"({_formats(EXTRAS_FORMATS)}) write extra files, not {given('to', to)}, which would ignore it; leave it "
            "out"
        )


TARGET_FORMATS = ("opv2v", "kitti", "kitti_tracking")
"""The formats that list targets by the evaluation range (``eval_range_m``, ``--range``) and ``include_usvs``."""
DEFAULT_RANGE_M = 200.0
"""``eval_range_m``'s default (metres)."""


def target_options(to: str, *, eval_range_m: float, include_usvs: bool) -> None:
    """Refuses (:class:`~mmusv.errors.ConfigError` naming the option) an evaluation range other than its default, or
    ``include_usvs``, for a format ``to`` that does not list targets by them (not in :data:`TARGET_FORMATS`): the
    camera exports label every vessel in the image, SemanticKITTI and MaSTr every point and pixel, and ROS 2 bags
    every recorded box; it would change nothing, silently."""
    chosen = [
        given("eval_range_m", float(eval_range_m)) if eval_range_m != DEFAULT_RANGE_M else "",
        given("include_usvs", True) if include_usvs else "",
    ]
    chosen = [g for g in chosen if g]
    if to not in TARGET_FORMATS and chosen:
        raise ConfigError(
            f"{', '.join(chosen)}: only the OPV2V, KITTI and KITTI tracking exports ({_formats(TARGET_FORMATS)}) "
            f"choose their targets with it, not {given('to', to)}, which labels every vessel it holds whatever its "
            "range or role; leave it out"
        )


def contrast_filter(min_contrast: Any) -> float | None:
    """``min_contrast`` as a float in ``[0, MAX_CONTRAST]``, or ``None``; :class:`~mmusv.errors.ConfigError` naming it
    otherwise."""
    if min_contrast is None:
        return None
    allowed = (
        f"must be a Weber contrast >= 0 and <= {MAX_CONTRAST:.1f} (the largest an 8-bit image holds; 0.05 is the "
        f"WMO's visibility threshold), or {'None' if named('min_contrast') == 'min_contrast' else 'left out'} to keep "
        "every box"
    )
    c = arguments.real(min_contrast, name=named("min_contrast"), finite=False)
    if not (math.isfinite(c) and 0 <= c <= MAX_CONTRAST):
        raise ConfigError(f"{given('min_contrast', min_contrast)}: {allowed}")
    return c


def kitti_type(kitti_class: Any, to: str) -> str | None:
    """``kitti_class`` (the type KITTI tracking labels give every target) as given, or ``None``;
    :class:`~mmusv.errors.ConfigError` naming it unless it is one word of letters, digits and ``_`` starting with a
    letter (a KITTI type, e.g. ``Car``), not ``DontCare`` (KITTI's regions to ignore), and ``to`` is
    ``kitti_tracking``."""
    if kitti_class is None:
        return None
    shown = given("kitti_class", kitti_class)
    if to != "kitti_tracking":
        raise ConfigError(f"{shown}: only {_formats(['kitti_tracking'])} writes it, not {given('to', to)}")
    if not isinstance(kitti_class, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", kitti_class):
        raise ConfigError(
            f"{shown}: must be one KITTI type word (letters, digits, _; e.g. Car, which stock TrackEval "
            "and the KITTI devkit score), or None for each vessel's class name"
        )
    if kitti_class.lower() == "dontcare":
        raise ConfigError(f"{shown}: DontCare marks regions to ignore, not objects to track")
    return kitti_class


def agent_selection(agents: Iterable[str] | str | None) -> tuple[str, ...] | None:
    """``agents`` (a list of ids or ``"usv_1,usv_2"``) as sorted unique ids, or ``None``; an empty selection or an
    id that is not a string is a :class:`~mmusv.errors.ConfigError` naming ``agents``."""
    if agents is None:
        return None
    if isinstance(agents, str):
        items = [a.strip() for a in agents.split(",")]
    elif isinstance(agents, Iterable) and not isinstance(agents, Mapping):  # a dict's keys are not a selection
        items = list(agents)
    else:
        raise ConfigError(
            f"agents = {arguments.shown(agents)}: must be agent ids (a list or 'usv_1,usv_2'), not "
            f"{type(agents).__name__}"
        )
    if not all(isinstance(a, str) and a for a in items) or not items:
        raise ConfigError(
            f"agents = {arguments.shown(agents)}: must be one or more agent ids (non-empty strings, comma-separated)"
        )
    return tuple(sorted(set(items)))


def outside_frames(infos: list[RecordingInfo], frames: tuple[int, int | None] | None) -> dict[int, str]:
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


def frame_selection(frames: Sequence[int | None] | str | None) -> tuple[int, int | None] | None:
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
    stop = None if pair[1] is None else arguments.whole(pair[1], name="frames stop", lo=0)
    if stop is not None and stop <= start:  # was "frames stop = 1: must be a whole number >= 3"
        raise ConfigError(
            f"frames = {shown}: STOP ({stop}) must be greater than START ({start}); STOP is excluded, so "
            f"{start}:{start + 1} is frame {start} alone and {start}: runs to the last frame"
        )
    return start, stop


def check_agents(cls: type[DatasetWriter], infos: list[RecordingInfo], agents: tuple[str, ...]) -> None:
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


def oxts_origin_of(value: Any, to: str) -> tuple[float, float] | None:
    """``value`` (``(lat, lon)`` in degrees or ``"LAT,LON"``; the KITTI tracking ``oxts`` files' world origin) as a
    pair, or ``None``; :class:`ConfigError` for another format or a point that is not one
    (:func:`mmusv.export.kitti_oxts.parse_origin`)."""
    from mmusv.export.kitti_oxts import parse_origin

    if value is None:
        return None
    if to != "kitti_tracking":
        raise ConfigError(
            f"{given('oxts_origin', value)}: only {_formats(['kitti_tracking'])} writes it, not {given('to', to)}"
        )
    return parse_origin(value, "oxts_origin =")
