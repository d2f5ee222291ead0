"""Parameters of the procedural maps: one frozen pydantic model per kind, the one definition of every knob.

Every length is metres. In a scenario they sit under ``map.params`` and are checked when the scenario loads
(:class:`mmusv.config.MapConfig` picks the model by ``map.type``), so an error names ``map.params.<field>``.
From Python, :func:`make_params` (and :func:`mmusv.world.maps.generate_map`) raise :class:`MapConfigError` (a
``ValueError`` and an ``mmusv.ConfigError``) naming the field and what is allowed. YAML-style lists are accepted
for pairs. Knobs whose range depends on others (``grid_m`` on ``extent_m``, the port layout on the harbour) are
checked by validators that run in field order, so every error still names its field.
"""

from __future__ import annotations

from typing import Any, TypeVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictBool, ValidationError, ValidationInfo, field_validator

from mmusv.errors import ConfigError
from mmusv.strict import bool_for_a_number

__all__ = [
    "COAST_SIDES",
    "DEFAULT_MOORED_ASSETS",
    "MAP_KINDS",
    "MOORED_SIZE_SLACK_M",
    "PARAM_MODELS",
    "IslandParams",
    "MapConfigError",
    "MapParams",
    "OpenSeaParams",
    "PortParams",
    "make_params",
    "resolved",
]

MAP_KINDS = ("island", "open_sea", "port")
_Berth = tuple[str, float, float]
COAST_SIDES = ("north", "south", "east", "west")
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


def _within(value: float, lo: float, hi: float, *, integer: bool = False, bounds: str = "") -> float:
    """``value`` if ``lo <= value <= hi``, else a ``ValueError`` saying the range; ``bounds`` says where a range
    that depends on other knobs comes from (``"the upper bound is extent_m / 4"``), so that a value the user never
    set (a default) is not blamed alone."""
    if not lo <= value <= hi:
        kind = "an integer" if integer else "a number"
        raise ValueError(f"must be {kind} in [{lo:g}, {hi:g}]" + (f" ({bounds})" if bounds else ""))
    return value


def _pair(value: tuple[float, float], lo: float, hi: float, *, bounds: str = "") -> tuple[float, float]:
    """``(a, b)`` if ``lo <= a <= b <= hi``, else a ``ValueError`` saying so (``bounds`` as for :func:`_within`)."""
    a, b = value
    if not lo <= a <= b <= hi:
        raise ValueError(
            f"must be two numbers [a, b] with {lo:g} <= a <= b <= {hi:g}" + (f" ({bounds})" if bounds else "")
        )
    return value


_EXTENT = "the upper bound is extent_m / {}: set this knob too, or raise extent_m"


def _known(info: ValidationInfo, *names: str) -> bool:
    """Whether every field in ``names`` validated (a field that failed is reported on its own)."""
    return all(n in info.data and info.data[n] is not None for n in names)


_Bounded = TypeVar("_Bounded", float, tuple[float, float])


def _up_to_extent(value: _Bounded, info: ValidationInfo, *, lo: float, divisor: int) -> _Bounded:
    """``value`` (metres: a number, or a pair ``(a, b)``) checked to lie in ``[lo, extent_m / divisor]`` by
    :func:`_within` (or :func:`_pair`), the error saying the upper bound comes from ``extent_m``; unchecked when
    ``extent_m`` itself failed (it is reported on its own)."""
    if not _known(info, "extent_m"):
        return value
    hi, bounds = info.data["extent_m"] / divisor, _EXTENT.format(divisor)
    if isinstance(value, tuple):
        return _pair(value, lo, hi, bounds=bounds)
    return _within(value, lo, hi, bounds=bounds)


_T = TypeVar("_T")


def resolved(value: _T | None) -> _T:
    """A knob left at ``None`` that its parameter model has resolved from ``extent_m`` and the other knobs (never
    ``None`` once the model is built: :class:`IslandParams`, :class:`OpenSeaParams`, :class:`PortParams`)."""
    if value is None:
        raise ValueError("map parameters were not resolved; build them with make_params(kind, ...)")
    return value


