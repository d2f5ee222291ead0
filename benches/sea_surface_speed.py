"""Frames/s with the physical sea's displaced surface against the flat sea (not a test): the same scenario,
frames and sensors, flat and displaced runs interleaved round by round in one sitting, so the machine's load
hits both alike.

Per frame it does what a recording does before encoding: the capture of every sensor of every USV
(:meth:`~mmusv.simulation.Simulation.capture`) and the annotations (:func:`~mmusv.acquire.annotations_for`,
which over waves adds each box's wave-occlusion share).

Usage: ``python benches/sea_surface_speed.py [SCENARIO] [--preset W3] [--lidar-only] [--frames N]
[--rounds R]`` (default: ``scenarios/port_entry.yaml`` with its own sea, W1, all sensors; ``--preset`` takes a
sea preset, W0..W3 or a WMO code, instead). Prints seconds per frame (median over rounds) and frames/s, flat and
displaced, and the loss.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import bench_env
from mmusv.acquire import annotations_for
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Simulation
from mmusv.world.sea_state import sea_spec_for_preset

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument(
        "scenario", nargs="?", default=str(ROOT / "scenarios/port_entry.yaml"), help="scenario file (port_entry)"
    )
    ap.add_argument("--preset", default=None, help="sea preset (W0..W3, WMO 0..9); default: the scenario's sea")
    ap.add_argument("--lidar-only", action="store_true", help="capture the LiDARs only")
    ap.add_argument("--frames", type=bench_env.positive_int, default=4, help="frames per round (4)")
    ap.add_argument("--rounds", type=bench_env.positive_int, default=3, help="rounds, the median counts (3)")
    args = ap.parse_args()
    sim = Simulation(args.scenario)
    sea = sim.scenario.environment.sea_spec() if args.preset is None else sea_spec_for_preset(args.preset)
    sensors = ["lidar"] if args.lidar_only else None
    sil = SilhouetteCache()
    for s in (None, sea):  # warm up both: lighting tables, silhouettes, the wave field of --preset
        sim.set_sea_surface(s)
        annotations_for(sim, sim.capture(0, sensors=sensors), sil)
    times: dict[str, list[float]] = {"flat": [], "waves": []}
    print(bench_env.machine())
    for _ in range(args.rounds):
        for name, s in (("flat", None), ("waves", sea)):
            sim.set_sea_surface(s)
            t0 = time.perf_counter()
            for f in range(1, args.frames + 1):
                annotations_for(sim, sim.capture(f, sensors=sensors), sil)
            times[name].append((time.perf_counter() - t0) / args.frames)
    flat, waves = statistics.median(times["flat"]), statistics.median(times["waves"])
    what = "LiDAR only" if args.lidar_only else "all sensors"
    print(
        f"{Path(args.scenario).stem}, {what}, Hs {sea.hs_m} m, Tp {sea.tp_s:.1f} s, "
        f"{args.frames} frames x {args.rounds}"
    )
    print(f"flat:  {flat:.3f} s/frame, {1 / flat:.2f} frames/s   (rounds: {[round(t, 3) for t in times['flat']]})")
    print(f"waves: {waves:.3f} s/frame, {1 / waves:.2f} frames/s   (rounds: {[round(t, 3) for t in times['waves']]})")
    print(f"loss: {100 * (1 - flat / waves):.1f} % of the frames/s")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    bench_env.run(main)
