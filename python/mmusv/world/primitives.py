"""Triangle-mesh building blocks for procedural maps and vessels.

Every builder returns a :class:`TriMesh`: ``vertices`` ``(V, 3)`` float64 metres, ``faces`` ``(F, 3)`` int64
(counter-clockwise seen from outside, so normals point outwards), ``classes`` ``(F,)`` uint16 semantic class per
face, ``materials`` ``(F,)`` uint16 material id per face (:mod:`mmusv.world.materials`; default 0, the class
colour). Meshes are combined with :func:`merge`. Nothing here is random: callers pass any randomness in.
The batched builders (:func:`boxes`, :func:`tubes`, :func:`lathe`, :func:`sweep`, :func:`torus`) make many closed
pieces in one vectorised call.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from mmusv._equality import same

__all__ = [
    "TriMesh",
    "box",
    "boxes",
    "cylinder",
    "lathe",
    "merge",
    "placed",
    "prism",
    "rotation_z",
    "sweep",
    "torus",
    "transformed",
    "tubes",
    "with_material",
]


def _no_materials() -> np.ndarray:
    return np.zeros(0, dtype=np.uint16)


def _per_face(ids: object, faces: int, *, name: str, empty_is_zero: bool) -> np.ndarray:
    """``ids`` (a mesh's classes or materials) as ``(faces,)`` uint16 ids, one per face: one id is broadcast to
    every face, and so, with ``empty_is_zero``, is id 0 when none is given; another count is a ``ValueError``
    naming ``name``."""
    a = np.ascontiguousarray(ids, dtype=np.uint16).reshape(-1)
    if empty_is_zero and a.size == 0:
        a = np.zeros(faces, dtype=np.uint16)
    elif a.size == 1 and faces != 1:
        a = np.full(faces, a[0], dtype=np.uint16)
    if a.shape[0] != faces:
        raise ValueError(f"{name} has {a.shape[0]} entries for {faces} faces")
    return a


@dataclass(frozen=True, eq=False)
class TriMesh:
    """A labelled triangle mesh (see module docstring for shapes and dtypes). Two compare equal (``==``) when
    their arrays hold the same dtypes, shapes and values; meshes are not hashable (key them by name)."""

    vertices: np.ndarray
    faces: np.ndarray
    classes: np.ndarray
    materials: np.ndarray = field(default_factory=_no_materials)
    """``(F,)`` uint16 material ids; given empty (the default) it is all 0, given one id it is broadcast."""

    def __eq__(self, other: object) -> bool:
        """Whether ``other`` is a mesh with the same arrays (the generated ``==`` asked arrays for a truth value
        and raised numpy's ``ValueError``)."""
        if type(other) is not type(self):
            return NotImplemented
        return same(self, other)

    __hash__ = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        f = np.ascontiguousarray(self.faces, dtype=np.int64).reshape(-1, 3)
        c = _per_face(self.classes, f.shape[0], name="classes", empty_is_zero=False)
        m = _per_face(self.materials, f.shape[0], name="materials", empty_is_zero=True)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        object.__setattr__(self, "classes", c)
        object.__setattr__(self, "materials", m)

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3)`` float64: min and max corner of the axis-aligned bounding box, metres, the mesh's frame."""
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
        materials=np.concatenate([p.materials for p in parts]),
    )


def with_material(mesh: TriMesh, material: int) -> TriMesh:
    """``mesh`` with every face given material id ``material``."""
    return TriMesh(mesh.vertices, mesh.faces, mesh.classes, np.array([material]))


def rotation_z(yaw: float) -> np.ndarray:
    """``(3, 3)`` float64 rotation about +z by ``yaw`` radians (counter-clockwise seen from above)."""
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
    return TriMesh(v, mesh.faces, mesh.classes, mesh.materials)


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


# ------------------------------------------------------------------------------------------ batched builders


