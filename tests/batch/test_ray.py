"""The batch runner on Ray (one local instance of 2 CPUs shared by the module): the same bytes as the local
pool, a killed driver re-run finishes only what was missing, a killed worker is retried by Ray, a bad scenario
is reported while the others complete, tasks get as many core threads as CPUs, parts and `mmusv dataset`."""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
import ray
from mmusv.batch import build_dataset, run_many
from mmusv.cli import main
from mmusv.recording.info import read_info
from mmusv.recording.stream import FrameStream

from .conftest import (
    GOOD,
    SPEC,
    WorkerKiller,
    cli,
    complete,
    descendants,
    good_folder,
    holders,
    kill_driver_partway,
    scenario,
    stamps,
    tree,
    wait_for,
    write,
)


@pytest.fixture(scope="module")
def address() -> Iterator[str]:
    """A local Ray instance with 2 CPUs for the whole module; its address lets child processes join it."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
    try:
        yield str(ray.get_runtime_context().gcs_address)
    finally:
        ray.shutdown()


def test_ray_gives_the_bytes_of_the_pool_and_reports_a_bad_scenario(
    address: str, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    _src, ref = reference
    mixed = good_folder(tmp_path / "src")
    write(mixed / "d_schema.yaml", {**scenario("d_schema"), "rigs": {"r": {"lidar": {"channels": 0}}}})
    write(mixed / "e_map.yaml", {**scenario("e_map"), "map": {"type": "port", "seed": 3, "params": {"n_moored": 999}}})
    report = run_many(mixed, out_dir=tmp_path / "out", ray=True)
    assert report.backend == "ray" and report.summary() == "3 done, 2 failed, 0 skipped, 0 retried"
    failed = {o.name: str(o.error) for o in report.outcomes if o.status == "failed"}
    assert "rigs.r.lidar.channels" in failed["d_schema"] and "n_moored" in failed["e_map"]
    # each task asked Ray for 1 CPU and ran the core with 1 thread
    assert all(o.threads == ["1"] for o in report.outcomes if o.status == "done")
    got = tree(tmp_path / "out")
    assert {k: v for k, v in got.items() if k != "dataset.json"} == {
        k: v for k, v in ref.items() if k != "dataset.json"
    }


@pytest.mark.slow
def test_killed_driver_rerun_on_ray_finishes_only_what_was_missing(
    address: str, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, ref = reference
    out = tmp_path / "out"
    proc = cli("run", str(src), "-o", str(out), "--ray", address)
    kill_driver_partway(proc, out)
    # Ray ends the tasks of a dead driver: wait until no worker holds a file of the output
    wait_for(lambda: not holders(out, descendants(os.getpid())), timeout=60, what="Ray to stop the dead driver's tasks")
    finished = complete(out)
    assert finished and finished != set(GOOD), finished
    untouched = stamps(out, finished)
    again = cli("run", str(src), "-o", str(out), "--ray", address)  # the same command
    stdout, stderr = again.communicate(timeout=600)
    assert again.returncode == 0, stderr
    assert f"{3 - len(finished)} done, 0 failed, {len(finished)} skipped, 0 retried" in stdout
    assert all(f"{n}.yaml │ skipped" in stdout for n in finished), stdout
    assert stamps(out, finished) == untouched
    assert tree(out) == ref


@pytest.mark.slow
def test_a_killed_ray_worker_is_retried_with_the_same_result(
    address: str, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, ref = reference
    out = tmp_path / "out"
    killer = WorkerKiller(out, lambda: descendants(os.getpid()))
    killer.start()
    report = run_many(src, out_dir=out, ray=True)
    killer.stop.set()
    assert killer.killed is not None, "no Ray worker was caught writing"
    assert report.ok and report.count("done") == 3
    assert report.retried >= 1, "the killed attempt should count as retried"
    assert tree(out) == ref


def test_cli_joins_the_cluster_of_ray_address_and_splits_long_scenarios(
    address: str, reference: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    src, _ref = reference
    out = tmp_path / "out"
    proc = cli(  # "auto": the cluster named by RAY_ADDRESS
        "run",
        str(src),
        "-o",
        str(out),
        "--ray",
        "auto",
        "--split-frames",
        "25",
        "--cpus-per-task",
        "2",
        extra_env={"RAY_ADDRESS": address},
    )
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    assert "3 done, 0 failed, 0 skipped, 0 retried" in stdout and "on ray" in stdout
    index = json.loads((out / "dataset.json").read_text())
    assert [r["parts"] for r in index["recordings"]] == [3, 3, 3]
    for name in GOOD:
        parts = read_info(out / name / f"{name}.parts.json")
        whole = read_info(_ref_recording(reference, name))
        assert parts.run["status"] == "complete" and len(parts.parts) == 3
        assert _frames(parts) == _frames(whole)
        for part in parts.parts:  # each part was written by a task with 2 CPUs and 2 core threads
            assert json.loads((part.parent / "manifest.json").read_text())["status"] == "complete"


def _ref_recording(reference: tuple[Path, dict[str, str]], name: str) -> Path:
    src, _ = reference
    return src.parent / "out" / name / f"{name}.mcap"


def _frames(info: object) -> list[tuple[int, dict[str, bytes]]]:
    return [
        (f.index, {t: m.SerializeToString() for t, m in sorted(f.messages.items())})
        for f in FrameStream(info, lambda t: True)  # type: ignore[arg-type]
    ]


def test_tasks_get_the_cpus_they_ask_for(address: str, tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", scenario("a", frames=2))
    report = run_many(src, out_dir=tmp_path / "out", ray=True, cpus_per_task=2)
    assert report.ok and report.outcomes[0].threads == ["2"]
    assert main(["run", str(src), "-o", str(tmp_path / "o2"), "--ray", address, "--cpus-per-task", "3"]) == 2


@pytest.mark.slow
def test_dataset_on_ray_is_the_dataset_of_the_pool(address: str, tmp_path: Path) -> None:
    spec = write(tmp_path / "spec.yaml", SPEC)
    on_ray = build_dataset(spec, out_dir=tmp_path / "ray", ray=True)
    on_pool = build_dataset(spec, out_dir=tmp_path / "pool", jobs=2)
    assert on_ray.ok and on_pool.ok and on_ray.batch.backend == "ray" and on_pool.batch.backend == "pool"
    assert tree(tmp_path / "ray") == tree(tmp_path / "pool")
