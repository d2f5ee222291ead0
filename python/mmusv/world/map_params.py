"""Parameters of the procedural maps: one frozen dataclass per kind, validated on construction.

Every length is metres. A bad value raises :class:`MapConfigError` (a ``ValueError`` and an
``mmusv.ConfigError``) naming the field and what is allowed; YAML-style lists are accepted for pairs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from mmusv.errors import ConfigError

__all__ = [
    "MAP_KINDS",
    "COAST_SIDES",
    "DEFAULT_MOORED_ASSETS",
    "MapConfigError",
    "IslandParams",
    "OpenSeaParams",
    "PortParams",
    "MapParams",
    "make_params",
]

MAP_KINDS = ("island", "open_sea", "port")
DEFAULT_MOORED_ASSETS: tuple[tuple[str, float, float], ...] = (
    # (asset name in the vessel library, length overall m, beam m), figures as in vessel_catalog.yaml
    ("container_ship_300m", 300.0, 48.2),
    ("feeder_container_140m", 140.0, 22.5),
    ("general_cargo_120m", 120.0, 20.0),
    ("ropax_ferry_90m", 90.0, 16.8),
    ("offshore_supply_85m", 85.0, 18.0),
    ("tug_32m", 32.0, 12.0),
    ("pilot_boat_16m", 16.5, 5.2),
    ("fishing_boat_12m", 12.0, 4.3),
)


class MapConfigError(ConfigError, ValueError):  # type: ignore[misc,unused-ignore]
    """A map parameter is invalid. ``field`` names it, ``allowed`` says what is accepted."""

    def __init__(self, field: str, value: object, allowed: str) -> None:
        super().__init__(f"map parameter {field}={value!r} is invalid; allowed: {allowed}")
        self.field = field
        self.allowed = allowed


# ---------------------------------------------------------------------------------------------- parameters


def _num(obj: object, name: str, lo: float, hi: float, *, integer: bool = False) -> None:
    v = getattr(obj, name)
    kind = "an integer" if integer else "a number"
    ok_type = isinstance(v, (int, np.integer)) if integer else isinstance(v, (int, float, np.integer, np.floating))
    if isinstance(v, bool) or not ok_type or not np.isfinite(v) or not lo <= v <= hi:
        raise MapConfigError(name, v, f"{kind} in [{lo:g}, {hi:g}]")
    object.__setattr__(obj, name, int(v) if integer else float(v))


def _pair(obj: object, name: str, lo: float, hi: float) -> None:
    v = getattr(obj, name)
    allowed = f"two numbers [a, b] with {lo:g} <= a <= b <= {hi:g}"
    try:
        a, b = (float(x) for x in v)
    except (TypeError, ValueError):
        raise MapConfigError(name, v, allowed) from None
    if any(isinstance(x, bool) for x in v) or not (np.isfinite(a) and np.isfinite(b) and lo <= a <= b <= hi):
        raise MapConfigError(name, v, allowed)
    object.__setattr__(obj, name, (a, b))


def _resolved(value: float | None) -> float:
    if value is None:  # pragma: no cover - callers resolve first
        raise RuntimeError("unresolved map parameter")
    return float(value)


@dataclass(frozen=True)
class _CommonParams:
    """Parameters shared by every map kind (metres)."""

    extent_m: float = 2000.0
    """Side of the square map."""
    grid_m: float = 5.0
    """Terrain heightfield spacing (effective value: ``extent_m / round(extent_m / grid_m)``)."""
    prior_resolution_m: float = 5.0
    """Prior raster cell size (effective value: ``extent_m / round(extent_m / prior_resolution_m)``)."""
    draft_margin_m: float = 2.0
    """Terrain shallower than this below the surface is not navigable."""
    clearance_m: float = 30.0
    """Shore / structure / map-edge clearance of the valid sampling zones."""
    occlusion_height_m: float = 3.0
    """Terrain and structures higher than this block line of sight in the priors."""
    n_buoys: int = 0
    """Extra free-standing buoys placed at random in open water (at most this many)."""

    def _validate(self) -> None:
        _num(self, "extent_m", 200.0, 20000.0)
        _num(self, "grid_m", 1.0, 20.0)
        if (self.extent_m / self.grid_m) ** 2 > 4.0e6:
            raise MapConfigError("grid_m", self.grid_m, f">= extent_m / 2000 = {self.extent_m / 2000.0:g}")
        _num(self, "prior_resolution_m", 0.5, 50.0)
        if self.extent_m / self.prior_resolution_m > 8000.0:
            raise MapConfigError(
                "prior_resolution_m", self.prior_resolution_m, f">= extent_m / 8000 = {self.extent_m / 8000.0:g}"
            )
        _num(self, "draft_margin_m", 0.0, 20.0)
        _num(self, "clearance_m", 0.0, self.extent_m / 4.0)
        _num(self, "occlusion_height_m", 0.5, 100.0)
        _num(self, "n_buoys", 0, 500, integer=True)


@dataclass(frozen=True)
class IslandParams(_CommonParams):
    """``island`` map: several islands of varied size on open water."""

    n_islands: int = 5
    island_radius_m: tuple[float, float] = (60.0, 280.0)
    """Range of mean coast radii."""
    island_height_m: tuple[float, float] = (15.0, 80.0)
    """Range of peak heights (capped at 0.35 x radius)."""
    min_gap_m: float = 120.0
    """Minimum open-water gap between two islands' coasts."""
    coast_roughness: float = 0.25
    """Relative coastline irregularity (0 = round)."""
    vegetation: bool = True
    """Label gentle terrain above ~4 m as VEGETATION."""
    n_buoys: int = 2

    def __post_init__(self) -> None:
        self._validate()
        _num(self, "n_islands", 0, 50, integer=True)
        _pair(self, "island_radius_m", 15.0, self.extent_m / 2.0)
        _pair(self, "island_height_m", 1.0, 500.0)
        _num(self, "min_gap_m", 0.0, self.extent_m / 2.0)
        _num(self, "coast_roughness", 0.0, 0.5)
        if not isinstance(self.vegetation, bool):
            raise MapConfigError("vegetation", self.vegetation, "true or false")


