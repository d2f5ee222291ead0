"""The geometry of a 3D box and the two target rules: a box's corners (:func:`box_corners`) and which vessels are
targets, by the box centre's bird's-eye-view distance (:func:`in_target_range`, the exports' and the detection
study's rule) or by the distance to the box's footprint (:func:`footprint_in_range`, the recording's annotations,
:mod:`mmusv.annotate`).

Frames: a box's pose is its ``(4, 4)`` box → frame transform, centred on the box; sizes are full extents (length,
beam, height along the box's x, y, z), metres. The ego LiDAR frame is x forward, y left, z up.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mmusv import arguments
from mmusv.errors import InputError

__all__ = ["box_corners", "footprint_in_range", "in_target_range"]

# Corner order of a box: bit 0 → +x, bit 1 → +y, bit 2 → +z.
_SIGNS = np.array(
    [[(i & 1) * 2 - 1, ((i >> 1) & 1) * 2 - 1, ((i >> 2) & 1) * 2 - 1] for i in range(8)], dtype=np.float64
)


def in_target_range(centres: np.ndarray, range_m: float) -> np.ndarray:
    """The box-centre target rule: which box centres lie within ``range_m`` metres of the ego LiDAR in bird's-eye
    view, ``hypot(x, y) <= range_m`` (height ignored). ``centres``: ``(..., 3)`` (or ``(..., 2)``) in the ego's
    LiDAR frame (its body frame when it has none), metres; returns a bool array of shape ``centres.shape[:-1]``
    (a 0-d array for one centre).

    Used by the OPV2V and KITTI exports (which vessels are labelled) and the detection study (the BEV distance it
    evaluates within), as OpenCOOD selects its objects; the recording's own 3D/BEV boxes reach farther, to every
    vessel whose footprint comes within range (:func:`footprint_in_range`), and the ROS 2 export's 3D detections are
    those boxes.
    """
    c = arguments.reals(
        centres, name="centres", what="(..., 3) or (..., 2) centres (x, y[, z] metres)", error=InputError
    )
    if c.ndim == 0 or c.shape[-1] not in (2, 3):
        raise InputError(f"centres must have shape (..., 3) or (..., 2) (x, y[, z] metres), got {c.shape}")
    return np.asarray(np.hypot(c[..., 0], c[..., 1]) <= _range(range_m))


def _range(range_m: Any) -> float:
    """A target range, metres: a real number, not negative (infinite: every box)."""
    return arguments.real(range_m, name="range_m", unit="metres", lo=0.0, finite=False, error=InputError)


def footprint_in_range(box: np.ndarray, *, size: np.ndarray, range_m: float) -> bool:
    """Whether a box's bird's-eye-view footprint comes within ``range_m`` metres of the ego LiDAR: the distance from
    the origin to the rectangle of ``size[0]`` (length) by ``size[1]`` (beam) centred at the box's ``(x, y)`` and
    turned by its yaw (the BEV box), 0 inside it. ``box``: ``(4, 4)`` box → ego LiDAR frame (centred), metres.

    The annotations' rule (:func:`~mmusv.annotate.annotate_agent`): a 330 m ship whose stern lies 45 m from the USV
    has its centre beyond a 200 m LiDAR's range, yet the LiDAR sees it; the centre rule of :func:`in_target_range`
    stays the exports' and the detection study's (OpenCOOD's convention). A box or size that is not finite, or a size
    below 0, raises :class:`mmusv.InputError`."""
    m = arguments.reals(box, name="box", tail=(4, 4), what="a (4, 4) box -> ego LiDAR transform", error=InputError)
    size = arguments.reals(size, name="size", what="the box's size (length, beam[, height])", error=InputError)
    if m.ndim != 2 or size.shape not in ((2,), (3,)):
        raise InputError(
            f"footprint_in_range takes a (4, 4) box and a (3,) or (2,) size, got {m.shape} and {size.shape}"
        )
    if not np.isfinite(m).all():
        raise InputError(f"box must be a (4, 4) box -> ego LiDAR transform of finite numbers, got {m.tolist()}")
    _extents(size)
    range_m = _range(range_m)
    yaw = np.arctan2(m[1, 0], m[0, 0])
    c, s = np.cos(yaw), np.sin(yaw)
    # The origin in the box's yaw-only frame, then its distance to the rectangle (0 inside).
    x, y = -m[0, 3], -m[1, 3]
    u, v = c * x + s * y, -s * x + c * y
    du = max(abs(u) - float(size[0]) / 2.0, 0.0)
    dv = max(abs(v) - float(size[1]) / 2.0, 0.0)
    return bool(np.hypot(du, dv) <= range_m)


def box_corners(matrix: np.ndarray, size: np.ndarray) -> np.ndarray:
    """``(8, 3)`` float64 corners of a box with pose ``matrix`` (``(4, 4)`` box → frame, centred) and full ``size``
    (length, beam, height along the box's x, y, z; metres), in the frame ``matrix`` maps to. Corner ``i`` lies at
    ``±size / 2`` in the box frame, the sign of x from bit 0 of ``i``, of y from bit 1 and of z from bit 2 (set:
    +; corner 0 is (−x, −y, −z), corner 7 (+x, +y, +z)). Other shapes, and a size not finite or below 0, raise
    :class:`mmusv.InputError`."""
    matrix = arguments.reals(matrix, name="matrix", what="a (4, 4) box pose", error=InputError)
    size = arguments.reals(size, name="size", what="the box's (3,) size (length, beam, height)", error=InputError)
    if matrix.shape != (4, 4) or size.shape != (3,):
        raise InputError(f"box_corners takes a (4, 4) matrix and a (3,) size, got {matrix.shape} and {size.shape}")
    _extents(size)
    local = _SIGNS * (size / 2.0)
    out: np.ndarray = local @ matrix[:3, :3].T + matrix[:3, 3]
    return out


def _extents(size: np.ndarray) -> None:
    """An :class:`InputError` unless a box's full ``size`` (length, beam[, height]) is finite metres >= 0: a negative
    extent is no box (it would mirror the corners' order), a NaN no answer."""
    if not (np.isfinite(size).all() and (size >= 0.0).all()):
        raise InputError(
            f"size must be a box's full extents, finite metres >= 0 (length, beam[, height]), got {size.tolist()}"
        )
