"""Regressions found by a soak of random valid scenarios (invariants of the outputs, checked independently)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from mmusv.acquire import annotations_for
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Simulation

# Small boats 30 m from the USV, across a 90° camera and round its edges: where lens distortion moves
# them most, and in the pinhole image partly or wholly outside.
BEARINGS_DEG = (-49, -47, -45, -42, -30, -20, 20, 30, 42, 45, 47, 49)


def _lens_scenario(lens: list[float]) -> dict[str, Any]:
    vessels: list[dict[str, Any]] = [
        {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[0, 0], [10, 0]]}
    ]
    for i, deg in enumerate(BEARINGS_DEG):
        x, y = 30.0 * math.cos(math.radians(deg)), 30.0 * math.sin(math.radians(deg))
        vessels.append({"id": f"t{i}", "asset": "speedboat_5m", "route": [[x, y], [x, y + 10]]})
    camera = {"name": "front", "resolution": [160, 60], "quality": "draft", "mount": {"point": "camera_front"}}
    return {
        "name": "lens_boxes",
        "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 1000.0, "islet_probability": 0.0, "n_buoys": 0}},
        "environment": {"motion": "paper"},
        "acquisition": {"frames": 1},
        "rigs": {"r": {"lidar": None, "radar": None, "top_view": None, "cameras": [{**camera, "distortion": lens}]}},
        "vessels": vessels,
    }


LENSES = {"barrel": [-0.12, 0, 0, 0, 0], "pincushion": [0.3, 0, 0, 0, 0], "tangential": [0, 0, 0.02, -0.02, 0]}


@pytest.mark.parametrize("lens", sorted(LENSES))
def test_2d_boxes_hold_every_pixel_of_their_vessel_through_lens_distortion(lens: str) -> None:
    """A camera with Brown–Conrady distortion renders the distorted image; its 2D boxes must be in the same pixels:
    every pixel of a vessel lies inside that vessel's box, and a vessel that shows in the image has a box. (The boxes
    were the ideal pinhole's: with barrel distortion a boat at the image edge lay up to 8 px outside its box.)"""
    sim = Simulation(_lens_scenario(LENSES[lens]))
    cap = sim.capture(0)
    cam = annotations_for(sim, cap, SilhouetteCache())["usv_1"].columns()["camera"]
    instance = cap.agents["usv_1"].cameras["front"].instance
    h, w = instance.shape
    seen = 0
    for v in sim.vessels[1:]:
        ys, xs = np.nonzero(instance == v.instance_id)
        rows = [j for j, t in enumerate(cam["target_id"]) if t == v.id]
        if xs.size == 0:
            continue
        seen += 1
        assert len(rows) == 1, f"{v.id} shows in {xs.size} pixels but has no 2D box"
        j = rows[0]
        x0, y0, x1, y1 = (float(cam[c][j]) for c in ("x_min", "y_min", "x_max", "y_max"))
        assert 0 <= x0 < x1 <= w and 0 <= y0 < y1 <= h
        # Pixel (u, v) covers [u, u + 1) x [v, v + 1): its centre must lie inside the box.
        assert x0 <= xs.min() + 0.5 and xs.max() + 0.5 <= x1, f"{v.id}: pixels {xs.min()}..{xs.max()} vs [{x0}, {x1}]"
        assert y0 <= ys.min() + 0.5 and ys.max() + 0.5 <= y1, f"{v.id}: pixels {ys.min()}..{ys.max()} vs [{y0}, {y1}]"
        assert cam["visible_pixels"][j] == xs.size
    assert seen >= 4


def _ripple_scenario(environment: dict[str, Any]) -> dict[str, Any]:
    lidar = {"channels": 4, "points_per_second": 4 * 5 * 64}
    return {
        "name": "ripples",
        "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 1000.0, "islet_probability": 0.0}},
        "environment": environment,
        "acquisition": {"frames": 1},
        "rigs": {"r": {"preset": "lidar_only", "lidar": lidar}},
        "vessels": [{"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[0, 0], [10, 0]]}],
    }


@pytest.mark.parametrize("environment", [{"wave": 0.009}, {"sea": {"hs_m": 0.01}}, {"sea": {"hs_m": 1e-4, "gamma": 3}}])
def test_every_wave_height_from_0_to_25_m_has_a_sea(environment: dict[str, Any]) -> None:
    """``wave`` and ``sea.hs_m`` take any height in 0..25 m. A fully developed sea below about 1 cm has a peak period
    under the core's 0.5 s: ``wave: 0.009`` passed the scenario schema and then failed building the simulation
    ("invalid config tp_s = 0.474", a field the user never wrote), and ``sea: {hs_m: 0.01}`` was refused the same
    way. Such ripples now take the shortest period the core models."""
    sim = Simulation(_ripple_scenario(environment))
    assert sim.sea is not None and sim.sea.tp_s == 0.5
    cap = sim.capture(0)
    assert np.isfinite(cap.world.poses).all()
