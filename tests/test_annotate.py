"""The 3D boxes of :func:`mmusv.annotate.annotate_agent` against their definition: each vessel's box pose in the
ego LiDAR's frame, worked out here from the world state, its quaternion the rotation of that pose."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mmusv.acquire import annotations_for
from mmusv.frames import translation
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Simulation
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]


def test_box_poses_and_quaternions_match_the_world_state() -> None:
    sim = Simulation(ROOT / "scenarios/open_sea_convoy.yaml")
    sim.set_sea_surface(None)  # the boxes do not depend on the sea; flat keeps the test quick
    ids = {v.id: i for i, v in enumerate(sim.vessels)}
    checked = 0
    for frame in (0, 7):
        cap = sim.capture(frame, sensors=["lidar"])
        for agent_id, ann in annotations_for(sim, cap, SilhouetteCache()).items():
            ref = cap.agents[agent_id].lidar_pose
            assert ref is not None
            rotations = ann.columns()["lidar"]["rotation"]
            assert len(ann.lidar_ids) == rotations.shape[0] > 0
            for j, vid in enumerate(ann.lidar_ids):
                vi = ids[vid]
                centre = np.asarray(sim.vessels[vi].box_center_body, dtype=np.float64)
                box_world = cap.world.matrices[vi].copy()
                box_world[:3, 3] = box_world[:3, :3] @ centre + box_world[:3, 3]
                box_ref = np.linalg.inv(ref) @ box_world
                np.testing.assert_allclose(ann.lidar_center[j], box_ref[:3, 3], atol=1e-9)
                # The quaternion is a unit one that turns vectors as the box's rotation does (an independent
                # check of the conversion), and the sign scipy gives one matrix alone (w >= 0).
                q = rotations[j]
                assert abs(np.linalg.norm(q) - 1.0) < 1e-12
                np.testing.assert_allclose(Rotation.from_quat(q).as_matrix(), box_ref[:3, :3], atol=1e-9)
                np.testing.assert_allclose(q, Rotation.from_matrix(box_ref[:3, :3]).as_quat(), rtol=0, atol=1e-12)
                checked += 1
    assert checked >= 6


def _footprint_distance(box: np.ndarray, size: np.ndarray) -> float:
    """The BEV distance from the ego to a box's footprint by shapely (0 inside): the rectangle's corners from the
    box's x axis and its perpendicular in the xy plane."""
    import shapely

    c = box[:2, 3]
    ax = box[:2, 0] / np.linalg.norm(box[:2, 0])
    ay = np.array([-ax[1], ax[0]])
    corners = [c + sx * size[0] / 2 * ax + sy * size[1] / 2 * ay for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return float(shapely.Polygon(corners).distance(shapely.Point(0.0, 0.0)))


def test_a_long_ship_whose_stern_is_near_gets_its_box() -> None:
    # A 330 m tanker centred 210 m astern of a USV whose LiDAR reaches 200 m: its stern lies 45 m away and the
    # LiDAR has a thousand points on it, yet the centre rule gave it no 3D/BEV box. Every vessel whose footprint
    # comes within the range (by shapely) has one, the others none.
    scenario = {
        "name": "long_ship",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 2},
        "acquisition": {"frequency_hz": 2, "frames": 1},
        "rigs": {"r": {"preset": "lidar_only"}},
        "vessels": [
            {
                "id": "usv_1",
                "role": "usv",
                "asset": "usv_wamv",
                "rig": "r",
                "speed_mps": 0.5,
                "route": [[0, 0], [10, 0]],
            },
            {"id": "vlcc", "asset": "vlcc_tanker_330m", "speed_mps": 0.0, "route": [[-210, 0], [-700, 0]]},
            {"id": "far", "asset": "fishing_boat_12m", "speed_mps": 0.0, "route": [[0, 260], [0, 300]]},
        ],
    }
    sim = Simulation(scenario)
    sim.set_sea_surface(None)
    cap = sim.capture(0, sensors=["lidar"])
    ann = annotations_for(sim, cap, SilhouetteCache())["usv_1"]
    ref = cap.agents["usv_1"].lidar_pose
    assert ref is not None
    assert "vlcc" in ann.lidar_ids and "far" not in ann.lidar_ids
    j = ann.lidar_ids.index("vlcc")
    assert ann.lidar_range[j] > 200.0 and ann.lidar_points[j] > 100
    from mmusv.boxes3d import footprint_in_range

    for vi, info in enumerate(sim.vessels):
        if info.id == "usv_1":
            continue
        box = np.linalg.inv(ref) @ cap.world.matrices[vi] @ translation(info.box_center_body)
        near = _footprint_distance(box, info.box_size) <= 200.0
        assert footprint_in_range(box, size=info.box_size, range_m=200.0) == near == (info.id in ann.lidar_ids), info.id
    # The rule against shapely over boxes all around, half of them reaching in.
    rng = np.random.default_rng(5)
    for _ in range(300):
        yaw, x, y = rng.uniform(-np.pi, np.pi), *rng.uniform(-400.0, 400.0, 2)
        size = np.array([rng.uniform(3.0, 330.0), rng.uniform(1.0, 60.0), 10.0])
        box = np.eye(4)
        box[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
        box[:2, 3] = x, y
        d = _footprint_distance(box, size)
        if abs(d - 150.0) > 1e-6:
            assert footprint_in_range(box, size=size, range_m=150.0) == (d <= 150.0)


def test_a_close_ship_cut_off_above_the_waterline_is_not_hidden_by_waves() -> None:
    """A camera looking steeply down beside a 120 m cargo ship at W3 sees only the water in front of its lower
    hull: the ship's 2D box is cut by the top border, and its pixels' rays meet the ship alone only below the still
    level. That was taken for a craft wholly in a trough, whose whole silhouette counts, and the ship was
    "hidden by waves" (``wave_occlusion`` 1). The part of it a calm sea would show is outside the image: none of it
    is exposed (``wave_occlusion`` 0; ``occlusion`` 1, nothing of it seen)."""
    cam = {
        "name": "down",
        "resolution": [80, 60],
        "hfov_deg": 40,
        "outputs": ["rgb", "instance"],
        "mount": {"xyz": [0.0, -1.0, 3.0], "rpy_deg": [0.0, 45.0, -90.0]},  # to starboard, 45 degrees down
    }
    scenario = {
        "name": "close_ship",
        "seed": 4,
        "map": {"type": "open_sea", "seed": 2},
        "environment": {"wave": "W3"},
        "acquisition": {"frequency_hz": 2, "frames": 1},
        "rigs": {"r": {"cameras": [cam]}},
        "vessels": [
            {"id": "ego", "role": "usv", "asset": "usv_patrol_12m", "rig": "r", "speed_mps": 2.0,
             "route": [[0, 0], [0, 60]]},
            {"id": "cargo", "asset": "general_cargo_120m", "speed_mps": 2.0, "route": [[22, -20], [22, 80]]},
        ],
    }  # fmt: skip
    sim = Simulation(scenario)
    cap = sim.capture(0, sensors=["cameras"])
    ann = annotations_for(sim, cap, SilhouetteCache())["ego"]
    cols = ann.columns()["camera"]
    j = list(cols["target_id"]).index("cargo")
    assert cols["y_min"][j] == 0.0 and cols["truncation"][j] > 0.5  # the top border cuts off its upper part
    assert cols["visible_pixels"][j] == 0  # the water in front of its lower hull fills the box
    assert cols["wave_occlusion"][j] == 0.0 and cols["occlusion"][j] == 1.0


def test_small_craft_at_the_image_border_keep_their_trough_rule(monkeypatch: pytest.MonkeyPatch) -> None:
    """The close-ship exception above must not reach small craft the side borders cut: ten 5 m speedboats at 80 to
    200 m crossing the left and right borders of a 90-degree camera at W3, 60 frames, get the annotations the
    trough rule alone gives (a first guard, the 3D box's top above the still level, made 9 of 143 cut rows
    "occlusion 1, wave_occlusion 0" again; one that took a box wholly below the level for one out of the picture,
    3). Some cut rows are a craft wholly hidden in a trough (occlusion and wave_occlusion 1)."""
    import mmusv.annotate as annotate

    cam = {"name": "front", "resolution": [160, 120], "hfov_deg": 90, "outputs": ["rgb", "instance"],
           "mount": {"xyz": [0.0, 0.0, 3.0], "rpy_deg": [0.0, 0.0, 0.0]}}  # fmt: skip
    vessels: list[dict[str, object]] = [
        {
            "id": "ego",
            "role": "usv",
            "asset": "usv_patrol_12m",
            "rig": "r",
            "speed_mps": 0.5,
            "route": [[0, 0], [0, 60]],
        }
    ]
    for k, r in enumerate([80, 110, 140, 170, 200]):
        for side in (-1, 1):  # across the line of sight at bearing +-45 degrees: the image's side borders
            c = np.array([side * r, r]) / np.sqrt(2)
            t = np.array([1.0, -side]) / np.sqrt(2) * side
            route = [(c - 6 * t).round(2).tolist(), (c + 6 * t).round(2).tolist()]
            vessels.append({"id": f"b{k}{'LR'[side > 0]}", "asset": "speedboat_5m", "speed_mps": 1.5, "route": route})
    scenario = {"name": "edge", "seed": 5, "map": {"type": "open_sea", "seed": 2}, "environment": {"wave": "W3"},
                "acquisition": {"frequency_hz": 5, "frames": 60}, "rigs": {"r": {"cameras": [cam]}},
                "vessels": vessels}  # fmt: skip
    sim = Simulation(scenario)
    caps = [sim.capture(f, sensors=["cameras"]) for f in range(60)]
    got = [annotations_for(sim, c, SilhouetteCache())["ego"].columns()["camera"] for c in caps]
    rays, boxes = annotate.exposed_rays, annotate.exposed_hidden_boxes
    monkeypatch.setattr(annotate, "exposed_rays", lambda *a, whole_when_low=None, **k: rays(*a, **k))
    monkeypatch.setattr(annotate, "exposed_hidden_boxes", lambda *a, whole_when_low=None, **k: boxes(*a, **k))
    want = [annotations_for(sim, c, SilhouetteCache())["ego"].columns()["camera"] for c in caps]
    cut = hidden = 0
    for g, w in zip(got, want, strict=True):
        assert list(g["target_id"]) == list(w["target_id"])
        for col in ("occlusion", "wave_occlusion", "x_min", "x_max", "y_min", "y_max"):
            np.testing.assert_array_equal(g[col], w[col], err_msg=col)
        on_border = np.asarray(g["truncation"]) > 0
        cut += int(on_border.sum())
        hidden += int((on_border & (np.asarray(g["wave_occlusion"]) == 1.0)).sum())
    assert cut > 100 and hidden > 0, (cut, hidden)
