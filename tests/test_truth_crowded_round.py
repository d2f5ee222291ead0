"""The ground truth of a crowded harbour, re-derived as a perception researcher would before training on it: from the
world state, the asset catalogue's meshes, the cameras' intrinsics and mounts, the instance and semantic images and
the LiDAR points, never from the annotation code.

One recording (module-scoped, 3 frames at 5 Hz, about 5 s): the port map (seed 3, four ships moored at its quays and
piers, one of them behind a pier as the USVs see it) on a W0 sea, two USVs (a 12 m patrol boat with a 200 m LiDAR and
a WAM-V with a 60 m one) running side by side 0.6 m apart, each with a 32-channel LiDAR and four 160 × 120 pinhole
cameras, a 3 m jet ski 1 m off the patrol boat's bow, a 4.5 m RIB close astern, a 32 m tug with a 5 m speedboat
alongside it (1 m between the hulls), a yacht at anchor (speed 0) and a 300 m cruise ship whose centre lies beyond
200 m while its stern comes within it. So each camera sees the other USV's hull so close that its box reaches behind
the camera, hulls cut by the image border, vessels hidden by a pier, by each other and by the other USV, and its own
hull.
"""

from __future__ import annotations

import csv
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.classes import SemanticClass
from mmusv.recording.decode import WorldFrame, decode_image, decode_point_cloud
from mmusv.recording.info import AgentInfo, RecordingInfo, read_info
from mmusv.recording.stream import Frame, FrameStream
from mmusv.scene import Scene
from mmusv.world.maps import generate_port
from mmusv.world.vessels import get_asset
from scipy.spatial.transform import Rotation

RANGE_M = 200.0  # the exports' default target range (``--range``), and the patrol boat's LiDAR's (its default)
SHORT_M = 60.0  # the WAM-V's LiDAR's range: the reach of its 3D boxes
CAMS = ("front", "left", "right", "rear")
W, H = 160, 120


def _rig(**lidar: Any) -> dict[str, Any]:
    cams = [{"name": n, "resolution": [W, H], "hfov_deg": 90, "mount": {"point": f"camera_{n}"}} for n in CAMS]
    return {
        "lidar": {"channels": 32, "points_per_second": 57600, "rotation_hz": 5, "range_noise_std_m": 0.0, **lidar},
        "cameras": cams,
    }


SCENARIO: dict[str, Any] = {
    "name": "crowded",
    "seed": 6,
    "map": {"type": "port", "seed": 3},
    "environment": {"time_of_day": "12:00", "weather": "clear", "wave": "W0"},
    "acquisition": {"frequency_hz": 5, "frames": 3},
    "rigs": {"r": _rig(), "short": _rig(range_m=SHORT_M)},
    "vessels": [
        {"id": "ego", "role": "usv", "asset": "usv_patrol_12m", "rig": "r", "speed_mps": 2.0,
         "route": [[330, 120], [330, 170]]},
        {"id": "usv2", "role": "usv", "asset": "usv_wamv", "rig": "short", "speed_mps": 2.0,
         "route": [[333.8, 118], [333.8, 168]]},
        {"id": "jetski", "role": "target", "asset": "jet_ski_3m", "speed_mps": 2.0,
         "route": [[330, 130.5], [330, 180]]},
        {"id": "rib", "role": "target", "asset": "rib_4_5m", "speed_mps": 2.0, "route": [[325.5, 112], [325.5, 160]]},
        {"id": "tug", "role": "target", "asset": "tug_32m", "speed_mps": 1.0, "route": [[260, 120], [260, 160]]},
        {"id": "boat", "role": "target", "asset": "speedboat_5m", "speed_mps": 1.0,
         "route": [[268, 125], [268, 165]]},
        {"id": "cruise", "role": "target", "asset": "cruise_ship_300m", "speed_mps": 1.0,
         "route": [[100, 40], [200, 40]]},
        {"id": "anchored", "role": "target", "asset": "sailing_yacht_12m", "speed_mps": 0.0,
         "route": [[300, 100], [300, 110]]},
    ],
}  # fmt: skip

SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
BODY_TO_OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # x right, y down, z forward


class Rec:
    """The recording, read once: its path, info and frames."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.info: RecordingInfo = read_info(path)
        self.frames: list[Frame] = list(FrameStream(self.info, lambda _t: True))


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Rec:
    from mmusv.acquire import run

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the route checks warn of the hulls this close on purpose
        res = run(SCENARIO, out_dir=tmp_path_factory.mktemp("crowded"))
    r = Rec(Path(res.recording))
    assert len(r.frames) == 3 and [a.id for a in r.info.agents] == ["ego", "usv2"]
    return r


# --- independent geometry ------------------------------------------------------------------------------------------


def _pose(w: WorldFrame, i: int) -> np.ndarray:
    """Vessel ``i``'s body → world from its world-state ``[x, y, z, roll, pitch, yaw]`` (yaw, then pitch, then roll
    about the body's axes)."""
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("xyz", w.poses[i][3:]).as_matrix()
    m[:3, 3] = w.poses[i][:3]
    return m


