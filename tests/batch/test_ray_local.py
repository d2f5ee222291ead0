"""`mmusv run ... --ray` with no address starts its own local Ray instance (and stops it): a file given with
batch options runs as a batch of one into OUT/<stem>/, with the bytes of a run in one process."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.batch import run_many

from .conftest import cli, scenario, tree, write


@pytest.mark.slow
def test_ray_without_an_address_starts_a_local_instance(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    file = write(src / "solo.yaml", scenario("solo", frames=8))
    proc = cli("run", str(file), "-o", str(tmp_path / "ray"), "--ray")
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    assert "1 done, 0 failed, 0 skipped, 0 retried" in stdout and "on ray" in stdout
    assert run_many([file], out_dir=tmp_path / "one").ok
    assert tree(tmp_path / "ray") == tree(tmp_path / "one") and "solo/solo.mcap" in tree(tmp_path / "one")
