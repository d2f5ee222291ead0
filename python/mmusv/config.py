"""The scenario file: a YAML schema validated into typed, frozen objects.

Every error is a :class:`mmusv.ConfigError` whose message names the field (``vessels[2].speed_mps``), the value
given and what is allowed. Everything a newcomer should not have to write has a default. Example::

    name: port_crossing
    seed: 7
    map: {type: port, seed: 3}
    environment: {time_of_day: "16:30", weather: fog, visibility_m: 800, wave: W2}
    acquisition: {frequency_hz: 5, frames: 100}
    vessels:
      - {id: usv_1, role: usv, asset: usv_wamv, speed_mps: 3.0, route: [[0, 0], [150, 40]]}
      - {id: target_1, role: target, asset: container_ship_300m, speed_mps: 6.0, route: [[-800, 300], [900, 200]]}

Units: metres, seconds, metres per second; angles in degrees only in keys ending in ``_deg``.
"""

from __future__ import annotations

import contextlib
import difflib
import hashlib
import json
import math
import os
import re
import reprlib
from dataclasses import replace
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    Field,
    PrivateAttr,
    SerializationInfo,
    SerializerFunctionWrapHandler,
    ValidationError,
    ValidationInfo,
    field_serializer,
    field_validator,
    model_serializer,
    model_validator,
)
from pydantic_core import InitErrorDetails, PydanticCustomError

from mmusv import arguments
from mmusv.config_errors import short_repr, validation_error, validation_problems
from mmusv.errors import ConfigError, MmusvError, located
from mmusv.scenario_assets import AssetHome
from mmusv.sensors.config import RigConfig
from mmusv.strict import StrictModel
from mmusv.world.environment import MAX_WAVE_HEIGHT_M, Environment, wave_height_m, wave_problem
from mmusv.world.map_params import PARAM_MODELS, IslandParams, MapParams
from mmusv.world.sea_state import TP_RANGE_S, SeaSpec
from mmusv.world.vessels import get_asset, known_asset
from mmusv.yamlio import mapping_source

__all__ = [
    "MAX_COORDINATE_M",
    "MAX_FRAMES",
    "MAX_SPEED_MPS",
    "RIG_NAME",
    "SCENARIO_NAME",
    "AcquisitionConfig",
    "EnvironmentConfig",
    "MapConfig",
    "Scenario",
    "SeaConfig",
    "VesselConfig",
    "load_scenario",
    "scenario_hash",
    "validation_error",
    "validation_problems",
]


MAX_FRAMES = 10_000_000
"""Most frames a scenario may configure (``acquisition.frames``): 23 days at 5 Hz."""

MAX_SPEED_MPS = 100.0
"""Fastest vessel speed a scenario may give, m/s (about 194 knots: past every craft afloat)."""
SCENARIO_NAME = r"[A-Za-z0-9_\-][A-Za-z0-9_\-.]*"
"""A scenario's (and a generation spec's) name, which names files and folders: letters, digits, ``_``, ``-``
and ``.``, not starting with ``.`` (``.``, ``..``, hidden files)."""
RIG_NAME = re.compile(r"[A-Za-z0-9_\-]{1,64}")
"""A rig's name under ``rigs`` (what the vessels' ``rig`` names): letters, digits, ``_`` and ``-``."""
MAX_COORDINATE_M = 1.0e6
"""Farthest a waypoint (and a route's start offset) may lie from the world origin, metres (1,000 km: far
beyond any map)."""


class _Model(StrictModel):
    """A scenario's models: :class:`~mmusv.strict.StrictModel` (no unknown keys, NaN, infinity or booleans for
    numbers)."""


