"""YAML merge keys (``<<``) that copy without bound: a few hundred bytes of merges of merges made PyYAML copy
millions of entries before the scenario's fields were read (a minute and gigabytes, four times more for each
level), though the mapping they make has one key; the alias-bomb limit counted only the values of the finished
document. Now the entries merge keys copy are counted as they are copied and refused past the limit, naming the
file and the line."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.yamlio import MAX_YAML_VALUES, parse_yaml


def _merge_bomb(levels: int) -> str:
    """A scenario whose anchors each merge the one before four times: 4**levels entries copied for one key."""
    lines = ["a0: &a0 {k: 1}"]
    lines += [f"a{i}: &a{i} {{<<: [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}]}}" for i in range(1, levels)]
    return "\n".join(["name: t", *lines, "vessels: [{id: u, asset: usv_wamv, route: [[0, 0], [50, 0]]}]"]) + "\n"


def test_merges_of_merges_are_refused_naming_the_file_and_line(tmp_path: Path) -> None:
    f = tmp_path / "bomb.yaml"
    f.write_text(_merge_bomb(12), encoding="utf-8")  # 4**11 = 4 million entries copied: 4 s and 100 MB before
    started = time.monotonic()
    with pytest.raises(ConfigError) as info:
        load_scenario(f)
    msg = str(info.value)
    assert str(f) in msg and "merge keys (<<)" in msg and f"{MAX_YAML_VALUES:,} entries" in msg, msg
    assert re.search(r"at line \d+ copy", msg), msg
    assert time.monotonic() - started < 3.0


def test_a_deep_merge_bomb_fails_at_once_on_the_command_line(tmp_path: Path) -> None:
    f = tmp_path / "bomb.yaml"
    f.write_text(_merge_bomb(40), encoding="utf-8")  # 4**39 entries: never finished before
    done = subprocess.run(
        [sys.executable, "-m", "mmusv", "run", str(f), "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr
    assert "merge keys (<<)" in done.stderr and str(f) in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_merges_read_as_yaml_reads_them() -> None:
    text = """\
a: &a {x: 1, y: 1}
b: &b {x: 2, z: 2}
c: {<<: [*a, *b], y: 3}
d: {<<: *b}
e: &e {<<: *a, w: 0}
f: {<<: [*e, *b]}
"""
    assert parse_yaml(text, "m.yaml") == yaml.safe_load(text)


def test_a_merge_of_a_scalar_is_refused_as_before() -> None:
    with pytest.raises(ConfigError, match=r"m\.yaml: not valid YAML at line 1.*expected a mapping"):
        parse_yaml("a: {<<: 3}\n", "m.yaml")
    with pytest.raises(ConfigError, match=r"m\.yaml: not valid YAML at line 1.*expected a mapping for merging"):
        parse_yaml("a: {<<: [{x: 1}, 3]}\n", "m.yaml")


# A sequence or a scalar tagged !!map reached the duplicate-key check, which unpacked its items as pairs: a bare
# TypeError traceback for `vessels: !!map [1, 2]`, and for `name: !!map x` "not valid YAML: not enough values to
# unpack (expected 2, got 1); no value of a scenario needs one". Both are said as PyYAML says them.


@pytest.mark.parametrize(
    ("text", "found"),
    [("name: x\nvessels: !!map [1, 2]\n", "sequence"), ("name: !!map x\n", "scalar"), ("a: !!map\n", "scalar")],
)
def test_a_map_tag_on_another_node_is_refused_naming_its_line(tmp_path: Path, text: str, found: str) -> None:
    f = tmp_path / "tagged.yaml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_scenario(f)
    msg = str(info.value)
    assert msg.startswith(f"{f}: not valid YAML at line "), msg
    assert f"expected a mapping node, but found {found}" in msg, msg


def test_a_map_tag_on_a_mapping_is_read() -> None:
    assert parse_yaml("a: !!map {b: 1}\nc: !!map\n  d: [1]\n", "m.yaml") == {"a": {"b": 1}, "c": {"d": [1]}}
