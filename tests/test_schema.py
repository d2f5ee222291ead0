"""mmusv schema: every file the loader accepts is valid under the JSON Schema (bundled scenarios and specs, the
documented examples, generated scenarios, hand-made variants and mutations of the bundled files), files it refuses
for a typo or a wrong type are invalid, and `mmusv schema` writes the same bytes every time."""

from __future__ import annotations

import contextlib
import copy
import json
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml
from mmusv import cli
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.generate import generate, load_spec
from mmusv.schema import DIALECT, json_schema, schema_text
from mmusv.sensors.config import RIG_PRESETS
from mmusv.world.map_params import PARAM_MODELS
from mmusv.yamlio import read_yaml
from user_assets import library_restored, write_boat

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))
SPECS = sorted((ROOT / "scenarios" / "specs").glob("*.yaml"))
VALIDATORS = {k: jsonschema.Draft202012Validator(json_schema(k)) for k in ("scenario", "spec")}
LOADERS = {"scenario": load_scenario, "spec": load_spec}

VESSEL = {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[0, 0], [100, 0]]}
SCENARIO: dict[str, Any] = {"rigs": {"r": {}}, "vessels": [VESSEL]}
SPEC: dict[str, Any] = {
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 10},
    "combinations": [{"family": "crossing", "targets": ["small"]}],
}


def _errors(kind: str, doc: Any) -> list[str]:
    return [f"{'.'.join(map(str, e.absolute_path))}: {e.message[:200]}" for e in VALIDATORS[kind].iter_errors(doc)]


def _accepted(kind: str, doc: Any) -> bool:
    try:
        LOADERS[kind](copy.deepcopy(doc))
    except ConfigError:
        return False
    return True


def _valid(kind: str, doc: Any, what: str = "") -> None:
    """``doc`` is loaded by the loader (the premise) and is valid under the schema (what is tested)."""
    LOADERS[kind](copy.deepcopy(doc))
    assert _errors(kind, doc) == [], what


