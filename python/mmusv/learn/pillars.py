"""PointPillars' pillar encoder and scatter (Lang et al., "PointPillars: Fast Encoders for Object Detection from
Point Clouds", CVPR 2019, Sec. 2.1).

:func:`pillarize` (numpy) bins a cloud ``(N, 4)`` float32 ``x, y, z, intensity`` (LiDAR frame, metres) into
pillars of ``pillar_m`` × ``pillar_m`` over the preset's x/y range, keeps the ``max_pillars`` fullest pillars
(ties by cell index) and the first ``max_points`` points of each (cloud order), and decorates every point with
the paper's nine features: ``x, y, z, r``, its offset from the arithmetic mean of its pillar's points
``x_c, y_c, z_c``, and its offset from the pillar's centre ``x_p, y_p``. Absolute ``x, y`` are divided by 100
and ``z`` by 10 (metres), so every feature is of order one.

:class:`PillarEncoder` (torch) is the simplified PointNet: a linear layer, batch norm, ReLU and a max over the
pillar's points, ``(P, max_points, 9)`` → ``(P, C)``. :func:`scatter` puts the pillar features back on the BEV
canvas ``(B, C, ny, nx)`` (row ``iy``, column ``ix``); :func:`scatter_max` adds another agent's pillars to a
canvas by element-wise max (F-Cooper's max fusion, Chen et al., SEC 2019).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from mmusv.learn._errors import input_error
from mmusv.learn.presets import Preset

__all__ = ["FEATURES", "PillarEncoder", "Pillars", "pillar_centres", "pillarize", "scatter", "scatter_max"]

FEATURES = 9
"""Per-point input features (module docstring)."""


@dataclass(frozen=True)
class Pillars:
    """One cloud's pillars: ``features`` ``(P, M, 9)`` float32, ``mask`` ``(P, M)`` bool (real points),
    ``coords`` ``(P, 2)`` int64 ``(iy, ix)`` grid cells."""

    features: np.ndarray
    mask: np.ndarray
    coords: np.ndarray


def pillarize(points: np.ndarray, p: Preset) -> Pillars:
    """The pillars of ``points`` ``(N, ≥4)`` (LiDAR frame, metres) on preset ``p``'s grid (module docstring)."""
    pts = np.asarray(points, dtype=np.float32)
    if pts.ndim != 2 or pts.shape[1] < 4:
        raise input_error(f"points: expected (N, 4) x, y, z, intensity; got shape {pts.shape}")
    pts = pts[:, :4]
    (x0, _), (y0, _), (z0, z1) = p.x_range, p.y_range, p.z_range
    nx, ny = p.grid
    fx = np.floor((pts[:, 0] - x0) / p.pillar_m)
    fy = np.floor((pts[:, 1] - y0) / p.pillar_m)
    # the grid's points chosen before the cast to cells: a NaN (or a point far off the grid) cast to int64 warned
    ok = (fx >= 0) & (fx < nx) & (fy >= 0) & (fy < ny) & (pts[:, 2] >= z0) & (pts[:, 2] < z1)
    ok &= np.isfinite(pts[:, 3])
    pts, ix, iy = pts[ok], fx[ok].astype(np.int64), fy[ok].astype(np.int64)
    m = p.max_points
    if len(pts) == 0:
        return Pillars(np.zeros((0, m, FEATURES), np.float32), np.zeros((0, m), bool), np.zeros((0, 2), np.int64))
    cell = iy * nx + ix
    order = np.argsort(cell, kind="stable")  # points grouped by pillar, cloud order within
    cell_s = cell[order]
    uniq, start, count = np.unique(cell_s, return_index=True, return_counts=True)
    keep = np.argsort(-count, kind="stable")[: p.max_pillars]  # the fullest pillars, ties by cell index
    keep.sort()
    uniq, start, count = uniq[keep], start[keep], count[keep]
    n_p = len(uniq)
    slot = np.arange(m)[None, :]
    mask = slot < count[:, None]
    src = order[np.minimum(start[:, None] + slot, len(order) - 1)]  # (P, M) point indices (padding: any)
    xyz = pts[src, :3].astype(np.float64)
    r = pts[src, 3].astype(np.float64)
    n_used = np.minimum(count, m).astype(np.float64)
    mean = (xyz * mask[:, :, None]).sum(axis=1) / n_used[:, None]
    cy, cx = np.divmod(uniq, nx)
    centre = np.column_stack([x0 + (cx + 0.5) * p.pillar_m, y0 + (cy + 0.5) * p.pillar_m])
    f = np.empty((n_p, m, FEATURES), dtype=np.float64)
    f[:, :, 0] = xyz[:, :, 0] / 100.0
    f[:, :, 1] = xyz[:, :, 1] / 100.0
    f[:, :, 2] = xyz[:, :, 2] / 10.0
    f[:, :, 3] = r
    f[:, :, 4:7] = xyz - mean[:, None, :]
    f[:, :, 7:9] = xyz[:, :, :2] - centre[:, None, :]
    f[~mask] = 0.0
    return Pillars(f.astype(np.float32), mask, np.column_stack([cy, cx]).astype(np.int64))


