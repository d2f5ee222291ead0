"""Triangle-mesh building blocks for procedural maps and vessels.

Every builder returns a :class:`TriMesh`: ``vertices`` ``(V, 3)`` float64 metres, ``faces`` ``(F, 3)`` int64
(counter-clockwise seen from outside, so normals point outwards), ``classes`` ``(F,)`` uint16 semantic class per
face. Meshes are combined with :func:`merge`. Nothing here is random: callers pass any randomness in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TriMesh", "box", "cylinder", "merge", "prism", "rotation_z", "transformed"]


@dataclass(frozen=True)
class TriMesh:
    """A labelled triangle mesh (see module docstring for shapes and dtypes)."""

    vertices: np.ndarray
    faces: np.ndarray
    classes: np.ndarray

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        f = np.ascontiguousarray(self.faces, dtype=np.int64).reshape(-1, 3)
        c = np.ascontiguousarray(self.classes, dtype=np.uint16).reshape(-1)
        if c.size == 1 and f.shape[0] != 1:
            c = np.full(f.shape[0], c[0], dtype=np.uint16)
        if c.shape[0] != f.shape[0]:
            raise ValueError(f"classes has {c.shape[0]} entries for {f.shape[0]} faces")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        object.__setattr__(self, "classes", c)

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3)`` array: min and max corner of the axis-aligned bounding box, metres."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def num_triangles(self) -> int:
        """Number of faces."""
        return int(self.faces.shape[0])


def merge(parts: list[TriMesh]) -> TriMesh:
    """Concatenates meshes into one (faces re-indexed)."""
    if not parts:
        raise ValueError("merge() needs at least one mesh")
    offsets = np.cumsum([0] + [p.vertices.shape[0] for p in parts[:-1]])
    return TriMesh(
        vertices=np.concatenate([p.vertices for p in parts]),
        faces=np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=False)]),
        classes=np.concatenate([p.classes for p in parts]),
    )


def rotation_z(yaw: float) -> np.ndarray:
    """``(3, 3)`` rotation about +z by ``yaw`` radians (counter-clockwise seen from above)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def transformed(
    mesh: TriMesh,
    *,
    rotation: np.ndarray | None = None,
    translation: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
) -> TriMesh:
    """``mesh`` with vertices mapped by ``rotation @ v + translation`` (rotation ``(3, 3)``, proper)."""
    r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
    v = mesh.vertices @ r.T + np.asarray(translation, dtype=np.float64)
    return TriMesh(v, mesh.faces, mesh.classes)


_BOX_FACES = np.array(
    [
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ],
    dtype=np.int64,
)


def box(
    *,
    center: tuple[float, float, float] | np.ndarray,
    size: tuple[float, float, float] | np.ndarray,
    cls: int,
    yaw: float = 0.0,
) -> TriMesh:
    """Axis-aligned box of full ``size`` (x, y, z metres) at ``center``, rotated by ``yaw`` about its centre."""
    h = np.asarray(size, dtype=np.float64) / 2.0
    corners = (
        np.array(
            [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
            dtype=np.float64,
        )
        * h
    )
    return transformed(TriMesh(corners, _BOX_FACES, np.array([cls])), rotation=rotation_z(yaw), translation=center)


def prism(*, outline: np.ndarray, z0: float, z1: float, cls: int, top_scale: float = 1.0) -> TriMesh:
    """Extrudes a convex-or-star-shaped, counter-clockwise ``(N, 2)`` outline from ``z0`` to ``z1``.

    The top outline is the bottom one scaled by ``top_scale`` about the outline centroid (``< 1`` tapers).
    Caps are fans from the centroid, so the outline must be star-shaped about its centroid.
    """
    p = np.asarray(outline, dtype=np.float64)
    n = p.shape[0]
    if n < 3:
        raise ValueError("prism outline needs at least 3 points")
    c = p.mean(axis=0)
    top = c + (p - c) * top_scale
    bottom3 = np.column_stack([p, np.full(n, z0)])
    top3 = np.column_stack([top, np.full(n, z1)])
    verts = np.vstack([bottom3, top3, [[c[0], c[1], z0], [c[0], c[1], z1]]])
    i = np.arange(n)
    j = (i + 1) % n
    sides = np.concatenate([np.column_stack([i, j, j + n]), np.column_stack([i, j + n, i + n])])
    bottom = np.column_stack([np.full(n, 2 * n), j, i])
    topf = np.column_stack([np.full(n, 2 * n + 1), i + n, j + n])
    return TriMesh(verts, np.vstack([sides, bottom, topf]), np.array([cls]))


def cylinder(
    *,
    center: tuple[float, float, float] | np.ndarray,
    radius: float,
    height: float,
    cls: int,
    segments: int = 12,
    top_radius: float | None = None,
) -> TriMesh:
    """Vertical cylinder (or cone frustum when ``top_radius`` differs) standing on ``center`` (its base centre)."""
    a = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    outline = np.column_stack([np.cos(a), np.sin(a)]) * radius + np.asarray(center, dtype=np.float64)[:2]
    scale = 1.0 if top_radius is None else top_radius / radius
    z0 = float(center[2])
    return prism(outline=outline, z0=z0, z1=z0 + height, cls=cls, top_scale=scale)