def _mesh_box(asset: str) -> tuple[np.ndarray, np.ndarray]:
    """The catalogue mesh's axis-aligned box in its body frame: ``(size, centre)``, metres."""
    v = np.asarray(get_asset(asset).mesh.vertices, dtype=np.float64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    return hi - lo, (hi + lo) / 2.0


def _box_world(w: WorldFrame, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Vessel ``i``'s 3D box: ``(box → world (4, 4), size (3,))`` from its pose and its mesh's extent."""
    size, centre = _mesh_box(w.assets[i])
    m = _pose(w, i)
    m[:3, 3] = m[:3, :3] @ centre + m[:3, 3]
    return m, size


def _corners(box: np.ndarray, size: np.ndarray) -> np.ndarray:
    out: np.ndarray = (SIGNS * size / 2.0) @ box[:3, :3].T + box[:3, 3]
    return out


def _sensor_poses(agent: AgentInfo, w: WorldFrame) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    body = _pose(w, agent.index)
    assert agent.lidar_mount is not None
    return body @ agent.lidar_mount, {n: body @ c.mount for n, c in agent.cameras.items()}


def _footprint_distance(box_in_lidar: np.ndarray, size: np.ndarray) -> float:
    """BEV distance from the LiDAR (origin) to the box's footprint, a ``length × beam`` rectangle turned by its yaw."""
    c = box_in_lidar[:3, 3]
    yaw = np.arctan2(box_in_lidar[1, 0], box_in_lidar[0, 0])
    u = np.array([np.cos(yaw), np.sin(yaw)])
    n = np.array([-u[1], u[0]])
    du = max(abs(c[:2] @ u) - size[0] / 2.0, 0.0)
    dv = max(abs(c[:2] @ n) - size[1] / 2.0, 0.0)
    return float(np.hypot(du, dv))


def _pixel_rays(agent: AgentInfo, name: str, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World origin and unit directions of the rays through every pixel centre of a pinhole camera, row-major."""
    fx, fy, cx, cy = agent.cameras[name].intrinsics
    v, u = np.mgrid[0:H, 0:W]
    opt = np.column_stack([(u.ravel() + 0.5 - cx) / fx, (v.ravel() + 0.5 - cy) / fy, np.ones(H * W)])
    d = (opt @ BODY_TO_OPTICAL) @ pose[:3, :3].T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.broadcast_to(pose[:3, 3], d.shape).copy(), d


def _slab_hits(o: np.ndarray, d: np.ndarray, box: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Which rays meet the oriented box at a positive distance (the slab test in the box's frame)."""
    inv = np.linalg.inv(box)
    lo_ = o @ inv[:3, :3].T + inv[:3, 3]
    ld = d @ inv[:3, :3].T
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-size / 2.0 - lo_) / ld
        t2 = (size / 2.0 - lo_) / ld
    tmin = np.nanmax(np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2)), axis=1)
    tmax = np.nanmin(np.where(np.isnan(t2), np.inf, np.maximum(t1, t2)), axis=1)
    out: np.ndarray = (tmax >= np.maximum(tmin, 0.0)) & (tmax > 0.0)
    return out


_ALONE: dict[str, Scene] = {}


