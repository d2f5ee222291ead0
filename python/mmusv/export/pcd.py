"""ASCII PCD files the way Open3D writes them: ``FIELDS x y z rgb`` with the LiDAR intensity in the red byte.

OPV2V loaders read a cloud with ``open3d.io.read_point_cloud`` and take ``colors[:, 0]`` as the intensity, so
the intensity (in [0, 1]) is stored as ``round(255·i) << 16`` in an unsigned ``rgb`` field (Open3D's own ASCII
layout, ``TYPE F F F U``); it reads back to within 1/510. A ``FIELDS x y z intensity`` file would make those
loaders fail.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import numpy.typing as npt

__all__ = ["pcd_bytes", "read_pcd", "write_pcd"]

_HEADER = (
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
    "COUNT 1 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA ascii\n"
)


def pcd_bytes(xyz: npt.ArrayLike, intensity: npt.ArrayLike, *, decimals: int = 4) -> bytes:
    """The PCD file (ASCII bytes) of ``(N, 3)`` points (metres, written in the frame given: the OPV2V export gives
    the LiDAR frame mirrored to CARLA's, y right) and ``(N,)`` intensities in [0, 1] (clipped, NaN as 0),
    coordinates rounded to ``decimals`` places (0.1 mm by default)."""
    xyz = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
    n = xyz.shape[0]
    red = np.rint(np.clip(np.nan_to_num(np.asarray(intensity, dtype=np.float64).reshape(n), nan=0.0), 0.0, 1.0) * 255.0)
    rgb = red.astype(np.int64) << 16
    buf = io.StringIO()
    buf.write(_HEADER.format(n=n))
    if n:
        # Rounded first, "-0" normalised to "0" (+ 0.0), so equal clouds give equal bytes.
        q = (np.round(xyz, decimals) + 0.0).tolist()
        f = f"{{:.{decimals}f}} {{:.{decimals}f}} {{:.{decimals}f}} {{}}\n".format
        buf.write("".join([f(a, b, c, e) for (a, b, c), e in zip(q, rgb.tolist(), strict=True)]))
    return buf.getvalue().encode("ascii")


def write_pcd(path: Path, *, xyz: npt.ArrayLike, intensity: npt.ArrayLike) -> int:
    """Writes :func:`pcd_bytes` of ``xyz`` ``(N, 3)`` metres and ``intensity`` ``(N,)`` in [0, 1] to ``path``;
    returns the number of bytes."""
    data = pcd_bytes(xyz, intensity)
    path.write_bytes(data)
    return len(data)


def read_pcd(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(N, 3)`` float64 points (metres, the file's frame) and ``(N,)`` float64 intensities in [0, 1] (red byte /
    255) of a file written by :func:`write_pcd`.

    Raises:
        ValueError: naming the file, when it is not an ASCII ``x y z rgb`` PCD (its header cut short too), or holds
            another number of points than its header's ``POINTS`` (a file cut short read as fewer points)."""
    text = path.read_text(encoding="ascii")
    head, sep, body = text.partition("DATA ascii\n")
    if not sep or "FIELDS x y z rgb" not in head:
        raise ValueError(f"{path} is not an ASCII x y z rgb PCD (no FIELDS x y z rgb and DATA ascii header)")
    points = re.search(r"^POINTS[ \t]+(\d+)[ \t]*$", head, flags=re.MULTILINE)
    if points is None:
        raise ValueError(f"{path}: its header gives no POINTS")
    n = int(points.group(1))
    rows = [line for line in body.splitlines() if line.strip()]
    if len(rows) != n:
        raise ValueError(f"{path}: its header gives POINTS {n}, and it holds {len(rows)} (a file cut short?)")
    if rows and not body.rstrip(" \t").endswith("\n"):  # as many rows, the last one cut (inside a number: read)
        raise ValueError(f"{path}: its last row {rows[-1]!r} ends without a newline (a file cut short?)")
    try:
        arr = np.loadtxt(rows, dtype=np.float64, ndmin=2).reshape(-1, 4) if n else np.zeros((0, 4))
    except ValueError as exc:
        raise ValueError(f"{path}: not rows of 4 numbers x y z rgb ({exc})") from None
    bad = ~np.isfinite(arr[:, :3]).all(axis=1)
    if bad.any():  # a detector fitting the water plane failed on them with numpy's LinAlgError
        k = int(np.argmax(bad))
        raise ValueError(
            f"{path}: point {k} ({rows[k].strip()!r}) and {int(bad.sum()) - 1} more have coordinates that are not "
            "finite (NaN or infinity); every x y z must be a finite number of metres"
        )
    colour = arr[:, 3]
    bad = ~((colour >= 0.0) & (colour < 2.0**32) & (colour == np.floor(colour)))
    if bad.any():
        k = int(np.argmax(bad))
        raise ValueError(
            f"{path}: point {k} ({rows[k].strip()!r}) has rgb {colour[k]:g}; rgb is an unsigned 32-bit integer "
            "(the intensity in its red byte)"
        )
    rgb = colour.astype(np.int64)
    return arr[:, :3], ((rgb >> 16) & 0xFF) / 255.0
