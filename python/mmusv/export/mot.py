"""``--to mot``: MOTChallenge (MOT17/MOT20) ground truth for multi-object tracking, one sequence per agent camera.

Layout (what TrackEval's ``MotChallenge2DBox`` and py-motmetrics read): ``<split>/<sequence>/`` per camera of each
converted agent, ``split`` = ``train``, ``validate``, ``test`` (by recording, :mod:`mmusv.export.splits`; every
sequence in ``train``, MOTChallenge's folder of sequences with ground truth, without a split), ``sequence`` =
``<scenario>.<agent>.<camera>`` (:func:`sequence_name`: the scenario folder, the agent id and the camera name, which
hold no ``.``, so the name splits back from the right). Each sequence holds:

* ``seqinfo.ini``: ``[Sequence]`` ``name``, ``imDir=img1``, ``frameRate`` (the recording's ``frequency_hz``, the
  nearest whole number, at least 1, where it is not one, as MOTChallenge's files and readers have it; the notes then
  say so),
  ``seqLength`` (frames converted), ``imWidth``, ``imHeight``, ``imExt=.png``;
* ``img1/000001.png`` …: the recorded RGB PNG of each converted frame, copied (as COCO and YOLO do);
* ``gt/gt.txt``: one line per kept 2D box (:meth:`mmusv.export.camera.CameraWriter.boxes_of`: COCO's and YOLO's boxes
  and filters, option ``box`` included), ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,class,visibility``,
  sorted by frame, then id; empty for a camera that saw no vessel;
* ``frames.txt``: the recording's acquisition index of MOT frame ``k`` on line ``k``.

Fields. ``frame``: 1-based and consecutive over the converted frames (MOT frame ``k`` is image ``k`` of ``img1``;
TrackEval refuses a frame outside ``1..seqLength``), whatever acquisition indices ``frames`` selects. ``id``: the
track id, :func:`track_id`: 1 + the vessel's row in the world state (scenario vessels in file order, then moored
ships; OPV2V's ``cav_id`` − 999), the same integer for the vessel in every frame and every sequence of a recording.
Box: MOTChallenge's coordinates are 1-based (its instructions: frame numbers, target ids and bounding boxes), the
image's top-left pixel is ``(1, 1)``: ``bb_left`` = ``x_min + 1``, ``bb_top`` = ``y_min + 1`` of mmusv's box (origin
at the image's top-left corner, pixel ``(i, j)`` over ``[i, i + 1) × [j, j + 1)``), ``bb_width`` and ``bb_height``
unchanged. With ``box="visible"`` (the default) that is the tight box of the vessel's pixels in the instance image:
``bb_left`` the 1-based column of its leftmost pixel, ``bb_width`` its number of columns (py-motmetrics' loader
subtracts the 1 again). ``conf`` 1 (every line is evaluated). ``class``: the vessel's semantic class id of
:mod:`mmusv.classes` (COCO's ``category_id``: 10 ``vessel``, 11 ``usv``). ``visibility``: MOT16/MOT17's ratio,
which counts both occlusion and the part cropped by the image border: ``(1 − occlusion) · (1 − truncation)`` of the
recorded 2D box (:mod:`mmusv.annotate`: ``occlusion`` the share of the vessel's silhouette above the still water
level, within the image, that other objects or the waves hide; ``truncation`` the share of the projected box outside
the image); a vessel wholly in view and unhidden has 1. Numbers: whole numbers as such,
the rest to 3 decimals (boxes) or 6 (visibility).

At the root: ``classes.csv`` (``class,name``: every class of :data:`mmusv.export.camera.CATEGORIES`), ``tracks.csv``
(``split,scenario,track_id,vessel_id,role,class,asset``: every vessel of every converted recording's world state)
and ``seqmaps/<split>.txt`` (TrackEval's sequence maps: ``name``, then the split's sequences).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from mmusv.classes import class_name
from mmusv.errors import IoError
from mmusv.export.camera import (
    CATEGORIES,
    ContrastBoxes,
    ProjectedBoxes,
    Sample,
    Shared,
    VisibleBoxes,
    box_writer,
)
from mmusv.export.common import Options, Sink, png_bytes
from mmusv.export.splits import SPLIT_NAMES
from mmusv.recording.decode import WorldFrame
from mmusv.recording.stream import Frame, frame_ranges

__all__ = [
    "CLASSES_FILE",
    "GT_COLUMNS",
    "TRACKS_COLUMNS",
    "TRACKS_FILE",
    "MotContrastWriter",
    "MotVisibleWriter",
    "MotWriter",
    "TrackRows",
    "csv_bytes",
    "mot_split",
    "sequence_name",
    "track_id",
    "track_rows",
    "visibility",
]

GT_COLUMNS = ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "class", "visibility")
"""The columns of ``gt/gt.txt`` (MOT17/MOT20 ground truth)."""
CLASSES_FILE = "classes.csv"
TRACKS_FILE = "tracks.csv"
TRACKS_COLUMNS = ("split", "scenario", "track_id", "vessel_id", "role", "class", "asset")
"""The columns of ``tracks.csv`` (the MOT and KITTI tracking exports)."""
IMAGE_DIR = "img1"
IMAGE_EXT = ".png"


def sequence_name(scenario: str, *, agent: str, camera: str) -> str:
    """``<scenario>.<agent>.<camera>``: agent ids and camera names hold no ``.`` (only letters, digits, ``_``, ``-``),
    so two (scenario, agent, camera) never share a name (``-`` would join ``a-b`` + ``c`` and ``a`` + ``b-c``)."""
    return f"{scenario}.{agent}.{camera}"


def mot_split(split: str) -> str:
    """The folder of a conversion split: the split's name, ``train`` without a split (``all``)."""
    return "train" if split == "all" else split


