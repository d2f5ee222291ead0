"""``mmusv.batch.plan.task_complete``: a recording damaged after its run (cut short, overwritten) is not skipped as
complete on a re-run because its manifest says so (the docs review's: both were skipped, and the conversion then
failed on them)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from mmusv.acquire import run
from mmusv.batch.plan import task_complete
from tiny_scenario import lidar_scenario


@pytest.fixture(scope="module")
def done(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("complete") / "run"
    run(lidar_scenario("whole", frames=2), out_dir=out)
    return out


def _complete(folder: Path) -> bool:
    m = json.loads((folder / "manifest.json").read_text())
    return task_complete(folder, scenario="whole", config_hash=m["config_hash"], frames=2)


@pytest.mark.parametrize("damage", ["cut", "garbage", "empty"])
def test_a_recording_damaged_after_its_run_is_not_complete(done: Path, tmp_path: Path, damage: str) -> None:
    assert _complete(done)
    folder = tmp_path / "copy"
    shutil.copytree(done, folder)
    rec = folder / "whole.mcap"
    data = rec.read_bytes()
    rec.write_bytes({"cut": data[: len(data) // 2], "garbage": b"garbage\n", "empty": b""}[damage])
    assert not _complete(folder)
