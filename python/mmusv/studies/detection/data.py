"""The detection dataset: sequences of frames, each with every instrumented USV's LiDAR cloud and pose and the
clean world-frame boxes of the targets (mmusv frames: world x east, y north, z up).

Sources: ``mmusv run`` recordings (one sequence each, read through :func:`read_recording`, the one place that
touches the recording reader) and OPV2V folders written by ``mmusv convert --to opv2v`` (one sequence per
scenario folder). Sequences are split (train / validate / test) by a seeded shuffle of their names *before*
agent-as-ego expansion (:func:`split_sequences`), so no scene is in two splits.

Ground truth for an ego (:func:`gt_in_ego`): every target box (USVs excluded) moved into the ego LiDAR frame and
kept when its BEV centre is within ``range_m`` (200 m) of the sensor (:func:`mmusv.boxes3d.in_target_range`, the
box-centre rule of OpenCOOD and of the OPV2V and KITTI exports; the recording's own boxes reach farther, to every
vessel whose footprint comes within range, :func:`mmusv.boxes3d.footprint_in_range`). USV platforms
(:func:`usv_boxes_in_ego`) are returned separately: detections centred on them are ignored in evaluation.
"""

from __future__ import annotations

import reprlib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mmusv.boxes3d import in_target_range
from mmusv.errors import InputError, IoError
from mmusv.frames import carla_matrix, invert, mirror_transform, pose_matrices
from mmusv.text import given

__all__ = [
    "OPV2V_USV_RADIUS_M",
    "AgentFrame",
    "SceneFrame",
    "SequenceData",
    "boxes_in_frame",
    "check_split",
    "gt_in_ego",
    "gt_with_ids",
    "opv2v_scenarios",
    "read_opv2v",
    "read_recording",
    "split_sequences",
    "usv_boxes_in_ego",
    "wave_shares",
]

OPV2V_USV_RADIUS_M = 8.0
"""An OPV2V folder gives no hull size for its CAVs: their platform is taken as a square of twice this half-size
about the body origin."""


@dataclass(frozen=True)
class AgentFrame:
    """One instrumented USV at one frame: ``points`` ``(N, 4)`` float32 ``x, y, z, intensity`` in its LiDAR
    frame (metres), ``body`` ``(4, 4)`` float64 body → world and ``mount`` ``(4, 4)`` float64 LiDAR → body;
    ``wave_occlusion``: the share (0..1) of each target (by vessel id) that the waves hide from this USV's LiDAR,
    from its annotations (a recording's ``boxes_lidar``, an OPV2V export's ``<ts>_additional.yaml`` by vehicle id;
    empty where the source has none: a stock OPV2V folder, an export or recording made before the field)."""

    id: str
    points: np.ndarray
    body: np.ndarray
    mount: np.ndarray
    wave_occlusion: Mapping[str, float] = field(default_factory=dict)

    @property
    def lidar(self) -> np.ndarray:
        """``(4, 4)`` float64 LiDAR → world (metres)."""
        out: np.ndarray = self.body @ self.mount
        return out


@dataclass(frozen=True)
class SceneFrame:
    """One acquisition index of a sequence: the USVs (``agents``, scenario order) and the world-frame boxes of
    the targets (``targets`` ``(K, 4, 4)`` float64 box → world, ``target_sizes`` ``(K, 3)`` float64 l, w, h,
    metres) and of the USV platforms (``usv_boxes``, ``usv_sizes``, the same)."""

    frame: int
    agents: tuple[AgentFrame, ...]
    target_ids: tuple[str, ...]
    targets: np.ndarray
    target_sizes: np.ndarray
    usv_boxes: np.ndarray
    usv_sizes: np.ndarray


@dataclass(frozen=True)
class SequenceData:
    """A whole sequence (one recording or one OPV2V scenario folder)."""

    name: str
    frames: tuple[SceneFrame, ...]

    @property
    def agent_ids(self) -> tuple[str, ...]:
        """The instrumented USVs (those present in the first frame)."""
        return tuple(a.id for a in self.frames[0].agents) if self.frames else ()

    @cached_property
    def _positions(self) -> dict[int, int]:
        return {f.frame: k for k, f in enumerate(self.frames)}

    def frame_at(self, index: int) -> SceneFrame | None:
        """The frame of acquisition index ``index`` (``None`` when the sequence has none: before its start, or
        missing from a damaged or partly recorded recording)."""
        k = self._positions.get(index)
        return None if k is None else self.frames[k]


