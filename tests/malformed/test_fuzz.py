"""Property tests: mutations of every bundled scenario and spec (wrong types, NaN and inf, huge and negative
values, dropped and duplicated keys, bad encodings) either load or raise an MmusvError naming the file; never
another exception. Mutated vessel catalogue entries build or raise an AssetSpecError naming the field. 200
examples per target in CI; set MMUSV_FUZZ_EXAMPLES (e.g. 5000) for the long run, which the ``slow`` marker also
selects at 2000."""

from __future__ import annotations

import copy
import math
import os
import resource
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mmusv.config import load_scenario
from mmusv.errors import MmusvError
from mmusv.generate.spec import load_spec
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.vessels import load_asset_file

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))
SPECS = sorted((ROOT / "scenarios/specs").glob("*.yaml"))
CATALOGUE = yaml.safe_load((ROOT / "python/mmusv/world/vessel_catalog.yaml").read_text(encoding="utf-8"))["vessels"]
EXAMPLES = int(os.environ.get("MMUSV_FUZZ_EXAMPLES", "200"))

ODD_VALUES = [
    None,
    "",
    "x",
    "7:30 pm",
    -1,
    0,
    -1e12,
    1e12,
    10**30,
    math.nan,
    math.inf,
    -math.inf,
    True,
    [],
    {},
    [1, 2, 3],
    {"a": 1},
    "W9",
    1e-9,
    -0.0,
]


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _paths(v, (*prefix, i))
    return out


def _mutate(data: Any, path: tuple[Any, ...], op: str, value: Any) -> Any:
    parent = data
    for p in path[:-1]:
        parent = parent[p]
    key = path[-1]
    if op == "drop":
        del parent[key]
    elif op == "replace":
        parent[key] = value
    elif op == "scale":
        v = parent[key]
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            parent[key] = v * value if isinstance(value, (int, float)) and not isinstance(value, bool) else value
        else:
            parent[key] = value
    return data


@st.composite
def mutations(draw: st.DrawFn, files: list[Path]) -> tuple[Path, bytes]:
    f = draw(st.sampled_from(files))
    text = f.read_text(encoding="utf-8")
    kind = draw(st.sampled_from(["value", "value", "value", "duplicate", "encoding", "truncate"]))
    if kind == "encoding":
        enc = draw(st.sampled_from(["utf-16", "latin-1", "garbage"]))
        if enc == "garbage":
            return f, draw(st.binary(min_size=1, max_size=200))
        return f, (text + "\n# é ü\n").encode(enc)
    if kind == "truncate":
        n = draw(st.integers(min_value=0, max_value=len(text)))
        return f, text[:n].encode()
    if kind == "duplicate":
        lines = [ln for ln in text.splitlines() if ln and not ln.startswith((" ", "#", "-"))]
        line = draw(st.sampled_from(lines))
        return f, (text + "\n" + line + "\n").encode()
    data = yaml.safe_load(text)
    paths = _paths(data)
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        paths = _paths(data)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        op = draw(st.sampled_from(["drop", "replace", "scale"]))
        value = copy.deepcopy(draw(st.sampled_from(ODD_VALUES)))  # never mutate the shared examples
        data = _mutate(data, path, op, value)
    return f, yaml.safe_dump(data, allow_unicode=True).encode()


def _check(tmp: Path, case: tuple[Path, bytes], loader: Any) -> None:
    src, raw = case
    f = tmp / f"mutated_{src.stem}.yaml"
    f.write_bytes(raw)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    resource.setrlimit(resource.RLIMIT_AS, (8 << 30, hard))  # a validation may not try to allocate gigabytes
    try:
        loader(f)
    except MmusvError as exc:
        msg = str(exc)
        assert f.name in msg, f"error does not name the file: {msg}"
        assert "\n" not in msg.strip() and "Traceback" not in msg
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


SETTINGS = settings(
    max_examples=EXAMPLES,
    deadline=5000,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@SETTINGS
@given(case=mutations(SCENARIOS))
def test_mutated_scenarios_load_or_fail_cleanly(tmp_path: Path, case: tuple[Path, bytes]) -> None:
    _check(tmp_path, case, load_scenario)


@SETTINGS
@given(case=mutations(SPECS))
def test_mutated_specs_load_or_fail_cleanly(tmp_path: Path, case: tuple[Path, bytes]) -> None:
    _check(tmp_path, case, load_spec)


@pytest.mark.slow
@settings(
    max_examples=max(EXAMPLES, 2000),
    deadline=5000,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(case=mutations(SCENARIOS + SPECS))
def test_many_mutations(tmp_path: Path, case: tuple[Path, bytes]) -> None:
    _check(tmp_path, case, load_spec if case[0].parent.name == "specs" else load_scenario)


@st.composite
def asset_mutations(draw: st.DrawFn) -> dict[str, Any]:
    entry = copy.deepcopy(draw(st.sampled_from(CATALOGUE)))
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        paths = _paths(entry)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        op = draw(st.sampled_from(["drop", "replace", "scale", "unknown"]))
        value = copy.deepcopy(draw(st.sampled_from(ODD_VALUES)))
        if op == "unknown":  # a key the schema does not know, beside the chosen one
            parent = entry
            for p in path[:-1]:
                parent = parent[p]
            if isinstance(parent, dict):
                parent["colour"] = value
            continue
        entry = _mutate(entry, path, op, value)
    return entry


@SETTINGS
@given(entry=asset_mutations())
def test_mutated_vessel_assets_build_or_name_the_field(entry: dict[str, Any]) -> None:
    try:
        load_asset_file(entry)
    except AssetSpecError as exc:
        msg = str(exc)
        assert msg.startswith(f"{exc.field}: ") and "\n" not in msg, msg
        # the path starts at the asset's name, or at the entry's root when the name itself is unusable
        assert exc.field.startswith((f"{entry.get('name')}.", "name", "hull", "parts", "mesh", "colour")), msg
