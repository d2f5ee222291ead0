"""A batch run (``mmusv run FOLDER``) leaves a user's files in ``OUT/<stem>/`` alone, as the run of one file does.

Its tasks run with ``overwrite`` (the folder is the batch's), and each removed the folder's ``manifest.json`` before
its run: a user's ``manifest.json`` was replaced and a file of the recording's name (not a recording) was replaced
without a word, exit 0; a user's ``scenario.yaml`` was refused, but only after the ``manifest.json`` beside it
was gone.
"""

from __future__ import annotations

from pathlib import Path

from mmusv.batch import run_many
from mmusv.batch.task import execute

from .conftest import scenario, write


def _folder(tmp_path: Path) -> Path:
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("sea_a", frames=2))
    write(src / "b.yaml", scenario("sea_b", frames=2))
    return src


def _refused(tmp_path: Path, files: dict[str, bytes], said: str, *, overwrite: bool = False) -> None:
    out = tmp_path / "out"
    (out / "a").mkdir(parents=True)
    for name, data in files.items():
        (out / "a" / name).write_bytes(data)
    report = run_many(_folder(tmp_path), out_dir=out, overwrite=overwrite)
    by = {o.name: o for o in report.outcomes}
    assert by["a"].status == "failed" and said in (by["a"].error or ""), by["a"]
    assert by["b"].status == "done", by["b"]  # the others are recorded
    for name, data in files.items():
        assert (out / "a" / name).read_bytes() == data, name
    assert sorted(p.name for p in (out / "a").iterdir()) == sorted(files)


def test_a_file_of_the_recordings_name_is_not_replaced_without_overwrite(tmp_path: Path) -> None:
    _refused(tmp_path, {"sea_a.mcap": b"my notes\n"}, "sea_a.mcap is not a recording of an mmusv run")


def test_a_users_manifest_is_kept(tmp_path: Path) -> None:
    _refused(tmp_path, {"manifest.json": b'{"owner": "me"}\n'}, "manifest.json was not written by an mmusv run")


def test_a_users_scenario_yaml_is_refused_with_the_manifest_beside_it_kept(tmp_path: Path) -> None:
    files = {"manifest.json": b"{}\n", "scenario.yaml": b"my own scenario\n"}
    _refused(tmp_path, files, "was not written by an mmusv run", overwrite=True)  # --overwrite or not, as for one


def test_with_overwrite_a_file_of_the_recordings_name_is_replaced(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (out / "a").mkdir(parents=True)
    (out / "a" / "sea_a.mcap").write_bytes(b"my notes\n")
    report = run_many(_folder(tmp_path), out_dir=out, overwrite=True)
    assert report.ok, report.outcomes
    assert (out / "a" / "sea_a.mcap").read_bytes().startswith(b"\x89MCAP0\r\n")


def test_a_batchs_own_recording_damaged_since_is_recorded_again(tmp_path: Path) -> None:
    src, out = _folder(tmp_path), tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    (out / "a" / "sea_a.mcap").write_bytes(b"garbage\n")  # its run's manifest.json still names it
    report = run_many(src, out_dir=out)
    assert report.ok and [o.status for o in report.outcomes] == ["done", "skipped"], report.outcomes


def test_a_task_refuses_a_manifest_put_there_after_the_plan(tmp_path: Path) -> None:
    """The plan checks the folder; a task checks it again before it removes the folder's manifest.json."""
    from mmusv.batch.plan import plan_scenarios

    src, out = _folder(tmp_path), tmp_path / "out"
    plans = plan_scenarios(
        [src / "a.yaml"], out, frames=None, split_frames=None, overwrite=False, checks=True, run_id="r"
    )
    (task,) = plans[0].to_run
    (out / "a").mkdir(parents=True)
    (out / "a" / "manifest.json").write_text('{"owner": "me"}\n')
    from mmusv.batch.plan import prepare

    prepare(plans[0])
    res = execute(task)
    assert res.status == "failed" and "manifest.json was not written by an mmusv run" in (res.error or ""), res
    assert (out / "a" / "manifest.json").read_text() == '{"owner": "me"}\n'


# ------------------------------------------------------------------ dataset.json of an earlier run into the folder


def test_the_index_keeps_the_recordings_of_an_earlier_run_that_this_one_does_not_record(tmp_path: Path) -> None:
    """A second folder run into the same output rewrote ``dataset.json`` with its own scenarios alone: the first
    run's recordings stayed on disk, unlisted, and conversion and the studies no longer read them."""
    from mmusv.batch import read_index

    src, out = _folder(tmp_path), tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    more = tmp_path / "more"
    more.mkdir()
    write(more / "c.yaml", scenario("sea_c", frames=2))
    report = run_many(more, out_dir=out)
    assert report.ok and report.kept == ["a", "b"], report
    doc = read_index(out / "dataset.json")
    assert [(r["name"], r["status"]) for r in doc["recordings"]] == [
        ("a", "complete"),
        ("b", "complete"),
        ("c", "complete"),
    ]
    assert doc["totals"]["complete"] == 3
    # a recording removed since is not listed again
    import shutil

    shutil.rmtree(out / "b")
    report = run_many(more, out_dir=out)
    assert report.kept == ["a"] and [r["name"] for r in read_index(out / "dataset.json")["recordings"]] == ["a", "c"]


def test_a_batch_run_refuses_a_datasets_index(tmp_path: Path) -> None:
    """`mmusv run DIR -o DATASET` replaced `mmusv dataset`'s index, its spec and opv2v sections with it."""
    import pytest
    from mmusv.batch.index import write_index
    from mmusv.errors import IoError

    out = tmp_path / "out"
    out.mkdir()
    index = write_index(out / "dataset.json", [], extra={"spec": {"file": "s.yaml", "name": "tiny", "hash": "0" * 64}})
    before = index.read_bytes()
    with pytest.raises(IoError, match=r"is the index of an `mmusv dataset` run \(spec 'tiny'\)"):
        run_many(_folder(tmp_path), out_dir=out)
    assert index.read_bytes() == before and sorted(p.name for p in out.iterdir()) == ["dataset.json"]


def test_a_dataset_refuses_a_batch_runs_index(tmp_path: Path) -> None:
    """`mmusv dataset SPEC -o OUT` over a batch run's output replaced its index: the batch's recordings stayed on
    disk, unlisted."""
    import pytest
    from mmusv.batch import build_dataset
    from mmusv.errors import IoError

    from .conftest import SPEC

    src, out = _folder(tmp_path), tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    before = (out / "dataset.json").read_bytes()
    spec = write(tmp_path / "tinyset.yaml", SPEC)
    with pytest.raises(IoError, match=r"is the index of a batch run \(mmusv run DIR\), not of mmusv dataset"):
        build_dataset(spec, out_dir=out)
    assert (out / "dataset.json").read_bytes() == before and not (out / "scenarios").exists()
