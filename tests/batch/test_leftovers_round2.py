"""Defects of the batch and run commands an earlier user round reported and left open, each test failing before
its fix: `mmusv dataset SPEC --ray auto` generated the scenarios and removed stale recordings before its batch
found it could not join Ray; `mmusv run SCENARIO --overwrite` removed the previous run's manifest.json and table
parts before the new recording was opened, so a stop (or a recording that could not be opened) in between lost
them while writing nothing new."""

from __future__ import annotations

import json
import signal
from pathlib import Path
from typing import Any

import pytest
from mcap_rechunk import no_ray_cluster
from mmusv.batch import build_dataset
from mmusv.batch.index import Entry, write_index
from mmusv.cli import main
from mmusv.errors import IoError
from mmusv.recording.info import read_info
from tiny_scenario import lidar_scenario

from .conftest import SPEC as BATCH_SPEC
from .conftest import tree, write

SPEC: dict[str, Any] = {**BATCH_SPEC, "name": "leftset2", "acquisition": {"frequency_hz": 5, "frames": 2}}
"""Three tiny LiDAR-only scenarios of two frames on the open sea."""


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``mmusv argv`` in this process: ``(exit status, stdout, stderr)``, rich's line breaks joined."""
    code = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err, out + err
    return code, out.replace("\n", " "), err.replace("\n", " ")


# ------------------------------------------------------------------------------------------------ dataset --ray


def test_a_dataset_on_a_ray_cluster_it_cannot_join_changes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`mmusv dataset SPEC --ray auto` with no cluster generated the scenario set and removed the recordings the
    spec no longer makes (of an earlier run of another spec) before the batch failed to join Ray. Now Ray is joined
    first: the command fails with nothing on disk changed, and a new output folder is not made."""
    spec = write(tmp_path / "s.yaml", SPEC)
    out = tmp_path / "out"
    gone = out / "recordings" / "gone"
    gone.mkdir(parents=True)
    (gone / "gone.mcap").write_bytes(b"an earlier run's recording")
    entry = Entry(
        name="gone",
        scenario_file="gone.yaml",
        scenario="gone",
        config_hash="0" * 16,
        seed=1,
        recording="recordings/gone/gone.mcap",
        status="complete",
        frames=2,
        frames_requested=2,
        parts=1,
        bytes=26,
    )
    write_index(out / "dataset.json", [entry], extra={"spec": {"file": "s.yaml", "name": "older", "hash": "0" * 64}})
    before = tree(out)
    no_ray_cluster(monkeypatch)
    with pytest.raises(IoError, match=r"--ray auto: cannot start or join Ray: Could not find any running Ray"):
        build_dataset(spec, out_dir=out, ray="auto")
    assert tree(out) == before and not (out / "scenarios").exists()
    fresh = tmp_path / "fresh"
    code, _out, err = _cli(["dataset", str(spec), "-o", str(fresh), "--ray", "auto"], capsys)
    assert code == 2 and err.startswith("mmusv: error: --ray auto: cannot start or join Ray"), err
    assert not fresh.exists()


# ------------------------------------------------------------------------------------------------ run --overwrite


@pytest.fixture
def previous(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[Path, Path, dict[str, str]]:
    """A scenario file, the folder of its complete run, and that folder's files (path -> digest)."""
    src = write(tmp_path / "s.yaml", lidar_scenario("keepme", frames=2))
    out = tmp_path / "out"
    code, _out, err = _cli(["run", str(src), "-o", str(out)], capsys)
    assert code == 0, err
    assert (out / "manifest.json").is_file() and list((out / "tables").glob("*/part-*.parquet"))
    return src, out, tree(out)


def test_a_stop_before_the_new_recording_opens_leaves_the_previous_run_whole(
    previous: tuple[Path, Path, dict[str, str]], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`mmusv run SCENARIO -o OUT --overwrite` removed the previous run's manifest.json and table parts (and
    replaced its scenario.yaml) before it opened the new recording: a Ctrl-C in between left the previous recording
    without its manifest and tables, and nothing new. Now they are replaced only once the new recording is open."""
    import mmusv.acquire

    src, out, before = previous
    real = mmusv.acquire.SilhouetteCache

    def stopped() -> Any:
        signal.raise_signal(signal.SIGINT)  # a Ctrl-C as the run readies its recording
        return real()

    monkeypatch.setattr(mmusv.acquire, "SilhouetteCache", stopped)
    code, _out, err = _cli(["run", str(src), "-o", str(out), "--overwrite"], capsys)
    monkeypatch.undo()
    assert code == 128 + signal.SIGINT, err
    assert tree(out) == before, sorted(set(tree(out)) ^ set(before))
    code, text, err = _cli(["info", str(out)], capsys)
    assert code == 0 and "status complete" in text, (text, err)


def test_a_recording_that_cannot_be_opened_leaves_the_previous_run_whole(
    previous: tuple[Path, Path, dict[str, str]], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same when the new recording cannot be opened (a full disk): the previous run's manifest and tables
    were gone, and the run said the disk was full."""
    from mmusv.recording import frames

    src, out, before = previous

    class Full:
        def __init__(self, path: Path, *_a: Any, **_kw: Any) -> None:
            raise IoError(f"{path}.partial: No space left on device")

    monkeypatch.setattr(frames, "FrameRecorder", Full)
    code, _out, err = _cli(["run", str(src), "-o", str(out), "--overwrite"], capsys)
    monkeypatch.undo()
    assert (
        code == 2 and "No space left on device" in err and "keepme.mcap and the rest of the run there are left" in err
    ), err
    assert tree(out) == before, sorted(set(tree(out)) ^ set(before))


def test_a_stop_while_the_new_recording_opens_leaves_a_run_that_says_so(
    previous: tuple[Path, Path, dict[str, str]], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A stop that comes while the new recording opens is held until it is open and ends the run as one during a
    frame does: the new recording, interrupted, and its manifest, with no table part of the previous run mixed in
    and no .partial left."""
    from mmusv.recording import writer

    src, out, _before = previous
    real = writer.Recording.metadata

    def metadata(self: Any, name: str, mapping: Any) -> None:
        if name == "manifest":
            signal.raise_signal(signal.SIGTERM)
        real(self, name, mapping)

    monkeypatch.setattr(writer.Recording, "metadata", metadata)
    code, _out, err = _cli(["run", str(src), "-o", str(out), "--overwrite"], capsys)
    monkeypatch.undo()
    assert code == 128 + signal.SIGTERM, err
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "interrupted" and manifest["frames_written"] == 0, manifest
    assert not list(out.glob("*.partial")) and not list((out / "tables").glob("*/part-*.parquet"))
    info = read_info(out / "keepme.mcap")
    assert info.run["status"] == "interrupted"
    code, text, err = _cli(["info", str(out)], capsys)
    assert code == 1 and "status interrupted" in text and "0 of 2 frames" in text, (text, err)  # 1: no frame
