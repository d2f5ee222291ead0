"""``mmusv.world.rain``: light's extinction by Marshall–Palmer rain drops and the visibility it leaves, and the
weather's default visibility following its rain rate."""

from __future__ import annotations

import math

import pytest
from mmusv.config import EnvironmentConfig
from mmusv.world.environment import Weather
from mmusv.world.rain import rain_extinction_per_m, visibility_in_rain

# σ (1/m) summed numerically over the drop sizes, with Marshall & Palmer's constants written out there, not ours
from test_physics_recheck3 import _rain_extinction_per_m as _summed_extinction_per_m


@pytest.mark.parametrize("rain", [0.5, 1.0, 4.0, 10.0, 25.0, 50.0, 200.0])
def test_the_closed_form_is_the_drop_size_integral(rain: float) -> None:
    assert rain_extinction_per_m(rain) == pytest.approx(_summed_extinction_per_m(rain), rel=1e-6)
    assert rain_extinction_per_m(rain) * 1e3 == pytest.approx(0.365 * rain**0.63, rel=2e-3)  # the docstrings' fit


def test_no_rain_no_extinction_and_extinctions_add() -> None:
    assert rain_extinction_per_m(0.0) == 0.0
    assert visibility_in_rain(20000.0, 0.0) == 20000.0
    # the drops alone (air without haze): 3.4, 1.9, 0.7 km at 4, 10, 50 mm/h
    assert [round(visibility_in_rain(math.inf, r) / 1e3, 1) for r in (4.0, 10.0, 50.0)] == [3.4, 1.9, 0.7]
    for air, rain in ((10000.0, 4.0), (500.0, 4.0), (2000.0, 25.0)):
        sigma = 3.0 / air + _summed_extinction_per_m(rain)
        assert visibility_in_rain(air, rain) == pytest.approx(3.0 / sigma, rel=1e-6)
        assert visibility_in_rain(air, rain) < min(air, visibility_in_rain(math.inf, rain))


def test_the_weathers_visibility_follows_its_rain_when_not_given() -> None:
    """Rain of 4 mm/h alone allows 3.4 km: the rain weather's default visibility was 5 km whatever its rate (25 mm/h,
    which alone allows 1.2 km, too); now it is its air's (an overcast sky's 10 km) with the drops in it."""
    rain = Weather.make("rain")
    assert rain.rain_mm_per_h == 4.0
    assert rain.visibility_m == pytest.approx(3.0 / (3.0 / 10000.0 + _summed_extinction_per_m(4.0)), rel=1e-6)
    assert round(rain.visibility_m) == 2557
    heavy = Weather.make("rain", rain_mm_per_h=25.0)
    assert heavy.visibility_m == pytest.approx(3.0 / (3.0 / 10000.0 + _summed_extinction_per_m(25.0)), rel=1e-6)
    assert Weather.make("rain", rain_mm_per_h=0.0).visibility_m == 10000.0  # a rain sky without its drops
    # rain falling from a fog or an overcast sky thickens its air too
    assert Weather.make("fog", rain_mm_per_h=4.0).visibility_m == pytest.approx(visibility_in_rain(500.0, 4.0))
    assert Weather.make("overcast", rain_mm_per_h=2.0).visibility_m == pytest.approx(visibility_in_rain(1e4, 2.0))
    # without rain, each sky keeps its air's visibility
    assert [Weather.make(k).visibility_m for k in ("clear", "overcast", "fog")] == [20000.0, 10000.0, 500.0]
    # a visibility given is the one in the rain, kept as given
    assert Weather.make("rain", visibility_m=1500.0, rain_mm_per_h=25.0).visibility_m == 1500.0


def test_a_scenarios_environment_resolves_the_same_visibility() -> None:
    env = EnvironmentConfig.model_validate({"weather": "rain", "rain_mm_per_h": 10}).resolve()
    assert env.weather.visibility_m == pytest.approx(visibility_in_rain(10000.0, 10.0))
    assert env.weather.extinction_per_m == pytest.approx(3.0 / 10000.0 + rain_extinction_per_m(10.0))