def _with(base: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """A deep copy of ``base`` with ``value`` at the dotted ``path`` (integers index lists)."""
    doc = copy.deepcopy(base)
    *parents, last = [int(p) if p.isdigit() else p for p in path.split(".")]
    node: Any = doc
    for p in parents:
        node = node.setdefault(p, {}) if isinstance(node, dict) else node[p]
    node[last] = value
    return doc


# ------------------------------------------------------------------------------------------------ the schemas


@pytest.mark.parametrize("kind", ["scenario", "spec"])
def test_schema_is_a_draft_2020_12_schema_naming_mmusv_and_the_loader(kind: str) -> None:
    s = json_schema(kind)
    jsonschema.Draft202012Validator.check_schema(s)
    assert s["$schema"] == DIALECT == "https://json-schema.org/draft/2020-12/schema"
    assert "mmusv" in s["title"] and "mmusv" in s["description"] and "authority" in s["description"]
    assert s["additionalProperties"] is False
    assert json_schema(kind) == s and json_schema(kind) is not s  # a fresh copy every call
    assert schema_text(kind) == json.dumps(s, indent=2, sort_keys=True, ensure_ascii=False) + "\n"
    refs = set(re.findall(r'"\$ref": "#/\$defs/([^"]+)"', schema_text(kind)))
    assert refs == set(s["$defs"])  # every definition used, none missing


def test_unknown_kind() -> None:
    with pytest.raises(ValueError, match="scenario, spec"):
        json_schema("rig")  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------ accepted files


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_bundled_scenarios_are_valid(path: Path) -> None:
    _valid("scenario", read_yaml(path), path.name)


@pytest.mark.parametrize("path", SPECS, ids=lambda p: p.name)
def test_bundled_specs_are_valid(path: Path) -> None:
    _valid("spec", read_yaml(path), path.name)


def _doc_examples() -> Iterator[tuple[str, str, str]]:
    """(where, kind, YAML) of the examples in the docs: fenced YAML blocks and the ``Example::`` blocks of the
    scenario and spec modules' docstrings."""
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        for m in re.finditer(r"^```ya?ml[^\n]*\n(.*?)^```", doc.read_text(encoding="utf-8"), re.M | re.S):
            yield doc.name, "spec" if "combinations:" in m.group(1) else "scenario", m.group(1)
    for module, kind in (("config.py", "scenario"), ("generate/spec.py", "spec")):
        text = (ROOT / "python" / "mmusv" / module).read_text(encoding="utf-8")
        for m in re.finditer(r"::\n\n((?:    .*\n|\n)+)", text):
            yield module, kind, re.sub(r"(?m)^    ", "", m.group(1))


@contextlib.contextmanager
def _user_assets(paths: list[str], folder: Path) -> Iterator[None]:
    """In ``folder`` (the current folder meanwhile: a scenario given as a dict reads its ``assets:`` from there),
    each asset file of ``paths``, named after its file, a 6 m box; the library as it was afterwards."""
    for rel in paths:
        write_boat(folder / rel, name=Path(rel).stem)
    cwd = Path.cwd()
    os.chdir(folder)
    try:
        with library_restored():
            yield
    finally:
        os.chdir(cwd)


def test_documented_examples_are_valid(tmp_path: Path) -> None:
    seen = 0
    for where, kind, text in _doc_examples():
        doc = yaml.safe_load(text)
        if not isinstance(doc, dict):
            continue
        if kind == "scenario" and "vessels" not in doc:  # a fragment (docs/sea.md): in a whole scenario
            doc = {**SCENARIO, **doc}
        if kind == "scenario" and "assets" in doc:  # the user's own asset files (docs/assets.md): made here
            with _user_assets(doc["assets"], tmp_path / f"assets_{seen}"):
                _valid(kind, doc, where)
        else:
            _valid(kind, doc, where)
        seen += 1
    assert seen >= 5


def test_generated_scenarios_are_valid(tmp_path: Path) -> None:
    spec = {
        **SPEC,
        "name": "tiny",
        "seed": 3,
        "environment": {"weather": ["clear", "fog"], "wave": ["W0", "W1"]},
        "difficulties": {"easy": {"range_m": [60, 200], "extra_targets": 1}},
        "combinations": [{"family": "crossing", "cooperating": 1, "targets": ["small"], "quota": 2}],
    }
    generate(spec, tmp_path)
    files = sorted(tmp_path.glob("*.yaml"))
    assert files
    for p in files:
        _valid("scenario", read_yaml(p), p.name)


SCENARIO_VARIANTS: list[tuple[str, Any]] = [
    ("seed", 3.0),
    ("seed", "3"),
    ("acquisition.frames", 10.0),
    ("acquisition.frames", "10"),
    ("acquisition.frequency_hz", " 2.5 "),
    ("acquisition.frequency_hz", "1e1"),
    ("environment.visibility_m", None),
    ("environment.rain_mm_per_h", None),
    ("environment.sea", None),
    ("environment.sea", {"state": 4.0, "direction_deg": "45"}),
    ("environment.wave", 1.5),
    ("environment.wave", "w1"),
    ("environment.time_of_day", " 16:30 "),
    ("vessels.0.id", " usv_1 "),
    ("vessels.0.rig", None),
    ("vessels.0.speed_mps", 3),
    ("vessels.0.route", [["0", 0], [100.0, "1e2"]]),
    ("name", " my_scenario "),
    ("map.params", None),
    ("map", {"type": "port", "params": None}),
    ("map", {"params": {"n_islands": 2.0, "vegetation": False}}),
    ("map", {"type": "island", "params": {"island_radius_m": ["60", 200], "n_buoys": "3"}}),
    ("map", {"type": "open_sea", "params": {"islet_probability": 0.2, "islet_radius_m": [30, 60]}}),
    ("map", {"type": "port", "params": {"n_moored": 2, "moored_assets": [["tug_32m", 32, 12]]}}),
    ("rigs.r.quality", None),
    ("rigs.r.lidar", None),
    ("rigs.r.lidar", {"channels": 2.0, "elevations_deg": [0, 1], "mount": {"point": None}}),
    ("rigs.r.radar", {"ppi_metres_per_pixel": None, "azimuth_bins": "1024"}),
    ("rigs.r.cameras", [{"name": "a", "resolution": [640.0, 480], "distortion": None, "noise": None}]),
    ("rigs.r.top_view", {"exposure": {"ev100": 12}}),
]
for _preset in RIG_PRESETS:
    SCENARIO_VARIANTS.append(("rigs.r", {"preset": _preset}))
for _quality in ("draft", "standard", "high"):
    SCENARIO_VARIANTS.append(("rigs.r", {"quality": _quality}))
    SCENARIO_VARIANTS.append(("rigs.r", {"preset": "lidar_only", "quality": _quality, "cameras": [{"name": "f"}]}))
for _type in PARAM_MODELS:
    SCENARIO_VARIANTS.append(("map", {"type": _type, "params": {"extent_m": 2000, "n_buoys": 1, "vegetation": True}}))


@pytest.mark.parametrize(("path", "value"), SCENARIO_VARIANTS, ids=lambda v: str(v)[:40])
def test_scenario_variants_the_loader_accepts_are_valid(path: str, value: Any) -> None:
    _valid("scenario", _with(SCENARIO, path, value), f"{path} = {value!r}")


SPEC_VARIANTS: list[tuple[str, Any]] = [
    ("seed", 2.0),
    ("name", " my_spec "),
    ("difficulties", {"easy": {"extra_targets": 2}, "hard": {"extra_targets": [0, "2"], "occluded_share": None}}),
    ("difficulties.easy.extra_classes", None),
    ("combinations.0.quota", "2"),
    ("combinations.0.max_attempts", None),
    ("combinations.0.map", None),
    ("combinations.0.map", {"type": "island", "seed": 2, "params": {"n_islands": 3}}),
    ("combinations.0.family", " crossing "),
    ("constraints.line_of_sight", {"enabled": "yes", "min_share": "0.5"}),
    ("constraints.separation", {"enabled": 0}),
    ("environment", {"weather": ["clear", "fog"], "visibility_m": [None, 800], "wave": "W1"}),
    ("environment", {"sea": [{"state": 3}, {"hs_m": 1.5}], "time_of_day": "08:00"}),
    ("environment", {"rain_mm_per_h": [0, 5], "weather": "rain"}),
    ("rigs", {"usv_standard": {"preset": "lidar_only", "quality": "draft"}}),
    ("rigs", {"usv_standard": {}, "spare": {"anything": 1}}),  # only the rig in use is loaded
    ("usv.speed_mps", ["1.5", 3]),
]


@pytest.mark.parametrize(("path", "value"), SPEC_VARIANTS, ids=lambda v: str(v)[:40])
def test_spec_variants_the_loader_accepts_are_valid(path: str, value: Any) -> None:
    _valid("spec", _with(SPEC, path, value), f"{path} = {value!r}")


# ------------------------------------------------------------------------------------------------ refused files


REFUSED: list[tuple[str, str, Any]] = [
    ("scenario", "vesels", []),
    ("scenario", "vessels.0.sped_mps", 3),
    ("scenario", "vessels.0.speed_mps", "fast"),
    ("scenario", "vessels.0.speed_mps", True),
    ("scenario", "vessels.0.speed_mps", None),
    ("scenario", "vessels.0.role", "boat"),
    ("scenario", "vessels.0.id", "usv 1"),
    ("scenario", "vessels.0.route", [[0, 0]]),
    ("scenario", "vessels.0.route", [[True, 0], [100, 0]]),  # the loader read `true` in a waypoint as 1
    ("scenario", "map.params", {"n_buoys": True}),  # and as a count of buoys
    ("scenario", "acquisition.frames", 10.5),
    ("scenario", "acquisition.frames", "ten"),
    ("scenario", "acquisition.frames", 0),
    ("scenario", "environment.weather", "sunny"),
    ("scenario", "environment.time_of_day", 780),
    ("scenario", "environment.sea", {"state": 3, "height": 2}),
    ("scenario", "map.type", "lake"),
    ("scenario", "map.params", {"n_moored": 2}),  # a port knob on the default island map
    ("scenario", "map", {"type": "port", "params": {"n_islands": 2}}),
    ("scenario", "map.params", {"vegetation": 1}),  # a strict boolean
    ("scenario", "rigs.r.preset", "radar_only"),
    ("scenario", "rigs.r.quality", "best"),
    ("scenario", "rigs.r.lidar", {"chanels": 32}),
    ("scenario", "rigs.r.cameras", [{"name": "a", "resolution": "640x480"}]),
    ("scenario", "rigs.r.cameras", None),
    ("scenario", "rigs", {"bad name": {}}),
    ("scenario", "rigs", None),
    ("spec", "combination", []),
    ("spec", "combinations.0.family", "crosing"),
    ("spec", "combinations.0.quota", "many"),
    ("spec", "combinations.0.quota", True),
    ("spec", "difficulties.easy.extra_targets", [1, 2, 3]),
    ("spec", "difficulties.easy.extra_targets", 17),
    ("spec", "difficulties.easy.extra_targets", "two"),
    ("spec", "environment.wether", "fog"),
    ("spec", "environment.weather", []),
    ("spec", "environment", {"wave": "W1", "sea": {"state": 3}}),
    ("spec", "constraints.separation.enabled", "maybe"),
    ("spec", "constraints.separaton", {}),
    ("spec", "name", ".hidden"),
    ("spec", "rigs.usv_standard", {"lidar": {"chanels": 3}}),
    ("spec", "usv.speed_mps", [True, 3]),
]


@pytest.mark.parametrize(("kind", "path", "value"), REFUSED, ids=lambda v: str(v)[:40])
def test_typos_and_wrong_types_are_invalid(kind: str, path: str, value: Any) -> None:
    doc = _with(SCENARIO if kind == "scenario" else SPEC, path, value)
    assert not _accepted(kind, doc), "the premise: the loader refuses it"
    assert _errors(kind, doc), f"{path} = {value!r}"


def _mutations(value: Any) -> list[Any]:
    if isinstance(value, bool):
        return [1, 0, "yes", "Off", None, 2, "maybe"]
    if isinstance(value, int):
        return [float(value), str(value), f" {value} ", None, True, "x", value + 0.5]
    if isinstance(value, float):
        return [str(value), None, True, "x", f"{value:e}"]
    if isinstance(value, str):
        return [f" {value} ", None, 5, value.upper(), ""]
    if isinstance(value, dict):
        return [None, {**value, "zz_unknown": 1}]
    return [None, []]


def _leaves(doc: Any, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], Any]]:
    if path:
        yield path, doc
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _leaves(v, (*path, str(k)))
    elif isinstance(doc, list):
        for i, v in enumerate(doc[:2]):
            yield from _leaves(v, (*path, str(i)))


