"""Where the main job's time goes (not a test): runs a scenario with ``mmusv.run(..., profile=True)`` and prints
the time per stage per frame (each sensor, annotation, encoding, writing, Python overhead), the wall time,
frames/s, CPU use, peak RSS and the load average (other work on the machine slows every figure).

Usage: ``python benches/profile_run.py [SCENARIO] [--frames N] [-o OUT]`` (default: the README's main job,
``scenarios/port_entry.yaml``, all 50 frames). Same table as ``mmusv run SCENARIO --profile``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import bench_env
from mmusv.acquire import run

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument(
        "scenario", nargs="?", default=str(ROOT / "scenarios/port_entry.yaml"), help="scenario file (port_entry)"
    )
    ap.add_argument("--frames", type=bench_env.positive_int, default=None, help="only the first N frames")
    ap.add_argument("-o", "--output", default=None, help="output folder (default: a temporary one, removed)")
    args = ap.parse_args()
    print(bench_env.machine())
    with tempfile.TemporaryDirectory() as tmp:
        res = run(args.scenario, out_dir=args.output or tmp, overwrite=True, frames=args.frames, profile=True)
        assert res.profile is not None
        print(res.profile.render())
        print(f"{res.frames_written} frames, {res.messages} messages, {res.bytes / 1e6:.1f} MB, status {res.status}")


if __name__ == "__main__":
    bench_env.run(main)