def pillar_centres(coords: np.ndarray | torch.Tensor, p: Preset) -> np.ndarray:
    """``(P, 2)`` float64 ``x, y`` centres (metres) of the pillars at ``coords`` ``(P, 2)`` ``(iy, ix)``."""
    c = np.asarray(coords, dtype=np.float64).reshape(-1, 2)
    return np.column_stack([p.x_range[0] + (c[:, 1] + 0.5) * p.pillar_m, p.y_range[0] + (c[:, 0] + 0.5) * p.pillar_m])


class PillarEncoder(nn.Module):
    """Linear(9 → C, no bias) + BatchNorm1d + ReLU, then max over each pillar's real points: ``(P, M, 9)``
    float32 and mask ``(P, M)`` → ``(P, C)`` (non-negative)."""

    def __init__(self, channels: int) -> None:
        super().__init__()
        self.linear = nn.Linear(FEATURES, channels, bias=False)
        self.norm = nn.BatchNorm1d(channels, eps=1e-3, momentum=0.1)

    def forward(self, features: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        n_p, m, _ = features.shape
        x = self.linear(features.reshape(n_p * m, FEATURES))
        x = torch.relu(self.norm(x)).reshape(n_p, m, self.linear.out_features)
        x = x * mask.unsqueeze(-1).to(x.dtype)  # padding contributes 0 to the max (features are ≥ 0)
        return x.max(dim=1).values if m else x.new_zeros((n_p, x.shape[-1]))


def scatter(
    features: torch.Tensor, *, coords: torch.Tensor, batch: torch.Tensor, size: int, grid: tuple[int, int]
) -> torch.Tensor:
    """The BEV canvas ``(size, C, ny, nx)`` with ``features`` ``(P, C)`` at ``coords`` ``(P, 2)`` ``(iy, ix)``
    of sample ``batch`` ``(P,)``; empty cells are 0. Cells must be unique per sample."""
    nx, ny = grid
    c = features.shape[1]
    canvas = features.new_zeros((size * ny * nx, c))
    flat = batch * (ny * nx) + coords[:, 0] * nx + coords[:, 1]
    canvas = canvas.index_copy(0, flat, features)
    return canvas.reshape(size, ny, nx, c).permute(0, 3, 1, 2).contiguous()


def scatter_max(
    canvas: torch.Tensor, *, features: torch.Tensor, cells: torch.Tensor, batch: torch.Tensor
) -> torch.Tensor:
    """``canvas`` ``(B, C, ny, nx)`` with ``features`` ``(P, C)`` max-fused into the cells ``cells`` ``(P, 2)``
    ``(iy, ix)`` of samples ``batch`` ``(P,)`` (several features may land in one cell: the max is taken, which
    does not depend on their order)."""
    b, c, ny, nx = canvas.shape
    flat_canvas = canvas.permute(0, 2, 3, 1).reshape(b * ny * nx, c)
    flat = (batch * (ny * nx) + cells[:, 0] * nx + cells[:, 1]).unsqueeze(1).expand(-1, c)
    fused = flat_canvas.scatter_reduce(0, flat, features.to(flat_canvas.dtype), reduce="amax", include_self=True)
    return fused.reshape(b, ny, nx, c).permute(0, 3, 1, 2).contiguous()
