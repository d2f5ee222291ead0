"""Speed-up of the batch runner over one process, and the overhead of a pool process and of a Ray task.

    python benches/batch_speedup.py [--scenarios 6] [--frames 40] [--cpus N] [--skip-ray]

Writes a folder of ``--scenarios`` LiDAR-only scenarios (open sea, 2 USVs with the default 64-channel LiDAR and
3 targets, ``--frames`` frames at 5 Hz, each its own seed) and records it, each time into a fresh folder, with:

* ``one process``: :func:`mmusv.run_many` with ``jobs=1``, in this process, the core on every CPU;
* ``pool, 1 process x N threads``: one spawned worker with every CPU: the same work as one process, so the
  difference is the pool's own cost (spawn, imports, pickling) — its overhead per task;
* ``pool, N processes x 1 thread``: ``--jobs N`` (N = CPUs);
* ``ray, 1 task x N CPUs``: a local Ray instance of N CPUs, each task asking for all N CPUs so tasks run one at a
  time with N core threads, the same work as one process: the difference is Ray's overhead per task;
* ``ray, N tasks x 1 CPU``: each task 1 CPU and 1 core thread, N at a time.

Ray's start-up (``ray.init``) is timed apart and not in the batch times. Every mode's recordings are checked to
be byte-identical to the one-process run. The load average (1 min) is printed before and after every mode: the
machine may be shared, so compare figures taken at the same load.
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import yaml
from mmusv.batch import run_many
from mmusv.batch.executors import available_cpus


def scenario(name: str, seed: int, frames: int) -> dict[str, Any]:
    """A detection-dataset-like scenario: two USVs with the default LiDAR, three targets, open sea."""
    return {
        "name": name,
        "seed": seed,
        "map": {"type": "open_sea", "seed": 2},
        "acquisition": {"frequency_hz": 5, "frames": frames},
        "rigs": {"r": {"preset": "lidar_only"}},
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


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenarios", type=int, default=6)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--cpus", type=int, default=available_cpus(), help="CPUs to use (default: all)")
    ap.add_argument("--skip-ray", action="store_true")
    args = ap.parse_args()
    n = args.cpus
    work = Path(tempfile.mkdtemp(prefix="mmusv_batch_bench_"))
    src = work / "src"
    src.mkdir()
    for i in range(args.scenarios):
        (src / f"s{i:02d}.yaml").write_text(
            yaml.safe_dump(scenario(f"s{i:02d}", 100 + i, args.frames), sort_keys=False)
        )
    warm = work / "warm"
    warm.mkdir()
    (warm / "w.yaml").write_text(yaml.safe_dump(scenario("w", 1, 1), sort_keys=False))
    run_many(warm, out_dir=work / "warm_out")  # imports, assets and map caches of this process, outside the timings

    rows: list[tuple[str, float, float, float]] = []
    ref: dict[str, str] | None = None
    k = 0

    def timed(label: str, **kw: Any) -> float:
        nonlocal ref, k
        k += 1
        out = work / f"out{k}"
        before = load()
        t0 = time.perf_counter()
        report = run_many(src, out_dir=out, **kw)
        wall = time.perf_counter() - t0
        after = load()
        assert report.ok and report.count("done") == args.scenarios, report.summary()
        got = tree(out)
        if ref is None:
            ref = got
        assert got == ref, f"{label}: recordings differ from the one-process run"
        rows.append((label, wall, before, after))
        print(f"{label:32s} {wall:7.2f} s   load {before:.2f} -> {after:.2f}", flush=True)
        shutil.rmtree(out)
        return wall

    print(f"{args.scenarios} scenarios x {args.frames} frames, {n} CPUs, {work}")
    serial = timed("one process", jobs=1)
    pool1 = timed(f"pool, 1 process x {n} threads", jobs=1, cpus_per_task=n)
    pool_n = timed(f"pool, {n} processes x 1 thread", jobs=n, cpus_per_task=1)
    ray_init = ray_1 = ray_n = float("nan")
    if not args.skip_ray:
        import ray

        t0 = time.perf_counter()
        ray.init(num_cpus=n, include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
        ray_init = time.perf_counter() - t0
        print(f"{'ray.init (local, not in the batch times)':32s} {ray_init:7.2f} s")
        try:
            ray_1 = timed(f"ray, 1 task x {n} CPUs", ray=True, cpus_per_task=n)
            ray_n = timed(f"ray, {n} tasks x 1 CPU", ray=True, cpus_per_task=1)
        finally:
            ray.shutdown()
    s = args.scenarios
    print()
    print(f"{'mode':32s} {'wall s':>8s} {'speed-up':>9s} {'load 1 min':>14s}")
    for label, wall, before, after in rows:
        print(f"{label:32s} {wall:8.2f} {serial / wall:8.2f}x {before:6.2f}->{after:5.2f}")
    print()
    print(f"pool overhead per task: {(pool1 - serial) / s:+.2f} s   (pool 1 x {n} threads vs one process, / {s} tasks)")
    if not args.skip_ray:
        print(
            f"ray overhead per task:  {(ray_1 - serial) / s:+.2f} s   (ray 1 task x {n} CPUs vs one process, / {s} tasks)"
        )
        print(f"ray start-up (ray.init, local): {ray_init:.2f} s")
    print(
        f"speed-up over one process: pool {serial / pool_n:.2f}x"
        + ("" if args.skip_ray else f", ray {serial / ray_n:.2f}x")
    )
    shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
