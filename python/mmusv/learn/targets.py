"""CenterPoint's training targets (Yin et al., CVPR 2021, Sec. 3; the Gaussian radius of CornerNet, Law and
Deng, ECCV 2018, as CenterNet/CenterPoint use it with ``min_overlap`` 0.1).

For every ground-truth box ``x, y, z, l, w, h, yaw`` (LiDAR frame, metres, radians) whose centre lies on the
output grid (cell ``cell_m = pillar_m · out_stride``, origin at the preset's ``x_range[0], y_range[0]``):

- the heatmap ``(1, H, W)`` gets a Gaussian ``exp(-(dx² + dy²) / (2σ²))`` about the centre cell (element-wise
  max with what is there), ``σ = (2r + 1) / 6`` and ``r = max(min_radius, floor(gaussian_radius(l, w)))`` in
  cells, where ``l, w`` are the box's length and beam in cells;
- the regression row is ``dx, dy`` (centre minus its cell's corner, cells), ``z``, ``log l, log w, log h``,
  ``sin yaw, cos yaw`` (of ``2 · yaw`` with the preset's ``yaw_double``) at flat index ``iy · W + ix``.

Rows beyond the first ``max_objects`` boxes are dropped (a frame of the bundled dataset holds under 20).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmusv.learn.presets import Preset

__all__ = ["REG_COLUMNS", "Targets", "center_targets", "draw_gaussian", "gaussian_radius"]

REG_COLUMNS = ("dx", "dy", "z", "log_l", "log_w", "log_h", "sin", "cos")


@dataclass(frozen=True)
class Targets:
    """``heatmap`` ``(1, H, W)`` float32, ``index`` ``(K,)`` int64 flat cells, ``mask`` ``(K,)`` bool (real
    rows), ``reg`` ``(K, 8)`` float32 (:data:`REG_COLUMNS`)."""

    heatmap: np.ndarray
    index: np.ndarray
    mask: np.ndarray
    reg: np.ndarray


def gaussian_radius(length: float, width: float, *, min_overlap: float = 0.1) -> float:
    """CornerNet's radius (cells) within which a box of ``length`` × ``width`` cells, shifted, still overlaps
    the original by ``min_overlap`` (the smallest root of its three cases, in the form CenterPoint uses)."""
    h, w = length, width
    b1 = h + w
    c1 = w * h * (1 - min_overlap) / (1 + min_overlap)
    r1 = (b1 + math.sqrt(b1 * b1 - 4 * c1)) / 2
    b2 = 2 * (h + w)
    c2 = (1 - min_overlap) * w * h
    r2 = (b2 + math.sqrt(b2 * b2 - 16 * c2)) / 2
    a3 = 4 * min_overlap
    b3 = -2 * min_overlap * (h + w)
    c3 = (min_overlap - 1) * w * h
    r3 = (b3 + math.sqrt(b3 * b3 - 4 * a3 * c3)) / 2
    return min(r1, r2, r3)


def draw_gaussian(heatmap: np.ndarray, centre: tuple[int, int], radius: int) -> None:
    """Max-draws a Gaussian of ``radius`` cells (σ = (2r+1)/6) about ``centre`` ``(ix, iy)`` into ``heatmap``
    ``(H, W)`` in place, clipped at the edges."""
    sigma = (2 * radius + 1) / 6.0
    ys, xs = np.ogrid[-radius : radius + 1, -radius : radius + 1]
    g = np.exp(-(xs * xs + ys * ys) / (2 * sigma * sigma))
    g[g < np.finfo(np.float32).eps * g.max()] = 0
    h, w = heatmap.shape
    ix, iy = centre
    left, right = min(ix, radius), min(w - ix, radius + 1)
    top, bottom = min(iy, radius), min(h - iy, radius + 1)
    view = heatmap[iy - top : iy + bottom, ix - left : ix + right]
    np.maximum(view, g[radius - top : radius + bottom, radius - left : radius + right], out=view)


def center_targets(boxes: np.ndarray, p: Preset, *, max_objects: int = 64) -> Targets:
    """The targets of ``boxes`` ``(G, 7)`` on preset ``p``'s output grid (module docstring)."""
    nx, ny = p.out_grid
    cell = p.pillar_m * p.out_stride
    heat = np.zeros((ny, nx), dtype=np.float32)
    index = np.zeros(max_objects, dtype=np.int64)
    mask = np.zeros(max_objects, dtype=bool)
    reg = np.zeros((max_objects, len(REG_COLUMNS)), dtype=np.float32)
    k = 0
    for b in np.asarray(boxes, dtype=np.float64).reshape(-1, 7):
        if k >= max_objects:
            break
        x, y, z, length, width, height, yaw = b
        if not (length > 0 and width > 0 and height > 0):
            continue
        cx, cy = (x - p.x_range[0]) / cell, (y - p.y_range[0]) / cell
        ix, iy = math.floor(cx), math.floor(cy)
        if not (0 <= ix < nx and 0 <= iy < ny):
            continue
        r = max(p.min_radius, math.floor(gaussian_radius(length / cell, width / cell)))
        draw_gaussian(heat, (ix, iy), r)
        index[k] = iy * nx + ix
        mask[k] = True
        a = 2 * yaw if p.yaw_double else yaw
        reg[k] = [cx - ix, cy - iy, z, math.log(length), math.log(width), math.log(height), math.sin(a), math.cos(a)]
        k += 1
    return Targets(heat[None], index, mask, reg)
