"""Encode throughput of the MCAP recorder (not a test): per frame, one 26,214-point LiDAR cloud
(x, y, z, intensity float32 + ring uint16 = 18 B/point) and four 640x480 RGB PNGs, written through
:class:`mmusv.recording.Recording` into a temporary file.

Reports MB/s of raw input bytes (cloud bytes + 4 x 640x480x3) and frames/s, for camera-like images (smooth
sky/water gradients with mild noise) and for worst-case uniform noise, after an untimed one-frame write.
Usage: ``python benches/record_throughput.py [--frames N]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import bench_env
import numpy as np
import numpy.typing as npt
from mmusv.recording import Recording, to_ns

POINTS = 26_214
W, H = 640, 480


def camera_like(rng: np.random.Generator, k: int) -> npt.NDArray[np.uint8]:
    """Sky gradient over rippled water, a few dark hulls, mild sensor noise."""
    rows = np.linspace(0.0, 1.0, H)[:, None, None]
    sky = np.array([120.0, 170.0, 230.0]) * (1 - 0.4 * rows)
    water = np.array([20.0, 60.0, 90.0]) + 30 * np.sin(np.arange(W)[None, :, None] * 0.05 + k) + 10 * rows
    img = np.where(rows < 0.45, sky, water)
    for i in range(4):
        x0 = 80 + 130 * i
        img[200:230, x0 : x0 + 60] = 40
    img = img + rng.normal(0, 2.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def run(frames: int, kind: str, *, show: bool = True) -> None:
    rng = np.random.default_rng(1)
    cloud = {
        "x": rng.normal(0, 50, POINTS).astype(np.float32),
        "y": rng.normal(0, 50, POINTS).astype(np.float32),
        "z": rng.normal(0, 2, POINTS).astype(np.float32),
        "intensity": rng.random(POINTS).astype(np.float32),
        "ring": (np.arange(POINTS) % 64).astype(np.uint16),
    }
    if kind == "noise":
        images = [rng.integers(0, 256, (H, W, 3), dtype=np.uint8) for _ in range(4)]
    else:
        images = [camera_like(rng, i) for i in range(4)]
    cloud_bytes = sum(v.nbytes for v in cloud.values())
    image_bytes = 4 * H * W * 3
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "bench.mcap"
        t_cloud = t_png = 0.0
        start = time.perf_counter()
        with Recording(path) as rec:
            for k in range(frames):
                t = to_ns(0.1 * k)
                t0 = time.perf_counter()
                rec.point_cloud("/usv0/lidar", log_time_ns=t, frame_id="usv0/lidar", columns=cloud)
                t1 = time.perf_counter()
                for c, img in enumerate(images):
                    rec.png_image(f"/usv0/camera/cam{c}/rgb", log_time_ns=t, frame_id=f"usv0/cam{c}", image=img)
                t2 = time.perf_counter()
                t_cloud += t1 - t0
                t_png += t2 - t1
        total = time.perf_counter() - start
        size = path.stat().st_size
    mb = 1e6
    if not show:
        return
    print(
        f"{kind:>11}: {frames} frames in {total:.2f} s = {frames / total:.1f} frames/s, "
        f"{frames * (cloud_bytes + image_bytes) / total / mb:.0f} MB/s raw in; "
        f"cloud {frames * cloud_bytes / t_cloud / mb:.0f} MB/s ({1e3 * t_cloud / frames:.2f} ms/frame), "
        f"4 PNGs {frames * image_bytes / t_png / mb:.0f} MB/s ({1e3 * t_png / frames:.1f} ms/frame); "
        f"file {size / frames / mb:.2f} MB/frame"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=bench_env.description(__doc__))
    parser.add_argument("--frames", type=bench_env.positive_int, default=50, help="frames per image kind (50)")
    args = parser.parse_args()
    print(bench_env.machine())
    run(
        1, "camera-like", show=False
    )  # untimed: the recorder's first use (its encoder threads), which the first kind paid
    for kind in ("camera-like", "noise"):
        run(args.frames, kind)


if __name__ == "__main__":
    bench_env.run(main)
