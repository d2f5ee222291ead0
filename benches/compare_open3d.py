"""Ray-casting throughput of mmusv against Open3D's RaycastingScene (Embree) on the same triangles and rays.

Both run in one process, one after the other, on the same number of threads (``--threads``, default every CPU this
process may use: mmusv's through ``RAYON_NUM_THREADS``, Open3D's through ``nthreads``), best of ``--repeat`` timed
casts each after one untimed warm-up cast (Open3D builds its BVH at its first cast; mmusv's is built with the scene,
outside the timing too). Before anything is timed, every layout's hit distances are checked against Open3D's
(hit or miss alike on every ray; the distances within 1e-3 relative): a disagreement ends the run with exit
status 1 and no figures, since the two would not be doing the same work.

Two scene layouts of the same 775,170 world triangles (mmusv's synthetic maritime benchmark scene: islands
heightfield, water plane, 48 vessel instances):

* ``instanced``: mmusv gets the scene as built (terrain, water plane and three hull meshes placed as 50
  instances under a top-level BVH);
* ``single_mesh``: mmusv gets the world triangles concatenated into one mesh with one instance, no instancing,
  the way a user's own exported scene often looks.

Open3D always gets the world triangles flattened into one mesh (the best case for Embree: a single BVH).
Ray sets: one 64×2048 LiDAR sweep (in the sensor's trace order: blocks of 8 neighbouring columns) and four
640×480 surround pinhole cameras, the sets `cargo bench` uses (the camera directions rotated here in float32).
Open3D has no range limit: mmusv casts to ``--max-range`` (2,000 m, beyond every hit of the scene); a shorter
range lets mmusv stop where Open3D goes on, and the script says so.

``--baseline-core PATH`` also times an older build of the extension (a ``_core*.so`` file) on the same scenes
and rays in the same run, for before/after figures.

Run: ``python benches/compare_open3d.py`` (``make bench-peers``; needs ``pip install open3d-cpu``, or
``pip install '.[bench]'``). Throughputs in millions of rays per second (Mrays/s); ratio = mmusv / Open3D.
"""

from __future__ import annotations

import argparse
import importlib.machinery
import importlib.util
import os
import time
from collections.abc import Callable
from types import ModuleType
from typing import Any

import bench_env
import mmusv
import numpy as np
from mmusv._native import core

LIDAR_HEIGHT = 2.5
CAMERA_HEIGHT = 2.0
MAX_DISAGREEING = 1e-4
"""The largest share of rays on which mmusv and Open3D may disagree (hit against miss, or distances further apart
than 1e-3 relative) before the comparison is refused: none did on the benchmark scene."""
INSTALL_OPEN3D = (
    "pip install open3d-cpu  (or pip install '.[bench]'; on Debian/Ubuntu Open3D also needs "
    "apt-get install libgomp1 libusb-1.0-0)"
)


