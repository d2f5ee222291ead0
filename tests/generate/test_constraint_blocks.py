"""A spec's constraint blocks: writing a check's block turns it on (``target_density`` and ``line_of_sight`` were
dropped without a word unless they said ``enabled: true``), and a combination whose vessels fit nowhere on its map
at the clearances asked is refused before the first attempt (it spent every attempt: 100,000 took 12 minutes)."""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.errors import ConfigError
from mmusv.generate import generate, load_spec
from mmusv.generate.checks import build_constraints
from mmusv.generate.cli import add_parser, run
from mmusv.generate.hulls import capsule
from mmusv.generate.runner import _infeasible
from mmusv.generate.spec_constraints import Constraints
from mmusv.generate.spec_models import class_assets

TINY: dict[str, Any] = {
    "name": "tiny",
    "seed": 5,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 2, "frames": 4},
    "difficulties": {"close": {"range_m": [80, 250]}},
    "combinations": [{"family": "crossing", "difficulty": "close", "cooperating": 1, "targets": ["small"]}],
}


def _spec(constraints: dict[str, Any], **more: Any) -> dict[str, Any]:
    return dict(TINY, constraints=constraints, **more)


# ------------------------------------------------------------------------------------ a block turns a check on


def test_an_impossible_target_density_block_is_refused_without_enabled() -> None:
    """The tester's spec: without ``enabled: true`` the block was dropped and the run wrote a scenario (rc 0)."""
    spec = _spec({"target_density": {"min_targets": 50, "range_m": 10, "min_share": 1}})
    with pytest.raises(ConfigError, match=r"constraints\.target_density\.min_targets = 50: .*could never pass"):
        load_spec(spec)


def test_a_line_of_sight_block_without_enabled_is_checked() -> None:
    spec = load_spec(_spec({"line_of_sight": {"min_share": 1.0}}))
    assert spec.constraints.line_of_sight.enabled and spec.constraints.line_of_sight.min_share == 1.0
    assert "line_of_sight" in [c.name for c in build_constraints(spec)]


@pytest.mark.parametrize("name", list(Constraints.model_fields))
def test_every_check_is_on_once_its_block_is_written_and_off_with_enabled_false(name: str) -> None:
    assert getattr(load_spec(_spec({name: {}})).constraints, name).enabled
    assert not getattr(load_spec(_spec({name: {"enabled": False}})).constraints, name).enabled


def test_a_spec_that_does_not_mention_a_check_keeps_the_documented_defaults() -> None:
    """All on, except target_density and line_of_sight (README, mmusv.generate.spec_constraints)."""
    cons = load_spec(_spec({})).constraints
    off = {name for name in Constraints.model_fields if not getattr(cons, name).enabled}
    assert off == {"target_density", "line_of_sight"}
    assert cons == Constraints()


# ---------------------------------------------------------------------------- clearance no vessel could meet


def test_a_clearance_no_water_offers_is_refused_at_once_and_writes_nothing(tmp_path: Path) -> None:
    spec = _spec({"shore_clearance": {"min_m": 100000}}, max_attempts_per_scenario=1000)
    out = tmp_path / "out"
    t0 = time.perf_counter()
    with pytest.raises(
        ConfigError,
        match=r"^spec: invalid spec constraints\.shore_clearance\.min_m = 100000\.0: combinations\[0\] "
        r"\(crossing_close_2usv_small\) could never pass: size class 'small' needs \d+ m of clearance from the "
        r"shore \(\w+ hull radius [0-9.]+ m \+ 100000 m\) and the most open water on this map \(open_sea, seed 2\) "
        r"offers \d+ m: lower shore_clearance\.min_m$",
    ):
        generate(spec, out)
    assert time.perf_counter() - t0 < 60.0
    assert not out.exists()


def test_the_cli_names_the_spec_file_and_writes_nothing(tmp_path: Path) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(_spec({"shore_clearance": {"min_m": 100000}}), sort_keys=False))
    parser = argparse.ArgumentParser(prog="mmusv")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["generate", str(path), "-o", str(tmp_path / "out"), "--no-progress"])
    with pytest.raises(
        ConfigError, match=rf"^{re.escape(str(path))}: invalid spec constraints\.shore_clearance\.min_m"
    ):
        run(args)
    assert not (tmp_path / "out").exists()


