"""Rain in the cameras: the drops near the lens (``crates/mmusv-core/src/sensors/shade/rain.rs``, Garg & Nayar's
photometric model of a streak), each as bright as the light it refracts and as long as the exposure lets it fall.

Until 2026-12-07 rain darkened every pixel by 30 % and drew streaks of 12 % of the image's full scale at random:
as bright at midnight, with nothing to light them, as at noon, and over the whole picture. The rain's extinction
is the visibility's (``mmusv.world.rain``), which these scenes fix, so the rain here changes only the drops.
"""

from __future__ import annotations

import copy
import functools
from typing import Any

import mmusv
import numpy as np
import pytest

_SCENE: dict[str, Any] = {
    "name": "rain_drops",
    "seed": 4,
    "map": {"type": "open_sea", "seed": 1, "params": {"n_buoys": 0, "islet_probability": 0.0}},
    "environment": {"time_of_day": "12:00", "weather": "rain", "wave": "W1", "visibility_m": 2000.0},
    "acquisition": {"frequency_hz": 5, "frames": 1},
    "rigs": {
        "view": {
            "lidar": None,
            "radar": None,
            "top_view": None,
            "cameras": [
                {
                    "name": "view",
                    "resolution": [320, 240],
                    "hfov_deg": 70.0,
                    "outputs": ["rgb"],
                    "mount": {"xyz": [0.0, 0.0, 3.0], "rpy_deg": [0.0, -4.0, 100.0]},
                }
            ],
        }
    },
    "vessels": [
        {"id": "observer", "role": "usv", "asset": "usv_wamv", "rig": "view", "route": [[0.0, 0.0], [10.0, 0.0]]},
        {"id": "tug", "asset": "tug_32m", "speed_mps": 2.0, "route": [[-10.4, 59.1], [-10.4, -1940.9]]},
    ],
}


@functools.cache
def _rgb(time_of_day: str, rain_mm_per_h: float) -> np.ndarray:
    """The camera's RGB, int16 ``(H, W, 3)``, read-only: rendered once per time and rain for the module (the dry
    pictures serve several tests)."""
    scene = copy.deepcopy(_SCENE)
    scene["environment"].update(time_of_day=time_of_day, rain_mm_per_h=rain_mm_per_h)
    sim = mmusv.Simulation(scene)
    rgb = sim.capture(0, sensors=["cameras"]).agents["observer"].cameras["view"].rgb
    assert rgb is not None
    out = np.asarray(rgb).astype(np.int16)
    out.flags.writeable = False
    return out


def _change(time_of_day: str, rain_mm_per_h: float) -> np.ndarray:
    """Per pixel, the largest change of a channel (8-bit levels) that the rain makes, against the same air dry."""
    return np.abs(_rgb(time_of_day, rain_mm_per_h) - _rgb(time_of_day, 0.0)).max(axis=-1)


def test_drops_in_the_dark_show_nothing() -> None:
    """At 23:00 (no sun, no twilight) a drop refracts next to no light: the heaviest rain leaves the picture as it
    is to a level (the streaks of 12 % full scale showed up to 112 levels above the black sky and sea)."""
    for rain in (4.0, 50.0):
        assert int(_change("23:00", rain).max()) <= 1, rain


@pytest.mark.parametrize("rain", [4.0, 25.0])
def test_by_day_the_drops_are_few_frozen_dots(rain: float) -> None:
    """At noon the shutter is a fraction of a millisecond: each drop is a dot where it is, and the drops near
    the lens cover a small share of the picture, which stays as it is elsewhere (the 30 % darkening changed
    every pixel). The dots are visible: a drop refracts the bright sky into the darker sea below the horizon."""
    change = _change("12:00", rain)
    seen = float((change >= 3).mean())
    assert 0.0005 < seen < 0.05, seen
    assert float((change == 0).mean()) > 0.8


def _long_runs(changed: np.ndarray) -> float:
    """The 90th percentile of the lengths (pixels) of the vertical runs of ``changed`` pixels (``(H, W)`` bool)."""
    padded = np.pad(changed, ((1, 1), (0, 0))).astype(np.int8)
    edges = np.diff(padded, axis=0)
    starts, ends = np.nonzero(edges.T == 1), np.nonzero(edges.T == -1)
    lengths = ends[1] - starts[1]
    return float(np.percentile(lengths, 90)) if lengths.size else 0.0


def test_a_longer_exposure_draws_longer_fainter_streaks() -> None:
    """At 20:00 the camera exposes 1/30 s: a drop falls down a streak of pixels for a sliver of that time each, so
    it changes each far less than the same rain's frozen dots at noon do, along vertical runs over twice as
    longer."""
    noon, dusk = _change("12:00", 25.0), _change("20:00", 25.0)
    assert int(dusk.max()) < int(noon.max()) // 2, (int(dusk.max()), int(noon.max()))
    runs = _long_runs(noon > 0), _long_runs(dusk > 0)
    assert runs[1] > 2.0 * runs[0], runs