def _clamped(default: tuple[float, float], *, lo: float, hi: float) -> tuple[float, float]:
    """A default range of sizes ``default`` (metres) with each end kept within ``[lo, hi]`` (the bounds the map's
    extent allows): the default where it is allowed, so that a map it built before is built the same."""
    a, b = (float(min(max(x, lo), hi)) for x in default)
    return a, b


class _CommonParams(BaseModel):
    """Parameters shared by every map kind (metres)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, validate_default=True)

    extent_m: float = Field(default=2000.0, ge=200.0, le=20000.0)
    """Side of the square map."""
    grid_m: float | None = Field(default=None, ge=1.0, le=20.0)
    """Terrain heightfield spacing (effective value: ``extent_m / round(extent_m / grid_m)``) [5, or ``extent_m /
    2000`` past 10 km, the finest the heightfield's 2000 × 2000 cells allow]."""
    prior_resolution_m: float = Field(default=5.0, ge=0.5, le=50.0)
    """Prior raster cell size (effective value: ``extent_m / round(extent_m / prior_resolution_m)``)."""
    draft_margin_m: float = Field(default=2.0, ge=0.0, le=20.0)
    """Terrain shallower than this below the surface is not navigable."""
    clearance_m: float = Field(default=30.0, ge=0.0)
    """Shore / structure / map-edge clearance of the valid sampling zones (at most ``extent_m / 4``)."""
    occlusion_height_m: float = Field(default=3.0, ge=0.5, le=100.0)
    """Terrain and structures higher than this block line of sight in the priors."""
    n_buoys: int = Field(default=0, ge=0, le=500)
    """Extra free-standing buoys placed at random in open water (at most this many)."""

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, v: Any, info: ValidationInfo) -> Any:
        return bool_for_a_number(cls, v, info)  # as in a scenario's other models (mmusv.strict)

    @field_validator("grid_m")
    @classmethod
    def _grid(cls, v: float | None, info: ValidationInfo) -> float | None:
        if not _known(info, "extent_m"):
            return v
        if v is None:
            return max(5.0, float(info.data["extent_m"]) / 2000.0)
        if (info.data["extent_m"] / v) ** 2 > 4.0e6:
            raise ValueError(f"must be >= extent_m / 2000 = {info.data['extent_m'] / 2000.0:g}")
        return v

    @field_validator("prior_resolution_m")
    @classmethod
    def _prior(cls, v: float, info: ValidationInfo) -> float:
        if _known(info, "extent_m") and info.data["extent_m"] / v > 8000.0:
            raise ValueError(f"must be >= extent_m / 8000 = {info.data['extent_m'] / 8000.0:g}")
        return v

    @field_validator("clearance_m")
    @classmethod
    def _clearance(cls, v: float, info: ValidationInfo) -> float:
        return _up_to_extent(v, info, lo=0.0, divisor=4)


