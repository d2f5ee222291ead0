"""Heightfield terrain: seeded value noise, island bumps, the terrain mesh and its contours.

Frame and units: world frame (x east, y north, z up, metres), water surface at z = 0. A :class:`Heightfield`
is a regular grid of vertex heights; its mesh splits every grid cell along the diagonal from the south-west
to the north-east corner, and :meth:`Heightfield.sample` interpolates on exactly those triangles, so sampled
heights are the heights of the emitted mesh.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from mmusv.classes import SemanticClass
from mmusv.world.primitives import TriMesh

__all__ = [
    "FaceClassifier",
    "FractalNoise",
    "Heightfield",
    "IslandSpec",
    "ValueNoise",
    "fbm",
    "island_heights",
    "polygons_of",
]

FaceClassifier = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``(centroids (F, 3), unit normals (F, 3)) -> classes (F,) uint16`` for terrain faces."""


class ValueNoise:
    """2-D value noise on a square lattice of random values in [-1, 1], smoothly (quintic) interpolated.

    The lattice covers ``[-half_extent_m - cell_m, half_extent_m + 2 cell_m]`` on both axes; points outside
    are clamped to the border values. One instance draws ``(n + 4)^2`` uniforms from ``rng`` when built.
    """

    def __init__(self, *, rng: np.random.Generator, half_extent_m: float, cell_m: float) -> None:
        self.cell_m = float(cell_m)
        self.origin = -float(half_extent_m) - self.cell_m
        n = int(np.ceil(2.0 * half_extent_m / self.cell_m)) + 4
        self.values = rng.uniform(-1.0, 1.0, size=(n, n))

    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Noise at world ``x``, ``y`` (same-shape float arrays, metres); values in [-1, 1], same shape."""
        n = self.values.shape[0]
        u = np.clip((np.asarray(x, dtype=np.float64) - self.origin) / self.cell_m, 0.0, n - 1.000001)
        v = np.clip((np.asarray(y, dtype=np.float64) - self.origin) / self.cell_m, 0.0, n - 1.000001)
        i = np.floor(v).astype(np.int64)
        j = np.floor(u).astype(np.int64)
        fu = u - j
        fv = v - i
        fu = fu * fu * fu * (fu * (fu * 6.0 - 15.0) + 10.0)
        fv = fv * fv * fv * (fv * (fv * 6.0 - 15.0) + 10.0)
        g = self.values
        a = g[i, j] + (g[i, j + 1] - g[i, j]) * fu
        b = g[i + 1, j] + (g[i + 1, j + 1] - g[i + 1, j]) * fu
        out: np.ndarray = a + (b - a) * fv
        return out


class FractalNoise:
    """Fractal sum of ``octaves`` :class:`ValueNoise` layers (cell halves, amplitude halves per octave),
    normalised by the amplitude sum so values stay in [-1, 1]. Draws its lattices from ``rng`` when built."""

    def __init__(self, *, rng: np.random.Generator, half_extent_m: float, cell_m: float, octaves: int = 4) -> None:
        self.layers = [
            ValueNoise(rng=rng, half_extent_m=half_extent_m, cell_m=cell_m * 0.5**k) for k in range(int(octaves))
        ]

    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Noise at world ``x``, ``y`` (same-shape float arrays, metres); same shape, values in [-1, 1]."""
        total = np.zeros(np.shape(x), dtype=np.float64)
        amp, norm = 1.0, 0.0
        for layer in self.layers:
            total += amp * layer(x, y)
            norm += amp
            amp *= 0.5
        out: np.ndarray = total / norm
        return out


def fbm(
    *, rng: np.random.Generator, x: np.ndarray, y: np.ndarray, half_extent_m: float, cell_m: float, octaves: int = 4
) -> np.ndarray:
    """One-shot :class:`FractalNoise` evaluated at ``x``, ``y``: an array shaped like ``x``, values in [-1, 1]."""
    return FractalNoise(rng=rng, half_extent_m=half_extent_m, cell_m=cell_m, octaves=octaves)(x, y)


@dataclass(frozen=True)
class IslandSpec:
    """One island: centre ``(x, y)`` metres, mean coast radius metres, peak height metres above water,
    ``harmonics`` ``(K, 3)`` rows (order k, relative amplitude, phase rad) shaping the coastline."""

    center: tuple[float, float]
    radius_m: float
    peak_m: float
    harmonics: tuple[tuple[float, float, float], ...]