@pytest.mark.parametrize(
    ("kind", "path"),
    [("scenario", ROOT / "scenarios" / "port_entry.yaml"), ("spec", ROOT / "scenarios" / "specs" / "port_demo.yaml")],
    ids=lambda v: getattr(v, "name", v),
)
def test_mutations_the_loader_accepts_are_valid(kind: str, path: Path) -> None:
    """Every value of a bundled file replaced by its string, float, padded, upper-case, null, bool... forms: what
    the loader accepts, the schema does."""
    base = read_yaml(path)
    missed, checked = [], 0
    for where, value in _leaves(base):
        for alt in _mutations(value):
            doc = _with(base, ".".join(where), alt)
            if _accepted(kind, doc):
                checked += 1
                if _errors(kind, doc):
                    missed.append(f"{'.'.join(where)} = {alt!r}: {_errors(kind, doc)[0]}")
    assert missed == []
    assert checked > 20


# ------------------------------------------------------------------------------------------------ the command


@pytest.mark.parametrize("kind", ["scenario", "spec"])
def test_cli_prints_and_writes_the_schema(kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["schema", kind]) == 0
    assert capsys.readouterr().out == schema_text(kind)
    out = tmp_path / f"{kind}.schema.json"
    assert cli.main(["schema", kind, "-o", str(out)]) == 0
    first = out.read_bytes()
    assert cli.main(["schema", kind, "-o", str(out)]) == 0
    assert out.read_bytes() == first == schema_text(kind).encode("utf-8")
    assert json.loads(first) == json_schema(kind)
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left


