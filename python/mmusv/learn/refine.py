"""A geometric second stage for the learned detector: each CenterPoint box tightened on the LiDAR points in it.

Not learned: it fits a rectangle to the points of each proposal with the detection study's training-free steps (the
baseline's water removal, :func:`mmusv.studies.detection.detector.above_water`, and its rectangle fit,
:func:`mmusv.studies.detection.detector.fit_box`, here with the closeness criterion of L-shape fitting: Zhang et
al., "Efficient L-shape fitting for vehicle detection using laser scanners", IEEE IV 2017) and combines that
rectangle with the network's box. The network keeps what the points cannot show (a hull seen from one side shows
its length but not its beam) and its score; the points give what 4 m output cells cannot (where the faces are,
the heading, and the length of hulls longer than the network's receptive field). The rule, with
the constants of :class:`RefineParams` (chosen on the validation split of the bundled dataset;
docs/studies/detection.md gives the measurements):

1. **Points.** The cloud's points above the water: the baseline's plane and ``water.min_height_m`` (0.5 m), and
   within ``near_m`` (50 m) of the sensor ``near_min_height_m`` (1 m), where the wave faces' returns stand above
   0.5 m. In a rough sea the crests rise higher still, so both heights rise to the sea the cloud shows (the
   baseline's :func:`~mmusv.studies.detection.detector.sea_height`, with ``water``'s ``sea_*`` fields, but
   without its column test: see :class:`RefineParams`): the
   ``sea_quantile`` (0.95) of the heights (below ``sea_cap_m``, 4 m) of the returns within ``sea_near_m`` (50 m),
   plus ``sea_margin_m`` (0.5 m) for the crests above it, where those returns cover at least ``sea_cells`` (400)
   cells of 2 m. (Without it, the water's returns round a hull at W3 carry the rounds of step 4 on across the sea:
   boxes 150 m × 80 m round a 27 m ship. The three constants were chosen on every third sequence of the W1 and W3
   sets of docs/studies/detection.md, *Sea state*.)
   Of those, the ones whose BEV position lies in the box grown by ``margin_length_m`` (10 m) at each end
   and ``margin_m`` (3 m) at each side. Fewer than ``min_points`` (3): the box is left as it is.
2. **Heading.** The rectangle ``fit_box`` fits to those points (without its widening; the side directions by the
   closeness criterion, :func:`~mmusv.studies.detection.detector.closeness_axis`: the minimum-area rectangle
   ties between the legs and the hypotenuse of an L of points) has two axes; the one nearer the network's
   heading becomes the length axis, when the rectangle is elongated (long side ≥ ``min_elongation`` (3) × short
   side and ≥ ``min_span_m`` (1 m)); otherwise the network's heading is kept (a blob of points, or a hull seen
   end-on, shows no reliable orientation).
3. **Extent, per axis** (length along the heading, beam across). The points' span on the axis, grown by
   ``pad_length_m`` (0.5 m) or ``pad_beam_m`` (0.25 m) at each end (the outermost returns lie inside the hull's
   outline: a tapering bow, a point spacing), is taken as the extent when the box holds at least
   ``dense_points`` (100) points and the span covers ``span_fraction`` (0.6) of the network's extent (both faces
   seen). Otherwise the extent is the larger of the network's and the span, and the box keeps the network's
   centre on that axis, slid just as far as it must to hold every point (one face seen: the network knows the
   beam; too few points: they under-measure it).
4. **Rounds.** Steps 1–3 are repeated on the new box (up to ``rounds``, 20) until it stops changing, so a hull
   longer than the network's box is followed along its length, ``margin_length_m`` per round, as long as its
   points continue.
5. **Kept from the network:** the score, the centre height ``z`` and the height ``h`` (the study scores BEV IoU).

Boxes: ``(M, 7)`` float64 ``x, y, z, l, w, h, yaw`` in the frame of the points (a LiDAR frame: sensor at the
origin, x forward, y left, z up; metres, radians); the output is row for row the input's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmusv.studies.detection.detector import BaselineParams, above_water, fit_box

__all__ = ["RefineParams", "refine_box", "refine_boxes", "refine_on", "surface_points"]


@dataclass(frozen=True)
class RefineParams:
    """The constants of the rule (module docstring; metres unless said otherwise). ``criterion``: ``fit_box``'s
    (``"closeness"`` or ``"area"``). ``water``: the baseline's parameters, of which the water plane,
    ``min_height_m``, ``self_radius_m`` and the sea's height (``sea_*``) are used; here without the baseline's
    column test (``sea_stack_m`` infinite): a hull's side near the sensor raises the refinement's water height, as it
    did when its constants were chosen, and leaving it out measured lower (AP@0.5 within 50 m of the bundled test
    split 0.856 → 0.821 without fusion, 0.938 → 0.925 early; docs/studies/detection.md)."""

    margin_m: float = 3.0
    margin_length_m: float = 10.0
    min_points: int = 3
    min_elongation: float = 3.0
    min_span_m: float = 1.0
    dense_points: int = 100
    span_fraction: float = 0.6
    pad_length_m: float = 0.5
    pad_beam_m: float = 0.25
    rounds: int = 20
    near_m: float = 50.0
    near_min_height_m: float = 1.0
    criterion: str = "closeness"
    water: BaselineParams = field(default_factory=lambda: BaselineParams(sea_stack_m=math.inf))

    def describe(self) -> str:
        """One line for the study's output."""
        return (
            f"geometric box refinement on the points (margins {self.margin_length_m:g}/{self.margin_m:g} m, "
            f"≥{self.min_points} points, ≤{self.rounds} rounds)"
        )


