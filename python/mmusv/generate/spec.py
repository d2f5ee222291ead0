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
candidate of a combination could meet together are refused here (:mod:`mmusv.generate.spec_checks`), naming the
constraint, the combination and the other bound (``separation.min_m`` above the difficulty's ``range_m`` or
``cooperation.max_m``, a sensing or density range inside the separation, ``target_density.min_targets`` above the
targets a combination has, a lone ego whose target is kept beyond its sensing range), rather than spending every
attempt on them. So are a size class
none of whose vessels sails as fast as its ``speed_mps`` low (each target is kept below its type's top speed, so
every draw would fall below the range) and an empty ``assets`` or ``extra_classes`` list (it named no vessel, and
drew the distractors from every class). A clearance that
no water of a combination's map offers to its vessels needs the map: :func:`mmusv.generate.runner.generate` refuses
it the same way once the map is built, before the first attempt.
"""

from __future__ import annotations

import os
from typing import Any

from pydantic import ValidationError

from mmusv.config import validation_error
from mmusv.errors import ConfigError, MmusvError, located
from mmusv.generate.spec_checks import cross_checks
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
    cross_checks(spec, where)
    return spec


def with_seed(spec: GenerationSpec, seed: Any, *, name: str = "seed") -> GenerationSpec:
    """``spec`` with ``seed`` in place of its own ``seed`` (``mmusv generate --seed N``): checked as that field is,
    a whole number in ``0 .. 2**63 - 1`` (:class:`~mmusv.errors.ConfigError` naming ``name`` otherwise). Every random
    draw of the set derives from it, so the result generates the same files, byte for byte, as the spec file with
    ``seed: N`` written in it."""
    from mmusv import arguments

    value = arguments.whole(seed, name=name, lo=0, hi=SEED_LIMIT - 1)
    return spec.model_copy(update={"seed": value})
