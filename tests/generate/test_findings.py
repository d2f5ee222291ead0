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
    ctx = map_context("port", 3, {})
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
        _, found = map_findings(sc, map_context(sc.map.type, sc.map.seed, sc.map.param_values()))
        assert all(f.severity == "warning" for f in found), name
        assert np.all([f.check != "in_water" for f in found])