def surface_points(points: np.ndarray, p: RefineParams) -> np.ndarray:
    """``(K, 2)`` float64 BEV ``x, y`` of the ``points`` ``(N, ≥3)`` above the water (step 1 of the module
    docstring), in their frame."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.shape[0] == 0:
        return np.zeros((0, 2))
    keep, height, _, sea = above_water(pts[:, :3], p.water)
    if p.near_m > 0:
        r = np.hypot(pts[:, 0], pts[:, 1])
        keep &= (r > p.near_m) | (height > max(p.near_min_height_m, sea))
    return pts[keep, :2]


def _axis(
    proj: np.ndarray, extent: float, centre: float, pad: float, dense: bool, p: RefineParams
) -> tuple[float, float]:
    """``(size, centre)`` on one axis of the points' projections ``proj`` (step 3 of the module docstring)."""
    lo, hi = float(proj.min()) - pad, float(proj.max()) + pad
    if dense and hi - lo >= p.span_fraction * extent:
        return hi - lo, (lo + hi) / 2.0
    size = max(extent, hi - lo)
    return size, float(np.clip(centre, hi - size / 2.0, lo + size / 2.0))


def _refine_once(xy: np.ndarray, box: np.ndarray, p: RefineParams) -> np.ndarray:
    out = np.array(box, dtype=np.float64)
    x, y, _, ln, wd, _, yaw = out
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    across = np.array([-heading[1], heading[0]])
    d = xy - np.array([x, y])
    sel = (np.abs(d @ heading) <= ln / 2.0 + p.margin_length_m) & (np.abs(d @ across) <= wd / 2.0 + p.margin_m)
    if int(sel.sum()) < p.min_points:
        return out
    pts = xy[sel]
    rect = fit_box(pts, z_low=0.0, z_high=1.0, min_width_m=0.0, beam_ratio=0.0, min_length_m=0.0, criterion=p.criterion)
    a = heading
    if rect[3] >= p.min_span_m and rect[3] >= p.min_elongation * rect[4]:
        u = np.array([np.cos(rect[6]), np.sin(rect[6])])
        v = np.array([-u[1], u[0]])
        a = u if abs(float(u @ heading)) >= abs(float(v @ heading)) else v
    b = np.array([-a[1], a[0]])
    dense = len(pts) >= p.dense_points
    centre = np.array([x, y])
    length, ca = _axis(pts @ a, float(ln), float(centre @ a), p.pad_length_m, dense, p)
    beam, cb = _axis(pts @ b, float(wd), float(centre @ b), p.pad_beam_m, dense, p)
    out[0], out[1] = ca * a + cb * b
    out[3], out[4] = length, beam
    out[6] = float(np.arctan2(a[1], a[0]))
    return out


def refine_box(xy: np.ndarray, *, box: np.ndarray, p: RefineParams) -> np.ndarray:
    """``(7,)`` the proposal ``box`` refined on ``xy`` ``(K, 2)``, the cloud's :func:`surface_points` (steps 1–4
    of the module docstring); a copy of ``box`` when it holds fewer than ``p.min_points`` of them."""
    out = np.array(box, dtype=np.float64)
    for _ in range(p.rounds):
        nxt = _refine_once(xy, out, p)
        if np.allclose(nxt, out, rtol=0.0, atol=1e-6):
            break
        out = nxt
    return out


def refine_on(xy: np.ndarray, *, boxes: np.ndarray, p: RefineParams) -> np.ndarray:
    """``(M, 7)`` float64 ``boxes`` ``(M, 7)`` refined on a cloud's :func:`surface_points` ``xy``, row for row."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    return np.array([refine_box(xy, box=row, p=p) for row in b]).reshape(-1, 7)


def refine_boxes(points: np.ndarray, boxes: np.ndarray, *, params: RefineParams | None = None) -> np.ndarray:
    """``(M, 7)`` float64 ``boxes`` refined on the cloud ``points`` ``(N, ≥3)`` (same frame, the sensor at the
    origin; module docstring), row for row."""
    p = params or RefineParams()
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    return refine_on(surface_points(points, p), boxes=b, p=p) if b.shape[0] else b.copy()
