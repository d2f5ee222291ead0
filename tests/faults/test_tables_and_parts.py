"""Damaged Parquet table parts and parts manifests: the damage is named (file and why), the frames it costs are
listed, everything else is read; ``mmusv recover`` rebuilds the tables from the recording."""

from __future__ import annotations

import shutil
from pathlib import Path

import polars as pl
import pytest
from mmusv.errors import IoError, MmusvError

from .conftest import api_readers, check_against, cli_main, frames_of, scenario, write_yaml


@pytest.fixture(scope="module")
def parted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 12-frame run whose tables are flushed every 4 frames (3 parts per table)."""
    import mmusv.acquire
    from mmusv.acquire import run

    base = tmp_path_factory.mktemp("parted")
    mp = pytest.MonkeyPatch()
    mp.setattr(mmusv.acquire, "TABLE_PART_FRAMES", 4)
    try:
        run(scenario("tiny", frames=12), out_dir=base / "run")
    finally:
        mp.undo()
    assert len(list((base / "run/tables/world_state").glob("part-*.parquet"))) == 3
    return base / "run"


def test_a_damaged_parquet_part_is_named_and_its_frames_listed(parted: Path, tmp_path: Path) -> None:
    from mmusv.recording.recover import rebuild_tables
    from mmusv.recording.tables import read_table

    folder = tmp_path / "run"
    shutil.copytree(parted, folder)
    part = folder / "tables/world_state/part-00001.parquet"
    data = part.read_bytes()
    part.write_bytes(data[: len(data) // 2])  # a torn write
    got = read_table(folder / "tables", "world_state", expected=range(12))
    assert len(got.damaged) == 1 and str(part) in got.damaged[0] and "not a readable Parquet file" in got.damaged[0]
    assert got.missing == [4, 5, 6, 7]
    assert sorted(set(got.rows["frame"].to_list())) == [0, 1, 2, 3, 8, 9, 10, 11]
    code, out, err = cli_main("info", str(folder))
    assert code == 0 and "Traceback" not in err
    assert f"{part}" in out.replace("\n", "") or "part-00001.parquet" in out, out
    assert "frames 4..7 have no world_state rows" in out.replace("\n", " ")
    # the tables are rebuilt from the recording: the same rows as the run wrote
    original = pl.read_parquet(parted / "tables/world_state/*.parquet")
    import mmusv.acquire

    mp = pytest.MonkeyPatch()
    mp.setattr(mmusv.acquire, "TABLE_PART_FRAMES", 4)
    try:
        stream = rebuild_tables(folder / "tiny.mcap", folder / "tables")
    finally:
        mp.undo()
    assert stream.report() is None
    for table in ("world_state", "boxes_3d"):
        for name in ("part-00000.parquet", "part-00001.parquet", "part-00002.parquet"):
            a, b = parted / "tables" / table / name, folder / "tables" / table / name
            if a.exists():
                assert pl.read_parquet(a).equals(pl.read_parquet(b)), (table, name)
    assert read_table(folder / "tables", "world_state", expected=range(12)).rows.equals(original)


def test_a_parts_manifest_naming_a_missing_part(tmp_path: Path) -> None:
    from mmusv.batch import run_many
    from mmusv.recording.contents import summary

    src = tmp_path / "src"
    write_yaml(src / "tiny.yaml", scenario("tiny", frames=12))
    rep = run_many(src, out_dir=tmp_path / "out", split_frames=4)
    assert rep.ok
    manifest = tmp_path / "out/tiny/tiny.parts.json"
    whole, _ = frames_of(manifest)
    assert sorted(whole) == list(range(12))
    shutil.rmtree(tmp_path / "out/tiny/parts/000004-000007")
    results = api_readers(manifest)
    check_against(results, whole)
    frames, stream = results["frames"]
    assert sorted(frames) == [0, 1, 2, 3, 8, 9, 10, 11]
    assert stream.missing() == [4, 5, 6, 7]
    assert "part 4..7 (frames 4..7) is not recorded" in str(stream.report())
    s = summary(manifest)
    assert not s["complete"] and s["frames"]["missing"] == [4, 5, 6, 7]
    code, out, err = cli_main("info", str(manifest))
    assert code == 0 and "mmusv: warning:" in out and "4..7" in out, out
    with pytest.raises(MmusvError, match="not recorded"):
        from mmusv.recording.messages import frame_messages

        frame_messages(manifest, 5)
    # a manifest that is not JSON, or names a part outside its folder: one line naming the file
    manifest.write_text('{"format": "mmusv.parts", "version": 1, "parts": [', encoding="utf-8")
    for call in (lambda: summary(manifest), lambda: frames_of(manifest)):
        with pytest.raises(IoError, match=r"tiny\.parts\.json"):
            call()
    code, _out, err = cli_main("info", str(manifest))
    assert code == 2 and err.startswith("mmusv: error: ") and "tiny.parts.json" in err and err.count("\n") == 1


def test_a_part_swapped_for_another_recording_is_named(tmp_path: Path) -> None:
    # A whole 12-frame recording of the same scenario put where the part of frames 4..7 was: `mmusv info` said
    # "complete, 12 frames" and convert wrote frames twice. And a part's file swapped for another part's.
    from mmusv.acquire import run
    from mmusv.batch import run_many

    src = tmp_path / "src"
    write_yaml(src / "tiny.yaml", scenario("tiny", frames=12))
    assert run_many(src, out_dir=tmp_path / "out", split_frames=4).ok
    whole = run(src / "tiny.yaml", out_dir=tmp_path / "whole").recording
    manifest = tmp_path / "out/tiny/tiny.parts.json"
    part = tmp_path / "out/tiny/parts/000004-000007/tiny.mcap"
    kept = part.read_bytes()
    shutil.copyfile(whole, part)
    code, _out, err = cli_main("info", str(manifest))
    assert code == 2 and "is a whole recording, not a part" in err and "4..7" in err, err
    part.write_bytes((tmp_path / "out/tiny/parts/000008-000011/tiny.mcap").read_bytes())
    code, _out, err = cli_main("info", str(manifest))
    assert code == 2 and "starts at frame 8, the manifest says 4" in err, err
    part.write_bytes(kept)
    assert cli_main("info", str(manifest))[0] == 0


@pytest.mark.parametrize(
    ("name", "make"),
    [
        ("tables", lambda p: p.write_bytes(b"")),
        ("tables/boxes_2d", lambda p: p.write_bytes(b"")),
        ("manifest.json", lambda p: p.mkdir()),
        ("scenario.yaml", lambda p: p.mkdir()),
        # "already exists; pass --overwrite"; "left by an interrupted run", then "cannot write ...: Is a directory"
        ("tiny.mcap", lambda p: p.mkdir()),
        ("tiny.mcap.partial", lambda p: p.mkdir()),
    ],
    ids=["tables-file", "table-file", "manifest-folder", "scenario-folder", "recording-folder", "partial-folder"],
)
def test_a_name_the_run_writes_taken_by_the_wrong_kind_is_refused_before_writing(
    tmp_path: Path, name: str, make: object
) -> None:
    """A file named ``tables`` in the output folder failed the run only after its last frame: the recording was
    finished as ``complete``, with no tables and no manifest, and the error said only "Not a directory" (found by
    the malformed-input review). Now it is refused before anything is written."""
    src = write_yaml(tmp_path / "tiny.yaml", scenario("tiny", frames=2))
    out = tmp_path / "out"
    target = out / name
    target.parent.mkdir(parents=True, exist_ok=True)
    make(target)  # type: ignore[operator]
    code, _out, err = cli_main("run", str(src), "-o", str(out))
    assert code == 2 and "Traceback" not in err, err
    assert str(target) in err and ("is not a folder" in err or "is a folder" in err), err
    assert not (out / "tiny.mcap").is_file() and not (out / "tiny.mcap.partial").is_file()
    code, _out, err = cli_main("run", str(src), "-o", str(out), "--overwrite")
    assert code == 2 and str(target) in err and "move it out of" in err, err


def test_tables_that_cannot_be_written_at_the_end_leave_a_failed_recording(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The last table part was written after the recording was finished as ``complete``: a failure there left a
    recording that said complete, without its tables. Now the tables are written first, and the recording and the
    manifest say ``failed`` and why."""
    import errno
    import json
    import os

    from mmusv.acquire import run
    from mmusv.recording.info import read_info
    from mmusv.recording.tables import TableWriter

    def full(self: TableWriter) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "out/tables/world_state"))

    monkeypatch.setattr(TableWriter, "flush", full)
    with pytest.raises(IoError, match="while writing the tables"):
        run(scenario("tiny", frames=2), out_dir=tmp_path / "out")
    info = read_info(tmp_path / "out/tiny.mcap")
    assert info.run.get("status") == "failed" and "writing the tables" in info.run.get("error", ""), info.run
    manifest = json.loads((tmp_path / "out/manifest.json").read_text())
    assert manifest["status"] == "failed" and manifest["tables"] == []
