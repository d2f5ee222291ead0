"""The radar's frequency and polarisation (``RadarConfig.frequency_ghz`` / ``polarisation``): checked on both sides
of the boundary, passed to the core, and the default (9.41 GHz HH) the X-band radar every recording was made with;
and the default rain reflectivity, Marshall–Palmer rain at that band."""

from __future__ import annotations

import math

import mmusv
import numpy as np
import pydantic
import pytest
from mmusv import _core as core
from mmusv.scene import Scene
from mmusv.sensors import sensor_env
from mmusv.sensors.config import RadarConfig
from mmusv.sensors.radar import radar_from_config, radar_sweep


def test_default_is_x_band_hh_and_the_core_gets_the_band() -> None:
    default = RadarConfig()
    assert (default.frequency_ghz, default.polarisation) == (9.41, "HH")
    radar = radar_from_config(RadarConfig(frequency_ghz=3.05, polarisation="VV"))
    assert (radar.frequency_ghz, radar.polarisation) == (3.05, "VV")


@pytest.mark.parametrize(
    ("fields", "name"),
    [
        ({"frequency_ghz": 0.4}, "frequency_ghz"),
        ({"frequency_ghz": 35.5}, "frequency_ghz"),
        ({"frequency_ghz": float("nan")}, "frequency_ghz"),
        ({"polarisation": "HV"}, "polarisation"),
        ({"polarisation": "hh"}, "polarisation"),
    ],
)
def test_bad_band_is_refused_naming_the_field(fields: dict[str, object], name: str) -> None:
    with pytest.raises(pydantic.ValidationError, match=name):
        RadarConfig(**fields)  # type: ignore[arg-type]


def test_the_core_refuses_a_bad_band_too() -> None:
    fields = radar_from_config(RadarConfig())
    base = {
        "range_min_m": 10.0,
        "range_max_m": 3000.0,
        "range_resolution_m": 3.0,
        "azimuth_bins": 64,
        "beamwidth_az_rad": 0.02,
        "elevation_fan_rad": (-0.17, 0.17),
        "rays_az": 1,
        "rays_el": 4,
        "target_rays": 0,
        "horizon_fraction": 0.0,
        "horizon_band_rad": 0.0,
        "detection_threshold": 0.3,
        "range_noise_std_m": 0.0,
        "sea_sigma0_at_1m": 4e-7,
        "critical_range_per_m": 300.0,
        "sea_max_range_m": 2500.0,
        "rain_eta_at_1mm_h": 5e-9,
    }
    assert fields.frequency_ghz == 9.41
    with pytest.raises(mmusv.ConfigError, match=r"radar\.frequency_ghz.*0\.5.*35"):
        core.Radar(**base, frequency_ghz=40.0, polarisation="HH")  # type: ignore[arg-type]
    with pytest.raises(mmusv.ConfigError, match=r"radar\.polarisation.*HH.*VV"):
        core.Radar(**base, frequency_ghz=9.41, polarisation="circular")  # type: ignore[arg-type]


def test_rain_clutter_is_marshall_palmer_rain_over_the_gaussian_fan() -> None:
    """With ``rain_clutter_eta`` set to Marshall–Palmer rain at X band, η = π⁵|K|²Z/λ⁴ with Z = 200 R^1.6 mm⁶/m³
    and |K|² = 0.93 (Skolnik, Introduction to Radar Systems, 3rd ed., §13.6), written out here (5.53e-8 m²/m³ at
    1 mm/h and 9.41 GHz; the default 5e-9 is 10.4 dB below it), a sweep in 10 mm/h of rain with nothing else in
    view gives, every cell drawn (threshold 0), the mean clutter of the radar equation with that η over the beam's
    volume r² θ_az θ_el √(π / (8 ln 2)) Δr (a Gaussian fan's two-way pattern integrated) and the two-way rain loss
    of ITU-R P.838-3 at 9.41 GHz HH (k = 0.009299, α = 1.28951): within 10 % at 100 and 400 m over 2048 beams
    (exponential draws: a 2.2 % standard error). Before 2026-12-01 the volume took the whole θ_el and the loss
    the 10 GHz coefficients."""
    lam = 299_792_458.0 / 9.41e9
    eta_1 = math.pi**5 * 0.93 * 200.0 * 1e-18 / lam**4
    assert eta_1 == pytest.approx(5.525e-8, rel=1e-3)
    cfg = RadarConfig(
        range_m=600.0,
        azimuth_bins=2048,
        rays_az=1,
        rays_el=1,
        detection_threshold=0.0,
        sea_clutter_sigma0=0.0,
        rain_clutter_eta=eta_1,
    )
    rain = 10.0
    env = sensor_env(fog_extinction_per_m=0.0, rain_mm_per_h=rain, wave_height_m=0.0)
    ret = radar_sweep(radar_from_config(cfg), Scene(), pose=np.eye(4), env=env, seed=4)
    lo, hi = cfg.elevation_fan_deg
    for r0 in (100.0, 400.0):
        r = (math.floor(r0 / cfg.range_resolution_m) + 0.5) * cfg.range_resolution_m
        x = ret.intensity[np.abs(ret.range - r) < 1e-3].astype(np.float64)
        volume = (
            r**2
            * math.radians(cfg.beamwidth_deg)
            * math.radians(hi - lo)
            * math.sqrt(math.pi / (8 * math.log(2)))
            * cfg.range_resolution_m
        )
        loss = 10 ** (-2 * 0.009299 * rain**1.28951 * r / 1000 / 10)
        mu = eta_1 * rain**1.6 * volume * (1000.0 / r) ** 4 * loss
        assert len(x) == 2048 and x.mean() / mu == pytest.approx(1.0, rel=0.1), f"{r0} m"
