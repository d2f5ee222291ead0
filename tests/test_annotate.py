"""The 3D boxes of :func:`mmusv.annotate.annotate_agent` against their definition: each vessel's box pose in the
ego LiDAR's frame, worked out here from the world state, its quaternion the rotation of that pose."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mmusv.acquire import annotations_for
from mmusv.annotate import SilhouetteCache
from mmusv.frames import translation
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
    from mmusv.annotate import footprint_in_range

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
