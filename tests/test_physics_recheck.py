"""An outside re-check of the LiDAR water model's calibration numbers, stated in
``crates/mmusv-core/src/sensors/lidar_water.rs`` and ``docs/sea/README.md``, computed here from the cited sources'
formulas (Cox & Munk 1954 slopes, Monahan & O'Muircheartaigh 1980 whitecaps, Koepke 1984 reflectance, Goodman 1976
speckle) with the W1 sea's wind as the sensors take it (the 10 m wind of a fully developed Pierson–Moskowitz sea).

The re-check found the header's calibration point (probability 0.2 at U ≈ 8.4 m/s) to be the 19.5 m wind; the
sensors take 8.2 m/s at 10 m since 2026-11-30, which gives 0.17 — the docs now say both.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from mmusv.sensors.env import wind_from_wave_height

ROOT = Path(__file__).resolve().parents[1]
G = 9.80665
FRESNEL_905 = ((1.328 - 1.0) / (1.328 + 1.0)) ** 2  # water at 905 nm, n ≈ 1.328
WHITECAP_REFLECTANCE = 0.22  # Koepke (1984)
THRESHOLD = 3.2e-4  # the header's I_d


def detection_probability(incidence_deg: float, wind: float, range_m: float) -> float:
    """P_d = exp(−I_d/⟨I⟩), ⟨I⟩ = π β / (1 + (r/100)²), β the Cox–Munk quasi-specular plus Monahan whitecaps."""
    c = math.cos(math.radians(incidence_deg))
    s2 = 0.003 + 5.12e-3 * wind
    tan2 = (1.0 - c * c) / (c * c)
    quasi = FRESNEL_905 * math.exp(-tan2 / s2) / (4.0 * math.pi * s2 * c**4)
    whitecap = min(1.0, 3.84e-6 * wind**3.41) * WHITECAP_REFLECTANCE * c / math.pi
    mean = math.pi * (quasi + whitecap) / (1.0 + (range_m / 100.0) ** 2)
    return math.exp(-THRESHOLD / mean)


def test_w1_winds_and_the_lidar_calibration_point() -> None:
    u19 = math.sqrt(1.5 * G / 0.21)  # PM: Hs = 0.21 U²/g, U at 19.5 m
    u10 = u19 / 1.026
    assert u19 == pytest.approx(8.4, abs=0.05)
    assert wind_from_wave_height(1.5) == pytest.approx(u10, rel=1e-12)
    assert round(u10, 1) == 8.2
    assert detection_probability(80.0, 8.4, 20.0) == pytest.approx(0.2, abs=0.005)
    assert detection_probability(80.0, u10, 20.0) == pytest.approx(0.17, abs=0.005)
    header = (ROOT / "crates/mmusv-core/src/sensors/lidar_water.rs").read_text(encoding="utf-8")
    assert "80° incidence (10° grazing)" in header and "8.2 m/s at 10 m" in header and "it is 0.17" in header
    readme = " ".join((ROOT / "docs/sea/README.md").read_text(encoding="utf-8").split())
    assert "the model's 0.17 detection probability 20 m out, at W1's 8.2 m/s of wind at 10 m" in readme
    # "a whitecap-covered 0.5 % of the footprints ... gives 0.005", "about 35-fold"
    coverage = 3.84e-6 * u10**3.41
    assert coverage == pytest.approx(0.005, abs=0.0002)
    assert detection_probability(80.0, u10, 20.0) / coverage == pytest.approx(35, rel=0.1)
