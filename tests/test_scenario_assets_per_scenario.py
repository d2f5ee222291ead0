"""Each scenario read in one process sees its own asset files' assets, none of another scenario's: the vessel
library is one per process, so a batch (``mmusv run FOLDER``, in one process or in reused workers) or a Python
session reading two scenarios whose asset files each name an asset ``skiff`` refused the second ("asset 'skiff' is
already in the library, from .../harbour_boats/boat.yaml"), and a scenario listing no asset file could use the
assets another scenario had registered (which ``mmusv run`` of it alone refuses)."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.config import load_scenario, scenario_hash
from mmusv.errors import ConfigError
from mmusv.simulation import Simulation
from mmusv.world.vessels import get_asset
from tiny_scenario import lidar_scenario
from user_assets import library_restored, write_boat

LENGTHS = {"harbour": 6.0, "lake": 12.0}


@pytest.fixture(autouse=True)
def _clean_library() -> Iterator[None]:
    with library_restored():
        yield


def _folder(root: Path) -> Path:
    """``root`` with harbour.yaml and lake.yaml, each listing its own asset file, which names a ``skiff`` of its
    own length (LENGTHS), and unlisted.yaml, which names ``skiff`` without listing an asset file."""
    for stem, length in LENGTHS.items():
        write_boat(root / f"{stem}_boats" / "boat.yaml", name="skiff", length=length)
        sc = lidar_scenario(stem, frames=2)
        sc["assets"] = [f"{stem}_boats/boat.yaml"]
        sc["vessels"][1]["asset"] = "skiff"
        (root / f"{stem}.yaml").write_text(yaml.safe_dump(sc), encoding="utf-8")
    return root


def test_two_scenarios_in_one_python_process_each_see_their_own_skiff(tmp_path: Path) -> None:
    folder = _folder(tmp_path)
    lake_hash = scenario_hash(folder / "lake.yaml")
    lake = load_scenario(folder / "lake.yaml")
    assert get_asset("skiff").length == pytest.approx(12.0)
    # was: assets[0]: asset 'skiff' is already in the library, from .../lake_boats/boat.yaml
    harbour = load_scenario(folder / "harbour.yaml")
    assert get_asset("skiff").length == pytest.approx(6.0)
    unlisted = lidar_scenario("unlisted", frames=2)
    unlisted["vessels"][1]["asset"] = "skiff"
    with pytest.raises(ConfigError, match=r"vessels\[1\]\.asset.*unknown asset"):  # was: the 6 m skiff of harbour
        load_scenario(unlisted)
    # a scenario loaded before another is run with its own assets (mmusv.run, Simulation, the studies)
    sim = Simulation(lake)
    assert sim.vessels[1].box_size[0] == pytest.approx(12.0)
    assert scenario_hash(harbour) == scenario_hash(folder / "harbour.yaml")
    assert scenario_hash(folder / "lake.yaml") == lake_hash  # whichever scenario was read before
    assert load_scenario(folder / "lake.yaml") == lake


def test_a_batch_records_each_scenario_with_its_own_skiff_in_one_process_or_in_workers(tmp_path: Path) -> None:
    folder = _folder(tmp_path / "scenarios")
    recorded: dict[str, dict[str, bytes]] = {}
    for jobs in ("1", "2"):
        out = tmp_path / f"out{jobs}"
        # was: lake.yaml failed, "asset 'skiff' is already in the library, from .../harbour_boats/boat.yaml"
        assert main(["run", str(folder), "-o", str(out), "--jobs", jobs]) == 0
        for stem, length in LENGTHS.items():
            boxes = pl.read_parquet(out / stem / "tables" / "boxes_3d")
            skiff = boxes.filter(pl.col("target_id") == "t")
            assert skiff.height > 0
            np.testing.assert_allclose(skiff["length"].to_numpy(), length, atol=1e-6)
        recorded[jobs] = {stem: (out / stem / f"{stem}.mcap").read_bytes() for stem in LENGTHS}
    assert recorded["1"] == recorded["2"]  # the same bytes in one process and in workers


def test_a_simulation_annotates_with_its_own_skiff_after_another_scenario_was_read(tmp_path: Path) -> None:
    """A Simulation keeps the assets it was built with: its annotations (a vessel's silhouette alone, for the share
    of it hidden) and its wakes (the displacements) looked the asset up again by name when first asked, so a
    scenario read in between, with a ``skiff`` of its own, gave the other scenario's skiff to this one's labels."""
    from mmusv.acquire import annotations_for
    from mmusv.silhouettes import SilhouetteCache

    folder = _folder(tmp_path)
    sim = Simulation(load_scenario(folder / "lake.yaml"))
    alone = Simulation(load_scenario(folder / "lake.yaml"))  # nothing read after it: the reference
    want = annotations_for(alone, alone.capture(1), SilhouetteCache())
    want_wakes = alone.wakes(alone.world_state(1))

    load_scenario(folder / "harbour.yaml")  # holds the library for the harbour's 6 m skiff
    assert get_asset("skiff").length == pytest.approx(6.0)
    got = annotations_for(sim, sim.capture(1), SilhouetteCache())
    assert got and got == want  # was: the hidden shares of the 6 m skiff's silhouette
    np.testing.assert_array_equal(sim.wakes(sim.world_state(1)), want_wakes)


def test_simulations_of_two_scenarios_built_in_two_threads_at_once_each_get_their_own_skiff(tmp_path: Path) -> None:
    """Two threads each build Simulations of their own scenario (both name a ``skiff``, of other lengths) at the
    same time (was: the library one thread held for its scenario could be switched by the other between reading
    the scenario and looking its assets up, so a Simulation was built with the other's skiff, or refused it as
    unknown)."""
    folder = _folder(tmp_path)
    got: dict[str, list[float]] = {stem: [] for stem in LENGTHS}
    errors: list[BaseException] = []
    start = threading.Barrier(2)

    def build(stem: str) -> None:
        try:
            start.wait()
            for _ in range(4):
                sim = Simulation(folder / f"{stem}.yaml")
                got[stem].append(sim.assets["skiff"].length)
                got[stem].append(float(sim.vessels[1].box_size[0]))
        except BaseException as exc:  # said below, in the test's thread
            errors.append(exc)

    threads = [threading.Thread(target=build, args=(stem,)) for stem in LENGTHS]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for stem, length in LENGTHS.items():
        np.testing.assert_allclose(got[stem], length, atol=1e-6)
