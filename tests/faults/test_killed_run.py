"""A run killed with SIGKILL at a random frame: every reader recovers its complete frames, ``mmusv recover``
finishes it into a valid MCAP with its tables, and ``mmusv run`` on the folder redoes it cleanly (and says so)."""

from __future__ import annotations

import json
import random
import shutil
import subprocess
import sys
from pathlib import Path

import polars as pl
import pytest

from .conftest import ROOT, api_readers, check_against, child_env, cli_main, frames_of, scenario, write_yaml

FRAMES = 110

_KILLER = """
import os, signal, sys
import mmusv
k = int(sys.argv[3])
def progress(done, total):
    if done == k:
        os.kill(os.getpid(), signal.SIGKILL)
mmusv.run(sys.argv[1], out_dir=sys.argv[2], progress=progress)
"""


@pytest.fixture(scope="module")
def killed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, int]:
    """``(scenario file, reference run folder, frame of the kill)``; the killed run's folder is ``killed/``."""
    from mmusv.acquire import run

    base = tmp_path_factory.mktemp("killed")
    src = write_yaml(base / "dense.yaml", scenario("dense", frames=FRAMES, dense=True))
    run(src, out_dir=base / "reference")
    k = random.Random(13).randrange(80, 105)  # the first 4 MiB chunk (about 70 frames) is on disk by then
    _run_killed(src, base / "killed", k)
    return src, base / "reference", k


def _run_killed(src: Path, out: Path, k: int, *, frames: int | None = None) -> None:
    """``mmusv.run(src, out_dir=out[, frames=frames])`` in a child killed with SIGKILL once frame ``k`` is done."""
    killer = (
        _KILLER if frames is None else _KILLER.replace("progress=progress)", f"progress=progress, frames={frames})")
    )
    proc = subprocess.run(
        [sys.executable, "-c", killer, str(src), str(out), str(k)],
        cwd=ROOT,
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == -9, proc.stderr


def _copy_of_killed(ref: Path, to: Path) -> Path:
    """A copy, at ``to``, of the killed run's folder (beside the reference run ``ref``): each test changes its own."""
    shutil.copytree(ref.parent / "killed", to)
    return to


def test_every_reader_recovers_the_complete_frames_of_a_killed_run(killed: tuple[Path, Path, int]) -> None:
    _src, ref, k = killed
    folder = ref.parent / "killed"
    partial = folder / "dense.mcap.partial"
    assert partial.is_file() and not (folder / "dense.mcap").exists() and not (folder / "manifest.json").exists()
    reference, _ = frames_of(ref / "dense.mcap")
    results = api_readers(partial)
    check_against(results, reference)
    frames, stream = results["frames"]
    assert 30 <= len(frames) < k and sorted(frames) == list(range(len(frames)))
    assert stream.missing() == list(range(len(frames), FRAMES)) and "the run did not finish" in str(stream.report())
    code, out, err = cli_main("info", str(folder))
    assert code == 0 and err == "" and f"{len(frames)} of {FRAMES} frames" in out and "mmusv recover" in out, out
    code, out, err = cli_main("preview", str(partial), "--frame", "3", "-o", str(folder.parent / "p.png"))
    assert code == 0 and (folder.parent / "p.png").is_file(), err
    code, out, err = cli_main("convert", str(partial), "-o", str(folder.parent / "c"), "--no-progress", "--no-split")
    assert code == 0 and f"{len(frames)} frames" in out, (out, err)
    from mmusv.scenario_checks import MmusvWarning
    from mmusv.studies.detection.data import read_recording

    with pytest.warns(MmusvWarning, match=f"{len(frames)} of {FRAMES} frames read"):
        seq = read_recording(partial)
    assert len(seq.frames) == len(frames)


def test_recover_finishes_the_partial_file_and_rebuilds_its_tables(
    killed: tuple[Path, Path, int], tmp_path: Path
) -> None:
    from mcap.reader import make_reader

    _src, ref, _k = killed
    folder = _copy_of_killed(ref, tmp_path / "killed")
    partial = folder / "dense.mcap.partial"
    kept, _ = frames_of(partial)
    code, out, err = cli_main("recover", str(folder))
    assert code == 0, err
    assert f"recovered {len(kept)} of {FRAMES} frames" in out
    rec = folder / "dense.mcap"
    assert rec.is_file() and not partial.exists()
    with rec.open("rb") as f:  # the official reader: summary, statistics and index are there
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None and summary.chunk_indexes
        assert summary.statistics.message_count == 5 * len(kept)
        run_meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}["run"]
    assert run_meta["status"] == "interrupted" and run_meta["frames_written"] == str(len(kept))
    got, stream = frames_of(rec)
    assert got == kept and stream.complete
    manifest = (folder / "manifest.json").read_text()
    assert '"status": "interrupted"' in manifest and f'"frames_written": {len(kept)}' in manifest
    for table in ("world_state", "boxes_3d"):
        want = pl.read_parquet(ref / "tables" / table / "*.parquet").filter(pl.col("frame") < len(kept))
        have = pl.read_parquet(folder / "tables" / table / "*.parquet")
        assert have.height > 0 and have.equals(want), table
    code, out, _ = cli_main("info", str(rec))
    assert code == 0 and "mmusv: warning" not in out and "status interrupted" in out