class MapConfig(_Model):
    """Which map to generate: ``type`` in {island, open_sea, port}, its ``seed`` and optional ``params``: the
    model of that type (:class:`~mmusv.world.map_params.IslandParams`, ``OpenSeaParams`` or ``PortParams``: a
    union discriminated by ``type``), validated when the scenario loads, so errors name ``map.params.<field>``.
    ``params`` dump as the values that were given (resolved port knobs stay on the model, out of the dump)."""

    type: Literal["island", "open_sea", "port"] = "island"
    seed: int = Field(default=0, ge=0, lt=2**63)
    params: MapParams = Field(default=None, validate_default=True)

    @field_validator("params", mode="before")
    @classmethod
    def _params_of_type(cls, v: Any, info: ValidationInfo) -> Any:
        if "type" not in info.data:  # a bad type is reported on its own
            return IslandParams()
        model = PARAM_MODELS[info.data["type"]]
        if v is None:
            return model()
        if isinstance(v, BaseModel):
            return v if type(v) is model else model.model_validate(v.model_dump(exclude_unset=True))
        return model.model_validate(v)

    @field_validator("params")
    @classmethod
    def _islands_fit(cls, v: MapParams, info: ValidationInfo) -> MapParams:
        """An island map whose islands cannot all be placed is refused here, naming ``map.params.n_islands``: it
        was found only when a run built the world (or a generator its map)."""
        seed = info.data.get("seed")
        if not isinstance(v, IslandParams) or not isinstance(seed, int):
            return v
        from mmusv.world.maps import island_fit_problem

        why = island_fit_problem(seed, v)
        if why is None:
            return v
        detail = InitErrorDetails(
            type=PydanticCustomError("value_error", "{why}", {"why": why}), loc=("n_islands",), input=v.n_islands
        )
        raise ValidationError.from_exception_data(type(v).__name__, [detail])

    @field_serializer("params")
    def _given_params(self, params: MapParams, info: SerializationInfo) -> dict[str, Any]:
        return params.model_dump(mode=info.mode, exclude_unset=True)

    def param_values(self) -> dict[str, Any]:
        """The parameters that were given, as JSON values sorted by name (what a scenario file would say)."""
        return dict(sorted(self.params.model_dump(mode="json", exclude_unset=True).items()))


