"""The physical sea of a scenario: sea-state presets and the resolved directional spectrum.

The sea is a directional JONSWAP spectrum (Hasselmann et al. 1973; Pierson–Moskowitz 1964 as γ = 1) with cos-2s
spreading (Longuet-Higgins et al. 1963, Mitsuyasu et al. 1975), realised in the core as one seeded wave field
(``mmusv._core.WaveField``; Rust ``mmusv_core::ocean``). Presets (their one definition is the core's
``ocean::presets``):

* WMO sea state code 0–9 (WMO code table 3700, the Douglas sea scale): Hs = the middle of the code's band.
* The paper's W0–W3: Hs = the paper's H (0.5, 1.5, 2.5, 3.5 m).
* Both with the peak period and wind of a fully developed sea (Pierson & Moskowitz 1964:
  Tp = 2π U/(0.877 g), Hs = 0.21 U²/g, U at 19.5 m), γ = 1, spreading s = 10 (Goda 1985, wind sea).

A scenario sets its sea with ``environment.sea`` (``{state: 0..9}`` or ``{hs_m, tp_s, gamma}``, plus
``direction_deg`` and ``spread_s``); without it the sea follows ``environment.wave`` (a preset W0–W3 or a height
in metres, taken as Hs of a fully developed sea). Directions are where the waves travel towards, degrees
counter-clockwise from east (+x) in the config, radians in :class:`SeaSpec`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import ConfigError

__all__ = [
    "MIN_TP_S",
    "SEA_PRESETS",
    "TP_RANGE_S",
    "SeaPreset",
    "SeaSpec",
    "sea_spec_for_height",
    "sea_spec_for_preset",
]

DEFAULT_SPREAD_S = 10.0
"""cos-2s exponent of the presets (wind sea, Goda 1985)."""
TP_RANGE_S: tuple[float, float] = core.sea_limits()["tp_s"]
"""Peak periods the core's sea takes, seconds (``ocean::field::TP_RANGE_S``, 0.5..30 s)."""
MIN_TP_S: float = TP_RANGE_S[0]
"""Shortest peak period, seconds: the fully developed period of a sea below about 1 cm (Tp = 4.99 √Hs) is raised
to it."""


class SeaPreset(NamedTuple):
    """A named sea state: ``name`` ("0".."9" WMO code, "W0".."W3" paper), ``description``, ``hs_m``, ``tp_s``,
    ``gamma`` and the fully developing ``wind_mps`` (at 19.5 m)."""

    name: str
    description: str
    hs_m: float
    tp_s: float
    gamma: float
    wind_mps: float


SEA_PRESETS: dict[str, SeaPreset] = {p[0]: SeaPreset(*p) for p in core.sea_presets()}
"""WMO codes "0".."9", then "W0".."W3", in order (read from the core, their one definition)."""


@dataclass(frozen=True)
class SeaSpec:
    """A resolved sea: ``hs_m`` (m), ``tp_s`` (s), ``gamma``, ``direction_rad`` (travel direction, world frame,
    counter-clockwise from +x), ``spread_s`` (cos-2s exponent)."""

    hs_m: float
    tp_s: float
    gamma: float
    direction_rad: float
    spread_s: float

    def field(self, *, scenario_seed: int) -> Any:
        """The ``mmusv._core.WaveField`` of this sea for a scenario seed (the field's own seed is
        ``core.sea_seed(scenario_seed)``, shared by every consumer). Raises the core's ``ConfigError`` naming
        ``hs_m``, ``tp_s``, ``gamma`` or ``spread_s`` for a sea outside the allowed ranges."""
        return core.WaveField(
            hs_m=self.hs_m,
            tp_s=self.tp_s,
            gamma=self.gamma,
            direction_rad=self.direction_rad,
            spread_s=self.spread_s,
            seed=core.sea_seed(scenario_seed),
        )


def sea_spec_for_preset(name: str, *, direction_deg: float = 0.0, spread_s: float = DEFAULT_SPREAD_S) -> SeaSpec:
    """The sea of a preset name (the strings "0".."9" or "W0".."W3"), travelling towards ``direction_deg``
    (degrees counter-clockwise from east) with spreading ``spread_s``; a :class:`~mmusv.errors.ConfigError`
    (also a ``KeyError``, as before) names the presets for an unknown name."""
    if not isinstance(name, str) or name not in SEA_PRESETS:
        raise UnknownSeaPresetError(
            f"sea preset {name!r:.60} is unknown; the presets are {', '.join(SEA_PRESETS)} (strings: WMO sea state "
            "codes and the paper's W0..W3)"
        )
    p = SEA_PRESETS[name]
    return _checked(SeaSpec(p.hs_m, p.tp_s, p.gamma, _radians(direction_deg), _spread(spread_s)))


def sea_spec_for_height(
    hs_m: float,
    *,
    tp_s: float | None = None,
    gamma: float | None = None,
    direction_deg: float = 0.0,
    spread_s: float = DEFAULT_SPREAD_S,
) -> SeaSpec:
    """The sea of a significant height ``hs_m``: fully developed (Pierson–Moskowitz; at least :data:`MIN_TP_S`, for
    ripples below about 1 cm) unless ``tp_s`` is given; ``gamma`` defaults to 1 for a fully developed sea and to
    DNV-RP-C205's ``exp(5.75 − 1.15 Tp/√Hs)`` (in [1, 5]) for a given period. Every value is a real number; a sea
    outside the core's ranges is a :class:`~mmusv.errors.ConfigError` naming the field (checked here, not first when
    the sea is used)."""
    hs_m = arguments.real(hs_m, name="invalid config hs_m", unit="metres")
    if tp_s is not None:
        tp_s = arguments.real(tp_s, name="invalid config tp_s", unit="seconds")
    if gamma is not None:
        gamma = arguments.real(gamma, name="invalid config gamma")
    if tp_s is None:
        tp, _ = core.fully_developed(hs_m)
        tp = max(tp, MIN_TP_S)  # every height in 0..25 m has a sea (Hs = 1 cm alone would give 0.499 s)
        g = 1.0 if gamma is None else gamma
    else:
        tp = tp_s
        g = core.dnv_gamma(hs_m, tp_s) if gamma is None else gamma
    return _checked(SeaSpec(float(hs_m), float(tp), float(g), _radians(direction_deg), _spread(spread_s)))


class UnknownSeaPresetError(ConfigError, KeyError):  # type: ignore[misc,unused-ignore]
    """No sea preset has this name (a :class:`~mmusv.errors.ConfigError`, and a ``KeyError`` as before)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def _radians(direction_deg: float) -> float:
    return math.radians(arguments.real(direction_deg, name="invalid config direction_deg", unit="degrees"))


def _spread(spread_s: float) -> float:
    return arguments.real(spread_s, name="invalid config spread_s")


def _checked(spec: SeaSpec) -> SeaSpec:
    """``spec`` after the core checked its ranges (it draws the sea's field once, about 2 ms; errors name the
    field: ``hs_m``, ``tp_s``, ``gamma``, ``spread_s``)."""
    spec.field(scenario_seed=0)
    return spec
