"""The models of a generation spec, each checking its own fields: the target size classes (:class:`SizeClass`), the
instrumented USVs (:class:`UsvRoles`), the difficulty levels (:class:`Difficulty`), the role combinations with their
quotas (:class:`Combination`) and the whole spec (:class:`GenerationSpec`). :mod:`mmusv.generate.spec` describes the
file (its keys, units and an example) and loads it; the checks across fields are :mod:`mmusv.generate.spec_checks`,
the constraint block :mod:`mmusv.generate.spec_constraints`.
"""

from __future__ import annotations

import difflib
import re
from functools import lru_cache
from typing import Any

from pydantic import Field, ValidationError, field_validator

from mmusv.config import (
    MAX_SPEED_MPS,
    SCENARIO_NAME,
    AcquisitionConfig,
    EnvironmentConfig,
    MapConfig,
    validation_problems,
)
from mmusv.config_errors import short_repr
from mmusv.generate.families import FAMILIES
from mmusv.generate.spec_constraints import Constraints, SpecModel
from mmusv.world.vessels import asset_names, get_asset, known_asset

__all__ = ["Combination", "Difficulty", "GenerationSpec", "SizeClass", "UsvRoles", "class_assets"]

Pair = tuple[float, float]

_NAME = re.compile(SCENARIO_NAME)
"""A spec name (as a scenario name): no path separators, and no leading dot (``.``, ``..``, hidden files)."""

SEED_LIMIT = 2**63
"""A spec's ``seed`` is a whole number in ``0 .. SEED_LIMIT - 1`` (the range of a signed 64-bit integer)."""

MAX_RANGE_M = 100_000.0
"""Farthest closest-approach ``range_m`` of a difficulty, metres (100 km: far beyond any sensor)."""
MAX_ENCOUNTER_CLEARANCE_M = 10_000.0
"""Largest ``encounter_clearance_m`` (shore distance of an encounter centre), metres; maps are a few km across and
the clearance is halved down to the map's own while no water cell has it."""


_Model = SpecModel
"""No unknown keys, NaN, infinity or booleans for numbers (:class:`~mmusv.generate.spec_constraints.SpecModel`)."""


def _ordered(v: Pair, what: str) -> Pair:
    if not v[0] <= v[1]:
        raise ValueError(f"{what} must be [low, high] with low <= high")
    return v


class SizeClass(_Model):
    """A target size class: assets whose length lies in ``length_m`` (or the explicit ``assets`` list), moving
    at a speed drawn uniformly from ``speed_mps``."""

    length_m: Pair = (0.0, 1000.0)
    speed_mps: Pair = (2.0, 8.0)
    assets: list[str] | None = None

    @field_validator("length_m", "speed_mps")
    @classmethod
    def _pairs(cls, v: Pair) -> Pair:
        if v[0] < 0:
            raise ValueError("must be >= 0")
        return _ordered(v, "range")

    @field_validator("speed_mps")
    @classmethod
    def _speed(cls, v: Pair) -> Pair:
        if v[1] > MAX_SPEED_MPS:
            raise ValueError(f"speeds must be <= {MAX_SPEED_MPS:g} m/s")
        return v

    @field_validator("assets")
    @classmethod
    def _assets(cls, v: list[str] | None) -> list[str] | None:
        if v is not None:
            if not v:  # read as "no list" by class_assets' caller, it was refused as the class's length_m range
                raise ValueError(
                    "an empty list names no vessel: name target assets, or leave `assets` out to pick them by length"
                )
            for name in v:
                known_asset(name)
                if get_asset(name).is_usv:
                    raise ValueError(f"{name} is a USV; targets must be other vessels")
        return v


def class_assets(c: SizeClass) -> list[str]:
    """Target asset names of a size class (non-USV assets with ``length_m[0] <= length < length_m[1]``, or the
    explicit list), sorted."""
    if c.assets is not None:
        return sorted(c.assets)
    return list(_by_length(c.length_m, tuple(asset_names())))


@lru_cache(maxsize=64)
def _by_length(length_m: Pair, names: tuple[str, ...]) -> tuple[str, ...]:
    lo, hi = length_m
    return tuple(sorted(n for n in names if not get_asset(n).is_usv and lo <= get_asset(n).length < hi))


DEFAULT_SIZE_CLASSES: dict[str, SizeClass] = {
    "small": SizeClass(length_m=(0.0, 15.0), speed_mps=(3.0, 10.0)),
    "medium": SizeClass(length_m=(15.0, 80.0), speed_mps=(3.0, 8.0)),
    "large": SizeClass(length_m=(80.0, 1000.0), speed_mps=(3.0, 7.0)),
}


