"""The generation spec: a YAML file describing a batch of scenarios to generate under constraints.

Units: metres, seconds, metres per second; shares are fractions of the frames in [0, 1]. Top-level keys:

- ``name``, ``seed`` (every random draw derives from it), ``map`` (``type``/``seed``/``params`` as in a scenario);
- ``acquisition`` (``frequency_hz``, ``frames``: the window every scenario covers) and ``environment`` (scenario
  environment keys; a list means one value drawn per scenario; a ``rain_mm_per_h`` drawn with a clear sky is left
  out, as a clear sky does not rain, and a rate above 0 with no weather that rains to draw is refused);
- ``rig``/``rigs``: the sensor rig every USV carries (``{usv_standard: {}}`` = the default rig);
- ``usv``: USV ``assets`` and ``speed_mps``; ``size_classes``: target classes by hull ``length_m`` (default
  small < 15 m <= medium < 80 m <= large) or an explicit ``assets`` list, with their ``speed_mps``;
- ``difficulties``: ``range_m`` (ego to target closest approach), ``extra_targets`` (distractors, n or
  [lo, hi], uniform over the accepted scenarios: each one's count is drawn for its place in the quota and kept over
  its attempts) from ``extra_classes``, ``occluded_share`` (ask for occlusion of the primary target);
- ``combinations``: ``family`` (:data:`mmusv.generate.families.FAMILIES`), ``difficulty``, ``ego`` asset,
  ``cooperating`` USVs, ``targets`` (one size class per role target, the first is primary), ``quota``,
  optional ``max_attempts`` (default ``quota x max_attempts_per_scenario``), ``name`` and ``map`` (this
  combination's own map instead of the spec's, so one spec can cover several maps);
- ``constraints``: the named checks and thresholds (:mod:`mmusv.generate.spec_constraints`): all on, except
  ``target_density`` and ``line_of_sight``; writing a check's block turns it on unless it says ``enabled: false``;
- ``max_attempts_per_scenario`` (default 40: a combination's attempt cap is its quota times this);
- tuning: ``check_step_m`` (sample spacing of the checks), ``sensor_height_m``, ``encounter_clearance_m``,
  ``proposals`` (prior-guided proposals per placed vessel).

Example (``scenarios/specs/island_demo.yaml`` is a commented one)::

    name: island_demo
    seed: 42
    map: {type: island, seed: 4}
    acquisition: {frequency_hz: 2, frames: 60}
    environment: {weather: [clear, fog], wave: [W0, W1]}
    combinations:
      - {family: crossing, difficulty: easy, cooperating: 1, targets: [small], quota: 3}
      - {family: occluded_by_island, difficulty: medium, cooperating: 1, targets: [medium], quota: 2}
    constraints:
      separation: {min_m: 20}
      occlusion: {min_occluded_share: 0.3}

Every error is a :class:`mmusv.ConfigError` whose message names the field (``combinations[1].difficulty``),
the value given and what is allowed, in the style of :func:`mmusv.config.load_scenario`. As in a scenario,
``true``/``false`` is never read as a number (``quota: true``, ``speed_mps: [true, 5]``). Constraints that no
candidate of a combination could meet together are refused here, naming the constraint, the combination and the
other bound (``separation.min_m`` above the difficulty's ``range_m`` or ``cooperation.max_m``, a sensing or
density range inside the separation, ``target_density.min_targets`` above the targets a combination has, a lone
ego whose target is kept beyond its sensing range), rather than spending every attempt on them. So are a size class
none of whose vessels sails as fast as its ``speed_mps`` low (each target is kept below its type's top speed, so
every draw would fall below the range) and an empty ``assets`` or ``extra_classes`` list (it named no vessel, and
drew the distractors from every class). A clearance that
no water of a combination's map offers to its vessels needs the map: :func:`mmusv.generate.runner.generate` refuses
it the same way once the map is built, before the first attempt.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from pydantic import ValidationError

from mmusv.config import load_scenario, validation_error
from mmusv.config_errors import short_repr
from mmusv.errors import ConfigError, MmusvError, located
from mmusv.generate.families import FAMILIES
from mmusv.generate.layout import top_speed_mps
from mmusv.generate.spec_constraints import (
    Constraints,
    CooperationCheck,
    InWaterCheck,
    LineOfSightCheck,
    OcclusionCheck,
    RouteSeparationCheck,
    SensingRangeCheck,
    SeparationCheck,
    ShoreClearanceCheck,
    StructureClearanceCheck,
    TargetRangeCheck,
)
from mmusv.generate.spec_models import (
    SEED_LIMIT,
    Combination,
    Difficulty,
    GenerationSpec,
    SizeClass,
    UsvRoles,
    class_assets,
)
from mmusv.yamlio import mapping_source

__all__ = [
    "Combination",
    "Constraints",
    "CooperationCheck",
    "Difficulty",
    "GenerationSpec",
    "InWaterCheck",
    "LineOfSightCheck",
    "OcclusionCheck",
    "RouteSeparationCheck",
    "SensingRangeCheck",
    "SeparationCheck",
    "ShoreClearanceCheck",
    "SizeClass",
    "StructureClearanceCheck",
    "TargetRangeCheck",
    "UsvRoles",
    "class_assets",
    "load_spec",
    "with_seed",
]


def _cross_checks(spec: GenerationSpec, source: str) -> None:
    """Checks that need several fields; raises ConfigError naming the field at fault."""

    def fail(path: str, value: object, msg: str) -> None:
        raise ConfigError(f"{source}: invalid spec {path} = {short_repr(value)}: {msg}")

    if spec.rig not in spec.rigs:
        fail("rig", spec.rig, f"not defined under rigs: ({', '.join(sorted(spec.rigs))})")
    try:  # the rig must be valid in a scenario: validate it in a one-vessel scenario
        load_scenario(
            {
                "rigs": {spec.rig: spec.rigs[spec.rig]},
                "vessels": [{"id": "probe", "asset": "usv_wamv", "route": [[0, 0], [1, 0]]}],
            }
        )
    except ConfigError as exc:
        fail(f"rigs.{spec.rig}", spec.rigs[spec.rig], str(exc).removeprefix("scenario: "))
    for name, sc in spec.size_classes.items():
        names = class_assets(sc)
        if not names:
            fail(f"size_classes.{name}.length_m", list(sc.length_m), "no target asset has a length in this range")
        tops = {a: top_speed_mps(a) for a in names}
        if all(t < sc.speed_mps[0] for t in tops.values()):
            # the sampler keeps each target below its type's top speed, so every one was drawn below the range
            fail(
                f"size_classes.{name}.speed_mps",
                list(sc.speed_mps),
                "no vessel of this class sails that fast ("
                + ", ".join(f"{a} {t:g} m/s at most" for a, t in sorted(tops.items()))
                + f"): lower the low speed to {max(tops.values()):g} m/s or less, or add faster assets",
            )
    for name, d in spec.difficulties.items():
        if d.extra_classes is not None and not d.extra_classes:
            fail(
                f"difficulties.{name}.extra_classes",
                [],
                "an empty list has no class to draw the extra targets from: name size classes "
                f"({', '.join(spec.size_classes)}), or leave it out for every class",
            )
        for c in d.extra_classes or []:
            if c not in spec.size_classes:
                fail(f"difficulties.{name}.extra_classes", c, f"not a size class ({', '.join(spec.size_classes)})")
    _check_budget(spec, fail)
    labels: set[str] = set()
    for i, combo in enumerate(spec.combinations):
        where = f"combinations[{i}]"
        if combo.difficulty not in spec.difficulties:
            fail(
                f"{where}.difficulty",
                combo.difficulty,
                f"not defined under difficulties: ({', '.join(spec.difficulties)})",
            )
        for j, t in enumerate(combo.targets):
            if t not in spec.size_classes:
                fail(f"{where}.targets[{j}]", t, f"not a size class ({', '.join(spec.size_classes)})")
        fam = FAMILIES[combo.family]
        map_type = spec.map_of(combo).type
        if fam.map_types and map_type not in fam.map_types:
            fail(
                f"{where}.family",
                combo.family,
                f"needs a map of type {' or '.join(fam.map_types)} (map.type is {map_type})",
            )
        if combo.cooperating < fam.min_cooperating:
            fail(
                f"{where}.cooperating", combo.cooperating, f"family {combo.family} needs at least {fam.min_cooperating}"
            )
        label = combo.label()
        if label in labels:
            fail(f"{where}.name", label, "two combinations have this name; give them distinct `name:`s")
        labels.add(label)
        bad = _contradiction(spec, combo)
        if bad is not None:
            fail(f"constraints.{bad[0]}", bad[1], f"{where} ({label}) could never pass: {bad[2]}")


def _contradiction(spec: GenerationSpec, combo: Combination) -> tuple[str, float, str] | None:
    """Two enabled constraints (or a constraint and the combination) that no candidate can meet together, as
    ``(constraint field, its value, why)``; None when none is found. Without this, such a combination spent its
    every attempt (quota x max_attempts_per_scenario) and its report named only the constraint that rejected most,
    not that it never could pass. The arguments are exact: hulls at least ``separation.min_m`` apart put their
    centres farther apart still, and a vessel's centre is always on its route."""
    c = spec.constraints
    diff = spec.difficulties[combo.difficulty]
    lo, hi = diff.range_m
    sep = c.separation.min_m if c.separation.enabled else 0.0
    route_uu = c.route_separation.min_m if c.route_separation.enabled and "usv-usv" in c.route_separation.pairs else 0
    route_ut = (
        c.route_separation.min_m if c.route_separation.enabled and "usv-target" in c.route_separation.pairs else 0
    )
    coop = c.cooperation.enabled and c.cooperation.min_share > 0 and combo.cooperating >= 1
    density = c.target_density
    sensing = c.sensing_range
    most = len(combo.targets) + diff.extra_targets[1]
    if density.enabled and density.min_share > 0 and density.min_targets > most:
        return (
            "target_density.min_targets",
            density.min_targets,
            f"the combination has at most {most} target(s) ({len(combo.targets)} role target(s) + at most "
            f"{diff.extra_targets[1]} extra of difficulty {combo.difficulty}): lower min_targets or add targets",
        )
    if c.target_range.enabled and hi < max(sep, route_ut):
        what = "separation.min_m" if sep >= route_ut else "route_separation.min_m"
        return (
            what,
            max(sep, route_ut),
            f"difficulty {combo.difficulty} asks the ego and its target to come within {hi:g} m (range_m) and "
            f"target_range checks it, but {what} keeps them farther apart: lower {what} or raise range_m",
        )
    if coop and c.cooperation.max_m < max(sep, route_uu):
        what = "separation.min_m" if sep >= route_uu else "route_separation.min_m"
        return (
            what,
            max(sep, route_uu),
            f"cooperation asks every USV's nearest USV to be within {c.cooperation.max_m:g} m (max_m), but {what} "
            f"keeps the USVs farther apart: lower {what} or raise cooperation.max_m",
        )
    for name, check, rng in (("sensing_range", sensing, sensing.range_m), ("target_density", density, density.range_m)):
        if check.enabled and check.min_share > 0 and rng < sep:
            return (
                f"{name}.range_m",
                rng,
                f"separation keeps every target more than {sep:g} m (min_m) from every USV, so none is ever within "
                f"{rng:g} m: raise {name}.range_m or lower separation.min_m",
            )
    if (
        combo.cooperating == 0
        and c.target_range.enabled
        and sensing.enabled
        and sensing.min_share > 0
        and lo > (sensing.range_m)
    ):
        return (
            "sensing_range.range_m",
            sensing.range_m,
            f"with no cooperating USV the ego must sense its target, which difficulty {combo.difficulty} keeps at "
            f"least {lo:g} m away (range_m): raise sensing_range.range_m, lower range_m or add a cooperating USV",
        )
    return None


