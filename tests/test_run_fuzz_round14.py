"""Round 14 of the run fuzz: scenarios that loaded but then ran wrong (tiny runs of mutated bundled and test
scenarios). Each is now refused when the scenario loads, naming the field and what is allowed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.world.map_params import MapConfigError, make_params
from tiny_scenario import lidar_scenario

ROOT = Path(__file__).resolve().parents[1]


def _port_entry(**params: Any) -> dict[str, Any]:
    doc: dict[str, Any] = yaml.safe_load((ROOT / "scenarios" / "port_entry.yaml").read_text(encoding="utf-8"))
    doc["map"]["params"] = params
    return doc


# ------------------------------------------------------------------------------- moored ships and their berths


def test_a_berth_smaller_than_its_moored_ship_is_refused_naming_the_entry() -> None:
    """``moored_assets: [[container_ship_300m, 1, 1]]`` loaded and ran: the port laid out 1 m berths 15-40 m apart,
    so ten 300 m ships lay in each other and in the quay (the map's buoys and the route checks kept off 1 m
    footprints), without a word. The entry is refused with the ship's own figures."""
    with pytest.raises(ConfigError) as err:
        load_scenario(_port_entry(n_moored=3, moored_assets=[["tug_32m", 32, 12], ["container_ship_300m", 1, 1]]))
    said = str(err.value)
    assert "map.params.moored_assets" in said and "entry 1 ('container_ship_300m')" in said, said
    assert "1 x 1 m" in said and "300 x 48.2 m" in said and "[container_ship_300m, 300, 48.2]" in said, said
    with pytest.raises(MapConfigError) as err2:
        make_params("port", moored_assets=[["usv_wamv", 1, 1]])
    assert err2.value.field == "moored_assets" and "4.88 x 2.44 m" in str(err2.value), str(err2.value)


@pytest.mark.parametrize(
    "entries",
    [
        # the ship's own figures (the 300 m container ship's before 2026-12-06: its 14.5 m draft reaches the
        # default 14 m basin, refused since, tests/world/test_maps.py)
        [["feeder_container_140m", 140, 22.5]],
        [["tug_32m", 60, 20]],  # a larger berth: more room
        [["tug_32m", 30, 10]],  # within the slack (1 m a side clears the quay, the piers and the next ship)
    ],
)
def test_berths_of_the_ships_size_or_larger_still_load(entries: list[list[Any]]) -> None:
    scenario = load_scenario(_port_entry(n_moored=1, moored_assets=entries))
    assert [list(e) for e in scenario.map.params.moored_assets] == [[e[0], float(e[1]), float(e[2])] for e in entries]


# ------------------------------------------------------------------------------------- a vessel named 'world'


@pytest.mark.parametrize("who", [0, 1])
def test_a_vessel_id_world_is_refused(who: int) -> None:
    """A vessel ``id: world`` loaded and ran: its body frame in /tf was a child of the world frame named 'world'
    (a tree whose root moves with the hull), and a USV's topics /world/lidar, /world/boxes, ... were taken for the
    world's (``mmusv preview`` of the recording: "frame 0 has no agent topics"). Other ids, 'World' among them,
    load as before."""
    from mmusv.recording import topics

    doc = lidar_scenario("world_id", frames=1)
    doc["vessels"][who]["id"] = topics.WORLD_FRAME
    with pytest.raises(ConfigError) as err:
        load_scenario(doc)
    said = str(err.value)
    assert f"vessels[{who}].id" in said and "'world' is the name of the world frame" in said, said
    doc["vessels"][who]["id"] = "World"
    assert load_scenario(doc).vessels[who].id == "World"


# ------------------------------------------------------------------------------ a top view inside its own hull


def test_a_top_view_at_or_below_its_hull_top_is_refused() -> None:
    """``top_view: {altitude_m: 1e-9}`` (or 1 m over a 5.2 m patrol boat) loaded and ran: the top view looks down
    from that height over the USV's own origin, inside its hull, and its picture held none of the USV (at 1e-9 m;
    42 pixels of 156 at 1 m), without a word. Any altitude above the hull's top (its z_base_m counted) loads."""
    doc = lidar_scenario("top_view_in_hull", frames=1)
    doc["vessels"][0]["asset"] = "usv_patrol_12m"  # top at z = 5.2 m
    doc["rigs"]["r"]["top_view"] = {"altitude_m": 1.0}
    with pytest.raises(ConfigError) as err:
        load_scenario(doc)
    said = str(err.value)
    assert "rigs.r.top_view.altitude_m = 1:" in said and "hull reaches 5.20 m" in said, said
    assert "altitude_m must be above 5.20 m" in said, said
    doc["rigs"]["r"]["top_view"] = {"altitude_m": 5.3}
    assert load_scenario(doc).rigs["r"].top_view is not None
    doc["vessels"][0]["z_base_m"] = 0.2  # lifts the hull's top to 5.4 m
    with pytest.raises(ConfigError, match=r"altitude_m = 5\.3: .*5\.40 m with z_base_m = 0\.2"):
        load_scenario(doc)
