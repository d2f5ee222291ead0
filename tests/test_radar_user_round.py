"""The marine radar as a radar user and a perception researcher meet it (a helper's round): each check against an
independent computation written out here.

* Blind sectors: a USV's default radar sees all round. Until 2026-12-06 both USV assets mounted it just forward of
  their own mast and below its top (the 12 m patrol boat 0.15 m before a 0.2 m mast, 0.6 m below its top; the WAM-V
  0.13 m before an 8 cm mast, below its yard), so the mast hid a sector astern from the radar: a 6 m target 150 m
  off went unseen from 164° to 196° off the bow (patrol boat) and 172° to 188° (WAM-V), a blind sector astern of
  ~30°, far more than a real installation accepts (and an antenna 0.15 m from a mast could not turn). The mounts now
  sit above the mast top, clear of every part of the hull.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
from mmusv import Simulation
from mmusv.classes import SemanticClass
from mmusv.world.vessels import library

REPO = Path(__file__).resolve().parents[1]
USV_ASSETS = sorted(a.name for a in library() if a.category == "usv")


def _cube(half: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    a = half
    v = np.array(
        [[-a, -a, -a], [a, -a, -a], [a, a, -a], [-a, a, -a], [-a, -a, a], [a, -a, a], [a, a, a], [-a, a, a]],
        dtype=np.float64,
    )
    f = np.array(
        [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]],
        dtype=np.int64,
    )  # fmt: skip
    return v, f


# --------------------------------------------------------------------------------------------------- blind sectors


@pytest.mark.parametrize("asset", USV_ASSETS)
def test_the_default_radar_sees_all_round(asset: str) -> None:
    """A ring of 6 m cubes 150 m around the USV, one every 4° (each 2.3° wide), on a calm sea: the USV's default
    radar (its asset's mount) returns from every one of them. Before the fix the patrol boat's mast hid those from
    164° to 196° off the bow, the WAM-V's from 172° to 188°."""
    sc = {
        "name": "ring",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"wave": "W0"},
        "acquisition": {"frequency_hz": 5, "frames": 1},
        "rigs": {"r": {"lidar": None, "cameras": [], "top_view": None, "radar": {"azimuth_bins": 1024}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": asset, "rig": "r", "speed_mps": 2.0, "route": [[0, 0], [200, 0]]}
        ],
    }
    sim = Simulation(sc)
    scene = sim.ws.scene
    v, f = _cube(3.0)
    mesh = scene.add_mesh(v, f, classes=int(SemanticClass.VESSEL))
    bearings = np.arange(0.0, 360.0, 4.0)
    ids = []
    for b in np.radians(bearings):
        pose = np.eye(4)
        pose[:3, 3] = [150.0 * math.cos(b), 150.0 * math.sin(b), 2.0]
        ids.append(scene.add_instance(mesh, pose=pose))
    ret = sim.capture(0, sensors=["radar"]).agents["u"].radar
    assert ret is not None
    assert abs(ret.sensor_yaw) < 0.05  # the USV heads east, as the ring's bearings are counted
    unseen = [float(b) for b, i in zip(bearings, ids, strict=True) if not (ret.instance_id == i).any()]
    assert unseen == [], f"{asset}: the radar does not see the targets at bearings {unseen}°"
    assert not (ret.instance_id == sim.vessels[0].instance_id).any(), "a return from the own hull"
    # And no ray of the fan (-10°..10°, every 0.5° of azimuth and 1° of elevation) meets the own hull.
    az, el = np.meshgrid(np.radians(np.arange(0.0, 360.0, 0.5)), np.radians(np.arange(-10.0, 10.5, 1.0)))
    az, el = az.ravel(), el.ravel()
    d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1) @ ret.pose[:3, :3].T
    hits = scene.cast_rays(np.repeat(ret.pose[None, :3, 3], len(d), axis=0), d, max_range=50.0)
    own = hits.instance_id == sim.vessels[0].instance_id
    assert not own.any(), f"{asset}: {int(own.sum())} of the fan's rays meet the own hull, e.g. at azimuth " + str(
        sorted({round(float(np.degrees(a))) for a in az[own]})[:5]
    )
