"""``--to semantickitti``: LiDAR scans with per-point labels in the SemanticKITTI layout.

One sequence per (recording, agent with a LiDAR), numbered ``00``, ``01``, ... in conversion order (split, then
scenario folder, then agent): ``sequences/NN/velodyne/<scan>.bin`` (float32 x, y, z, intensity per point, the
LiDAR frame: x forward, y left, z up), ``labels/<scan>.label`` (uint32 per point: the instance id in the upper 16
bits, the semantic class id of :mod:`mmusv.classes` in the lower 16; the instance is the vessel's world-state
``instance_id`` for points on a vessel, 0 for the rest: water, land, structures, buoys), ``poses.txt``
(per scan, the 3×4 row-major pose of camera 0 in camera 0's frame at the first scan), ``calib.txt`` (``P0``..``P3``:
the front camera's ``K·[I|0]``, its pinhole even when its lens distorts (the conversion's notes then give the
coefficients); ``Tr``: LiDAR → front optical frame; all zeros and the identity without a front camera, so camera 0
is the LiDAR) and ``times.txt`` (sim time of each scan, s). Scans are numbered ``000000``
consecutively over the converted frames (SemanticKITTI's readers pair scan ``i`` with line ``i`` of
``poses.txt``); ``frames.txt`` gives the recording's frame index of each scan.

``semantic-kitti.yaml`` at the root is the label map in the semantic-kitti-api layout: ``labels`` (id → name),
``color_map`` (BGR, from the mmusv palette), ``content`` (fraction of the exported points per class),
``learning_map`` (``none`` → 0, the other classes → 1.. in id order; ``none`` labels the returns of rain drops,
the only points of class 0), ``learning_map_inv``, ``learning_ignore`` (0 only) and ``split``
(``train``/``valid``/``test``: sequence numbers; the split is made by recording, :mod:`mmusv.export.splits`; every
sequence is ``train`` without a split).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.classes import PALETTE, SemanticClass, class_name
from mmusv.errors import ConfigError
from mmusv.export.common import Options, Sink, dump_yaml
from mmusv.export.geometry import agent_view
from mmusv.export.kitti import front_calib, kitti_numbers
from mmusv.export.writer import DatasetWriter
from mmusv.frames import invert
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.stream import Frame

__all__ = ["LABEL_MAP_NAME", "SemanticKittiWriter", "label_words", "vessel_instances"]

LABEL_MAP_NAME = "semantic-kitti.yaml"
_YAML_SPLIT = {"train": "train", "validate": "valid", "test": "test"}


def label_words(semantic_class: np.ndarray, instance: np.ndarray) -> np.ndarray:
    """``(N,)`` uint32 SemanticKITTI labels: ``instance << 16 | class`` (negative instances → 0). Raises
    :class:`~mmusv.errors.ConfigError` for ids that do not fit in 16 bits."""
    cls = np.asarray(semantic_class).astype(np.int64)
    inst = np.maximum(np.asarray(instance).astype(np.int64), 0)
    if cls.size and (cls.max() > 0xFFFF or cls.min() < 0):
        raise ConfigError(f"semantic class ids {int(cls.min())}..{int(cls.max())} do not fit in 16 bits")
    if inst.size and inst.max() > 0xFFFF:
        raise ConfigError(f"instance id {int(inst.max())} does not fit in the 16 bits of a SemanticKITTI label")
    return ((inst << 16) | cls).astype(np.uint32)


def vessel_instances(instance: np.ndarray, world: WorldFrame) -> np.ndarray:
    """``(N,)`` int64: the points' instance ids where they hit a vessel of the world state (scenario vessels, USVs,
    moored ships: their ``instance_id``, the one COCO's masks use), 0 elsewhere. The recorded ``instance`` is the
    scene instance of the surface hit, and water, land, structures and buoys are scene instances too (each buoy
    one of its own, the first of them 0, else the first static mesh), so without this the sea would read as one
    SemanticKITTI instance and every buoy but the first as one too."""
    inst = np.asarray(instance).astype(np.int64)
    ids = np.asarray(world.instance_ids, dtype=np.int64)
    return np.where(np.isin(inst, ids), inst, 0)


@dataclass
class _Shared:
    out: Path
    sequences: list[tuple[int, str | None]] = field(default_factory=list)
    counts: np.ndarray = field(default_factory=lambda: np.zeros(65536, dtype=np.int64))


@dataclass
class _Sequence:
    number: int
    folder: Path
    calib: list[str]
    origin_inv: np.ndarray
    tr_inv: np.ndarray
    poses: list[str] = field(default_factory=list)
    times: list[str] = field(default_factory=list)
    frames: list[str] = field(default_factory=list)


class SemanticKittiWriter(DatasetWriter):
    """Writes SemanticKITTI sequences (see the module docstring)."""

    owns_folder: ClassVar[bool] = False
    needs_agent: ClassVar[bool] = True
    no_agent_reason: ClassVar[str] = "no agent with a LiDAR"

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.extra_counts = {}
        self.sequences: dict[str, _Sequence] = {}
        for a in self.agents:
            cam = a.cameras.get("front")
            if cam is not None and cam.distortion is not None and any(cam.distortion):
                self.notes.append(
                    f"agent {a.id}: front camera has lens distortion {list(cam.distortion)} [k1, k2, p1, p2, k3]: "
                    "calib.txt's P0..P3 are its pinhole K, so a scan's points projected with P2 * Tr land where "
                    "the recorded (unrectified) image shows them only once the distortion is applied (OpenCV's "
                    "projectPoints with these coefficients)"
                )

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return _Shared(out=out)

    def required_topics(self) -> list[str]:
        return [topics.WORLD_STATE, *(topics.lidar(a.id) for a in self.agents)]

    def optional_topics(self) -> list[str]:
        return []

    def write_frame(self, frame: Frame) -> None:
        from mmusv.recording import decode_point_cloud

        world = frame.world
        assert world is not None
        st: _Shared = self.shared
        for a in self.agents:
            view = agent_view(a, world)
            assert view.lidar is not None
            seq = self.sequences.get(a.id)
            if seq is None:
                k, tr = front_calib(a, view)
                number = len(st.sequences)
                st.sequences.append((number, self.split))
                folder = st.out / "sequences" / f"{number:02d}"
                seq = _Sequence(
                    number=number,
                    folder=folder,
                    calib=[*(f"P{i}: {kitti_numbers(k)}" for i in range(4)), f"Tr: {kitti_numbers(tr[:3, :])}"],
                    origin_inv=invert(view.lidar @ invert(tr)),
                    tr_inv=invert(tr),
                )
                self.sequences[a.id] = seq
                self.notes.append(f"agent {a.id} -> sequences/{number:02d}")
            name = f"{len(seq.poses):06d}"
            cloud = decode_point_cloud(frame.messages[topics.lidar(a.id)])
            n = len(cloud["x"])
            pts = np.column_stack([cloud["x"], cloud["y"], cloud["z"], cloud.get("intensity", np.zeros(n))])
            cls = cloud.get("class", np.zeros(n, dtype=np.uint16))
            labels = label_words(cls, vessel_instances(cloud.get("instance", np.zeros(n, dtype=np.int32)), world))
            self.put(self.sink.mkdir(seq.folder / "velodyne") / f"{name}.bin", pts.astype("<f4").tobytes())
            self.put(self.sink.mkdir(seq.folder / "labels") / f"{name}.label", labels.astype("<u4").tobytes())
            st.counts += np.bincount(labels & 0xFFFF, minlength=65536)[:65536]
            cam0 = view.lidar @ seq.tr_inv  # camera 0 → world
            seq.poses.append(kitti_numbers((seq.origin_inv @ cam0)[:3, :]))
            seq.times.append(f"{world.time_s:.6e}")
            seq.frames.append(str(frame.index))

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        super().finish(frames, skipped)
        for seq in self.sequences.values():
            for name, lines in (
                ("calib.txt", seq.calib),
                ("poses.txt", seq.poses),
                ("times.txt", seq.times),
                ("frames.txt", seq.frames),
            ):
                self.put(seq.folder / name, "".join(line + "\n" for line in lines).encode())

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        st: _Shared = shared
        if not st.sequences:
            return
        ids = [int(c) for c in SemanticClass]
        train_ids = {c: (0 if c == SemanticClass.NONE else i) for i, c in enumerate(ids)}
        total = max(int(st.counts.sum()), 1)
        split: dict[str, list[int]] = {"train": [], "valid": [], "test": []}
        for number, s in st.sequences:
            split[_YAML_SPLIT[s] if s else "train"].append(number)
        doc = {
            "name": "mmusv",
            "labels": {c: class_name(c) for c in ids},
            "color_map": {c: [int(v) for v in PALETTE[c][::-1]] for c in ids},
            "content": {c: round(int(st.counts[c]) / total, 9) for c in ids},
            "learning_map": train_ids,
            "learning_map_inv": {v: c for c, v in train_ids.items()},
            "learning_ignore": {v: v == 0 for v in sorted(set(train_ids.values()))},
            "split": split,
        }
        sink.write(out / LABEL_MAP_NAME, dump_yaml(doc))
