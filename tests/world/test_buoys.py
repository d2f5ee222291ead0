"""The map's buoys: each its own instance, riding the physical sea (:mod:`mmusv.world.buoys`).

Before, every buoy of a map was one merged static mesh (one instance id for all of them in the instance images)
standing still at the still-water level while waves of 0.5–3.5 m passed through it: at W3 the floats drowned under
the crests and hung in the air over the troughs. The checks here are independent of the model's code: the surface
normal comes from finite differences of the elevation (not the field's slopes), and the buoys' heights from rays
cast down on them in the simulation's scene.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from mmusv.classes import SemanticClass
from mmusv.simulation import Simulation
from mmusv.world.buoys import buoy_matrices, buoy_poses
from mmusv.world.sea_state import sea_spec_for_preset

MARK_TOP_M = 3.8
"""Height of a buoy's top mark above its waterline (``mmusv.world.port.buoy_mesh``: "3.8 m above water")."""


def _scenario(*, motion: str) -> dict[str, Any]:
    return {
        "name": "buoys",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0, "n_buoys": 4}},
        "environment": {"time_of_day": "11:00", "weather": "clear", "wave": "W3", "motion": motion},
        "acquisition": {"frequency_hz": 2, "frames": 8},
        "rigs": {"r": {"preset": "lidar_only"}},
        "vessels": [{"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0,
                     "route": [[-300, -300], [-200, -300]]}],
    }  # fmt: skip


def _normals(field: Any, xy: np.ndarray, t: float) -> np.ndarray:
    """``(N, 3)`` unit normals of the surface at ``xy`` from central differences of its elevation."""
    h, x, y = 1e-3, xy[:, 0].copy(), xy[:, 1].copy()
    ex = field.elevation(x + h, y, t) - field.elevation(x - h, y, t)
    ey = field.elevation(x, y + h, t) - field.elevation(x, y - h, t)
    n = np.stack([-ex / (2 * h), -ey / (2 * h), np.ones(len(x))], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_a_buoy_stands_on_the_surface_along_its_normal() -> None:
    field = sea_spec_for_preset("W3").field(scenario_seed=3)
    rng = np.random.default_rng(0)
    xy = rng.uniform(-400.0, 400.0, size=(40, 2))
    for t in (0.0, 7.3, 61.0):
        poses = buoy_poses(field, xy, t)
        assert poses.shape == (40, 6) and np.array_equal(poses[:, :2], xy) and not poses[:, 5].any()
        assert np.array_equal(poses[:, 2], field.elevation(xy[:, 0].copy(), xy[:, 1].copy(), t))
        normal = _normals(field, xy, t)
        axis = buoy_matrices(field, xy, t)[:, :3, 2]
        np.testing.assert_allclose(axis, normal, atol=1e-6)
        assert np.degrees(np.arccos(normal[:, 2])).max() > 2.0  # the sea tilts them visibly: the check means something
    rest = buoy_matrices(None, xy, 5.0)
    assert np.array_equal(rest[:, :3, :3], np.broadcast_to(np.eye(3), (40, 3, 3)))
    assert np.array_equal(rest[:, :2, 3], xy) and not rest[:, 2, 3].any()


def _marks(sim: Simulation, frame: int, above: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays straight down on the points ``above`` ``(B, 2)`` after ``set_frame(frame)``: the instance and class
    hit and the height of the hit."""
    sim.set_frame(frame)
    origins = np.column_stack([above, np.full(len(above), 60.0)])
    down = np.tile([0.0, 0.0, -1.0], (len(above), 1))
    hits = sim.ws.scene.cast_rays(origins, down)
    return hits.instance_id, hits.semantic_class, 60.0 - hits.distance


@pytest.mark.parametrize("motion", ["physical", "paper"])
def test_each_buoy_is_its_own_instance_and_rides_the_sea(motion: str) -> None:
    sim = Simulation(_scenario(motion=motion))
    xy = sim.world.priors.buoys
    assert len(xy) >= 2
    ids = np.asarray(sim.ws.buoy_instances)
    assert len(np.unique(ids)) == len(xy)  # one instance id a buoy, not one for all of them
    others = set(sim.ws.static_instances.values()) | set(sim.ws.vessel_instances.tolist())
    assert not set(ids.tolist()) & others
    field = sim.scenario.environment.sea_spec().field(scenario_seed=sim.scenario.seed)
    tops = []
    for frame in (0, 3, 7):
        t = frame / 2.0
        if motion == "physical":
            # The mark's tip stands its height above the water at the buoy, along the surface's normal there.
            tip = np.column_stack([xy, field.elevation(xy[:, 0].copy(), xy[:, 1].copy(), t)])
            tip += MARK_TOP_M * _normals(field, xy, t)
        else:  # the paper's flat water: at rest
            tip = np.column_stack([xy, np.full(len(xy), MARK_TOP_M)])
        inst, cls, z = _marks(sim, frame, tip[:, :2])
        assert np.array_equal(inst, ids) and (cls == int(SemanticClass.BUOY)).all()
        np.testing.assert_allclose(z, tip[:, 2], atol=0.05)
        tops.append(z)
    moved = np.ptp(np.array(tops), axis=0).max()
    assert moved > 0.5 if motion == "physical" else moved == 0.0
