"""The sampler: one candidate scenario per (spec, combination, attempt), deterministically.

The random generator of an attempt is ``numpy.random.default_rng(SeedSequence([spec.seed, combination key,
attempt]))``, so a candidate does not depend on what other combinations or attempts drew, but for its number of
distractors, drawn for its place in the quota (:func:`extra_count`) so that the accepted scenarios have the counts
the spec asks for. The combination key comes from the combination's name (:func:`combination_key`), not from its
place in the list: a combination added, removed or moved leaves the scenarios of the others as they were. The
sampler draws the environment choices, the assets and nominal speeds of every role, an encounter centre in open water
(map priors), lets the family template lay out the routes, scatters the difficulty's distractor targets around the
centre and assembles a scenario dict with every number rounded (metres and m/s to 0.01) in a fixed key order, validated
with :func:`mmusv.config.load_scenario`. Units: metres, seconds, m/s; world frame.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mmusv.config import Scenario, load_scenario
from mmusv.generate.families import FAMILIES
from mmusv.generate.hulls import capsule
from mmusv.generate.layout import (
    FamilyInput,
    Layout,
    Role,
    SamplingError,
    Track,
    pick_best,
    straight_track,
    top_speed_mps,
)
from mmusv.generate.mapctx import MapContext
from mmusv.generate.spec_models import Combination, GenerationSpec, class_assets
from mmusv.world.vessels import get_asset

__all__ = [
    "Candidate",
    "CandidateMeta",
    "attempt_rng",
    "combination_key",
    "extra_count",
    "hull_radius",
    "sample_candidate",
    "scenario_seed",
]


@dataclass(frozen=True)
class CandidateMeta:
    """The roles of a candidate's vessels (ids) and what its checks need beyond the scenario itself.

    ``occlusion_share`` is the share of frames the primary target must be hidden from the ego (None: no
    occlusion requirement); ``range_m`` the difficulty's closest-approach range for the ``ranged`` targets.
    """

    combination: str
    family: str
    difficulty: str
    attempt: int
    ego: str
    cooperating: tuple[str, ...]
    targets: tuple[str, ...]
    primary: str
    ranged: tuple[str, ...]
    distractors: tuple[str, ...]
    range_m: tuple[float, float]
    occlusion_share: float | None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready roles (for the report)."""
        return {
            "ego": self.ego,
            "cooperating": list(self.cooperating),
            "targets": list(self.targets),
            "primary": self.primary,
            "ranged": list(self.ranged),
            "distractors": list(self.distractors),
            "range_m": list(self.range_m),
            "occlusion_share": self.occlusion_share,
        }


@dataclass(frozen=True)
class Candidate:
    """A sampled scenario: the rounded ``data`` dict (what gets written), its validated ``scenario`` and roles."""

    data: dict[str, Any]
    scenario: Scenario
    meta: CandidateMeta


def combination_key(name: str) -> int:
    """The key of a combination in every seed of its draws: the first 128 bits of the SHA-256 of its name
    (:meth:`~mmusv.generate.spec_models.Combination.label`, unique in a spec), a whole number in ``[0, 2**128)``."""
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:16], "little")


def attempt_rng(seed: int, *, combination: str, attempt: int) -> np.random.Generator:
    """The random generator of one attempt of the combination named ``combination`` (see module docstring)."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), combination_key(combination), int(attempt)]))


def scenario_seed(seed: int, *, combination: str, attempt: int) -> int:
    """The ``seed`` written into a scenario (wave phases etc.), in ``[0, 2**63)``, from the same triple."""
    entropy = [int(seed), combination_key(combination), int(attempt), 1]
    hi, lo = np.random.SeedSequence(entropy).generate_state(2, np.uint32)
    return ((int(hi) << 32) | int(lo)) >> 1


def hull_radius(asset: str) -> float:
    """Radius (metres) of the bounding circle of an asset's hull footprint: half its length-beam diagonal."""
    a = get_asset(asset)
    return 0.5 * math.hypot(a.length, a.beam)


def _r(x: float) -> float:
    """Rounded to 0.01 with -0.0 normalised (byte-stable YAML)."""
    return round(float(x), 2) + 0.0