@dataclass(frozen=True)
class OpenSeaParams(_CommonParams):
    """``open_sea`` map: open water, a few buoys and maybe one distant small islet."""

    extent_m: float = 4000.0
    islet_probability: float = 0.5
    islet_radius_m: tuple[float, float] = (25.0, 70.0)
    islet_height_m: tuple[float, float] = (5.0, 20.0)
    vegetation: bool = True
    n_buoys: int = 4

    def __post_init__(self) -> None:
        self._validate()
        _num(self, "islet_probability", 0.0, 1.0)
        _pair(self, "islet_radius_m", 10.0, self.extent_m / 4.0)
        _pair(self, "islet_height_m", 1.0, 200.0)
        if not isinstance(self.vegetation, bool):
            raise MapConfigError("vegetation", self.vegetation, "true or false")


COAST_SIDES = ("north", "south", "east", "west")


@dataclass(frozen=True)
class PortParams(_CommonParams):
    """``port`` map: land on one side with quay, piers, breakwaters and a harbour entrance, container yard,
    gantry cranes, buildings, channel buoys and moored ships. Layout distances are metres from the quay line.

    Layout knobs left at ``None`` scale with ``extent_m`` (values in brackets are those for 2000 m) and are
    replaced by the resolved numbers, so ``MapWorld.params`` always records what was built.
    """

    coast_side: str = "north"
    """Side of the map the land is on: north, south, east or west."""
    coast_offset_m: float | None = None
    """Distance from the map centre to the quay line, towards the land [0.125 extent: 250]."""
    harbour_width_m: float | None = None
    """Length of the harbour front between the two breakwater roots [0.5 extent: 1000]."""
    harbour_depth_m: float | None = None
    """Distance from the quay line out to the outer breakwater arms [0.21 extent: 420]."""
    entrance_width_m: float | None = None
    """Gap between the breakwater heads, at their toes [0.1 extent within 60..250: 200]."""
    quay_height_m: float = 2.5
    basin_depth_m: float = 14.0
    n_piers: int | None = None
    """Piers in the eastern 40 % of the harbour front [2, or as many as fit]."""
    pier_length_m: tuple[float, float] | None = None
    """Range of pier lengths [(0.07, 0.13) extent: (140, 260), at most harbour_depth_m - 100]."""
    pier_width_m: float = 24.0
    n_cranes: int | None = None
    """Gantry cranes along the container-terminal quay [4, or as many as fit]."""
    container_fill: float = 0.8
    """Probability that a container-stack slot in the yard is occupied."""
    max_container_tiers: int = 5
    n_buildings: int = 8
    n_channel_buoy_pairs: int = 3
    n_moored: int = 4
    moored_assets: tuple[tuple[str, float, float], ...] = DEFAULT_MOORED_ASSETS
    """Candidate moored ships: ``(asset_name, length_m, beam_m)``."""
    hill_height_m: float = 35.0
    vegetation: bool = True

    def _auto(self, name: str, value: object) -> None:
        if getattr(self, name) is None:
            object.__setattr__(self, name, value)

    def __post_init__(self) -> None:
        self._validate()
        e = self.extent_m
        if e < 600.0:
            raise MapConfigError("extent_m", e, "a number in [600, 20000] for a port map")
        half = e / 2.0
        if self.coast_side not in COAST_SIDES:
            raise MapConfigError("coast_side", self.coast_side, " | ".join(COAST_SIDES))
        self._auto("coast_offset_m", 0.125 * e)
        _num(self, "coast_offset_m", -half + 300.0, half - 150.0)
        self._auto("harbour_width_m", 0.5 * e)
        _num(self, "harbour_width_m", 200.0, e - 300.0)
        q, hw = _resolved(self.coast_offset_m), _resolved(self.harbour_width_m)
        self._auto("harbour_depth_m", float(np.clip(0.21 * e, 120.0, q + half - 100.0)))
        _num(self, "harbour_depth_m", 120.0, q + half - 100.0)
        hd = _resolved(self.harbour_depth_m)
        self._auto("entrance_width_m", float(np.clip(0.1 * e, 60.0, min(250.0, hw - 140.0))))
        _num(self, "entrance_width_m", 60.0, hw - 140.0)
        _num(self, "quay_height_m", 1.0, 6.0)
        _num(self, "basin_depth_m", self.draft_margin_m + 3.0, 40.0)
        _num(self, "pier_width_m", 8.0, 60.0)
        piers_max = max(int((0.4 * hw - 60.0) // (self.pier_width_m + 80.0)), 0)
        self._auto("n_piers", min(2, piers_max))
        _num(self, "n_piers", 0, piers_max, integer=True)
        longest = max(hd - 100.0, 30.0)
        self._auto(
            "pier_length_m", (min(max(round(0.07 * e, 1), 30.0), longest), min(max(round(0.13 * e, 1), 30.0), longest))
        )
        _pair(self, "pier_length_m", 30.0, longest)
        terminal = (0.6 if self.n_piers else 1.0) * hw - 60.0
        cranes_max = max(int(terminal // 35.0), 0)
        self._auto("n_cranes", min(4, cranes_max))
        _num(self, "n_cranes", 0, cranes_max, integer=True)
        _num(self, "container_fill", 0.0, 1.0)
        _num(self, "max_container_tiers", 1, 8, integer=True)
        _num(self, "n_buildings", 0, 200, integer=True)
        _num(self, "n_channel_buoy_pairs", 0, 50, integer=True)
        _num(self, "n_moored", 0, 50, integer=True)
        _num(self, "hill_height_m", 0.0, 200.0)
        if not isinstance(self.vegetation, bool):
            raise MapConfigError("vegetation", self.vegetation, "true or false")
        allowed = "a list of [asset_name, length_m > 0, beam_m > 0] (non-empty when n_moored > 0)"
        try:
            assets = tuple((str(a), float(length), float(beam)) for a, length, beam in self.moored_assets)
        except (TypeError, ValueError):
            raise MapConfigError("moored_assets", self.moored_assets, allowed) from None
        if any(not a or length <= 0.0 or beam <= 0.0 for a, length, beam in assets) or (self.n_moored and not assets):
            raise MapConfigError("moored_assets", self.moored_assets, allowed)
        object.__setattr__(self, "moored_assets", assets)


MapParams = IslandParams | OpenSeaParams | PortParams
_PARAM_TYPES: dict[str, type[IslandParams] | type[OpenSeaParams] | type[PortParams]] = {
    "island": IslandParams,
    "open_sea": OpenSeaParams,
    "port": PortParams,
}


def make_params(kind: str, **params: Any) -> MapParams:
    """Validated parameters of map ``kind`` from keyword values (lists are accepted for pairs).

    Raises :class:`MapConfigError` naming ``kind`` or the first unknown/invalid field and the allowed values.
    """
    if kind not in _PARAM_TYPES:
        raise MapConfigError("kind", kind, " | ".join(MAP_KINDS))
    cls = _PARAM_TYPES[kind]
    names = sorted(f.name for f in dataclasses.fields(cls))
    for key in params:
        if key not in names:
            raise MapConfigError(key, params[key], f"a parameter of the {kind} map: {', '.join(names)}")
    return cls(**params)
