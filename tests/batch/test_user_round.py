"""A perception researcher's round on batch runs and datasets: a changed spec re-run into its dataset folder records
what changed (it failed every changed scenario, telling to pass an `--overwrite` that `mmusv dataset` did not take)
and drops what the spec no longer makes; an output folder blocked by a file fails that scenario alone (the batch
stopped before recording any); a `--frames 2` batch no longer replaces complete recordings of every frame; a
Ctrl-C on a pool leaves every started recording finished (a second signal interrupted the clean-up, leaving a
`.partial` without its manifest) and the index saying what finished; a spec's environment error names the field
inside the value; `--ray auto` without a cluster says what to do. Each test failed before its fix."""

from __future__ import annotations

import copy
import json
import os
import shutil
import signal
import time
from pathlib import Path
from typing import Any

import pytest
from mmusv.batch import build_dataset, read_index, run_many
from mmusv.batch import executors as batch_executors
from mmusv.batch import runner as batch_runner
from mmusv.cli import main
from mmusv.errors import ConfigError, IoError
from mmusv.generate import load_spec

from .conftest import SPEC as BATCH_SPEC
from .conftest import cli, complete, scenario, stamps, tree, wait_for, write

SPEC: dict[str, Any] = {**BATCH_SPEC, "name": "roundset", "acquisition": {"frequency_hz": 5, "frames": 2}}
"""Three tiny LiDAR-only scenarios of two frames on the open sea: a dataset in a few seconds."""


def _spec(path: Path, **changes: Any) -> Path:
    data = copy.deepcopy(SPEC)
    data.update(changes)
    return write(path, data)


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """SPEC's dataset, built once."""
    base = tmp_path_factory.mktemp("round")
    out = base / "ds"
    rep = build_dataset(_spec(base / "roundset.yaml"), out_dir=out)
    assert rep.ok and not rep.shortfall and rep.batch.count("done") == 3
    return out


# ------------------------------------------------------------------------------------------------ datasets


def test_a_changed_spec_records_its_changed_scenarios_again(dataset: Path, tmp_path: Path) -> None:
    """Another seed changes every scenario: the same `mmusv dataset` command into the folder failed every one
    ("complete recording of another configuration; pass --overwrite", an option `mmusv dataset` did not have)
    and converted nothing. Now it records them again, into the bytes of a fresh dataset of the new spec."""
    out = tmp_path / "ds"
    shutil.copytree(dataset, out)
    changed = _spec(tmp_path / "roundset.yaml", seed=8)
    rep = build_dataset(changed, out_dir=out)
    assert rep.ok and rep.generated and rep.batch.summary() == "3 done, 0 failed, 0 skipped, 0 retried"
    fresh = tmp_path / "fresh"
    assert build_dataset(changed, out_dir=fresh).ok
    assert tree(out) == tree(fresh)


def test_a_spec_that_makes_fewer_scenarios_drops_their_recordings(dataset: Path, tmp_path: Path) -> None:
    """One scenario fewer: its recording stayed in DIR/recordings beside the dataset.json that no longer listed it
    (a tool reading the recordings folder read it too). Now the folder holds what the index lists."""
    out = tmp_path / "ds"
    shutil.copytree(dataset, out)
    combos = copy.deepcopy(SPEC["combinations"])
    combos[0]["quota"] = 1
    rep = build_dataset(_spec(tmp_path / "roundset.yaml", combinations=combos), out_dir=out)
    assert rep.ok and rep.batch.summary() == "0 done, 0 failed, 2 skipped, 0 retried" and rep.converted == 4
    doc = read_index(out)
    assert (
        _names(out / "recordings")
        == sorted(r["name"] for r in doc["recordings"])
        == [
            "crossing_near_2usv_small_000",
            "head_on_near_2usv_medium_000",
        ]
    )
    kept = {k: v for k, v in tree(dataset / "recordings").items() if not k.startswith("crossing_near_2usv_small_001")}
    assert tree(out / "recordings") == kept
    assert sorted(doc["opv2v"]["sources"]) == _names(out / "recordings")
    # and its task file went with it (an empty `.mmusv/crossing_near_2usv_small_001.task` stayed)
    assert sorted(p.stem for p in (out / "recordings/.mmusv").iterdir()) == _names(out / "recordings")