class UsvRoles(_Model):
    """The instrumented vessels: assets the cooperating USVs are drawn from (the ego's default is the first)
    and their speed range."""

    assets: list[str] = Field(default_factory=lambda: ["usv_wamv"], min_length=1)
    speed_mps: Pair = (1.5, 3.5)

    @field_validator("assets")
    @classmethod
    def _assets(cls, v: list[str]) -> list[str]:
        for name in v:
            known_asset(name)
            if not get_asset(name).is_usv:
                raise ValueError(f"{name} is not a USV asset (USVs: {', '.join(_usv_names())})")
        return v

    @field_validator("speed_mps")
    @classmethod
    def _speed(cls, v: Pair) -> Pair:
        if v[0] <= 0:
            raise ValueError("USV speeds must be > 0")
        if v[1] > MAX_SPEED_MPS:
            raise ValueError(f"USV speeds must be <= {MAX_SPEED_MPS:g} m/s")
        return _ordered(v, "speed_mps")


def _usv_names() -> list[str]:
    return [n for n in asset_names() if get_asset(n).is_usv]


class Difficulty(_Model):
    """A difficulty level: the closest-approach range between the ego and each ranged target, the number of
    extra (distractor) targets, drawn from ``extra_classes`` (default: every size class), and an optional
    occlusion requirement (share of frames the primary target is hidden from the ego by the static map)."""

    range_m: Pair = (100.0, 400.0)
    extra_targets: tuple[int, int] = (0, 0)
    extra_classes: list[str] | None = None
    occluded_share: float | None = Field(default=None, gt=0.0, le=1.0)

    @field_validator("range_m")
    @classmethod
    def _range(cls, v: Pair) -> Pair:
        if v[0] < 0:
            raise ValueError("must be >= 0")
        if v[1] > MAX_RANGE_M:
            raise ValueError(f"must be <= {MAX_RANGE_M:,.0f} m")
        if v[0] == v[1]:  # accepted, then every attempt failed: a closest approach is never exactly that
            raise ValueError(
                f"must be [low, high] with low < high: no candidate passes at exactly {v[0]:g} m (give a range, e.g. "
                f"[{max(v[0] - 10.0, 0.0):g}, {v[1] + 10.0:g}])"
            )
        return _ordered(v, "range_m")

    @field_validator("extra_targets", mode="before")
    @classmethod
    def _extra(cls, v: Any) -> Any:
        return (v, v) if isinstance(v, int) and not isinstance(v, bool) else v

    @field_validator("extra_targets")
    @classmethod
    def _extra_range(cls, v: tuple[int, int]) -> tuple[int, int]:
        if v[0] < 0 or v[1] > 16 or v[0] > v[1]:
            raise ValueError("must be n or [low, high] with 0 <= low <= high <= 16")
        return v


DEFAULT_DIFFICULTIES: dict[str, Difficulty] = {
    "easy": Difficulty(range_m=(80.0, 250.0), extra_targets=(0, 0)),
    "medium": Difficulty(range_m=(150.0, 500.0), extra_targets=(0, 1)),
    "hard": Difficulty(range_m=(300.0, 900.0), extra_targets=(1, 3)),
}


class Combination(_Model):
    """One role combination with its quota: a family template, a difficulty, the ego USV asset, the number of
    cooperating USVs and the size class of each role target (the first is the primary target)."""

    name: str | None = Field(default=None, pattern=r"^[A-Za-z0-9_\-]+$", max_length=80)
    family: str
    difficulty: str = "easy"
    ego: str | None = None
    cooperating: int = Field(default=0, ge=0, le=8)
    targets: list[str] = Field(default_factory=lambda: ["small"], min_length=1, max_length=8)
    quota: int = Field(default=1, ge=1, le=100_000)
    max_attempts: int | None = Field(default=None, ge=1, le=10_000_000)
    map: MapConfig | None = None

    @field_validator("family")
    @classmethod
    def _family(cls, v: str) -> str:
        if v not in FAMILIES:
            close = difflib.get_close_matches(v, list(FAMILIES), n=2, cutoff=0.5)
            hint = f"did you mean {', '.join(close)}? " if close else ""
            raise ValueError(f"unknown family; {hint}(families: {', '.join(FAMILIES)})")
        return v

    @field_validator("ego")
    @classmethod
    def _ego(cls, v: str | None) -> str | None:
        if v is not None:
            known_asset(v)
            if not get_asset(v).is_usv:
                raise ValueError(f"the ego must be a USV asset ({', '.join(_usv_names())})")
        return v

    def label(self) -> str:
        """The combination's name: ``name`` or ``<family>_<difficulty>_<1+cooperating>usv_<classes>``."""
        if self.name is not None:
            return self.name
        return f"{self.family}_{self.difficulty}_{1 + self.cooperating}usv_{'-'.join(self.targets)}"


# ---------------------------------------------------------------------------------------------------- the spec