def _route(points: np.ndarray) -> list[list[float]]:
    out: list[list[float]] = []
    for x, y in np.asarray(points, dtype=np.float64):
        p = [_r(x), _r(y)]
        if not out or math.hypot(p[0] - out[-1][0], p[1] - out[-1][1]) >= 0.01:
            out.append(p)
    if len(out) < 2:
        out.append([_r(out[0][0] + 1.0), out[0][1]])
    return out


def _choice(rng: np.random.Generator, items: list[str]) -> str:
    return items[int(rng.integers(len(items)))]


def _environment(spec: GenerationSpec, rng: np.random.Generator) -> dict[str, Any]:
    """One draw of the spec's environment choices. A rain rate drawn beside a clear sky is left out (a clear sky
    does not rain, and the scenario refuses the pair): the rates are for the draws of the other weathers."""
    env: dict[str, Any] = {}
    for key in sorted(spec.environment):
        value = spec.environment[key]
        env[key] = value[int(rng.integers(len(value)))] if isinstance(value, list) else value
    if env.get("weather", "clear") == "clear":
        env.pop("rain_mm_per_h", None)
    return env


def _vessel(t: Track, rig: str) -> dict[str, Any]:
    r = t.role
    out: dict[str, Any] = {"id": r.id, "role": r.role, "asset": r.asset}
    if r.role == "usv":
        out["rig"] = rig
    out["speed_mps"] = _r(t.speed)
    out["end"] = "stop"
    out["start_offset_m"] = _r(t.start_offset)
    out["route"] = _route(t.route)
    return out


def extra_count(seed: int, *, combination: str, slot: int, extra: tuple[int, int]) -> int:
    """The number of distractors of the ``slot``-th scenario of the quota of the combination named
    ``combination`` (0-based), uniform over ``extra`` (the difficulty's ``extra_targets``), from
    ``SeedSequence([seed, combination key, slot, 2])``.
    Drawn per place in the quota, not per attempt: a candidate with more distractors fails the checks more often,
    so a count drawn anew at every attempt left the accepted scenarios with mostly few (39, 37, 16 and 8 of 100
    with 0, 1, 2 and 3 asked uniform)."""
    lo, hi = extra
    if lo == hi:
        return lo
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), combination_key(combination), int(slot), 2]))
    return int(rng.integers(lo, hi + 1))