def ray_sets() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The LiDAR and camera ray sets: name -> (origins (N,3) f32, directions (N,3) f32), world frame."""
    el = core.uniform_elevations(channels=64, lower=np.deg2rad(-25.0), upper=np.deg2rad(15.0))
    lidar = np.asarray(core._lidar_directions(elevations=list(el), azimuth_steps=2048))
    lidar = lidar[np.asarray(core.lidar_trace_order(channels=64, azimuth_steps=2048))]  # the sensor's trace order
    body = np.asarray(core._pinhole_directions(width=640, height=480, hfov=np.pi / 2))
    cams = []
    for k in range(4):
        yaw = 2 * np.pi * k / 4
        c, s = np.cos(yaw), np.sin(yaw)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], dtype=np.float32)
        cams.append(body @ rot.T)
    cam = np.concatenate(cams).astype(np.float32)
    return {
        "lidar_64x2048": (np.tile(np.float32([0, 0, LIDAR_HEIGHT]), (lidar.shape[0], 1)), lidar),
        "cameras_4x640x480": (np.tile(np.float32([0, 0, CAMERA_HEIGHT]), (cam.shape[0], 1)), cam),
    }


def best_of(fn: Callable[[], Any], repeat: int) -> float:
    """Smallest wall time of ``repeat`` calls of ``fn`` after one warm-up call, seconds."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def load_core(path: str) -> ModuleType:
    """Loads another build of the extension module from ``path`` beside the installed one."""
    loader = importlib.machinery.ExtensionFileLoader("_core", path)
    spec = importlib.util.spec_from_file_location("_core", path, loader=loader)
    if spec is None:
        raise SystemExit(f"cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def scenes(mod: ModuleType) -> dict[str, Any]:
    """The two layouts built with extension module ``mod``: name -> its native ``Scene``."""
    demo = mod.demo_scene(seed=1, extent=2000.0, terrain_cells=512, vessels=48)
    native = demo[0] if isinstance(demo, tuple) else demo
    v, f, classes = native.world_mesh()[:3]
    single = mod.Scene()
    mesh = single.add_mesh(
        np.ascontiguousarray(v, np.float32), np.ascontiguousarray(f, np.int64), np.ascontiguousarray(classes), "world"
    )
    single.add_instance(mesh, np.eye(4))
    return {"instanced": native, "single_mesh": single}


def disagreement(ours: np.ndarray, theirs: np.ndarray) -> tuple[int, int]:
    """Rays where one side hits and the other misses, and rays both hit at distances further apart than 1e-3
    relative (1 mm under 1 m). ``theirs``: Open3D's distances with its hits beyond the range made misses."""
    hit_miss = int(np.count_nonzero(np.isfinite(ours) != np.isfinite(theirs)))
    both = np.isfinite(ours) & np.isfinite(theirs)
    far = np.abs(ours[both] - theirs[both]) > 1e-3 * np.maximum(theirs[both], 1.0)
    return hit_miss, int(np.count_nonzero(far))


def main() -> None:
    ap = argparse.ArgumentParser(description=bench_env.description(__doc__))
    ap.add_argument(
        "--repeat", type=bench_env.positive_int, default=5, help="timed casts per side, the fastest counts (5)"
    )
    ap.add_argument(
        "--max-range",
        type=float,
        default=2000.0,
        help="mmusv's range, metres (2000: beyond every hit; Open3D has no range limit)",
    )
    ap.add_argument(
        "--threads",
        type=bench_env.positive_int,
        default=bench_env.available_cpus(),
        help=f"threads of each side (default: the CPUs this process may use, {bench_env.available_cpus()})",
    )
    ap.add_argument("--baseline-core", help="path of an older _core*.so to time in the same run")
    args = ap.parse_args()
    if not args.max_range > 0:
        ap.error(f"--max-range {args.max_range}: give a range above 0 metres")
    if args.threads > 4 * (os.cpu_count() or 1):
        ap.error(f"--threads {args.threads}: at most 4 per CPU ({4 * (os.cpu_count() or 1)} here)")
    if args.baseline_core and not os.path.isfile(args.baseline_core):
        ap.error(f"--baseline-core {args.baseline_core}: no such file (give a built _core*.so)")
    # The same threads on both sides: mmusv's rayon pool reads RAYON_NUM_THREADS when it starts (at the first
    # parallel call, below), Open3D takes nthreads per call.
    inherited = os.environ.get("RAYON_NUM_THREADS")
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)

    o3d = bench_env.require("open3d", INSTALL_OPEN3D, "the peer this script compares with")

    builds: dict[str, ModuleType] = {"mmusv": core}
    if args.baseline_core:
        builds["baseline"] = load_core(args.baseline_core)
    layouts = {name: scenes(mod) for name, mod in builds.items()}
    v, f = layouts["mmusv"]["single_mesh"].world_mesh()[:2]
    o3d_scene = o3d.t.geometry.RaycastingScene(nthreads=args.threads)
    mesh = o3d.t.geometry.TriangleMesh()
    mesh.vertex.positions = o3d.core.Tensor(np.ascontiguousarray(v, np.float32))
    mesh.triangle.indices = o3d.core.Tensor(np.ascontiguousarray(f, np.int32))
    o3d_scene.add_triangles(mesh)
    print(bench_env.machine())
    print(f"mmusv {mmusv.__version__}, open3d {o3d.__version__}")
    note = f" (RAYON_NUM_THREADS={inherited} in the environment replaced)" if inherited not in (None, "") else ""
    print(
        f"threads: {args.threads} each (mmusv: RAYON_NUM_THREADS={args.threads}; open3d: nthreads={args.threads}){note}"
    )
    print(f"scene: {len(f)} triangles; mmusv range {args.max_range:g} m, open3d unlimited")
    print(
        f"best of {args.repeat} timed casts after a warm-up; Mr/s = millions of rays per second, ratio = mmusv / open3d"
    )
    header = f"{'layout':<13}{'ray set':<20}{'rays':>9}{'open3d Mr/s':>13}"
    for name in builds:
        header += f"{name + ' Mr/s':>16}{'ratio':>7}"
    print(header + f"{'disagree':>10}")
    for set_name, (o, d) in ray_sets().items():
        n = o.shape[0]
        rays = o3d.core.Tensor(np.concatenate([o, d], axis=1))
        theirs = o3d_scene.cast_rays(rays, nthreads=args.threads)["t_hit"].numpy()  # also builds Open3D's BVH
        beyond = int(np.count_nonzero(np.isfinite(theirs) & (theirs > args.max_range)))
        theirs = np.where(theirs <= args.max_range, theirs, np.inf)
        # Checked before timing: both sides must do the same work.
        checks: dict[tuple[str, str], int] = {}
        for layout in ("instanced", "single_mesh"):
            for name in builds:
                ours = np.asarray(layouts[name][layout].cast_rays(o, d, args.max_range)[0])
                hit_miss, far = disagreement(ours, theirs)
                if hit_miss + far > MAX_DISAGREEING * n:
                    raise SystemExit(
                        f"{name} {layout} {set_name}: results differ from Open3D's on {hit_miss + far} of {n} rays "
                        f"({hit_miss} hit against miss, {far} distances more than 1e-3 apart): not the same work, "
                        "no figures"
                    )
                checks[layout, name] = hit_miss + far
        if beyond:
            print(
                f"note: {beyond} of Open3D's {set_name} hits lie beyond --max-range {args.max_range:g} m, where mmusv "
                "stops and Open3D goes on: mmusv does less work, the ratio favours it"
            )
        t_o = best_of(lambda rays=rays: o3d_scene.cast_rays(rays, nthreads=args.threads), args.repeat)
        for layout in ("instanced", "single_mesh"):
            line = f"{layout:<13}{set_name:<20}{n:>9}{n / t_o / 1e6:>13.2f}"
            for name in builds:
                sc = layouts[name][layout]
                t_m = best_of(lambda sc=sc, o=o, d=d: sc.cast_rays(o, d, args.max_range), args.repeat)
                line += f"{n / t_m / 1e6:>16.2f}{t_o / t_m:>7.2f}"
            worst = max(checks[layout, name] for name in builds)
            print(line + f"{worst:>10}", flush=True)
    print("disagree: rays whose hit or distance (1e-3 relative) differs from Open3D's, checked before timing")


if __name__ == "__main__":
    bench_env.run(main)
