"""``--to kitti_tracking``: the KITTI tracking benchmark's layout, one sequence per (recording, agent with a LiDAR), for
3D multi-object tracking (the KITTI tracking loaders of trackers such as AB3DMOT) and TrackEval's ``Kitti2DBox``.

Per split (``train``, ``validate``, ``test`` by recording, :mod:`mmusv.export.splits`; ``train`` without a split, as
:func:`mmusv.export.mot.mot_split`), ``<split>/`` holds, per sequence ``<seq>`` (4 digits, numbered 0000, 0001, …
over the whole conversion in its order: split, scenario, agent; so no two sequences of a conversion share a number):

* ``velodyne/<seq>/<frame:06d>.bin`` and ``image_02/<seq>/<frame:06d>.png``: the LiDAR scan and the front camera's
  RGB image, the KITTI export's ``velodyne`` and ``image_2`` files
  (:meth:`mmusv.export.kitti.KittiWriter.write_sensors`), with the extras beside them (``depth_02``,
  ``semantic_02``, ``instance_02``, ``radar_ppi``, ``top_view_rgb``, ``top_view_semantic``);
* ``label_02/<seq>.txt``: per frame and target, ``frame track_id`` then the KITTI export's ``label_2`` line of that
  frame and agent (:func:`mmusv.export.kitti.label_lines`: ``type truncated occluded alpha x1 y1 x2 y2 h w l x y z
  rotation_y``) with ``truncated`` the tracking benchmark's level 0, 1, 2
  (:func:`mmusv.export.kitti.truncation_level`), sorted by frame, then track id; ``frame`` 0, 1, … over the
  converted frames (whatever ``frames`` selects), ``track_id`` :func:`mmusv.export.mot.track_id` (1 + the
  vessel's world-state row: the MOT export's id); and per frame, first, with track id -1, the ``DontCare`` lines of
  the vessels the front image shows that are not targets (:func:`mmusv.export.kitti.dont_care_lines`: TrackEval's
  ``Kitti2DBox`` takes them as regions to ignore, as in KITTI's own labels);
* ``calib/<seq>.txt``: ``P0:`` … ``P3:``, ``R_rect``, ``Tr_velo_cam``, ``Tr_imu_velo`` (the tracking benchmark's
  names, the last three without a colon), the KITTI export's calibration of the sequence's first frame: the front
  camera is rigid on the hull, so LiDAR → camera is one matrix per sequence, checked on every frame (a camera that
  moved against the LiDAR is refused, :class:`~mmusv.errors.IoError`);
* ``pose/<seq>.txt``: line ``frame``: LiDAR → mmusv world, 3×4 row-major (the KITTI export's ``pose``);
* ``oxts/<seq>.txt``: line ``frame``: the vessel body's (the IMU frame of ``Tr_imu_velo``) GPS/IMU values as KITTI's
  oxts files hold them (:func:`mmusv.export.kitti_oxts.oxts_lines`: latitude and longitude on the devkit's
  Mercator projection with the world origin at :attr:`~mmusv.export.common.Options.oxts_origin`, roll, pitch, yaw,
  velocities, accelerations and angular rates by finite differences at the frames' times);
* ``frames/<seq>.txt``: line ``frame``: the recording's acquisition index (sim time = index / ``frequency_hz``;
  where frames in the middle were skipped, consecutive frames are further apart, which the conversion's notes say);
* ``evaluate_tracking.seqmap.<split>``: ``<seq> empty 000000 <frames:06d>`` per sequence (TrackEval's and the
  devkit's sequence map; ``GT_FOLDER`` = ``<split>``, ``SPLIT_TO_EVAL`` = ``<split>``).

At the root: ``sequences.csv`` (``split,sequence,scenario,agent,cav_id,frames,frequency_hz``: the KITTI export's
folder of the agent is ``cav_id``), ``tracks.csv`` (the MOT export's: every vessel of each converted recording's
world state) and, with the ``top_view`` extra, ``top_views.yaml``: ``top_views``, each sequence's top view by
``<split>/<seq>`` (``resolution``, ``metres_per_pixel``, ``orientation``, ``altitude_m``), and ``top_view_png``, where
each pixel lies (:func:`mmusv.export.common.top_view_png`). ``kind``
(:attr:`~mmusv.export.common.Options.kitti_class`): the type written for every target (``Car``: what TrackEval's
``Kitti2DBox`` and the devkit score), each target's class name (``Vessel``, ``Usv``) without it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.errors import IoError
from mmusv.export.common import Options, Sink, cav_id, dump_yaml, top_view_entry, top_view_png
from mmusv.export.geometry import AgentView, Target
from mmusv.export.kitti import KittiWriter, calib_text, camera0, dont_care_lines, kitti_numbers, label_lines
from mmusv.export.kitti_oxts import DEFAULT_ORIGIN, oxts_lines
from mmusv.export.mot import TRACKS_COLUMNS, TrackRows, csv_bytes, mot_split, track_id, track_rows
from mmusv.export.splits import SPLIT_NAMES
from mmusv.export.writer import DatasetWriter
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo
from mmusv.recording.stream import Frame, frame_ranges

__all__ = [
    "SEQUENCES_COLUMNS",
    "TRACKING_CALIB_KEYS",
    "KittiTrackingWriter",
    "seqmap_name",
]

TRACKING_CALIB_KEYS = ("R_rect", "Tr_velo_cam", "Tr_imu_velo")
"""The tracking benchmark's names of ``R0_rect``, ``Tr_velo_to_cam`` and ``Tr_imu_to_velo`` (no colon)."""
SEQUENCES_COLUMNS = ("split", "sequence", "scenario", "agent", "cav_id", "frames", "frequency_hz")
"""The columns of ``sequences.csv``."""
FOLDERS = {"image_2": "image_02", "depth_2": "depth_02", "semantic_2": "semantic_02", "instance_2": "instance_02"}
"""The KITTI object layout's per-frame folders renamed in the tracking layout (the others keep their name)."""
RIGID_TOLERANCE = 1e-6
"""The most an entry of LiDAR → front camera (metres, or a rotation's entry) may differ between frames of a sequence."""


