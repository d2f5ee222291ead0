"""Reading KITTI files back in tests: shared by the KITTI export tests and the OpenCV geometry checks (``tests/`` is
on the tests' path, ``pythonpath`` in pyproject.toml)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def read_calib(path: Path) -> dict[str, np.ndarray]:
    """The matrices of a KITTI ``calib/*.txt``: each ``KEY: v v v …`` line as a flat float64 array by key."""
    out = {}
    for line in path.read_text().splitlines():
        key, vals = line.split(":", 1)
        out[key] = np.array([float(v) for v in vals.split()])
    return out


def label_corners(fields: list[str]) -> np.ndarray:
    """The ``(8, 3)`` corners, in the camera frame (metres), of the box of a KITTI ``label_2`` line split into
    ``fields``: ``h w l`` (fields 8–10), the location its bottom centre (11–13), ``rotation_y`` about y (14); the
    first four corners on the bottom face (y = location), the others ``h`` above it (y − h)."""
    h, w, l_, x, y, z, ry = (float(v) for v in fields[8:15])
    xs = np.array([1, 1, -1, -1, 1, 1, -1, -1]) * l_ / 2
    ys = np.array([0, 0, 0, 0, -1, -1, -1, -1]) * h
    zs = np.array([1, -1, -1, 1, 1, -1, -1, 1]) * w / 2
    c, s = np.cos(ry), np.sin(ry)
    return np.stack([c * xs + s * zs + x, ys + y, -s * xs + c * zs + z], axis=1)
