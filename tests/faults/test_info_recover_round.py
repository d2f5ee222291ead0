"""A tester's round on ``mmusv info`` of a batch and ``mmusv recover``, each finding a test that failed before its
fix:

* ``mmusv info`` on a batch's folder left out, without a word and with exit status 0, a run whose recording was
  gone although ``dataset.json`` and the run's ``manifest.json`` name it (``mmusv convert`` refuses the batch);
  a recording of no readable frame was exit status 0 too;
* ``mmusv info`` said ``mmusv recover`` rebuilds a finished run's missing tables, and ``recover`` refused ("nothing
  to recover"): it now rebuilds a finished run's missing or damaged tables, the bytes the run wrote;
* a stop (Ctrl-C) or an error while ``recover`` wrote left its ``.mcap.recovering`` file and rebuilt tables behind.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from mcap_rechunk import killed_copy
from mmusv.errors import IoError

from .conftest import ROOT, child_env, chunk_spans, cli_main, scenario, write_yaml


def _files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (relative path -> bytes), and every folder (-> ``b"<dir>"``)."""
    return {str(p.relative_to(folder)): b"<dir>" if p.is_dir() else p.read_bytes() for p in sorted(folder.rglob("*"))}


# ------------------------------------------------------------------------------------------- info of a batch


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A batch's folder: scenarios ``a``, ``b``, ``c`` (2 frames each), ``dataset.json`` listing them."""
    from mmusv.batch import run_many

    base = tmp_path_factory.mktemp("batch")
    for name in "abc":
        write_yaml(base / "src" / f"{name}.yaml", scenario(name, frames=2))
    assert run_many(base / "src", out_dir=base / "out").ok
    return base / "out"


def _rows(out: str) -> dict[str, list[str]]:
    return {ln.split("│")[1].strip(): [c.strip() for c in ln.split("│")[2:-1]] for ln in out.splitlines() if "│" in ln}


def test_info_of_a_batch_lists_a_recording_that_is_gone_and_exits_1(
    batch: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "250")  # one line a row
    code, out, err = cli_main("info", str(batch))
    assert code == 0 and "3 recordings below" in out and "missing" not in out, (out, err)
    copy = tmp_path / "batch2"
    shutil.copytree(batch, copy)
    (copy / "c" / "c.mcap").unlink()
    code, out, err = cli_main("info", str(copy))
    assert code == 1 and "Traceback" not in err, (out, err)
    assert "2 recordings below" in out and "1 missing" in out, out
    row = _rows(out)["c/c.mcap"]
    assert row[:4] == ["c", "missing", "0 of 2", "u"], row
    assert "dataset.json (c: status complete)" in row[4] and "c/manifest.json (status complete)" in row[4], row
    assert "1 recording missing" in out, out
    # the run folder itself: one line naming the file and what names it
    code, out, err = cli_main("info", str(copy / "c"))
    assert code == 2 and "c.mcap is gone, though manifest.json names it (status complete)" in err, err
    # the whole run folder gone: dataset.json still names it
    shutil.rmtree(copy / "c")
    code, out, _ = cli_main("info", str(copy))
    assert code == 1 and _rows(out)["c/c.mcap"][1] == "missing" and "dataset.json (c: status complete)" in out, out
    # a killed run's .partial in its place is there (a row of its own, as before), not missing
    shutil.copytree(batch / "c", copy / "c")
    killed_copy(batch / "c" / "c.mcap", copy / "c" / "c.mcap.partial", messages=None)
    (copy / "c" / "c.mcap").unlink()
    code, out, _ = cli_main("info", str(copy))
    assert code == 0 and "missing" not in out and _rows(out)["c/c.mcap.partial"][1] == "unfinished", out


