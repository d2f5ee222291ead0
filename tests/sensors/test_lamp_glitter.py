"""The navigation lamps' glitter on the water at night (``sensors/shade/lamp_glitter.rs``): estimated at every water
pixel from the lamps themselves, so every quality that traces reflections shows the same glitter paths.

Before it, the traced glossy reflections found a lamp only by chance and spread what they found over the lobe: a
ferry 130 m off at midnight left a saturated hard-edged rectangle of water at ``high`` quality and nothing at
``standard``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from mmusv.simulation import Simulation

#: sRGB level above which a water pixel counts as lit by a lamp (the moonless night sea around is 0 to 2).
LIT = 20


def _night(*, quality: str, ferry_speed: float = 6.0) -> dict[str, Any]:
    cam = {"name": "front", "mount": {"point": "camera_front"}, "quality": quality, "resolution": [320, 240]}
    return {
        "name": "night_glitter",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 2},
        "environment": {"time_of_day": "00:00", "weather": "clear", "wave": "W1"},
        "acquisition": {"frequency_hz": 5, "frames": 1},
        "rigs": {"cam": {"cameras": [cam], "lidar": None, "radar": None, "top_view": None}},
        "vessels": [
            {
                "id": "usv_1",
                "role": "usv",
                "asset": "usv_wamv",
                "rig": "cam",
                "speed_mps": 1.5,
                "route": [[0, 0], [100, 0]],
            },
            {
                "id": "ferry",
                "role": "target",
                "asset": "ropax_ferry_90m",
                "speed_mps": ferry_speed,
                "route": [[120, -60], [120, 200]],
            },
        ],
    }


def _front(cfg: dict[str, Any]) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16], npt.NDArray[np.int32]]:
    cam = Simulation(cfg).capture(0).agents["usv_1"].cameras["front"]
    assert cam.rgb is not None and cam.semantic is not None and cam.instance is not None
    return np.asarray(cam.rgb), np.asarray(cam.semantic), np.asarray(cam.instance)


@pytest.fixture(scope="module")
def standard() -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16], npt.NDArray[np.int32]]:
    return _front(_night(quality="standard"))


def test_standard_and_high_show_the_same_glitter(standard: Any) -> None:
    rgb_s, sem, _ = standard
    rgb_h, _, _ = _front(_night(quality="high"))
    water = sem == 1
    lit_s = (rgb_s.max(axis=2) > LIT) & water
    lit_h = (rgb_h.max(axis=2) > LIT) & water
    # The glitter paths are there (before: no lit water pixel at standard; at high, 640 × 480, a saturated
    # rectangle of 4,571).
    assert lit_s.sum() > 0.01 * water.sum(), lit_s.sum()
    assert abs(int(lit_h.sum()) - int(lit_s.sum())) <= 0.05 * lit_s.sum(), (lit_s.sum(), lit_h.sum())
    diff = np.abs(rgb_h.astype(np.int16) - rgb_s.astype(np.int16))[water]
    assert diff.mean() < 0.5, diff.mean()


def test_the_glitter_lies_below_the_ferrys_lamps(standard: Any) -> None:
    rgb, sem, inst = standard
    ids, counts = np.unique(inst[(sem != 1) & (inst >= 0)], return_counts=True)
    ferry = inst == ids[counts.argmax()]  # the largest vessel in view
    cols = np.flatnonzero(ferry.any(axis=0))
    glitter = (rgb.max(axis=2) > LIT) & (sem == 1)
    gcols = np.flatnonzero(glitter.any(axis=0))
    # Each path runs from the ferry's waterline towards the camera, under the lamps: within the ferry's columns.
    assert gcols.size > 0 and cols.min() - 5 <= gcols.min() and gcols.max() <= cols.max() + 5, (cols, gcols)
    rows = np.flatnonzero(glitter.any(axis=1))
    assert rows.min() >= np.flatnonzero(ferry.any(axis=1)).min(), "below the lamps, not above them"


def test_no_glitter_without_lamps() -> None:
    # A ferry at speed 0 is not under way: its lamps are off, and no water pixel lights up.
    rgb, sem, _ = _front(_night(quality="standard", ferry_speed=0.0))
    assert ((rgb.max(axis=2) > LIT) & (sem == 1)).sum() == 0


def test_draft_traces_no_reflections_and_shows_none() -> None:
    rgb, sem, _ = _front(_night(quality="draft"))
    assert ((rgb.max(axis=2) > LIT) & (sem == 1)).sum() == 0
