"""Shared fixtures of the sensor tests: a small scenario (built once per session) and simple geometry.

The scenario ``sensors_small`` is an open-sea map (no islet, a few buoys) with two instrumented USVs and a tug:

* ``usv_a`` (``usv_patrol_12m``) cruises at 3 m/s on a heading of atan2(200, 300) ≈ 33.7° (north of east) with
  the tug ``tgt`` (``tug_32m``) 45 m ahead and 6 m to port on a parallel course at the same speed, so the tug
  stays in front of ``usv_a``'s front camera and LiDAR for every frame;
* ``usv_b`` (``usv_wamv``) heads north-west (135°) towards the tug's side.

Rigs are small (32-channel LiDAR without range noise, 160×120 cameras, 160×160 top views at 1 m/px) so a
capture takes well under a second; ``usv_a`` has a heading-up top view, ``usv_b`` a north-up one without RGB and
a second camera ``aux`` without RGB.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from typing import Any

import pytest
from mmusv.simulation import Simulation

USV_A_HEADING = math.atan2(200.0, 300.0)

SMALL_SCENARIO: dict[str, Any] = {
    "name": "sensors_small",
    "seed": 5,
    "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0}},
    "environment": {"time_of_day": "11:00", "weather": "clear", "wave": "W1"},
    "acquisition": {"frequency_hz": 5, "frames": 20},
    "rigs": {
        "r": {
            "lidar": {"channels": 32, "points_per_second": 57600, "rotation_hz": 5, "range_noise_std_m": 0.0},
            "cameras": [
                {"name": "front", "resolution": [160, 120], "hfov_deg": 90, "mount": {"point": "camera_front"}}
            ],
            "top_view": {"resolution": [160, 160], "metres_per_pixel": 1.0, "orientation": "heading_up"},
            "radar": None,
        },
        "rn": {
            "lidar": {"channels": 32, "points_per_second": 57600, "rotation_hz": 5, "range_noise_std_m": 0.0},
            "cameras": [
                {"name": "front", "resolution": [160, 120], "hfov_deg": 90, "mount": {"point": "camera_front"}},
                {
                    "name": "aux",
                    "resolution": [48, 32],
                    "hfov_deg": 60,
                    "outputs": ["depth", "semantic", "instance"],
                    "mount": {"point": "camera_left"},
                },
            ],
            "top_view": {
                "resolution": [160, 160],
                "metres_per_pixel": 1.0,
                "orientation": "north_up",
                "outputs": ["semantic", "instance"],
            },
            "radar": None,
        },
    },
    "vessels": [
        {
            "id": "usv_a",
            "role": "usv",
            "asset": "usv_patrol_12m",
            "rig": "r",
            "speed_mps": 3.0,
            "route": [[0, 0], [300, 200]],
        },
        {"id": "tgt", "role": "target", "asset": "tug_32m", "speed_mps": 3.0, "route": [[34.1, 30.0], [334.1, 230.0]]},
        {
            "id": "usv_b",
            "role": "usv",
            "asset": "usv_wamv",
            "rig": "rn",
            "speed_mps": 2.0,
            "route": [[90, -30], [60, 0]],
        },
    ],
}


def small_scenario() -> dict[str, Any]:
    """A fresh deep copy of :data:`SMALL_SCENARIO` (edit it freely)."""
    return copy.deepcopy(SMALL_SCENARIO)


@pytest.fixture()
def make_scenario() -> Callable[[], dict[str, Any]]:
    """A factory of fresh deep copies of the small scenario (edit them freely)."""
    return small_scenario


@pytest.fixture(scope="session")
def sim() -> Simulation:
    """The small scenario, built once. Captures are pure functions of the frame, so sharing it is safe."""
    return Simulation(small_scenario())