def seqmap_name(split: str) -> str:
    """The sequence map of split folder ``split``, TrackEval's ``evaluate_tracking.seqmap.<SPLIT_TO_EVAL>``."""
    return f"evaluate_tracking.seqmap.{split}"


@dataclass
class _Sequence:
    """One agent of one recording."""

    number: int
    folder: Path
    """The split folder."""
    agent: AgentInfo
    velo_to_cam: np.ndarray
    calib: bytes
    labels: dict[int, list[str]] = field(default_factory=dict)
    """Acquisition index → the frame's label lines without the frame number."""
    poses: dict[int, str] = field(default_factory=dict)
    bodies: dict[int, np.ndarray] = field(default_factory=dict)
    """Acquisition index → the vessel body → world pose (``oxts``)."""
    files: dict[str, str] = field(default_factory=dict)
    """Per-frame folders written (under the split folder) → their files' extension."""

    @property
    def name(self) -> str:
        return f"{self.number:04d}"


@dataclass
class _Shared:
    out: Path
    sequences: list[list[Any]] = field(default_factory=list)
    """The rows of ``sequences.csv``."""
    seqmaps: dict[str, list[str]] = field(default_factory=dict)
    """Split folder → its seqmap lines."""
    tracks: list[list[Any]] = field(default_factory=list)
    top_views: dict[str, dict[str, Any]] = field(default_factory=dict)
    """``<split>/<seq>`` → the sequence agent's top view (:func:`~mmusv.export.common.top_view_entry`), for the
    sequences whose ``top_view_*`` images were written (``top_views.yaml``)."""
    count: int = 0
    """Sequences numbered so far."""


