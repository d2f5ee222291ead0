"""``findings`` of the named checks: every failing vessel, the first one being exactly what ``check`` says (the
generator's verdict), and the failing route samples of a route over land."""

from __future__ import annotations

import numpy as np
from mmusv.bundled import resolve_scenario
from mmusv.config import load_scenario
from mmusv.generate.checks import Cooperation, InWater, LineOfSight, SensingRange, Separation, ShoreClearance
from mmusv.generate.mapctx import map_context
from mmusv.scenario_checks import map_check_spec, map_findings, scenario_samples


def _scenario(edit: dict[int, list[list[float]]]) -> object:
    data = load_scenario(resolve_scenario("port_entry")).model_dump(mode="json")
    for i, route in edit.items():
        data["vessels"][i]["route"] = route
    return load_scenario(data)


def test_first_finding_is_the_check_and_every_vessel_is_listed() -> None:
    # usv_1 and the tug sail onto land; the speedboat crosses the pilot's path; usv_3 goes far from the others
    sc = _scenario(
        {
            0: [[-170, -110], [-170, -30], [-120, 600]],
            4: [[-300, -60], [-220, -10], [-160, 650]],
            2: [[-700, -800], [-650, -850]],
        }
    )
    ctx = map_context("port", seed=3, params={})
    spec = map_check_spec(sc)
    s = scenario_samples(sc, ctx, spec)
    cons = spec.constraints
    for check in (
        InWater(),
        ShoreClearance(cons.shore_clearance),
        Separation(cons.separation),
        SensingRange(cons.sensing_range),
        Cooperation(cons.cooperation),
        LineOfSight(cons.line_of_sight),
    ):
        found = check.findings(s)
        assert check.check(s) == (found[0].message if found else None), check.name
    assert sorted(f.vessels[0] for f in InWater().findings(s)) == ["tug", "usv_1"]
    for f in InWater().findings(s):
        ((vid, mask),) = f.route.items()
        v = s.index(vid)
        land = ctx.world.heightfield.sample(s.geo[:, v]) > 0.0
        assert land.any() and not (land & ~mask).any()  # every route sample on land is flagged
        assert not mask[0]  # the start, in the harbour, is fine
    coop = {f.vessels[0] for f in Cooperation(cons.cooperation).findings(s)}
    assert "usv_3" in coop


def test_map_findings_of_the_bundled_scenarios_are_clean_or_warnings() -> None:
    for name in ("port_entry", "island_occlusion"):
        sc = load_scenario(resolve_scenario(name))
        _, found = map_findings(sc, map_context(sc.map.type, seed=sc.map.seed, params=sc.map.param_values()))
        assert all(f.severity == "warning" for f in found), name
        assert np.all([f.check != "in_water" for f in found])


def _crowded() -> object:
    """port_entry with every target sent across the same stretch of the entrance: many close pairs."""
    data = load_scenario(resolve_scenario("port_entry")).model_dump(mode="json")
    for k, v in enumerate(data["vessels"][3:]):
        v["route"] = [[-150.0 + 3.0 * k, -200.0], [-150.0 + 3.0 * k, -100.0]]
    return load_scenario(data)


