"""Vessel motion through the Python API: spline routes at nominal speed and wave perturbations."""

from __future__ import annotations

import mmusv
import numpy as np
import pytest
from mmusv.config import load_scenario
from mmusv.motion import build_fleet, scenario_poses


def scenario(**kw: object) -> dict[str, object]:
    return {
        "seed": 3,
        "acquisition": {"frequency_hz": 10, "frames": 200},
        "environment": {"wave": kw.pop("wave", "W2")},
        "vessels": [
            {"id": "usv", "role": "usv", "asset": "usv_wamv", "speed_mps": 2.0, "route": [[0, 0], [60, 30], [120, 0]]},
            {"id": "big", "asset": "container_ship_300m", "speed_mps": 5.0, "route": [[0, 500], [2000, 500]]},
            {"id": "small", "asset": "jet_ski_3m", "speed_mps": 0.0, "route": [[10, 10], [20, 10]]},
        ],
    }


def test_distance_travelled_follows_speed_and_yaw_follows_tangent() -> None:
    poses = scenario_poses(load_scenario(scenario()))
    assert poses.shape == (200, 3, 6)
    xy = poses[:, 0, :2]
    travelled = np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1))
    assert travelled == pytest.approx(2.0 * 19.9, rel=5e-3)
    heading = np.arctan2(np.diff(xy[:, 1]), np.diff(xy[:, 0]))
    yaw = poses[:-1, 0, 5]
    err = np.angle(np.exp(1j * (heading - yaw)))
    assert np.max(np.abs(err)) < 0.05  # finite-difference heading vs analytic yaw at 10 Hz
    assert np.allclose(poses[:, 2, :2], [10, 10])  # speed 0 stays put


def test_small_vessels_move_more_than_large_ones_and_same_seed_same_poses() -> None:
    s = load_scenario(scenario())
    poses = scenario_poses(s)
    roll_rms = np.sqrt(np.mean(poses[:, :, 3] ** 2, axis=0))
    assert roll_rms[2] > roll_rms[0] > roll_rms[1]
    assert np.array_equal(poses, scenario_poses(load_scenario(scenario())))
    other = load_scenario({**scenario(), "seed": 4})
    assert not np.array_equal(poses, scenario_poses(other))


def test_fleet_rejects_bad_values_by_name() -> None:
    fleet = build_fleet(load_scenario(scenario()))
    with pytest.raises(mmusv.InputError):
        fleet.poses_at(-1.0)
    with pytest.raises(mmusv.ConfigError, match="W0"):
        build_fleet(load_scenario(scenario()), wave="W9")
    s = load_scenario(scenario())
    with pytest.raises(mmusv.ConfigError, match=r"vessels\[0\]"):
        # The Rust side validates too: a route doubling on a point is caught with the vessel named.
        build_fleet(
            s.model_copy(update={"vessels": [s.vessels[0].model_copy(update={"route": [(0.0, 0.0), (0.0, 0.0)]})]})
        )