def _default_rigs() -> dict[str, dict[str, Any]]:
    return {"usv_standard": {}}


class GenerationSpec(_Model):
    """A whole generation spec (see :mod:`mmusv.generate.spec`)."""

    name: str = Field(default="generated", min_length=1, max_length=200)
    seed: int = Field(default=0, ge=0, lt=SEED_LIMIT)
    map: MapConfig = Field(default_factory=MapConfig)
    environment: dict[str, Any] = Field(default_factory=dict)
    acquisition: AcquisitionConfig = Field(default_factory=AcquisitionConfig)
    rig: str = Field(default="usv_standard", pattern=r"^[A-Za-z0-9_\-]+$")
    rigs: dict[str, dict[str, Any]] = Field(default_factory=_default_rigs)
    usv: UsvRoles = Field(default_factory=UsvRoles)
    size_classes: dict[str, SizeClass] = Field(default_factory=lambda: dict(DEFAULT_SIZE_CLASSES))
    difficulties: dict[str, Difficulty] = Field(default_factory=lambda: dict(DEFAULT_DIFFICULTIES))
    combinations: list[Combination] = Field(min_length=1)
    constraints: Constraints = Field(default_factory=Constraints)
    max_attempts_per_scenario: int = Field(default=40, ge=1, le=100_000)
    check_step_m: float = Field(default=2.0, ge=0.25, le=50.0)
    sensor_height_m: float = Field(default=2.5, gt=0.0, le=100.0)
    encounter_clearance_m: float = Field(default=100.0, ge=0.0, le=MAX_ENCOUNTER_CLEARANCE_M)
    proposals: int = Field(default=6, ge=1, le=100)

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not _NAME.fullmatch(v):
            raise ValueError(
                "use letters, digits, '_', '-' and '.', not starting with '.' (it names files and folders)"
            )
        return v

    @field_validator("environment")
    @classmethod
    def _environment(cls, v: dict[str, Any]) -> dict[str, Any]:
        fields = EnvironmentConfig.model_fields

        def drawn(key: str, default: list[Any]) -> list[Any]:
            """The values the sampler can draw for ``key`` (a list is a choice, one value is always drawn)."""
            value = v.get(key, default)
            return value if isinstance(value, list) else [value]

        for key in v:
            if key not in fields:
                raise ValueError(f"unknown environment key {key!r} (allowed: {', '.join(fields)})")
            choices = drawn(key, [])
            if not choices:
                raise ValueError(f"environment.{key}: an empty list has nothing to choose from")
            # A rain rate alone is checked under a sky that rains (the sampler leaves it out of clear-sky draws).
            with_key = {"weather": "rain"} if key == "rain_mm_per_h" else {}
            for c in choices:
                try:
                    EnvironmentConfig.model_validate({**with_key, key: c})
                except ValidationError as exc:
                    # the field inside the value too (environment.sea.preset, with the keys allowed there), as a
                    # scenario names it: "environment.sea = {...}: Extra inputs are not permitted" named neither
                    field, shown, msg = validation_problems(exc, root=key, model=EnvironmentConfig)[0]
                    if not field.startswith(key):  # a check across the fields: the value as the spec gives it
                        field, shown = key, repr(c)
                    raise ValueError(f"environment.{field} = {shown}: {msg}") from None
        # What a scenario refuses across keys (EnvironmentConfig's checks), for any choice the sampler can draw.
        if "sea" in v and "wave" in v:
            raise ValueError(
                "environment: give `wave` or `sea`, not both: `sea` sets the waves every sensor and hull meet"
            )
        if "sea" in v and "paper" in drawn("motion", []):
            raise ValueError(
                "environment: `sea` is the physical sea, which `motion: paper` leaves out: drop one of them"
            )
        # A rate drawn beside a clear sky is dropped (the sampler); with no weather that rains to draw, every rate
        # would be, and the whole dataset would come out dry without a word.
        if any(drawn("rain_mm_per_h", [])) and set(drawn("weather", ["clear"])) == {"clear"}:
            raise ValueError(
                f"environment.rain_mm_per_h = {short_repr(v['rain_mm_per_h'])} with weather "
                f"{short_repr(v.get('weather', 'clear'))}"
                ": a clear sky does not rain, so every rate would be dropped; add a weather that rains (rain, "
                "overcast or fog) to weather"
            )
        return v

    def map_of(self, combo: Combination) -> MapConfig:
        """The map a combination's scenarios use: its own ``map`` or the spec's (one spec can cover several maps)."""
        return combo.map if combo.map is not None else self.map

    def max_attempts(self, combo: Combination) -> int:
        """The attempt cap of a combination: its own ``max_attempts`` or ``quota x max_attempts_per_scenario``."""
        return combo.max_attempts if combo.max_attempts is not None else combo.quota * self.max_attempts_per_scenario
