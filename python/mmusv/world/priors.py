"""Map priors: the navigable-water raster and the vector layers scenario generation samples and checks against.

Frame and units: world frame (x east, y north, z up), metres, map centred at the origin. Rasters are
``(H, W)`` arrays; cell ``(row, col)`` covers ``x in [ox + col*res, ox + (col+1)*res]`` and
``y in [oy + row*res, oy + (row+1)*res]`` where ``(ox, oy) = origin`` is the south-west corner, so **row 0
is the southern edge and rows grow northwards** (flip vertically to show it as a north-up image).

The masks are conservative: a cell is water only when no terrain anywhere in it rises above
``-draft_margin`` and no structure footprint touches it, so any point of a water cell is open water in the
map meshes. The terrain test takes the highest vertex of every terrain-grid cell the raster cell touches: exact
when the raster resolution is a whole multiple of the terrain spacing (the default, 5 m and 5 m), otherwise
conservative by up to one terrain spacing. Distances are measured between cell centres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from scipy.ndimage import distance_transform_edt
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from mmusv.world.primitives import TriMesh
from mmusv.world.terrain import Heightfield, polygons_of

__all__ = ["MapPriors", "build_priors", "footprint"]


def footprint(mesh: TriMesh) -> Polygon:
    """Convex hull of a mesh's vertices projected on the xy plane (shapely Polygon, metres).

    A mesh with no area seen from above (a vertical plate) gets its hull grown by a millimetre.
    """
    hull = shapely.convex_hull(shapely.multipoints(mesh.vertices[:, :2]))
    if not isinstance(hull, Polygon):
        hull = shapely.buffer(hull, 1e-3)
    assert isinstance(hull, Polygon)
    return hull


@dataclass(frozen=True, eq=False)
class MapPriors:
    """Water mask, shore distance, valid sampling zones and vector layers of one map (see module docstring).

    Attributes:
        resolution: metres per raster cell.
        origin: world ``(x, y)`` of the raster's south-west corner, metres.
        water_mask: ``(H, W)`` bool, True = navigable water (no terrain above ``-draft_margin``, no structure).
        shore_distance: ``(H, W)`` float32 metres from the cell centre to the nearest non-water cell centre;
            0 on non-water cells, ``inf`` everywhere when the map has no non-water cell.
        valid_zones: ``(H, W)`` bool, water cells with ``shore_distance >= clearance``, at least ``clearance``
            from the map edge and from every moored ship.
        clearance: metres, the clearance ``valid_zones`` was built with.
        draft_margin: metres; terrain deeper than this below the surface counts as water.
        shoreline: terrain waterline polylines, each ``(N, 2)`` float64 (closed rings repeat the first point).
        land: polygons where the terrain is above the water surface.
        structure_boundaries: merged footprints of every static structure (quays, piers, breakwaters,
            cranes, container blocks, buildings, buoys), polygons.
        occlusion_regions: footprints of terrain above ``occlusion_height`` and of structures whose top is above
            it: polygons that can block the line of sight between two vessels.
        buoys: ``(B, 2)`` float64 buoy positions.
        moored_footprints: hull rectangles of the moored ships (dynamic assets, not part of the static meshes).
    """

    resolution: float
    origin: tuple[float, float]
    water_mask: np.ndarray
    shore_distance: np.ndarray
    valid_zones: np.ndarray
    clearance: float
    draft_margin: float
    shoreline: tuple[np.ndarray, ...]
    land: tuple[Polygon, ...]
    structure_boundaries: tuple[Polygon, ...]
    occlusion_regions: tuple[Polygon, ...]
    buoys: np.ndarray
    moored_footprints: tuple[Polygon, ...]

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` raster shape."""
        return (int(self.water_mask.shape[0]), int(self.water_mask.shape[1]))

    def world_to_cell(self, xy: npt.ArrayLike) -> np.ndarray:
        """Cells containing points ``xy`` ``(N, 2)`` metres -> ``(N, 2)`` int64 ``(row, col)``; may be out of
        range (see :meth:`in_bounds`)."""
        p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        col = np.floor((p[:, 0] - self.origin[0]) / self.resolution)
        row = np.floor((p[:, 1] - self.origin[1]) / self.resolution)
        return np.column_stack([row, col]).astype(np.int64)

    def cell_to_world(self, rc: npt.ArrayLike) -> np.ndarray:
        """Centres of cells ``rc`` ``(N, 2)`` ``(row, col)`` -> ``(N, 2)`` float64 world ``(x, y)`` metres."""
        c = np.asarray(rc, dtype=np.float64).reshape(-1, 2)
        return np.column_stack(
            [self.origin[0] + (c[:, 1] + 0.5) * self.resolution, self.origin[1] + (c[:, 0] + 0.5) * self.resolution]
        )

    def in_bounds(self, rc: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` bool: cells ``rc`` ``(N, 2)`` lie inside the raster."""
        c = np.asarray(rc).reshape(-1, 2)
        h, w = self.shape
        return (c[:, 0] >= 0) & (c[:, 0] < h) & (c[:, 1] >= 0) & (c[:, 1] < w)

    def _lookup(self, raster: np.ndarray, xy: npt.ArrayLike, outside: float | bool) -> np.ndarray:
        rc = self.world_to_cell(xy)
        ok = self.in_bounds(rc)
        out = np.full(rc.shape[0], outside, dtype=raster.dtype)
        out[ok] = raster[rc[ok, 0], rc[ok, 1]]
        return out

    def is_water(self, xy: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` bool: points ``xy`` ``(N, 2)`` (world, metres) lie in navigable water; False outside the map."""
        return self._lookup(self.water_mask, xy, False)

    def is_valid(self, xy: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` bool: points ``xy`` ``(N, 2)`` lie in :attr:`valid_zones`; False outside the map."""
        return self._lookup(self.valid_zones, xy, False)

    def shore_distance_at(self, xy: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` float64 shore distance (metres) of the cells holding points ``xy`` ``(N, 2)``; 0 outside."""
        return self._lookup(self.shore_distance, xy, 0.0).astype(np.float64)

    def sample_water_points(
        self, n: int, *, rng: np.random.Generator, min_clearance: float | None = None
    ) -> np.ndarray:
        """``n`` points ``(n, 2)`` float64 (world, metres), uniform over the eligible area.

        Eligible cells are :attr:`valid_zones` when ``min_clearance`` is None, otherwise water cells with
        ``shore_distance >= min_clearance``. Raises ``ValueError`` when no cell is eligible.
        """
        ok = self.valid_zones if min_clearance is None else self.water_mask & (self.shore_distance >= min_clearance)
        flat = np.flatnonzero(ok)
        if flat.size == 0:
            raise ValueError(
                f"no water cell with clearance >= {self.clearance if min_clearance is None else min_clearance} m"
            )
        pick = flat[rng.integers(0, flat.size, size=int(n))]
        rc = np.column_stack(np.unravel_index(pick, ok.shape)).astype(np.float64)
        jitter = rng.uniform(0.0, 1.0, size=(int(n), 2))
        return np.column_stack(
            [
                self.origin[0] + (rc[:, 1] + jitter[:, 0]) * self.resolution,
                self.origin[1] + (rc[:, 0] + jitter[:, 1]) * self.resolution,
            ]
        )

    def line_of_sight(self, a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` bool: the segments ``a[i] -> b[i]`` (each ``(N, 2)``, metres) cross no occlusion region."""
        pa = np.asarray(a, dtype=np.float64).reshape(-1, 2)
        pb = np.asarray(b, dtype=np.float64).reshape(-1, 2)
        if not self.occlusion_regions:
            return np.ones(pa.shape[0], dtype=bool)
        occ = shapely.union_all(list(self.occlusion_regions))
        shapely.prepare(occ)
        segs = shapely.linestrings(np.stack([pa, pb], axis=1))
        blocked = np.asarray(shapely.intersects(occ, segs), dtype=bool)
        return ~blocked


def _rasterize(geom: BaseGeometry, *, origin: tuple[float, float], res: float, shape: tuple[int, int]) -> np.ndarray:
    """``(H, W)`` bool: cells whose closed square intersects ``geom``."""
    out = np.zeros(shape, dtype=bool)
    if geom.is_empty:
        return out
    x0, y0, x1, y1 = geom.bounds
    c0 = max(int(np.floor((x0 - origin[0]) / res)) - 1, 0)
    c1 = min(int(np.floor((x1 - origin[0]) / res)) + 1, shape[1] - 1)
    r0 = max(int(np.floor((y0 - origin[1]) / res)) - 1, 0)
    r1 = min(int(np.floor((y1 - origin[1]) / res)) + 1, shape[0] - 1)
    if c1 < c0 or r1 < r0:
        return out
    rr, cc = np.meshgrid(np.arange(r0, r1 + 1), np.arange(c0, c1 + 1), indexing="ij")
    bx0 = origin[0] + cc.ravel() * res
    by0 = origin[1] + rr.ravel() * res
    near = shapely.contains_xy(geom.buffer(res), bx0 + res / 2.0, by0 + res / 2.0)
    boxes = shapely.box(bx0[near], by0[near], bx0[near] + res, by0[near] + res)
    shapely.prepare(geom)
    hit = np.zeros(near.shape, dtype=bool)
    hit[near] = shapely.intersects(geom, boxes)
    out[rr.ravel()[hit], cc.ravel()[hit]] = True
    return out


def build_priors(
    *,
    heightfield: Heightfield,
    structures: list[TriMesh],
    buoys: np.ndarray,
    moored_footprints: list[Polygon],
    extent_m: float,
    resolution_m: float,
    draft_margin_m: float,
    clearance_m: float,
    occlusion_height_m: float,
) -> MapPriors:
    """Derives :class:`MapPriors` from the terrain and the static structure parts (world frame).

    ``structures`` are rigid parts (each a TriMesh, buoys included) whose convex footprints are obstacles;
    ``buoys`` ``(B, 2)`` their positions; the raster has ``round(extent_m / resolution_m)`` cells a side.
    """
    n = max(round(extent_m / resolution_m), 1)
    res = extent_m / n
    origin = (-extent_m / 2.0, -extent_m / 2.0)
    shape = (n, n)
    terrain_max = heightfield.raster_max(origin=origin, resolution=res, shape=shape)
    hulls = [footprint(m) for m in structures]
    union = shapely.union_all(hulls) if hulls else Polygon()
    # A millimetre of slack keeps cells whose edge a footprint meets up to rounding (e.g. after a rotation) out.
    struct = _rasterize(union.buffer(1e-3, quad_segs=2), origin=origin, res=res, shape=shape)
    water = (terrain_max <= -draft_margin_m) & ~struct
    if water.all():
        shore = np.full(shape, np.inf, dtype=np.float32)
    else:
        shore = (distance_transform_edt(water) * res).astype(np.float32)
    centres = origin[0] + (np.arange(n) + 0.5) * res
    edge_1d = np.minimum(centres - origin[0], origin[0] + extent_m - centres)
    edge = np.minimum(edge_1d[:, None], edge_1d[None, :])
    valid = water & (shore >= clearance_m) & (edge >= clearance_m)
    if moored_footprints:
        zone = shapely.union_all(moored_footprints).buffer(clearance_m)
        cx, cy = np.meshgrid(centres, centres)
        valid &= ~shapely.contains_xy(zone, cx, cy)
    tall = [h for h, m in zip(hulls, structures, strict=True) if float(m.vertices[:, 2].max()) > occlusion_height_m]
    occl = shapely.union_all([heightfield.region_above(occlusion_height_m), *tall])
    return MapPriors(
        resolution=float(res),
        origin=origin,
        water_mask=water,
        shore_distance=shore,
        valid_zones=valid,
        clearance=float(clearance_m),
        draft_margin=float(draft_margin_m),
        shoreline=heightfield.contour_lines(0.0),
        land=polygons_of(heightfield.region_above(0.0)),
        structure_boundaries=polygons_of(union),
        occlusion_regions=polygons_of(occl),
        buoys=np.asarray(buoys, dtype=np.float64).reshape(-1, 2),
        moored_footprints=tuple(moored_footprints),
    )