def test_cli_output_dash_is_the_standard_output(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert cli.main(["schema", "spec", "-o", "-"]) == 0  # it wrote a file named "-" and said "wrote -"
    assert capsys.readouterr().out == schema_text("spec") and list(tmp_path.iterdir()) == []
    assert cli.main(["schema", "spec", "-o", ""]) == 2
    assert "give the schema's file name" in capsys.readouterr().err  # not '"." for the current folder'


def test_written_schema_works_as_the_files_schema(tmp_path: Path) -> None:
    """The file from `mmusv schema scenario -o` validates a scenario that names it in its first line."""
    schema_file = tmp_path / "scenario.schema.json"
    assert cli.main(["schema", "scenario", "-o", str(schema_file)]) == 0
    scenario = tmp_path / "port.yaml"
    scenario.write_text(
        "# yaml-language-server: $schema=./scenario.schema.json\n"
        + (ROOT / "scenarios" / "port_entry.yaml").read_text()
    )
    first = scenario.read_text().splitlines()[0]
    named = tmp_path / re.fullmatch(r"# yaml-language-server: \$schema=(\S+)", first).group(1)  # type: ignore[union-attr]
    validator = jsonschema.Draft202012Validator(json.loads(named.read_text()))
    assert list(validator.iter_errors(read_yaml(scenario))) == []
    assert list(validator.iter_errors({**read_yaml(scenario), "vessel": []}))


@pytest.mark.parametrize("bad", ["{dir}", "{dir}/missing/x.json", "{file}/x.json", ""])
def test_cli_bad_output_is_one_line_naming_the_flag(
    bad: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "f").write_text("x")
    assert cli.main(["schema", "scenario", "-o", bad.format(dir=tmp_path, file=tmp_path / "f")]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mmusv: error: -o/--output"), cap.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]


def test_cli_replaces_only_a_schema_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``-o`` over an existing schema of mmusv's (an older one) replaces it; over any other file (``-o
    my_scenario.yaml``: the scenario was replaced by JSON, for good) it refuses in one line and leaves it."""
    old = tmp_path / "scenario.schema.json"
    old.write_text('{"$schema": "https://json-schema.org/draft/2020-12/schema", "title": "mmusv scenario"}')
    assert cli.main(["schema", "scenario", "-o", str(old)]) == 0
    assert old.read_text(encoding="utf-8") == schema_text("scenario")
    capsys.readouterr()
    mine = tmp_path / "my_scenario.yaml"
    mine.write_text("name: mine\n")
    assert cli.main(["schema", "scenario", "-o", str(mine)]) == 2
    err = capsys.readouterr().err
    assert "the file exists and is not a schema mmusv wrote" in err and err.count("\n") == 1, err
    assert mine.read_text() == "name: mine\n"
