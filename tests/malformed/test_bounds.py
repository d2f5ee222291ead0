"""Values a scenario file can hold that once got past validation (a fuzzing round of 2026-11-30): overflowing
sensor arithmetic, hangs in the route checks, a Rust panic, booleans read as numbers, names of dots, unquoted
times, YAML alias bombs and 5,000-digit integers. Each is refused by loading, with a ConfigError naming the file
and the field."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.yamlio import MAX_YAML_VALUES

BASE: dict[str, Any] = {
    "name": "t",
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 10},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 3, "route": [[-300, 0], [300, 0]]},
        {"id": "t1", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[-100, 20], [-400, 25]]},
    ],
}


def _with(path: str, value: Any) -> dict[str, Any]:
    """BASE with the value at the dotted ``path`` (list indices as numbers) set."""
    doc = yaml.safe_load(yaml.safe_dump(BASE))
    *head, last = [int(p) if p.isdigit() else p for p in path.split(".")]
    node = doc
    for p in head:
        node = node[p] if not isinstance(node, dict) or p in node else node.setdefault(p, {})
    node[last] = value
    return doc


def _refused(doc: dict[str, Any], tmp_path: Path) -> str:
    return _yaml_refused(yaml.safe_dump(doc), tmp_path)


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("rigs.r.lidar.rotation_hz", 1e-320, "rigs.r.lidar.rotation_hz"),  # was OverflowError (round of inf)
        ("rigs.r.lidar.points_per_second", 1e308, "rigs.r.lidar.points_per_second"),
        ("rigs.r.lidar.points_per_second", 1, "columns per sweep"),  # was clamped to one column without a word
        ("rigs.r.radar.range_resolution_m", 1e-320, "rigs.r.radar.range_resolution_m"),  # was OverflowError
        ("rigs.r.radar.ppi_metres_per_pixel", 1e308, "rigs.r.radar.ppi_metres_per_pixel"),  # failed mid-recording
        ("rigs.r.top_view.altitude_m", 1e308, "rigs.r.top_view.altitude_m"),
        ("rigs.r.top_view.metres_per_pixel", 1e308, "rigs.r.top_view.metres_per_pixel"),
        ("acquisition.frequency_hz", 1e-6, "acquisition.frequency_hz"),  # the route checks hung
        ("vessels.1.speed_mps", 1e6, "vessels[1].speed_mps"),  # hung; 1e308 gave a pose error naming no field
        ("vessels.1.route", [[-1e12, 100], [1e12, 100]], "vessels[1].route"),  # 7 TiB allocation
        ("vessels.1.route", [[-1e308, 100], [1e308, 100]], "vessels[1].route"),  # a Rust panic
        ("vessels.1.z_base_m", -1000, "vessels[1].z_base_m"),  # a hull 1 km under water, silently
        ("environment.rain_mm_per_h", 1000, "environment.rain_mm_per_h"),  # the radar refused it mid-recording
        ("environment.visibility_m", 1e-300, "environment.visibility_m"),  # reported as env.fog_extinction_per_m
        ("acquisition.frames", True, "acquisition.frames"),  # read as 1 frame
        ("vessels.1.speed_mps", True, "vessels[1].speed_mps"),  # read as 1 m/s
        ("environment.wave", True, "environment.wave"),  # read as a 1 m sea
        ("environment.wave", 1e9, "environment.wave"),  # the paper's formula took a 1e9 m sea; physical: named hs_m
        ("map.seed", 10**30, "map.seed"),  # accepted, as the scenario's own seed was not (< 2**63)
        ("name", "..", "name"),  # wrote `...mcap`; exports then failed
        ("name", ".hidden", "name"),
    ],
)
def test_out_of_range_values_are_refused_naming_the_field(path: str, value: Any, field: str, tmp_path: Path) -> None:
    msg = _refused(_with(path, value), tmp_path)
    assert field in msg, msg


def test_camera_settings_out_of_range_are_refused(tmp_path: Path) -> None:
    cams = [{"name": "front", "hfov_deg": 1e-300}]
    assert "rigs.r.cameras[0].hfov_deg" in _refused(_with("rigs.r.cameras", cams), tmp_path)
    for key, value in (("full_well_e", 1e-300), ("read_noise_e", 1e308)):
        cams = [{"name": "front", "noise": {key: value}}]
        assert f"rigs.r.cameras[0].noise.{key}" in _refused(_with("rigs.r.cameras", cams), tmp_path)


@pytest.mark.parametrize("direction", [1e300, -721.0, float("nan")])
def test_a_sea_direction_past_a_turn_is_refused(direction: float, tmp_path: Path) -> None:
    """The malformed-input review's: ``environment.sea.direction_deg: 1e300`` was taken (its sine and cosine then
    any values at all), as a mount's ``rpy_deg`` no longer is."""
    doc = yaml.safe_load(yaml.safe_dump(BASE))
    doc["environment"] = {"sea": {"state": 3, "direction_deg": direction}}
    assert "environment.sea.direction_deg" in _refused(doc, tmp_path)


