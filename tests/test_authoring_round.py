"""A researcher writing scenarios by hand from the docs: the mistakes found in that round are refused with one
message that names the file, the field and what is allowed (a helper's round)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError


def _scenario(**changes: Any) -> dict[str, Any]:
    doc: dict[str, Any] = {
        "name": "authoring",
        "map": {"type": "port", "seed": 3},
        "environment": {"time_of_day": "16:30"},
        "rigs": {"lid": {"preset": "lidar_only"}},
        "vessels": [
            {
                "id": "usv_1",
                "role": "usv",
                "asset": "usv_wamv",
                "rig": "lid",
                "speed_mps": 2,
                "route": [[0, 0], [9, 1]],
            },
            {"id": "tug", "asset": "tug_32m", "route": [[250, -20], [260, -20]]},
        ],
    }
    doc.update(changes)
    return doc


def _refused(tmp_path: Path, doc: dict[str, Any]) -> str:
    path = tmp_path / "mine.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: ") and "\n" not in msg and "Traceback" not in msg
    return msg


@pytest.mark.parametrize("moored_id", ["moored_00", "moored_03"])
def test_an_id_of_the_port_maps_moored_ships_is_refused(tmp_path: Path, moored_id: str) -> None:
    # The port map labels its moored ships moored_00.. beside the scenario's vessels: a vessel named moored_00 gave
    # two vessels with one id in world_state and boxes_3d, without a word.
    doc = _scenario()
    doc["vessels"][1]["id"] = moored_id
    msg = _refused(tmp_path, doc)
    assert f"vessels[1].id = {moored_id!r}" in msg and "moored_00..moored_03" in msg and "map.params.n_moored" in msg


def test_moored_ids_are_free_where_the_map_has_no_such_ship() -> None:
    doc = _scenario()
    doc["vessels"][1]["id"] = "moored_00"
    assert load_scenario({**doc, "map": {"type": "open_sea"}}).vessels[1].id == "moored_00"
    assert load_scenario({**doc, "map": {"type": "port", "params": {"n_moored": 0}}}).vessels[1].id == "moored_00"
    doc["vessels"][1]["id"] = "moored_02"
    assert load_scenario({**doc, "map": {"type": "port", "params": {"n_moored": 2}}}).vessels[1].id == "moored_02"


@pytest.mark.parametrize("time", [13.5, 13.0, None, True, [13, 0]])
def test_a_time_of_day_that_is_not_a_string_says_hh_mm(tmp_path: Path, time: object) -> None:
    # `time_of_day: 13.30` (a YAML float) said only "Input should be a valid string".
    msg = _refused(tmp_path, _scenario(environment={"time_of_day": time}))
    assert "environment.time_of_day" in msg and '24-hour "HH:MM" in quotes' in msg


@pytest.mark.parametrize(
    ("where", "typo", "field", "meant"),
    [
        (("vessels", 1), "sped_mps", "vessels[1].sped_mps", "speed_mps"),
        (("environment",), "wether", "environment.wether", "weather"),
        (("rigs", "lid", "lidar"), "chanels", "rigs.lid.lidar.chanels", "channels"),
        (("rigs", "lid", "cameras", 0), "resolutoin", "rigs.lid.cameras[0].resolutoin", "resolution"),
        (("map", "params"), "n_mored", "map.params.n_mored", "n_moored"),
        ((), "vesels", "vesels", "vessels"),
    ],
)
def test_a_misspelt_key_says_which_keys_are_allowed(
    tmp_path: Path, where: tuple[Any, ...], typo: str, field: str, meant: str
) -> None:
    # "Extra inputs are not permitted" named the key but not what is allowed there.
    doc = _scenario()
    doc["rigs"]["lid"]["lidar"] = {"channels": 8}
    doc["rigs"]["lid"]["cameras"] = [{"name": "c", "resolution": [16, 12]}]
    doc["map"]["params"] = {"n_moored": 2}
    node: Any = doc
    for part in where:
        node = node[part]
    if typo == "vesels":
        node[typo] = node.pop("vessels")
    elif meant in node:
        node[typo] = node.pop(meant)
    else:
        node[typo] = 1
    msg = _refused(tmp_path, doc)
    assert f"{field} = " in msg and f"did you mean {meant!r}?" in msg and "allowed keys: " in msg


def test_map_params_of_another_map_type_list_that_types_keys(tmp_path: Path) -> None:
    doc = _scenario(map={"type": "island", "params": {"n_moored": 3}})
    msg = _refused(tmp_path, doc)
    allowed = msg.split("allowed keys: ", 1)[1]
    assert "map.params.n_moored = 3" in msg and "n_islands" in allowed and "n_moored" not in allowed


def test_too_many_frames_names_the_scenario_file(tmp_path: Path) -> None:
    """`mmusv run X.yaml --frames 10` on a scenario of 5 frames said "frames = 10: must be in 1..5
    (acquisition.frames)", naming neither the file nor the flag."""
    from mmusv.acquire import run

    path = tmp_path / "five.yaml"
    path.write_text(yaml.safe_dump(_scenario(acquisition={"frames": 5}), sort_keys=False), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"--frames\): must be in 1\.\.5, the acquisition\.frames of .*five\.yaml"):
        run(path, out_dir=tmp_path / "out", frames=10)
    assert not (tmp_path / "out").exists()


def test_the_allowed_keys_are_listed_once_where_several_keys_are_unknown(tmp_path: Path) -> None:
    """A JSON Schema given as a scenario listed the allowed top-level keys after each of its eight keys."""
    doc = _scenario()
    doc.update({"nmae": "x", "sed": 3, "title": "t"})
    msg = _refused(tmp_path, doc)
    assert msg.count("allowed keys: ") == 1, msg
    assert "did you mean 'name'?" in msg and "did you mean 'seed'?" in msg, msg  # each still told its nearest