def test_info_of_a_batch_exits_1_for_a_recording_of_no_readable_frame(
    batch: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "250")
    copy = tmp_path / "batch2"
    shutil.copytree(batch, copy)
    # a killed run's .partial holding no complete frame
    killed_copy(batch / "b" / "b.mcap", copy / "b" / "b.mcap.partial", messages=0)
    (copy / "b" / "b.mcap").unlink()
    code, out, err = cli_main("info", str(copy))
    assert code == 1 and _rows(out)["b/b.mcap.partial"][2] == "0 of 2", (out, err)
    assert "1 recording holds no readable frame" in out, out
    # a finished recording whose every chunk is damaged
    shutil.copytree(batch / "b", copy / "b", dirs_exist_ok=True)
    (copy / "b" / "b.mcap.partial").unlink()
    data = bytearray((copy / "b" / "b.mcap").read_bytes())
    for _start, end in chunk_spans(batch / "b" / "b.mcap"):
        data[end - 40] ^= 0x21
    (copy / "b" / "b.mcap").write_bytes(bytes(data))
    code, out, err = cli_main("info", str(copy))
    assert code == 1 and _rows(out)["b/b.mcap"][2] == "0 of 2" and "holds no readable frame" in out, (out, err)
    # each on its own exits 1 as well: it exited 0, so `mmusv info rec && mmusv convert rec` went on to nothing
    for one in (copy / "b" / "b.mcap", copy / "b"):
        code, out, err = cli_main("info", str(one))
        assert code == 1 and "0 of 2 frames" in out and "Traceback" not in err, (out, err)
    killed_copy(batch / "b" / "b.mcap", copy / "b" / "b.mcap.partial", messages=0)
    (copy / "b" / "b.mcap").unlink()
    code, out, err = cli_main("info", str(copy / "b" / "b.mcap.partial"))
    assert code == 1 and "nothing to recover" in out, (out, err)
    # one that reads in part still warns and exits 0
    killed_copy(batch / "b" / "b.mcap", copy / "b" / "b.mcap.partial", messages=8)
    code, out, err = cli_main("info", str(copy / "b" / "b.mcap.partial"))
    assert code == 0 and "mmusv recover" in out, (out, err)
    assert re.search(r", 1 of 2 frames,", " ".join(out.split())), out


