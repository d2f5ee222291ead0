"""Harbour approach routes on port maps: shortest grid paths from open water into the harbour basin for a hull
that needs a given clearance.

The basin is the navigable water inside the convex hull of the port's large structures (quay, breakwaters,
yard); its goal cell is the basin cell farthest from any obstacle. For a clearance ``c`` (metres, compared with
:meth:`MapContext.clearance`), one multi-neighbour Dijkstra over the cells with at least ``c`` of clearance
(8-connected, edge weights in metres) gives every cell's path length to the goal and the path itself, cached per
clearance. World frame, metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from mmusv.errors import MmusvError
from mmusv.generate.mapctx import MapContext

__all__ = ["HarbourPlanner", "PlannerError", "harbour_planner"]


class PlannerError(MmusvError):
    """No route exists (the message says why)."""


@dataclass(frozen=True)
class _Field:
    dist: np.ndarray  # (H*W,) metres to the goal, inf where unreachable
    pred: np.ndarray  # (H*W,) predecessor towards the goal, -9999 at the goal / unreachable
    outside: np.ndarray  # (K,) flat indices of reachable cells outside the basin
    entry_dist: float  # path length from the basin boundary (entrance) to the goal


class HarbourPlanner:
    """Paths into the harbour basin of one port map (see module docstring)."""

    def __init__(self, ctx: MapContext) -> None:
        self.ctx = ctx
        big = [p for p in ctx.priors.structure_boundaries if p.area >= 500.0]
        if not big:
            raise PlannerError("the map has no port structures, so no harbour basin")
        self.basin = shapely.union_all(big).convex_hull
        h, w = ctx.d_nav.shape
        res = ctx.resolution
        cx = ctx.origin[0] + (np.arange(w) + 0.5) * res
        cy = ctx.origin[1] + (np.arange(h) + 0.5) * res
        gx, gy = np.meshgrid(cx, cy)
        self.centres = np.column_stack([gx.ravel(), gy.ravel()])
        self.in_basin = np.asarray(shapely.contains_xy(self.basin, gx, gy), dtype=bool).ravel()
        self.clear = (ctx.d_nav - ctx.cell_slack).ravel()
        self._fields: dict[float, _Field] = {}

    def field(self, need: float) -> _Field:
        """The Dijkstra field for hulls needing ``need`` metres of clearance (rounded up to 5 m, cached)."""
        key = float(5.0 * math.ceil(need / 5.0))
        if key in self._fields:
            return self._fields[key]
        h, w = self.ctx.d_nav.shape
        nav = self.clear >= key
        basin_nav = np.flatnonzero(nav & self.in_basin)
        if basin_nav.size == 0:
            raise PlannerError(f"no water in the harbour basin has {key:.0f} m of clearance")
        goal = int(basin_nav[np.argmax(self.clear[basin_nav])])
        idx = np.arange(h * w).reshape(h, w)
        rows, cols, wts = [], [], []
        res = self.ctx.resolution
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            r0, r1 = max(0, -dr), h - max(0, dr)
            c0, c1 = max(0, -dc), w - max(0, dc)
            a = idx[r0:r1, c0:c1].ravel()
            b = idx[r0 + dr : r1 + dr, c0 + dc : c1 + dc].ravel()
            keep = nav[a] & nav[b]
            rows.append(a[keep])
            cols.append(b[keep])
            wts.append(np.full(int(keep.sum()), res * math.hypot(dr, dc)))
        r, c, wt = np.concatenate(rows), np.concatenate(cols), np.concatenate(wts)
        graph = coo_matrix((wt, (r, c)), shape=(h * w, h * w)).tocsr()
        dist, pred = dijkstra(graph, directed=False, indices=goal, return_predecessors=True)
        reach = np.isfinite(dist)
        outside = np.flatnonzero(reach & ~self.in_basin)
        if outside.size == 0:
            raise PlannerError(
                f"no navigable path from open water into the harbour for a hull needing {key:.0f} m of clearance"
            )
        fld = _Field(dist=dist, pred=pred, outside=outside, entry_dist=float(dist[outside].min()))
        self._fields[key] = fld
        return fld

    def approach(self, need: float, *, entry_after_m: float, rng: np.random.Generator) -> np.ndarray:
        """A path ``(K, 2)`` (metres) from an open-water cell into the basin goal, crossing into the basin about
        ``entry_after_m`` metres after its start, simplified to waypoints; raises :class:`PlannerError`."""
        fld = self.field(need)
        target = fld.entry_dist + entry_after_m
        d = fld.dist[fld.outside]
        tol = 2.0 * self.ctx.resolution
        cand = fld.outside[np.abs(d - target) <= tol]
        if cand.size == 0:
            far = float(d.max()) - fld.entry_dist
            raise PlannerError(
                f"open water reaches at most {far:.0f} m from the harbour entrance (wanted {entry_after_m:.0f} m)"
            )
        cur = int(cand[rng.integers(cand.size)])
        cells = [cur]
        while fld.pred[cur] >= 0:
            cur = int(fld.pred[cur])
            cells.append(cur)
        pts = self.centres[np.asarray(cells)]
        line = shapely.simplify(shapely.linestrings(pts), self.ctx.resolution)
        out = np.asarray(shapely.get_coordinates(line), dtype=np.float64)
        if out.shape[0] < 2:
            out = np.vstack([pts[0], pts[-1]])
        return out


def harbour_planner(ctx: MapContext) -> HarbourPlanner:
    """The planner of a map context, built once and kept in ``ctx.cache``; raises :class:`PlannerError` on maps
    without a harbour."""
    planner = ctx.cache.get("harbour_planner")
    if planner is None:
        planner = HarbourPlanner(ctx)
        ctx.cache["harbour_planner"] = planner
    assert isinstance(planner, HarbourPlanner)
    return planner
