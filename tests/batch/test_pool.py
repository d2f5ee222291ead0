"""The batch runner on the local pool: same bytes as one process, restart after a killed driver, a killed worker
re-run, --retries, one bad scenario never stops the others, conflicting recordings, the table."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import mmusv
import pytest
from mmusv.batch import run_many
from mmusv.cli import main
from mmusv.errors import ConfigError

from .conftest import (
    GOOD,
    WorkerKiller,
    cli,
    complete,
    descendants,
    good_folder,
    group,
    kill_driver_partway,
    scenario,
    stamps,
    tree,
    wait_for,
    write,
)


def test_pool_gives_the_bytes_of_one_process_and_reports_a_bad_scenario(
    reference: tuple[Path, dict[str, str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _src, ref = reference
    mixed = good_folder(tmp_path / "src")
    write(mixed / "d_schema.yaml", {**scenario("d_schema"), "rigs": {"r": {"lidar": {"channels": 0}}}})
    write(mixed / "e_map.yaml", {**scenario("e_map"), "map": {"type": "port", "seed": 3, "params": {"n_moored": 999}}})
    assert main(["run", str(mixed), "-o", str(tmp_path / "out"), "--jobs", "2"]) == 1
    printed = capsys.readouterr().out
    assert "3 done, 2 failed, 0 skipped, 0 retried" in printed
    assert "d_schema.yaml" in printed and "rigs.r.lidar.channels" in printed and "n_moored" in printed
    got = tree(tmp_path / "out")
    index = json.loads((tmp_path / "out/dataset.json").read_text())
    by_name = {r["name"]: r for r in index["recordings"]}
    assert by_name["d_schema"]["status"] == "failed" and by_name["d_schema"]["recording"] is None
    assert by_name["e_map"]["status"] == "failed" and "n_moored" in by_name["e_map"]["error"]
    assert not (tmp_path / "out/d_schema").exists() and not (tmp_path / "out/e_map").exists()
    # every file of the good scenarios is the same bytes as the reference run's (dataset.json differs: it lists 5)
    assert {k: v for k, v in got.items() if k != "dataset.json"} == {
        k: v for k, v in ref.items() if k != "dataset.json"
    }


def test_rerun_skips_complete_recordings_and_leaves_them_untouched(
    reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, ref = reference
    out = tmp_path / "out"
    shutil.copytree(src.parent / "out", out)  # the reference run's output
    before = stamps(out, GOOD)
    again = run_many(src, out_dir=out, jobs=2)
    assert again.summary() == "0 done, 0 failed, 3 skipped, 0 retried" and again.backend == "serial"
    assert stamps(out, GOOD) == before and tree(out) == ref


@pytest.mark.slow
def test_killed_driver_rerun_finishes_only_what_was_missing(
    reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, ref = reference
    out = tmp_path / "out"
    proc = cli("run", str(src), "-o", str(out), "--jobs", "2")
    kill_driver_partway(proc, out)
    # the pool's workers notice their driver is gone and stop (they are in its process group)
    wait_for(lambda: not group(proc.pid), timeout=30, what="the orphaned pool workers to exit", every=0.05)
    finished = complete(out)
    assert finished and finished != set(GOOD), finished
    untouched = stamps(out, finished)
    again = cli("run", str(src), "-o", str(out), "--jobs", "2")  # the same command
    stdout, stderr = again.communicate(timeout=600)
    assert again.returncode == 0, stderr
    assert f"{3 - len(finished)} done, 0 failed, {len(finished)} skipped, 0 retried" in stdout
    assert all(f"{n}.yaml │ skipped" in stdout for n in finished), stdout
    assert stamps(out, finished) == untouched
    assert tree(out) == ref


def test_a_task_waits_for_the_lock_of_a_worker_still_writing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A re-run never writes a folder that a worker of a killed run still writes: it waits for that worker's lock
    (the lock goes with the process), and gives up with a clear, retryable error after LOCK_TIMEOUT_S."""
    import fcntl
    import threading

    import mmusv.batch.task

    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=3))
    out = tmp_path / "out"
    lock = out / ".mmusv/a.task"
    lock.parent.mkdir(parents=True)
    held = os.open(lock, os.O_RDWR | os.O_CREAT)
    fcntl.flock(held, fcntl.LOCK_EX)  # "the other worker"
    reports = []
    runner = threading.Thread(target=lambda: reports.append(run_many(src, out_dir=out)))
    runner.start()
    time.sleep(1.5)
    assert runner.is_alive() and not (out / "a").exists(), "the task did not wait for the lock"
    os.close(held)
    runner.join(timeout=120)
    assert reports and reports[0].ok and complete(out) == {"a"}
    held = os.open(lock, os.O_RDWR)
    fcntl.flock(held, fcntl.LOCK_EX)
    monkeypatch.setattr(mmusv.batch.task, "LOCK_TIMEOUT_S", 0.3)
    report = run_many(src, out_dir=out, overwrite=True, retries=1)
    os.close(held)
    (a,) = report.outcomes
    assert a.status == "failed" and "is locked by another process" in str(a.error) and a.retried == 1