def test_a_recording_the_index_does_not_list_is_replaced_only_with_overwrite(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without the index (deleted), a recording of another configuration is not known as the dataset's own: the
    run refuses it, and the `--overwrite` its message names is one `mmusv dataset` takes."""
    out = tmp_path / "ds"
    shutil.copytree(dataset, out)
    (out / "dataset.json").unlink()
    changed = _spec(tmp_path / "roundset.yaml", seed=8)
    assert main(["dataset", str(changed), "-o", str(out)]) == 1
    printed = capsys.readouterr().out
    assert "3 failed" in printed and "another configuration" in printed and "--overwrite" in printed
    assert main(["dataset", str(changed), "-o", str(out), "--overwrite"]) == 0
    assert "3 done, 0 failed" in capsys.readouterr().out
    assert read_index(out)["totals"]["complete"] == 3


# ------------------------------------------------------------------------------------------------ batch runs


def test_an_output_folder_blocked_by_a_file_fails_that_scenario_alone(tmp_path: Path) -> None:
    """OUT/b was a file: the batch ended at once with "OUT/b/b.parts.json: Not a directory" (no split was asked
    for) and recorded none of the others."""
    src = tmp_path / "src"
    src.mkdir()
    for n in ("a", "b", "c"):
        write(src / f"{n}.yaml", scenario(n, frames=2))
    out = tmp_path / "out"
    out.mkdir()
    (out / "b").write_text("not a folder")
    rep = run_many(src, out_dir=out)
    assert rep.summary() == "2 done, 1 failed, 0 skipped, 0 retried"
    (b,) = (o for o in rep.outcomes if o.name == "b")
    assert str(src / "b.yaml") in str(b.error) and f"{out / 'b'} is a file" in str(b.error) and b.frames == 0
    assert "parts.json" not in str(b.error)
    assert [r["status"] for r in read_index(out)["recordings"]] == ["complete", "failed", "complete"]
    assert (out / "b").read_text() == "not a folder"


def test_a_run_of_fewer_frames_does_not_replace_complete_recordings(tmp_path: Path) -> None:
    """`mmusv run DIR --frames 2` into a folder of complete 4-frame recordings silently replaced each by a 2-frame
    one (the run of one file refuses: "already exists; pass --overwrite"); now each is refused by name, left as it
    was, and replaced with overwrite."""
    src = tmp_path / "src"
    src.mkdir()
    for n in ("a", "b"):
        write(src / f"{n}.yaml", scenario(n, frames=4))
    out = tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    before = stamps(out, ["a", "b"])
    rep = run_many(src, out_dir=out, frames=2)
    assert rep.summary() == "0 done, 2 failed, 0 skipped, 0 retried"
    for o in rep.outcomes:
        assert f"{out / o.name / o.name}.mcap is a complete recording of frames 0..3" in str(o.error)
        assert "frames 0..1" in str(o.error) and "--overwrite" in str(o.error)
    assert stamps(out, ["a", "b"]) == before
    assert run_many(src, out_dir=out).summary() == "0 done, 0 failed, 2 skipped, 0 retried"
    assert run_many(src, out_dir=out, frames=2, overwrite=True).ok
    assert json.loads((out / "a/manifest.json").read_text())["frames_written"] == 2
    # the same for a recording made of parts
    split = tmp_path / "split"
    assert run_many(src, out_dir=split, split_frames=2).ok
    rep = run_many(src, out_dir=split, frames=3)
    assert rep.count("failed") == 2 and "complete parts of a recording of frames 0..3" in str(rep.outcomes[0].error)


def test_an_interrupted_batch_indexes_what_finished_on_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A Ctrl-C that reaches the driver after a worker finished its recording but before the driver heard of it
    left that recording "pending" in dataset.json, though complete on disk."""
    src = tmp_path / "src"
    src.mkdir()
    for n in ("a", "b"):
        write(src / f"{n}.yaml", scenario(n, frames=2))

    def run_then_stop(task: Any) -> Any:
        batch_executors.execute(task)
        raise KeyboardInterrupt

    monkeypatch.setattr(batch_runner, "_executor", lambda *a: batch_executors.SerialExecutor(run=run_then_stop))
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_many(src, out_dir=out)
    assert [(r["name"], r["status"], r["frames"]) for r in read_index(out)["recordings"]] == [
        ("a", "complete", 2),
        ("b", "pending", 0),
    ]


def test_a_second_stop_signal_does_not_interrupt_the_recordings_clean_up(monkeypatch: pytest.MonkeyPatch) -> None:
    """A pool worker's first SIGINT/SIGTERM stops its recording (KeyboardInterrupt); the next, while it finishes the
    recording as interrupted (a Ctrl-C reaches every worker, and the driver SIGTERMs them right after), raised
    again inside that clean-up."""
    from mmusv.held_signals import note_stop

    monkeypatch.setattr(batch_executors, "_IN_TASK", True)
    monkeypatch.setattr(batch_executors, "_STOPPING", False)
    try:
        with pytest.raises(KeyboardInterrupt):
            batch_executors._stop(signal.SIGINT, None)
        try:
            batch_executors._stop(signal.SIGTERM, None)  # ignored: the task is finishing
        except KeyboardInterrupt:
            pytest.fail("a second signal interrupted the task again, inside its clean-up")
        assert batch_executors._STOPPING
    finally:  # the worker's handler notes its stop (held_signals): not left noted for the tests after this one
        note_stop(None)


@pytest.mark.slow
def test_ctrl_c_on_a_pool_leaves_every_started_recording_finished(tmp_path: Path) -> None:
    """Ctrl-C (SIGINT to the whole process group) on `mmusv run DIR --jobs 2`: the recording in progress was left a
    `.partial` without a manifest (5 runs out of 5), and the index could call a finished recording pending. Now
    each ends complete or interrupted, the exit status is 130 without a traceback, and the same command finishes
    the batch into the bytes of an uninterrupted run."""
    src = tmp_path / "src"
    src.mkdir()
    for n in ("a", "b", "c"):
        write(src / f"{n}.yaml", scenario(n, frames=60))
    ref = tmp_path / "ref"
    assert run_many(src, out_dir=ref, jobs=2).ok
    out = tmp_path / "out"
    proc = cli("run", str(src), "-o", str(out), "--jobs", "2")
    seen: dict[Path, float] = {}

    def recording_for_a_while() -> bool:
        """A recording in its frame loop: its .partial there for 0.3 s (a stop while the recording file is being
        opened, before mmusv.acquire's frame loop, is another matter, and a Ctrl-C by hand lands there rarely)."""
        now = time.monotonic()
        live = set(out.rglob("*.mcap.partial"))
        for p in set(seen) - live:
            del seen[p]
        for p in live:
            seen.setdefault(p, now)
        return any(now - t >= 0.3 for t in seen.values()) or proc.poll() is not None

    try:
        wait_for(recording_for_a_while, timeout=240, what="a recording in progress for 0.3 s")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
    _stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, stderr
    assert not list(out.rglob("*.partial"))
    statuses = {m.parent.name: json.loads(m.read_text())["status"] for m in out.glob("*/manifest.json")}
    assert set(statuses.values()) <= {"complete", "interrupted"} and "interrupted" in statuses.values(), statuses
    for d in _names(out):
        assert d in statuses, f"{d} has no manifest"
    indexed = {r["name"] for r in read_index(out)["recordings"] if r["status"] == "complete"}
    assert indexed == complete(out)
    again = cli("run", str(src), "-o", str(out), "--jobs", "2")
    _stdout, stderr = again.communicate(timeout=600)
    assert again.returncode == 0, stderr
    assert tree(out) == tree(ref)


# ------------------------------------------------------------------------------------------------ messages


def test_a_spec_environment_error_names_the_field_inside_the_value() -> None:
    """`environment: {sea: {preset: W2}}` said only "environment.sea = {...}: Extra inputs are not permitted";
    a scenario names environment.sea.preset and the keys allowed there."""
    for sea, field, hint in (
        ({"preset": "W2"}, "environment.sea.preset = 'W2'", "allowed keys: state, hs_m"),
        ([{"state": 3}, {"stat": 4}], "environment.sea.stat = 4", "did you mean 'state'?"),
    ):
        with pytest.raises(ConfigError) as exc:
            load_spec({**copy.deepcopy(SPEC), "environment": {"sea": sea}})
        assert field in str(exc.value) and hint in str(exc.value), str(exc.value)
    with pytest.raises(ConfigError, match=r"environment\.wave = 'W5': allowed presets are W0"):
        load_spec({**copy.deepcopy(SPEC), "environment": {"wave": ["W0", "W5"]}})


def test_ray_auto_without_a_cluster_says_what_to_do(monkeypatch: pytest.MonkeyPatch) -> None:
    """Ray's own advice named its `--address` flag and RAY_ADDRESS; mmusv takes --ray HOST:PORT."""
    ray = pytest.importorskip("ray")
    from mmusv.batch.ray_backend import RayExecutor

    def no_cluster(**_kw: Any) -> None:
        raise ConnectionError(
            "Could not find any running Ray instance. Please specify the one to connect to by setting `--address` "
            "flag or `RAY_ADDRESS` environment variable."
        )

    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", no_cluster)
    with pytest.raises(IoError) as exc:
        RayExecutor("auto", num_cpus=1, max_retries=0)
    msg = str(exc.value)
    assert msg.startswith("--ray auto: cannot start or join Ray: Could not find any running Ray instance")
    assert "ray start --head" in msg and "--ray HOST:PORT" in msg and "`--address`" not in msg


def test_a_broken_pool_leaves_no_thread_to_race_the_exit(tmp_path: Path) -> None:
    """A stop signal ends the pool's idle workers at once, which breaks the pool: the runner dropped it (shut down
    without waiting) and started another, and the dropped pool's manager thread could still be closing its wake-up
    pipe when the interpreter's exit hook wrote to it: "Exception ignored in: <module 'threading'> ... OSError:
    [Errno 9] Bad file descriptor", a traceback after the one-line stop message (1 run of `mmusv run DIR --jobs 2`
    in 7 ended by SIGTERM). Closing the executor now waits for every pool it dropped."""
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=60))
    (plan,) = batch_runner.plan_scenarios(
        [src / "a.yaml"], tmp_path / "out", frames=None, split_frames=None, overwrite=False, checks=True, run_id="x"
    )
    pool = batch_executors.PoolExecutor(1, 1)
    pool.submit(plan.to_run[0])
    assert pool._pool is not None
    manager = pool._pool._executor_manager_thread  # type: ignore[attr-defined]
    (worker,) = pool._pool._processes.values()  # type: ignore[attr-defined]
    wait_for(lambda: any((tmp_path / "out").rglob("*.mcap.partial")), timeout=120, what="the recording to start")
    os.kill(worker.pid, signal.SIGKILL)
    _task, res = pool.next_done()
    assert res.lost
    pool.close(cancel=True)
    assert manager is not None and not manager.is_alive()