def track_id(world: WorldFrame, vessel_id: str) -> int:
    """The MOT track id of a vessel: 1 + its row in the world state."""
    return world.ids.index(vessel_id) + 1


def visibility(*, occlusion: float, truncation: float) -> float:
    """MOTChallenge's ``visibility`` (MOT16: the level of occlusion *and cropping* of each object) of a recorded 2D
    box: the share of the vessel in view within the image, ``1 − occlusion``, times the share of its projected box
    inside the image, ``1 − truncation``; both fractions in ``[0, 1]`` (clamped), the result too."""
    inside = min(1.0, max(0.0, 1.0 - truncation))
    return min(1.0, max(0.0, 1.0 - occlusion)) * inside


def track_rows(split: str, *, scenario: str, world: WorldFrame) -> list[list[Any]]:
    """The ``tracks.csv`` rows (:data:`TRACKS_COLUMNS`) of every vessel of ``world``, a recording's world state."""
    w = world
    return [[split, scenario, i + 1, vid, w.roles[i], int(w.classes[i]), w.assets[i]] for i, vid in enumerate(w.ids)]


class TrackRows:
    """The world-state row of each vessel of one recording as first seen: :meth:`check` refuses a frame where a vessel
    has moved to another row, since its track id (:func:`track_id`) would change."""

    def __init__(self, path: Path, what: str) -> None:
        self.path = path
        self.what = what
        self.rows: dict[str, int] = {}
        """Vessel id → world-state row."""

    def check(self, world: WorldFrame, index: int) -> None:
        """Raises :class:`~mmusv.errors.IoError` when a vessel of ``world`` (acquisition index ``index``) is not in
        the row it was in before."""
        for row, vid in enumerate(world.ids):
            if self.rows.setdefault(vid, row) != row:
                raise IoError(
                    f"{self.path}: vessel {vid!r} is in world-state row {row} at frame {index} and in row "
                    f"{self.rows[vid]} before: its {self.what} track id would change"
                )


def _num(value: float, decimals: int) -> str:
    """``value`` rounded to ``decimals``: a whole number without a point, else Python's shortest repr."""
    r = round(float(value), decimals) + 0.0
    return str(int(r)) if r.is_integer() else repr(r)