def test_the_values_at_the_bounds_still_load() -> None:
    doc = _with("vessels.1.speed_mps", 100.0)
    doc["vessels"][1]["route"] = [[-1e6, 100], [1e6, 100]]
    doc["environment"] = {"weather": "rain", "rain_mm_per_h": 500, "visibility_m": 1, "time_of_day": "13:00"}
    doc["acquisition"]["frequency_hz"] = 0.01
    load_scenario(doc)
    doc["environment"] = {"sea": {"state": 3, "direction_deg": -360}}
    doc["map"]["seed"] = 2**63 - 1
    load_scenario(doc)
    doc["environment"]["sea"]["direction_deg"] = 360
    load_scenario(doc)


def _yaml_refused(text: str, tmp_path: Path) -> str:
    f = tmp_path / "case.yaml"
    f.write_text(textwrap.dedent(text), encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_scenario(f)
    msg = str(err.value)
    assert msg.startswith(f"{f}:"), msg
    return msg


def test_an_unquoted_time_is_explained(tmp_path: Path) -> None:
    text = yaml.safe_dump(BASE) + "environment: {time_of_day: 13:00}\n"
    msg = _yaml_refused(text, tmp_path)
    assert "environment.time_of_day = 13:00 at line" in msg and "in quotes" in msg, msg
    assert "reads it as the number 780" in msg, msg


def test_pydantic_step_names_stay_out_of_field_paths(tmp_path: Path) -> None:
    msg = _refused(_with("environment.wave", float("nan")), tmp_path)
    assert "constrained-str" not in msg and "environment.wave" in msg, msg


def test_a_huge_value_is_shown_shortened(tmp_path: Path) -> None:
    msg = _refused(_with("name", "ab" * 1_000_000), tmp_path)
    assert "name" in msg and len(msg) < 600, len(msg)


def test_an_integer_of_5000_digits_is_refused(tmp_path: Path) -> None:
    msg = _yaml_refused(yaml.safe_dump(BASE).replace("name: t", "name: t\nseed: " + "9" * 5000), tmp_path)
    assert "4,300 digits" in msg, msg


def test_an_alias_bomb_is_refused_before_it_is_walked(tmp_path: Path) -> None:
    lines = ["a: &a [x, x, x, x, x, x, x, x, x]"]
    for prev, name in zip("abcdefgh", "bcdefghi", strict=True):
        lines.append(f"{name}: &{name} [" + ", ".join([f"*{prev}"] * 9) + "]")
    lines.append("vessels: *i")
    msg = _yaml_refused("\n".join(lines) + "\n", tmp_path)
    assert f"{MAX_YAML_VALUES:,} values" in msg and "aliases" in msg, msg


def test_a_plain_document_past_the_value_limit_is_not_blamed_on_aliases(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mmusv.yamlio

    monkeypatch.setattr(mmusv.yamlio, "MAX_YAML_VALUES", 2000)  # the real limit takes seconds to reach
    route = "[" + ", ".join(f"[{k}, 0]" for k in range(1200)) + "]"
    msg = _yaml_refused(f"name: t\nvessels: [{{id: a, route: {route}}}]\n", tmp_path)
    assert "more than 2,000 values" in msg and "aliases" not in msg and "split it" in msg, msg


def test_a_merge_key_may_be_overridden(tmp_path: Path) -> None:
    text = """\
    name: t
    map: {type: open_sea, seed: 2}
    acquisition: {frequency_hz: 5, frames: 10}
    rigs: {r: {preset: lidar_only}}
    vessels:
      - &u {id: u, role: usv, asset: usv_wamv, rig: r, speed_mps: 3, route: [[-300, 0], [300, 0]]}
      - {<<: *u, id: u2, route: [[-300, 60], [300, 60]]}
    """
    f = tmp_path / "merge.yaml"
    f.write_text(textwrap.dedent(text), encoding="utf-8")
    s = load_scenario(f)
    assert [v.id for v in s.vessels] == ["u", "u2"] and s.vessels[1].route[0] == (-300.0, 60.0)
    # A key written twice in the mapping itself is still refused.
    f.write_text(textwrap.dedent(text).replace("id: u2,", "id: u2, id: u3,"), encoding="utf-8")
    with pytest.raises(ConfigError, match="duplicate key 'id'"):
        load_scenario(f)


@pytest.mark.parametrize(
    ("environment", "said"),
    [
        ({"wave": "W3", "sea": {"hs_m": 1.0}}, "not both"),  # the sea's 1 m decided; W3 was dropped silently
        ({"motion": "paper", "sea": {"state": 5}}, "motion: physical"),  # the flat sea of the paper; `sea` unused
    ],
)
def test_a_sea_given_twice_is_refused(environment: dict[str, Any], said: str, tmp_path: Path) -> None:
    msg = _refused(_with("environment", environment), tmp_path)
    assert "environment" in msg and said in msg, msg
    alone = load_scenario(_with("environment", {"sea": {"hs_m": 1.0}}))  # either alone loads
    # A resolved scenario written out (a run folder's scenario.yaml) holds the default `wave: W0` beside its sea.
    assert load_scenario(yaml.safe_load(yaml.safe_dump(alone.model_dump(mode="json")))) == alone
    load_scenario(_with("environment", {"wave": "W3", "motion": "paper"}))


@pytest.mark.parametrize("name", [" ", "", "a b", "usv\nrig", "x" * 65, "rig.1"])
def test_rig_names_are_refused_unless_plain(name: str, tmp_path: Path) -> None:
    """A rig name is checked as written: " " and "" used to become one rig named '' (two rigs merged, silently)."""
    doc = _with("name", "t")
    doc["rigs"] = {name: {}, "r": doc["rigs"]["r"]}
    msg = _refused(doc, tmp_path)
    assert "rig name" in msg and "letters, digits" in msg, msg


@pytest.mark.parametrize(
    ("weather", "refused"), [("clear", True), ("rain", False), ("overcast", False), ("fog", False)]
)
def test_rain_needs_a_sky_that_rains(weather: str, refused: bool, tmp_path: Path) -> None:
    """A rain rate under a clear sky was taken as given (rain falling from a cloudless sky); 0 mm/h is fine."""
    doc = _with("name", "t")
    doc["environment"] = {"weather": weather, "rain_mm_per_h": 4.0}
    if refused:
        msg = _refused(doc, tmp_path)
        assert "rain_mm_per_h = 4 with weather: clear" in msg, msg
    else:
        load_scenario(doc)
    load_scenario({**doc, "environment": {"weather": weather, "rain_mm_per_h": 0.0}})