def test_a_folders_yml_scenarios_are_run_too(tmp_path: Path) -> None:
    """A folder's ``*.yml`` scenarios were skipped without a word (the run of one file takes them); a ``.yaml``
    and a ``.yml`` of one stem still clash by name."""
    from mmusv.batch.plan import scenario_files

    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=1))
    write(src / "b.yml", scenario("b", frames=1))
    assert [f.name for f in scenario_files(src)] == ["a.yaml", "b.yml"]
    rep = run_many(src, out_dir=tmp_path / "out")
    assert rep.summary() == "2 done, 0 failed, 0 skipped, 0 retried"
    write(src / "a.yml", scenario("a", frames=1))
    with pytest.raises(ConfigError) as err:
        scenario_files(src)
    # named by their files ("files ['a'] share a file stem" named neither)
    assert f"scenario files {src / 'a.yaml'} and {src / 'a.yml'} share a file stem" in str(err.value), err.value


def test_a_folder_whose_scenarios_are_in_a_folder_below_says_so(tmp_path: Path) -> None:
    from mmusv.batch.plan import scenario_files

    src = tmp_path / "src"
    (src / "set1").mkdir(parents=True)
    write(src / "set1" / "a.yaml", scenario("a", frames=1))
    with pytest.raises(
        ConfigError,
        match=r"holds no \*\.yaml or \*\.yml scenarios \(folders below are not searched: "
        r"set1/ holds some; give it\)",
    ):
        scenario_files(src)


