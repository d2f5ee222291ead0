"""Numbers only YAML 1.1 has (octal ``017``, base 60 ``1:20``, binary ``0b11``, hexadecimal ``0x1F``) are refused by
the one YAML reader (mmusv.yamlio), naming the file, the field, its line and column, the text as written, what
YAML 1.1 reads it as and what to write instead: ``seed: 017`` ran seed 15, ``frames: 1:0`` recorded 60 frames and a
waypoint ``-1:00`` sailed to x = -60, without a word. Decimal numbers read as before."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.generate import load_spec
from mmusv.yamlio import parse_yaml

SCENARIO = """\
name: base
seed: 7
map: {type: port, seed: 3}
environment: {time_of_day: "16:30"}
acquisition: {frequency_hz: 5, frames: 2}
vessels:
  - {id: usv_1, role: usv, asset: usv_wamv, speed_mps: 2.5, route: [[-170, -110], [-170, -30]]}
"""

SPEC = """\
name: gbase
seed: 9
map: {type: port, seed: 3}
acquisition: {frequency_hz: 2, frames: 4}
environment: {time_of_day: ["07:15", "19:30"]}
combinations:
  - {family: crossing, difficulty: easy, cooperating: 1, targets: [small], quota: 1}
"""


@pytest.mark.parametrize(
    ("line", "written", "field", "kind", "value", "instead"),
    [
        ("seed: 017", "017", "seed", "an octal", "15", "without the leading zero (17)"),
        ("seed: -017", "-017", "seed", "an octal", "-15", "without the leading zero (-17)"),
        ("seed: 0_17", "0_17", "seed", "an octal", "15", "without the leading zero (17)"),
        ("seed: 1:20", "1:20", "seed", "a base-60", "80", "in decimal (80)"),
        ("frames: 1:0", "1:0", "frames", "a base-60", "60", "in decimal (60)"),
        ("frames: 0b11", "0b11", "frames", "a binary", "3", "in decimal (3)"),
        ("seed: 0x1F", "0x1F", "seed", "a hexadecimal", "31", "in decimal (31)"),
        ("speed_mps: 1:20.5", "1:20.5", "speed_mps", "a base-60", "80.5", "in decimal (80.5)"),
        ("route: [[0, 0], [-1:00, 5]]", "-1:00", "route[1][0]", "a base-60", "-60", "in decimal (-60)"),
    ],
)
def test_a_yaml11_number_is_refused_saying_what_to_write(
    line: str, written: str, field: str, kind: str, value: str, instead: str
) -> None:
    with pytest.raises(ConfigError) as err:
        parse_yaml(f"name: x\n{line}\n", "f.yaml")
    col = line.index(written) + 1
    assert str(err.value) == (
        f"f.yaml: {field} = {written} at line 2, column {col} is {kind} number in YAML 1.1, which reads it as "
        f'{value}; write the number {instead} or, if it is text, put it in quotes ("{written}")'
    )


def test_a_scenario_file_names_the_file_line_and_field(tmp_path: Path) -> None:
    f = tmp_path / "s.yaml"
    f.write_text(SCENARIO.replace("[-170, -30]", "[-1:00, -30]"), encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(f))}: vessels\[0\]\.route\[1\]\[0\] = -1:00 at line 7, "):
        load_scenario(f)
    f.write_text(SCENARIO.replace("frames: 2", "frames: 1:0"), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"acquisition\.frames = 1:0 at line 5, column 40 is a base-60 number"):
        load_scenario(f)


def test_a_spec_file_is_refused_too(tmp_path: Path) -> None:
    f = tmp_path / "spec.yaml"
    f.write_text(SPEC.replace("seed: 9", "seed: 017"), encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(f))}: seed = 017 at line 2, column 7 is an octal"):
        load_spec(f)
    f.write_text(SPEC.replace('["07:15", "19:30"]', '["07:15", 19:30]'), encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_spec(f)
    assert (
        'environment.time_of_day[1] = 19:30 at line 5, column 38: use 24-hour "HH:MM" in quotes, e.g. "19:30"'
        in str(err.value)
    )


def test_a_key_and_an_anchor_are_named_where_written() -> None:
    with pytest.raises(ConfigError, match=r"the key 017 of rigs at line 1, column 8 is an octal number"):
        parse_yaml("rigs: {017: {}}", "f.yaml")
    with pytest.raises(ConfigError, match=r"base\.seed = 017 at line 1, column 17 is an octal number"):
        parse_yaml("base: &b {seed: 017}\nother: *b\nmerged: {<<: *b}\n", "f.yaml")


def test_decimal_numbers_read_as_before() -> None:
    data = parse_yaml(
        "a: [0, -0, 7, -17, +5, 1_000, 0.5, -1.5, 017.5, .5, 1.0e+3, 1e3, .inf, -.inf, .nan]\n"
        "b: ['017', \"1:20\", 0:30, 0o17, 08, 12:30:x, 0x, 1:2:3.x]\n",
        "f.yaml",
    )
    assert data["a"][:-1] == [0, 0, 7, -17, 5, 1000, 0.5, -1.5, 17.5, 0.5, 1000.0, "1e3", math.inf, -math.inf]
    assert math.isnan(data["a"][-1])
    assert data["b"] == ["017", "1:20", "0:30", "0o17", "08", "12:30:x", "0x", "1:2:3.x"]  # text in YAML 1.1 too


def test_mmusvs_own_files_are_read_by_the_fast_parser_with_the_same_refusal() -> None:
    with pytest.raises(ConfigError, match=r"f\.yaml: x = 017 at line 1, column 4 is an octal number"):
        parse_yaml("x: 017", "f.yaml", trusted=True)
    assert parse_yaml("x: [17, 0.5]", "f.yaml", trusted=True) == {"x": [17, 0.5]}
