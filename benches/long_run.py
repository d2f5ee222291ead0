"""Long runs stay flat (not a test; issue #30): a 10,000-frame LiDAR-only run and a 1,000-frame full-suite run of
the README's main job (``scenarios/port_entry.yaml``: 3 USVs), each in a fresh process. Every 10 % of a run it
samples the resident set size (VmRSS), the open file descriptors, the threads (the OS's count, the core's rayon
pool included) and the frames/s since the previous sample, then prints the rows at 10 % and 100 % side by side:
flat columns are the point (no leak of memory, descriptors or threads, no slow-down).

Usage: ``python benches/long_run.py [--lidar-frames 10000] [--full-frames 1000] [--only lidar|full] [-o OUT]``
(shorter runs for a quick look: ``--lidar-frames 1000 --full-frames 50``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import bench_env
import yaml

ROOT = Path(__file__).resolve().parents[1]


def scenario(kind: str, frames: int) -> dict[str, Any]:
    """The main job with ``frames`` frames: the paper's full suite (``full``) or the LiDAR-only preset (``lidar``)."""
    sc: dict[str, Any] = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = frames
    if kind == "lidar":
        sc["rigs"] = {"usv_standard": {"preset": "lidar_only"}}
    return sc


def sample() -> dict[str, float]:
    """RSS (MB), open file descriptors and OS threads of this process, from ``/proc/self``."""
    status = dict(line.split(":", 1) for line in Path("/proc/self/status").read_text().splitlines() if ":" in line)
    return {
        "rss_mb": int(status["VmRSS"].split()[0]) / 1024.0,
        "fds": float(len(os.listdir("/proc/self/fd"))),
        "threads": float(int(status["Threads"])),
    }


def child(kind: str, frames: int, out: str) -> None:
    """One run in this process; prints one JSON line per 10 % of it."""
    from mmusv.acquire import run

    marks = {max(1, round(frames * p / 10)) for p in range(1, 11)}
    last = [time.perf_counter(), 0]

    def progress(done: int, total: int) -> None:
        if done in marks:
            now = time.perf_counter()
            rate = (done - last[1]) / (now - last[0]) if now > last[0] else float("nan")
            last[:] = [now, done]
            print(json.dumps({"done": done, "total": total, "fps": rate, **sample()}), flush=True)

    res = run(scenario(kind, frames), out_dir=out, overwrite=True, progress=progress, checks=False)
    print(json.dumps({"end": True, "frames": res.frames_written, "seconds": res.seconds, "bytes": res.bytes}))


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument(
        "--lidar-frames", type=bench_env.positive_int, default=10_000, help="frames of the LiDAR-only run (10000)"
    )
    ap.add_argument(
        "--full-frames", type=bench_env.positive_int, default=1_000, help="frames of the full-suite run (1000)"
    )
    ap.add_argument("--only", choices=("lidar", "full"), default=None, help="run only one of the two")
    ap.add_argument("-o", "--output", default=None, help="output folder (default: a temporary one, removed)")
    ap.add_argument("--child", nargs=3, metavar=("KIND", "FRAMES", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]), args.child[2])
        return
    runs = [("lidar", args.lidar_frames), ("full", args.full_frames)]
    print(bench_env.machine())
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(args.output or tmp)
        for kind, frames in runs:
            if args.only not in (None, kind):
                continue
            print(
                f"== {kind}: {frames} frames of port_entry ({'LiDAR-only preset' if kind == 'lidar' else 'full suite'})"
            )
            print(f"{'done':>6} {'%':>4} {'RSS MB':>8} {'fds':>5} {'threads':>8} {'frames/s':>9}", flush=True)
            proc = subprocess.Popen(
                [sys.executable, __file__, "--child", kind, str(frames), str(base / kind)],
                stdout=subprocess.PIPE,
                text=True,
            )
            assert proc.stdout is not None
            rows = []
            for line in proc.stdout:
                row = json.loads(line)
                if row.get("end"):
                    print(
                        f"{row['frames']} frames in {row['seconds']:.1f} s "
                        f"({row['frames'] / row['seconds']:.2f} frames/s overall), {row['bytes'] / 1e6:.1f} MB"
                    )
                    continue
                rows.append(row)
                pct = 100 * row["done"] / row["total"]
                print(
                    f"{row['done']:>6} {pct:>4.0f} {row['rss_mb']:>8.1f} {row['fds']:>5.0f} {row['threads']:>8.0f} "
                    f"{row['fps']:>9.2f}",
                    flush=True,
                )
            if proc.wait() != 0:
                raise SystemExit(f"the {kind} run failed (exit status {proc.returncode})")
            if rows:
                a, b = rows[0], rows[-1]
                print(
                    f"10 % -> 100 %: RSS {a['rss_mb']:.1f} -> {b['rss_mb']:.1f} MB, fds {a['fds']:.0f} -> "
                    f"{b['fds']:.0f}, threads {a['threads']:.0f} -> {b['threads']:.0f}, frames/s {a['fps']:.2f} -> "
                    f"{b['fps']:.2f}\n"
                )


if __name__ == "__main__":
    bench_env.run(main)
