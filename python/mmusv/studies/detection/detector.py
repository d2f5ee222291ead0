"""Detectors: the interface a user's model plugs into, and the training-free baseline.

**Interface.** A detector is any Python callable ``detect(points) -> (boxes, scores)``:

- ``points``: ``(N, 4)`` float32 ``x, y, z, intensity`` in the ego LiDAR frame (metres; x forward, y left,
  z up; intensity in [0, 1]). For early fusion it is the aggregate of the ego's and its neighbours' points.
- ``boxes``: ``(M, 7)`` float ``x, y, z, l, w, h, yaw`` in the same frame (box centre, length along the
  heading, beam, height, heading in radians); ``scores``: ``(M,)`` float, higher is more confident.

It is selected on the command line as ``--detector package.module:function`` (:func:`load_detector`). A model
that cannot run in-process can instead hand over its predictions as a Parquet file (``--predictions``, see
:mod:`mmusv.studies.detection.predictions`).

**Baseline** (:func:`baseline_detect`, the default). Deterministic, no training, no GPU. It is *not* the learned
model of the paper (a PointPillars-style network), so its absolute numbers are not the paper's:

1. the water surface is fitted as a plane ``z = a·x + b·y + c`` to the lowest point of every occupied 10 m BEV
   cell (least squares, trimmed to the cells within 1 m of the plane, three rounds): this follows the ego's roll,
   pitch and heave without knowing its pose;
2. points more than ``min_height_m`` above that plane are kept; points within ``self_radius_m`` of the sensor
   (the own platform) are dropped. In a rough sea the crests' returns stand higher than that, so the height rises
   to the sea the cloud shows (:func:`sea_height`): the ``sea_quantile`` (0.95) of the heights (below
   ``sea_cap_m``, 4 m) of the returns within ``sea_near_m`` (50 m), plus ``sea_margin_m`` (0.5 m) for the crests
   above it, where those returns cover at least ``sea_cells`` (400) cells of 2 m (a calm sea returns from too
   little water to tell: the fixed height stands; returns stacked more than ``sea_stack_m``, 1 m, high in
   a 1 m column, a hull's side, are not water and are left out). Without it, a W3 sea's crests leave clusters
   of water all round the ego (docs/studies/detection.md, *A baseline that sees the sea*). In rain the LiDAR
   returns from the drops in its beams near the sensor (``sensors/lidar_rain.rs``): of the kept points, those
   within ``rain_radius_m`` (6 m) of the sensor fainter than ``rain_intensity`` (0.025; a drop returns at most
   water's Fresnel reflectance, 0.02) are left out too (:func:`rain_clutter`), the low-intensity outlier test of
   LIOR (Park, Park & Kim 2020, "Fast and Accurate Desnowing Algorithm for LiDAR Point Clouds", IEEE Access 8)
   within a fixed radius; the water plane and the sea's height still see every point (so a cloud without rain
   gives the boxes it gave before this step, 2026-12-08). Without it the drops about the sensor made a box there,
   scored 0.98, in every frame of rain (which the study's evaluation ignores, as it ignores every box centred on a
   USV: a user of the detector saw it);
3. the kept points are binned into 0.5 m BEV cells and the cells are clustered by single linkage with a
   range-adaptive gap (``max(gap_m, gap_per_m · range)``: the LiDAR's point spacing grows with range);
4. each cluster gets the minimum-area rectangle of its points (shapely), with length along the longer side;
   a side seen edge-on is widened to ``max(min_width_m, beam_ratio · length)`` (a usual beam-to-length ratio)
   away from the sensor (the visible face is the near one);
   z spans the water plane to the highest point;
5. the score is the point support ``n / (n + 20)``; clusters with fewer than ``min_points`` points, or larger
   than any vessel (``max_length_m``, ``max_width_m``: land) are dropped.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from mmusv.errors import ConfigError, MmusvError
from mmusv.text import given

__all__ = [
    "BASELINE_NOTE",
    "SEA_CELL_M",
    "SEA_COLUMN_M",
    "BaselineParams",
    "Detector",
    "UserDetector",
    "above_water",
    "baseline_detect",
    "cell_keys",
    "closeness_axis",
    "fit_box",
    "load_detector",
    "rain_clutter",
    "rain_free",
    "sea_height",
    "water_plane",
]

Detector = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
"""``(points (N, 4) float32 ego LiDAR frame) -> (boxes (M, 7), scores (M,))``."""

BASELINE_NOTE = (
    "baseline detector: training-free BEV clustering with oriented box fitting, NOT the paper's "
    "learned model; absolute AP values are not comparable with the paper's"
)


@dataclass(frozen=True)
class BaselineParams:
    """Tuning of :func:`baseline_detect` (metres unless said otherwise). The ``sea_*`` fields: the water height
    learnt from the cloud (:func:`sea_height`; ``sea_cells`` above the cloud's size turns it off)."""

    plane_cell_m: float = 10.0
    min_height_m: float = 0.5
    self_radius_m: float = 2.0
    sea_near_m: float = 50.0
    sea_quantile: float = 0.95
    sea_margin_m: float = 0.5
    sea_cap_m: float = 4.0
    sea_cells: int = 400
    sea_stack_m: float = 1.0
    cell_m: float = 0.5
    gap_m: float = 1.5
    gap_per_m: float = 0.05
    min_points: int = 3
    min_width_m: float = 0.8
    beam_ratio: float = 0.25
    min_length_m: float = 3.0
    max_length_m: float = 320.0
    max_width_m: float = 50.0
    support_half: float = 20.0
    rain_radius_m: float = 6.0
    rain_intensity: float = 0.025
    rain_points: int = 20


def water_plane(points: np.ndarray, *, cell_m: float = 10.0, rounds: int = 3, tol_m: float = 1.0) -> np.ndarray:
    """``(3,)`` plane ``(a, b, c)``, ``z = a·x + b·y + c``, fitted to the lowest point of each ``cell_m`` BEV
    cell of ``points`` ``(N, ≥3)`` (see the module docstring). Fewer than 3 cells: a level plane at the lowest
    point (or 0 without points)."""
    p = np.asarray(points, dtype=np.float64)
    if p.shape[0] == 0:
        return np.zeros(3)
    keys = np.floor(p[:, :2] / cell_m).astype(np.int64)
    order = np.lexsort((p[:, 2], keys[:, 1], keys[:, 0]))
    k = keys[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(k[1:] != k[:-1], axis=1)
    low = p[order[first], :3]
    if low.shape[0] < 3:
        return np.array([0.0, 0.0, float(low[:, 2].min())])
    sel = low[:, 2] <= np.quantile(low[:, 2], 0.5)
    coef = np.array([0.0, 0.0, float(np.median(low[:, 2]))])
    for _ in range(rounds):
        if sel.sum() < 3:
            break
        a = np.column_stack([low[sel, 0], low[sel, 1], np.ones(int(sel.sum()))])
        coef = np.linalg.lstsq(a, low[sel, 2], rcond=None)[0]
        resid = low[:, 2] - (low[:, 0] * coef[0] + low[:, 1] * coef[1] + coef[2])
        sel = np.abs(resid) <= tol_m
    return np.asarray(coef, dtype=np.float64)


SEA_CELL_M = 2.0
"""BEV cell (metres) in which :func:`sea_height` counts how much of the water round the sensor returns."""

SEA_COLUMN_M = 1.0
"""BEV column (metres) whose returns :func:`sea_height` leaves out when they stack higher than ``sea_stack_m``."""


def sea_height(points: np.ndarray, *, height: np.ndarray, r: np.ndarray, params: BaselineParams) -> float:
    """How high the sea's own returns stand above the fitted water plane (metres; step 2 of the module docstring):
    the ``params.sea_quantile`` of the ``height`` of the ``points`` ``(N, ≥2)`` within ``params.sea_near_m``
    (``r``: their BEV range; the sensor's own ``params.self_radius_m`` left out) that lie below
    ``params.sea_cap_m``, plus ``params.sea_margin_m``, where those cover at least ``params.sea_cells`` cells of
    :data:`SEA_CELL_M`; else 0 (a calm sea returns from too little water to tell its crests from the hulls near the
    sensor). Returns in a :data:`SEA_COLUMN_M` column that spans more than ``params.sea_stack_m`` from its lowest to
    its highest are a hull's side, not water, and are left out: a hull within the near range otherwise raised the
    height by up to 2.6 m at W1 (docs/studies/detection.md, *A baseline that sees the sea*)."""
    sel = (r < params.sea_near_m) & (r > params.self_radius_m) & (height < params.sea_cap_m)
    if int(sel.sum()) < params.sea_cells:
        return 0.0
    h = height[sel]
    xy = points[sel, :2]
    water = np.ones(len(h), dtype=bool)
    if np.isfinite(params.sea_stack_m):
        col = cell_keys(np.floor(xy / SEA_COLUMN_M).astype(np.int64))
        order = np.lexsort((h, col))
        c = col[order]
        starts = np.flatnonzero(np.r_[True, c[1:] != c[:-1]])
        ends = np.r_[starts[1:], len(c)]
        flat = h[order][ends - 1] - h[order][starts] <= params.sea_stack_m
        water[order] = np.repeat(flat, ends - starts)
        if int(water.sum()) < params.sea_cells:
            return 0.0
    cell = np.floor(xy[water] / SEA_CELL_M).astype(np.int64)
    if len(np.unique(cell_keys(cell))) < params.sea_cells:
        return 0.0
    return float(np.quantile(h[water], params.sea_quantile)) + params.sea_margin_m


def above_water(
    points: np.ndarray, params: BaselineParams | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Steps 1–2 of the module docstring, for the ``points`` ``(N, ≥3)`` (ego LiDAR frame, metres): the
    ``(N,)`` bool mask of those higher above the fitted water plane than ``params.min_height_m`` and the sea's
    height (:func:`sea_height`) and farther than ``params.self_radius_m`` from the sensor, every point's ``(N,)``
    float64 height above that plane (metres), the plane ``(a, b, c)`` (:func:`water_plane`) and the sea's height
    (metres; 0 where the cloud shows no rough sea)."""
    prm = params or BaselineParams()
    p = np.asarray(points, dtype=np.float64)
    if p.shape[0] == 0:
        return np.zeros(0, dtype=bool), np.zeros(0), np.zeros(3), 0.0
    plane = water_plane(p, cell_m=prm.plane_cell_m)
    height = p[:, 2] - (plane[0] * p[:, 0] + plane[1] * p[:, 1] + plane[2])
    r = np.hypot(p[:, 0], p[:, 1])
    sea = sea_height(p, height=height, r=r, params=prm)
    keep: np.ndarray = (height > max(prm.min_height_m, sea)) & (r > prm.self_radius_m)
    return keep, height, plane, sea


def cell_keys(cell: np.ndarray) -> np.ndarray:
    """``(N,)`` int64, one key per row of the integer BEV cell indices ``cell`` ``(N, 2)`` (|index| < 2³¹), ordered
    as the rows are lexicographically: ``np.unique`` on the keys is ``np.unique(cell, axis=0)`` without its row-wise
    sort, an order of magnitude slower (4 of a W3 cloud's 18 ms in the baseline)."""
    c = np.asarray(cell, dtype=np.int64)
    out: np.ndarray = c[:, 0] * (1 << 32) + c[:, 1]
    return out


def _coordinates(pts: np.ndarray) -> shapely.Geometry:
    """The ``(K, 2)`` points ``pts`` as one shapely geometry whose convex hull (and oriented envelope) is theirs:
    a line string through them (one coordinate sequence, built in one step) rather than a multipoint, which builds
    a point geometry per point (GEOS takes the same coordinates from either, in the same order: the same hull and
    rectangle to the bit, tested). The multipoint built so was 57 % of a robustness study with the learned model's
    box refinement (3 ms a cluster). A single point stays a point."""
    return shapely.linestrings(pts) if len(pts) >= 2 else shapely.multipoints(pts)


def closeness_axis(xy: np.ndarray, *, d0_m: float = 0.1) -> np.ndarray | None:
    """``(2,)`` unit direction of one side of the rectangle that best fits the BEV points ``xy`` ``(K, 2)`` as
    seen from one place, by the closeness criterion of L-shape fitting (Zhang et al., "Efficient L-shape fitting
    for vehicle detection using laser scanners", IEEE IV 2017): for a direction, each point's distance to the
    nearer of the rectangle's two sides along each axis (the side the points lie closer to, as a whole), the
    smaller of the two, floored at ``d0_m``; the score is the sum of the inverses. The candidate directions are
    the edges of the points' convex hull (one of which the minimum-area rectangle has, by rotating calipers).
    Unlike the minimum area, the criterion does not tie for an L of points: the rectangle on the hypotenuse of
    a right triangle has the same area as the one on its legs. ``None`` for fewer than 3 points or a hull
    without area (collinear points)."""
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if pts.shape[0] < 3:
        return None
    hull = shapely.convex_hull(_coordinates(pts))
    if hull.geom_type != "Polygon":
        return None
    ring = np.asarray(hull.exterior.coords)
    edges = np.diff(ring, axis=0)
    length = np.hypot(edges[:, 0], edges[:, 1])
    keep = length > 1e-9
    # every hull edge at once: rows are edges, columns points
    u = edges[keep] / length[keep, None]
    d = np.full((len(u), len(pts)), np.inf)
    for ax in (u, np.column_stack([-u[:, 1], u[:, 0]])):
        c = ax @ pts.T
        lo, hi = c - c.min(axis=1, keepdims=True), c.max(axis=1, keepdims=True) - c
        near_lo = np.sqrt(np.einsum("ek,ek->e", lo, lo)) <= np.sqrt(np.einsum("ek,ek->e", hi, hi))
        d = np.minimum(d, np.where(near_lo[:, None], lo, hi))
    scores = np.sum(1.0 / np.maximum(d, d0_m), axis=1)
    best, best_score = None, -1.0
    for e, score in enumerate(scores.tolist()):  # the first of (near-)equal scores, edge by edge along the ring
        if score > best_score + 1e-9:
            best, best_score = u[e], score
    return best


def fit_box(
    xy: np.ndarray,
    *,
    z_low: float,
    z_high: float,
    min_width_m: float = 0.8,
    beam_ratio: float = 0.25,
    min_length_m: float = 3.0,
    criterion: str = "area",
) -> np.ndarray:
    """``(7,)`` box ``x, y, z, l, w, h, yaw`` of the BEV points ``xy`` ``(K, 2)`` (K ≥ 1): the bounding
    rectangle chosen by ``criterion`` (``"area"``: the minimum-area one; ``"closeness"``:
    :func:`closeness_axis`), length along the longer side, yaw in (-π/2, π/2]; a width under
    ``max(min_width_m, beam_ratio · length)`` is widened to it away from the origin (the sensor); a length under
    ``min_length_m`` is raised."""
    if criterion not in ("area", "closeness"):
        raise ValueError(f"fit_box criterion {criterion!r}: allowed: area, closeness")
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    axis = closeness_axis(pts) if criterion == "closeness" else None
    if axis is not None:
        across = np.array([-axis[1], axis[0]])
        pu, pv = pts @ axis, pts @ across
        e1, e2 = axis * float(np.ptp(pu)), across * float(np.ptp(pv))
        centre = axis * (pu.min() + pu.max()) / 2.0 + across * (pv.min() + pv.max()) / 2.0
    else:
        rect = shapely.minimum_rotated_rectangle(_coordinates(pts))
        if rect.geom_type == "Polygon":
            c = np.asarray(rect.exterior.coords)[:4]
            e1, e2 = c[1] - c[0], c[2] - c[1]
            centre = c.mean(axis=0)
        else:  # a segment or a point
            c = np.asarray(rect.coords) if rect.geom_type == "LineString" else pts[:1]
            e1 = c[-1] - c[0] if len(c) > 1 else np.array([0.0, 0.0])
            e2 = np.zeros(2)  # no extent across
            centre = c.mean(axis=0)
    if np.hypot(*e2) > np.hypot(*e1):
        e1, e2 = e2, e1
    length, width = float(np.hypot(*e1)), float(np.hypot(*e2))
    if length > 1e-9:
        u = e1 / length
    else:
        r = np.hypot(*centre)
        u = np.array([-centre[1], centre[0]]) / r if r > 1e-9 else np.array([1.0, 0.0])
    v = np.array([-u[1], u[0]])
    out_dir = 1.0 if float(np.dot(v, centre)) >= 0 else -1.0  # across the box, away from the sensor
    length = max(length, min_length_m)
    wmin = max(min_width_m, beam_ratio * length)
    if width < wmin:
        centre = centre + v * out_dir * (wmin - width) / 2.0
        width = wmin
    yaw = float(np.arctan2(u[1], u[0]))
    if yaw <= -np.pi / 2:
        yaw += np.pi
    elif yaw > np.pi / 2:
        yaw -= np.pi
    h = max(z_high - z_low, 0.1)
    return np.array([centre[0], centre[1], (z_low + z_high) / 2.0, length, width, h, yaw])


def linked_pairs(centres: np.ndarray, gap: np.ndarray, *, growth: float = 2.0) -> np.ndarray:
    """``(P, 2)`` int64 index pairs ``i < j`` of the BEV cells ``centres`` ``(n, 2)`` (metres) no farther apart
    than the smaller of their gaps ``gap`` ``(n,)`` (metres), each pair once: step 3's links. Searched level by level
    rather than within the largest gap everywhere: the pairs whose smaller gap is the least gap ``t_0`` (every
    near cell's) among all cells within ``t_0``; then, for ``t_l = t_0 · growth^l`` up to the largest gap, those
    whose smaller gap lies in ``(t_(l−1), t_l]`` among only the cells with gaps above ``t_(l−1)`` (the far, sparse
    ones) within ``t_l``. One search within the largest gap (11 m at 220 m range) met about 200 near cells around
    every near cell: 1.7 M candidate pairs for 0.14 M links in an early-fusion cloud of a port, most of the
    baseline's time in the robustness study."""
    gap = np.asarray(gap, dtype=np.float64)
    if len(gap) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    top = float(gap.max())
    levels = [(-np.inf, float(gap.min()))]
    while levels[-1][1] < top:
        levels.append((levels[-1][1], min(levels[-1][1] * growth, top)))
    found = []
    for above, r in levels:
        idx = np.flatnonzero(gap > above)
        if len(idx) < 2:
            continue
        sub = idx[cKDTree(centres[idx]).query_pairs(r=r, output_type="ndarray")].reshape(-1, 2)
        d = np.hypot(*(centres[sub[:, 0]] - centres[sub[:, 1]]).T)
        least = np.minimum(gap[sub[:, 0]], gap[sub[:, 1]])
        found.append(sub[(d <= least) & (least > above) & (least <= r)])  # each pair at its smaller gap's level
    return np.concatenate(found).astype(np.int64) if found else np.zeros((0, 2), dtype=np.int64)


def rain_clutter(points: np.ndarray, params: BaselineParams | None = None) -> np.ndarray:
    """Step 2 of the module docstring, its rain: the ``(N,)`` bool mask of the ``points`` ``(N, 4)`` (ego LiDAR
    frame, metres, intensity) that look like rain drops: nearer the sensor than ``params.rain_radius_m`` (3D range)
    and fainter than ``params.rain_intensity``."""
    prm = params or BaselineParams()
    p = np.asarray(points, dtype=np.float64)
    if p.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    near = np.einsum("ij,ij->i", p[:, :3], p[:, :3]) < prm.rain_radius_m**2
    faint: np.ndarray = near & (p[:, 3] < prm.rain_intensity)
    return faint


def rain_free(points: np.ndarray, params: BaselineParams | None = None) -> np.ndarray:
    """The ``points`` ``(N, 4)`` of one LiDAR's own cloud (its frame, metres, intensity) less its rain drops, in
    their order and dtype: where rain shows (at least ``params.rain_points`` of the faint points near the sensor,
    :func:`rain_clutter`, lie above its own height plus ``min_height_m``, where no water returns), every such faint
    near point; else those of them kept above the sea (:func:`above_water`: none of a dry cloud's, so far as
    checked). Early fusion passes every agent's cloud through it before gathering them
    (:func:`mmusv.studies.detection.fusion.early_points`): the drops about a neighbour's sensor lie far from the
    ego's, where :func:`baseline_detect` cannot tell them, and its water plane is not theirs (drops just above a
    neighbour's water stood above the ego's plane)."""
    p = np.asarray(points)
    if p.shape[0] == 0:
        return p
    prm = params or BaselineParams()
    q = p.astype(np.float64)
    clutter = rain_clutter(q, prm)
    if not clutter.any():
        return p
    # Rain shows where faint returns lie about the sensor above its own height, where no water reaches: then every
    # faint point near it goes (the drops down to the water too, which another sensor's water plane may put above
    # the sea); else only those kept above the sea (so a dry cloud keeps every point it kept).
    raining = int(np.count_nonzero(clutter & (q[:, 2] > prm.min_height_m))) >= prm.rain_points
    drop = clutter if raining else clutter & above_water(q, prm)[0]
    out: np.ndarray = p[~drop]
    return out


def baseline_detect(points: np.ndarray, params: BaselineParams | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The baseline detector (see the module docstring): ``points`` ``(N, 4)`` float32 in the ego LiDAR frame →
    boxes ``(M, 7)`` float64 and scores ``(M,)`` float64, sorted by descending score then position."""
    prm = params or BaselineParams()
    p = np.asarray(points, dtype=np.float64).reshape(-1, 4) if np.size(points) else np.zeros((0, 4))
    if p.shape[0] == 0:
        return np.zeros((0, 7)), np.zeros(0)
    keep, _, (a, b, c), _ = above_water(p, prm)
    q = p[keep & ~rain_clutter(p, prm)]
    if q.shape[0] < prm.min_points:
        return np.zeros((0, 7)), np.zeros(0)
    cell = np.floor(q[:, :2] / prm.cell_m).astype(np.int64)
    _, first, inv = np.unique(cell_keys(cell), return_index=True, return_inverse=True)
    uniq = cell[first]
    inv = inv.reshape(-1)
    centres = (uniq + 0.5) * prm.cell_m
    rng = np.hypot(centres[:, 0], centres[:, 1])
    gap = np.maximum(prm.gap_m, prm.gap_per_m * rng)
    pairs = linked_pairs(centres, gap)
    n = uniq.shape[0]
    graph = coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])) if len(pairs) else ([], ([], [])), shape=(n, n)
    )
    _, cell_label = connected_components(graph, directed=False)
    label = cell_label[inv]
    boxes: list[np.ndarray] = []
    scores: list[float] = []
    order = np.argsort(label, kind="stable")
    starts = np.flatnonzero(np.r_[True, label[order][1:] != label[order][:-1]])
    for group in np.split(order, starts[1:]):
        npts = len(group)
        if npts < prm.min_points:
            continue
        pts = q[group]
        z_low = float(np.mean(a * pts[:, 0] + b * pts[:, 1] + c))
        box = fit_box(
            pts[:, :2],
            z_low=z_low,
            z_high=float(pts[:, 2].max()),
            min_width_m=prm.min_width_m,
            beam_ratio=prm.beam_ratio,
            min_length_m=prm.min_length_m,
        )
        if box[3] > prm.max_length_m or box[4] > prm.max_width_m:
            continue
        boxes.append(box)
        scores.append(npts / (npts + prm.support_half))
    if not boxes:
        return np.zeros((0, 7)), np.zeros(0)
    bx = np.array(boxes)
    sc = np.array(scores)
    rank = np.lexsort((bx[:, 1], bx[:, 0], -sc))
    return bx[rank], sc[rank]


def load_detector(spec: str) -> Detector:
    """The callable named by ``spec`` = ``"package.module:function"``, as a :class:`UserDetector` whose failures
    name ``spec`` (``"baseline"`` is :func:`baseline_detect`): as its user gave it (:func:`mmusv.text.given`:
    ``spec = 'pkg.mod:fn'`` from Python, ``--detector pkg.mod:fn`` from ``mmusv study``)."""
    if spec == "baseline":
        return baseline_detect
    mod_name, sep, attr = spec.partition(":")
    if not sep or not mod_name or not attr:
        raise ConfigError(f"{given('spec', spec)}: expected 'baseline' or 'package.module:function'")
    try:
        mod = importlib.import_module(mod_name)
    except ImportError as exc:
        raise ConfigError(f"{given('spec', spec)}: cannot import module {mod_name!r} ({exc})") from None
    fn = getattr(mod, attr, None)
    if not callable(fn):
        raise ConfigError(f"{given('spec', spec)}: module {mod_name!r} has no callable {attr!r}")
    return baseline_detect if fn is baseline_detect else UserDetector(spec, fn)


_SIGNATURE = (
    "expected detect(points (N, 4) float32 x, y, z, intensity in the ego LiDAR frame) -> "
    "(boxes (M, 7) x, y, z, l, w, h, yaw, scores (M,))"
)


class UserDetector:
    """The user's detector ``fn`` named by ``spec`` (``--detector`` of ``mmusv study``), called as itself: an
    exception it raises (a function of another signature, a bug in it) becomes a :class:`~mmusv.errors.ConfigError`
    naming ``spec`` as :func:`load_detector` does,
    what failed and the signature expected. Its other attributes (``early``, a detector's own early-fusion
    entry) are its own, ``early`` checked the same way."""

    def __init__(self, spec: str, fn: Callable[..., object], name: str | None = None) -> None:
        self.spec, self.fn, self.name = spec, fn, name

    def __call__(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        what = f"its {self.name!r}" if self.name else "calling it"
        try:
            out = self.fn(points)
        except MmusvError:
            raise
        except Exception as exc:
            raise ConfigError(
                f"{given('spec', self.spec)}: {what} on a ({len(points)}, 4) point cloud failed: "
                f"{type(exc).__name__}: {exc}; {_SIGNATURE}"
            ) from exc
        if not isinstance(out, (tuple, list)) or len(out) != 2:
            raise ConfigError(f"{given('spec', self.spec)}: {what} returned {type(out).__name__}; {_SIGNATURE}")
        return out[0], out[1]

    def __getattr__(self, name: str) -> object:
        if name.startswith("__") or "fn" not in self.__dict__:
            raise AttributeError(name)
        value = getattr(self.fn, name)
        return UserDetector(self.spec, value, name) if name == "early" and callable(value) else value