class SeaConfig(_Model):
    """The physical sea (:mod:`mmusv.world.sea_state`): either a WMO sea ``state`` 0..9 (Douglas scale, fully
    developed), or a significant height ``hs_m`` with optional peak period ``tp_s`` (default: fully developed,
    Pierson–Moskowitz) and peak enhancement ``gamma`` (default: 1 when fully developed, else DNV-RP-C205's value
    for Tp/√Hs); plus the waves' travel direction ``direction_deg`` (counter-clockwise from east, towards) and the
    cos-2s spreading ``spread_s`` (10: a wind sea; larger is longer-crested); and ``wind_10m_mps``, the wind at 10 m
    (m/s) the sensors take for the whitecaps (Monahan), the water's slopes and glint (Cox–Munk), the LiDAR's water
    returns and foam (default: the wind of a fully developed sea of this Hs,
    :func:`mmusv.sensors.env.wind_from_wave_height`; a swell, long Tp under a light wind, wants a smaller one). The
    waves themselves, and so the hulls' motion and the wave surface every ray meets, come from the spectrum alone."""

    state: int | None = Field(default=None, ge=0, le=9)
    hs_m: float | None = Field(default=None, ge=0, le=MAX_WAVE_HEIGHT_M)
    tp_s: float | None = Field(default=None, ge=TP_RANGE_S[0], le=TP_RANGE_S[1])
    gamma: float | None = Field(default=None, ge=1, le=7)
    direction_deg: float = Field(default=0.0, ge=-360, le=360, allow_inf_nan=False)
    spread_s: float = Field(default=10.0, ge=0.5, le=100)
    wind_10m_mps: float | None = Field(default=None, ge=0, le=60, allow_inf_nan=False)

    @model_serializer(mode="wrap")
    def _unset_wind_left_out(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """The dump without ``wind_10m_mps`` when it is not given: a scenario that gives no wind keeps the config
        hash it had before the field existed (``scenario_hash`` hashes the dump), as its recordings stay the same."""
        out: dict[str, Any] = handler(self)
        if self.wind_10m_mps is None:
            out.pop("wind_10m_mps", None)
        return out

    @model_validator(mode="after")
    def _one_height(self) -> SeaConfig:
        if (self.state is None) == (self.hs_m is None):
            given = "neither was given" if self.state is None else "not both"
            raise ValueError(f"environment.sea: give either `state` (WMO sea state 0..9) or `hs_m` (metres), {given}")
        if self.state is not None and self.tp_s is not None:
            raise ValueError("environment.sea: `tp_s` goes with `hs_m`; a WMO `state` is a fully developed sea")
        self.spec()  # the core checks the steepness and the ranges together
        return self

    def spec(self) -> SeaSpec:
        """The resolved sea."""
        from mmusv.world.sea_state import sea_spec_for_height, sea_spec_for_preset

        try:  # the core checks the ranges together (errors name the field)
            if self.state is not None:
                p = sea_spec_for_preset(str(self.state), direction_deg=self.direction_deg, spread_s=self.spread_s)
                return p if self.gamma is None else replace(p, gamma=self.gamma)
            assert self.hs_m is not None
            return sea_spec_for_height(
                self.hs_m, tp_s=self.tp_s, gamma=self.gamma, direction_deg=self.direction_deg, spread_s=self.spread_s
            )
        except MmusvError as exc:
            raise ValueError(f"environment.sea: {exc}") from None


class EnvironmentConfig(_Model):
    """Time of day (``"HH:MM"``), weather, visibility (metres, in the rain where it rains; left out, the weather's
    own air thinned by its rain's drops: :meth:`mmusv.world.environment.Weather.make`), rain (a rate above 0 needs a
    sky that rains: ``weather`` other than ``clear``), the wave setting (``W0``..``W3`` or metres), the
    physical ``sea`` (optional; else it follows ``wave``) and the vessels' ``motion``: ``physical`` (default: each
    hull's response to the sea through its RAOs) or ``paper`` (the paper's formula, driven by ``wave``)."""

    time_of_day: str = "12:00"
    weather: Literal["clear", "overcast", "fog", "rain"] = "clear"
    visibility_m: float | None = Field(default=None, ge=1, le=1e7)
    rain_mm_per_h: float | None = Field(default=None, ge=0, le=500)
    wave: str | float = "W0"
    latitude_deg: float = Field(default=45.0, ge=-90, le=90)
    day_of_year: int = Field(default=172, ge=1, le=366)
    sea: SeaConfig | None = None
    motion: Literal["physical", "paper"] = "physical"

    @field_validator("time_of_day", mode="before")
    @classmethod
    def _time_quoted(cls, v: Any) -> Any:
        # YAML 1.1 reads an unquoted 13:00 as the sexagesimal integer 780.
        if isinstance(v, int) and not isinstance(v, bool):
            raise ValueError(f'use 24-hour "HH:MM" in quotes, e.g. "16:30" (unquoted, YAML reads it as the number {v})')
        if not isinstance(v, str):  # 13.5, 13.00 (YAML's float), true, null, a list: not a time either
            raise ValueError(f'use 24-hour "HH:MM" in quotes, e.g. "16:30", not {short_repr(v)}')
        return v

    @field_validator("time_of_day")
    @classmethod
    def _time(cls, v: str) -> str:
        from mmusv.world.environment import _parse_time

        try:
            hours = _parse_time(v)
        except ConfigError:
            raise ValueError('use 24-hour "HH:MM", e.g. "16:30"') from None
        # One spelling of one time ("6:30" is "06:30"): the scenario's hash and its recorded text follow the time,
        # as they follow the wave preset whatever its case.
        minutes = round(hours * 60)
        return f"{minutes // 60:02d}:{minutes % 60:02d}"

    @field_validator("wave", mode="before")
    @classmethod
    def _wave_kind(cls, v: Any) -> Any:
        # Anything but text or a finite number (null, a list, a mapping, .inf) was the union's two lines, "Input
        # should be a valid string; ... a valid number", which did not say what `wave` takes. (true/false is left
        # to the strict numbers' own message.)
        if isinstance(v, str | bool) or (arguments.is_number(v) and math.isfinite(float(v))):
            return v
        problem = wave_problem(v)
        raise ValueError(problem or "allowed presets are W0..W3 or a wave height in metres")

    @field_validator("wave")
    @classmethod
    def _wave(cls, v: str | float) -> str | float:
        # a ValueError (not the ConfigError of wave_height_m): pydantic then reports the other fields' errors too
        problem = wave_problem(v)
        if problem is not None:
            raise ValueError(problem)
        return v.strip().upper() if isinstance(v, str) else float(v)

    @model_validator(mode="after")
    def _one_sea(self) -> EnvironmentConfig:
        # Either setting alone decides the sea; given both, one would be dropped without a word.
        # (`wave: W0`, the default, goes with a `sea`: a resolved scenario written out, scenario.yaml, holds both.)
        # Every problem at once (a user fixes them in one go).
        problems = []
        if self.sea is not None and "wave" in self.model_fields_set and self.wave != "W0":
            problems.append(
                "environment: give `wave` (W0..W3 or metres) or `sea`, not both: `sea` sets the waves every sensor "
                "and every hull meets"
            )
        if self.weather == "clear" and self.rain_mm_per_h:
            problems.append(
                f"environment: rain_mm_per_h = {self.rain_mm_per_h:g} with weather: clear: a clear sky does not rain; "
                "give weather: rain (or overcast or fog, for the rain falling from them)"
            )
        if self.sea is not None and self.motion == "paper":
            problems.append(
                "environment: `sea` is the physical sea, which `motion: paper` leaves out (the paper's formula, "
                "driven by `wave`, over flat water): drop `sea`, or use `motion: physical`"
            )
        if problems:
            raise ValueError("; ".join(problems))
        return self

    def resolve(self) -> Environment:
        """The resolved :class:`~mmusv.world.environment.Environment` (sun, weather, wave height)."""
        return Environment.make(**self.model_dump(exclude={"sea", "motion"}))

    def sea_spec(self) -> SeaSpec:
        """The physical sea: ``sea`` when given, else the fully developed sea of ``wave`` (a preset W0..W3 or
        Hs in metres)."""
        from mmusv.world.sea_state import sea_spec_for_height, sea_spec_for_preset

        if self.sea is not None:
            return self.sea.spec()
        if isinstance(self.wave, str):
            return sea_spec_for_preset(self.wave)
        return sea_spec_for_height(float(self.wave))


class AcquisitionConfig(_Model):
    """Acquisition: ``frequency_hz`` (Δt = 1/f) and the number of ``frames`` (indices 0..frames-1)."""

    frequency_hz: float = Field(default=5.0, ge=0.01, le=1000)
    frames: int = Field(default=100, ge=1, le=MAX_FRAMES)

    def times(self) -> list[float]:
        """Acquisition times t_k = k / f in seconds."""
        return [k / self.frequency_hz for k in range(self.frames)]


_WORLD_FRAME = "world"
"""The world frame's id and topic namespace (:data:`mmusv.recording.topics.WORLD_FRAME`, not imported here: that
package loads the recorder), which no vessel id may take."""


class VesselConfig(_Model):
    """One vessel: a USV (instrumented, carries ``rig``) or a target, on a spline ``route`` through waypoints
    (metres, world frame) at ``speed_mps``; ``end`` says what happens at the route end."""

    id: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", min_length=1, max_length=64)
    role: Literal["usv", "target"] = "target"
    asset: str
    rig: str | None = None
    speed_mps: float = Field(default=0.0, ge=0, le=MAX_SPEED_MPS, allow_inf_nan=False)
    """Speed along the route (m/s, constant; 0: the vessel stays at its start, ``static``)."""
    route: list[tuple[float, float]] = Field(min_length=2)
    """Waypoints ``[x, y]`` (world metres, x east, y north) the centripetal Catmull-Rom spline passes through."""
    end: Literal["stop", "loop", "ping_pong"] = "stop"
    """At the route's end: ``stop`` (at rest on the last waypoint), ``loop`` (on from the last waypoint round to the
    first, a closed spline: at least 3 distinct waypoints) or ``ping_pong`` (the route backwards, turned about on
    the spot, heading by π, and so on)."""
    start_offset_m: float = Field(default=0.0, ge=0, le=MAX_COORDINATE_M, allow_inf_nan=False)
    """Distance (m) along the route the vessel has sailed at t = 0 (``loop``: wraps round, ``ping_pong``: there and
    back; ``stop``: at most the route's length)."""
    z_base_m: float = Field(default=0.0, ge=-30, le=30, allow_inf_nan=False)
    """Height (m) of the vessel's frame over the still water: 0 floats the asset at its own waterline, below 0 sits it
    deeper (not so deep that the whole hull is under the water), above 0 lifts it (clear of the water, for a
    controlled set-up: an object against the horizon sky)."""

    @field_validator("id")
    @classmethod
    def _not_the_world(cls, v: str) -> str:
        # The recording names each vessel's frame after its id, under the world frame, and each USV's topics
        # /<id>/...: a vessel 'world' was a frame of the world frame's name (a /tf tree whose root moves with a hull)
        # and a USV 'world' topics /world/... that readers take for the world's (`mmusv preview`: "no agent topics").
        if v == _WORLD_FRAME:
            raise ValueError(
                f"{v!r} is the name of the world frame (the recording's /tf tree and /world/... topics use it); "
                "choose another id"
            )
        return v

    @field_validator("asset")
    @classmethod
    def _asset(cls, v: str) -> str:
        return known_asset(v)

    @property
    def static(self) -> bool:
        """Whether the vessel never moves (``speed_mps`` 0). Moored ships of port maps are static too; boxes,
        tables and exports carry this flag so users can filter static vessels."""
        return self.speed_mps == 0.0

    @field_validator("route")
    @classmethod
    def _route(cls, v: list[tuple[float, float]]) -> list[tuple[float, float]]:
        for i, (x, y) in enumerate(v):
            if not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError(f"waypoint {i} is not finite")
            if max(abs(x), abs(y)) > MAX_COORDINATE_M:
                raise ValueError(f"waypoint {i} lies beyond {MAX_COORDINATE_M:,.0f} m of the origin (world metres)")
        return v


class Scenario(_Model):
    """A whole scenario: map, environment, acquisition, sensor rigs and vessels."""

    name: str = Field(default="scenario", pattern=f"^{SCENARIO_NAME}$", max_length=200)
    seed: int = Field(default=0, ge=0, lt=2**63)
    map: MapConfig = Field(default_factory=MapConfig)
    environment: EnvironmentConfig = Field(default_factory=EnvironmentConfig)
    acquisition: AcquisitionConfig = Field(default_factory=AcquisitionConfig)
    rigs: dict[str, RigConfig] = Field(default_factory=dict)
    assets: list[Annotated[str, Field(min_length=1, max_length=4096)]] = Field(default_factory=list, max_length=256)
    """Asset YAML files of the user's own vessels (meshes or procedural entries), relative to the scenario's folder:
    :func:`load_scenario` builds and registers them before the vessels are read (:mod:`mmusv.scenario_assets`)."""
    vessels: list[VesselConfig] = Field(min_length=1)
    _asset_home: AssetHome | None = PrivateAttr(default=None)
    """Where its user assets come from, when :func:`load_scenario` read it (:mod:`mmusv.scenario_assets`)."""

    @field_validator("rigs", mode="before")
    @classmethod
    def _rig_names(cls, v: Any) -> Any:
        # Checked as written, before whitespace is stripped (" " and "" would become one rig named '').
        if isinstance(v, dict):
            for name in v:
                if not (isinstance(name, str) and RIG_NAME.fullmatch(name)):
                    raise ValueError(
                        f"rig name {reprlib.repr(name)}: letters, digits, _ and - only (1..64 characters), as the "
                        "vessels' `rig` names it"
                    )
        return v

    @model_validator(mode="after")
    def _cross_checks(self) -> Scenario:
        problems: list[str] = []  # every problem at once (a user fixes them in one go)
        # A port map's moored ships are labelled moored_00, moored_01, ... beside the scenario's vessels.
        n_moored = getattr(self.map.params, "n_moored", 0)
        moored = {f"moored_{k:02d}" for k in range(n_moored)}
        for i, v in enumerate(self.vessels):
            if v.id.casefold() in moored:
                problems.append(
                    f"vessels[{i}].id = {v.id!r}: the port map labels its moored ships moored_00..moored_"
                    f"{n_moored - 1:02d} (map.params.n_moored = {n_moored}); ids must be unique: choose another id"
                )
        first: dict[str, int] = {}  # case-folded id -> index of its first vessel
        for i, v in enumerate(self.vessels):
            j = first.setdefault(v.id.casefold(), i)
            if j != i and self.vessels[j].id == v.id:
                problems.append(f"vessels[{i}].id = {v.id!r} is used twice (vessels[{j}]); ids must be unique")
            elif j != i:
                # Exports name folders and files after ids: on macOS and Windows the two would be one folder.
                problems.append(
                    f"vessels[{i}].id = {v.id!r} differs from vessels[{j}].id = {self.vessels[j].id!r} only in "
                    "case; ids must be unique ignoring case (exports name files and folders after them)"
                )
            if v.rig is not None and v.rig not in self.rigs:
                problems.append(
                    f"vessel {v.id!r} names rig {short_repr(v.rig)}, which is not defined under rigs: "
                    f"({sorted(self.rigs)})"
                )
        for i, v in enumerate(self.vessels):
            if v.rig is not None and v.role != "usv":
                problems.append(
                    f"vessels[{i}].rig = {short_repr(v.rig)}: only instrumented vessels (role: usv) carry a rig; "
                    f"vessel {v.id!r} has role {v.role!r} (add `role: usv` or remove `rig`)"
                )
            if v.z_base_m < 0.0:
                # A hull sunk whole is seen by no sensor yet labelled in every frame.
                lo, hi = (float(z) for z in get_asset(v.asset).bbox[:, 2])
                if hi + v.z_base_m <= 0.0:
                    problems.append(
                        f"vessels[{i}].z_base_m = {v.z_base_m:g}: it puts the whole hull of {v.asset} (z from {lo:.2f} "
                        f"to {hi:.2f} m in its own frame) below the still water; a vessel floats, so z_base_m must "
                        f"be above {-hi:.2f} m (0: the asset's own waterline)"
                    )
            if v.role == "usv" and v.rig is not None and v.rig in self.rigs:
                try:
                    _check_mount_points(v, i, v.rig, self.rigs[v.rig])
                except ValueError as exc:
                    problems.append(str(exc))
            if v.role == "usv" and (v.rig is None or v.rig in self.rigs):
                why = _top_view_in_hull(v, i, v.rig, self.rigs[v.rig] if v.rig is not None else RigConfig())
                if why is not None:
                    problems.append(why)
        if problems:
            raise ValueError("; ".join(dict.fromkeys(problems)))
        return self

    @property
    def usvs(self) -> list[VesselConfig]:
        """The instrumented vessels, in file order."""
        return [v for v in self.vessels if v.role == "usv"]

    def with_wave(self, wave: str | float) -> Scenario:
        """A copy with another wave setting (everything else unchanged); a bad ``wave`` is a
        :class:`~mmusv.errors.ConfigError` naming ``environment.wave``."""
        wave_height_m(wave)  # the ConfigError, not the schema's ValueError
        env = self.environment.model_copy(update={"wave": EnvironmentConfig._wave(wave)})
        return self.model_copy(update={"environment": env})

    def with_sea(self, sea: SeaConfig | None, *, motion: Literal["physical", "paper"] | None = None) -> Scenario:
        """A copy with another physical sea (``None``: the sea of ``wave``) and optionally another ``motion``."""
        update: dict[str, Any] = {"sea": sea}
        if motion is not None:
            update["motion"] = motion
        return self.model_copy(update={"environment": self.environment.model_copy(update=update)})


def _check_mount_points(v: VesselConfig, index: int, rig_name: str, rig: RigConfig) -> None:
    """Every mount ``point`` of ``rig`` must be one of the asset's mount points (assets without any fall back to
    the top of the hull, as documented in :mod:`mmusv.sensors.config`)."""
    points = sorted(get_asset(v.asset).mounts)
    if not points:
        return
    for where, m in rig.mounts():
        if m.point is not None and m.point not in points:
            close = difflib.get_close_matches(m.point, points, n=1, cutoff=0.5)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise ValueError(
                f"rigs.{rig_name}.{where}.point = {m.point!r}: asset {v.asset} (vessels[{index}], {v.id}) has no such "
                f"mount point; {hint}its points: {', '.join(points)}"
            )


def _top_view_in_hull(v: VesselConfig, index: int, rig_name: str | None, rig: RigConfig) -> str | None:
    """What is wrong with the top view of ``rig`` on USV ``v``, or ``None``: it looks straight down from ``altitude_m``
    over the still water above the USV's own origin, so at or below the top of its hull (``z_base_m`` counted) it
    sat in that hull, and its picture lost the USV (all of it at 1e-9 m, most of it at 1 m on a 5.2 m patrol boat)
    without a word; a sensor mounted inside its hull is refused (:mod:`mmusv.agents`)."""
    if rig.top_view is None:
        return None
    top = float(get_asset(v.asset).bbox[1, 2]) + v.z_base_m
    altitude = rig.top_view.altitude_m
    if altitude > top:
        return None
    field = f"rigs.{rig_name}.top_view.altitude_m" if rig_name is not None else "the default rig's top_view.altitude_m"
    lifted = f" with z_base_m = {v.z_base_m:g}" if v.z_base_m else ""
    return (
        f"{field} = {altitude:g}: the top view looks down from {altitude:g} m over the still water above vessel "
        f"{v.id!r} (vessels[{index}], {v.asset}), whose hull reaches {top:.2f} m{lifted}: it would cut through the "
        f"hull and lose the vessel, whole or in part, from its picture; altitude_m must be above {top:.2f} m "
        "(default 120)"
    )


def load_scenario(source: str | os.PathLike[str] | dict[str, Any] | Scenario) -> Scenario:
    """Validates a scenario given as a YAML path, a dict, or a :class:`Scenario` (returned as is). A path that does
    not exist but names a bundled scenario (``"port_entry"``) is that scenario, as on the command line
    (:func:`mmusv.bundled.resolve_scenario`). The vessel library is then held for it (its own asset files' assets,
    no other scenario's; :mod:`mmusv.scenario_assets`), while another thread reading a scenario waits."""
    from mmusv.scenario_assets import holding_library

    with holding_library():
        return _load_scenario(source)


def _load_scenario(source: str | os.PathLike[str] | dict[str, Any] | Scenario) -> Scenario:
    if isinstance(source, Scenario):
        home = source._asset_home
        if home is not None and not home.held():  # another scenario was read since: the library held for it again
            from mmusv.scenario_assets import use_scenario_assets

            use_scenario_assets(list(home.entries), base_dir=home.base_dir, where=home.where)
        return source
    if isinstance(source, str) and ("\n" in source or "\r" in source):  # the path's OSError said "File name too long"
        raise ConfigError(
            "the scenario is given as text (it holds line breaks), not as the path of a file: give the path of its "
            ".yaml file, or the mapping (yaml.safe_load(text))"
        )
    if isinstance(source, (str, os.PathLike)) and not os.path.isfile(source):  # a folder: a bundled name too?
        from mmusv.bundled import resolve_scenario
        from mmusv.errors import NotFoundError

        with contextlib.suppress(NotFoundError):  # not bundled either: the file error below names the path
            source = resolve_scenario(os.fspath(source))
    data, where = mapping_source(source, kind="scenario", root_hint="at least `vessels:`")
    # the user's own vessels, registered before the vessels naming them are read; those of the other scenarios read
    # in this process taken out of the library first (a batch, a study or a Python session reads several)
    from mmusv.scenario_assets import scenario_base, use_scenario_assets

    path = source if isinstance(source, (str, os.PathLike)) else None
    home = use_scenario_assets(data.get("assets"), base_dir=scenario_base(path), where=where)
    try:
        scenario = Scenario.model_validate(data)
        scenario._asset_home = home  # load_scenario of it holds the library for it again (mmusv.run, Simulation)
        return scenario
    except ValidationError as exc:
        if "combinations" in data and "vessels" not in data:  # a spec's dozen "invalid config" problems said less
            shown = where if isinstance(source, (str, os.PathLike)) else "SPEC.yaml"
            raise ConfigError(
                f"{where} is a generation spec (combinations:, no vessels:), not a scenario: make scenarios from "
                f"it with `mmusv generate {shown}` (or a recorded dataset with `mmusv dataset {shown}`)"
            ) from None
        raise validation_error(exc, where, data=data) from None
    except MmusvError as exc:  # a validator that checks through the core (wave presets, ...)
        raise located(exc, where) from None


def scenario_hash(scenario: str | os.PathLike[str] | dict[str, Any] | Scenario) -> str:
    """SHA-256 (64 lowercase hex digits) of the resolved scenario's canonical JSON: the config hash written into
    manifests (``RecordingInfo.config_hash``, ``dataset.json``'s ``config_hash``). ``scenario`` is anything
    :func:`load_scenario` takes (a YAML path, a dict or a :class:`Scenario`), validated first: a dict and its YAML
    file hash alike, and anything else is a :class:`~mmusv.errors.ConfigError`."""
    scenario = load_scenario(scenario)
    text = json.dumps(scenario.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))
    from mmusv.scenario_assets import asset_digest

    # the user's own assets by their meshes: a changed mesh is a changed configuration (empty for built-ins,
    # so a scenario of built-in assets hashes as it always did)
    text += asset_digest(v.asset for v in scenario.vessels)
    return hashlib.sha256(text.encode()).hexdigest()