def _check_budget(spec: GenerationSpec, fail: Callable[[str, object, str], None]) -> None:
    """Refuses a spec whose every candidate would take more samples in time than the checks take at most
    (:data:`~mmusv.generate.samples.MAX_CHECK_SAMPLES`): a long window at the fastest speeds, many vessels."""
    from mmusv.generate.samples import MAX_CHECK_SAMPLES, time_samples

    acq = spec.acquisition
    speeds = [spec.usv.speed_mps[1], *(c.speed_mps[1] for c in spec.size_classes.values())]
    n_t = time_samples(acq.frames, frequency_hz=acq.frequency_hz, step=spec.check_step_m, max_speed_mps=max(speeds))
    for i, combo in enumerate(spec.combinations):
        diff = spec.difficulties.get(combo.difficulty)
        n_v = 1 + combo.cooperating + len(combo.targets) + (diff.extra_targets[1] if diff is not None else 0)
        if n_t * n_v > MAX_CHECK_SAMPLES:
            fail(
                "acquisition",
                {"frequency_hz": acq.frequency_hz, "frames": acq.frames},
                f"the checks of a combinations[{i}] candidate could take {n_t * n_v:,} samples ({n_t:,} in time at "
                f"up to {max(speeds):g} m/s, x {n_v} vessels), more than the {MAX_CHECK_SAMPLES:,} they take at most: "
                "lower frames or frequency_hz, the speeds (usv.speed_mps, size_classes.*.speed_mps) or raise "
                "check_step_m",
            )