def test_scenario_files_whose_stems_differ_only_in_case_are_refused(tmp_path: Path) -> None:
    """``a.yaml`` and ``A.yaml`` were recorded into ``OUT/a`` and ``OUT/A``: one folder on macOS or Windows."""
    from mmusv.batch.plan import scenario_files

    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=1))
    write(src / "A.yaml", scenario("b", frames=1))
    for given in (src, [src / "a.yaml", src / "A.yaml"]):
        with pytest.raises(ConfigError, match=r"'A' and 'a' have stems that differ only in case"):
            scenario_files(given)


def test_the_detection_studys_generate_records_a_changed_spec_again(tmp_path: Path) -> None:
    """`study detection --generate SPEC -o OUT` after editing the spec: every scenario failed ("a complete
    recording of another configuration; pass --overwrite", which the study does not take). Now the changed ones
    are recorded again and the study reads the new recordings."""
    from mmusv.recording import read_info
    from mmusv.studies.detection.sources import generate_dataset

    out = tmp_path / "det"
    first = generate_dataset(out, spec=_spec(tmp_path / "roundset.yaml"))
    hashes = {read_info(p).config_hash for p in first}
    again = generate_dataset(out, spec=_spec(tmp_path / "roundset.yaml", seed=8))
    assert len(again) == 3 and not hashes & {read_info(p).config_hash for p in again}
