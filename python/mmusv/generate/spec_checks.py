"""The checks of a generation spec across its fields (:func:`cross_checks`), once each model has checked its own
(:mod:`mmusv.generate.spec_models`): the rig in use, the size classes' assets and speeds, the difficulties and
size classes a combination names, a family's map type and USVs, two combinations of one name, constraints that no
candidate of a combination could meet together, and the samples a candidate's checks could take.
:func:`mmusv.generate.spec.load_spec` runs them; each failure is a :class:`mmusv.ConfigError` naming the field.
"""

from __future__ import annotations

from collections.abc import Callable

from mmusv.config import load_scenario
from mmusv.config_errors import short_repr
from mmusv.errors import ConfigError
from mmusv.generate.families import FAMILIES
from mmusv.generate.layout import top_speed_mps
from mmusv.generate.spec_models import Combination, GenerationSpec, class_assets

__all__ = ["cross_checks"]


def cross_checks(spec: GenerationSpec, source: str) -> None:
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