def _per_piece(value: npt.ArrayLike, n: int, repeat: int) -> np.ndarray:
    """A scalar or ``(n,)`` per-piece id repeated ``repeat`` times per piece: ``(n * repeat,)`` uint16."""
    a = np.asarray(value, dtype=np.int64).reshape(-1)
    if a.size == 1:
        a = np.full(n, a[0])
    if a.shape[0] != n:
        raise ValueError(f"{a.shape[0]} ids for {n} pieces")
    return np.repeat(a, repeat).astype(np.uint16)


def boxes(
    *,
    centers: npt.ArrayLike,
    sizes: npt.ArrayLike,
    cls: int,
    material: npt.ArrayLike = 0,
    yaw: npt.ArrayLike = 0.0,
) -> TriMesh:
    """``N`` closed boxes in one mesh: ``centers`` ``(N, 3)`` and full ``sizes`` ``(N, 3)`` metres, each turned by
    ``yaw`` (scalar or ``(N,)`` radians) about its vertical axis; ``material`` one id or ``(N,)`` ids."""
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    n = c.shape[0]
    h = np.broadcast_to(np.asarray(sizes, dtype=np.float64).reshape(-1, 3), (n, 3)) / 2.0
    unit = np.array(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
        dtype=np.float64,
    )
    local = unit[None, :, :] * h[:, None, :]
    yw = np.broadcast_to(np.asarray(yaw, dtype=np.float64).reshape(-1), (n,))
    cs, sn = np.cos(yw)[:, None], np.sin(yw)[:, None]
    x = local[:, :, 0] * cs - local[:, :, 1] * sn
    y = local[:, :, 0] * sn + local[:, :, 1] * cs
    v = np.stack([x, y, local[:, :, 2]], axis=2) + c[:, None, :]
    f = (_BOX_FACES[None, :, :] + 8 * np.arange(n)[:, None, None]).reshape(-1, 3)
    return TriMesh(v.reshape(-1, 3), f, np.array([cls]), _per_piece(material, n, 12))


