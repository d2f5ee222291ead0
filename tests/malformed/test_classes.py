"""Every class of malformed input of issue #14 gets a clear MmusvError naming file and field, nothing written,
and the CLI prints one line and exits 2 (or, for a folder run, reports each file and keeps going)."""

from __future__ import annotations

import pickle
import warnings
from pathlib import Path
from typing import Any

import mmusv
import pytest
import yaml
from mmusv.cli import main
from mmusv.config import load_scenario
from mmusv.errors import ConfigError, MmusvError
from mmusv.generate.layout import SamplingError
from mmusv.generate.planner import PlannerError
from mmusv.generate.spec import load_spec
from mmusv.scenario_checks import MmusvWarning
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.vessels import UnknownAssetError, get_asset

ROOT = Path(__file__).resolve().parents[2]
PORT = ROOT / "scenarios/port_entry.yaml"
SPEC = ROOT / "scenarios/specs/island_demo.yaml"


def tiny(**changes: Any) -> dict[str, Any]:
    """A fast open-sea scenario (LiDAR only, 2 frames); keyword arguments replace top-level keys."""
    d: dict[str, Any] = {
        "name": "tiny",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": 2},
        "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 8 * 64 * 5}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[0, 60], [60, 60]]},
        ],
    }
    d.update(changes)
    return d


def write(path: Path, data: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def cli_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmusv: error: ") and "\n" not in err and "Traceback" not in err, err
    return err


# ---------------------------------------------------------------------------------------------- encodings


@pytest.mark.parametrize(
    ("encode", "expect"),
    [
        (lambda t: t.encode("latin-1"), "not UTF-8 text (byte 0xe9"),
        (lambda t: t.encode("utf-16"), "UTF-16"),
        (lambda t: b"\x89PNG\r\n\x1a\n\x00\x00\x00" + bytes(range(256)), "not a text file"),
    ],
    ids=["latin1", "utf16", "binary"],
)
def test_bad_encodings_are_config_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], encode: Any, expect: str
) -> None:
    text = PORT.read_text(encoding="utf-8").replace("# Port map", "# Port map, café")
    f = tmp_path / "bad.yaml"
    f.write_bytes(encode(text))
    with pytest.raises(ConfigError, match=r"bad\.yaml") as exc:
        load_scenario(f)
    assert expect in str(exc.value)
    with pytest.raises(ConfigError, match=r"bad\.yaml"):
        load_spec(f)
    err = cli_error(capsys, ["run", str(f), "-o", str(tmp_path / "out")])
    assert "bad.yaml" in err
    assert not (tmp_path / "out").exists()


def test_utf8_bom_is_accepted(tmp_path: Path) -> None:
    f = tmp_path / "bom.yaml"
    f.write_bytes(b"\xef\xbb\xbf" + PORT.read_bytes())
    assert load_scenario(f) == load_scenario(PORT)


def test_duplicate_keys_are_refused(tmp_path: Path) -> None:
    text = PORT.read_text(encoding="utf-8") + "vessels:\n  - {id: x, asset: tug_32m, route: [[0, 0], [1, 0]]}\n"
    f = tmp_path / "dup.yaml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=r"dup.yaml: duplicate key 'vessels' at line \d+ \(first at line \d+\)"):
        load_scenario(f)


