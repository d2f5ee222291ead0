"""Hull footprints as capsules, and the vectorised geometry the checks need.

A hull of length ``L`` and beam ``B`` (its bounding box in the body frame, centred on the pose) is covered by the
capsule whose axis runs along the body x axis from ``-a`` to ``+a`` with ``a = (L - B) / 2`` and whose radius is
``r = B / √2``: the rectangle's corners ``(±L/2, ±B/2)`` lie exactly ``B/√2`` from the axis end points. That is
much tighter than the bounding circle for long ships (a 300 m x 48 m ship: r = 34 m instead of 152 m), which
matters in channels and harbour entrances. A hull wider than long falls back to its bounding circle.

World frame, metres, radians (yaw of the body x axis from +x).
"""

from __future__ import annotations

import math

import numpy as np

from mmusv.world.vessels import get_asset

__all__ = ["axis_points", "capsule", "segment_distance"]


def capsule(asset: str) -> tuple[float, float]:
    """``(a, r)``: half-length of the axis and radius (metres) of the capsule covering the asset's hull."""
    v = get_asset(asset)
    if v.length >= v.beam:
        return (v.length - v.beam) / 2.0, v.beam / math.sqrt(2.0)
    return 0.0, math.hypot(v.length, v.beam) / 2.0


def axis_points(xy: np.ndarray, *, yaw: np.ndarray, half: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Points along every capsule axis: ``xy`` ``(N, V, 2)``, ``yaw`` ``(N, V)``, ``half`` ``(V,)`` ->
    ``(N, V, K, 2)`` points (the same K for all vessels, evenly spread from ``-a`` to ``+a``) and ``(V,)`` the
    largest distance from any axis point to its nearest sample (half the point spacing, at most ``spacing/2``)."""
    k = max(math.ceil(2.0 * float(half.max(initial=0.0)) / spacing) + 1, 1)
    f = np.linspace(-1.0, 1.0, k) if k > 1 else np.zeros(1)
    off = half[:, None] * f[None, :]  # (V, K)
    d = np.stack([np.cos(yaw), np.sin(yaw)], axis=-1)  # (N, V, 2)
    pts = xy[:, :, None, :] + off[None, :, :, None] * d[:, :, None, :]
    slack = half / max(k - 1, 1) if k > 1 else np.zeros_like(half)
    return pts, slack


def segment_distance(p1: np.ndarray, q1: np.ndarray, *, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distances between segments ``p1q1`` and ``p2q2`` (arrays ``(..., 2)``, broadcast) -> ``(...)``; closest
    points by clamped parameters (Ericson, Real-Time Collision Detection, 5.1.9), degenerate segments included."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.sum(d1 * d1, axis=-1)
    e = np.sum(d2 * d2, axis=-1)
    f = np.sum(d2 * r, axis=-1)
    c = np.sum(d1 * r, axis=-1)
    b = np.sum(d1 * d2, axis=-1)
    eps = 1e-12
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > eps, np.clip((b * f - c * e) / np.where(denom > eps, denom, 1.0), 0.0, 1.0), 0.0)
        t = np.where(e > eps, (b * s + f) / np.where(e > eps, e, 1.0), 0.0)
        a_safe = np.where(a > eps, a, 1.0)
        s = np.where(t < 0.0, np.where(a > eps, np.clip(-c / a_safe, 0.0, 1.0), 0.0), s)
        s = np.where(t > 1.0, np.where(a > eps, np.clip((b - c) / a_safe, 0.0, 1.0), 0.0), s)
        t = np.clip(t, 0.0, 1.0)
        s = np.where((e <= eps) & (a > eps), np.clip(-c / a_safe, 0.0, 1.0), s)
    gap = (p1 + d1 * s[..., None]) - (p2 + d2 * t[..., None])
    out: np.ndarray = np.sqrt(np.sum(gap * gap, axis=-1))
    return out