def _frames(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(N, 3)`` completing each unit ``axis`` ``(N, 3)`` to a right-handed frame (e2 x e3 = axis)."""
    ref = np.where(np.abs(axis[:, 2:3]) < 0.99, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e2 = np.cross(ref, axis)
    e2 /= np.linalg.norm(e2, axis=1, keepdims=True)
    return e2, np.cross(axis, e2)


def tubes(
    *,
    starts: npt.ArrayLike,
    ends: npt.ArrayLike,
    radius: npt.ArrayLike,
    cls: int,
    material: npt.ArrayLike = 0,
    segments: int = 8,
    end_radius: npt.ArrayLike | None = None,
) -> TriMesh:
    """``N`` closed straight tubes (``segments``-gon prisms, or frustums with ``end_radius``) from ``starts`` to
    ``ends`` ``(N, 3)`` metres, each ``4 * segments`` triangles; ``radius`` scalar or ``(N,)`` metres."""
    p0 = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
    p1 = np.asarray(ends, dtype=np.float64).reshape(-1, 3)
    n, s = p0.shape[0], segments
    axis = p1 - p0
    length = np.linalg.norm(axis, axis=1, keepdims=True)
    if np.any(length <= 0.0):
        raise ValueError("a tube has zero length")
    axis = axis / length
    e2, e3 = _frames(axis)
    r0 = np.broadcast_to(np.asarray(radius, dtype=np.float64).reshape(-1), (n,))[:, None, None]
    r1 = (
        r0
        if end_radius is None
        else np.broadcast_to(np.asarray(end_radius, dtype=np.float64).reshape(-1), (n,))[:, None, None]
    )
    a = np.linspace(0.0, 2.0 * np.pi, s, endpoint=False)
    ring = np.cos(a)[None, :, None] * e2[:, None, :] + np.sin(a)[None, :, None] * e3[:, None, :]
    v = np.concatenate(
        [p0[:, None, :] + r0 * ring, p1[:, None, :] + r1 * ring, p0[:, None, :], p1[:, None, :]], axis=1
    )  # (n, 2s + 2, 3)
    i = np.arange(s)
    j = (i + 1) % s
    one = np.concatenate(
        [
            np.column_stack([i, j, j + s]),
            np.column_stack([i, j + s, i + s]),
            np.column_stack([np.full(s, 2 * s), j, i]),
            np.column_stack([np.full(s, 2 * s + 1), i + s, j + s]),
        ]
    )
    f = (one[None, :, :] + (2 * s + 2) * np.arange(n)[:, None, None]).reshape(-1, 3)
    return TriMesh(v.reshape(-1, 3), f, np.array([cls]), _per_piece(material, n, 4 * s))


def lathe(
    profile: np.ndarray | Sequence[tuple[float, float]],
    *,
    cls: int,
    material: int | np.ndarray = 0,
    segments: int = 12,
    scale: tuple[float, float] = (1.0, 1.0),
    phase: float = 0.0,
) -> TriMesh:
    """A closed surface of revolution about the local z axis: ``profile`` ``(K, 2)`` ``(r, z)`` bottom to top
    (``r = 0`` makes a pole; open ends are capped), its x/y radii scaled by ``scale``, the first of its
    ``segments`` at angle ``phase`` (radians). ``material`` is one id or ``(K - 1,)`` ids, one per profile band
    (caps take the nearest band's)."""
    prof = np.asarray(profile, dtype=np.float64).reshape(-1, 2)
    k, s = prof.shape[0], segments
    mats = np.asarray(material, dtype=np.int64).reshape(-1)
    mats = np.full(k - 1, mats[0]) if mats.size == 1 else mats
    if mats.shape[0] != k - 1:
        raise ValueError(f"{mats.shape[0]} band materials for {k - 1} profile bands")
    ang = np.linspace(0.0, 2.0 * np.pi, s, endpoint=False) + phase
    ca, sa = np.cos(ang) * scale[0], np.sin(ang) * scale[1]
    pole = prof[:, 0] <= 0.0
    counts = np.where(pole, 1, s)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rings = [
        np.array([[0.0, 0.0, z]]) if p else np.column_stack([r * ca, r * sa, np.full(s, z)])
        for (r, z), p in zip(prof, pole, strict=True)
    ]
    total = int(counts.sum())
    i = np.arange(s)
    j = (i + 1) % s
    faces: list[np.ndarray] = []
    fm: list[np.ndarray] = []
    if not pole[0]:
        rings.append(np.array([[0.0, 0.0, prof[0, 1]]]))
        faces.append(np.column_stack([np.full(s, total), starts[0] + j, starts[0] + i]))
        fm.append(np.full(s, mats[0]))
        total += 1
    if not pole[-1]:
        rings.append(np.array([[0.0, 0.0, prof[-1, 1]]]))
        faces.append(np.column_stack([np.full(s, total), starts[-1] + i, starts[-1] + j]))
        fm.append(np.full(s, mats[-1]))
        total += 1
    for b in range(k - 1):
        lo, hi = starts[b], starts[b + 1]
        if pole[b] and pole[b + 1]:
            raise ValueError("two consecutive poles in a lathe profile")
        if pole[b]:
            faces.append(np.column_stack([np.full(s, lo), hi + j, hi + i]))
            fm.append(np.full(s, mats[b]))
        elif pole[b + 1]:
            faces.append(np.column_stack([lo + i, lo + j, np.full(s, hi)]))
            fm.append(np.full(s, mats[b]))
        else:
            faces.append(np.column_stack([lo + i, lo + j, hi + j, lo + i, hi + j, hi + i]).reshape(-1, 3))
            fm.append(np.full(2 * s, mats[b]))
    return TriMesh(np.vstack(rings), np.vstack(faces), np.array([cls]), np.concatenate(fm))


def placed(mesh: TriMesh, *, rotations: npt.ArrayLike, translations: npt.ArrayLike) -> TriMesh:
    """``N`` copies of ``mesh`` in one mesh, copy ``k`` mapped by ``rotations[k] @ v + translations[k]``
    (``(N, 3, 3)`` proper rotations, or ``(N,)`` yaws in radians about +z; ``(N, 3)`` metres)."""
    t = np.asarray(translations, dtype=np.float64).reshape(-1, 3)
    n = t.shape[0]
    r = np.asarray(rotations, dtype=np.float64)
    if r.ndim == 1 or r.shape == (n,):
        yaw = np.broadcast_to(r.reshape(-1), (n,))
        c, s = np.cos(yaw), np.sin(yaw)
        r = np.zeros((n, 3, 3))
        r[:, 0, 0], r[:, 0, 1], r[:, 1, 0], r[:, 1, 1], r[:, 2, 2] = c, -s, s, c, 1.0
    v = np.einsum("nij,vj->nvi", r, mesh.vertices) + t[:, None, :]
    nv = mesh.vertices.shape[0]
    f = (mesh.faces[None, :, :] + nv * np.arange(n)[:, None, None]).reshape(-1, 3)
    return TriMesh(v.reshape(-1, 3), f, np.tile(mesh.classes, n), np.tile(mesh.materials, n))


def sweep(
    path: npt.ArrayLike,
    *,
    radius: float,
    cls: int,
    material: int = 0,
    segments: int = 8,
    closed: bool = False,
) -> TriMesh:
    """A closed tube of ``radius`` along the polyline ``path`` ``(P, 3)`` metres (capped ends; ``closed`` joins the
    last point to the first). Cross-sections are perpendicular to the mean of the neighbouring segments."""
    p = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    keep = np.ones(p.shape[0], dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9
    p = p[keep]
    n, s = p.shape[0], segments
    if n < 2:
        raise ValueError("a swept tube needs two distinct points")
    seg = np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    tan = seg + np.roll(seg, 1, axis=0) if closed else np.vstack([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    e2, e3 = _frames(tan)
    a = np.linspace(0.0, 2.0 * np.pi, s, endpoint=False)
    ring = radius * (np.cos(a)[None, :, None] * e2[:, None, :] + np.sin(a)[None, :, None] * e3[:, None, :])
    v = (p[:, None, :] + ring).reshape(-1, 3)
    i = np.arange(s)
    j = (i + 1) % s
    rows = np.arange(n if closed else n - 1)
    lo = (rows * s)[:, None]
    hi = (((rows + 1) % n) * s)[:, None]
    f = np.stack([lo + i, lo + j, hi + j, lo + i, hi + j, hi + i], axis=2).reshape(-1, 3)
    faces = [f]
    if not closed:
        v = np.vstack([v, p[:1], p[-1:]])
        c0, c1 = n * s, n * s + 1
        last = (n - 1) * s
        faces += [np.column_stack([np.full(s, c0), j, i]), np.column_stack([np.full(s, c1), last + i, last + j])]
    return TriMesh(v, np.vstack(faces), np.array([cls]), np.array([material]))


def torus(*, major: float, minor: float, cls: int, material: int = 0, segments: tuple[int, int] = (12, 6)) -> TriMesh:
    """A closed torus about the local z axis (ring radius ``major``, tube radius ``minor``, metres)."""
    nu, nv = segments
    u = np.linspace(0.0, 2.0 * np.pi, nu, endpoint=False)[:, None]
    w = np.linspace(0.0, 2.0 * np.pi, nv, endpoint=False)[None, :]
    rr = major + minor * np.cos(w)
    v = np.stack([rr * np.cos(u), rr * np.sin(u), np.broadcast_to(minor * np.sin(w), (nu, nv))], axis=2).reshape(-1, 3)
    i = np.arange(nu)[:, None]
    k = np.arange(nv)[None, :]
    i1, k1 = (i + 1) % nu, (k + 1) % nv
    a, b, c, d = i * nv + k, i1 * nv + k, i1 * nv + k1, i * nv + k1
    f = np.stack([a, b, c, a, c, d], axis=2).reshape(-1, 3)
    return TriMesh(v, f, np.array([cls]), np.array([material]))
