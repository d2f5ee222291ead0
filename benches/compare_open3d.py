"""Ray-casting throughput of mmusv against Open3D's RaycastingScene (Embree) on the same triangles and rays.

Both use every core of this machine, in one process, one after the other, best of ``--repeat`` runs each.
The scene is mmusv's synthetic maritime benchmark scene (≈0.75 M triangles: islands heightfield, water plane,
48 vessel instances); Open3D gets the same world triangles flattened into one mesh, which is the best case
for Embree (a single BVH, no instancing). Ray sets: one 64×2048 LiDAR sweep and four 640×480 surround
pinhole cameras, exactly the sets `cargo bench` uses (the LiDAR rays in the sensor's trace order: blocks of 8
neighbouring columns).

Run: ``python benches/compare_open3d.py`` (needs ``pip install open3d-cpu``).
"""

from __future__ import annotations

import argparse
import functools
import os
import time

import mmusv
import numpy as np
from mmusv._native import core
from mmusv.scene import demo_scene

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


def best_of(fn, repeat: int) -> float:  # type: ignore[no-untyped-def]
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--max-range", type=float, default=2000.0)
    args = ap.parse_args()

    import open3d as o3d

    scene, _ = demo_scene()
    world = scene.world_mesh()
    o3d_scene = o3d.t.geometry.RaycastingScene()
    mesh = o3d.t.geometry.TriangleMesh()
    mesh.vertex.positions = o3d.core.Tensor(world["vertices"])
    mesh.triangle.indices = o3d.core.Tensor(world["faces"].astype(np.int32))
    o3d_scene.add_triangles(mesh)
    print(f"mmusv {mmusv.__version__}, open3d {o3d.__version__}, {os.cpu_count()} cores")
    print(f"scene: {scene.num_world_triangles} triangles, {scene.num_instances} instances")
    print(f"{'ray set':<20}{'rays':>10}{'mmusv Mrays/s':>16}{'open3d Mrays/s':>16}{'ratio':>8}{'agree':>8}")
    for name, (o, d) in ray_sets().items():
        rays = o3d.core.Tensor(np.concatenate([o, d], axis=1))
        t_m = best_of(functools.partial(scene.cast_rays, o, d, max_range=args.max_range), args.repeat)
        t_o = best_of(functools.partial(o3d_scene.cast_rays, rays), args.repeat)
        ours = scene.cast_rays(o, d, max_range=args.max_range).distance
        theirs = o3d_scene.cast_rays(rays)["t_hit"].numpy()
        theirs = np.where(theirs <= args.max_range, theirs, np.inf)
        both = np.isfinite(ours) & np.isfinite(theirs)
        agree = np.mean(np.isfinite(ours) == np.isfinite(theirs))
        close = (
            np.mean(np.abs(ours[both] - theirs[both]) <= 1e-3 * np.maximum(theirs[both], 1.0)) if both.any() else 1.0
        )
        n = o.shape[0]
        print(
            f"{name:<20}{n:>10}{n / t_m / 1e6:>16.2f}{n / t_o / 1e6:>16.2f}{t_o / t_m:>8.2f}{min(agree, close):>8.4f}"
        )


if __name__ == "__main__":
    main()