def boxes_in_frame(to_frame: np.ndarray, *, boxes: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """``(K, 7)`` ``x, y, z, l, w, h, yaw`` (metres, radians; float64, float32 only where every input is) of box →
    world transforms ``boxes`` ``(K, 4, 4)`` with ``sizes`` ``(K, 3)`` seen from the frame whose world → frame
    transform is ``to_frame`` (``(4, 4)``; yaw of the box x axis projected on the frame's xy plane)."""
    if len(boxes) == 0:
        return np.zeros((0, 7))
    m = np.einsum("ij,kjl->kil", to_frame, boxes)
    yaw = np.arctan2(m[:, 1, 0], m[:, 0, 0])
    return np.column_stack([m[:, :3, 3], sizes, yaw])


def gt_in_ego(frame: SceneFrame, ego: AgentFrame, *, range_m: float = 200.0) -> np.ndarray:
    """``(G, 7)`` float64 ground-truth target boxes ``x, y, z, l, w, h, yaw`` (metres, radians) in ``ego``'s
    LiDAR frame within ``range_m`` by the box-centre rule,
    :func:`mmusv.boxes3d.in_target_range` (BEV distance ``<= range_m``)."""
    return gt_with_ids(frame, ego, range_m=range_m)[0]


def gt_with_ids(frame: SceneFrame, ego: AgentFrame, *, range_m: float = 200.0) -> tuple[np.ndarray, list[str]]:
    """:func:`gt_in_ego` and the vessel id of each of its boxes."""
    b = boxes_in_frame(invert(ego.lidar), boxes=frame.targets, sizes=frame.target_sizes)
    if not len(b):
        return b, []
    keep = in_target_range(b[:, :3], range_m)
    return b[keep], [i for i, k in zip(frame.target_ids, keep, strict=True) if k]


def wave_shares(ego: AgentFrame, ids: Sequence[str]) -> np.ndarray:
    """``(len(ids),)`` float64: the share of each target that the waves hide from ``ego``'s LiDAR (its
    annotations); NaN where the source gives none (no annotation of that target, a stock OPV2V folder, an export
    or recording made before the shares existed)."""
    return np.array([ego.wave_occlusion.get(i, np.nan) for i in ids], dtype=np.float64)


def usv_boxes_in_ego(frame: SceneFrame, ego: AgentFrame) -> np.ndarray:
    """``(U, 7)`` float64 boxes ``x, y, z, l, w, h, yaw`` (metres, radians) of every USV platform (the ego's
    included) in ``ego``'s LiDAR frame."""
    return boxes_in_frame(invert(ego.lidar), boxes=frame.usv_boxes, sizes=frame.usv_sizes)


def _box_mats(poses: np.ndarray, centres: np.ndarray) -> np.ndarray:
    m = pose_matrices(poses).reshape(-1, 4, 4)
    m[:, :3, 3] = centres
    return m


@dataclass(frozen=True)
class RecordingSummary:
    """What a recording says about itself without reading its frames."""

    frames_configured: int
    config_hash: str
    complete: bool


def recording_summary(path: str | Path) -> RecordingSummary:
    """The frame count, config hash and completeness (summary section present) of a recording; raises
    :class:`~mmusv.IoError` for a file that is not one."""
    from mmusv.recording.info import read_info

    info = read_info(path)
    return RecordingSummary(int(info.frames_configured), str(info.config_hash), bool(info.has_summary))


def find_recordings(folder: str | Path) -> list[Path]:
    """The recordings below ``folder`` (``.mcap`` files and parts manifests of split recordings, whose parts are
    not listed on their own), sorted."""
    from mmusv.recording.folders import find_recordings as find

    return find(folder)


def recording_name(path: str | Path) -> str:
    """A recording's name: its file name without ``.mcap`` or ``.parts.json``."""
    from mmusv.recording.info import recording_name as name

    return name(path)


def read_recording(path: str | Path) -> SequenceData:
    """A recording (``mmusv run`` MCAP) as a sequence: every frame with the LiDAR of every instrumented USV that
    has one. Raises :class:`~mmusv.IoError` for a file that is not a readable recording."""
    from mmusv.recording.decode import decode_point_cloud
    from mmusv.recording.info import read_info
    from mmusv.recording.stream import FrameStream, warn_missing

    info = read_info(path)
    agents = [a for a in info.agents if a.lidar_mount is not None]
    from mmusv.recording import topics as names

    topics = {names.lidar(a.id) for a in agents}
    notes = {names.agent_annotations(a.id) for a in agents}
    frames: list[SceneFrame] = []
    stream = FrameStream(info, want=lambda t: t in topics or t in notes)
    for fr in stream:
        w = fr.world
        if w is None or not all(t in fr.messages for t in topics):
            continue
        afs = []
        for a in agents:
            c = decode_point_cloud(fr.messages[names.lidar(a.id)])
            pts = np.column_stack([c["x"], c["y"], c["z"], c.get("intensity", np.zeros(len(c["x"])))])
            assert a.lidar_mount is not None
            body = pose_matrices(w.poses[a.index])
            waves = _wave_occlusion(fr.messages.get(names.agent_annotations(a.id)))
            afs.append(AgentFrame(a.id, pts.astype(np.float32), body, a.lidar_mount, waves))
        is_usv = np.array([r == "usv" for r in w.roles], dtype=bool)
        boxes = _box_mats(w.poses, w.box_centers)
        frames.append(
            SceneFrame(
                frame=fr.index,
                agents=tuple(afs),
                target_ids=tuple(i for i, u in zip(w.ids, is_usv, strict=True) if not u),
                targets=boxes[~is_usv],
                target_sizes=w.box_sizes[~is_usv],
                usv_boxes=boxes[is_usv],
                usv_sizes=w.box_sizes[is_usv],
            )
        )
    warn_missing(stream, reader="the detection study")  # frames missing or damaged: said, not dropped silently
    frames.sort(key=lambda f: f.frame)
    return SequenceData(recording_name(info.path), tuple(frames))


def _wave_occlusion(annotations: object) -> dict[str, float]:
    """Target id → wave-occlusion share of an agent's annotations message (``boxes_lidar``); no entry for a box
    without one (a recording made before the field existed)."""
    out: dict[str, float] = {}
    for b in getattr(annotations, "boxes_lidar", ()):
        share = getattr(b, "wave_occlusion", None)
        if share is not None:
            out[str(b.target_id)] = float(share)
    return out


def opv2v_scenarios(root: str | Path, *, name: str = "root") -> list[Path]:
    """The scenario folders of an OPV2V tree: ``root`` itself when it holds CAV folders, else its
    sub-folders (one level, or split folders ``train``/``validate``/``test`` below them) that do. Raises
    :class:`~mmusv.IoError` when there is none, naming ``root`` as the argument ``name`` its user gave
    (:func:`mmusv.text.given`: ``opv2v = '...'`` of :func:`~mmusv.studies.detection.sources.resolve_dataset`,
    ``--opv2v ...`` of ``mmusv study`` and ``mmusv train``; it said ``--opv2v`` to every caller)."""
    r = Path(root)
    if not r.is_dir():
        raise IoError(f"{given(name, r)}: not a folder")

    def is_scenario(d: Path) -> bool:
        return any(c.is_dir() and c.name.isdigit() and any(c.glob("*.pcd")) for c in d.iterdir())

    if is_scenario(r):
        return [r]
    found = sorted(d for d in r.iterdir() if d.is_dir() and is_scenario(d))
    if not found:
        found = sorted(s for d in r.iterdir() if d.is_dir() for s in d.iterdir() if s.is_dir() and is_scenario(s))
    if not found:
        raise IoError(f"{given(name, r)}: not an OPV2V folder (no <scenario>/<cav_id>/<timestamp>.pcd + .yaml found)")
    return found


def read_opv2v(folder: str | Path) -> SequenceData:
    """One OPV2V scenario folder (as ``mmusv convert --to opv2v`` writes it) as a sequence, converted back from
    the CARLA frame (y mirrored, degrees) to mmusv frames. Targets are the union of the CAVs' ``vehicles``
    but the CAVs themselves and the USVs that mmusv's ``<ts>_additional.yaml`` gives role ``usv`` (a USV without a
    LiDAR, no CAV, listed with ``--include-usvs``): those are platforms with their listed box, as a recording's
    USVs are (ground truth was every vessel but the instrumented USVs; such a USV was a target read from OPV2V and
    a platform read from the recording). The CAVs' platforms are squares of half-size :data:`OPV2V_USV_RADIUS_M`
    about their body origin."""
    from mmusv.export.pcd import read_pcd

    d = Path(folder)
    cavs = sorted((c for c in d.iterdir() if c.is_dir() and c.name.isdigit()), key=lambda c: int(c.name))
    clouds = [p for c in cavs for p in c.glob("*.pcd")]
    odd = [p for p in clouds if not p.stem.isdigit()]
    if odd:  # int(stem) below was a bare ValueError
        raise IoError(f"{odd[0]}: not an OPV2V frame (a CAV's frames are <timestamp>.pcd and <timestamp>.yaml)")
    # the frames of the .yaml files too: one whose .pcd is gone is said below (a lone CAV's frame was dropped)
    stamps = sorted({p.stem for p in clouds} | {p.stem for c in cavs for p in c.glob("*.yaml") if p.stem.isdigit()})
    frames: list[SceneFrame] = []
    for ts in stamps:
        afs: list[AgentFrame] = []
        vehicles: dict[str, np.ndarray] = {}
        sizes: dict[str, np.ndarray] = {}
        usvs: set[str] = set()
        for c in cavs:
            y_path, p_path = c / f"{ts}.yaml", c / f"{ts}.pcd"
            if not (y_path.is_file() or p_path.is_file()):
                continue
            if not (y_path.is_file() and p_path.is_file()):  # the CAV was left out of the frame without a word
                have, lack = (y_path, p_path) if y_path.is_file() else (p_path, y_path)
                raise IoError(f"{lack}: missing beside {have.name}; an OPV2V frame of a CAV is a .pcd and a .yaml")
            try:
                doc = yaml.safe_load(y_path.read_text(encoding="utf-8"))
                xyz, inten = read_pcd(p_path)
                lidar = mirror_transform(carla_matrix(_opv2v_pose(doc, "lidar_pose")))
                body = mirror_transform(carla_matrix(_opv2v_pose(doc, "true_ego_pos")))
                # inside the try: a vehicle without a location or of 2 angles was a bare KeyError / ValueError
                for vid, (box, size) in _opv2v_vehicles(doc.get("vehicles") or {}).items():
                    vehicles[vid], sizes[vid] = box, size
                listed_usvs, waves = _opv2v_additional(c / f"{ts}_additional.yaml")
                usvs |= listed_usvs
            except (OSError, ValueError, KeyError, TypeError, AttributeError, yaml.YAMLError) as exc:
                why = " ".join(str(exc).split())  # a YAML error spans several lines
                raise IoError(f"{y_path}: not a readable OPV2V frame ({type(exc).__name__}: {why})") from None
            pts = np.column_stack([xyz[:, 0], -xyz[:, 1], xyz[:, 2], inten]).astype(np.float32)
            afs.append(AgentFrame(c.name, pts, body, invert(body) @ lidar, waves))
        if not afs:
            continue
        cavs_here = {a.id for a in afs}
        ids = sorted(k for k in vehicles if k not in cavs_here and k not in usvs)
        others = sorted(k for k in vehicles if k not in cavs_here and k in usvs)
        usv = np.stack([a.body for a in afs] + [vehicles[k] for k in others])
        cav_size = [2 * OPV2V_USV_RADIUS_M, 2 * OPV2V_USV_RADIUS_M, 5.0]
        frames.append(
            SceneFrame(
                frame=int(ts),
                agents=tuple(afs),
                target_ids=tuple(ids),
                targets=np.stack([vehicles[k] for k in ids]) if ids else np.zeros((0, 4, 4)),
                target_sizes=np.stack([sizes[k] for k in ids]) if ids else np.zeros((0, 3)),
                usv_boxes=usv,
                usv_sizes=np.array([cav_size] * len(afs) + [sizes[k] for k in others], dtype=np.float64),
            )
        )
    return SequenceData(d.name, tuple(frames))


def _opv2v_additional(path: Path) -> tuple[set[str], dict[str, float]]:
    """What the study reads of an OPV2V frame's ``<ts>_additional.yaml`` (mmusv's, beside the stock files): the ids
    of the vehicles it gives role ``usv`` and, by vehicle id, the share the waves hide of each from this CAV's LiDAR
    (its ``wave_occlusion``, as the recording's annotations give it; none where the file has no such number: a stock
    folder, an export made before the field). Neither without the file (a stock OPV2V folder) or for a mapping
    without an ``mmusv`` key (a file of that name that another tool wrote); mmusv's that is not such a document, or
    a file that is not a YAML mapping, raises as the frame's yaml does (``ValueError``, ``yaml.YAMLError``)."""
    if not path.is_file():
        return set(), {}
    doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    if isinstance(doc, dict) and "mmusv" not in doc:
        return set(), {}
    mm = doc.get("mmusv") if isinstance(doc, dict) else None
    listed = mm.get("vehicles") if isinstance(mm, dict) else None
    if not isinstance(listed, dict):
        raise ValueError(f"{path.name}: not mmusv's additional yaml (mmusv.vehicles: {{id: {{role, ...}}}})")
    usvs = {str(vid) for vid, v in listed.items() if isinstance(v, dict) and v.get("role") == "usv"}
    waves = {
        str(vid): float(v["wave_occlusion"])
        for vid, v in listed.items()
        if isinstance(v, dict)
        and isinstance(v.get("wave_occlusion"), (int, float))
        and not isinstance(v["wave_occlusion"], bool)
    }
    return usvs, waves


def _opv2v_pose(doc: Any, key: str) -> np.ndarray:
    """The CARLA pose ``doc[key]`` of an OPV2V frame (``lidar_pose``, ``true_ego_pos``); a ``ValueError`` naming
    ``key`` unless it is 6 finite numbers: a NaN pose dropped the frame's ground truth without a word, and a pose of
    another length was refused without naming the file."""
    pose = np.asarray(doc[key], dtype=np.float64)
    if pose.shape != (6,):
        raise ValueError(f"{key} = {reprlib.repr(doc[key])}: must be 6 numbers [x, y, z, roll, yaw, pitch]")
    if not np.isfinite(pose).all():
        raise ValueError(f"{key} = {pose.tolist()}: must be 6 finite numbers [x, y, z, roll, yaw, pitch]")
    return pose


def _opv2v_vehicles(doc: Any) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Vehicle id → (box pose in mmusv's frame, size ``2 * extent``) of an OPV2V frame's ``vehicles``; a
    ``ValueError`` naming the vehicle for a location, centre or angle that is not finite or an extent that is not
    finite and >= 0 (a NaN or negative box was scored without a word)."""
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for vid, v in doc.items():
        loc = np.asarray(v["location"], dtype=np.float64) + np.asarray(v["center"], dtype=np.float64)
        angle = np.asarray(v["angle"], dtype=np.float64)
        extent = np.asarray(v["extent"], dtype=np.float64)
        if loc.shape != (3,) or angle.shape != (3,) or extent.shape != (3,):
            raise ValueError(f"vehicles[{vid!r}]: location, center, angle and extent must be 3 numbers each")
        if not (np.isfinite(loc).all() and np.isfinite(angle).all()):
            raise ValueError(f"vehicles[{vid!r}]: location, center and angle must be finite numbers")
        if not (np.isfinite(extent).all() and (extent >= 0).all()):
            raise ValueError(f"vehicles[{vid!r}].extent = {extent.tolist()}: must be finite half-sizes >= 0 (metres)")
        roll, yaw, pitch = (float(x) for x in angle)
        box = mirror_transform(carla_matrix(np.array([loc[0], loc[1], loc[2], roll, yaw, pitch])))
        out[str(vid)] = (box, 2.0 * extent)
    return out


def check_split(split: str, seed: int) -> None:
    """Refuses a ``split`` other than ``train``, ``validate``, ``test`` or ``all``, and a negative ``seed`` where it
    seeds a split, each named as its user gave it (:func:`mmusv.text.given`: ``split = 'x'`` from Python, ``--split
    x`` from ``mmusv study`` and ``mmusv train``; a Python caller of :func:`split_sequences` was told of
    ``--split``, which it never gave). The CLIs ask before ``--generate``: both were refused only after the whole
    dataset had been generated and recorded."""
    from mmusv.export.splits import SPLIT_NAMES

    if split not in (*SPLIT_NAMES, "all"):
        raise InputError(f"{given('split', split)}: expected one of {', '.join((*SPLIT_NAMES, 'all'))}")
    if split != "all" and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise InputError(f"{given('seed', seed)}: the split's seed must be a whole number >= 0")


def split_sequences(names: Sequence[str], *, split: str, ratios: Sequence[float], seed: int) -> list[str]:
    """The names in ``split`` (``train``, ``validate``, ``test`` or ``all``), split by sequence with the seeded
    shuffle of :func:`mmusv.export.splits.assign_splits`, in sorted order."""
    from mmusv.export.splits import assign_splits

    check_split(split, seed)
    if split == "all":
        return sorted(names)
    sp = assign_splits(list(names), ratios=ratios, seed=seed)
    return sorted(n for n in names if sp[n] == split)


def iter_frames(seq: SequenceData) -> Iterator[SceneFrame]:
    """The frames of ``seq`` in order."""
    yield from seq.frames
