"""Cooperative consistency, checked as a perception researcher would before fusing two USVs' data: several USVs record
the same frozen scene at each acquisition index, and late, early and intermediate fusion (the OPV2V export read by
OpenCOOD, ``mmusv study detection``) move one USV's points and boxes into another's frame with the poses as written.
If those poses were wrong (a mount applied on the wrong side, a mirrored axis, a delay that pairs old points with the
current pose, pose noise of other units or axes than documented), the quays seen by one USV would not land on the
quays seen by the other. Everything here is an independent computation: poses from the world state through scipy's
``ZYX`` Euler angles, OPV2V poses through OpenCOOD's ``x_to_world`` written out here (``[x, y, z, roll, yaw, pitch]``
in degrees, left-handed; read in ``opencood/utils/transformation_utils.py`` of ``DerrickXuNu/OpenCOOD`` at
``31ba160``), the ``.pcd`` files parsed as text, and alignment measured as point-to-plane residuals between the two
USVs' clouds (each check also shows that a 0.3° or 0.5 m pose error would be seen).

One recording (module scope, 4 frames at 5 Hz, about 3 s): the bundled port map on the physical W3 sea (hulls roll
and pitch by degrees), two LiDAR-only USVs sailing 60-100 m apart in the east basin (``usv_a`` a WAM-V at 4 m/s,
``usv_b`` a 12 m patrol boat at 5 m/s, a metre a frame), both seeing the pier, the quays and three moored ships; a
20 m motor yacht crossing between them. Range noise is off, so that flat walls register to the millimetre.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.classes import SemanticClass
from mmusv.recording.decode import decode_point_cloud
from mmusv.recording.info import RecordingInfo, read_info
from mmusv.recording.stream import FrameStream
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

SCENARIO: dict[str, Any] = {
    "name": "coop_round",
    "seed": 5,
    "map": {"type": "port", "seed": 3},
    "environment": {"time_of_day": "12:00", "weather": "clear", "wave": "W3"},
    "acquisition": {"frequency_hz": 5, "frames": 4},
    "rigs": {
        "r": {
            "lidar": {"channels": 64, "points_per_second": 230400, "rotation_hz": 5, "range_noise_std_m": 0.0},
            "cameras": [],
        }
    },
    "vessels": [
        {"id": "usv_a", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 4.0,
         "route": [[320, 180], [320, 100]]},
        {"id": "usv_b", "role": "usv", "asset": "usv_patrol_12m", "rig": "r", "speed_mps": 5.0,
         "route": [[262, 100], [268, 170]]},
        {"id": "yacht", "role": "target", "asset": "motor_yacht_20m", "speed_mps": 3.0,
         "route": [[300, 60], [250, 40]]},
    ],
}  # fmt: skip

STRUCTURE = int(SemanticClass.PORT_STRUCTURE)
MIRROR = np.diag([1.0, -1.0, 1.0, 1.0])
"""mmusv (y left) ↔ CARLA (y right)."""


class Rec:
    """The recording read once: per frame index, the world state and each agent's decoded cloud."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.info: RecordingInfo = read_info(path)
        self.agents = {a.id: a for a in self.info.agents}
        self.world: dict[int, Any] = {}
        self.clouds: dict[tuple[int, str], dict[str, np.ndarray]] = {}
        self.annotations: dict[tuple[int, str], Any] = {}
        for fr in FrameStream(self.info, lambda _t: True):
            self.world[fr.index] = fr.world
            for a in self.info.agents:
                if a.lidar_mount is None:
                    continue
                self.clouds[fr.index, a.id] = decode_point_cloud(fr.messages[f"/{a.id}/lidar"])
                self.annotations[fr.index, a.id] = fr.messages[f"/{a.id}/annotations"]

    def body(self, frame: int, vessel: str) -> np.ndarray:
        """Body → world of ``vessel`` at ``frame`` from the world state's pose (scipy: intrinsic ZYX = yaw, pitch,
        roll, i.e. ``Rz(yaw)·Ry(pitch)·Rx(roll)``)."""
        w = self.world[frame]
        return _pose(w.poses[w.ids.index(vessel)])

    def lidar(self, frame: int, agent: str) -> np.ndarray:
        """LiDAR → world: the body pose times the recorded mount (LiDAR → body)."""
        mount = self.agents[agent].lidar_mount
        assert mount is not None
        out: np.ndarray = self.body(frame, agent) @ mount
        return out

    def points(self, frame: int, agent: str, cls: int | None = None) -> np.ndarray:
        """``(N, 3)`` the agent's points in its LiDAR frame (of semantic class ``cls`` if given)."""
        c = self.clouds[frame, agent]
        p = np.column_stack([c["x"], c["y"], c["z"]]).astype(np.float64)
        return p if cls is None else p[c["class"] == cls]