@pytest.mark.slow
def test_killed_worker_is_run_again_with_the_same_result(
    reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, ref = reference
    out = tmp_path / "out"
    killer = WorkerKiller(out, lambda: descendants(os.getpid()))
    killer.start()
    report = run_many(src, out_dir=out, jobs=2)
    killer.stop.set()
    assert killer.killed is not None, "no worker was caught writing"
    assert report.ok and report.count("done") == 3 and report.retried >= 1, report.summary()
    assert tree(out) == ref


def test_retries_rerun_a_failed_task_but_not_bad_input(
    reference: tuple[Path, dict[str, str]],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    _src, ref = reference
    import mmusv.acquire

    real = mmusv.acquire.run
    calls: dict[str, int] = {}

    def flaky(cfg: object, **kw: object) -> mmusv.RunResult:
        name = Path(str(cfg)).stem
        calls[name] = calls.get(name, 0) + 1
        if name == "b_sea" and calls[name] == 1:
            raise RuntimeError("disk hiccup")
        return real(cfg, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(mmusv.acquire, "run", flaky)
    folder = good_folder(tmp_path / "src")
    (folder / "z_broken.yaml").write_bytes(b"name: z\nvessels: ]\n")
    out = tmp_path / "out"
    assert main(["run", str(folder), "-o", str(out), "--retries", "2"]) == 1
    printed = capsys.readouterr().out
    assert "3 done, 1 failed, 0 skipped, 1 retried" in printed and "z_broken.yaml" in printed
    assert calls == {"a_sea": 1, "b_sea": 2, "c_sea": 1}
    assert {k: v for k, v in tree(out).items() if k != "dataset.json"} == {
        k: v for k, v in ref.items() if k != "dataset.json"
    }
    # without --retries the failure stays, with its error, and the others complete
    calls.clear()
    shutil.rmtree(out)
    report = run_many(folder, out_dir=out)
    failed = {o.name: o.error for o in report.outcomes if o.status == "failed"}
    assert set(failed) == {"b_sea", "z_broken"} and "internal error RuntimeError: disk hiccup" in str(failed["b_sea"])
    assert report.count("done") == 2 and not report.ok


def test_a_complete_recording_of_another_configuration_needs_overwrite(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=4))
    write(src / "b.yaml", scenario("b", frames=4))
    out = tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    write(src / "a.yaml", scenario("a", frames=4, seed=2))
    report = run_many(src, out_dir=out)
    (a,) = (o for o in report.outcomes if o.name == "a")
    assert a.status == "failed" and "another configuration" in str(a.error) and "--overwrite" in str(a.error)
    assert report.count("skipped") == 1
    report = run_many(src, out_dir=out, overwrite=True)
    assert report.summary() == "2 done, 0 failed, 0 skipped, 0 retried"
    assert json.loads((out / "a/manifest.json").read_text())["seed"] == 2


def test_an_interrupted_recording_is_run_again(tmp_path: Path) -> None:
    """A recording whose run stopped (Ctrl-C: status interrupted) is not complete: the next run redoes it."""
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=6))

    def stop(done: int, total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        mmusv.run(src / "a.yaml", out_dir=tmp_path / "out/a", progress=stop)
    assert json.loads((tmp_path / "out/a/manifest.json").read_text())["status"] == "interrupted"
    report = run_many(src, out_dir=tmp_path / "out")
    assert report.summary() == "1 done, 0 failed, 0 skipped, 0 retried"
    assert json.loads((tmp_path / "out/a/manifest.json").read_text())["frames_written"] == 6


def test_bad_options_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = good_folder(tmp_path / "src")
    for argv in (["--jobs", "0"], ["--retries", "-1"], ["--split-frames", "0"], ["--cpus-per-task", "0"]):
        assert main(["run", str(src), "-o", str(tmp_path / "out"), *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("mmusv: error: ") and "\n" not in err, err
    with pytest.raises(ConfigError, match="holds no"):
        run_many(tmp_path, out_dir=tmp_path / "o")


def test_ray_missing_says_how_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray now fails as if it were not installed
    src = good_folder(tmp_path / "src")
    assert main(["run", str(src), "-o", str(tmp_path / "out"), "--ray"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmusv: error: --ray needs Ray") and "pip install 'mmusv[ray]'" in err and "\n" not in err


def test_pool_workers_get_their_share_of_the_cpus(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    for n in ("a", "b"):
        write(src / f"{n}.yaml", scenario(n, frames=2))
    report = run_many(src, out_dir=tmp_path / "out", jobs=2, cpus_per_task=1)
    assert report.backend == "pool" and [o.threads for o in report.outcomes] == [["1"], ["1"]]
    again = run_many(src, out_dir=tmp_path / "out", jobs=2)
    assert again.count("skipped") == 2 and again.backend == "serial"  # nothing to run: no pool is started


def test_a_script_without_the_main_guard_is_told_so(tmp_path: Path) -> None:
    """The pool's workers import the script that starts them: a call to run or run_many at its top level runs
    again in each of them. Said where it happens (the worker refuses, naming the guard) and in the driver's lost
    tasks; the guarded script runs. Before, each worker ran the script's own mmusv.run again (a whole recording
    into the same folder), then died on the folder lock, and the batch said only 'worker lost ... out of
    memory'."""
    import subprocess
    import sys

    from .conftest import ROOT

    src = tmp_path / "src"
    src.mkdir()
    for name in ("a", "b"):
        write(src / f"{name}.yaml", scenario(name, frames=1))
    body = (
        "import mmusv\n"
        "r = mmusv.run_many('src', out_dir='out', jobs=2, lost_worker_retries=0)\n"
        "print('STATUS', sorted({o.status for o in r.outcomes}), r.outcomes[0].error)\n"
    )
    guarded = "if __name__ == '__main__':\n" + "".join(f"    {line}\n" for line in body.splitlines())
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    for name, text in (("unguarded.py", body), ("guarded.py", guarded)):
        (tmp_path / name).write_text(text, encoding="utf-8")
        shutil.rmtree(tmp_path / "out", ignore_errors=True)
        proc = subprocess.run(
            [sys.executable, name], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=240
        )
        status = [line for line in proc.stdout.splitlines() if line.startswith("STATUS")]
        assert proc.returncode == 0 and status, (name, proc.stdout[-2000:], proc.stderr[-2000:])
        if name == "guarded.py":
            assert status[0].startswith("STATUS ['done'] None"), status
        else:
            assert "STATUS ['failed'] worker lost" in status[0] and '__name__ == "__main__"' in status[0], status
            assert "mmusv.run_many was called while a worker process imported the script" in proc.stderr
