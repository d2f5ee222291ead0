"""Frames/s per camera quality level, over the physical sea and over flat water (not a test): the README's table.

Runs the scenario (``mmusv.run``, recording included, into a temporary folder) once per quality level (``draft``,
``standard``, ``high``: every camera and top view of every rig set to it) and sea (the scenario's own physical
sea, and the flat water of ``motion: paper``), round by round so that the machine's load hits every variant
alike, and prints per variant the frames/s (median over rounds, with every round's), the CPU seconds per frame
(every thread of this process: the sensors' and the writer's) and the recording's size. The world's start-up (map,
scene, vessels) counts, as it does for a user's run; the process's own (imports, tables built once per process)
is paid by an untimed one-frame run before the first variant, which otherwise carried it alone.

Usage: ``python benches/quality_speed.py [SCENARIO] [--frames N] [--rounds R] [--quality Q ...] [--sea S ...]``
(default: the README's main job, ``scenarios/port_entry.yaml``, all its frames, one round, every quality, both
seas).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time
from pathlib import Path

import bench_env
from mmusv.acquire import run
from mmusv.config import Scenario, load_scenario

ROOT = Path(__file__).resolve().parents[1]
QUALITIES = ("draft", "standard", "high")
SEAS = ("waves", "flat")


def variant(base: Scenario, quality: str, sea: str) -> Scenario:
    """``base`` with every camera and top view at ``quality``, over its own sea (``waves``) or flat water
    (``flat``: ``motion: paper``)."""
    rigs = {}
    for name, rig in base.rigs.items():
        cams = [c.model_copy(update={"quality": quality}) for c in rig.cameras]
        top = rig.top_view.model_copy(update={"quality": quality}) if rig.top_view is not None else None
        rigs[name] = rig.model_copy(update={"cameras": cams, "top_view": top})
    sc = base.model_copy(update={"rigs": rigs, "name": f"{base.name}_{quality}_{sea}"})
    return sc.with_sea(base.environment.sea, motion="paper") if sea == "flat" else sc


def cpu_seconds() -> float:
    """User and system CPU seconds of this process so far (all its threads)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument(
        "scenario", nargs="?", default=str(ROOT / "scenarios/port_entry.yaml"), help="scenario file (port_entry)"
    )
    ap.add_argument(
        "--frames", type=bench_env.positive_int, default=None, help="only the first N frames (default: all)"
    )
    ap.add_argument("--rounds", type=bench_env.positive_int, default=1, help="rounds over every variant (1)")
    ap.add_argument("--quality", nargs="+", choices=QUALITIES, default=list(QUALITIES), help="quality levels (all)")
    ap.add_argument("--sea", nargs="+", choices=SEAS, default=list(SEAS), help="seas (both)")
    args = ap.parse_args()
    base = load_scenario(args.scenario)
    print(bench_env.machine())
    results: dict[tuple[str, str], list[tuple[float, float, int]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        # untimed: the process's one-time costs, which the first variant alone paid
        run(variant(base, args.quality[0], args.sea[0]), out_dir=tmp, overwrite=True, frames=1)
        for _ in range(args.rounds):
            for quality in args.quality:
                for sea in args.sea:
                    sc = variant(base, quality, sea)
                    c0, t0 = cpu_seconds(), time.perf_counter()
                    res = run(sc, out_dir=tmp, overwrite=True, frames=args.frames)
                    wall, cpu = time.perf_counter() - t0, cpu_seconds() - c0
                    n = res.frames_written
                    results.setdefault((quality, sea), []).append((n / wall, cpu / n, res.bytes))
    print(f"{base.name}: {args.frames or base.acquisition.frames} frames with start-up, {args.rounds} round(s)")
    print("| quality | sea | frames/s | CPU s per frame | recording |")
    print("|---|---|---|---|---|")
    for (quality, sea), runs in results.items():
        fps = statistics.median(r[0] for r in runs)
        rounds = ", ".join(f"{r[0]:.2f}" for r in runs)
        cpu = statistics.median(r[1] for r in runs)
        mb = runs[-1][2] / 1e6
        print(f"| `{quality}` | {sea} | {fps:.2f} ({rounds}) | {cpu:.2f} | {mb:.0f} MB |")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    bench_env.run(main)
