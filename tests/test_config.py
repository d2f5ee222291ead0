"""Scenario schema: defaults, validation errors that name the field, and the bundled scenarios."""

from __future__ import annotations

from pathlib import Path

import mmusv
import pytest
from mmusv.config import load_scenario, scenario_hash

ROOT = Path(__file__).resolve().parents[1]


def minimal(**vessel: object) -> dict[str, object]:
    v: dict[str, object] = {
        "id": "usv_1",
        "role": "usv",
        "asset": "usv_wamv",
        "speed_mps": 2.0,
        "route": [[0, 0], [100, 0]],
    }
    v.update(vessel)
    return {"vessels": [v]}


def test_defaults_fill_everything_a_newcomer_omits() -> None:
    s = load_scenario(minimal())
    assert s.acquisition.frequency_hz == 5.0 and s.acquisition.frames == 100
    assert s.environment.wave == "W0" and s.map.type == "island"
    assert s.usvs[0].id == "usv_1"


@pytest.mark.parametrize(
    ("vessel", "field", "fragment"),
    [
        ({"asset": "container_ship_3000m"}, "vessels[0].asset", "did you mean"),
        ({"route": [[0, 0]]}, "vessels[0].route", "at least 2"),
        ({"speed_mps": -1.0}, "vessels[0].speed_mps", "greater than or equal to 0"),
        ({"end": "bounce"}, "vessels[0].end", "'stop', 'loop' or 'ping_pong'"),
        ({"colour": "red"}, "vessels[0].colour", "Extra inputs"),
    ],
)
def test_bad_vessel_fields_are_named(vessel: dict[str, object], field: str, fragment: str) -> None:
    with pytest.raises(mmusv.ConfigError) as info:
        load_scenario(minimal(**vessel))
    assert field in str(info.value)
    assert fragment in str(info.value)


def test_a_hull_sunk_whole_is_refused() -> None:
    # z_base_m lowers a vessel's frame: a target 30 m down was seen by no sensor and still got 3D and 2D boxes. The
    # whole hull under the water is an error naming the field and how far it may go; lifting stays allowed (a
    # controlled set-up: tests/export/test_contrast.py lifts a boat 30 m against the horizon sky).
    from mmusv.world.vessels import get_asset

    hi = float(get_asset("usv_wamv").bbox[1, 2])
    for z in (-30.0, -hi - 0.01):
        with pytest.raises(mmusv.ConfigError) as info:
            load_scenario(minimal(z_base_m=z))
        msg = str(info.value)
        assert "vessels[0].z_base_m" in msg and "below the still water" in msg and f"above {-hi:.2f} m" in msg, msg
    assert load_scenario(minimal(z_base_m=-0.3)).vessels[0].z_base_m == -0.3
    assert load_scenario(minimal(z_base_m=30.0)).vessels[0].z_base_m == 30.0


def test_unknown_wave_setting_is_rejected_with_allowed_values() -> None:
    data = minimal()
    data["environment"] = {"wave": "W7"}
    with pytest.raises(mmusv.ConfigError) as info:
        load_scenario(data)
    assert "environment.wave" in str(info.value) and "W0, W1, W2, W3" in str(info.value)


def test_duplicate_ids_and_missing_rig() -> None:
    data = minimal()
    data["vessels"] = [data["vessels"][0], data["vessels"][0]]  # type: ignore[index]
    with pytest.raises(mmusv.ConfigError, match="used twice"):
        load_scenario(data)
    with pytest.raises(mmusv.ConfigError, match="rig 'nope'"):
        load_scenario(minimal(rig="nope"))


def test_ids_must_differ_beyond_case() -> None:
    """Exports name folders after ids: ``usv_1`` and ``USV_1`` would be one folder on macOS and Windows."""
    data = minimal()
    data["vessels"].append({**data["vessels"][0], "id": "USV_1", "route": [[0, 50], [100, 50]]})  # type: ignore[attr-defined]
    with pytest.raises(mmusv.ConfigError) as info:
        load_scenario(data)
    msg = str(info.value)
    assert "vessels[1].id = 'USV_1' differs from vessels[0].id = 'usv_1' only in case" in msg, msg
    data = minimal()
    data["vessels"] = [data["vessels"][0], data["vessels"][0]]  # type: ignore[index]
    with pytest.raises(mmusv.ConfigError, match=r"vessels\[1\]\.id = 'usv_1' is used twice \(vessels\[0\]\)"):
        load_scenario(data)


