"""The radar's frequency and polarisation (``RadarConfig.frequency_ghz`` / ``polarisation``): checked on both sides
of the boundary, passed to the core, and the default (9.41 GHz HH) the X-band radar every recording was made with."""

from __future__ import annotations

import mmusv
import pydantic
import pytest
from mmusv import _core as core
from mmusv.sensors.config import RadarConfig
from mmusv.sensors.radar import radar_from_config


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