class IslandParams(_CommonParams):
    """``island`` map: several islands of varied size on open water."""

    n_buoys: int = Field(default=2, ge=0, le=500)
    n_islands: int = Field(default=5, ge=0, le=50)
    """Islands on the map. A number the scenario sets is built exactly, and refused where they do not fit (naming
    how many do); left at its default, as many as fit up to 5, and ``MapWorld.params.n_islands`` says how many."""
    island_radius_m: tuple[float, float] | None = None
    """Range of island radii ``R`` (15 m to ``extent_m / 2``) [(60, 280), cut to ``extent_m / 2`` on a map under
    560 m]: a quarter of the islands are one dome of radius ``R``, the rest a main dome of ``0.72 R`` with one to
    three lobes reaching out to ``R``, so an island's farthest coast is about ``R`` from its centre and its
    mean coast radius ``0.75 R`` to ``R`` (before ``coast_roughness``). Where the islands do not fit, ``R`` is cut
    by 15 % at a time (down to 15 m) before the map is refused (or, with ``n_islands`` left at its default, the
    island left out)."""
    island_height_m: tuple[float, float] = (15.0, 80.0)
    """Range of the islands' dome heights (capped at 0.35 x radius); the terrain's relief adds up to 35 % of it up or
    down, so a summit may stand above the range's top: ``[40, 40]`` gives summits of 34-47 m, the defaults up to
    86 m."""
    min_gap_m: float | None = Field(default=None, ge=0.0)
    """Minimum open-water gap between two islands' coasts (at most ``extent_m / 2``) [120, cut to ``extent_m / 2``
    on a map under 240 m]."""
    coast_roughness: float = Field(default=0.25, ge=0.0, le=0.5)
    """Relative coastline irregularity (0 = round)."""
    vegetation: StrictBool = True
    """Label gentle terrain above ~4 m as VEGETATION."""

    @field_validator("island_radius_m")
    @classmethod
    def _radius(cls, v: tuple[float, float] | None, info: ValidationInfo) -> tuple[float, float] | None:
        if v is None and _known(info, "extent_m"):
            v = _clamped((60.0, 280.0), lo=15.0, hi=info.data["extent_m"] / 2.0)
        return v if v is None else _up_to_extent(v, info, lo=15.0, divisor=2)

    @field_validator("island_height_m")
    @classmethod
    def _height(cls, v: tuple[float, float]) -> tuple[float, float]:
        return _pair(v, 1.0, 500.0)

    @field_validator("min_gap_m")
    @classmethod
    def _gap(cls, v: float | None, info: ValidationInfo) -> float | None:
        if v is None and _known(info, "extent_m"):
            v = min(120.0, info.data["extent_m"] / 2.0)
        return v if v is None else _up_to_extent(v, info, lo=0.0, divisor=2)


class OpenSeaParams(_CommonParams):
    """``open_sea`` map: open water, a few buoys and maybe one distant small islet."""

    extent_m: float = Field(default=4000.0, ge=200.0, le=20000.0)
    n_buoys: int = Field(default=4, ge=0, le=500)
    islet_probability: float = Field(default=0.5, ge=0.0, le=1.0)
    islet_radius_m: tuple[float, float] | None = None
    """Range of islet radii (10 m to ``extent_m / 4``) [(25, 70), cut to ``extent_m / 4`` on a map under 280 m]."""
    islet_height_m: tuple[float, float] = (5.0, 20.0)
    vegetation: StrictBool = True

    @field_validator("islet_radius_m")
    @classmethod
    def _radius(cls, v: tuple[float, float] | None, info: ValidationInfo) -> tuple[float, float] | None:
        if v is None and _known(info, "extent_m"):
            v = _clamped((25.0, 70.0), lo=10.0, hi=info.data["extent_m"] / 4.0)
        return v if v is None else _up_to_extent(v, info, lo=10.0, divisor=4)

    @field_validator("islet_height_m")
    @classmethod
    def _height(cls, v: tuple[float, float]) -> tuple[float, float]:
        return _pair(v, 1.0, 200.0)


