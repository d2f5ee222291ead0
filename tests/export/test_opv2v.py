"""OPV2V output read back the way OPV2V loaders read it.

The loader maths (``x_to_world``, ``x1_to_x2``, the 8-corner box from ``extent``, the box pose = location + center
with ``angle``) is written out here from the OPV2V/OpenCOOD conventions, independently of the converter's
``mmusv.frames``; the ground truth it is compared with (instance ids of LiDAR points, annotation yaws, world
state) comes straight from the recording.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.export import convert
from mmusv.recording import decode_image, decode_point_cloud, read_messages

EXTRA_FILES = {"_depth{i}.png", "_depth_cm{i}.png", "_semantic{i}.png"}
"""Depth: HEAL's 8-bit metres under OPV2V-H's name, the uint16 centimetres beside it (``_depth_cm``)."""
YAML_KEYS = {
    "camera0",
    "camera1",
    "camera2",
    "camera3",
    "ego_speed",
    "lidar_pose",
    "plan_trajectory",
    "predicted_ego_pos",
    "true_ego_pos",
    "vehicles",
}
VEHICLE_KEYS = {"location", "center", "extent", "angle", "speed"}
TOL_M = 0.12  # range noise (2 cm σ) and 0.1 mm rounding of the PCD


# ---------------------------------------------------------------------------------------------- loader maths


def x_to_world(pose: list[float]) -> np.ndarray:
    x, y, z, roll, yaw, pitch = pose
    c_y, s_y = np.cos(np.radians(yaw)), np.sin(np.radians(yaw))
    c_r, s_r = np.cos(np.radians(roll)), np.sin(np.radians(roll))
    c_p, s_p = np.cos(np.radians(pitch)), np.sin(np.radians(pitch))
    m = np.identity(4)
    m[0, 3], m[1, 3], m[2, 3] = x, y, z
    m[0, 0] = c_p * c_y
    m[0, 1] = c_y * s_p * s_r - s_y * c_r
    m[0, 2] = -c_y * s_p * c_r - s_y * s_r
    m[1, 0] = s_y * c_p
    m[1, 1] = s_y * s_p * s_r + c_y * c_r
    m[1, 2] = -s_y * s_p * c_r + c_y * s_r
    m[2, 0] = s_p
    m[2, 1] = -c_p * s_r
    m[2, 2] = c_p * c_r
    return m


def x1_to_x2(x1: list[float], x2: list[float]) -> np.ndarray:
    out: np.ndarray = np.linalg.inv(x_to_world(x2)) @ x_to_world(x1)
    return out


def object_pose(obj: dict[str, Any]) -> list[float]:
    loc, c, a = obj["location"], obj["center"], obj["angle"]
    return [loc[0] + c[0], loc[1] + c[1], loc[2] + c[2], a[0], a[1], a[2]]


def corners(obj: dict[str, Any], lidar_pose: list[float]) -> np.ndarray:
    e = np.asarray(obj["extent"])
    signs = np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], dtype=float)
    local = np.hstack([signs * e, np.ones((8, 1))])
    out: np.ndarray = (x1_to_x2(object_pose(obj), lidar_pose) @ local.T).T[:, :3]
    return out


def inside(points: np.ndarray, obj: dict[str, Any], lidar_pose: list[float], tol: float) -> np.ndarray:
    t = np.linalg.inv(x1_to_x2(object_pose(obj), lidar_pose))
    local = points @ t[:3, :3].T + t[:3, 3]
    out: np.ndarray = np.all(np.abs(local) <= np.asarray(obj["extent"]) + tol, axis=1)
    return out


def read_pcd_o3d(path: Path) -> tuple[np.ndarray, np.ndarray]:
    import open3d as o3d

    pc = o3d.io.read_point_cloud(str(path))  # type: ignore[arg-type]
    return np.asarray(pc.points), np.asarray(pc.colors)[:, 0]


def to_ego(points: np.ndarray, cav_pose: list[float], ego_pose: list[float]) -> np.ndarray:
    t = x1_to_x2(cav_pose, ego_pose)
    out: np.ndarray = points @ t[:3, :3].T + t[:3, 3]
    return out


def wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


# ---------------------------------------------------------------------------------------------- recording side


def recorded(path: Path) -> dict[int, Any]:
    """Per frame index: world state, per agent point cloud columns and annotations, instance images."""
    out: dict[int, dict[str, Any]] = {}
    for topic, t, msg in read_messages(path):
        if topic == "/tf" or topic.endswith(("/rgb", "/depth", "/semantic", "/ppi", "/boxes", "/returns")):
            continue
        k = round(t * 5 / 1e9)
        fr = out.setdefault(k, {})
        if topic == "/world/state":
            fr["world"] = msg
        elif topic.endswith("/lidar"):
            fr[topic] = decode_point_cloud(msg)
        elif topic.endswith("/instance"):
            fr[topic] = decode_image(msg)
        else:
            fr[topic] = msg
    return out


@pytest.fixture(scope="module")
def coop_out(coop_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("opv2v_coop")
    convert(coop_rec, to="opv2v", out_dir=out, splits=None)
    return out / "export_coop"


@pytest.fixture(scope="module")
def coop_rec_data(coop_rec: Path) -> dict[int, Any]:
    return recorded(coop_rec)


def frames_of(d: Path) -> list[str]:
    return sorted(p.stem for p in d.glob("*.yaml") if "additional" not in p.name)


def load(p: Path) -> dict[str, Any]:
    doc: dict[str, Any] = yaml.safe_load(p.read_text())
    return doc


# ---------------------------------------------------------------------------------------------- layout


def test_layout_names_and_keys(coop_out: Path, coop_rec_data: dict[int, Any]) -> None:
    cavs = sorted(p.name for p in coop_out.iterdir() if p.is_dir())
    assert cavs == ["1000", "1002"]  # usv_a is vessel 0, usv_b vessel 2: string order = numeric = scenario order
    assert (coop_out / "data_protocol.yaml").is_file()
    stamps = {c: frames_of(coop_out / c) for c in cavs}
    assert stamps["1000"] == stamps["1002"] == ["000000", "000001", "000002"]
    for c in cavs:
        names = {p.name for p in (coop_out / c).iterdir()}
        for ts in stamps[c]:
            expected = {
                f"{ts}.yaml",
                f"{ts}.pcd",
                f"{ts}_additional.yaml",
                f"{ts}_radar_ppi.png",
                f"{ts}_topview_rgb.png",
                f"{ts}_topview_semantic.png",
            }
            expected |= {f"{ts}_camera{i}.png" for i in range(4)}
            expected |= {f"{ts}{pat.format(i=i)}" for pat in EXTRA_FILES for i in range(4)}
            assert expected <= names
            doc = load(coop_out / c / f"{ts}.yaml")
            assert set(doc) == YAML_KEYS
            for i in range(4):
                assert set(doc[f"camera{i}"]) == {"cords", "intrinsic", "extrinsic", "distortion"}
                assert doc[f"camera{i}"]["distortion"] == [0.0] * 5  # the test rig has ideal pinholes
                assert np.asarray(doc[f"camera{i}"]["intrinsic"]).shape == (3, 3)
                assert np.asarray(doc[f"camera{i}"]["extrinsic"]).shape == (4, 4)
            for key in ("lidar_pose", "true_ego_pos", "predicted_ego_pos"):
                assert len(doc[key]) == 6
            assert isinstance(doc["ego_speed"], float)
            for vid, v in doc["vehicles"].items():
                assert isinstance(vid, int) and set(v) == VEHICLE_KEYS
                assert str(vid) not in cavs  # instrumented USVs are not targets by default
        assert len(names) == len(stamps[c]) * len(expected)  # nothing else in the folder
    # the tug (vessel 1) and the speedboat (vessel 3) are the targets
    doc = load(coop_out / "1000" / "000000.yaml")
    assert set(doc["vehicles"]) == {1001, 1003}
    ws = coop_rec_data[0]["world"]
    v = doc["vehicles"][1001]
    np.testing.assert_allclose(np.asarray(v["extent"]) * 2, list(ws.vessels[1].box_size), atol=1e-6)
    np.testing.assert_allclose(v["speed"], np.linalg.norm(list(ws.vessels[1].velocity)) * 3.6, atol=1e-5)
    np.testing.assert_allclose(doc["ego_speed"], np.linalg.norm(list(ws.vessels[0].velocity)) * 3.6, atol=1e-5)


def test_pcd_is_the_recorded_cloud_mirrored_with_intensity(coop_out: Path, coop_rec_data: dict[int, Any]) -> None:
    for cav, agent in (("1000", "usv_a"), ("1002", "usv_b")):
        for k in range(3):
            pts, inten = read_pcd_o3d(coop_out / cav / f"{k:06d}.pcd")
            rec = coop_rec_data[k][f"/{agent}/lidar"]
            assert len(pts) == len(rec["x"]) > 100
            np.testing.assert_allclose(pts[:, 0], rec["x"], atol=1e-4)
            np.testing.assert_allclose(pts[:, 1], -rec["y"], atol=1e-4)  # left-handed: y to the right
            np.testing.assert_allclose(pts[:, 2], rec["z"], atol=1e-4)
            np.testing.assert_allclose(inten, np.clip(rec["intensity"], 0, 1), atol=1 / 255)


def _instance_rows(ws: Any) -> dict[int, int]:
    """Dataset id (1000 + world-state row) → instance id."""
    return {1000 + i: int(v.instance_id) for i, v in enumerate(ws.vessels)}


def check_round_trip(out: Path, rec: dict[int, Any], agents: dict[str, str]) -> dict[str, int]:
    """Every target box of every ego holds that target's points from the ego and from every cooperating agent
    (moved into the ego LiDAR frame with x1_to_x2), and its yaw matches the heading; returns counts checked."""
    n = {"own": 0, "coop": 0, "yaw": 0}
    stamps = frames_of(out / next(iter(agents)))
    for ts in stamps:
        k = int(ts)
        ws = rec[k]["world"]
        inst = _instance_rows(ws)
        docs = {c: load(out / c / f"{ts}.yaml") for c in agents}
        clouds = {c: read_pcd_o3d(out / c / f"{ts}.pcd")[0] for c in agents}
        for ego, ego_agent in agents.items():
            ego_pose = docs[ego]["lidar_pose"]
            ann = {b.target_id: b for b in rec[k][f"/{ego_agent}/annotations"].boxes_lidar}
            for vid, obj in docs[ego]["vehicles"].items():
                row = vid - 1000
                # heading: world yaw and yaw in the ego LiDAR frame (our frames are right-handed: mirrored sign)
                assert wrap(math.radians(obj["angle"][1]) + ws.vessels[row].pose[5]) == pytest.approx(0.0, abs=1e-5)
                r = x1_to_x2(object_pose(obj), ego_pose)
                tid = ws.vessels[row].id
                if tid in ann:
                    assert wrap(math.atan2(r[1, 0], r[0, 0]) + ann[tid].yaw) == pytest.approx(0.0, abs=1e-4)
                    n["yaw"] += 1
                for cav, cav_agent in agents.items():
                    ids = rec[k][f"/{cav_agent}/lidar"]["instance"]
                    pts = clouds[cav][ids == inst[vid]]
                    if len(pts) == 0:
                        continue
                    if cav != ego:
                        pts = to_ego(pts, docs[cav]["lidar_pose"], ego_pose)
                    ok = inside(pts, obj, ego_pose, TOL_M)
                    assert ok.all(), (
                        f"ts {ts}: {(~ok).sum()} of {len(ok)} points of {vid} from {cav} outside the box seen by {ego}"
                    )
                    n["own" if cav == ego else "coop"] += len(pts)
    return n


def test_round_trip_boxes_hold_points_own_and_cooperating(coop_out: Path, coop_rec_data: dict[int, Any]) -> None:
    n = check_round_trip(coop_out, coop_rec_data, {"1000": "usv_a", "1002": "usv_b"})
    assert n["own"] > 200 and n["coop"] > 100 and n["yaw"] >= 6, n


def test_box_corners_contain_points_in_ego_frame_tightly(coop_out: Path, coop_rec_data: dict[int, Any]) -> None:
    # the box is not just large: the tug's points reach near its faces (the box is the hull's bounding box)
    doc = load(coop_out / "1000" / "000000.yaml")
    obj = doc["vehicles"][1001]
    c = corners(obj, doc["lidar_pose"])
    pts = read_pcd_o3d(coop_out / "1000" / "000000.pcd")[0]
    ids = coop_rec_data[0]["/usv_a/lidar"]["instance"]
    tug = pts[ids == _instance_rows(coop_rec_data[0]["world"])[1001]]
    assert len(tug) > 50
    lo, hi = c.min(axis=0), c.max(axis=0)
    assert np.all(tug.min(axis=0) >= lo - TOL_M) and np.all(tug.max(axis=0) <= hi + TOL_M)
    # the ego sees the tug ahead on its port side: +x, and y < 0 in the left-handed frame
    centre = c.mean(axis=0)
    assert centre[0] > 20 and centre[1] < 0


def test_cameras_order_extrinsic_and_projection(coop_out: Path, coop_rec_data: dict[int, Any]) -> None:
    names = {0: "front", 1: "right", 2: "left", 3: "rear"}
    offsets = {0: 0.0, 1: 90.0, 2: -90.0, 3: 180.0}  # CARLA yaw grows towards +y (right)
    hits = total = 0
    for ts in ("000000", "000002"):
        k = int(ts)
        doc = load(coop_out / "1000" / f"{ts}.yaml")
        pts = read_pcd_o3d(coop_out / "1000" / f"{ts}.pcd")[0]
        ids = coop_rec_data[k]["/usv_a/lidar"]["instance"]
        lidar_yaw = doc["lidar_pose"][4]
        for i, name in names.items():
            cam = doc[f"camera{i}"]
            ext = np.asarray(cam["extrinsic"])
            np.testing.assert_allclose(ext, x1_to_x2(doc["lidar_pose"], cam["cords"]), atol=1e-6)
            assert math.degrees(wrap(math.radians(cam["cords"][4] - lidar_yaw - offsets[i]))) == pytest.approx(
                0.0, abs=2.0
            )
            k_mat = np.asarray(cam["intrinsic"])
            assert k_mat[0, 0] == pytest.approx(160 / (2 * math.tan(math.radians(45))))
            assert (k_mat[0, 2], k_mat[1, 2]) == (80.0, 60.0)
            p = pts @ ext[:3, :3].T + ext[:3, 3]  # UE camera axes: x forward, y right, z up
            front = p[:, 0] > 1.0
            u = k_mat[0, 0] * p[:, 1] / np.where(front, p[:, 0], 1) + k_mat[0, 2]
            v = k_mat[1, 1] * -p[:, 2] / np.where(front, p[:, 0], 1) + k_mat[1, 2]
            ok = front & (u >= 0) & (u < 160) & (v >= 0) & (v < 120) & (ids > 0)
            img = coop_rec_data[k][f"/usv_a/camera/{name}/instance"]
            sel = np.flatnonzero(ok & np.isin(ids, list(_instance_rows(coop_rec_data[k]["world"]).values())))
            total += len(sel)
            hits += int(np.sum(img[v[sel].astype(int), u[sel].astype(int)] == ids[sel]))
    assert total > 50 and hits / total > 0.8, (hits, total)


def test_include_usvs_lists_other_usvs_never_self(coop_rec: Path, tmp_path: Path) -> None:
    convert(coop_rec, to="opv2v", out_dir=tmp_path, splits=None, include_usvs=True, extras=())
    d = tmp_path / "export_coop"
    for ego, other in (("1000", 1002), ("1002", 1000)):
        doc = load(d / ego / "000000.yaml")
        assert other in doc["vehicles"] and int(ego) not in doc["vehicles"]
        assert not list((d / ego).glob("*_depth*.png"))  # extras=() writes none


def test_eval_range_filters_vehicles(coop_rec: Path, tmp_path: Path) -> None:
    """The export keeps exactly the vessels within the range in bird's-eye view (the one target rule, changed from
    a square |x|, |y| window): those of a 200 m export whose centre is within 40 m."""
    convert(coop_rec, to="opv2v", out_dir=tmp_path / "near", splits=None, eval_range_m=40.0, extras=())
    convert(coop_rec, to="opv2v", out_dir=tmp_path / "all", splits=None, extras=())
    doc = load(tmp_path / "near" / "export_coop" / "1000" / "000000.yaml")
    every = load(tmp_path / "all" / "export_coop" / "1000" / "000000.yaml")

    def bev(d: dict[str, Any], obj: dict[str, Any]) -> float:
        c = corners(obj, d["lidar_pose"]).mean(axis=0)
        return math.hypot(c[0], c[1])

    assert all(bev(doc, obj) <= 40 for obj in doc["vehicles"].values())
    assert set(doc["vehicles"]) == {k for k, obj in every["vehicles"].items() if bev(every, obj) <= 40}
    full = load(tmp_path / "near" / "export_coop" / "data_protocol.yaml")
    assert full["mmusv"]["eval_range_m"] == 40.0


def test_round_trip_port(port_rec: Path, tmp_path: Path) -> None:
    convert(port_rec, to="opv2v", out_dir=tmp_path, splits=None, extras=())
    out = tmp_path / "port_entry"
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["1000", "1001", "1002"]
    n = check_round_trip(out, recorded(port_rec), {"1000": "usv_1", "1001": "usv_2", "1002": "usv_3"})
    assert n["own"] > 100, n


def test_moored_ships_are_labelled_static_with_boxes_that_hold_their_points(port_rec: Path, tmp_path: Path) -> None:
    """Moored ships are vessels like any other: in the annotations, the tables and the OPV2V export, flagged
    ``static`` with role ``moored``; their boxes hold their LiDAR points, seen by the ego in port_entry."""
    import polars as pl

    convert(port_rec, to="opv2v", out_dir=tmp_path, splits=None, extras=())
    out = tmp_path / "port_entry"
    rec = recorded(port_rec)
    moored_pts = 0
    for ts in frames_of(out / "1001"):
        k = int(ts)
        inst = _instance_rows(rec[k]["world"])
        doc = load(out / "1001" / f"{ts}.yaml")
        extra = load(out / "1001" / f"{ts}_additional.yaml")["mmusv"]["vehicles"]
        pts_all = read_pcd_o3d(out / "1001" / f"{ts}.pcd")[0]
        ids = rec[k]["/usv_2/lidar"]["instance"]
        for vid, meta in extra.items():
            assert meta["static"] == (meta["role"] == "moored"), meta  # the scenario's other vessels all move
            if meta["role"] != "moored":
                continue
            pts = pts_all[ids == inst[vid]]
            ok = inside(pts, doc["vehicles"][vid], doc["lidar_pose"], TOL_M)
            assert ok.all()
            moored_pts += len(pts)
    assert moored_pts > 100, "usv_2 waits beside the quays: it must see a moored ship"
    boxes = pl.read_parquet(port_rec.parent / "tables" / "boxes_3d")
    moored = boxes.filter(pl.col("role") == "moored")
    assert moored.height > 0 and moored["static"].all() and moored["lidar_points"].sum() > 0
    assert not boxes.filter(pl.col("role") != "moored")["static"].any()
    world = pl.read_parquet(port_rec.parent / "tables" / "world_state")
    assert world.filter(pl.col("role") == "moored")["static"].all()