def test_info_of_a_batch_names_a_listing_that_cannot_be_read_and_exits_1(
    batch: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A batch whose dataset.json was cut short (or a run's manifest.json damaged) listed its recordings and exited
    0, passing over the file without a word, though convert and the study refuse that folder and info could no
    longer say whether the recordings it names are there. Another tool's file of that name stays passed over."""
    monkeypatch.setenv("COLUMNS", "250")
    copy = tmp_path / "batch2"
    shutil.copytree(batch, copy)
    index = (copy / "dataset.json").read_bytes()
    (copy / "dataset.json").write_bytes(index[:150])
    code, out, err = cli_main("info", str(copy))
    assert code == 1 and "Traceback" not in err and "3 recordings below" in out, (out, err)
    row = _rows(out)["dataset.json"]
    assert row[1] == "unreadable listing" and row[4].startswith("not JSON: "), row
    assert "1 file listing recordings (dataset.json, manifest.json) cannot be read" in out, out
    code, _, err = cli_main("convert", str(copy), "--to", "kitti", "-o", str(tmp_path / "conv"))
    assert code == 2 and "dataset.json is not a JSON file" in err, err  # what info now warns of
    # an index of mmusv's format that its reader refuses, and a run's manifest.json that is no object
    (copy / "dataset.json").write_bytes(index.replace(b'"status": "complete"', b'"status": "bogus"', 1))
    (copy / "b" / "manifest.json").write_text('["mmusv_version"]')
    code, out, _ = cli_main("info", str(copy))
    rows = _rows(out)
    assert code == 1 and "status = 'bogus': must be one of" in rows["dataset.json"][4], out
    assert rows["b/manifest.json"][4] == "holds a JSON list, not an object", out
    # another tool's dataset.json is none of mmusv's business
    (copy / "dataset.json").write_text("{ not json, and not ours")
    (copy / "b" / "manifest.json").write_bytes((batch / "b" / "manifest.json").read_bytes())
    code, out, err = cli_main("info", str(copy))
    assert code == 0 and "unreadable listing" not in out, (out, err)


# ------------------------------------------------------------------------- recover: tables of a finished run


@pytest.fixture(scope="module")
def parted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 12-frame run whose tables are flushed every 4 frames (3 parts per table)."""
    import mmusv.acquire
    from mmusv.acquire import run

    base = tmp_path_factory.mktemp("parted")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mmusv.acquire, "TABLE_PART_FRAMES", 4)
        run(scenario("tiny", frames=12), out_dir=base / "run")
    assert len(list((base / "run/tables/world_state").glob("part-*.parquet"))) == 3
    return base / "run"


def test_recover_rebuilds_the_missing_or_damaged_tables_of_a_finished_run_byte_for_byte(
    parted: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mmusv.acquire

    monkeypatch.setattr(mmusv.acquire, "TABLE_PART_FRAMES", 4)  # as the run flushed them
    original = _files(parted)
    folder = tmp_path / "run"
    # tables removed: info's hint, and recover does what it says
    shutil.copytree(parted, folder)
    shutil.rmtree(folder / "tables")
    code, out, _ = cli_main("info", str(folder))
    assert code == 0 and f"`mmusv recover {folder}` rebuilds it from tiny.mcap" in " ".join(out.split()), out
    code, out, err = cli_main("recover", str(folder))
    assert code == 0 and f"rebuilt the tables of {folder / 'tiny.mcap'}" in out and "12 of 12 frames" in out, err
    assert f"before: {folder / 'tables'} does not exist" in out, out
    assert _files(folder) == original  # the tables the run wrote, byte for byte; nothing else changed
    # whole tables: nothing to recover, nothing touched
    code, out, err = cli_main("recover", str(folder))
    assert code == 2 and "nothing to recover" in err and "tiny.mcap is finished and its tables are whole" in err, err
    assert _files(folder) == original
    # a damaged part, a table folder gone (manifest.json lists it): named by info, rebuilt by recover (given the file)
    part = folder / "tables/world_state/part-00001.parquet"
    part.write_bytes(part.read_bytes()[:100])
    shutil.rmtree(folder / "tables/boxes_3d")
    code, out, _ = cli_main("info", str(folder))
    flat = " ".join(out.split())
    assert code == 0 and "part-00001.parquet" in flat and "boxes_3d does not exist (manifest.json lists it)" in flat
    assert f"`mmusv recover {folder}` rebuilds the tables from the recording" in flat, out
    code, out, err = cli_main("recover", str(folder / "tiny.mcap"))
    assert code == 0 and "rebuilt the tables" in out and "part-00001.parquet" in out, (out, err)
    assert _files(folder) == original


def test_recover_keeps_table_rows_a_damaged_recording_lacks(
    small: Path, chunky: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path
) -> None:
    """Tables rebuilt from a recording that lacks frames (a damaged chunk) would lose the rows the tables still
    hold of them: refused, nothing changed."""
    src, _reference = chunky
    folder = tmp_path / "run"
    shutil.copytree(small, folder)
    data = bytearray(src.read_bytes())
    spans = chunk_spans(src)
    data[spans[len(spans) // 2][1] - 40] ^= 0x21  # one frame's chunk
    (folder / "tiny.mcap").write_bytes(bytes(data))
    shutil.rmtree(folder / "tables/boxes_3d")  # the tables are damaged too
    before = _files(folder)
    code, _out, err = cli_main("recover", str(folder))
    assert code == 2 and "whose rows its tables still hold" in err and "left as it was" in err, err
    assert _files(folder) == before


# ------------------------------------------------------------------------------------ recover: stopped midway


def _killed_run(small: Path, folder: Path) -> Path:
    """A run folder as a run killed after frame 7 leaves it: the ``.partial`` and its scenario, no manifest."""
    folder.mkdir()
    shutil.copy2(small / "scenario.yaml", folder / "scenario.yaml")
    n = sum(1 for _ in _messages(small / "tiny.mcap")) * 8 // 12
    killed_copy(small / "tiny.mcap", folder / "tiny.mcap.partial", messages=n)
    return folder


def test_recover_of_a_batch_folder_names_the_runs_below_it_to_recover(batch: Path, small: Path, tmp_path: Path) -> None:
    # A batch killed with two runs unfinished: recover of its folder said only "nothing to recover in OUT: it holds
    # no .mcap.partial ... nor a finished .mcap", though the runs below it held them; it now names them and the
    # command for one, and recovers nothing (recover takes one run at a time).
    copy = tmp_path / "out"
    shutil.copytree(batch, copy)
    for name in "ab":
        shutil.rmtree(copy / name)
        _killed_run(small, copy / name)
    before = _files(copy)
    code, out, err = cli_main("recover", str(copy))
    assert code == 2 and f"nothing to recover in {copy}" in err, (out, err)
    assert f"2 below it hold a killed run's .partial: {copy / 'a'}, {copy / 'b'}; recover each: mmusv recover " in err
    assert _files(copy) == before
    # every run finished: it names them as the folders whose tables recover rebuilds
    code, out, err = cli_main("recover", str(batch))
    assert code == 2 and f"3 below it hold a finished recording: {batch / 'a'}, {batch / 'b'}, {batch / 'c'}" in err


def _messages(path: Path) -> list[object]:
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return list(make_reader(f).iter_messages())


@pytest.mark.parametrize("fault", [KeyboardInterrupt, lambda: OSError(28, "No space left on device")])
def test_a_recover_stopped_or_failing_midway_leaves_the_folder_as_it_was(
    small: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fault: type[BaseException]
) -> None:
    from mcap.writer import Writer
    from mmusv.recording.recover import recover

    folder = _killed_run(small, tmp_path / "killed")
    before = _files(folder)
    add = Writer.add_message
    calls = []

    def failing(self: Writer, *args: object, **kwargs: object) -> None:
        calls.append(1)
        if len(calls) == 5:  # the recording half written, the tables built
            raise fault()
        add(self, *args, **kwargs)

    monkeypatch.setattr(Writer, "add_message", failing)
    with pytest.raises(KeyboardInterrupt if fault is KeyboardInterrupt else IoError):
        recover(folder)
    assert _files(folder) == before  # no .recovering, no tables, no manifest.json: the .partial as it was
    assert not (tmp_path / "killed" / "tables.rebuilding").exists()
    monkeypatch.setattr(Writer, "add_message", add)
    res = recover(folder)  # and a second try finishes it
    assert res.frames == list(range(8)) and (folder / "tiny.mcap").is_file() and (folder / "tables").is_dir()


def test_recover_refuses_a_folder_a_run_is_still_writing(small: Path, tmp_path: Path) -> None:
    """recover did not take the folder's lock: a .partial a run was still writing was finished under it, its tables
    replaced."""
    from mmusv.recording.guard import FolderLock
    from mmusv.recording.recover import recover

    folder = _killed_run(small, tmp_path / "running")
    before = _files(folder)
    with FolderLock(folder, what="mmusv run"):  # as the run holds it while it writes
        with pytest.raises(IoError, match=r"running is being written by another mmusv process"):
            recover(folder)
        assert _files(folder) == before
    assert recover(folder).frames == list(range(8))


_STOPPER = """
import os, signal, sys
from mcap.writer import Writer
add, calls = Writer.add_message, []
def stop(self, *args, **kwargs):
    calls.append(1)
    if len(calls) == 5:
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C, halfway through the recording
    add(self, *args, **kwargs)
Writer.add_message = stop
from mmusv.cli import main
sys.exit(main(["recover", sys.argv[1]]))
"""


def test_ctrl_c_during_recover_leaves_the_folder_as_it_was(small: Path, tmp_path: Path) -> None:
    folder = _killed_run(small, tmp_path / "killed")
    before = _files(folder)
    proc = subprocess.run(
        [sys.executable, "-c", _STOPPER, str(folder)],
        cwd=ROOT,
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 130 and proc.stderr.strip() == "mmusv: interrupted", (proc.returncode, proc.stderr)
    assert _files(folder) == before
    code, out, err = cli_main("recover", str(folder))
    assert code == 0 and "recovered 8 of 12 frames" in out, (out, err)


# ------------------------------------------------------------ info: a killed --overwrite run beside a finished one


def test_info_names_the_partial_of_a_killed_overwrite_run_beside_a_finished_recording(
    small: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``mmusv run --overwrite`` killed (SIGKILL, a power cut) leaves the earlier finished ``tiny.mcap`` beside the
    new run's ``.partial``, with the new run's tables and scenario.yaml and no manifest. ``mmusv info`` on the folder,
    and on a folder of such folders, showed the earlier recording complete with no problem, as if the tables were
    its own; now a warning names the ``.partial`` and the way out (``recover --overwrite``), which works."""
    monkeypatch.setenv("COLUMNS", "400")  # one line a row and a warning
    folder = tmp_path / "runs" / "run"
    shutil.copytree(small, folder)
    (folder / "manifest.json").unlink()  # removed when the killed run opened its recording
    n = sum(1 for _ in _messages(small / "tiny.mcap")) * 8 // 12
    killed_copy(small / "tiny.mcap", folder / "tiny.mcap.partial", messages=n)
    said = (
        f"{folder}/tiny.mcap.partial lies beside it: a later run of it (mmusv run --overwrite) was killed, so the "
        f"tables and scenario.yaml here are that run's, not tiny.mcap's; `mmusv recover {folder} --overwrite` "
        "finishes it into tiny.mcap with its tables"
    )
    code, out, err = cli_main("info", str(folder))
    assert code == 0 and f"mmusv: warning: {said}" in " ".join(out.split()), (out, err)
    assert "rebuilds the tables" not in out  # not from the earlier recording: they are the killed run's
    code, out, err = cli_main("info", str(tmp_path / "runs"))
    row = _rows(out)["run/tiny.mcap"]
    assert row[-1].startswith("run/tiny.mcap.partial lies beside it: a later run of it"), row
    assert "1 recording unfinished, damaged or unreadable" in out
    code, out, err = cli_main("recover", str(folder), "--overwrite")
    assert code == 0, (out, err)
    code, out, err = cli_main("info", str(folder))
    assert code == 0 and "warning" not in out and "status interrupted" in out, out
