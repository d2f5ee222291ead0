"""A scenario's own vessel assets (``assets:``, :mod:`mmusv.scenario_assets`): a user mesh named from a scenario
file works with ``mmusv run`` and a batch, not only after a ``load_asset_file`` call in the same Python process
(docs review: ``mmusv run`` said "unknown asset")."""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.config import load_scenario, scenario_hash
from mmusv.editor.document import scenario_file
from mmusv.errors import ConfigError
from mmusv.world.vessels import get_asset
from user_assets import library_restored, write_boat

SCENARIO = """\
name: own_boat
map: {type: open_sea, seed: 1}
acquisition: {frequency_hz: 5, frames: 2}
rigs: {r: {preset: lidar_only}}
assets: [boats/skiff.yaml]
vessels:
  - {id: u, role: usv, asset: usv_wamv, rig: r, speed_mps: 2, route: [[-60, -300], [60, -300]]}
  - {id: s, asset: my_skiff, speed_mps: 3, route: [[0, -280], [40, -280]]}
"""


@pytest.fixture(autouse=True)
def _clean_library() -> Iterator[None]:
    """Each test's registered assets are removed after it (the library is per process)."""
    with library_restored():
        yield


def _boat(folder: Path, *, length: float = 6.0, name: str = "my_skiff") -> None:
    write_boat(folder / "boats" / "skiff.yaml", name=name, length=length)


def test_a_scenario_names_its_own_mesh_and_mmusv_run_records_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _boat(tmp_path)
    (tmp_path / "scen.yaml").write_text(SCENARIO, encoding="utf-8")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # relative to the scenario's folder, not the current one
    assert main(["run", "../scen.yaml", "-o", "out"]) == 0
    boxes = pl.read_parquet(elsewhere / "out" / "tables" / "boxes_3d")
    skiff = boxes.filter(pl.col("target_id") == "s")
    assert skiff.height > 0
    # the box is the mesh's: 6 m long, 2.4 m wide (the library's bounding box of the file, not a stand-in)
    np.testing.assert_allclose(skiff["length"].to_numpy(), 6.0, atol=1e-6)
    np.testing.assert_allclose(skiff["beam"].to_numpy(), 2.4, atol=1e-6)
    assert get_asset("my_skiff").source.endswith("skiff.yaml")


def test_a_missing_asset_file_is_named_with_its_field_before_anything_is_written(tmp_path: Path) -> None:
    (tmp_path / "scen.yaml").write_text(SCENARIO, encoding="utf-8")
    out = tmp_path / "out"
    with pytest.raises(ConfigError) as info:
        load_scenario(tmp_path / "scen.yaml")
    msg = str(info.value)
    assert "scen.yaml" in msg and "assets[0] = 'boats/skiff.yaml'" in msg, msg
    assert str(tmp_path / "boats" / "skiff.yaml") in msg and "does not exist" in msg, msg
    assert main(["run", str(tmp_path / "scen.yaml"), "-o", str(out)]) == 2
    assert not out.exists()


@pytest.mark.parametrize(("text", "kind"), [("just words\n", "text"), ("42\n", "a number"), ("", "nothing")])
def test_an_asset_file_that_holds_no_asset_says_what_it_holds(tmp_path: Path, text: str, kind: str) -> None:
    """It said "must hold one asset mapping; use load_asset_catalog() for a list", the Python API's advice, though a
    scenario's assets entry takes a list already."""
    (tmp_path / "boats").mkdir()
    (tmp_path / "boats" / "skiff.yaml").write_text(text, encoding="utf-8")
    (tmp_path / "scen.yaml").write_text(SCENARIO, encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"skiff\.yaml holds {kind}, not an asset: .*or a list of them") as info:
        load_scenario(tmp_path / "scen.yaml")
    assert "load_asset_catalog" not in str(info.value)


def test_an_asset_name_the_library_holds_is_refused_naming_both(tmp_path: Path) -> None:
    _boat(tmp_path, name="usv_wamv")
    (tmp_path / "scen.yaml").write_text(SCENARIO, encoding="utf-8")
    with pytest.raises(ConfigError, match=r"assets\[0\].*asset 'usv_wamv' is already in the library, from the built"):
        load_scenario(tmp_path / "scen.yaml")
    # another of the scenario's own files giving a name an earlier one registered: both files named (another
    # scenario's file may: tests/test_scenario_assets_per_scenario.py)
    _boat(tmp_path)
    other = tmp_path / "other"
    _boat(other)
    (other / "scen.yaml").write_text(
        SCENARIO.replace("assets: [boats/skiff.yaml]", "assets: [../boats/skiff.yaml, boats/skiff.yaml]"),
        encoding="utf-8",
    )
    with pytest.raises(ConfigError, match=r"assets\[1\]") as info:
        load_scenario(other / "scen.yaml")
    assert str(other / "scen.yaml") in str(info.value) and str(tmp_path / "boats" / "skiff.yaml") in str(info.value)


def test_reading_again_keeps_the_asset_and_a_changed_mesh_is_a_changed_configuration(tmp_path: Path) -> None:
    _boat(tmp_path)
    path = tmp_path / "scen.yaml"
    path.write_text(SCENARIO, encoding="utf-8")
    first = scenario_hash(path)
    assert scenario_hash(path) == first  # read twice in one process: no "already registered"
    built = get_asset("my_skiff")
    load_scenario(path)
    assert get_asset("my_skiff") is built  # unchanged files: not rebuilt
    _boat(tmp_path, length=9.0)
    st = (tmp_path / "boats" / "skiff.ply").stat()
    os.utime(tmp_path / "boats" / "skiff.ply", ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    changed = scenario_hash(path)
    assert get_asset("my_skiff").length == pytest.approx(9.0)
    assert changed != first  # a batch records it again instead of skipping it as complete
    # a scenario of built-in assets hashes as before: its canonical JSON alone
    plain = yaml.safe_load(SCENARIO)
    del plain["assets"]
    plain["vessels"] = plain["vessels"][:1]
    sc = load_scenario(plain)
    import hashlib

    text = json.dumps(sc.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))
    assert scenario_hash(sc) == hashlib.sha256(text.encode()).hexdigest()


def test_the_editor_saves_the_assets_list(tmp_path: Path) -> None:
    _boat(tmp_path)
    (tmp_path / "scen.yaml").write_text(SCENARIO, encoding="utf-8")
    text, _ = scenario_file(load_scenario(tmp_path / "scen.yaml"))
    assert yaml.safe_load(text)["assets"] == ["boats/skiff.yaml"]  # was dropped on save


def test_an_unknown_asset_says_how_to_bring_ones_own(tmp_path: Path) -> None:
    data = yaml.safe_load(SCENARIO)
    del data["assets"]
    with pytest.raises(ConfigError, match=r"vessels\[1\]\.asset.*list its asset file under the scenario's `assets:`"):
        load_scenario(data)