def test_yaml_syntax_errors_name_line_and_column(tmp_path: Path) -> None:
    f = tmp_path / "syntax.yaml"
    f.write_text("name: x\nvessels: [{id: a,\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"syntax.yaml: not valid YAML at line \d+, column \d+"):
        load_scenario(f)


# ---------------------------------------------------------------------------------------------- numbers


def test_deep_nesting_is_refused_without_a_crash(tmp_path: Path) -> None:
    """A scenario nested 100,000 deep (a hostile or corrupted file) is a ConfigError naming the file, in this
    process: user inputs go through the pure-Python parser, whose recursion is bounded (libyaml's C composer,
    used for mmusv's own catalogue, would overflow the C stack and kill the process)."""
    for text in ("[" * 100_000 + "]" * 100_000, "- " * 20_000 + "1", "a: " + "{b: " * 5_000 + "1" + "}" * 5_000):
        bad = tmp_path / "deep.yaml"
        bad.write_text(text)
        with pytest.raises(ConfigError, match=r"deep\.yaml: not valid YAML: nested too deeply"):
            load_scenario(bad)


def test_the_built_in_catalogue_parses_alike_with_either_parser() -> None:
    """The vessel catalogue, read by libyaml's C parser (trusted: mmusv's own file), is the document the
    pure-Python parser reads, and a refused document gets the pure-Python parser's message either way."""
    from importlib import resources

    from mmusv.yamlio import parse_yaml

    text = resources.files("mmusv.world").joinpath("vessel_catalog.yaml").read_text(encoding="utf-8")
    assert parse_yaml(text, "c", trusted=True) == parse_yaml(text, "c")
    for bad in ("a:\n\t- 1", "a: &x 1\nb: *y"):
        messages = []
        for trusted in (True, False):
            with pytest.raises(ConfigError) as err:
                parse_yaml(bad, "f.yaml", trusted=trusted)
            messages.append(str(err.value))
        assert messages[0] == messages[1] and "line 2" in messages[0], messages


@pytest.mark.parametrize("value", [float("inf"), float("-inf"), float("nan")])
def test_non_finite_numbers_are_refused_with_the_field(value: float) -> None:
    d = tiny()
    d["rigs"]["r"]["lidar"]["points_per_second"] = value
    with pytest.raises(ConfigError, match=r"rigs\.r\.lidar\.points_per_second = .*finite number"):
        load_scenario(d)
    d = tiny(environment={"visibility_m": value})
    with pytest.raises(ConfigError, match=r"environment\.visibility_m = .*finite"):
        load_scenario(d)


def test_spec_ranges_with_infinite_bounds_are_refused() -> None:
    d = yaml.safe_load(SPEC.read_text(encoding="utf-8"))
    d["usv"]["speed_mps"] = [1.0, float("inf")]
    with pytest.raises(ConfigError, match=r"usv\.speed_mps.*finite"):
        load_spec(d)


@pytest.mark.parametrize(
    ("rig", "field"),
    [
        (
            {"cameras": [{"name": "c", "resolution": [16384, 16384]}]},
            r"cameras\.0\.resolution|cameras\[0\]\.resolution",
        ),
        ({"lidar": {"channels": 1024, "points_per_second": 1024 * 65536 * 5.0}}, r"lidar"),
        ({"radar": {"azimuth_bins": 65536, "rays_az": 64, "rays_el": 256}}, r"radar"),
        ({"top_view": {"resolution": [16000, 16000]}}, r"top_view\.resolution"),
    ],
)
def test_allocation_sizes_are_bounded_by_their_cost(rig: dict[str, Any], field: str) -> None:
    with pytest.raises(ConfigError, match=field) as exc:
        load_scenario(tiny(rigs={"r": rig}))
    assert "GB" in str(exc.value)


def test_tiny_check_step_is_refused_before_allocating() -> None:
    d = yaml.safe_load(SPEC.read_text(encoding="utf-8"))
    d["check_step_m"] = 0.001
    with pytest.raises(ConfigError, match=r"check_step_m = 0\.001"):
        load_spec(d)


# ---------------------------------------------------------------------------------------------- semantics


def test_a_rig_on_a_vessel_that_is_not_a_usv_is_an_error() -> None:
    d = tiny()
    d["vessels"][1]["rig"] = "r"
    with pytest.raises(ConfigError, match=r"vessels\[1\]\.rig = 'r': only instrumented vessels \(role: usv\)"):
        load_scenario(d)


def test_an_unknown_mount_point_lists_the_assets_points() -> None:
    d = tiny()
    d["rigs"]["r"]["lidar"]["mount"] = {"point": "lidr"}
    with pytest.raises(
        ConfigError, match=r"rigs\.r\.lidar\.mount\.point = 'lidr'.*did you mean 'lidar'.*its points: camera_front"
    ):
        load_scenario(d)


def test_a_sensor_the_core_refuses_names_the_rig_and_the_sensor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Two cameras, the second's distortion folding over within its image: only the core can tell (it inverts the
    # distortion at every pixel), and its error must name which camera of which rig, not just `camera.distortion`.
    d = tiny()
    cam = {"resolution": [32, 24], "outputs": ["depth"]}
    d["rigs"]["r"]["cameras"] = [
        {**cam, "name": "bow", "mount": {"point": "camera_front"}},
        {**cam, "name": "aft", "mount": {"point": "camera_rear"}, "distortion": [-5.0, 3.0, 0.0, 0.0, 0.0]},
    ]
    path = write(tmp_path / "folded.yaml", d)
    err = cli_error(capsys, ["run", str(path), "-o", str(tmp_path / "out")])
    # cameras is a list: the path is its index, as the schema's own errors and the YAML spell it
    assert "folded.yaml: invalid config rigs.r.cameras[1].distortion = [-5.0, 3.0" in err, err
    assert "the distortion folds over" in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.mcap"))


def test_a_mount_kilometres_away_is_a_warning_naming_it(tmp_path: Path) -> None:
    d = tiny()
    d["rigs"]["r"]["lidar"]["mount"] = {"xyz": [0.0, 0.0, 2300.0]}  # millimetres typed as metres
    with pytest.warns(MmusvWarning, match=r"rigs\.r\.lidar\.mount \(vessel u\) is \d+ m from the usv_wamv hull"):
        mmusv.run(d, out_dir=tmp_path / "o")


def test_a_route_over_land_is_an_error_unless_checks_are_off(tmp_path: Path) -> None:
    d = tiny(map={"type": "island", "seed": 4})
    d["vessels"][0]["route"] = [[460, -330], [500, -200]]  # across the islet of island map 4
    with pytest.raises(ConfigError, match=r"in_water: u leaves navigable water"):
        mmusv.run(d, out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = mmusv.run(d, out_dir=tmp_path / "o2", checks=False)
    assert res.frames_written == 2


def test_a_route_off_the_map_is_said_to_leave_the_map(tmp_path: Path) -> None:
    """Routes 50 km out on a 4 km open-sea map were said to leave "navigable water (centre)", as if over land."""
    d = tiny(map={"type": "open_sea", "seed": 0, "params": {"extent_m": 4000}})
    d["vessels"][1]["route"] = [[50000, 50000], [50100, 50000]]
    with pytest.raises(ConfigError) as info:
        mmusv.run(d, out_dir=tmp_path / "o")
    msg = str(info.value)
    assert "in_water: t leaves the map near (50000, 50000) (the map spans x -2000..2000 m, y -2000..2000 m)" in msg
    assert "(vessels[1].route)" in msg and "u leaves" not in msg, msg


def test_every_stranded_route_is_named_by_its_field(tmp_path: Path) -> None:
    d = tiny(map={"type": "island", "seed": 4})
    d["vessels"][0]["route"] = [[460, -330], [500, -200]]  # across the islet of island map 4
    d["vessels"].append({"id": "w", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[470, -330], [510, -200]]})
    with pytest.raises(ConfigError) as info:
        mmusv.run(d, out_dir=tmp_path / "o")
    msg = str(info.value)
    assert "u leaves navigable water" in msg and "(vessels[0].route)" in msg, msg
    assert "w leaves navigable water" in msg and "(vessels[2].route)" in msg, msg
    assert "t leaves" not in msg, msg


def test_a_camera_inside_the_hull_is_named_by_its_index(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    d = tiny()
    cam = {"resolution": [32, 24], "outputs": ["depth"]}
    d["rigs"]["r"]["cameras"] = [
        {**cam, "name": "bow", "mount": {"point": "camera_front"}},
        {**cam, "name": "aft", "mount": {"xyz": [0.0, 1.0, 0.0]}},  # inside the WAM-V's port pontoon
    ]
    path = write(tmp_path / "inside.yaml", d)
    err = cli_error(capsys, ["run", str(path), "-o", str(tmp_path / "out")])
    assert "invalid config rigs.r.cameras[1].mount = " in err and "inside the hull" in err, err


def test_a_sensor_under_the_water_is_refused_naming_its_field(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """A camera 3 m under the waterline saw the sea from below and labelled half its picture sky; a USV lowered by
    ``z_base_m`` took its LiDAR and radar under with it, and they returned points on hulls under their waterlines.
    Both ran without a word; now each is refused, naming the field, before anything is written."""
    d = tiny()
    cam = {"resolution": [32, 24], "outputs": ["depth"]}
    d["rigs"]["r"]["cameras"] = [
        {**cam, "name": "bow", "mount": {"point": "camera_front"}},
        {**cam, "name": "keel", "mount": {"xyz": [0.0, 0.0, -3.0]}},
    ]
    path = write(tmp_path / "under.yaml", d)
    err = cli_error(capsys, ["run", str(path), "-o", str(tmp_path / "out")])
    assert "invalid config rigs.r.cameras[1].mount = [0.0, 0.0, -3.0]" in err, err
    assert "3.00 m under the still water" in err and "z > 0 in the vessel frame" in err, err
    d = tiny()
    # Lowered 2.1 m, the WAM-V (hull top at z = 2.20 m) still floats, with a camera 1 m up its frame under the water.
    d["rigs"]["r"]["cameras"] = [{**cam, "name": "low", "mount": {"xyz": [2.0, 0.0, 1.0]}}]
    d["vessels"][0]["z_base_m"] = -2.1
    with pytest.raises(ConfigError, match=r"cameras\[0\]\.mount = .* under the still water \(the vessel's z_base_m"):
        mmusv.run(d, out_dir=tmp_path / "o")
    # Lowered 5 m, its whole hull is under the water: refused for that first.
    d["vessels"][0]["z_base_m"] = -5.0
    with pytest.raises(
        ConfigError, match=r"vessels\[0\]\.z_base_m = -5: it puts the whole hull .* below the still water"
    ):
        mmusv.run(d, out_dir=tmp_path / "o")
    assert not (tmp_path / "out").exists() and not (tmp_path / "o").exists()
    # At the waterline (a camera without a mount sits there) is still allowed.
    d = tiny()
    d["rigs"]["r"]["cameras"] = [{**cam, "name": "low", "mount": {"xyz": [5.0, 0.0, 0.0]}}]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert mmusv.run(d, out_dir=tmp_path / "ok").frames_written == 2


def test_close_passes_are_warnings(tmp_path: Path) -> None:
    d = tiny()
    d["vessels"][1]["route"] = [[0, 8], [60, 8]]  # 8 m abeam of the USV
    with pytest.warns(MmusvWarning, match="separation"):
        mmusv.run(d, out_dir=tmp_path / "o")


def test_hulls_that_run_into_each_other_are_an_error_unless_checks_are_off(tmp_path: Path) -> None:
    """A USV sailing inside a tug recorded 26,202 of 26,202 LiDAR points on the tug's inside, with a warning only
    ("overlap by 10.2 m"); two hulls that intersect are an error now, as a route over land is, naming both."""
    d = tiny()
    d["vessels"][1] = {"id": "t", "asset": "tug_32m", "speed_mps": 2, "route": [[0, 0], [50, 0]]}
    with pytest.raises(ConfigError) as info:
        mmusv.run(d, out_dir=tmp_path / "o")
    msg = str(info.value)
    assert "hulls_intersect: the hulls of u and t intersect at t=0.0 s" in msg, msg
    assert "(vessels[0] and vessels[1])" in msg and "--no-checks" in msg, msg
    assert not (tmp_path / "o").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert mmusv.run(d, out_dir=tmp_path / "o2", checks=False).frames_written == 2
    # Alongside, 8 m abeam, is a close pass: a warning, not an error.
    d["vessels"][1]["route"] = [[0, 8], [50, 8]]
    with pytest.warns(MmusvWarning, match="separation: u and t pass with their hull capsules overlapping by"):
        mmusv.run(d, out_dir=tmp_path / "o3")


def test_a_separation_warning_says_when_only_the_motion_between_samples_is_too_close() -> None:
    """A 300 m ship turning a hairpin 150 m off a USV was said to "come 120.3 m apart (hulls) ...; need 15 m": the
    check's allowance for the motion between its samples was not said."""
    from mmusv.simulation import Simulation

    d = tiny(acquisition={"frequency_hz": 0.05, "frames": 6})
    d["vessels"][0]["route"] = [[-200, -150], [-100, -150]]
    d["vessels"][1] = {
        "id": "ship",
        "asset": "container_ship_300m",
        "speed_mps": 8,
        "route": [[0, 0], [400, 0], [0, 5]],
    }
    sc = load_scenario(d)
    with pytest.warns(MmusvWarning) as caught:
        from mmusv.scenario_checks import check_routes

        found = check_routes(sc, Simulation(sc).world, source="hairpin.yaml")
    seps = [m for m in found if ": separation: " in m]  # beside it, the hairpin's sharp_turn
    assert len(seps) == 1 and len(caught) == len(found), found
    msg = seps[0]
    assert msg.startswith("hairpin.yaml: separation: u and ship come "), msg
    assert "between the samples checked they can come up to" in msg and msg.endswith("need 15 m"), msg


def test_a_route_that_doubles_back_warns_of_a_turn_no_hull_can_make(tmp_path: Path) -> None:
    """A 12 m boat reversed on the spot at a waypoint that doubled back (heading 0 to 180 degrees in 0.2 s), and a
    300 m ship swung round a 5 m hairpin at 300 degrees a second, without a word."""
    d = tiny()
    d["vessels"][1]["route"] = [[0, 60], [60, 60], [0, 60.5], [60, 61]]
    with pytest.warns(MmusvWarning) as caught:
        mmusv.run(d, out_dir=tmp_path / "o")
    turns = [str(w.message) for w in caught if "sharp_turn" in str(w.message)]
    assert len(turns) == 1, [str(w.message) for w in caught]
    msg = turns[0]
    assert msg.startswith("scenario: sharp_turn: t turns at a radius of ") and "(vessels[1].route[" in msg, msg
    assert "tighter than its 12 m hull can" in msg, msg
    # The bundled scenarios' turns (the tightest a 90 m ferry's, 1.4 lengths) are not warned of.
    from mmusv.bundled import bundled_scenarios
    from mmusv.generate.mapctx import map_context
    from mmusv.scenario_checks import map_check_spec, scenario_samples, sharp_turns

    for b in bundled_scenarios():
        sc = load_scenario(b.path)
        ctx = map_context(sc.map.type, seed=sc.map.seed, params=sc.map.param_values())
        assert sharp_turns(sc, scenario_samples(sc, ctx, map_check_spec(sc))) == [], b.name


def test_generation_spec_shares_the_scenario_field_types() -> None:
    d = yaml.safe_load(SPEC.read_text(encoding="utf-8"))
    d["environment"]["time_of_day"] = ["7:30 pm"]
    with pytest.raises(ConfigError, match=r"environment\.time_of_day = '7:30 pm': use 24-hour"):
        load_spec(d)
    with pytest.raises(ConfigError, match=r"environment\.time_of_day"):
        load_scenario(tiny(environment={"time_of_day": "7:30 pm"}))


# ---------------------------------------------------------------------------------------------- where


def test_world_build_errors_name_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    f = write(tmp_path / "bad_map.yaml", tiny(map={"type": "port", "seed": 3, "params": {"n_moored": 999}}))
    err = cli_error(capsys, ["run", str(f), "-o", str(tmp_path / "out")])
    assert "bad_map.yaml" in err and "n_moored" in err


def test_run_of_a_directory_says_so(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"is a directory; mmusv\.run takes one scenario file"):
        mmusv.run(tmp_path, out_dir=tmp_path / "o")


@pytest.mark.parametrize("jobs", [1, 2])
def test_folder_runs_report_each_file_and_keep_going(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], jobs: int
) -> None:
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a_good.yaml", tiny(name="a_good"))
    write(src / "b_bad.yaml", tiny(name="b_bad", map={"type": "port", "seed": 3, "params": {"n_moored": 999}}))
    (src / "c_broken.yaml").write_bytes(b"name: c\nvessels: ]\n")
    write(src / "d_good.yaml", tiny(name="d_good"))
    assert main(["run", str(src), "-o", str(tmp_path / "out"), "--jobs", str(jobs)]) == 1
    out = capsys.readouterr().out
    assert "Traceback" not in out and "BrokenProcessPool" not in out
    assert "b_bad.yaml" in out and "c_broken.yaml" in out and "2 done, 2 failed" in out
    assert (tmp_path / "out/a_good/a_good.mcap").is_file() and (tmp_path / "out/d_good/d_good.mcap").is_file()
    assert not (tmp_path / "out/b_bad").exists() and not (tmp_path / "out/c_broken").exists()


def test_every_error_class_is_an_mmusv_error_and_pickles() -> None:
    errors: list[Exception] = [
        ConfigError("f.yaml: invalid config x = 1: y"),
        AssetSpecError("tug.hull.beam", "must be positive"),
        SamplingError("no water"),
        PlannerError("no route"),
    ]
    with pytest.raises(UnknownAssetError) as exc:
        get_asset("tugg_32m")
    errors.append(exc.value)
    for e in errors:
        assert isinstance(e, MmusvError), type(e)
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is type(e) and str(back) == str(e)
    assert isinstance(exc.value, KeyError)  # still what callers caught before
