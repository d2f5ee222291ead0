"""Environment: sun from time of day, weather presets, wave settings."""

from __future__ import annotations

import math

import mmusv
import pytest
from mmusv._native import core
from mmusv.world.environment import WAVE_PRESETS, Environment, Weather, sun_at, wave_height_m


def test_wave_presets_and_free_height() -> None:
    assert [wave_height_m(w) for w in ("W0", "w1", "W2", "W3")] == [0.5, 1.5, 2.5, 3.5]
    # One definition: the core's presets, in order, are what Python uses (and what the core's parser gives).
    assert list(WAVE_PRESETS.items()) == core.wave_presets() == [("W0", 0.5), ("W1", 1.5), ("W2", 2.5), ("W3", 3.5)]
    assert all(core.wave_height(name) == h for name, h in WAVE_PRESETS.items())
    assert wave_height_m(2.0) == 2.0
    env = Environment.make(wave="W2")
    assert env.wave_amplitude_m == 1.25
    for bad in ("W4", -1.0, float("nan")):
        with pytest.raises(mmusv.ConfigError, match=r"environment\.wave"):
            wave_height_m(bad)


def test_sun_rises_peaks_at_noon_and_sets() -> None:
    noon = sun_at("12:00")
    assert noon.elevation_deg == pytest.approx(90 - 45 + 23.44, abs=0.5)  # summer solstice at 45° N
    assert noon.direction[1] < 0  # due south at noon in the northern hemisphere
    morning, evening = sun_at("07:00"), sun_at("17:00")
    assert morning.direction[0] > 0 > evening.direction[0]  # east in the morning, west in the evening
    assert morning.elevation_deg == pytest.approx(evening.elevation_deg, abs=1e-6)
    night = sun_at("00:30")
    assert night.elevation_deg < 0 and night.intensity == 0.0
    assert math.isclose(sum(c * c for c in noon.direction), 1.0)
    # Warmer (less blue) light near the horizon.
    assert morning.color[2] < noon.color[2] or sun_at("05:30").color[2] < noon.color[2]


def test_weather_defaults_and_validation() -> None:
    fog = Weather.make("fog", visibility_m=800)
    assert fog.extinction_per_m == pytest.approx(3.0 / 800)
    assert Weather.make("rain").rain_mm_per_h > 0
    with pytest.raises(mmusv.ConfigError, match=r"environment\.weather"):
        Weather.make("snow")
    with pytest.raises(mmusv.ConfigError, match="visibility_m"):
        Weather.make("fog", visibility_m=0)
    with pytest.raises(mmusv.ConfigError, match="time_of_day"):
        sun_at("25:00")
