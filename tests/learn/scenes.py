"""Synthetic LiDAR scenes for the mmusv.learn tests: boxes whose sides and top are sampled with points, a few
water returns, and an in-memory sample source with the interface of :class:`mmusv.learn.cache.Cache`."""

from __future__ import annotations

import numpy as np


def box_points(box: np.ndarray, rng: np.random.Generator, *, n: int = 300) -> np.ndarray:
    """``(n, 4)`` float32 points on the four sides and the top of ``box`` ``(7,)`` (LiDAR frame)."""
    x, y, z, length, width, height, yaw = box
    u = rng.random((n, 3))
    face = rng.integers(0, 5, n)
    local = np.column_stack([(u[:, 0] - 0.5) * length, (u[:, 1] - 0.5) * width, (u[:, 2] - 0.5) * height])
    local[face == 0, 0] = length / 2
    local[face == 1, 0] = -length / 2
    local[face == 2, 1] = width / 2
    local[face == 3, 1] = -width / 2
    local[face == 4, 2] = height / 2
    c, s = np.cos(yaw), np.sin(yaw)
    pts = np.column_stack(
        [x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1], z + local[:, 2]]
    )
    return np.column_stack([pts, np.full(n, 0.5)]).astype(np.float32)


def scene(boxes: np.ndarray, seed: int, *, extent: float = 30.0) -> np.ndarray:
    """Points of every box plus 200 water returns at z = -2 m within ±``extent``."""
    rng = np.random.default_rng(seed)
    water = np.column_stack([rng.uniform(-extent, extent, (200, 2)), np.full(200, -2.0), np.full(200, 0.1)])
    parts = [box_points(b, rng) for b in boxes] + [water.astype(np.float32)]
    return np.concatenate(parts)


SCENES = [
    np.array([[10.0, 5.0, 1.0, 8.0, 3.0, 3.0, 0.3], [-12.0, -8.0, 1.5, 12.0, 4.0, 4.0, -1.0]]),
    np.array([[-5.0, 14.0, 1.0, 6.0, 2.5, 2.5, 1.2], [15.0, -15.0, 2.0, 16.0, 5.0, 5.0, 2.5]]),
    np.array([[0.0, -20.0, 1.0, 10.0, 3.5, 3.0, 0.0], [20.0, 10.0, 1.0, 7.0, 2.5, 3.0, -2.0]]),
]


class MemorySource:
    """Samples ``(points, [], boxes)`` held in memory (no neighbours), with :class:`Cache`'s interface."""

    def __init__(self, scenes: list[np.ndarray], *, seed: int = 0) -> None:
        self.items = [(scene(b, seed + i), b) for i, b in enumerate(scenes)]
        self.path = "memory"

    def __len__(self) -> int:
        return len(self.items)

    def frame_position(self, k: int) -> int:
        return k

    def sample(self, k: int) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]], np.ndarray]:
        pts, boxes = self.items[k]
        return pts.copy(), [], boxes.astype(np.float64).copy()
