"""Speed-up of the batch runner over one process, and the overhead of a pool process and of a Ray task.

    python benches/batch_speedup.py [--scenarios 6] [--frames 40] [--rig lidar|full] [--cpus N] [--repeat 2]

Writes a folder of ``--scenarios`` scenarios (open sea, 2 USVs with the ``--rig`` sensors: the 64-channel LiDAR
alone or the full suite, 3 targets, ``--frames`` frames at 5 Hz, each its own seed) and records it, each time
into a fresh folder, with:

* ``one process``: :func:`mmusv.run_many` with ``jobs=1``, in this process, the core on every CPU;
* ``pool, 1 process x N threads``: one spawned worker with every CPU: the same work as one process, so the
  difference is the pool's own cost (spawn, imports, pickling) — its overhead per task;
* ``pool, N processes x 1 thread``: ``--jobs N`` (N = CPUs);
* ``ray, 1 task x N CPUs``: a local Ray instance of N CPUs, each task asking for all N CPUs so tasks run one at a
  time with N core threads, the same work as one process: the difference is Ray's overhead per task;
* ``ray, N tasks x 1 CPU``: each task 1 CPU and 1 core thread, N at a time.

Ray's start-up (``ray.init``) is timed apart and not in the batch times. Every mode runs ``--repeat`` times, the
modes interleaved, and the fastest round counts. Where tasks run one at a time, the wall time not spent inside
the tasks (their own timing) divided by the tasks is the overhead per task outside the task (planning, spawn or
scheduling, imports in a fresh worker, results); against the one-process run, the difference per task is the
whole overhead. Every mode's recordings are checked byte-identical to the one-process run. The load average
(1 min) is printed before and after every run: the machine may be shared, so compare figures at the same load.
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import bench_env
import yaml
from mmusv.batch import run_many
from mmusv.batch.executors import available_cpus

RIGS: dict[str, dict[str, Any]] = {"lidar": {"preset": "lidar_only"}, "full": {}}
"""``lidar``: the detection-dataset rig (64-channel LiDAR); ``full``: the paper's suite (LiDAR, radar + PPI, four
640x480 cameras, top view)."""


def scenario(name: str, seed: int, frames: int, rig: str = "lidar") -> dict[str, Any]:
    """Two USVs with the rig ``rig``, three targets, open sea."""
    return {
        "name": name,
        "seed": seed,
        "map": {"type": "open_sea", "seed": 2},
        "acquisition": {"frequency_hz": 5, "frames": frames},
        "rigs": {"r": RIGS[rig]},
        "vessels": [
            {"id": "u1", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [80, 0]]},
            {"id": "u2", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 40], [80, 40]]},
            {"id": "t1", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[-20, 90], [100, 90]]},
            {"id": "t2", "asset": "tug_32m", "speed_mps": 3, "route": [[120, -40], [120, 120]]},
            {"id": "t3", "asset": "jet_ski_3m", "speed_mps": 6, "route": [[-60, 20], [160, 20]]},
        ],
    }


def tree(root: Path) -> dict[str, str]:
    return {
        p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file() and ".mmusv" not in p.relative_to(root).parts
    }


def load() -> float:
    return os.getloadavg()[0]


def _ray_round_trip(ray: Any, cpus: int, calls: int = 20) -> tuple[float, float]:
    """Seconds of the first call of an empty Ray task with the options the batch runner uses (``cpus`` CPUs, its
    own ``RAYON_NUM_THREADS``: a worker is started), and the mean of ``calls`` more, one after the other."""

    def noop() -> int:
        return 0

    task = ray.remote(noop).options(num_cpus=cpus, runtime_env={"env_vars": {"RAYON_NUM_THREADS": str(cpus)}})
    t0 = time.perf_counter()
    ray.get(task.remote())
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(calls):
        ray.get(task.remote())
    return first, (time.perf_counter() - t0) / calls


def main() -> int:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument("--scenarios", type=bench_env.positive_int, default=6, help="scenarios in the folder (6)")
    ap.add_argument("--frames", type=bench_env.positive_int, default=40, help="frames per scenario (40)")
    ap.add_argument("--cpus", type=bench_env.positive_int, default=available_cpus(), help="CPUs to use (default: all)")
    ap.add_argument(
        "--repeat", type=bench_env.positive_int, default=2, help="rounds over every mode; the fastest round counts"
    )
    ap.add_argument("--rig", choices=sorted(RIGS), default="lidar", help="sensor rig of the USVs (default lidar)")
    ap.add_argument("--skip-ray", action="store_true", help="leave Ray out (it needs pip install '.[ray]')")
    args = ap.parse_args()
    # before any work: without Ray the run ended in a traceback after writing and warming up
    ray = (
        None
        if args.skip_ray
        else bench_env.require("ray", "pip install '.[ray]'  (or pass --skip-ray)", "the Ray modes")
    )
    print(bench_env.machine())
    work = Path(tempfile.mkdtemp(prefix="mmusv_batch_bench_"))
    try:  # the folder goes whatever ends the run (it stayed behind a failure, each time one more)
        return measure(args, ray, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def measure(args: argparse.Namespace, ray: Any, work: Path) -> int:
    """Writes the scenarios into ``work``, records them in every mode and prints the table."""
    n, s = args.cpus, args.scenarios
    src = work / "src"
    src.mkdir()
    for i in range(s):
        (src / f"s{i:02d}.yaml").write_text(
            yaml.safe_dump(scenario(f"s{i:02d}", 100 + i, args.frames, args.rig), sort_keys=False)
        )
    warm = work / "warm"
    warm.mkdir()
    (warm / "w.yaml").write_text(yaml.safe_dump(scenario("w", 1, 1, args.rig), sort_keys=False))
    run_many(warm, out_dir=work / "warm_out")  # imports, assets and map caches of this process, outside the timings

    modes: list[tuple[str, dict[str, Any]]] = [
        ("one process", {"jobs": 1}),
        (f"pool, 1 process x {n} threads", {"jobs": 1, "cpus_per_task": n}),
        (f"pool, {n} processes x 1 thread", {"jobs": n, "cpus_per_task": 1}),
    ]
    ray_init = float("nan")
    if ray is not None:
        t0 = time.perf_counter()
        ray.init(num_cpus=n, include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
        ray_init = time.perf_counter() - t0
        noop_first, noop_warm = _ray_round_trip(ray, n)
        modes += [
            (f"ray, 1 task x {n} CPUs", {"ray": True, "cpus_per_task": n}),
            (f"ray, {n} tasks x 1 CPU", {"ray": True, "cpus_per_task": 1}),
        ]
    best: dict[str, tuple[float, float, float, float]] = {}  # wall, seconds inside the tasks, load before, after
    ref: dict[str, str] | None = None
    print(f"{s} scenarios x {args.frames} frames, rig {args.rig}, {n} CPUs, {args.repeat} rounds, {work}")
    if not args.skip_ray:
        print(f"ray.init (local, not in the batch times): {ray_init:.2f} s")
        print(
            f"ray empty task with the batch's options: first {noop_first:.2f} s (starts a worker), "
            f"then {noop_warm * 1e3:.1f} ms a task"
        )
    try:
        for r in range(args.repeat):
            for k, (label, kw) in enumerate(modes):
                out = work / f"out{r}_{k}"
                before = load()
                t0 = time.perf_counter()
                report = run_many(src, out_dir=out, **kw)
                wall = time.perf_counter() - t0
                after = load()
                assert report.ok and report.count("done") == s, report.summary()
                got = tree(out)
                ref = got if ref is None else ref
                assert got == ref, f"{label}: recordings differ from the one-process run"
                inside = sum(o.seconds for o in report.outcomes)
                print(f"round {r + 1}: {label:32s} {wall:7.2f} s   load {before:.2f} -> {after:.2f}", flush=True)
                if label not in best or wall < best[label][0]:
                    best[label] = (wall, inside, before, after)
                shutil.rmtree(out)
    finally:
        if not args.skip_ray:
            ray.shutdown()
    serial = best["one process"][0]
    print()
    print(
        f"{'mode (fastest round)':32s} {'wall s':>7s} {'speed-up':>8s} {'in tasks s':>10s} "
        f"{'outside/task s':>14s} {'load 1 min':>12s}"
    )
    for label, (wall, inside, before, after) in best.items():
        # tasks one at a time: the wall time not spent inside tasks is the runner's and the executor's, per task
        per_task = (
            f"{(wall - inside) / s:14.2f}"
            if label == "one process" or "1 process" in label or "1 task" in label
            else f"{'':14s}"
        )
        print(f"{label:32s} {wall:7.2f} {serial / wall:7.2f}x {inside:10.2f} {per_task} {before:5.2f}->{after:5.2f}")
    print()
    print("overhead per task against one process (same threads, tasks one at a time):")
    print(f"  pool: {(best[modes[1][0]][0] - serial) / s:+.2f} s")
    if not args.skip_ray:
        print(f"  ray:  {(best[modes[3][0]][0] - serial) / s:+.2f} s   (plus ray.init {ray_init:.2f} s once)")
    return 0


if __name__ == "__main__":
    bench_env.run(main)
