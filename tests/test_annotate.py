"""The 3D boxes of :func:`mmusv.annotate.annotate_agent` against their definition: each vessel's box pose in the
ego LiDAR's frame, worked out here from the world state, its quaternion the rotation of that pose."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mmusv.acquire import annotations_for
from mmusv.annotate import SilhouetteCache
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