def island_heights(
    x: np.ndarray,
    y: np.ndarray,
    *,
    islands: list[IslandSpec],
    floor_z: float,
    shelf_slope: float,
    warp: np.ndarray,
    detail: np.ndarray,
    detail_frac: float,
) -> np.ndarray:
    """Terrain heights (metres, same shape as ``x``) for islands on a flat sea floor at ``floor_z``.

    Each island is a radial dome ``peak (1 - s^2)^2`` in the normalised radius ``s = d / r(θ, x, y)``, flat at
    the waterline (a beach), continued under water by a shelf of slope ``shelf_slope`` (m/m) down to
    ``floor_z``. ``r`` carries the island's angular harmonics and the domain ``warp`` (noise in [-1, 1], same
    shape as ``x``, relative radius change). ``detail`` (noise in [-1, 1]) adds relief of
    ``detail_frac * peak`` on land only, fading out towards the coast.
    """
    z = np.full(np.shape(x), floor_z, dtype=np.float64)
    for isl in islands:
        dx = x - isl.center[0]
        dy = y - isl.center[1]
        d = np.hypot(dx, dy)
        theta = np.arctan2(dy, dx)
        shape = np.ones_like(d)
        for k, amp, phase in isl.harmonics:
            shape += amp * np.cos(k * theta + phase)
        r = isl.radius_m * shape * (1.0 + warp)
        s = d / r
        land = s < 1.0
        dome = isl.peak_m * (1.0 - np.minimum(s, 1.0) ** 2) ** 2
        relief = detail_frac * isl.peak_m * detail * np.clip(dome / max(0.15 * isl.peak_m, 1e-9), 0.0, 1.0)
        zi = np.where(land, np.maximum(dome + relief, 0.05 * dome), -(d - r) * shelf_slope)
        z = np.maximum(z, zi)
    return z


