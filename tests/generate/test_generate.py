"""mmusv generate: report arithmetic, byte determinism, impossible specs end with a clear report, spec errors
name the field, outputs load with load_scenario, the CLI entry points."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError, IoError, NotFoundError
from mmusv.generate import FAMILIES, generate, load_spec
from mmusv.generate.cli import add_parser, run

ROOT = Path(__file__).resolve().parents[2]
SPECS = ROOT / "scenarios" / "specs"
CHECK_NAMES = {
    "in_water",
    "shore_clearance",
    "structure_clearance",
    "separation",
    "route_separation",
    "target_range",
    "sensing_range",
    "cooperation",
    "line_of_sight",
    "occlusion",
}

SMALL: dict[str, Any] = {
    "name": "small",
    "seed": 3,
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 24},
    "environment": {"time_of_day": ["08:30", "12:00"], "weather": ["clear", "rain"], "wave": ["W0", "W1"]},
    "difficulties": {"easy": {"range_m": [60, 200]}, "hard": {"range_m": [300, 700], "extra_targets": [1, 3]}},
    "combinations": [
        {"family": "crossing", "difficulty": "hard", "cooperating": 2, "targets": ["large", "small"], "quota": 3},
        {"family": "head_on", "difficulty": "easy", "cooperating": 1, "targets": ["small"], "quota": 2},
        {"family": "convoy", "difficulty": "easy", "targets": ["medium", "medium", "small"], "quota": 2},
        {"family": "occluded_by_island", "difficulty": "hard", "cooperating": 1, "targets": ["small"], "quota": 1},
    ],
    "constraints": {"separation": {"min_m": 25}, "route_separation": {"min_m": 40}, "line_of_sight": {"enabled": True}},
}


@pytest.fixture(scope="module")
def small_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    out = tmp_path_factory.mktemp("small")
    generate(SMALL, out)
    return out, json.loads((out / "report.json").read_text())


def test_report_adds_up_and_names_the_constraints(small_run: tuple[Path, dict[str, Any]]) -> None:
    out, rep = small_run
    assert rep["constraints"] == [n for n in load_spec(SMALL).constraints.model_dump() if n in CHECK_NAMES]
    for c in rep["combinations"]:
        assert c["accepted"] + sum(c["rejected"].values()) == c["attempts"] <= c["max_attempts"]
        assert set(c["rejected"]) <= CHECK_NAMES | {"sampling", "schema", "under_keel"}  # under_keel: always on
        assert set(c["examples"]) == set(c["rejected"])
        assert c["quota_met"] == (c["accepted"] >= c["quota"]) and len(c["files"]) == c["accepted"]
        assert c["why"] == "quota met" if c["quota_met"] else c["why"].startswith(f"{c['accepted']}/{c['quota']}")
    assert rep["accepted"] + sum(rep["rejected"].values()) == rep["attempts"]
    assert rep["attempts"] == sum(c["attempts"] for c in rep["combinations"])
    assert sum(rep["rejected"].values()) > 0, "the hard combination should have rejected something"
    assert sorted(p.name for p in out.glob("*.yaml")) == sorted(s["file"] for s in rep["scenarios"])


def test_outputs_are_valid_scenarios_with_a_rig_for_every_usv(small_run: tuple[Path, dict[str, Any]]) -> None:
    out, rep = small_run
    seeds = set()
    for entry in rep["scenarios"]:
        sc = load_scenario(out / entry["file"])
        assert sc.name == entry["file"].removesuffix(".yaml") and sc.seed == entry["seed"]
        assert sc.map.type == "island" and sc.map.seed == 4 and sc.acquisition.frames == 24
        assert list(sc.rigs) == ["usv_standard"]
        assert all(v.rig == "usv_standard" for v in sc.vessels if v.role == "usv")
        assert sc.vessels[0].id == entry["roles"]["ego"] == "usv_ego"
        assert {v.id for v in sc.vessels} == {
            "usv_ego",
            *entry["roles"]["cooperating"],
            *entry["roles"]["targets"],
            *entry["roles"]["distractors"],
        }
        seeds.add(sc.seed)
        for v in sc.vessels:  # numbers rounded to 0.01 before writing
            assert all(round(x, 2) == x for p in v.route for x in p) and round(v.speed_mps, 2) == v.speed_mps
    assert len(seeds) == len(rep["scenarios"])


def test_same_spec_same_bytes(small_run: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    out, _ = small_run
    generate(SMALL, tmp_path)
    a = {p.name: p.read_bytes() for p in sorted(out.iterdir())}
    b = {p.name: p.read_bytes() for p in sorted(tmp_path.iterdir())}
    assert a.keys() == b.keys() and "report.json" in a
    assert a == b


def test_another_seed_gives_other_scenarios(small_run: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    out, _ = small_run
    spec = dict(SMALL, seed=4, combinations=SMALL["combinations"][1:2])
    generate(spec, tmp_path)
    for p in tmp_path.glob("*.yaml"):
        assert p.read_bytes() != (out / p.name).read_bytes()


def test_a_combination_keeps_its_scenarios_when_the_others_are_added_removed_or_moved(
    small_run: tuple[Path, dict[str, Any]], tmp_path: Path
) -> None:
    # The seeds of a combination's draws came from its place in the list: a combination put before it (or one
    # before it removed) gave it other scenarios, other seeds and other distractor counts. They come from its name.
    out, _ = small_run
    head_on, convoy, occluded = SMALL["combinations"][1:4]
    added = {"family": "overtaking", "difficulty": "easy", "targets": ["small"], "quota": 1}
    spec = dict(SMALL, combinations=[added, occluded, convoy, head_on])
    generate(spec, tmp_path)
    kept = [p for p in sorted(out.glob("*.yaml")) if not p.name.startswith("crossing_")]
    assert len(kept) == 5
    for p in kept:
        assert (tmp_path / p.name).read_bytes() == p.read_bytes(), p.name
    report = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    ours = {s["file"]: s for s in json.loads((out / "report.json").read_text(encoding="utf-8"))["scenarios"]}
    for s in report["scenarios"]:
        if s["file"] in ours:
            assert s == ours[s["file"]]  # the same attempt, seed and roles


def test_impossible_spec_ends_with_a_clear_report(tmp_path: Path) -> None:
    t0 = time.perf_counter()
    rep = generate(SPECS / "impossible_port.yaml", tmp_path)
    assert time.perf_counter() - t0 < 30.0
    assert not rep.all_met and rep.accepted == 0
    data = json.loads((tmp_path / "report.json").read_text())
    assert data["all_quotas_met"] is False and data["accepted"] == 0
    assert data["accepted"] + sum(data["rejected"].values()) == data["attempts"] > 0
    for c in data["combinations"]:
        assert c["attempts"] == c["max_attempts"] and not c["quota_met"]
        assert "accepted after" in c["why"] and "rejected" in c["why"]
    entry = data["combinations"][0]
    assert "sampling" in entry["rejected"] and "clearance" in entry["why"]


def test_existing_output_is_not_overwritten_without_force(tmp_path: Path) -> None:
    spec = dict(SMALL, combinations=[dict(SMALL["combinations"][1], quota=1)])
    generate(spec, tmp_path)
    with pytest.raises(IoError, match="--force"):
        generate(spec, tmp_path)
    generate(spec, tmp_path, force=True)
    assert len(list(tmp_path.glob("*.yaml"))) == 1


BAD_SPECS: list[tuple[dict[str, Any], str]] = [
    (
        {"combinations": [{"family": "crosing"}]},
        r"combinations\[0\]\.family = 'crosing': unknown family; did you mean crossing",
    ),
    ({"combinations": [{"family": "crossing", "difficulty": "insane"}]}, r"combinations\[0\]\.difficulty = 'insane'"),
    (
        {"combinations": [{"family": "crossing", "targets": ["tiny"]}]},
        r"combinations\[0\]\.targets\[0\] = 'tiny': not a size class",
    ),
    ({"combinations": [{"family": "crossing", "quota": 0}]}, r"combinations\[0\]\.quota = 0"),
    ({"combinations": [{"family": "crossing", "ego": "tug_32m"}]}, r"combinations\[0\]\.ego = 'tug_32m': .*USV"),
    (
        {"combinations": [{"family": "port_entry"}]},
        r"combinations\[0\]\.family = 'port_entry': needs a map of type port",
    ),
    ({"combinations": [{"family": "occluded_by_island"}]}, r"combinations\[0\]\.cooperating = 0"),
    ({"combinations": []}, r"invalid spec combinations = \[\]"),
    (
        {"combinations": [{"family": "crossing"}], "constraints": {"separation": {"min_m": -1}}},
        r"constraints\.separation\.min_m = -1",
    ),
    (
        {"combinations": [{"family": "crossing"}], "constraints": {"cooperation": {"min_m": 900, "max_m": 100}}},
        r"constraints\.cooperation",
    ),
    ({"combinations": [{"family": "crossing"}], "constraints": {"sepration": {}}}, r"constraints\.sepration"),
    (
        {"combinations": [{"family": "crossing"}], "size_classes": {"huge": {"length_m": [500, 900]}}},
        r"size_classes\.huge\.length_m",
    ),
    (
        {"combinations": [{"family": "crossing"}], "difficulties": {"easy": {"range_m": [300, 100]}}},
        r"difficulties\.easy\.range_m",
    ),
    (
        {"combinations": [{"family": "crossing"}], "environment": {"weather": ["clear", "snow"]}},
        r"environment\.weather = 'snow'",
    ),
    ({"combinations": [{"family": "crossing"}], "rig": "missing"}, r"rig = 'missing': not defined under rigs"),
    ({"combinations": [{"family": "crossing"}, {"family": "crossing"}]}, r"combinations\[1\]\.name"),
    ({"combinations": [{"family": "crossing"}], "map": {"type": "lake"}}, r"map\.type = 'lake'"),
]


@pytest.mark.parametrize(("spec", "pattern"), BAD_SPECS)
def test_invalid_specs_name_the_field(spec: dict[str, Any], pattern: str) -> None:
    with pytest.raises(ConfigError, match=pattern):
        load_spec(spec)


def test_spec_file_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="does not exist"):
        load_spec(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("combinations: [\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_spec(bad)
    bad.write_text("- 1\n")
    with pytest.raises(ConfigError, match="mapping"):
        load_spec(bad)
    bad.write_text("combinations:\n  - {family: crossing, targets: [smal]}\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml: invalid spec combinations\[0\]\.targets\[0\] = 'smal'"):
        load_spec(bad)


def test_bundled_specs_validate() -> None:
    names = sorted(p.name for p in SPECS.glob("*.yaml"))
    assert {"island_demo.yaml", "rate_100.yaml", "impossible_port.yaml"} <= set(names)
    for p in SPECS.glob("*.yaml"):
        spec = load_spec(p)
        assert {c.family for c in spec.combinations} <= set(FAMILIES)
    assert sum(c.quota for c in load_spec(SPECS / "rate_100.yaml").combinations) == 100


def _cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="mmusv")
    add_parser(parser.add_subparsers(dest="command", required=True))
    return run(parser.parse_args(argv))


def test_cli_generates_and_exit_status_reflects_quotas(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "tiny.yaml"
    spec.write_text(yaml.safe_dump(dict(SMALL, combinations=[dict(SMALL["combinations"][1], quota=2)])))
    assert _cli(["generate", str(spec), "-o", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    assert "scenarios/s" in text and "head_on_easy_2usv_small" in text
    assert len(list((tmp_path / "out").glob("*.yaml"))) == 2
    rc = _cli(["generate", str(SPECS / "impossible_port.yaml"), "-o", str(tmp_path / "imp"), "--no-progress"])
    assert rc == 1
    assert "quota not met" in capsys.readouterr().out
    with pytest.raises(NotFoundError, match="does not exist and is not a bundled spec"):
        _cli(["generate", str(tmp_path / "missing.yaml"), "-o", str(tmp_path / "x")])


def test_a_rain_rate_is_drawn_for_the_skies_that_rain(tmp_path: Path) -> None:
    """The spec's rain rates go with the weathers that rain: a scenario drawn with a clear sky carries none (a clear
    sky with rain is refused by the scenario), one drawn with rain carries the rate drawn."""
    spec = {
        **SMALL,
        "environment": {**SMALL["environment"], "rain_mm_per_h": [6.0]},
        "combinations": [
            {"family": "head_on", "difficulty": "easy", "cooperating": 1, "targets": ["small"], "quota": 6},
        ],
    }
    generate(spec, tmp_path)
    weathers = []
    for f in sorted(tmp_path.glob("*.yaml")):
        env = yaml.safe_load(f.read_text())["environment"]
        weathers.append(env["weather"])
        assert env.get("rain_mm_per_h") == (6.0 if env["weather"] == "rain" else None), (f.name, env)
    assert set(weathers) == {"clear", "rain"}, weathers
