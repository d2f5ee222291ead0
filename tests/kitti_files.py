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
