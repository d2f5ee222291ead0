"""No sensor is blinded by its own vessel: for every USV asset of the library and every default mount, the own
hull covers under 1 % of the upper half of each surround camera, and no LiDAR or radar return comes from it.

The instance image (exact per pixel) is the independent measure; waves (W2) roll and pitch the hull so the
check does not only hold on a flat sea.
"""

from __future__ import annotations

import numpy as np
import pytest
from mmusv import Simulation
from mmusv.world.vessels import library

USV_ASSETS = sorted(a.name for a in library() if a.category == "usv")


def _scenario(asset: str) -> dict[str, object]:
    cams = [
        {"name": n, "resolution": [160, 120], "mount": {"point": f"camera_{n}"}}
        for n in ("front", "left", "rear", "right")
    ]
    return {
        "name": f"own_hull_{asset}",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"wave": "W2"},
        "acquisition": {"frequency_hz": 5, "frames": 4},
        "rigs": {"r": {"cameras": cams, "top_view": None, "radar": {"azimuth_bins": 512}}},
        "vessels": [
            {
                "id": "u",
                "role": "usv",
                "asset": asset,
                "rig": "r",
                "speed_mps": 2.0,
                "route": [[0.0, 0.0], [200.0, 0.0]],
            }
        ],
    }


def test_every_usv_asset_is_covered() -> None:
    assert len(USV_ASSETS) >= 2


@pytest.mark.parametrize("asset", USV_ASSETS)
def test_no_sensor_sees_its_own_hull(asset: str) -> None:
    sim = Simulation(_scenario(asset))
    own = sim.vessels[0].instance_id
    for frame in (0, 3):
        cap = sim.capture(frame).agents["u"]
        assert set(cap.cameras) == {"front", "left", "rear", "right"}
        for name, img in cap.cameras.items():
            upper = img.instance[: img.instance.shape[0] // 2]
            share = float(np.mean(upper == own))
            assert share < 0.01, f"{asset} camera {name}: own hull on {share:.1%} of the upper half (frame {frame})"
        assert cap.lidar is not None and cap.lidar.xyz.shape[0] > 0
        assert not np.any(cap.lidar.instance == own), f"{asset}: LiDAR returns from the own hull"
        assert cap.radar is not None
        assert not np.any(cap.radar.instance_id == own), f"{asset}: radar returns from the own hull"


def test_the_check_would_catch_a_blinded_camera() -> None:
    """A camera mounted looking back down at the deck sees its own hull: the measure above detects it."""
    cfg = _scenario("usv_patrol_12m")
    rig = cfg["rigs"]["r"]  # type: ignore[index]
    rig["cameras"] = [
        {"name": "down", "resolution": [160, 120], "mount": {"point": "camera_front", "rpy_deg": [0.0, 60.0, 180.0]}}
    ]
    sim = Simulation(cfg)
    img = sim.capture(0).agents["u"].cameras["down"].instance
    assert float(np.mean(img == sim.vessels[0].instance_id)) > 0.05
