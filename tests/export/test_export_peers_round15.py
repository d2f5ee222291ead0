"""Exports re-read as their users' tools read them (round 15).

* COCO: two recordings of scenarios that share a name (seeds differ) go to folders ``<name>_<hash8>``; each image's
  ``scenario`` names that folder, the first part of its ``file_name``, as MOT's ``tracks.csv`` does, so
  ``(scenario, agent, camera, frame)`` tells every image apart (it was the scenario's name, the same for both
  recordings: two images per key, and the field disagreed with the image's own path).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from conftest import small_rig
from mmusv.acquire import run
from mmusv.export import convert


def _namesakes(make_coop: Callable[..., dict[str, Any]], root: Path) -> list[Path]:
    """Two 1-frame recordings of a scenario named ``namesake``, seeds 1 and 2, one camera each USV."""
    rig = {**small_rig(), "radar": None, "top_view": None}
    rig["cameras"] = rig["cameras"][:1]
    out = []
    for seed in (1, 2):
        cfg = make_coop(name="namesake", seed=seed, rigs={"r": rig})
        cfg["acquisition"] = {"frequency_hz": 5, "frames": 1}
        out.append(Path(run(cfg, out_dir=root / f"run_{seed}").recording))
    return out


def test_coco_scenario_names_the_folder_of_recordings_that_share_a_name(
    make_coop: Callable[..., dict[str, Any]], tmp_path: Path
) -> None:
    recs = _namesakes(make_coop, tmp_path)
    convert(recs, to="coco", out_dir=tmp_path / "coco", splits=None)
    convert(recs, to="mot", out_dir=tmp_path / "mot", splits=None)
    images = json.loads((tmp_path / "coco" / "annotations" / "instances_all.json").read_text())["images"]
    folders = {i["file_name"].split("/")[0] for i in images}
    assert len(folders) == 2 and all(f.startswith("namesake_") for f in folders)
    assert all(i["scenario"] == i["file_name"].split("/")[0] for i in images)
    keys = [(i["scenario"], i["agent"], i["camera"], i["frame"]) for i in images]
    assert len(set(keys)) == len(keys) == 4
    with (tmp_path / "mot" / "tracks.csv").open(newline="") as f:
        assert {r["scenario"] for r in csv.DictReader(f)} == folders
