"""Seeded global data augmentation for LiDAR detection (as in SECOND, Yan et al. 2018, and PointPillars): a
random flip across the x axis (``y → −y``), a rotation about z by an angle uniform in ±``rot_deg`` and a uniform
scaling in ``scale``, applied to the ego frame: to the ego's points, to the ground-truth boxes (centres moved,
sizes scaled, yaw mirrored then turned) and to the neighbours' pose in the ego frame.

A neighbour's own points are scaled by the same factor in its own frame, and its pose ``rel`` (neighbour LiDAR →
ego LiDAR, ``(4, 4)``) becomes ``A · rel · S⁻¹`` (``A`` the ego-frame transform, ``S`` the scaling), so that
``A · rel · x = (A · rel · S⁻¹) · (S · x)``: early and intermediate fusion see a consistent scene.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmusv.learn.presets import Preset

__all__ = ["Augmentation", "apply", "draw"]


@dataclass(frozen=True)
class Augmentation:
    """One draw: ``flip`` (mirror y), ``angle`` (radians, about z, after the flip), ``scale``."""

    flip: bool = False
    angle: float = 0.0
    scale: float = 1.0

    @property
    def matrix(self) -> np.ndarray:
        """``(4, 4)`` ego-frame transform: scale · rotation · flip."""
        f = np.diag([1.0, -1.0 if self.flip else 1.0, 1.0, 1.0])
        c, s = math.cos(self.angle), math.sin(self.angle)
        r = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=np.float64)
        out: np.ndarray = np.diag([self.scale, self.scale, self.scale, 1.0]) @ r @ f
        return out


def draw(rng: np.random.Generator, p: Preset) -> Augmentation:
    """A draw of preset ``p``'s augmentation from ``rng`` (always three draws, so streams stay aligned)."""
    u = rng.random(3)
    flip = bool(p.flip and u[0] < 0.5)
    angle = math.radians(p.rot_deg) * (2 * u[1] - 1)
    lo, hi = p.scale
    return Augmentation(flip=flip, angle=angle, scale=lo + (hi - lo) * float(u[2]))


def _points(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    out: np.ndarray = np.asarray(pts, dtype=np.float32).copy()
    if len(out):
        out[:, :3] = (out[:, :3].astype(np.float64) @ m[:3, :3].T + m[:3, 3]).astype(np.float32)
    return out


def apply(
    a: Augmentation, *, ego: np.ndarray, neighbours: list[tuple[np.ndarray, np.ndarray]], boxes: np.ndarray
) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]], np.ndarray]:
    """``ego`` points ``(N, 4)``, ``neighbours`` ``[(points (N_i, 4) in their own frame, rel (4, 4))]`` and
    ``boxes`` ``(G, 7)`` (ego frame) under draw ``a`` (module docstring)."""
    m = a.matrix
    s_inv = np.diag([1 / a.scale, 1 / a.scale, 1 / a.scale, 1.0])
    s = np.diag([a.scale, a.scale, a.scale, 1.0])
    nbs = [(_points(s, pts), m @ rel @ s_inv) for pts, rel in neighbours]
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7).copy()
    if len(b):
        b[:, :3] = b[:, :3] @ m[:3, :3].T
        b[:, 3:6] *= a.scale
        yaw = -b[:, 6] if a.flip else b[:, 6]
        b[:, 6] = np.arctan2(np.sin(yaw + a.angle), np.cos(yaw + a.angle))
    return _points(m, ego), nbs, b