def load_spec(source: str | os.PathLike[str] | dict[str, Any] | GenerationSpec) -> GenerationSpec:
    """Validates a generation spec given as a YAML path, a dict or a :class:`GenerationSpec` (returned as is)."""
    if isinstance(source, GenerationSpec):
        return source
    data, where = mapping_source(source, kind="spec", root_hint="at least `combinations:`")
    try:
        spec = GenerationSpec.model_validate(data)
    except ValidationError as exc:
        if "vessels" in data and "combinations" not in data:  # a scenario: its "vessels: extra input" said less
            shown = where if isinstance(source, (str, os.PathLike)) else "SCENARIO.yaml"
            raise ConfigError(
                f"{where} is a scenario (vessels:, no combinations:), not a generation spec: record it with "
                f"`mmusv run {shown}`"
            ) from None
        # an unknown key gets the keys allowed there and the closest one, as in a scenario ("sed": did you mean
        # 'seed'?); it said only "Extra inputs are not permitted"
        raise validation_error(exc, where, noun="spec", root="spec", data=data, model=GenerationSpec) from None
    except MmusvError as exc:  # a validator that checks through the core (wave presets, ...)
        raise located(exc, where) from None
    _cross_checks(spec, where)
    return spec


def with_seed(spec: GenerationSpec, seed: Any, *, name: str = "seed") -> GenerationSpec:
    """``spec`` with ``seed`` in place of its own ``seed`` (``mmusv generate --seed N``): checked as that field is,
    a whole number in ``0 .. 2**63 - 1`` (:class:`~mmusv.errors.ConfigError` naming ``name`` otherwise). Every random
    draw of the set derives from it, so the result generates the same files, byte for byte, as the spec file with
    ``seed: N`` written in it."""
    from mmusv import arguments

    value = arguments.whole(seed, name=name, lo=0, hi=SEED_LIMIT - 1)
    return spec.model_copy(update={"seed": value})