def test_run_on_a_killed_run_redoes_it_cleanly_and_says_so(killed: tuple[Path, Path, int], tmp_path: Path) -> None:
    src, ref, _k = killed
    folder = _copy_of_killed(ref, tmp_path / "killed")
    code, _out, err = cli_main("run", str(src), "-o", str(folder))
    assert code == 0, err
    assert "was left by an interrupted run" in err and "clean redo" in err
    assert (folder / "dense.mcap").read_bytes() == (ref / "dense.mcap").read_bytes()
    assert not (folder / "dense.mcap.partial").exists()
    for table in ("world_state", "boxes_3d"):
        assert pl.read_parquet(folder / "tables" / table / "*.parquet").equals(
            pl.read_parquet(ref / "tables" / table / "*.parquet")
        )


def test_recover_leaves_a_partial_without_a_complete_frame_as_it_was(
    killed: tuple[Path, Path, int], tmp_path: Path
) -> None:
    # The first 64 KiB of the killed run's file: its header and metadata, no whole chunk. Recovering it used to write
    # a recording of no frame, report success and delete the .partial (and the tables there).
    _src, ref, _k = killed
    folder = _copy_of_killed(ref, tmp_path / "early")
    partial = folder / "dense.mcap.partial"
    partial.write_bytes(partial.read_bytes()[:65536])
    tables = sorted(p.relative_to(folder) for p in (folder / "tables").rglob("*.parquet"))
    code, _out, err = cli_main("recover", str(folder))
    assert code != 0 and "no complete frame" in err and "left as it was" in err, err
    assert partial.stat().st_size == 65536 and not (folder / "dense.mcap").exists()
    assert sorted(p.relative_to(folder) for p in (folder / "tables").rglob("*.parquet")) == tables


def test_a_killed_run_of_its_first_n_frames_is_reported_against_n(tmp_path: Path) -> None:
    """`mmusv run --frames N` killed: `mmusv info` and `mmusv recover` counted its frames against the scenario's
    acquisition.frames ("4 of 50 frames" for a run of 30), since only the run metadata written at the end said N;
    the recording now says what it set out to write from its start."""
    src = write_yaml(tmp_path / "dense.yaml", scenario("dense", frames=FRAMES, dense=True))
    asked, k = FRAMES - 20, 85
    _run_killed(src, tmp_path / "killed", k, frames=asked)
    frames, stream = frames_of(tmp_path / "killed" / "dense.mcap.partial")
    assert 30 <= len(frames) < k and stream.missing() == list(range(len(frames), asked))
    code, out, _err = cli_main("info", str(tmp_path / "killed"))
    assert code == 0 and f"{len(frames)} of {asked} frames" in out, out
    code, out, err = cli_main("recover", str(tmp_path / "killed"))
    assert code == 0 and f"recovered {len(frames)} of {asked} frames" in out, (out, err)
    manifest = (tmp_path / "killed" / "manifest.json").read_text(encoding="utf-8")
    assert f'"frames_requested": {asked}' in manifest and f'"frames_written": {len(frames)}' in manifest


def test_a_plan_out_of_bounds_is_not_believed() -> None:
    """A damaged manifest record's frame plan (10**18 frames, negative, not a number) is ignored, not iterated:
    the readers then count against the scenario's acquisition.frames, as for recordings that predate the plan."""
    from mmusv.recording.info import _planned

    assert _planned({"first_frame": "40", "frames_requested": "30"}) == (40, 30)
    for first, count in (("0", str(10**18)), ("-1", "5"), ("0", "0"), ("x", "5"), (None, "5")):
        meta = {"frames_requested": count} if first is None else {"first_frame": first, "frames_requested": count}
        assert _planned(meta) is None, meta


def test_recover_beside_another_finished_run_is_refused(killed: tuple[Path, Path, int], tmp_path: Path) -> None:
    """A review's: recovering a ``.partial`` in a folder holding another recording's finished run rebuilt the
    folder's tables and manifest.json from the ``.partial`` alone, and that run's tables were gone. It is refused
    now, naming the other recording, with every file as it was; ``--overwrite`` replaces them."""
    _src, ref, _k = killed
    folder = _copy_of_killed(ref, tmp_path / "killed")
    shutil.copy(ref / "dense.mcap", folder / "other.mcap")
    (folder / "manifest.json").write_text(json.dumps({"recording": "other.mcap", "status": "complete"}))
    before = {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}
    code, _out, err = cli_main("recover", str(folder))
    assert code != 0 and "holds the run of another recording, other.mcap" in err and "left as it was" in err, err
    assert {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()} == before
    code, _out, err = cli_main("recover", str(folder), "--overwrite")
    assert code == 0, err
    assert json.loads((folder / "manifest.json").read_text())["recording"] == "dense.mcap"
    assert (folder / "other.mcap").is_file()