def csv_bytes(rows: list[list[Any]]) -> bytes:
    """``rows`` as CSV (``\\n`` line ends), UTF-8."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return buf.getvalue().encode("utf-8")


@dataclass
class _Sequence:
    """One camera of one agent: its folder and its boxes by acquisition index."""

    name: str
    folder: Path
    width: int
    height: int
    rows: dict[int, list[tuple[int, str, str, str, str, int, str]]] = field(default_factory=dict)
    """acquisition index → ``(id, bb_left, bb_top, bb_width, bb_height, class, visibility)`` per kept box."""


class _MotShared(Shared):
    def __init__(self, out: Path, box: str) -> None:
        super().__init__(out=out)
        self.box = box
        self.sequences: dict[str, list[str]] = {}
        """MOT split folder → its sequence names."""
        self.tracks: list[list[Any]] = []
        """The rows of ``tracks.csv``."""


class MotWriter(ProjectedBoxes):
    """Writes MOTChallenge sequences (see the module docstring); this class with ``box="projected"``, which needs
    only RGB images, :class:`MotVisibleWriter` with ``box="visible"`` and :class:`MotContrastWriter` with
    ``box="projected"`` and ``min_contrast``."""

    format_version: ClassVar[int] = 3
    """2 (2026-12-02): ``visibility`` counts the part cut by the image border too (it was 1 − occlusion). 3
    (2026-12-03): ``frameRate`` is a whole number (a rate that is not one was written as it was, ``2.5``)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.sequences: dict[tuple[str, str], _Sequence] = {}
        self.rows = TrackRows(self.info.path, "MOT")
        self.world: WorldFrame | None = None
        """The first converted frame's world state (``tracks.csv``)."""

    @classmethod
    def for_options(cls, options: Options) -> type[MotWriter]:
        return box_writer(options, projected=MotWriter, visible=MotVisibleWriter, contrast=MotContrastWriter)

    @classmethod
    def format_name(cls) -> str:
        return "mot"

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return _MotShared(out, options.box)

    def write_frame(self, frame: Frame) -> None:
        world = frame.world
        assert world is not None
        if self.world is None:
            self.world = world
        self.rows.check(world, frame.index)
        for seq in self.sequences.values():
            seq.rows.pop(frame.index, None)  # a frame written again replaces its rows (convert hands each frame once)
        super().write_frame(frame)

    def sequence(self, sample: Sample) -> _Sequence:
        """The sample's sequence, created on its first frame."""
        key = (sample.agent.id, sample.camera.name)
        seq = self.sequences.get(key)
        if seq is None:
            name = sequence_name(self.folder.name, agent=sample.agent.id, camera=sample.camera.name)
            split = mot_split(sample.split)
            seq = _Sequence(name, self.root / split / name, sample.camera.width, sample.camera.height)
            self.sequences[key] = seq
            self.shared.sequences.setdefault(split, []).append(name)
        return seq

    def write_sample(self, sample: Sample) -> None:
        seq = self.sequence(sample)
        # named by acquisition index + 1 while writing, renumbered 1.. over the converted frames in finish()
        image = self.sink.mkdir(seq.folder / IMAGE_DIR) / f"{sample.frame.index + 1:06d}{IMAGE_EXT}"
        self.put(image, png_bytes(sample.message("rgb")))
        rows = seq.rows.setdefault(sample.frame.index, [])
        for b in self.boxes_of(sample):
            rows.append(
                (
                    track_id(sample.world, b.target_id),
                    _num(b.x_min + 1.0, 3),
                    _num(b.y_min + 1.0, 3),
                    _num(b.width, 3),
                    _num(b.height, 3),
                    b.semantic_class,
                    _num(visibility(occlusion=b.occlusion, truncation=b.truncation), 6),
                )
            )

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        super().finish(frames, skipped)
        freq = _num(self.info.frequency_hz, 6)
        rate = str(max(1, math.floor(self.info.frequency_hz + 0.5)))
        if rate != freq and self.sequences:
            self.notes.append(
                f"recorded at {freq} Hz: seqinfo.ini's frameRate is {rate}, the nearest whole number, since "
                "MOTChallenge's files hold whole numbers and trackers read them so (FairMOT's and JDE's int()); a "
                f"frame's time is its frames.txt index / {freq} s"
            )
        order = sorted(frames)
        done = set(order)
        gaps = [k for k in range(order[0], order[-1] + 1) if k not in done] if order else []
        if gaps and self.sequences:  # a tracker steps by frame: say where a step is longer than 1 / frequency_hz
            what = "index {} is" if len(gaps) == 1 else "indices {} are"
            self.notes.append(
                f"acquisition {what.format(frame_ranges(gaps))} not converted, so the frames of its sequences "
                f"({', '.join(sorted(s.name for s in self.sequences.values()))}) are not all 1 / frequency_hz apart "
                "(each sequence's frames.txt gives each frame's index)"
            )
        for seq in self.sequences.values():
            order = sorted(seq.rows)
            img = seq.folder / IMAGE_DIR
            for k, index in enumerate(order, start=1):
                if index + 1 != k:  # k <= index + 1: the target is free (its own image has moved already)
                    (img / f"{index + 1:06d}{IMAGE_EXT}").rename(img / f"{k:06d}{IMAGE_EXT}")
            lines = [
                f"{k},{r[0]},{r[1]},{r[2]},{r[3]},{r[4]},1,{r[5]},{r[6]}\n"
                for k, index in enumerate(order, start=1)
                for r in sorted(seq.rows[index])
            ]
            self.put(self.sink.mkdir(seq.folder / "gt") / "gt.txt", "".join(lines).encode())
            ini = (
                f"[Sequence]\nname={seq.name}\nimDir={IMAGE_DIR}\nframeRate={rate}\nseqLength={len(order)}\n"
                f"imWidth={seq.width}\nimHeight={seq.height}\nimExt={IMAGE_EXT}\n\n"
            )
            self.put(seq.folder / "seqinfo.ini", ini.encode())
            self.put(seq.folder / "frames.txt", "".join(f"{i}\n" for i in order).encode())
        if self.world is not None and self.sequences:
            self.shared.tracks += track_rows(mot_split(self.split_name), scenario=self.folder.name, world=self.world)

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        st: _MotShared = shared
        if not st.sequences:
            return
        sink.write(out / CLASSES_FILE, csv_bytes([["class", "name"], *([c, class_name(c)] for c in CATEGORIES)]))
        tracks = sorted(st.tracks, key=lambda r: (r[1], r[2]))
        sink.write(out / TRACKS_FILE, csv_bytes([list(TRACKS_COLUMNS), *tracks]))
        sink.mkdir(out / "seqmaps")
        for split in [*SPLIT_NAMES]:
            if split in st.sequences:
                names = sorted(st.sequences[split])
                sink.write(out / "seqmaps" / f"{split}.txt", "".join(f"{n}\n" for n in ["name", *names]).encode())


class MotVisibleWriter(VisibleBoxes, MotWriter):
    """:class:`MotWriter` with ``box="visible"``: the boxes come from the instance images, so a camera must record
    them too."""


class MotContrastWriter(ContrastBoxes, MotWriter):
    """:class:`MotWriter` with ``box="projected"`` and ``min_contrast``: the contrast is measured on the vessel's
    pixels in the instance images, so a camera must record them too."""
