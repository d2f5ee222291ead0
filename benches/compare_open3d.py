"""Ray-casting throughput of mmusv against Open3D's RaycastingScene (Embree) on the same triangles and rays.

Both use every core of this machine, in one process, one after the other, best of ``--repeat`` runs each.
Two scene layouts of the same ≈0.78 M world triangles (mmusv's synthetic maritime benchmark scene: islands
heightfield, water plane, 48 vessel instances):

* ``instanced``: mmusv gets the scene as built (terrain, water plane and three hull meshes placed as 51
  instances under a top-level BVH);
* ``single_mesh``: mmusv gets the world triangles concatenated into one mesh with one instance, no instancing,
  the way a user's own exported scene often looks.

Open3D always gets the world triangles flattened into one mesh (the best case for Embree: a single BVH).
Ray sets: one 64×2048 LiDAR sweep (in the sensor's trace order: blocks of 8 neighbouring columns) and four
640×480 surround pinhole cameras, exactly the sets `cargo bench` uses.

``--baseline-core PATH`` also times an older build of the extension (a ``_core*.so`` file) on the same scenes
and rays in the same run, for before/after figures.

Run: ``python benches/compare_open3d.py`` (needs ``pip install open3d-cpu``).
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

import mmusv
import numpy as np
from mmusv._native import core

LIDAR_HEIGHT = 2.5
CAMERA_HEIGHT = 2.0


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


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--max-range", type=float, default=2000.0)
    ap.add_argument("--baseline-core", help="path of an older _core*.so to time in the same run")
    args = ap.parse_args()

    import open3d as o3d

    builds: dict[str, ModuleType] = {"mmusv": core}
    if args.baseline_core:
        builds["baseline"] = load_core(args.baseline_core)
    layouts = {name: scenes(mod) for name, mod in builds.items()}
    v, f = layouts["mmusv"]["single_mesh"].world_mesh()[:2]
    o3d_scene = o3d.t.geometry.RaycastingScene()
    mesh = o3d.t.geometry.TriangleMesh()
    mesh.vertex.positions = o3d.core.Tensor(np.ascontiguousarray(v, np.float32))
    mesh.triangle.indices = o3d.core.Tensor(np.ascontiguousarray(f, np.int32))
    o3d_scene.add_triangles(mesh)
    print(f"mmusv {mmusv.__version__}, open3d {o3d.__version__}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    print(f"scene: {len(f)} triangles")
    header = f"{'layout':<13}{'ray set':<20}{'rays':>9}{'open3d Mr/s':>13}"
    for name in builds:
        header += f"{name + ' Mr/s':>16}{'ratio':>7}"
    print(header + f"{'agree':>8}")
    for set_name, (o, d) in ray_sets().items():
        rays = o3d.core.Tensor(np.concatenate([o, d], axis=1))
        t_o = best_of(lambda rays=rays: o3d_scene.cast_rays(rays), args.repeat)
        theirs = o3d_scene.cast_rays(rays)["t_hit"].numpy()
        theirs = np.where(theirs <= args.max_range, theirs, np.inf)
        n = o.shape[0]
        for layout in ("instanced", "single_mesh"):
            line = f"{layout:<13}{set_name:<20}{n:>9}{n / t_o / 1e6:>13.2f}"
            agree_all = 1.0
            for name in builds:
                sc = layouts[name][layout]
                t_m = best_of(lambda sc=sc, o=o, d=d: sc.cast_rays(o, d, args.max_range), args.repeat)
                ours = np.asarray(sc.cast_rays(o, d, args.max_range)[0])
                both = np.isfinite(ours) & np.isfinite(theirs)
                agree = np.mean(np.isfinite(ours) == np.isfinite(theirs))
                rel = np.abs(ours[both] - theirs[both]) <= 1e-3 * np.maximum(theirs[both], 1.0)
                close = np.mean(rel) if both.any() else 1.0
                agree_all = min(agree_all, agree, close)
                line += f"{n / t_m / 1e6:>16.2f}{t_o / t_m:>7.2f}"
            print(line + f"{agree_all:>8.4f}")


if __name__ == "__main__":
    main()