def polygons_of(geom: BaseGeometry) -> tuple[Polygon, ...]:
    """The polygons of a (Multi)Polygon or collection, in shapely's stored order; ``()`` when empty."""
    if geom.is_empty:
        return ()
    if isinstance(geom, Polygon):
        return (geom,)
    if isinstance(geom, MultiPolygon):
        return tuple(geom.geoms)
    out: list[Polygon] = []
    for g in getattr(geom, "geoms", ()):
        out.extend(polygons_of(g))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Terrain heights ``z`` ``(ny, nx)`` float64 metres at grid vertices ``(x0 + j*spacing, y0 + i*spacing)``.

    Row index ``i`` grows northwards, column ``j`` eastwards. The surface between vertices is the
    triangulation described in the module docstring.
    """

    x0: float
    y0: float
    spacing: float
    z: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)`` vertex counts."""
        return (int(self.z.shape[0]), int(self.z.shape[1]))

    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertex coordinates: ``xs`` ``(nx,)`` and ``ys`` ``(ny,)`` float64 metres."""
        ny, nx = self.shape
        return self.x0 + np.arange(nx) * self.spacing, self.y0 + np.arange(ny) * self.spacing

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` metres of the grid."""
        ny, nx = self.shape
        return (self.x0, self.y0, self.x0 + (nx - 1) * self.spacing, self.y0 + (ny - 1) * self.spacing)

    def sample(self, xy: npt.ArrayLike) -> np.ndarray:
        """Mesh height at points ``xy`` ``(N, 2)`` (metres, world frame) -> ``(N,)`` float64; NaN outside."""
        p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        ny, nx = self.shape
        u = (p[:, 0] - self.x0) / self.spacing
        v = (p[:, 1] - self.y0) / self.spacing
        inside = (u >= 0.0) & (u <= nx - 1) & (v >= 0.0) & (v <= ny - 1)
        j = np.clip(np.floor(u), 0, nx - 2).astype(np.int64)
        i = np.clip(np.floor(v), 0, ny - 2).astype(np.int64)
        fu = u - j
        fv = v - i
        z = self.z
        z00, z10, z01, z11 = z[i, j], z[i, j + 1], z[i + 1, j], z[i + 1, j + 1]
        lower = z00 + fu * (z10 - z00) + fv * (z11 - z10)
        upper = z00 + fv * (z01 - z00) + fu * (z11 - z01)
        out: np.ndarray = np.where(fu >= fv, lower, upper)
        out[~inside] = np.nan
        return out

    def raster_max(self, *, origin: tuple[float, float], resolution: float, shape: tuple[int, int]) -> np.ndarray:
        """Conservative maximum height over each cell of a raster.

        The raster has ``shape`` ``(H, W)`` cells of ``resolution`` metres, cell ``(r, c)`` covering
        ``[ox + c res, ox + (c+1) res] x [oy + r res, oy + (r+1) res]``. Returns ``(H, W)`` float64: the largest
        vertex height of every grid cell touching the raster cell, which bounds the mesh from above there
        (exactly its maximum when ``resolution`` is a whole multiple of ``spacing`` and the grids line up).
        Vertex indices are clamped to the grid, so raster cells beyond it see the nearest border vertices.
        """
        ny, nx = self.shape

        def windows(n_cells: int, start: float, n_vert: int) -> tuple[np.ndarray, np.ndarray]:
            c = np.arange(n_cells, dtype=np.float64)
            lo = np.floor((start + c * resolution) / self.spacing + 1e-9).astype(np.int64)
            hi = np.ceil((start + (c + 1) * resolution) / self.spacing - 1e-9).astype(np.int64)
            return np.clip(lo, 0, n_vert - 1), np.clip(np.maximum(hi, lo), 0, n_vert - 1)

        def pool(a: np.ndarray, lo: np.ndarray, hi: np.ndarray, axis: int) -> np.ndarray:
            width = int((hi - lo).max()) + 1 if lo.size else 1
            out = np.full((*a.shape[:axis], lo.size, *a.shape[axis + 1 :]), -np.inf)
            for o in range(width):
                idx = np.minimum(lo + o, hi)
                out = np.maximum(out, np.take(a, idx, axis=axis))
            return out

        h, w = shape
        clo, chi = windows(w, origin[0] - self.x0, nx)
        rlo, rhi = windows(h, origin[1] - self.y0, ny)
        return pool(pool(self.z, clo, chi, axis=1), rlo, rhi, axis=0)

    def to_mesh(self, *, min_z: float, classify: FaceClassifier | None = None) -> TriMesh | None:
        """Terrain mesh of the grid cells with any vertex above ``min_z`` metres; ``None`` when there is none.

        Two counter-clockwise (seen from above) triangles per kept cell; unused vertices are dropped.
        Face classes default to TERRAIN; ``classify`` may relabel them (see :data:`FaceClassifier`).
        """
        ny, nx = self.shape
        z = self.z
        cmax = np.maximum(np.maximum(z[:-1, :-1], z[:-1, 1:]), np.maximum(z[1:, :-1], z[1:, 1:]))
        ci, cj = np.nonzero(cmax > min_z)
        if ci.size == 0:
            return None
        v00 = ci * nx + cj
        v10 = v00 + 1
        v01 = v00 + nx
        v11 = v01 + 1
        faces = np.empty((2 * ci.size, 3), dtype=np.int64)
        faces[0::2] = np.column_stack([v00, v10, v11])
        faces[1::2] = np.column_stack([v00, v11, v01])
        used = np.unique(faces)
        remap = np.full(ny * nx, -1, dtype=np.int64)
        remap[used] = np.arange(used.size)
        xs, ys = self.axes()
        verts = np.column_stack([xs[used % nx], ys[used // nx], z.reshape(-1)[used]])
        faces = remap[faces]
        classes = np.full(faces.shape[0], int(SemanticClass.TERRAIN), dtype=np.uint16)
        if classify is not None:
            tri = verts[faces]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            classes = np.asarray(classify(tri.mean(axis=1), n), dtype=np.uint16)
        return TriMesh(verts, faces, classes)

    # ------------------------------------------------------------------ contours (marching triangles)

    def _segments(self, level: float) -> np.ndarray:
        """Level-``level`` contour of the mesh as ``(K, 2, 2)`` segments (metres); shared ends are bitwise equal."""
        ny, nx = self.shape
        z = self.z
        xs, ys = self.axes()
        above = z > level
        # Edge families: H (i,j)-(i,j+1); V (i,j)-(i+1,j); D (i,j)-(i+1,j+1). Ids are offsets into one array.
        n_h, n_v = ny * (nx - 1), (ny - 1) * nx
        ii, jj = np.meshgrid(np.arange(ny - 1), np.arange(nx - 1), indexing="ij")
        e_h0 = ii * (nx - 1) + jj  # H[i, j]
        e_h1 = (ii + 1) * (nx - 1) + jj  # H[i+1, j]
        e_v0 = n_h + ii * nx + jj  # V[i, j]
        e_v1 = n_h + ii * nx + jj + 1  # V[i, j+1]
        e_d = n_h + n_v + ii * (nx - 1) + jj  # D[i, j]
        a00, a10, a01, a11 = above[:-1, :-1], above[:-1, 1:], above[1:, :-1], above[1:, 1:]
        c_h0, c_h1 = a00 != a10, a01 != a11
        c_v0, c_v1, c_d = a00 != a01, a10 != a11, a00 != a11
        segs: list[np.ndarray] = []
        # Triangle 1 (v00, v10, v11): edges H0, V1, D. Triangle 2 (v00, v11, v01): edges D, H1, V0.
        for edges, crossed in (((e_h0, e_v1, e_d), (c_h0, c_v1, c_d)), ((e_d, e_h1, e_v0), (c_d, c_h1, c_v0))):
            e = np.stack([x.reshape(-1) for x in edges], axis=1)
            c = np.stack([x.reshape(-1) for x in crossed], axis=1)
            hit = c.sum(axis=1) == 2
            e, c = e[hit], c[hit]
            order = np.argsort(~c, axis=1, kind="stable")[:, :2]
            segs.append(np.take_along_axis(e, order, axis=1))
        pairs = np.concatenate(segs)
        if pairs.size == 0:
            return np.zeros((0, 2, 2))
        ids = np.unique(pairs)
        # Endpoint vertices of every needed edge, in the family's canonical order (lower index first).
        ea = np.empty((ids.size, 2), dtype=np.int64)
        eb = np.empty((ids.size, 2), dtype=np.int64)
        h = ids < n_h
        v = (ids >= n_h) & (ids < n_h + n_v)
        d = ids >= n_h + n_v
        hi_, hj = np.divmod(ids[h], nx - 1)
        ea[h] = np.column_stack([hi_, hj])
        eb[h] = np.column_stack([hi_, hj + 1])
        vi, vj = np.divmod(ids[v] - n_h, nx)
        ea[v] = np.column_stack([vi, vj])
        eb[v] = np.column_stack([vi + 1, vj])
        di, dj = np.divmod(ids[d] - n_h - n_v, nx - 1)
        ea[d] = np.column_stack([di, dj])
        eb[d] = np.column_stack([di + 1, dj + 1])
        za, zb = z[ea[:, 0], ea[:, 1]], z[eb[:, 0], eb[:, 1]]
        t = (level - za) / (zb - za)
        px = xs[ea[:, 1]] + t * (xs[eb[:, 1]] - xs[ea[:, 1]])
        py = ys[ea[:, 0]] + t * (ys[eb[:, 0]] - ys[ea[:, 0]])
        pts = np.column_stack([px, py])
        idx = np.searchsorted(ids, pairs)
        seg = pts[idx]
        keep = np.any(seg[:, 0] != seg[:, 1], axis=1)
        out: np.ndarray = seg[keep]
        return out

    def contour_lines(self, level: float) -> tuple[np.ndarray, ...]:
        """Level-``level`` contour polylines, each ``(N, 2)`` float64 metres (closed rings repeat their first
        point), ordered by descending length then first point, so the order is deterministic."""
        seg = self._segments(level)
        if seg.shape[0] == 0:
            return ()
        merged = shapely.line_merge(shapely.multilinestrings(shapely.linestrings(seg)))
        lines = [np.asarray(g.coords, dtype=np.float64) for g in getattr(merged, "geoms", [merged])]
        lines.sort(key=lambda a: (-a.shape[0], float(a[0, 0]), float(a[0, 1])))
        return tuple(lines)

    def region_above(self, level: float) -> BaseGeometry:
        """Polygonal region (shapely, metres) where the mesh is above ``level``, clipped to the grid bounds."""
        pad = Heightfield(
            x0=self.x0 - self.spacing,
            y0=self.y0 - self.spacing,
            spacing=self.spacing,
            z=np.pad(self.z, 1, constant_values=min(float(self.z.min()), level) - 1.0),
        )
        seg = pad._segments(level)
        if seg.shape[0] == 0:
            return Polygon()
        faces = shapely.get_parts(shapely.polygonize(shapely.linestrings(seg)))
        if faces.size == 0:
            return Polygon()
        rep = shapely.get_coordinates(shapely.point_on_surface(faces))
        keep = pad.sample(rep) > level
        region = shapely.union_all(faces[keep]) if keep.any() else Polygon()
        return shapely.intersection(region, shapely.box(*self.bounds()))