class KittiTrackingWriter(KittiWriter):
    """Writes KITTI tracking sequences (see the module docstring): the KITTI export's files, by sequence."""

    owns_folder: ClassVar[bool] = False
    image_folder: ClassVar[str] = "image_02"
    velo_key: ClassVar[str] = "Tr_velo_cam"
    distortion_file: ClassVar[str] = ""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.sequences: dict[str, _Sequence] = {}
        self.rows = TrackRows(self.info.path, "KITTI tracking")
        self.world: WorldFrame | None = None
        """The first converted frame's world state (``tracks.csv``)."""
        self.origin = self.options.oxts_origin or DEFAULT_ORIGIN
        """The geodetic point (latitude, longitude) of the world origin in the ``oxts`` files."""

    @classmethod
    def format_name(cls) -> str:
        return "kitti_tracking"

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return _Shared(out=out)

    @property
    def split_folder(self) -> str:
        return mot_split(self.split or "all")

    def write_frame(self, frame: Frame) -> None:
        assert frame.world is not None
        self.rows.check(frame.world, frame.index)
        if self.world is None:
            self.world = frame.world
        super().write_frame(frame)

    def frame_file(self, agent: AgentInfo, folder: str, *, index: int, ext: str) -> Path:
        seq = self.sequences[agent.id]
        sub = f"{FOLDERS.get(folder, folder)}/{seq.name}"
        seq.files[sub] = ext
        return self.sink.mkdir(seq.folder / sub) / f"{index:06d}{ext}"

    def sequence(self, view: AgentView) -> _Sequence:
        """The agent's sequence, numbered and calibrated on its first frame."""
        a = view.agent
        seq = self.sequences.get(a.id)
        if seq is None:
            assert a.lidar_mount is not None
            st: _Shared = self.shared
            k, velo_to_cam = camera0(a, view)
            folder = st.out / self.split_folder
            calib = calib_text(k, velo_to_cam=velo_to_cam, lidar_mount=a.lidar_mount, keys=TRACKING_CALIB_KEYS)
            seq = _Sequence(st.count, folder, a, velo_to_cam, calib)
            st.count += 1
            self.sequences[a.id] = seq
            self.notes.append(f"agent {a.id} -> {self.split_folder}/{seq.name}")
        return seq

    def write_agent(self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target]) -> None:
        a = view.agent
        assert view.lidar is not None
        seq = self.sequence(view)
        _, velo_to_cam = camera0(a, view)
        moved = float(np.max(np.abs(velo_to_cam - seq.velo_to_cam)))
        if moved > RIGID_TOLERANCE:
            raise IoError(
                f"{self.info.path}: agent {a.id}'s front camera moves against its LiDAR (by {moved:.3g} at frame "
                f"{frame.index}): a KITTI tracking sequence has one calibration"
            )
        self.write_sensors(frame, view)
        lines = label_lines(view, targets, frame.messages, velo_to_cam, self.options.kitti_class, levels=True)
        ids = [track_id(world, t.id) for t in targets]
        ignored = [f"-1 {line}" for line in dont_care_lines(view, targets, frame.messages)]  # track id -1, as KITTI's
        seq.labels[frame.index] = ignored + [f"{i} {line}" for i, line in sorted(zip(ids, lines, strict=True))]
        seq.poses[frame.index] = kitti_numbers(view.lidar[:3, :])
        seq.bodies[frame.index] = np.array(view.body, dtype=np.float64)

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        DatasetWriter.finish(self, frames, skipped)  # the KITTI export's mmusv_kitti.yaml is not written
        st: _Shared = self.shared
        for seq in self.sequences.values():
            order = sorted(seq.labels)
            gaps = [k for k in range(order[0], order[-1] + 1) if k not in seq.labels] if order else []
            if gaps:  # a tracker steps by frame: say where a step is longer than 1 / frequency_hz
                what = "index {} is" if len(gaps) == 1 else "indices {} are"
                self.notes.append(
                    f"{self.split_folder}/{seq.name}: acquisition {what.format(frame_ranges(gaps))} not converted, so "
                    f"its frames are not all 1 / frequency_hz apart (frames/{seq.name}.txt gives each frame's index)"
                )
            freq = self.info.frequency_hz
            for sub, ext in seq.files.items():
                where = seq.folder / sub
                for k, index in enumerate(order):
                    src = where / f"{index:06d}{ext}"
                    if index != k and src.exists():  # k <= index: the target is free (its own file has moved)
                        src.rename(where / f"{k:06d}{ext}")
            for sub, lines in (
                ("label_02", [f"{k} {line}" for k, index in enumerate(order) for line in seq.labels[index]]),
                ("pose", [seq.poses[index] for index in order]),
                ("frames", [str(index) for index in order]),
                ("oxts", oxts_lines([i / freq for i in order], [seq.bodies[i] for i in order], self.origin)),
            ):
                text = "".join(x + "\n" for x in lines)
                self.put(self.sink.mkdir(seq.folder / sub) / f"{seq.name}.txt", text.encode())
            self.put(self.sink.mkdir(seq.folder / "calib") / f"{seq.name}.txt", seq.calib)
            split = self.split_folder
            st.seqmaps.setdefault(split, []).append(f"{seq.name} empty 000000 {len(order):06d}")
            st.sequences.append(
                [split, seq.name, self.folder.name, seq.agent.id, cav_id(seq.agent.index), len(order), freq]
            )
            if any(sub.startswith("top_view_") for sub in seq.files) and seq.agent.rig.get("top_view"):
                st.top_views[f"{split}/{seq.name}"] = top_view_entry(seq.agent.rig["top_view"])
        if self.world is not None and self.sequences:
            st.tracks += track_rows(self.split_folder, scenario=self.folder.name, world=self.world)
        if self.sequences:
            lat, lon = self.origin
            self.notes.append(f"oxts: the world origin is at latitude {lat!r}, longitude {lon!r} (--oxts-origin)")

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        st: _Shared = shared
        if not st.sequences:
            return
        sink.write(out / "sequences.csv", csv_bytes([list(SEQUENCES_COLUMNS), *st.sequences]))
        tracks = sorted(st.tracks, key=lambda r: (r[1], r[2]))
        sink.write(out / "tracks.csv", csv_bytes([list(TRACKS_COLUMNS), *tracks]))
        if st.top_views:
            files = "<split>/top_view_{rgb,semantic}/<seq>/<frame:06d>.png"
            doc = {
                "top_views": dict(sorted(st.top_views.items())),
                "top_view_png": top_view_png(frame="kitti_tracking", files=files),
            }
            sink.write(out / "top_views.yaml", dump_yaml(doc))
        for split in SPLIT_NAMES:
            if split in st.seqmaps:
                lines = sorted(st.seqmaps[split])
                sink.write(out / split / seqmap_name(split), "".join(x + "\n" for x in lines).encode())
