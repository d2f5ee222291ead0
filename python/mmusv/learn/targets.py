"""CenterPoint's training targets (Yin et al., CVPR 2021, Sec. 3; the Gaussian radius of CornerNet, Law and
Deng, ECCV 2018, as CenterNet/CenterPoint use it with ``min_overlap`` 0.1).

For every ground-truth box ``x, y, z, l, w, h, yaw`` (LiDAR frame, metres, radians) whose centre lies on the
output grid (cell ``cell_m = pillar_m · out_stride``, origin at the preset's ``x_range[0], y_range[0]``):

- the heatmap ``(1, H, W)`` gets a Gaussian ``exp(-(dx² + dy²) / (2σ²))`` about the centre cell (element-wise
  max with what is there), ``σ = (2r + 1) / 6`` and ``r = max(min_radius, floor(gaussian_radius(l, w)))`` in
  cells, where ``l, w`` are the box's length and beam in cells;
- the regression row is ``dx, dy`` (centre minus its cell's corner, cells), ``z``, ``log l, log w, log h``,
  ``sin yaw, cos yaw`` (of ``2 · yaw`` with the preset's ``yaw_double``) at flat index ``iy · W + ix``, weight 1.

With the preset's ``reg_radius`` ``r > 0`` every box also gets regression rows at the cells within ``r`` of its
centre cell (Chebyshev distance; a cell another box already holds is skipped), whose ``dx, dy`` are the centre
minus that cell's corner and whose weight is the box's heatmap value there (dense regression around the centre,
as TTFNet, Liu et al., AAAI 2020, and AFDet, Ge et al., 2020, do): a peak one cell off still decodes the box,
and the few objects per frame give more regression signal. ``r = 0`` is CenterPoint's single row.

Rows beyond the first ``max_objects`` boxes are dropped (a frame of the bundled dataset holds under 20); with
``reg_radius`` the arrays hold ``max_objects · (2r + 1)²`` rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmusv.learn.presets import Preset

__all__ = ["REG_COLUMNS", "Targets", "center_targets", "draw_gaussian", "gaussian_radius", "points_in_boxes"]

REG_COLUMNS = ("dx", "dy", "z", "log_l", "log_w", "log_h", "sin", "cos")


@dataclass(frozen=True)
class Targets:
    """``heatmap`` ``(1, H, W)`` float32, ``index`` ``(K,)`` int64 flat cells, ``mask`` ``(K,)`` bool (the
    boxes' centre rows), ``reg`` ``(K, 8)`` float32 (:data:`REG_COLUMNS`), ``weight`` ``(K,)`` float32 each
    row's regression weight (1 at the centre rows, 0 for padding; module docstring)."""

    heatmap: np.ndarray
    index: np.ndarray
    mask: np.ndarray
    reg: np.ndarray
    weight: np.ndarray


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


def points_in_boxes(points: np.ndarray, boxes: np.ndarray, *, z_margin_m: float = 0.5) -> np.ndarray:
    """``(G,)`` int64 the number of ``points`` ``(N, ≥3)`` inside each box of ``boxes`` ``(G, 7)`` (same frame,
    metres): inside the rotated BEV rectangle and within ``z ± (h/2 + z_margin_m)``, the detection study's
    visibility rule (:func:`mmusv.studies.detection.study.gt_visibility`) in numpy alone."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    out = np.zeros(len(b), dtype=np.int64)
    pts = np.asarray(points, dtype=np.float64)
    if len(b) == 0 or len(pts) == 0:
        return out
    for i, (x, y, z, length, width, height, yaw) in enumerate(b):
        near = np.abs(pts[:, 2] - z) <= height / 2 + z_margin_m
        dx, dy = pts[near, 0] - x, pts[near, 1] - y
        c, s = math.cos(yaw), math.sin(yaw)
        u, v = dx * c + dy * s, -dx * s + dy * c
        out[i] = int(((np.abs(u) <= length / 2) & (np.abs(v) <= width / 2)).sum())
    return out


def center_targets(boxes: np.ndarray, p: Preset, *, max_objects: int = 64) -> Targets:
    """The targets of ``boxes`` ``(G, 7)`` on preset ``p``'s output grid (module docstring)."""
    nx, ny = p.out_grid
    cell = p.pillar_m * p.out_stride
    rr = max(0, int(p.reg_radius))
    rows = max_objects * (2 * rr + 1) ** 2
    heat = np.zeros((ny, nx), dtype=np.float32)
    index = np.zeros(rows, dtype=np.int64)
    mask = np.zeros(rows, dtype=bool)
    weight = np.zeros(rows, dtype=np.float32)
    reg = np.zeros((rows, len(REG_COLUMNS)), dtype=np.float32)
    placed: list[tuple[float, float, int, int, int, list[float]]] = []
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
        weight[k] = 1.0
        a = 2 * yaw if p.yaw_double else yaw
        rest = [z, math.log(length), math.log(width), math.log(height), math.sin(a), math.cos(a)]
        reg[k] = [cx - ix, cy - iy, *rest]
        placed.append((cx, cy, ix, iy, r, rest))
        k += 1
    if rr:
        taken = set(index[:k].tolist())
        for cx, cy, ix, iy, r, rest in placed:
            sigma = (2 * r + 1) / 6.0
            for jy in range(iy - rr, iy + rr + 1):
                for jx in range(ix - rr, ix + rr + 1):
                    flat = jy * nx + jx
                    if not (0 <= jx < nx and 0 <= jy < ny) or flat in taken:
                        continue
                    taken.add(flat)
                    index[k] = flat
                    weight[k] = math.exp(-((jx - ix) ** 2 + (jy - iy) ** 2) / (2 * sigma * sigma))
                    reg[k] = [cx - jx, cy - jy, *rest]
                    k += 1
    return Targets(heat[None], index, mask, reg, weight)
