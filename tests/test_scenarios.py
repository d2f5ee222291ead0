"""The bundled scenarios: valid, runnable, and the island one shows the occlusion of Fig. 1."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mmusv.config import load_scenario
from mmusv.simulation import Simulation

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = sorted((ROOT / "scenarios").glob("*.yaml"))


@pytest.mark.parametrize("path", BUNDLED, ids=lambda p: p.stem)
def test_bundled_scenarios_validate_with_two_to_four_usvs(path: Path) -> None:
    sc = load_scenario(path)
    assert 2 <= len(sc.usvs) <= 4
    assert len(sc.vessels) - len(sc.usvs) >= 2


def test_maps_covered() -> None:
    assert {load_scenario(p).map.type for p in BUNDLED} == {"island", "open_sea", "port"}


def test_island_hides_the_target_from_the_ego_but_not_from_the_others() -> None:
    sim = Simulation(ROOT / "scenarios/island_occlusion.yaml")
    target = next(v.instance_id for v in sim.vessels if v.id == "target_1")
    for k in (0, sim.frames - 1):
        cap = sim.capture(k, sensors=["lidar"])
        seen = {a: int(np.count_nonzero(c.lidar.instance == target)) for a, c in cap.agents.items() if c.lidar is not None}
        assert seen["usv_1"] == 0
        assert seen["usv_2"] + seen["usv_3"] > 0