def _ctx(shore: list[float], struct: list[float]) -> Any:
    """A map of two cells with these clearances from the shore and from structures (no cell slack)."""
    return SimpleNamespace(d_shore=np.array([shore]), d_struct=np.array([struct]), cell_slack=0.0)


def _small_radius() -> float:
    return min(capsule(a)[1] for a in class_assets(load_spec(TINY).size_classes["small"]))


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"difficulties": {"close": {"range_m": [6000, 7000]}}}, r"difficulties\.close\.range_m = 6000\.0"),
        (
            {"constraints": {"cooperation": {"min_m": 6000, "max_m": 7000}}},
            r"constraints\.cooperation\.min_m = 6000\.0",
        ),
    ],
)
def test_a_distance_beyond_the_maps_water_is_refused_at_once(
    change: dict[str, Any], field: str, tmp_path: Path
) -> None:
    """A cooperation of 3,000 m, or a closest approach of 5,000 m, on a 2,000 m island map spent every attempt on
    rejections (120 of them, then "quota not met"): no two points of its water lie that far apart."""
    out = tmp_path / "out"
    with pytest.raises(
        ConfigError,
        match=rf"^spec: invalid spec {field}: combinations\[0\] \(crossing_close_2usv_small\) could never pass: .* "
        r"the navigable water of this map \(open_sea, seed 2\) spans at most \d+ m: lower",
    ):
        generate(dict(TINY, **change), out)
    assert not out.exists()


def test_the_clearance_refusal_is_exact() -> None:
    """A clearance a cell just offers is kept; a vessel needs one cell clear of the shore and the structures at
    once, each against its own raster (the old estimate took the nearer of both for either)."""
    r = _small_radius()
    both = load_spec(_spec({"shore_clearance": {"min_m": 50}, "structure_clearance": {"min_m": 50}}))
    widest = max(r, capsule(both.usv.assets[0])[1])  # the USVs' hull: the widest the roles need
    assert _infeasible(both, _ctx([50 + widest, 0], [50 + widest, 0]), 0) is None
    assert _infeasible(both, _ctx([50 + widest - 0.01, 0], [50 + widest, 0]), 0) is not None
    bad = _infeasible(both, _ctx([1000, 10], [10, 1000]), 0)
    assert bad is not None and bad[:2] == ("constraints.shore_clearance.min_m", 50.0)
    assert bad[2].startswith(f"size class 'small' needs {50 + r:.0f} m of clearance from the shore and ")
    assert bad[2].endswith(
        "and no water on this map (open_sea, seed 2) offers both: lower shore_clearance.min_m or "
        "structure_clearance.min_m"
    )
    bad = _infeasible(both, _ctx([1000, 1000], [10, 40]), 0)
    assert bad is not None and bad[0] == "constraints.structure_clearance.min_m" and "lies farther than 40 m" in bad[2]
    shore_only = load_spec(_spec({"shore_clearance": {"min_m": 50}, "structure_clearance": {"enabled": False}}))
    assert _infeasible(shore_only, _ctx([1000, 10], [10, 1000]), 0) is None
    off = load_spec(_spec({"shore_clearance": {"enabled": False}, "structure_clearance": {"enabled": False}}))
    assert _infeasible(off, _ctx([0, 0], [0, 0]), 0) is None


def test_the_ego_is_checked_too() -> None:
    """Targets that fit do not hide an ego that does not (a USV hull wider than the slimmest small target)."""
    spec = load_spec(_spec({"shore_clearance": {"min_m": 10}, "structure_clearance": {"enabled": False}}))
    r_target = _small_radius()
    r_ego = capsule(spec.usv.assets[0])[1]
    assert r_ego > r_target
    room = 10 + (r_ego + r_target) / 2
    bad = _infeasible(spec, _ctx([room, room], [np.inf, np.inf]), 0)
    assert bad is not None and f"the ego ({spec.usv.assets[0]})" in bad[2]


def test_a_closest_approach_range_of_one_value_is_refused() -> None:
    """``range_m: [100, 100]`` was accepted, then every attempt failed ("is 100 m, outside [100, 100] m")."""
    spec = dict(TINY, difficulties={"close": {"range_m": [100, 100]}})
    with pytest.raises(
        ConfigError, match=r"difficulties\.close\.range_m.*low < high: no candidate passes at exactly 100"
    ):
        load_spec(spec)
    load_spec(dict(TINY, difficulties={"close": {"range_m": [99, 100]}}))