def test_separation_in_blocks_is_the_whole_array(monkeypatch: object) -> None:
    """The separation check compares pairs x times in blocks (bounded memory); with blocks of 7 pair samples (so
    both the pairs and the times are split) its findings are those of one (times, pairs) array, computed here the
    plain way."""
    import mmusv.generate.checks as checks
    from mmusv.generate.hulls import segment_distance

    sc = _crowded()
    ctx = map_context("port", seed=3, params={})
    spec = map_check_spec(sc)
    s = scenario_samples(sc, ctx, spec)
    sep = Separation(spec.constraints.separation)
    iu, ju = np.triu_indices(len(s.ids), 1)
    d = np.stack([np.cos(s.motion_yaw), np.sin(s.motion_yaw)], axis=-1) * s.half[None, :, None]
    p, q = s.motion - d, s.motion + d
    hull = segment_distance(p[:, iu], q[:, iu], p2=p[:, ju], q2=q[:, ju]) - (s.radius[iu] + s.radius[ju])[None, :]
    slack = s.motion_slack + s.motion_turn
    gap = hull - (slack[iu] + slack[ju])[None, :] - sep.min_m
    worst = gap.min(axis=0)
    want = []
    for j in sorted(np.flatnonzero(worst < 0.0), key=lambda j: (float(worst[j]), int(j))):
        k = int(np.argmin(gap[:, j]))
        words = (
            f"pass with their hull capsules overlapping by {-hull[k, j]:.1f} m"
            if hull[k, j] < 0
            else f"come {hull[k, j]:.1f} m apart (hulls)"
        )
        want.append((s.ids[int(iu[j])], s.ids[int(ju[j])], words, f"{s.times[k]:.1f}"))
    assert len(want) >= 3
    for block in (7, 10**6):
        monkeypatch.setattr(checks, "_PAIR_BLOCK", block)  # type: ignore[attr-defined]
        got = sep.findings(s)
        assert [f.vessels for f in got] == [w[:2] for w in want]
        assert all(w[2] in f.message and f"t={w[3]} s" in f.message for f, w in zip(got, want, strict=True))


def test_route_separation_is_the_closest_pair_of_route_samples() -> None:
    """RouteSeparation's k-d tree finds the closest pair of route samples of every USV-target pair: the distance
    it reports is the brute-force minimum over all pairs of samples."""
    from mmusv.generate.checks import RouteSeparation
    from mmusv.generate.spec import RouteSeparationCheck

    sc = _crowded()
    s = scenario_samples(sc, map_context("port", seed=3, params={}), map_check_spec(sc))
    usv, target = s.index("usv_3"), s.index("pilot")
    brute = float(np.linalg.norm(s.geo[:, usv, None, :] - s.geo[None, :, target, :], axis=-1).min())
    gap = brute - s.geo_slack[usv] - s.geo_slack[target]
    near = RouteSeparation(RouteSeparationCheck(min_m=gap + 0.05, pairs=["usv-target"])).check(s)
    far = RouteSeparation(RouteSeparationCheck(min_m=gap - 0.05, pairs=["usv-target"])).check(s)
    assert near is not None and "come within" in near
    assert far is None or "usv_3 and pilot" not in far


def test_a_fleet_too_large_to_compare_pairwise_is_refused_before_sampling() -> None:
    """Thousands of vessels: the pairs at every time exceed MAX_CHECK_PAIR_SAMPLES, so the checks refuse (naming
    the pairs) instead of taking minutes."""
    from mmusv.generate.samples import MAX_CHECK_PAIR_SAMPLES, budget_problem

    data = load_scenario(resolve_scenario("port_entry")).model_dump(mode="json")
    base = data["vessels"][3]
    data["vessels"] += [{**base, "id": f"extra_{k}"} for k in range(1500)]
    sc = load_scenario(data)
    problem = budget_problem(sc, n_motion=100, n_route=100)
    assert problem is not None and "pairs of vessels" in problem and f"{MAX_CHECK_PAIR_SAMPLES:,}" in problem
    assert budget_problem(load_scenario(resolve_scenario("port_entry")), n_motion=100, n_route=100) is None


def test_overlapping_hulls_are_said_to_overlap() -> None:
    """Two hulls that overlap were said to "come -33.7 m apart" (found by the soak of random scenarios); the words
    say the covering capsules overlap (alongside, the hulls need not: hulls that intersect are an error of their
    own, ``hulls_intersect``)."""
    from mmusv.generate.checks import separation_words

    assert separation_words(-33.74) == "pass with their hull capsules overlapping by 33.7 m"
    assert separation_words(3.26) == "come 3.3 m apart (hulls)"
    assert separation_words(0.0) == "come 0.0 m apart (hulls)"