def test_missing_file_and_bad_yaml(tmp_path: Path) -> None:
    with pytest.raises(mmusv.ConfigError, match="does not exist"):
        load_scenario(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("vessels: [\n")
    with pytest.raises(mmusv.ConfigError, match="not valid YAML"):
        load_scenario(bad)


def test_bundled_scenarios_validate_and_hash_is_stable() -> None:
    files = sorted((ROOT / "scenarios").glob("*.yaml"))
    assert files
    for f in files:
        s = load_scenario(f)
        assert scenario_hash(s) == scenario_hash(load_scenario(f))
    a = load_scenario(files[0])
    assert scenario_hash(a) != scenario_hash(a.with_wave("W3"))


@pytest.mark.parametrize(
    ("map_cfg", "path", "fragment"),
    [
        ({"type": "port", "params": {"n_moored": -1}}, "map.params.n_moored", "greater than or equal to 0"),
        ({"type": "island", "params": {"n_moored": 3}}, "map.params.n_moored", "Extra inputs"),
        ({"type": "port", "params": {"entrance_width_m": 5000}}, "map.params.entrance_width_m", "in [60, 860]"),
        ({"type": "open_sea", "params": {"islet_radius_m": [50, 20]}}, "map.params.islet_radius_m", "a <= b"),
        ({"type": "island", "params": {"extent_m": 20000, "grid_m": 5}}, "map.params.grid_m", "extent_m / 2000 = 10"),
        ({"type": "port", "params": {"vegetation": "yes"}}, "map.params.vegetation", "boolean"),
    ],
)
def test_map_params_are_checked_when_the_scenario_loads(map_cfg: dict[str, object], path: str, fragment: str) -> None:
    """``map.params`` is the parameter model of ``map.type``, validated with the scenario (no world is built)."""
    with pytest.raises(mmusv.ConfigError) as info:
        load_scenario({**minimal(), "map": map_cfg})
    msg = str(info.value)
    assert f"invalid config {path} = " in msg and fragment in msg, msg


def test_map_params_are_typed_by_map_type_and_dump_as_given() -> None:
    from mmusv.world.map_params import IslandParams, OpenSeaParams, PortParams

    port = load_scenario({**minimal(), "map": {"type": "port", "seed": 3, "params": {"n_moored": 2}}})
    assert isinstance(port.map.params, PortParams) and port.map.params.n_moored == 2
    assert port.map.params.coast_offset_m == 250.0  # resolved from extent_m = 2000
    assert port.model_dump(mode="json")["map"] == {"type": "port", "seed": 3, "params": {"n_moored": 2}}
    assert port.map.param_values() == {"n_moored": 2}
    assert load_scenario(port.model_dump(mode="json")) == port  # the dump loads back to the same scenario
    sea = load_scenario({**minimal(), "map": {"type": "open_sea"}})
    assert isinstance(sea.map.params, OpenSeaParams) and sea.map.params.extent_m == 4000.0
    assert sea.model_dump()["map"]["params"] == {}
    assert isinstance(load_scenario(minimal()).map.params, IslandParams)


def test_a_bad_wave_is_reported_with_the_other_errors() -> None:
    """The wave's check raised the core's ConfigError inside pydantic, which stopped the validation there: a
    scenario with a bad wave and a bad frame count said only the wave."""
    import yaml
    from mmusv.errors import ConfigError

    sc = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = -3
    for wave in ("W9", 30, True):
        sc["environment"]["wave"] = wave
        with pytest.raises(ConfigError) as info:
            load_scenario(sc)
        msg = str(info.value)
        assert "environment.wave = " in msg and "acquisition.frames = -3" in msg, msg
        assert msg.count("environment.wave") == 1, msg


def test_the_cross_checks_report_every_problem_at_once() -> None:
    """The scenario's and the environment's cross-checks stopped at their first problem: a user fixing a file met
    them one per round (noted by the editor round)."""
    import yaml
    from mmusv.errors import ConfigError

    sc = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios/port_entry.yaml").read_text())
    sc["vessels"][1]["id"] = sc["vessels"][0]["id"]  # a duplicate id
    sc["vessels"][2]["rig"] = "nope"  # an unknown rig
    sc["vessels"][3]["rig"] = "usv_standard"  # a rig on a target
    with pytest.raises(ConfigError) as info:
        load_scenario(sc)
    msg = str(info.value)
    assert "is used twice" in msg and "names rig 'nope'" in msg and "only instrumented vessels" in msg, msg
    sc = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios/port_entry.yaml").read_text())
    sc["environment"] = {"weather": "clear", "rain_mm_per_h": 2, "sea": {"state": 4}, "motion": "paper"}
    with pytest.raises(ConfigError) as info:
        load_scenario(sc)
    msg = str(info.value)
    assert "a clear sky does not rain" in msg and "which `motion: paper` leaves out" in msg, msg


def test_time_of_day_takes_ascii_digits_only() -> None:
    """The loader read "١٢:٠٠" (Arabic-Indic digits, which ``\\d`` matches) as noon; the schema's pattern refuses it."""
    data = minimal()
    data["environment"] = {"time_of_day": "١٢:٠٠"}
    with pytest.raises(mmusv.ConfigError, match=r"environment\.time_of_day = .*HH:MM"):
        load_scenario(data)


@pytest.mark.parametrize(
    ("sea", "said"),
    [({}, "neither was given"), ({"tp_s": 8}, "neither was given"), ({"state": 4, "hs_m": 2.0}, "not both")],
)
def test_a_sea_without_a_height_says_neither_was_given(sea: dict[str, float], said: str) -> None:
    """A review's: ``sea: {tp_s: 8}`` was told "give either `state` or `hs_m`, not both"."""
    from mmusv.config import SeaConfig

    with pytest.raises(ValueError, match=said):
        SeaConfig.model_validate(sea)


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ("name: a\nseed: 1\nvessels: []\n", "given as text"),
        ("x" * 300, "cannot be read: File name too long"),
        ("a/" * 3000, "cannot be read: File name too long"),
    ],
    ids=["yaml-text", "long-name", "long-path"],
)
def test_text_or_a_name_too_long_is_a_config_error(given: str, said: str) -> None:
    """A review's: ``mmusv.run(open("s.yaml").read())`` raised a bare ``OSError: File name too long`` from a path
    check (and so did ``load_scenario`` on a name too long for the file system)."""
    import mmusv
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError

    for call in (load_scenario, mmusv.run):
        with pytest.raises(ConfigError, match=said):
            call(given)


@pytest.mark.parametrize(
    ("mount", "said"),
    [
        (
            {"xyz": [1e39, 0, 0]},
            "rigs.usv_standard.lidar.mount.xyz = [1e+39, 0, 0]: must be three numbers within ±100,000 m",
        ),
        ({"xyz": [0, -1e308, 0]}, "lidar.mount.xyz = [0, -1e+308, 0]: must be three numbers within ±100,000 m"),
        ({"rpy_deg": [0, 0, 1e308]}, "lidar.mount.rpy_deg = [0, 0, 1e+308]: must be three numbers within ±360 degrees"),
    ],
)
def test_a_mount_out_of_all_reach_is_named(mount: dict[str, object], said: str) -> None:
    """A review's: a LiDAR mounted 1e39 m off overflowed the core's floats ("invalid origins[0]: [inf, 0.0, 0.0]",
    naming no field), and a turn of 1e308 degrees was taken."""
    import yaml
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError

    doc = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios" / "port_entry.yaml").read_text())
    doc["rigs"]["usv_standard"] = {"lidar": {"mount": mount}}
    with pytest.raises(ConfigError) as err:
        load_scenario(doc)
    assert said in str(err.value), str(err.value)
