"""Per-map data shared by the sampler and the checks: clearance rasters, the static ray-casting scene and
candidate occluders (islands), built once per ``(kind, seed, params)`` and cached.

Frame and units: world frame (x east, y north, z up), metres; rasters share the grid of
:class:`mmusv.world.priors.MapPriors` (row 0 is the southern edge). Distances in the rasters are between cell
centres, like ``MapPriors.shore_distance``:

- ``d_shore``: distance to the nearest cell that is not navigable water (terrain, shallows, static structures)
  or lies outside the map;
- ``d_struct``: distance to the nearest cell touched by a static structure (quays, piers, breakwaters, cranes,
  buildings, buoys) or a moored ship (``inf`` when the map has none);
- ``d_nav = min(d_shore, d_struct)``.

A point ``p`` whose raster value is ``D`` lies at least ``D - resolution·√2`` from the obstacle region itself
(half a cell diagonal at each end), which :data:`cell_slack` gives; the checks subtract it to be conservative.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt
import shapely
from scipy.ndimage import distance_transform_edt
from shapely.geometry import Polygon

from mmusv.scene import Scene
from mmusv.world.build import build_static_scene
from mmusv.world.maps import MapWorld, generate_map

__all__ = ["MapContext", "Occluder", "map_context"]


@dataclass(frozen=True)
class Occluder:
    """An island-like occlusion region: ``polygon`` (metres), ``centre`` (its centroid, inside it) and
    ``diameter`` (of the circle with the same area)."""

    polygon: Polygon
    centre: np.ndarray
    diameter: float


class MapContext:
    """One generated map with the rasters, scene and occluders the generator needs (see module docstring)."""

    def __init__(self, world: MapWorld) -> None:
        self.world = world
        pri = world.priors
        self.priors = pri
        self.resolution = float(pri.resolution)
        self.origin = (float(pri.origin[0]), float(pri.origin[1]))
        self.extent = float(pri.shape[0] * self.resolution)
        self.cell_slack = self.resolution * math.sqrt(2.0)
        h, w = pri.shape
        padded = np.pad(pri.water_mask, 1, constant_values=False)
        self.d_shore: np.ndarray = (distance_transform_edt(padded) * self.resolution)[1:-1, 1:-1].astype(np.float64)
        obstacles = [*pri.structure_boundaries, *pri.moored_footprints]
        if obstacles:
            geom = shapely.union_all(obstacles).buffer(self.resolution / math.sqrt(2.0) + 1e-6, quad_segs=4)
            shapely.prepare(geom)
            cx = self.origin[0] + (np.arange(w) + 0.5) * self.resolution
            cy = self.origin[1] + (np.arange(h) + 0.5) * self.resolution
            gx, gy = np.meshgrid(cx, cy)
            touched = np.asarray(shapely.contains_xy(geom, gx, gy), dtype=bool)
            self.d_struct: np.ndarray = (distance_transform_edt(~touched) * self.resolution).astype(np.float64)
        else:
            self.d_struct = np.full((h, w), np.inf)
        self.d_nav: np.ndarray = np.minimum(self.d_shore, self.d_struct)
        self._scene: Scene | None = None
        self.occluders = self._find_occluders()
        self.cache: dict[str, Any] = {}
        """Derived per-map helpers (e.g. the harbour planner), built on first use."""

    # ------------------------------------------------------------------------------------------ rasters

    def lookup(self, raster: np.ndarray, xy: npt.ArrayLike) -> np.ndarray:
        """Raster values at points ``xy`` ``(..., 2)`` metres -> ``(...)`` float64; 0 outside the map."""
        p = np.asarray(xy, dtype=np.float64)
        shape = p.shape[:-1]
        p = p.reshape(-1, 2)
        col = np.floor((p[:, 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((p[:, 1] - self.origin[1]) / self.resolution).astype(np.int64)
        h, w = raster.shape
        ok = (row >= 0) & (row < h) & (col >= 0) & (col < w)
        out = np.zeros(p.shape[0], dtype=np.float64)
        out[ok] = raster[row[ok], col[ok]]
        return out.reshape(shape)

    def clearance(self, xy: npt.ArrayLike) -> np.ndarray:
        """Conservative distance (metres) from points ``xy`` ``(..., 2)`` to any obstacle: ``d_nav - cell_slack``."""
        return self.lookup(self.d_nav, xy) - self.cell_slack

    def sample_points(self, n: int, *, min_clearance: float, rng: np.random.Generator) -> np.ndarray:
        """``n`` points ``(n, 2)`` uniform over the water cells of the map priors whose shore distance is at
        least ``min_clearance`` (halved, down to the priors' ``clearance``, while no cell qualifies), each
        jittered uniformly inside its cell. Raises ``ValueError`` when the map has no valid cell at all."""
        cells = self._eligible(float(min_clearance))
        pick = cells[rng.integers(0, cells.size, size=int(n))]
        row, col = np.unravel_index(pick, self.priors.shape)
        jitter = rng.uniform(0.0, 1.0, size=(int(n), 2))
        return np.column_stack(
            [
                self.origin[0] + (col + jitter[:, 0]) * self.resolution,
                self.origin[1] + (row + jitter[:, 1]) * self.resolution,
            ]
        )

    def _eligible(self, need: float) -> np.ndarray:
        """Water cells of the priors at least ``need`` metres from shore, ``need`` halved (down to the priors'
        ``clearance``) while none qualifies; a loop, so any finite ``need`` ends quickly."""
        key = f"eligible:{need:.3f}"
        if key not in self.cache:
            pri = self.priors
            ok = pri.water_mask & pri.valid_zones
            if not ok.any():
                raise ValueError(f"the map has no valid water cell (clearance {pri.clearance:g} m)")
            need_now, top = float(need), float(pri.shore_distance[ok].max())
            while need_now > top and need_now > pri.clearance:  # no cell qualifies: halve without looking
                need_now = max(need_now / 2.0, pri.clearance)
            while True:
                cells = np.flatnonzero(ok & (pri.shore_distance >= need_now))
                if cells.size > 0:
                    break
                if need_now <= pri.clearance:
                    raise ValueError(f"the map has no valid water cell (clearance {pri.clearance:g} m)")
                need_now = max(need_now / 2.0, pri.clearance)
            self.cache[key] = cells
        out: np.ndarray = self.cache[key]
        return out

    # ------------------------------------------------------------------------------------- ray casting

    @property
    def scene(self) -> Scene:
        """The static map (terrain, structures, buoys, moored ships; no water plane) as a ray-castable scene."""
        if self._scene is None:
            self._scene = build_static_scene(self.world, include_water=False).scene
        return self._scene

    def blocked(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``(N,)`` bool: the segment ``a[i] -> b[i]`` (``(N, 3)`` world points, metres) hits the static map
        before reaching ``b[i]`` (one batched ray cast)."""
        a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
        b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
        if a.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        d = b - a
        length = np.linalg.norm(d, axis=1)
        ok = length > 1e-6
        out = np.zeros(a.shape[0], dtype=bool)
        if not ok.any():
            return out
        dirs = d[ok] / length[ok, None]
        hits = self.scene.cast_rays(
            a[ok].astype(np.float32), dirs.astype(np.float32), max_range=float(length[ok].max())
        )
        out[ok] = np.isfinite(hits.distance) & (hits.distance.astype(np.float64) < length[ok] - 1e-3)
        return out

    # ------------------------------------------------------------------------------------------ occluders

    def _find_occluders(self) -> tuple[Occluder, ...]:
        half = self.extent / 2.0
        out = []
        for poly in self.priors.occlusion_regions:
            if poly.area < 2000.0:
                continue
            hull = poly.convex_hull
            if poly.area < 0.5 * hull.area:
                continue
            c = poly.centroid
            if not poly.contains(c):
                continue
            x0, y0, x1, y1 = poly.bounds
            if min(x0 + half, y0 + half, half - x1, half - y1) < 60.0:
                continue
            out.append(
                Occluder(polygon=poly, centre=np.array([c.x, c.y]), diameter=2.0 * math.sqrt(poly.area / math.pi))
            )
        return tuple(out)

    def ray_exit(self, centre: np.ndarray, *, angle: float, need: float, max_len: float) -> float | None:
        """Distance from ``centre`` along the ray at ``angle`` (radians from +x) to the first point from which
        the conservative clearance stays at least ``need`` for 40 m; None when there is none within ``max_len``."""
        step = self.resolution / 2.0
        s = np.arange(0.0, max_len, step)
        pts = centre[None, :] + s[:, None] * np.array([math.cos(angle), math.sin(angle)])[None, :]
        ok = self.clearance(pts) >= need
        run = round(40.0 / step)
        if ok.size < run:
            return None
        # windows of `run` consecutive ok samples, after the first not-ok sample (we start inside the island)
        bad = np.flatnonzero(~ok)
        if bad.size == 0:
            return None
        window = np.convolve(ok.astype(np.int64), np.ones(run, dtype=np.int64), mode="valid") == run
        idx = np.flatnonzero(window & (np.arange(window.size) > bad[0]))
        return float(s[idx[0]]) if idx.size else None


@lru_cache(maxsize=8)
def _cached(kind: str, seed: int, params_json: str) -> MapContext:
    params: dict[str, Any] = json.loads(params_json)
    return MapContext(generate_map(kind, seed=seed, **params))


def map_context(kind: str, *, seed: int, params: dict[str, Any]) -> MapContext:
    """The (cached) :class:`MapContext` of the map ``kind``/``seed``/``params``."""
    return _cached(kind, int(seed), json.dumps(params, sort_keys=True))
