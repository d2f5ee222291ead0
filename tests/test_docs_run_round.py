"""What a new user met running the documented commands (README.md, docs/*.md) and what they said: each test
is a command or call the docs give, on a tiny input, with what its output should have said."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import mmusv
import pytest
from mcap_rechunk import emptied
from mmusv.recording import read_info
from mmusv.recording.stream import FrameStream
from tiny_scenario import lidar_scenario

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rec")
    return mmusv.run(lidar_scenario("docs_run", frames=2), out_dir=out).recording


def test_the_report_names_an_incomplete_frame_as_a_frame_not_a_count(recording: Path, tmp_path: Path) -> None:
    """``mmusv info`` of a recording whose frame 0 is incomplete said ``incomplete frames left out: 0 (...)``,
    which reads as "none were left out"; it names the frame: ``incomplete frames left out: frame 0 (...)``."""
    path = emptied(recording, "/world/state", 0, tmp_path / "hollow" / recording.name)
    stream = FrameStream(read_info(path), lambda t: True)
    assert [f.index for f in stream] == [1]
    report = stream.report()
    assert report is not None
    assert "incomplete frames left out: frame 0 (" in report, report


def _cli(*args: str) -> tuple[int, str]:
    """``mmusv ARGS`` in this process: ``(exit status, stderr)``."""
    from mmusv.cli import main

    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, err.getvalue()


@pytest.mark.parametrize("command", ["preview", "convert"])
def test_a_run_folder_given_for_a_recording_names_the_recording_in_it(
    recording: Path, tmp_path: Path, command: str
) -> None:
    """The README's next step after ``mmusv run SCENARIO -o out/run`` is ``mmusv preview`` or ``mmusv convert``
    of the recording; given the run folder instead (as ``mmusv info`` and ``mmusv recover`` take it), they said
    only ``is not a file (it is a directory)`` (``... a folder without a dataset.json``). They name the recording
    the folder holds: ``it holds out/run/NAME.mcap: give that``."""
    folder = recording.parent
    extra = ["--to", "kitti", "-o", str(tmp_path / "out"), "--no-progress"] if command == "convert" else []
    code, err = _cli(command, str(folder), *extra)
    assert code == 2, err
    assert f"it holds {recording}: give that" in err, err
    assert not (tmp_path / "out").exists()


def test_info_of_a_split_recording_missing_a_part_does_not_call_it_a_partial(tmp_path: Path) -> None:
    """``mmusv run DIR --split-frames N`` (README, *Batch runs*) and ``mmusv info NAME.parts.json`` with a part
    not recorded (a failed or pending task) began ``incomplete recording (.partial, no summary or damaged)``,
    where no file is a ``.partial`` or damaged; it says what a split recording lacks."""
    import yaml

    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "split.yaml").write_text(yaml.safe_dump(lidar_scenario("split", frames=2)), encoding="utf-8")
    report = mmusv.run_many(folder, out_dir=tmp_path / "out", split_frames=1)
    assert report.ok
    manifest = tmp_path / "out" / "split" / "split.parts.json"
    (tmp_path / "out" / "split" / "parts" / "000001-000001" / "split.mcap").unlink()
    from mmusv.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        main(["info", str(manifest)])
    text = out.getvalue()
    assert ".partial, no summary or damaged" not in text, text
    assert "incomplete split recording (a part not recorded, unfinished or damaged)" in text, text


def test_two_copies_of_a_run_given_as_files_are_not_told_to_give_files(recording: Path, tmp_path: Path) -> None:
    """``mmusv convert A.mcap COPY.mcap`` (docs/exports.md: ``REC [REC ...]``) of two runs of one configuration is
    refused, and was told to "pass the recordings to convert instead of their folder", though no folder was given;
    that hint is for a batch folder that lists both, and files given one by one are told to leave one out."""
    import shutil

    copy = tmp_path / "copy" / recording.name
    copy.parent.mkdir()
    shutil.copyfile(recording, copy)
    code, err = _cli("convert", str(recording), str(copy), "--to", "kitti", "-o", str(tmp_path / "out"))
    assert code == 2, err
    assert "runs of the same scenario configuration" in err, err
    assert "instead of their folder" not in err and "give each only once: leave one of these out" in err, err


def test_dataset_after_an_edited_spec_says_which_recordings_it_removed(tmp_path: Path) -> None:
    """README, *Batch runs*: ``mmusv dataset SPEC -o DIR`` re-run "after editing the spec ... removes the recordings
    of those the spec no longer makes". It did, without a word: a user saw the same summary as a run that removed
    nothing. It names them now (``DatasetReport.removed`` and a line of the command's output)."""
    import yaml

    spec = yaml.safe_load((ROOT / "scenarios/specs/island_demo.yaml").read_text(encoding="utf-8"))
    spec["name"] = "docs_run_ds"
    spec["acquisition"] = {"frequency_hz": 2, "frames": 2}
    spec["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}}
    spec["combinations"] = [dict(c, quota=1) for c in spec["combinations"][:2]]
    path = tmp_path / "ds.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    out = tmp_path / "ds"
    code, _ = _cli("dataset", str(path), "-o", str(out))
    assert code == 0
    before = sorted(p.name for p in (out / "recordings").iterdir() if not p.name.startswith("."))
    assert len(before) == 2, before
    spec["combinations"] = spec["combinations"][:1]  # the spec edited: it no longer makes the second scenario
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    from mmusv.cli import main

    said = io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(io.StringIO()):
        assert main(["dataset", str(path), "-o", str(out)]) == 0
    after = sorted(p.name for p in (out / "recordings").iterdir() if not p.name.startswith("."))
    (gone,) = sorted(set(before) - set(after))
    text = " ".join(said.getvalue().split())
    assert f"removed those of 1 scenario the spec no longer makes ({gone})" in text, text