def sample_candidate(
    spec: GenerationSpec, *, combo_index: int, attempt: int, ctx: MapContext, name: str, slot: int | None = None
) -> Candidate:
    """Draws candidate ``attempt`` of combination ``combo_index``, named ``name``; raises :class:`SamplingError`
    when the template cannot place the vessels. ``slot``: the place in the quota the candidate is for (the number
    of scenarios the combination has accepted so far), which fixes its distractor count (:func:`extra_count`);
    None draws the count from the attempt's generator."""
    combo: Combination = spec.combinations[combo_index]
    fam = FAMILIES[combo.family]
    diff = spec.difficulties[combo.difficulty]
    key = combo.label()  # the seeds' key: the combination's name, not its place in the list
    rng = attempt_rng(spec.seed, combination=key, attempt=attempt)
    acq = spec.acquisition
    duration = max((acq.frames - 1) / acq.frequency_hz, 1.0 / acq.frequency_hz)
    cons = spec.constraints
    env = _environment(spec, rng)
    usv_lo, usv_hi = spec.usv.speed_mps

    def usv(role_id: str, asset: str) -> Role:
        return Role(role_id, "usv", asset, float(rng.uniform(usv_lo, usv_hi)), hull_radius(asset), capsule(asset)[1])

    def target(role_id: str, cls: str) -> Role:
        sc = spec.size_classes[cls]
        asset = _choice(rng, class_assets(sc))
        # the class's range, kept below what the vessel type makes (from half its top speed; one draw either way)
        top = top_speed_mps(asset)
        speed = float(rng.uniform(min(sc.speed_mps[0], top / 2.0), min(sc.speed_mps[1], top)))
        return Role(role_id, "target", asset, speed, hull_radius(asset), capsule(asset)[1])

    ego = usv("usv_ego", combo.ego or spec.usv.assets[0])
    coops = [usv(f"usv_coop_{k + 1}", _choice(rng, spec.usv.assets)) for k in range(combo.cooperating)]
    targets = [target(f"target_{k + 1}", cls) for k, cls in enumerate(combo.targets)]
    shore = cons.shore_clearance.min_m if cons.shore_clearance.enabled else 0.0
    struct = cons.structure_clearance.min_m if cons.structure_clearance.enabled else 0.0
    inp = FamilyInput(
        ctx=ctx,
        rng=rng,
        duration=duration,
        ego=ego,
        coops=coops,
        targets=targets,
        range_m=diff.range_m,
        coop_m=(cons.cooperation.min_m, cons.cooperation.max_m),
        usv_speed=spec.usv.speed_mps,
        separation_m=cons.separation.min_m if cons.separation.enabled else 0.0,
        clearance_m=max(shore, struct),
        encounter_clearance=spec.encounter_clearance_m,
        proposals=spec.proposals,
    )
    try:
        layout: Layout = fam.build(inp)
    except ValueError as exc:  # no valid water cell at all
        raise SamplingError(str(exc)) from None
    # distractors: extra targets around the encounter centre on random straight tracks
    # (drawn from the attempt's generator either way, so that its later draws stay where they were)
    n_extra = int(rng.integers(diff.extra_targets[0], diff.extra_targets[1] + 1))
    if slot is not None:  # the count for the candidate's place in the quota
        n_extra = extra_count(spec.seed, combination=key, slot=slot, extra=diff.extra_targets)
    classes = diff.extra_classes or list(spec.size_classes)
    reach = max(diff.range_m[1], 150.0)
    distractors = []
    for k in range(n_extra):
        role = target(f"distractor_{k + 1}", _choice(rng, classes))

        def make(role: Role = role) -> list[Track]:
            dist = reach * math.sqrt(float(rng.uniform()))
            bearing = float(rng.uniform(0.0, 2.0 * math.pi))
            at = layout.centre + dist * np.array([math.cos(bearing), math.sin(bearing)])
            psi = float(rng.uniform(0.0, 2.0 * math.pi))
            vel = role.speed * np.array([math.cos(psi), math.sin(psi)])
            return [
                straight_track(role, at=at, vel=vel, t_at=float(rng.uniform(0.0, duration)), duration=duration, rng=rng)
            ]

        distractors += pick_best(inp, make)
    tracks = layout.tracks + distractors
    map_cfg = spec.map_of(combo)
    order = {"usv": 0, "target": 1}
    tracks.sort(key=lambda t: (order[t.role.role], 0 if t.role.id == "usv_ego" else 1))
    data: dict[str, Any] = {
        "name": name,
        "seed": scenario_seed(spec.seed, combination=key, attempt=attempt),
        "map": {"type": map_cfg.type, "seed": map_cfg.seed, "params": map_cfg.param_values()},
        "environment": env,
        "acquisition": {"frequency_hz": acq.frequency_hz, "frames": acq.frames},
        "rigs": {spec.rig: dict(spec.rigs[spec.rig])},
        "vessels": [_vessel(t, spec.rig) for t in tracks],
    }
    if not data["map"]["params"]:
        del data["map"]["params"]
    if not env:
        del data["environment"]
    occl: float | None = None
    if cons.occlusion.enabled and (fam.occlusion or diff.occluded_share is not None):
        occl = diff.occluded_share if diff.occluded_share is not None else cons.occlusion.min_occluded_share
    meta = CandidateMeta(
        combination=combo.label(),
        family=combo.family,
        difficulty=combo.difficulty,
        attempt=attempt,
        ego=ego.id,
        cooperating=tuple(c.id for c in coops),
        targets=tuple(t.id for t in targets),
        primary=targets[0].id,
        ranged=tuple(layout.ranged),
        distractors=tuple(t.role.id for t in distractors),
        range_m=diff.range_m,
        occlusion_share=occl,
    )
    return Candidate(data=data, scenario=load_scenario(data), meta=meta)