def _pose(eta: Any) -> np.ndarray:
    x, y, z, roll, pitch, yaw = (float(v) for v in eta)
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
    m[:3, 3] = [x, y, z]
    return m


def _move(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    out: np.ndarray = p @ m[:3, :3].T + m[:3, 3]
    return out


def _rz(deg: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("z", deg, degrees=True).as_matrix()
    return m


def _shift(v: list[float]) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = v
    return m


def plane_residuals(src: np.ndarray, dst: np.ndarray, *, k: int = 6, radius: float = 2.0) -> np.ndarray:
    """Point-to-plane distance (m) of each ``src`` point whose ``k`` nearest ``dst`` points lie within ``radius``:
    to the plane fitted (least squares, SVD) through those neighbours."""
    d, idx = cKDTree(dst).query(src, k=k, distance_upper_bound=radius)
    ok = np.isfinite(d).all(axis=1)
    q = dst[idx[ok]]  # (M, k, 3)
    c = q.mean(axis=1)
    normal = np.linalg.svd(q - c[:, None, :])[2][:, 2]
    out: np.ndarray = np.abs(np.einsum("ij,ij->i", src[ok] - c, normal))
    return out


def x_to_world(pose: list[float]) -> np.ndarray:
    """OpenCOOD's ``x_to_world``: a CARLA pose ``[x, y, z, roll, yaw, pitch]`` (metres, degrees) → ``(4, 4)``."""
    x, y, z, roll, yaw, pitch = pose
    cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    cr, sr = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    cp, sp = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    return np.array(
        [
            [cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr, x],
            [sy * cp, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr, y],
            [sp, -cp * sr, cp * cr, z],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def x1_to_x2(x1: list[float], x2: list[float]) -> np.ndarray:
    out: np.ndarray = np.linalg.inv(x_to_world(x2)) @ x_to_world(x1)
    return out


def read_ascii_pcd(path: Path) -> np.ndarray:
    """``(N, 3)`` the x, y, z columns of an ASCII PCD file, parsed here from its text."""
    lines = path.read_text(encoding="ascii").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("DATA")) + 1
    assert lines[start - 1] == "DATA ascii" and any(line == "FIELDS x y z rgb" for line in lines[:start])
    return np.array([[float(v) for v in line.split()[:3]] for line in lines[start:]], dtype=np.float64).reshape(-1, 3)


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Rec:
    from mmusv.acquire import run

    r = Rec(Path(run(SCENARIO, out_dir=tmp_path_factory.mktemp("coop")).recording))
    assert sorted(r.world) == [0, 1, 2, 3]
    return r


@pytest.fixture(scope="module")
def opv2v(rec: Rec, tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.export import convert

    out = tmp_path_factory.mktemp("coop_opv2v")
    convert(rec.path, to="opv2v", out_dir=out, splits=None, extras="", include_usvs=True)
    return out / "coop_round"


def _cav(rec: Rec, agent: str) -> str:
    return str(1000 + rec.agents[agent].index)


def _doc(folder: Path, cav: str, frame: int) -> dict[str, Any]:
    doc: dict[str, Any] = yaml.safe_load((folder / cav / f"{frame:06d}.yaml").read_text())
    return doc


# ---------------------------------------------------------------------------------------------- the recording


def test_static_structure_seen_by_each_usv_lands_on_the_other_s(rec: Rec) -> None:
    """The quays and the pier that ``usv_a`` sees, moved to the world with its pose as recorded (world state · LiDAR
    mount), lie on the surfaces ``usv_b``'s points of them span, and the other way round: point-to-plane residuals of
    millimetres on flat concrete, where a 0.3° heading error or a 0.5 m shift of one USV gives decimetres."""
    for f in rec.world:
        for a, b in (("usv_a", "usv_b"), ("usv_b", "usv_a")):
            pa, pb = rec.points(f, a, STRUCTURE), rec.points(f, b, STRUCTURE)
            wb = _move(rec.lidar(f, b), pb)
            res = plane_residuals(_move(rec.lidar(f, a), pa), wb)
            assert len(res) >= 150, (f, a, len(res))  # the two USVs see the same quay faces
            assert np.median(res) < 0.005 and np.percentile(res, 90) < 0.05, (f, a, np.percentile(res, [50, 90]))
            for wrong in (rec.lidar(f, a) @ _rz(0.3), _shift([0.5, 0.0, 0.0]) @ rec.lidar(f, a)):
                bad = plane_residuals(_move(wrong, pa), wb)
                assert np.median(bad) > 0.1, (f, a, np.median(bad))


def test_moored_ships_seen_by_each_usv_land_on_the_other_s(rec: Rec) -> None:
    """The moored ships (riding the W3 sea at their berths, frozen per frame like everything else) register across
    the two USVs as the quays do: a centimetre at the median on their curved hulls."""
    checked = 0
    for f in rec.world:
        w = rec.world[f]
        moored = [int(i) for i, r in zip(w.instance_ids, w.roles, strict=True) if r == "moored"]
        clouds = {}
        for ag in ("usv_a", "usv_b"):
            c = rec.clouds[f, ag]
            sel = np.isin(c["instance"], moored)
            clouds[ag] = _move(rec.lidar(f, ag), rec.points(f, ag)[sel])
        res = plane_residuals(clouds["usv_a"], clouds["usv_b"])
        assert len(res) > 500 and np.median(res) < 0.03, (f, len(res), np.median(res))
        checked += len(res)
    assert checked > 3000


def test_each_usv_s_box_of_a_vessel_is_one_world_box(rec: Rec) -> None:
    """Every vessel labelled by several USVs (``boxes_lidar`` of their annotations: centre, quaternion x, y, z, w,
    size), brought to the world with each labeller's LiDAR pose, is the same box, the world state's (its pose's
    rotation at its box centre), to float precision; the label's ``yaw`` is the heading of the box's x axis in the
    labeller's LiDAR xy plane."""
    shared = 0
    for f in rec.world:
        w = rec.world[f]
        seen: dict[str, list[np.ndarray]] = {}
        for ag in ("usv_a", "usv_b"):
            inv = np.linalg.inv(rec.lidar(f, ag))
            for b in rec.annotations[f, ag].boxes_lidar:
                m = np.eye(4)
                m[:3, :3] = Rotation.from_quat(list(b.rotation)).as_matrix()
                m[:3, 3] = list(b.center)
                world = rec.lidar(f, ag) @ m
                seen.setdefault(b.target_id, []).append(world)
                i = w.ids.index(b.target_id)
                truth = rec.body(f, b.target_id)
                truth[:3, 3] = w.box_centers[i]
                np.testing.assert_allclose(world[:3, 3], truth[:3, 3], atol=1e-6)
                np.testing.assert_allclose(world[:3, :3], truth[:3, :3], atol=1e-7)
                np.testing.assert_allclose(list(b.size), w.box_sizes[i], atol=1e-9)
                heading = (inv @ truth)[:3, 0]
                assert abs(math.remainder(math.atan2(heading[1], heading[0]) - b.yaw, math.tau)) < 1e-7
        for boxes in seen.values():
            for other in boxes[1:]:
                np.testing.assert_allclose(other, boxes[0], atol=1e-6)
                shared += 1
    assert shared >= 4 * 4  # the yacht and three moored ships, in every frame


def test_a_vessel_s_points_from_either_usv_lie_in_either_usv_s_tilted_box(rec: Rec) -> None:
    """The points of a vessel (by instance id) from each USV, moved into the other USV's LiDAR frame, lie inside the
    box that other USV labelled (its full rotation: the hulls roll and pitch by degrees at W3), within 5 cm."""
    n = 0
    for f in rec.world:
        for src in ("usv_a", "usv_b"):
            c = rec.clouds[f, src]
            for lab in ("usv_a", "usv_b"):
                to_lab = np.linalg.inv(rec.lidar(f, lab)) @ rec.lidar(f, src)
                for b in rec.annotations[f, lab].boxes_lidar:
                    pts = rec.points(f, src)[c["instance"] == b.instance_id]
                    if not len(pts):
                        continue
                    r = Rotation.from_quat(list(b.rotation)).as_matrix()
                    local = (_move(to_lab, pts) - np.array(list(b.center))) @ r
                    excess = np.max(np.abs(local) - np.array(list(b.size)) / 2.0, axis=1)
                    assert excess.max() < 0.05, (f, src, lab, b.target_id, float(excess.max()))
                    n += len(pts) * (src != lab)
    assert n > 3000  # points checked in the other USV's boxes


# ---------------------------------------------------------------------------------------------- the OPV2V export


def test_opv2v_clouds_moved_with_x1_to_x2_register_their_static_structure(rec: Rec, opv2v: Path) -> None:
    """OpenCOOD's early fusion moves a CAV's ``.pcd`` into the ego's with ``x1_to_x2(cav lidar_pose, ego
    lidar_pose)``: done here on the files, the pier and quays of one CAV land on the other's (the structure points
    picked by the recording's class column: the ``.pcd`` keeps the recording's point order)."""
    for f in rec.world:
        for a, b in (("usv_a", "usv_b"), ("usv_b", "usv_a")):
            ca, cb = _cav(rec, a), _cav(rec, b)
            pa = read_ascii_pcd(opv2v / ca / f"{f:06d}.pcd")
            pb = read_ascii_pcd(opv2v / cb / f"{f:06d}.pcd")
            assert len(pa) == len(rec.clouds[f, a]["x"]) and len(pb) == len(rec.clouds[f, b]["x"])
            sa = pa[rec.clouds[f, a]["class"] == STRUCTURE]
            sb = pb[rec.clouds[f, b]["class"] == STRUCTURE]
            m = x1_to_x2(_doc(opv2v, ca, f)["lidar_pose"], _doc(opv2v, cb, f)["lidar_pose"])
            res = plane_residuals(_move(m, sa), sb)
            assert len(res) >= 150 and np.median(res) < 0.005 and np.percentile(res, 90) < 0.05, (
                f,
                a,
                np.percentile(res, [50, 90]),
            )
            bad = plane_residuals(_move(m @ _rz(0.3), sa), sb)
            assert np.median(bad) > 0.1


def test_opv2v_lidar_pose_is_true_ego_pos_times_the_fixed_mount(rec: Rec, opv2v: Path) -> None:
    """``x_to_world(true_ego_pos)⁻¹ · x_to_world(lidar_pose)`` is the LiDAR's mount on the hull (mirrored to CARLA's
    axes) in every frame, however the hull rolls: the two poses of a yaml describe one rigid body; and
    ``lidar_pose`` is the recording's LiDAR pose (to the export's 6 decimals)."""
    for ag, info in rec.agents.items():
        assert info.lidar_mount is not None
        for f in rec.world:
            doc = _doc(opv2v, _cav(rec, ag), f)
            mount = np.linalg.inv(x_to_world(doc["true_ego_pos"])) @ x_to_world(doc["lidar_pose"])
            np.testing.assert_allclose(MIRROR @ mount @ MIRROR, info.lidar_mount, atol=5e-6)
            np.testing.assert_allclose(MIRROR @ x_to_world(doc["lidar_pose"]) @ MIRROR, rec.lidar(f, ag), atol=5e-6)


def test_opv2v_timestamps_are_one_instant_for_every_cav(rec: Rec, opv2v: Path) -> None:
    """docs/exports.md: one file set per acquisition index ``<ts>``, the same for every agent, taken at ``<ts>`` /
    ``frequency_hz`` s: each CAV has the same timestamps, its ``_additional.yaml`` says that frame and time, and
    ``data_protocol.yaml`` gives the step OpenCOOD's delay would need (``fixed_delta_seconds`` = 1 / 5 Hz)."""
    stamps = {ag: sorted(p.stem for p in (opv2v / _cav(rec, ag)).glob("*.pcd")) for ag in ("usv_a", "usv_b")}
    assert stamps["usv_a"] == stamps["usv_b"] == [f"{f:06d}" for f in sorted(rec.world)]
    for ag in stamps:
        for f in rec.world:
            add = yaml.safe_load((opv2v / _cav(rec, ag) / f"{f:06d}_additional.yaml").read_text())["mmusv"]
            assert add["agent"] == ag and add["frame"] == f
            assert add["time_s"] == pytest.approx(f / 5.0, abs=1e-9) == pytest.approx(rec.world[f].time_s, abs=1e-9)
    protocol = yaml.safe_load((opv2v / "data_protocol.yaml").read_text())
    assert protocol["world"]["fixed_delta_seconds"] == pytest.approx(0.2)


def test_opv2v_a_cav_listed_by_another_is_where_it_says_it_is(rec: Rec, opv2v: Path) -> None:
    """With ``include_usvs``, each CAV lists the other as a vehicle under its CAV id: that entry's ``location`` and
    ``angle`` are the other CAV's ``true_ego_pos`` of the same timestamp, and its box (``location + center`` with
    ``angle``) is the world state's box of that USV; every vessel listed by both CAVs is the same box in both."""
    for f in rec.world:
        docs = {ag: _doc(opv2v, _cav(rec, ag), f) for ag in ("usv_a", "usv_b")}
        for a, b in (("usv_a", "usv_b"), ("usv_b", "usv_a")):
            v = docs[a]["vehicles"][int(_cav(rec, b))]
            np.testing.assert_allclose(v["location"], docs[b]["true_ego_pos"][:3], atol=2e-6)
            np.testing.assert_allclose(v["angle"], docs[b]["true_ego_pos"][3:], atol=2e-6)
            box = MIRROR @ x_to_world([v["location"][i] + v["center"][i] for i in range(3)] + v["angle"]) @ MIRROR
            w = rec.world[f]
            truth = rec.body(f, b)
            truth[:3, 3] = w.box_centers[w.ids.index(b)]
            np.testing.assert_allclose(box, truth, atol=5e-6)
        both = set(docs["usv_a"]["vehicles"]) & set(docs["usv_b"]["vehicles"])
        assert len(both) >= 4  # the yacht and three moored ships
        for vid in both:
            assert docs["usv_a"]["vehicles"][vid] == docs["usv_b"]["vehicles"][vid]


def test_the_study_reads_the_same_poses_from_the_recording_and_from_opv2v(rec: Rec, opv2v: Path) -> None:
    """``mmusv study detection`` on the recording and on its OPV2V export (``--opv2v``) gets the same LiDAR poses
    and the same world boxes of the vessels the CAVs list: the OPV2V reader undoes the mirror and the degrees."""
    from mmusv.studies.detection.data import read_opv2v, read_recording

    a, b = read_recording(rec.path), read_opv2v(opv2v)
    assert [f.frame for f in a.frames] == [f.frame for f in b.frames] == [0, 1, 2, 3]
    ids = {_cav(rec, ag): ag for ag in rec.agents}
    for fa, fb in zip(a.frames, b.frames, strict=True):
        for x, y in zip(fa.agents, fb.agents, strict=True):
            assert ids[y.id] == x.id
            np.testing.assert_allclose(y.lidar, x.lidar, atol=5e-6)
            np.testing.assert_allclose(x.lidar, rec.lidar(fa.frame, x.id), atol=1e-9)
        names = {str(1000 + rec.world[fa.frame].ids.index(t)): k for k, t in enumerate(fa.target_ids)}
        assert set(fb.target_ids) <= set(names) and len(fb.target_ids) >= 4
        for k, vid in enumerate(fb.target_ids):
            np.testing.assert_allclose(fb.targets[k], fa.targets[names[vid]], atol=5e-6)
            np.testing.assert_allclose(fb.target_sizes[k], fa.target_sizes[names[vid]], atol=2e-6)


# ---------------------------------------------------------------------------------------------- delay and pose noise


def _structure_only(rec: Rec) -> Any:
    """The study's sequence of the recording with every cloud cut to its port-structure points."""
    from mmusv.studies.detection.data import SequenceData, read_recording

    seq = read_recording(rec.path)
    frames = []
    for fr in seq.frames:
        agents = tuple(replace(a, points=a.points[rec.clouds[fr.frame, a.id]["class"] == STRUCTURE]) for a in fr.agents)
        frames.append(replace(fr, agents=agents))
    return SequenceData(seq.name, tuple(frames))


@pytest.mark.parametrize("delay", [1, 2, 3])
def test_a_delayed_neighbour_s_cloud_comes_with_its_pose_of_then(rec: Rec, delay: int) -> None:
    """``delay:k`` (docs/studies/detection.md, *Robustness*): the neighbour's points and pose of the frame k earlier.
    The study's early-fusion aggregate (``early_points``) then still puts the neighbour's quays on the ego's current
    quays (the quays do not move; a neighbour sailing a metre a frame would put them metres off if its old cloud
    came with its current pose: then not a tenth as many points register, which is checked too); the points are the
    recording's cloud of frame f − k and the pose its world-state pose of then."""
    from mmusv.studies.detection.fusion import early_points
    from mmusv.studies.detection.robustness import Setting, neighbours_for

    seq = _structure_only(rec)
    for t, fr in enumerate(seq.frames):
        if fr.frame < delay:
            continue
        for ego in fr.agents:
            (nb,) = neighbours_for(seq, t, ego.id, Setting(delay_frames=delay), seed=0)
            then = fr.frame - delay
            np.testing.assert_array_equal(nb.points[:, :3], rec.points(then, nb.id, STRUCTURE).astype(np.float32))
            np.testing.assert_allclose(nb.lidar, rec.lidar(then, nb.id), atol=1e-9)
            alone = replace(ego, points=ego.points[:0])
            got = early_points(alone, [nb], crop_m=1e4)[:, :3].astype(np.float64)
            res = plane_residuals(got, rec.points(fr.frame, ego.id, STRUCTURE))
            assert len(res) >= 100 and np.median(res) < 0.005, (fr.frame, ego.id, np.median(res))
            now_pose = next(a for a in fr.agents if a.id == nb.id).body
            wrong = early_points(alone, [replace(nb, body=now_pose)], crop_m=1e4)[:, :3].astype(np.float64)
            bad = plane_residuals(wrong, rec.points(fr.frame, ego.id, STRUCTURE))
            assert (bad < 0.02).sum() < 0.1 * (res < 0.02).sum(), (fr.frame, ego.id, (bad < 0.02).sum())


def test_late_fusion_under_delay_places_the_neighbour_s_old_boxes_with_its_old_pose(rec: Rec) -> None:
    """Late fusion under ``delay:2`` with an oracle detector (each USV's own labelled boxes, the ego's none): what the
    ego receives is each vessel's box of two frames earlier (world state of then) seen from the ego's *current* LiDAR
    frame, to float precision (the heading: the labelled yaw, level in the neighbour's LiDAR frame of then, turned
    into the ego's; within 0.03 rad of the tilted hull's own heading there, all a yaw-only box can carry between two
    tilted frames): the moving yacht lags by its own motion, nothing else moves."""
    from mmusv.studies.detection.data import read_recording
    from mmusv.studies.detection.fusion import fuse
    from mmusv.studies.detection.robustness import Setting, neighbours_for

    seq = read_recording(rec.path)
    labels: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for fr in seq.frames:
        for a in fr.agents:
            boxes = [
                [*b.center, *b.size, b.yaw]
                for b in rec.annotations[fr.frame, a.id].boxes_lidar
                if b.target_id not in rec.agents
            ]
            labels[id(a.points)] = (np.array(boxes, dtype=np.float64).reshape(-1, 7), np.full(len(boxes), 0.9))

    def oracle(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return labels[id(points)]

    checked = 0
    for t, fr in enumerate(seq.frames):
        if fr.frame < 2:
            continue
        for ego in fr.agents:
            nbs = neighbours_for(seq, t, ego.id, Setting(delay_frames=2), seed=0)

            def own(a: Any, ego_points: np.ndarray = ego.points) -> tuple[np.ndarray, np.ndarray]:
                return (np.zeros((0, 7)), np.zeros(0)) if a.points is ego_points else oracle(a.points)

            boxes, _ = fuse("late", ego, nbs, detector=oracle, own_detections=own)
            (nb,) = nbs
            then = fr.frame - 2
            want = {}
            for b in rec.annotations[then, nb.id].boxes_lidar:
                if b.target_id in rec.agents:
                    continue
                w = rec.world[then]
                box = rec.body(then, b.target_id)
                box[:3, 3] = w.box_centers[w.ids.index(b.target_id)]
                to_ego = np.linalg.inv(rec.lidar(fr.frame, ego.id))
                m = to_ego @ box
                # the labelled yaw's heading, level in the neighbour's LiDAR frame of then, seen from the ego now
                h = (to_ego @ rec.lidar(then, nb.id))[:3, :3] @ [math.cos(b.yaw), math.sin(b.yaw), 0.0]
                want[b.target_id] = [*m[:3, 3], math.atan2(h[1], h[0]), math.atan2(m[1, 0], m[0, 0])]
            assert len(boxes) == len(want) >= 2
            for got in boxes:
                best = min(want.values(), key=lambda v: float(np.hypot(v[0] - got[0], v[1] - got[1])))
                np.testing.assert_allclose(got[:3], best[:3], atol=1e-6)
                assert abs(math.remainder(got[6] - best[3], math.tau)) < 1e-6
                # a 7-number box keeps only the heading in its own LiDAR's xy plane: turned into the ego's tilted
                # frame, it differs from the tilted hull's own heading there at second order in the tilts
                assert abs(math.remainder(got[6] - best[4], math.tau)) < 0.03
                checked += 1
    assert checked >= 8


def test_pose_noise_has_the_documented_sigmas_on_the_documented_axes(rec: Rec) -> None:
    """``noise:σxyz/σrpy`` with σxyz ≠ σrpy (the test with 1 m / 1° could not tell them apart): over 300 seeds the
    neighbour's body pose moves by zero-mean draws of σxyz metres on x, y, z and σrpy degrees on roll, pitch and yaw,
    independent across axes; its mount and points are untouched."""
    from mmusv.studies.detection.data import read_recording
    from mmusv.studies.detection.robustness import neighbours_for, parse_settings

    seq = read_recording(rec.path)
    (s,) = [x for x in parse_settings("noise:2/0.5") if x.kind == "noise"]
    fr = seq.frames[1]
    clean = {a.id: a for a in fr.agents}
    draws = []
    for seed in range(300):
        (nb,) = neighbours_for(seq, 1, "usv_a", s, seed=seed)
        assert nb.id == "usv_b" and nb.points is clean["usv_b"].points
        np.testing.assert_array_equal(nb.mount, clean["usv_b"].mount)
        a = Rotation.from_matrix(nb.body[:3, :3]).as_euler("ZYX")[::-1]
        b = Rotation.from_matrix(clean["usv_b"].body[:3, :3]).as_euler("ZYX")[::-1]
        turn = np.remainder(a - b + math.pi, math.tau) - math.pi
        draws.append([*(nb.body[:3, 3] - clean["usv_b"].body[:3, 3]), *np.degrees(turn)])
    d = np.array(draws)
    assert np.all(np.abs(d.mean(axis=0)) < 3 * np.array([2, 2, 2, 0.5, 0.5, 0.5]) / math.sqrt(300))
    np.testing.assert_allclose(d.std(axis=0), [2, 2, 2, 0.5, 0.5, 0.5], rtol=0.12)
    corr = np.corrcoef(d.T) - np.eye(6)
    assert np.abs(corr).max() < 0.2


def test_a_usv_without_lidar_listed_in_opv2v_is_a_platform_for_the_study_not_a_target(tmp_path: Path) -> None:
    """Ground truth is every vessel but the instrumented USVs (docs/studies/detection.md), from a recording and from
    its OPV2V export alike. A USV with cameras but no LiDAR is no CAV of the export, and ``--include-usvs`` lists it
    among the CAVs' ``vehicles`` (``_additional.yaml``: role ``usv``): the study read it from OPV2V as a target, which
    the recording's reading never does, so a detection of it scored as a true positive from OPV2V and was ignored
    from the recording. Read from either, it is a USV platform (its box, where detections are ignored), not ground
    truth."""
    import copy

    from mmusv.acquire import run
    from mmusv.export import convert
    from mmusv.studies.detection.data import read_opv2v, read_recording

    sc = copy.deepcopy(SCENARIO)
    sc["name"], sc["acquisition"]["frames"] = "coop_camera_usv", 1
    camera = {"name": "front", "resolution": [32, 24], "hfov_deg": 90, "mount": {"point": "camera_front"}}
    sc["rigs"]["camera_only"] = {"lidar": None, "cameras": [camera]}
    sc["vessels"].append(
        {"id": "usv_c", "role": "usv", "asset": "usv_wamv", "rig": "camera_only", "speed_mps": 2.0,
         "route": [[290, 120], [290, 160]]}
    )  # fmt: skip
    rec = Path(run(sc, out_dir=tmp_path / "rec").recording)
    convert(rec, to="opv2v", out_dir=tmp_path / "opv2v", splits=None, extras="", include_usvs=True)
    a, b = read_recording(rec).frames[0], read_opv2v(tmp_path / "opv2v" / "coop_camera_usv").frames[0]
    w = Rec(rec).world[0]
    listed = {w.ids[int(t) - 1000] for t in b.target_ids}
    assert "usv_c" not in listed and "yacht" in listed and listed <= set(a.target_ids), listed
    # usv_c's box is among the platforms, as the recording's reading has it (the third of its USV boxes)
    assert [v for v, r in zip(w.ids, w.roles, strict=True) if r == "usv"] == ["usv_a", "usv_b", "usv_c"]
    c = next(k for k, m in enumerate(b.usv_boxes) if np.allclose(m[:3, 3], a.usv_boxes[2][:3, 3], atol=1e-5))
    np.testing.assert_allclose(b.usv_boxes[c], a.usv_boxes[2], atol=1e-5)
    np.testing.assert_allclose(b.usv_sizes[c], a.usv_sizes[2], atol=1e-5)
