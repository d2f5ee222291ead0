"""Memory over a long run (not a test): the README's main job with a small-resolution rig for speed (3 USVs;
16-channel LiDAR, two 128x96 cameras, a 128x128 top view, a short radar with a 128-pixel PPI), run for N frames
(default 1,000). Every ``--every`` frames it prints the resident set size (VmRSS) and the peak so far
(ru_maxrss): a flat column is the point. Run it under ``/usr/bin/time -v`` for the peak as the OS sees it.

Usage: ``python benches/memory_long_run.py [--frames 1000] [--every 100] [-o OUT]``.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path
from typing import Any

import bench_env
import yaml
from mmusv.acquire import run

ROOT = Path(__file__).resolve().parents[1]


def small_rig_scenario(frames: int) -> dict[str, Any]:
    """``scenarios/port_entry.yaml`` with ``frames`` frames and a small rig on every USV."""
    sc: dict[str, Any] = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = frames
    sc["rigs"] = {
        "usv_standard": {
            "lidar": {"channels": 16, "points_per_second": 16 * 360 * 5},
            "radar": {"range_m": 1000, "azimuth_bins": 256, "rays_el": 8, "ppi_size_px": 128},
            "cameras": [
                {"name": "front", "resolution": [128, 96], "mount": {"point": "camera_front"}},
                {"name": "rear", "resolution": [128, 96], "mount": {"point": "camera_rear"}},
            ],
            "top_view": {"resolution": [128, 128], "metres_per_pixel": 1.0},
        }
    }
    return sc


def rss_mb() -> float:
    """The current resident set size, MB (``VmRSS`` of ``/proc/self/status``)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument("--frames", type=bench_env.positive_int, default=1000, help="frames to run (1000)")
    ap.add_argument("--every", type=bench_env.positive_int, default=100, help="print a row every N frames (100)")
    ap.add_argument("-o", "--output", default=None, help="output folder (default: a temporary one, removed)")
    args = ap.parse_args()
    print(bench_env.machine())
    t0 = time.perf_counter()
    print(f"{'frame':>6} {'RSS MB':>8} {'peak MB':>8} {'s':>7}")

    def report(done: int, total: int) -> None:
        if done % args.every == 0 or done == total:
            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
            print(f"{done:>6} {rss_mb():>8.1f} {peak:>8.1f} {time.perf_counter() - t0:>7.1f}", flush=True)

    with tempfile.TemporaryDirectory() as tmp:
        res = run(small_rig_scenario(args.frames), out_dir=args.output or tmp, overwrite=True, progress=report)
        print(f"{res.frames_written} frames in {res.seconds:.1f} s, {res.bytes / 1e6:.1f} MB, status {res.status}")


if __name__ == "__main__":
    bench_env.run(main)
