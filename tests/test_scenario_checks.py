"""mmusv.scenario_checks.check_sensors: a scenario that records no sensor at all is said so, once, as a warning (the
malformed-input review's: ``preset: lidar_only`` with ``lidar: null``, or no vessel with ``role: usv``, ran without a
word and recorded the world state only). check_rain_visibility: a visibility given clearer than its rain's drops
alone allow is said so (it was kept without a word, and the LiDAR dims in rain by the visibility alone)."""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.cli import main
from mmusv.config import load_scenario
from mmusv.scenario_checks import MmusvWarning, check_rain_visibility, check_sensors

BASE: dict[str, Any] = {
    "name": "t",
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 2},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 3, "route": [[-300, 0], [300, 0]]},
        {"id": "t1", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[-100, 20], [-400, 25]]},
    ],
}


def _warned(check: Callable[..., list[str]], doc: dict[str, Any]) -> list[str]:
    """What ``check`` finds in the scenario ``doc`` (as from ``s.yaml``), checked to be what it warned, one
    :class:`MmusvWarning` each."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = check(load_scenario(doc), source="s.yaml")
    assert [str(w.message) for w in caught if w.category is MmusvWarning] == found
    return found


def _no_lidar() -> dict[str, Any]:
    doc = copy.deepcopy(BASE)
    doc["rigs"]["r"]["lidar"] = None
    return doc


def _no_usv() -> dict[str, Any]:
    doc = copy.deepcopy(BASE)
    del doc["rigs"]
    doc["vessels"] = doc["vessels"][1:]
    return doc


def _one_rig_empty() -> dict[str, Any]:  # two USVs, one of them with a sensor: nothing to say
    doc = copy.deepcopy(BASE)
    doc["rigs"]["off"] = {"preset": "lidar_only", "lidar": None}
    doc["vessels"].append({**doc["vessels"][0], "id": "u2", "rig": "off", "route": [[-300, 50], [300, 50]]})
    return doc


@pytest.mark.parametrize(
    ("make", "said"),
    [
        (_no_lidar, "rigs.r switches every sensor off"),
        (_no_usv, "no vessel has role: usv"),
        (_one_rig_empty, None),
        (lambda: copy.deepcopy(BASE), None),
    ],
    ids=["lidar-null", "no-usv", "one-of-two-empty", "lidar-only"],
)
def test_a_scenario_without_any_sensor_is_warned_about(make: Any, said: str | None) -> None:
    found = _warned(check_sensors, make())
    if said is None:
        assert found == []
    else:
        assert len(found) == 1 and found[0].startswith(f"s.yaml: {said}"), found


def test_the_run_says_it_on_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "t.yaml"
    src.write_text(yaml.safe_dump(_no_lidar()), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("always", MmusvWarning)  # printed, as on the command line (the tests make them errors)
        assert main(["run", str(src), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert f"mmusv: warning: {src}: rigs.r switches every sensor off" in err, err
    assert (tmp_path / "out" / "t.mcap").exists()  # a warning: the run still records the world state


def test_the_editor_lists_it_among_the_problems() -> None:
    from mmusv.editor.evaluate import evaluate

    ev = evaluate(_no_lidar())
    (p,) = [p for p in ev["problems"] if p["check"] == "sensors"]
    assert p["severity"] == "warning" and p["field"] == "rigs.r" and "switches every sensor off" in p["message"]
    ev = evaluate(_no_usv())
    (p,) = [p for p in ev["problems"] if p["check"] == "sensors"]
    assert p["field"] == "vessels" and "no vessel has role: usv" in p["message"]


def test_a_vessel_whose_keel_reaches_the_seabed_is_warned_about(tmp_path: Path) -> None:
    """``under_keel``: ``in_water`` takes every hull's water alike (2 m deep), so the 300 m container ship (draft
    14.5 m) sailed the port's basin, 14 m deep (``basin_depth_m``'s default), with its keel in the floor and not a
    word (the maps sweep's finding). ``mmusv run`` now warns, naming the vessel, its draft, the depth, where and
    when, and the editor lists it; a 16 m pilot boat there and the container ship over the open sea's 25 m do
    not."""
    from mmusv.acquire import run
    from mmusv.scenario_checks import check_routes
    from mmusv.simulation import Simulation

    def check_under_keel(sc: dict[str, Any]) -> list[str]:
        """The ``under_keel`` warnings of the run's route checks (its frames' samples), each also warned."""
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            said = [
                w
                for w in check_routes(load_scenario(sc), Simulation(sc).world, source="s.yaml")
                if ": under_keel: " in w
            ]
        assert [str(w.message) for w in caught if ": under_keel: " in str(w.message)] == said
        return said

    def scenario(kind: str) -> dict[str, Any]:
        return {
            "seed": 1,
            "map": {"type": kind, "seed": 3},
            "acquisition": {"frequency_hz": 1, "frames": 3},
            "vessels": [
                {"id": "big", "asset": "container_ship_300m", "speed_mps": 2, "route": [[250, -60], [100, -60]]},
                {"id": "small", "asset": "pilot_boat_16m", "speed_mps": 2, "route": [[250, -100], [100, -100]]},
            ],
        }

    said = check_under_keel(scenario("port"))
    assert check_under_keel(scenario("open_sea")) == []
    assert len(said) == 1
    assert said[0].startswith("s.yaml: under_keel: vessels[0] big (container_ship_300m, draft 14.5 m) sails over ")
    assert "14.0 m of water at (250, -60) m in frame 0" in said[0] and "basin_depth_m" in said[0]
    # mmusv run says it, and the run goes on (a warning)
    with pytest.warns(MmusvWarning) as ran:
        run(scenario("port"), out_dir=tmp_path / "run", frames=1)
    assert any("under_keel: vessels[0] big (" in str(w.message) for w in ran)
    # the scenario editor lists it too, on the vessel's route, where mmusv run warns
    from mmusv.editor.evaluate import evaluate

    (p,) = [p for p in evaluate(scenario("port"))["problems"] if p["check"] == "under_keel"]
    assert p["severity"] == "warning" and p["field"] == "vessels[0].route" and p["vessels"] == ["big"]
    assert p["message"].startswith("big (container_ship_300m, draft 14.5 m) sails over 14.0 m of water at (250, -60) m")
    assert p["point"] == [250.0, -60.0]
    deeper = copy.deepcopy(scenario("port"))
    deeper["map"]["params"] = {"basin_depth_m": 16.0}
    assert check_under_keel(deeper) == []


def _rainy(**environment: Any) -> dict[str, Any]:
    doc = copy.deepcopy(BASE)
    doc["environment"] = {"time_of_day": "12:00", **environment}
    return doc


@pytest.mark.parametrize(
    ("environment", "limit_m"),
    [
        ({"weather": "rain", "rain_mm_per_h": 25, "visibility_m": 1500}, 1083),
        ({"weather": "rain", "visibility_m": 5000}, 3435),  # the rain weather's default 4 mm/h
        ({"weather": "fog", "rain_mm_per_h": 50, "visibility_m": 800}, 700),
        ({"weather": "rain", "rain_mm_per_h": 25, "visibility_m": 1000}, None),  # within the drops' limit
        ({"weather": "rain", "rain_mm_per_h": 50}, None),  # left out: the rain's own
        ({"weather": "rain", "rain_mm_per_h": 0, "visibility_m": 20000}, None),  # a rain sky without its drops
        ({"weather": "clear", "visibility_m": 50000}, None),
    ],
)
def test_a_visibility_clearer_than_its_rain_allows_is_warned_about(
    environment: dict[str, Any], limit_m: int | None
) -> None:
    """The limit is the drops' own, ``3 / σ`` with σ = π N₀ / Λ³ of Marshall and Palmer's drops (``mmusv.world.rain``,
    checked there against the drop-size integral): 0.365 R^0.63 per km, 3.4 km at 4 mm/h, 1.1 km at 25, 0.7 km at 50."""
    found = _warned(check_rain_visibility, _rainy(**environment))
    if limit_m is None:
        assert found == []
    else:
        given = environment["visibility_m"]
        assert len(found) == 1 and found[0].startswith(f"s.yaml: environment.visibility_m = {given} is clearer"), found
        assert f"limit the visibility to {limit_m} m" in found[0], found


def test_the_run_and_the_editor_say_the_rain_s_visibility(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from mmusv.editor.evaluate import evaluate

    doc = _rainy(weather="rain", rain_mm_per_h=25, visibility_m=1500)
    doc["acquisition"]["frames"] = 1
    src = tmp_path / "t.yaml"
    src.write_text(yaml.safe_dump(doc), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("always", MmusvWarning)  # printed, as on the command line (the tests make them errors)
        assert main(["run", str(src), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert f"mmusv: warning: {src}: environment.visibility_m = 1500 is clearer than rain of 25 mm/h" in err, err
    (p,) = [p for p in evaluate(doc)["problems"] if p["check"] == "rain"]
    assert p["severity"] == "warning" and p["field"] == "environment.visibility_m", p