def _alone_distance(asset: str, pose: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Distance along each ray to the vessel ``asset`` at ``pose``, alone in an otherwise empty scene (inf: miss)."""
    if asset not in _ALONE:
        a = get_asset(asset)
        s = Scene()
        s.add_instance(s.add_mesh(a.mesh.vertices, a.mesh.faces, name=asset))
        _ALONE[asset] = s
    s = _ALONE[asset]
    s.set_poses([0], pose[None])
    return np.asarray(s.cast_rays(o, d).distance, dtype=np.float64)


def _images(f: Frame, agent: str, cam: str) -> tuple[np.ndarray, np.ndarray]:
    inst = decode_image(f.messages[f"/{agent}/camera/{cam}/instance"]).astype(np.int64)
    sem = decode_image(f.messages[f"/{agent}/camera/{cam}/semantic"]).astype(np.int64)
    return inst, sem


def _targets_by_centre(w: WorldFrame, agent: AgentInfo, range_m: float = RANGE_M) -> set[str]:
    """The exports' targets (OPV2V, KITTI): non-USV vessels whose box centre lies within ``range_m``, BEV."""
    lidar, _ = _sensor_poses(agent, w)
    inv = np.linalg.inv(lidar)
    out = set()
    for i, vid in enumerate(w.ids):
        if i == agent.index or w.roles[i] == "usv":
            continue
        c = inv[:3, :3] @ _box_world(w, i)[0][:3, 3] + inv[:3, 3]
        if np.hypot(c[0], c[1]) <= range_m:
            out.add(vid)
    return out


# --- the checks ----------------------------------------------------------------------------------------------------


def test_the_scene_holds_the_awkward_cases(rec: Rec) -> None:
    """What the checks below rely on: four moored ships at the map's own berths (the map generated here, not read
    from the recording), riding there; the USVs' hulls 0.6 m apart; the tug and speedboat 1 m apart; the cruise
    ship's centre beyond the range with its footprint within it; a 3 m and a 300 m hull; every vessel under one id
    and one instance id, the same in every frame."""
    w = rec.frames[0].world
    assert w is not None
    berths = generate_port(seed=3).moored
    moored = [i for i, r in enumerate(w.roles) if r == "moored"]
    assert len(moored) == len(berths) == 4
    for i, (asset, (x, y, yaw)) in zip(moored, berths, strict=True):
        assert w.assets[i] == asset
        assert np.hypot(w.poses[i][0] - x, w.poses[i][1] - y) < 1.0
        assert abs((w.poses[i][5] - yaw + np.pi) % (2 * np.pi) - np.pi) < np.radians(3)
    ix = {v: w.ids.index(v) for v in ("ego", "usv2", "tug", "boat", "cruise", "jetski")}
    beam = {v: _mesh_box(w.assets[i])[0][1] for v, i in ix.items()}
    gap = abs(w.poses[ix["usv2"]][0] - w.poses[ix["ego"]][0]) - (beam["ego"] + beam["usv2"]) / 2
    assert 0.0 < gap < 1.0
    gap = abs(w.poses[ix["boat"]][0] - w.poses[ix["tug"]][0]) - (beam["tug"] + beam["boat"]) / 2
    assert 0.0 < gap < 1.5
    ego = rec.info.agents[0]
    lidar, _ = _sensor_poses(ego, w)
    box, size = _box_world(w, ix["cruise"])
    rel = np.linalg.inv(lidar) @ box
    assert np.hypot(*rel[:2, 3]) > RANGE_M > _footprint_distance(rel, size)
    assert _mesh_box("jet_ski_3m")[0][0] == pytest.approx(3.0) and _mesh_box("cruise_ship_300m")[0][0] == 300.0
    # every vessel once, under the same id, instance, asset and role in every frame
    assert len(set(w.ids)) == len(w.ids) and len(set(w.instance_ids.tolist())) == len(w.ids)
    for f in rec.frames[1:]:
        assert f.world is not None
        assert (f.world.ids, f.world.assets, f.world.roles) == (w.ids, w.assets, w.roles)
        assert np.array_equal(f.world.instance_ids, w.instance_ids)


def test_every_vessel_in_range_has_one_3d_and_bev_box_from_the_catalogue(rec: Rec) -> None:
    """Per agent and frame: a 3D box for every other vessel (moored ones, the other USV and the 300 m ship whose
    centre is out of range included) whose footprint comes within the agent's own LiDAR range of it (200 m for the
    patrol boat, 60 m for the WAM-V, read from the recorded rig), none other, none twice, the agent never; its
    centre, size and rotation those of the catalogue mesh's extent at the world-state pose, in the LiDAR frame
    (1e-6); its instance and class the world state's; ``lidar_points`` the points carrying its instance; the BEV box
    the 3D box's x, y, length, beam and yaw."""
    seen_moored = set()
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            lidar, _ = _sensor_poses(agent, w)
            inv = np.linalg.inv(lidar)
            ann = f.messages[f"/{agent.id}/annotations"]
            pts = np.asarray(decode_point_cloud(f.messages[f"/{agent.id}/lidar"])["instance"])
            got = [b.target_id for b in ann.boxes_lidar]
            assert len(got) == len(set(got)) and agent.id not in got
            want = set()
            for i, vid in enumerate(w.ids):
                if i == agent.index:
                    continue
                box, size = _box_world(w, i)
                rel = inv @ box
                if _footprint_distance(rel, size) <= agent.rig["lidar"]["range_m"]:
                    want.add(vid)
                if vid not in got:
                    continue
                b = ann.boxes_lidar[got.index(vid)]
                assert np.allclose(list(b.center), rel[:3, 3], atol=1e-6), (f.index, agent.id, vid)
                assert np.allclose(list(b.size), size, atol=1e-6), (f.index, agent.id, vid)
                q = Rotation.from_quat(list(b.rotation)).as_matrix()
                assert np.allclose(q, rel[:3, :3], atol=1e-6), (f.index, agent.id, vid)
                assert b.yaw == pytest.approx(np.arctan2(rel[1, 0], rel[0, 0]), abs=1e-9)
                assert (b.instance_id, b.semantic_class) == (w.instance_ids[i], w.classes[i])
                assert b.lidar_points == int(np.count_nonzero(pts == w.instance_ids[i]))
                if w.roles[i] == "moored":
                    seen_moored.add(vid)
            assert set(got) == want, (f.index, agent.id, sorted(set(got) ^ want))
            assert ("cruise" in got) == (agent.id == "ego")  # its stern is within 200 m, not within 60 m
            bev = [(b.target_id, b.x, b.y, b.length, b.width, b.yaw) for b in ann.boxes_bev]
            assert bev == [
                (b.target_id, b.center[0], b.center[1], b.size[0], b.size[1], b.yaw) for b in ann.boxes_lidar
            ]
            assert int(np.count_nonzero(pts == w.instance_ids[agent.index])) == 0  # its own hull: no LiDAR point
    assert len(seen_moored) >= 3


def test_the_tables_are_the_messages_and_flag_the_moored_ships_static(rec: Rec) -> None:
    """The Parquet tables a researcher reads instead of the MCAP hold the same boxes, row for row; the moored ships
    (role ``moored``) and the scenario's anchored yacht (speed 0) are ``static``, the moving vessels are not."""
    import polars as pl

    w0 = rec.frames[0].world
    assert w0 is not None
    still = {v["id"] for v in rec.info.scenario["vessels"] if v["speed_mps"] == 0}
    still |= {v for v, r in zip(w0.ids, w0.roles, strict=True) if r == "moored"}
    assert "anchored" in still and len(still) == 5
    root = rec.path.parent / "tables"
    b3 = pl.read_parquet(next((root / "boxes_3d").glob("*.parquet")))
    b2 = pl.read_parquet(next((root / "boxes_2d").glob("*.parquet")))
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            ann = f.messages[f"/{agent.id}/annotations"]
            t3 = b3.filter((pl.col("frame") == f.index) & (pl.col("agent") == agent.id))
            assert t3["target_id"].to_list() == [b.target_id for b in ann.boxes_lidar]
            for r, b in zip(t3.iter_rows(named=True), ann.boxes_lidar, strict=True):
                assert [r["x"], r["y"], r["z"], r["yaw"]] == [*b.center, b.yaw]
                assert r["lidar_points"] == b.lidar_points
                i = w.ids.index(b.target_id)
                assert r["role"] == w.roles[i] and r["static"] == (b.target_id in still)
            t2 = b2.filter((pl.col("frame") == f.index) & (pl.col("agent") == agent.id))
            assert list(zip(t2["target_id"], t2["camera"], strict=True)) == [
                (b.target_id, b.camera) for b in ann.boxes_camera
            ]
            for r, b in zip(t2.iter_rows(named=True), ann.boxes_camera, strict=True):
                assert [r["x_min"], r["y_min"], r["x_max"], r["y_max"]] == [b.x_min, b.y_min, b.x_max, b.y_max]
                assert (r["visible_pixels"], r["occlusion"], r["truncation"]) == (
                    b.visible_pixels,
                    b.occlusion,
                    b.truncation,
                )


def test_instance_images_name_only_vessels_and_every_one_has_one_2d_box(rec: Rec) -> None:
    """Per image: each vessel instance with a pixel (the agent's own hull aside) has exactly one 2D box of that
    camera, its ``visible_pixels`` all of its pixels in the image, every pixel centre inside the box; the quays,
    cranes, land and water carry instances that are no vessel's and never the vessel or USV class; the agent's own
    hull shows in its cameras (class USV) and has no box; no box names a vessel twice."""
    vessel_classes = {int(SemanticClass.VESSEL), int(SemanticClass.USV)}
    own_seen = 0
    structures = set()
    for f in rec.frames:
        w = f.world
        assert w is not None
        by_inst = dict(zip(w.instance_ids.tolist(), range(len(w.ids)), strict=True))
        for agent in rec.info.agents:
            ann = f.messages[f"/{agent.id}/annotations"]
            for cam in CAMS:
                inst, sem = _images(f, agent.id, cam)
                boxes = [b for b in ann.boxes_camera if b.camera == cam]
                ids = [b.target_id for b in boxes]
                assert len(ids) == len(set(ids)) and agent.id not in ids
                for k in np.unique(inst).tolist():
                    classes = set(np.unique(sem[inst == k]).tolist())
                    if k not in by_inst:
                        assert not classes & vessel_classes, (f.index, agent.id, cam, k, classes)
                        structures |= classes
                        continue
                    i = by_inst[k]
                    assert classes == {int(w.classes[i])}
                    if i == agent.index:
                        own_seen += 1
                        continue
                    assert w.ids[i] in ids, (f.index, agent.id, cam, w.ids[i])
                    b = boxes[ids.index(w.ids[i])]
                    ys, xs = np.nonzero(inst == k)
                    assert b.visible_pixels == xs.size
                    assert b.x_min <= xs.min() + 0.5 and xs.max() + 0.5 <= b.x_max
                    assert b.y_min <= ys.min() + 0.5 and ys.max() + 0.5 <= b.y_max
    assert own_seen > 0
    assert int(SemanticClass.PORT_STRUCTURE) in structures


def _clipped_at(opt: np.ndarray, near: float) -> np.ndarray:
    """The vertices of the part of a box (its ``(8, 3)`` optical-frame corners, corner ``i``'s signs ``SIGNS[i]``)
    in front of the plane ``z = near``: the corners there and where the box's twelve edges cross the plane."""
    keep = [c for c in opt if c[2] >= near]
    for a in range(8):
        for b in range(a + 1, 8):
            if np.count_nonzero(SIGNS[a] != SIGNS[b]) != 1:
                continue  # not an edge
            za, zb = opt[a, 2] - near, opt[b, 2] - near
            if za * zb < 0:
                keep.append(opt[a] + za / (za - zb) * (opt[b] - opt[a]))
    return np.array(keep).reshape(-1, 3)


def test_2d_boxes_are_the_image_of_the_3d_box_inside_the_image(rec: Rec) -> None:
    """Each 2D box against an own per-pixel slab test of the 3D box (catalogue extent at the world-state pose): it
    holds every pixel centre whose ray meets the box; and it is the bounds of the convex hull of the projected box,
    cut at the documented near plane (``mmusv.image_boxes.NEAR_M``, 5 cm) and then by the image (1e-6 px), its
    truncation 1 − that hull's bounding box clipped to the image / unclipped (1e-9). The boxes of the other USV
    alongside, which reach behind the cameras, are among them."""
    from shapely import MultiPoint, box

    behind = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            _, cams = _sensor_poses(agent, w)
            ann = f.messages[f"/{agent.id}/annotations"]
            for cam in CAMS:
                o, d = _pixel_rays(agent, cam, cams[cam])
                fx, fy, cx, cy = agent.cameras[cam].intrinsics
                inv = np.linalg.inv(cams[cam])
                for b in (b for b in ann.boxes_camera if b.camera == cam):
                    i = w.ids.index(b.target_id)
                    bw, size = _box_world(w, i)
                    hit = _slab_hits(o, d, bw, size).reshape(H, W)
                    ys, xs = np.nonzero(hit)
                    assert xs.size, (f.index, agent.id, cam, b.target_id)
                    rb = np.array([b.x_min, b.y_min, b.x_max, b.y_max])
                    lo, hi = np.array([xs.min(), ys.min()]) + 0.5, np.array([xs.max(), ys.max()]) + 0.5
                    where = (f.index, agent.id, cam, b.target_id, rb.tolist())
                    assert (rb[:2] <= lo + 1e-9).all() and (hi - 1e-9 <= rb[2:]).all(), where
                    opt = (_corners(bw, size) @ inv[:3, :3].T + inv[:3, 3]) @ BODY_TO_OPTICAL.T
                    behind += bool((opt[:, 2] < 0.0).any())
                    p = _clipped_at(opt, 0.05)
                    uv = np.column_stack([fx * p[:, 0] / p[:, 2] + cx, fy * p[:, 1] / p[:, 2] + cy])
                    hull = MultiPoint(uv).convex_hull
                    assert np.allclose(hull.intersection(box(0, 0, W, H)).bounds, rb, atol=1e-6), where
                    x0, y0, x1, y1 = hull.bounds
                    clipped = (min(x1, W) - max(x0, 0)) * (min(y1, H) - max(y0, 0))
                    assert b.truncation == pytest.approx(1 - clipped / ((x1 - x0) * (y1 - y0)), abs=1e-9), where
    assert behind > 0  # the USVs alongside: boxes reaching behind the cameras were met


def _polytope(planes: list[tuple[np.ndarray, float]]) -> np.ndarray:
    """The vertices of the convex polytope ``{x : n · x <= c}`` of ``planes`` ``(n, c)``: every point where three of
    the planes meet and that keeps to all of them (``(0, 3)`` when it is empty)."""
    out = []
    for a in range(len(planes)):
        for b in range(a + 1, len(planes)):
            for c in range(b + 1, len(planes)):
                n = np.array([planes[a][0], planes[b][0], planes[c][0]])
                if abs(np.linalg.det(n)) < 1e-12:
                    continue
                x = np.linalg.solve(n, [planes[a][1], planes[b][1], planes[c][1]])
                if all(nn @ x <= cc + 1e-7 for nn, cc in planes):
                    out.append(x)
    return np.array(out).reshape(-1, 3)


def _box_planes(box: np.ndarray, size: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """The six faces of an oriented box (box → world, full size) as half-spaces ``n · x <= c`` in the world."""
    out = []
    for k in range(3):
        axis = box[:3, k]
        for s in (1.0, -1.0):
            out.append((s * axis, s * axis @ box[:3, 3] + size[k] / 2.0))
    return out


def _above_water_in_image(box: np.ndarray, size: np.ndarray, cam: np.ndarray, k: tuple[float, ...]) -> bool:
    """Whether the part of the box above the still water level (world z >= 0) and 5 cm or more in front of the
    camera (``cam``: camera body → world, its x the optical axis) has any of its image inside the image."""
    from shapely import MultiPoint
    from shapely import box as rect

    fwd = cam[:3, 0]
    planes = [*_box_planes(box, size), (np.array([0.0, 0.0, -1.0]), 0.0), (-fwd, -(0.05 + fwd @ cam[:3, 3]))]
    p = _polytope(planes)
    if len(p) == 0:
        return False
    inv = np.linalg.inv(cam)
    opt = (p @ inv[:3, :3].T + inv[:3, 3]) @ BODY_TO_OPTICAL.T
    fx, fy, cx, cy = k
    uv = np.column_stack([fx * opt[:, 0] / opt[:, 2] + cx, fy * opt[:, 1] / opt[:, 2] + cy])
    return bool(MultiPoint(uv).convex_hull.intersects(rect(0, 0, W, H)))


def test_occlusion_is_the_hidden_share_of_the_silhouette_above_the_water(rec: Rec) -> None:
    """Each 2D box's ``occlusion`` recounted over the whole image: the pixels whose rays meet the vessel alone (its
    mesh in an empty scene) above z = 0, and of them those the instance image gives to the vessel; occlusion = 1 −
    seen / exposed (1e-9). A vessel met only below z = 0 counts its whole silhouette unless the image border cuts off
    all of its box's part above the water (the module docstring of ``mmusv.annotate``; in this recording the 300 m
    ship at the edge of the patrol boat's rear image, whose above-water hull lies in the image's last 0.3 px column,
    met by no pixel centre, while its lower hull is, below the water). The fishing boat behind the pier, the RIB
    behind the other USV and the hulls hiding one another are among them: some boxes are wholly hidden (occlusion 1,
    no pixel), and they are still boxed."""
    wholly_hidden, partly = 0, 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            _, cams = _sensor_poses(agent, w)
            ann = f.messages[f"/{agent.id}/annotations"]
            for cam in CAMS:
                inst, _ = _images(f, agent.id, cam)
                o, d = _pixel_rays(agent, cam, cams[cam])
                for b in (b for b in ann.boxes_camera if b.camera == cam):
                    i = w.ids.index(b.target_id)
                    where = (f.index, agent.id, cam, b.target_id)
                    t = _alone_distance(w.assets[i], _pose(w, i), o, d)
                    met = np.isfinite(t)
                    z = o[:, 2] + d[:, 2] * np.where(met, t, 0.0)
                    exposed = met & (z > 0.0)
                    if met.any() and not exposed.any():
                        bw, size = _box_world(w, i)
                        if _above_water_in_image(bw, size, cams[cam], agent.cameras[cam].intrinsics):
                            exposed = met
                    seen = exposed & (inst.ravel() == w.instance_ids[i])
                    if exposed.any():
                        occ = 1.0 - seen.sum() / exposed.sum()
                    else:
                        occ = float(met.any() and b.visible_pixels == 0)
                    assert b.occlusion == pytest.approx(occ, abs=1e-9), where
                    wholly_hidden += b.visible_pixels == 0
                    partly += 0.2 < occ < 0.99
    assert wholly_hidden >= 3 and partly >= 3


@pytest.fixture(scope="module")
def exports(rec: Rec, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    from mmusv.export import convert

    out = {}
    for to in ("coco", "yolo", "mot", "kitti", "kitti_tracking", "opv2v"):
        d = tmp_path_factory.mktemp(to)
        convert(rec.path, to=to, out_dir=d, splits=None)
        out[to] = d
    return out


def _decode_rle(segmentation: dict[str, Any]) -> np.ndarray:
    """pycocotools' decoding of a COCO RLE (``counts`` a string), as a bool mask (its ``__array__`` predates numpy
    2's ``copy`` keyword: a DeprecationWarning of pycocotools 2.0.11, ignored here)."""
    from pycocotools import mask as coco_mask

    rle = {"size": segmentation["size"], "counts": segmentation["counts"].encode("ascii")}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, message=".*copy keyword")
        out: np.ndarray = np.asarray(coco_mask.decode(rle), dtype=bool)
    return out


def test_image_exports_keep_every_visible_vessel(rec: Rec, exports: dict[str, Path]) -> None:
    """COCO, YOLO and MOT per image: one label per vessel with a pixel (moored ones and the other USV included, the
    agent's own hull never), its box the tight box of its pixels, COCO's mask those pixels and its role the world
    state's; MOT's track ids one per vessel for the whole recording (``tracks.csv``), its visibility
    (1 − occlusion)(1 − truncation) of the recorded box."""
    coco = json.loads((exports["coco"] / "annotations" / "instances_all.json").read_text())
    images = {(m["agent"], m["camera"], m["frame"]): m for m in coco["images"]}
    by_image: dict[int, list[dict[str, Any]]] = {}
    for a in coco["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a)
    tracks = (exports["mot"] / "tracks.csv").read_text().splitlines()
    head = tracks[0].split(",")
    track = {
        r["vessel_id"]: int(r["track_id"]) for r in (dict(zip(head, t.split(","), strict=True)) for t in tracks[1:])
    }
    w0 = rec.frames[0].world
    assert w0 is not None and set(track) == set(w0.ids)
    roles = set()
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            ann = f.messages[f"/{agent.id}/annotations"]
            for cam in CAMS:
                inst, _ = _images(f, agent.id, cam)
                want = {
                    w.ids[i]: inst == w.instance_ids[i]
                    for i in range(len(w.ids))
                    if i != agent.index and (inst == w.instance_ids[i]).any()
                }
                labels = by_image.get(images[(agent.id, cam, f.index)]["id"], [])
                assert sorted(a["mmusv_id"] for a in labels) == sorted(want), (f.index, agent.id, cam)
                tight = {}
                for a in labels:
                    m = want[a["mmusv_id"]]
                    ys, xs = np.nonzero(m)
                    tight[a["mmusv_id"]] = [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]
                    x0, y0, x1, y1 = tight[a["mmusv_id"]]
                    assert a["bbox"] == [x0, y0, x1 - x0, y1 - y0] and a["area"] == m.sum()
                    assert np.array_equal(_decode_rle(a["segmentation"]), m)
                    assert a["role"] == w.roles[w.ids.index(a["mmusv_id"])]
                    roles.add(a["role"])
                stem = f"images/all/{rec.info.scenario_name}/{agent.id}/{cam}/{f.index:06d}"
                yolo = (exports["yolo"] / stem.replace("images", "labels", 1)).with_suffix(".txt").read_text()
                rows = sorted(tuple(float(x) for x in line.split()[1:]) for line in yolo.splitlines())
                expect = sorted(
                    ((x0 + x1) / 2 / W, (y0 + y1) / 2 / H, (x1 - x0) / W, (y1 - y0) / H)
                    for x0, y0, x1, y1 in tight.values()
                )
                assert np.allclose(rows, expect, atol=1e-6) if rows else not expect
                seq = exports["mot"] / "train" / f"{rec.info.scenario_name}.{agent.id}.{cam}" / "gt" / "gt.txt"
                gt = [line.split(",") for line in seq.read_text().splitlines() if line]
                mine = sorted((int(g[1]), *map(float, g[2:6]), float(g[8])) for g in gt if int(g[0]) == f.index + 1)
                boxes = {b.target_id: b for b in ann.boxes_camera if b.camera == cam}
                vis = [(1 - boxes[v].occlusion) * (1 - boxes[v].truncation) for v in tight]
                expect_mot = sorted(
                    (track[v], t[0] + 1, t[1] + 1, t[2] - t[0], t[3] - t[1], round(s, 6))
                    for (v, t), s in zip(tight.items(), vis, strict=True)
                )
                assert np.allclose(mine, expect_mot, atol=1e-6) if mine else not expect_mot, (f.index, agent.id, cam)
    assert {"moored", "usv", "target"} <= roles


def _kitti_lines(path: Path) -> list[list[float]]:
    # the targets' lines; a DontCare line (a region to ignore) is checked on its own, below
    return [
        [float(x) for x in line.split()[1:]]
        for line in path.read_text().splitlines()
        if line and "DontCare" not in line
    ]


def test_3d_exports_keep_every_target_in_range(rec: Rec, exports: dict[str, Path]) -> None:
    """KITTI and OPV2V per agent and frame: a label for every non-USV vessel whose box centre lies within 200 m
    (moored ones included; the 300 m ship, centre beyond, left out, as the exports' documented rule says), each
    matching its own 3D box: KITTI's ``h w l`` the mesh's height, beam and length and its location the box's centre
    in the front optical frame moved h/2 down the camera's y axis (KITTI's upright box's bottom centre; 1 cm), its
    ``rotation_y`` the bow's heading about the camera's y axis, its 2D box and truncation the recorded front box's
    (``0 0 0 0`` and 1 without one: none of them is in view too small for a box here); OPV2V's vehicle id 1000 +
    the vessel's index, its ``extent`` half the size and its box (location + center, the CARLA frame, y mirrored)
    the world-state box's centre (1 cm)."""
    kitti_agents = yaml.safe_load((exports["kitti"] / rec.info.scenario_name / "mmusv_kitti.yaml").read_text())[
        "agents"
    ]
    folder = {v: str(k) for k, v in kitti_agents.items()}
    moored = 0
    for f in rec.frames:
        w = f.world
        assert w is not None
        for agent in rec.info.agents:
            want = _targets_by_centre(w, agent)
            assert "cruise" not in want
            moored += sum(w.roles[w.ids.index(v)] == "moored" for v in want)
            _, cams = _sensor_poses(agent, w)
            inv = np.linalg.inv(cams["front"])
            ann = f.messages[f"/{agent.id}/annotations"]
            lines = _kitti_lines(
                exports["kitti"] / rec.info.scenario_name / folder[agent.id] / "label_2" / f"{f.index:06d}.txt"
            )
            assert len(lines) == len(want), (f.index, agent.id)
            for vid in want:
                i = w.ids.index(vid)
                bw, size = _box_world(w, i)
                # KITTI's box is upright in the camera frame: its location the centre h/2 down the camera's y axis
                loc = BODY_TO_OPTICAL @ (inv[:3, :3] @ bw[:3, 3] + inv[:3, 3]) + [0.0, size[2] / 2, 0.0]
                hwl = [size[2], size[1], size[0]]
                same = [
                    ln
                    for ln in lines
                    if np.allclose(ln[7:10], hwl, atol=0.006) and np.allclose(ln[10:13], loc, atol=0.01)
                ]
                assert len(same) == 1, (f.index, agent.id, vid, loc)
                ln = same[0]
                heading = BODY_TO_OPTICAL @ inv[:3, :3] @ bw[:3, 0]  # the bow's direction in the optical frame
                ry = -np.arctan2(heading[2], heading[0])
                assert abs((ln[13] - ry + np.pi) % (2 * np.pi) - np.pi) < 0.006, (f.index, agent.id, vid)
                front = {b.target_id: b for b in ann.boxes_camera if b.camera == "front"}
                b = front.get(vid)
                # (no box, or one of no pixel seen, hidden wholly: occluded 3, box 0 0 0 0)
                bbox = [0.0] * 4 if b is None or b.visible_pixels == 0 else [b.x_min, b.y_min, b.x_max, b.y_max]
                assert np.allclose(ln[3:7], bbox, atol=0.006), (f.index, agent.id, vid)
                assert ln[0] == pytest.approx(1.0 if b is None else b.truncation, abs=0.006)
            doc = yaml.safe_load(
                (
                    exports["opv2v"] / rec.info.scenario_name / str(1000 + agent.index) / f"{f.index:06d}.yaml"
                ).read_text()
            )
            vehicles = doc["vehicles"]
            assert set(vehicles) == {1000 + w.ids.index(v) for v in want}, (f.index, agent.id)
            for key, v in vehicles.items():
                bw, size = _box_world(w, key - 1000)
                assert np.allclose(v["extent"], size / 2, atol=1e-4)
                centre = np.add(v["location"], v["center"]) * [1, -1, 1]
                assert np.allclose(centre, bw[:3, 3], atol=0.01), (f.index, agent.id, key)
    assert moored >= 6


@pytest.mark.parametrize("range_m", [RANGE_M, 40.0])
def test_kitti_marks_the_vessels_it_leaves_out_as_dont_care(
    rec: Rec, exports: dict[str, Path], range_m: float, tmp_path: Path
) -> None:
    """KITTI's ``label_2`` (and KITTI tracking's ``label_02``, track id -1) hold, besides the targets, one ``DontCare``
    line (KITTI's own form: ``-1 -1 -10``, the 2D box, ``-1 -1 -1 -1000 -1000 -1000 -10``) for each vessel the front
    image shows (a recorded front box with a visible pixel) that is not a target: the other USV, and at a 40 m range
    the vessels beyond it. KITTI's evaluation ignores detections there; without them a detector finding such a
    vessel was counted wrong (2026-12-06)."""
    from mmusv.export import convert

    scenario = rec.info.scenario_name
    if range_m != RANGE_M:
        exports = {to: tmp_path / to for to in ("kitti", "kitti_tracking")}
        for to, d in exports.items():
            convert(rec.path, to=to, out_dir=d, splits=None, eval_range_m=range_m)
    kitti_agents = yaml.safe_load((exports["kitti"] / scenario / "mmusv_kitti.yaml").read_text())["agents"]
    folder = {v: str(k) for k, v in kitti_agents.items()}
    tracking = exports["kitti_tracking"] / "train"
    rows = csv.DictReader((exports["kitti_tracking"] / "sequences.csv").read_text().splitlines())
    sequences = {row["agent"]: row["sequence"] for row in rows}
    ignored: set[str] = set()
    for agent in rec.info.agents:
        seq = (tracking / "label_02" / f"{sequences[agent.id]}.txt").read_text().splitlines()
        for k, f in enumerate(rec.frames):
            w = f.world
            assert w is not None
            want = _targets_by_centre(w, agent, range_m)
            ann = f.messages[f"/{agent.id}/annotations"]
            shown = {b.target_id: b for b in ann.boxes_camera if b.camera == "front" and b.visible_pixels > 0}
            left = sorted(
                (round(b.x_min, 2), round(b.y_min, 2), round(b.x_max, 2), round(b.y_max, 2))
                for vid, b in shown.items()
                if vid not in want
            )
            ignored.update(vid for vid in shown if vid not in want)
            text = (exports["kitti"] / scenario / folder[agent.id] / "label_2" / f"{f.index:06d}.txt").read_text()
            dont = [line.split() for line in text.splitlines() if line.startswith("DontCare ")]
            for fields in dont:
                assert fields[1:4] == ["-1", "-1", "-10"] and fields[8:] == [
                    "-1",
                    "-1",
                    "-1",
                    "-1000",
                    "-1000",
                    "-1000",
                    "-10",
                ]
            got = sorted(tuple(float(x) for x in fields[4:8]) for fields in dont)
            assert len(got) == len(left), (f.index, agent.id)
            np.testing.assert_allclose(np.reshape(got, (-1, 4)), np.reshape(left, (-1, 4)), atol=0.0051)
            in_seq = [line.split()[2:] for line in seq if line.split()[:3] == [str(k), "-1", "DontCare"]]
            assert in_seq == dont, (f.index, agent.id)
    assert "ego" in ignored  # the other USV, never a target
    if range_m < RANGE_M:  # vessels beyond the range, in the picture
        assert len(ignored - {"ego"}) >= 2, ignored