class PortParams(_CommonParams):
    """``port`` map: land on one side with quay, piers, breakwaters and a harbour entrance, container yard,
    gantry cranes, buildings, channel buoys and moored ships. Layout distances are metres from the quay line.

    Layout knobs left at ``None`` scale with ``extent_m`` (values in brackets are those for 2000 m) and are
    replaced by the resolved numbers, so ``MapWorld.params`` always records what was built (a dump with
    ``exclude_unset`` gives back only what the user set).
    """

    extent_m: float = Field(default=2000.0, ge=600.0, le=20000.0)
    """Side of the square map; a port needs at least 600 m."""
    coast_side: str = "north"
    """Side of the map the land is on: north, south, east or west."""
    coast_offset_m: float | None = None
    """Distance from the map centre to the quay line, towards the land [0.125 extent: 250]. The quay wall's seaward
    face stands ``grid_m`` (its effective value) + 1 m seaward of it, over the terrain's step: at 244 m with the
    defaults, 229 m with ``grid_m: 20``."""
    harbour_width_m: float | None = None
    """Length of the harbour front between the two breakwater roots [0.5 extent: 1000]."""
    harbour_depth_m: float | None = None
    """Distance from the quay line out to the outer breakwater arms [0.21 extent: 420]."""
    entrance_width_m: float | None = None
    """Width of the harbour entrance the breakwater arms are laid out for [0.1 extent within 60..250: 200]. Each arm's
    head reaches 19 m into it (the head's light stands 15 m in, the arm's end 4 m past that), so the open gap between
    the arms' ends is ``entrance_width_m - 38`` m: 162 m by default, 22 m at the least, 60 m; the channel buoy pairs
    stand ``entrance_width_m / 2 - 15`` m either side of its middle, 4 m wider than the gap."""
    quay_height_m: float = Field(default=2.5, ge=1.0, le=6.0)
    basin_depth_m: float = 14.0
    """Water depth in the basin, from ``draft_margin_m + 3`` to 40 m."""
    pier_width_m: float = Field(default=24.0, ge=8.0, le=60.0)
    n_piers: int | None = None
    """Piers in the eastern 40 % of the harbour front [2, or as many as fit]."""
    pier_length_m: tuple[float, float] | None = None
    """Range of pier lengths [(0.07, 0.13) extent: (140, 260), at most harbour_depth_m - 100]."""
    n_cranes: int | None = None
    """Gantry cranes along the container-terminal quay [4, or as many as fit]."""
    container_fill: float = Field(default=0.8, ge=0.0, le=1.0)
    """Probability that a container-stack slot in the yard is occupied."""
    max_container_tiers: int = Field(default=5, ge=1, le=8)
    n_buildings: int = Field(default=8, ge=0, le=200)
    """Warehouses and offices on the land behind the pier section and behind the container yard: at most this many,
    as many as the room there takes, each tried at up to 40 random spots (``n_buildings: 200`` on the default
    2000 m port of seed 3 builds 84; a port under about 900 m has no room: none)."""
    n_channel_buoy_pairs: int = Field(default=3, ge=0, le=50)
    """Pairs of buoys marking the fairway out from the harbour entrance, 150 m apart, the last at least 40 m inside
    the map's edge. Left at its default, as many as fit up to 3; a number the scenario sets is built exactly, and a
    fairway without room for it is refused when the port is built, naming the most that fit."""
    n_moored: int = Field(default=4, ge=0, le=50)
    """Ships moored at the terminal quay and the piers (labelled ``moored_00``, ...). A number the scenario sets is
    moored exactly: a port whose quay and piers have fewer free berths for ``moored_assets`` is refused when it is
    built, naming the most that fit. Left at its default, as many as fit up to 4 (a port under about 900 m has room
    for fewer), and ``MapWorld.params.n_moored`` says how many were moored."""
    moored_assets: tuple[_Berth, ...] = DEFAULT_MOORED_ASSETS
    """Candidate moored ships: ``(asset_name, length_m, beam_m)``, the size its berth is laid out for: the ship's
    own length and beam (or larger, for more room), at most :data:`MOORED_SIZE_SLACK_M` less. No ship whose draft
    reaches ``basin_depth_m`` is moored: an entry given that would ground is refused, and in the default list the 300 m
    container ship (draft 14.5 m, the default basin 14 m) gives way to the longest entry that fits its berth and
    floats (set ``basin_depth_m: 16`` to moor it)."""
    hill_height_m: float = Field(default=35.0, ge=0.0, le=200.0)
    vegetation: StrictBool = True

    @field_validator("coast_side")
    @classmethod
    def _side(cls, v: str) -> str:
        if v not in COAST_SIDES:
            raise ValueError(f"must be one of {' | '.join(COAST_SIDES)}")
        return v

    @field_validator("coast_offset_m")
    @classmethod
    def _offset(cls, v: float | None, info: ValidationInfo) -> float | None:
        if not _known(info, "extent_m"):
            return v
        e = info.data["extent_m"]
        return _within(0.125 * e if v is None else v, -e / 2.0 + 300.0, e / 2.0 - 150.0)

    @field_validator("harbour_width_m")
    @classmethod
    def _width(cls, v: float | None, info: ValidationInfo) -> float | None:
        if not _known(info, "extent_m"):
            return v
        e = info.data["extent_m"]
        return _within(0.5 * e if v is None else v, 200.0, e - 300.0)

    @field_validator("harbour_depth_m")
    @classmethod
    def _depth(cls, v: float | None, info: ValidationInfo) -> float | None:
        if not _known(info, "extent_m", "coast_offset_m"):
            return v
        e, q = info.data["extent_m"], info.data["coast_offset_m"]
        hi = q + e / 2.0 - 100.0
        return _within(float(np.clip(0.21 * e, 120.0, hi)) if v is None else v, 120.0, hi)

    @field_validator("entrance_width_m")
    @classmethod
    def _entrance(cls, v: float | None, info: ValidationInfo) -> float | None:
        if not _known(info, "extent_m", "harbour_width_m"):
            return v
        e, hw = info.data["extent_m"], info.data["harbour_width_m"]
        return _within(float(np.clip(0.1 * e, 60.0, min(250.0, hw - 140.0))) if v is None else v, 60.0, hw - 140.0)

    @field_validator("basin_depth_m")
    @classmethod
    def _basin(cls, v: float, info: ValidationInfo) -> float:
        if not _known(info, "draft_margin_m"):
            return v
        why = "the lower bound is draft_margin_m + 3: set basin_depth_m too, or lower draft_margin_m"
        return _within(v, info.data["draft_margin_m"] + 3.0, 40.0, bounds=why)

    @field_validator("n_piers")
    @classmethod
    def _piers(cls, v: int | None, info: ValidationInfo) -> int | None:
        if not _known(info, "harbour_width_m", "pier_width_m"):
            return v
        most = max(int((0.4 * info.data["harbour_width_m"] - 60.0) // (info.data["pier_width_m"] + 80.0)), 0)
        return int(_within(min(2, most) if v is None else v, 0, most, integer=True))

    @field_validator("pier_length_m")
    @classmethod
    def _pier_length(cls, v: tuple[float, float] | None, info: ValidationInfo) -> tuple[float, float] | None:
        if not _known(info, "extent_m", "harbour_depth_m"):
            return v
        e = info.data["extent_m"]
        longest = max(info.data["harbour_depth_m"] - 100.0, 30.0)
        if v is None:
            v = (min(max(round(0.07 * e, 1), 30.0), longest), min(max(round(0.13 * e, 1), 30.0), longest))
        return _pair(v, 30.0, longest)

    @field_validator("n_cranes")
    @classmethod
    def _cranes(cls, v: int | None, info: ValidationInfo) -> int | None:
        if not _known(info, "harbour_width_m", "n_piers"):
            return v
        terminal = (0.6 if info.data["n_piers"] else 1.0) * info.data["harbour_width_m"] - 60.0
        most = max(int(terminal // 35.0), 0)
        return int(_within(min(4, most) if v is None else v, 0, most, integer=True))

    @field_validator("moored_assets")
    @classmethod
    def _moored(cls, v: tuple[_Berth, ...], info: ValidationInfo) -> tuple[_Berth, ...]:
        if any(not a or length <= 0.0 or beam <= 0.0 for a, length, beam in v) or (info.data.get("n_moored") and not v):
            raise ValueError("must be a list of [asset_name, length_m > 0, beam_m > 0] (non-empty when n_moored > 0)")
        from mmusv.world.vessels import AssetNameError, known_asset  # the library is built lazily, never here

        for k, (name, _length, _beam) in enumerate(v):
            try:
                known_asset(name)
            except AssetNameError as exc:  # said with the entry, as a vessel's asset is: not only when built
                raise ValueError(f"entry {k} ({name!r}): {exc}") from None
        _berths_hold_their_ships(v)
        if v != DEFAULT_MOORED_ASSETS and "basin_depth_m" in info.data:
            _ships_float(v, info.data["basin_depth_m"])
        return v


MOORED_SIZE_SLACK_M = 2.0
"""How much shorter or narrower (metres) than its ship a ``moored_assets`` entry's ``length_m`` and ``beam_m`` may
be. The port lays each berth out for the entry's size (3 m off the quay or pier face, at least 4 m from the next
berth), and the map keeps buoys and the route checks off that footprint: a ship up to 2 m longer and broader than
it (1 m a side) still clears all of them."""


def _berths_hold_their_ships(entries: tuple[_Berth, ...]) -> None:
    """A ``ValueError`` naming the first entry of ``moored_assets`` whose berth (its ``length_m`` x ``beam_m``) is
    more than :data:`MOORED_SIZE_SLACK_M` shorter or narrower than its ship: ``[container_ship_300m, 1, 1]`` moored
    ten 300 m ships 30 m apart, into each other and the quay, without a word. The defaults are the ships' own
    figures (nothing built for them); another entry's asset is built (cached) for its size."""
    from mmusv.world.vessels import get_asset

    for k, (name, length, beam) in enumerate(entries):
        if (name, length, beam) in DEFAULT_MOORED_ASSETS:
            continue
        ship = get_asset(name)
        if length < ship.length - MOORED_SIZE_SLACK_M or beam < ship.beam - MOORED_SIZE_SLACK_M:
            raise ValueError(
                f"entry {k} ({name!r}) gives its berth length_m x beam_m = {length:g} x {beam:g} m, but the ship is "
                f"{ship.length:g} x {ship.beam:g} m: the port lays the berth out for the size given, so a ship more "
                f"than {MOORED_SIZE_SLACK_M:g} m longer or broader than it lies in the quay, a pier or the next ship; "
                f"give the ship's own figures [{name}, {ship.length:g}, {ship.beam:g}] (or larger, for more room)"
            )


def _ships_float(entries: tuple[_Berth, ...], basin_depth_m: float) -> None:
    """A ``ValueError`` naming the first entry of a ``moored_assets`` a user gave whose ship's draft (its hull
    particulars, as the ``under_keel`` check reads them) reaches ``basin_depth_m``: the port moors no ship that would
    ground, so such an entry would leave its berths to others, or the port empty, without a word. The default list
    is not refused: the 300 m container ship in it gives way to the longest ship that floats where the basin is too
    shallow for it (:mod:`mmusv.world.port`)."""
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    for k, (name, _length, _beam) in enumerate(entries):
        draft = hull_particulars(get_asset(name))[2]
        if draft >= basin_depth_m:
            raise ValueError(
                f"entry {k} ({name!r}): its draft, {draft:g} m, reaches the basin's floor (basin_depth_m = "
                f"{basin_depth_m:g} m), so it would ground at its berth and is never moored; set basin_depth_m "
                f"above {draft:g} or leave the entry out"
            )


MapParams = IslandParams | OpenSeaParams | PortParams
"""The parameters of one map kind: a union discriminated by the map's ``type`` (see :data:`PARAM_MODELS`)."""

PARAM_MODELS: dict[str, type[IslandParams] | type[OpenSeaParams] | type[PortParams]] = {
    "island": IslandParams,
    "open_sea": OpenSeaParams,
    "port": PortParams,
}
"""The parameter model of each map ``type``."""


def make_params(kind: str, **params: Any) -> MapParams:
    """Validated parameters of map ``kind`` from keyword values (lists are accepted for pairs).

    Raises :class:`MapConfigError` naming ``kind`` or the first unknown/invalid field and the allowed values.
    """
    if kind not in PARAM_MODELS:
        raise MapConfigError("kind", kind, " | ".join(MAP_KINDS))
    cls = PARAM_MODELS[kind]
    try:
        return cls.model_validate(params)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = str(first["loc"][0]) if first["loc"] else "params"
        msg = str(first["msg"]).removeprefix("Value error, ").removeprefix("must be ")
        if first["type"] == "extra_forbidden":
            msg = f"a parameter of the {kind} map: {', '.join(sorted(cls.model_fields))}"
        raise MapConfigError(field, params.get(field, first.get("input")), msg) from None
