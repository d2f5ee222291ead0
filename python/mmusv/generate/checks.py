"""Named, configurable constraints checked on a candidate scenario, vectorised (no Python call per sample).

One :class:`~mmusv.generate.samples.Samples` per candidate holds everything the checks read (its route geometry,
motion and frames, sampled in Rust by :mod:`mmusv.generate.samples`, which also bounds how many samples they take).

Continuous guarantees: between two samples a vessel is within ``δ`` of one (half the route spacing, or
``speed·dt/2`` in time), and a raster distance ``D`` is at least ``D - cell_slack`` from the obstacle itself
(:mod:`mmusv.generate.mapctx`), so the clearance and separation checks subtract both and hold for every point of
every route and every instant, not just the samples. Hulls are capsules covering the hull rectangle at the
vessel's yaw (:mod:`mmusv.generate.hulls`); between samples the capsule axis ends also turn with the yaw, which
adds ``a·|Δyaw|/2`` (largest yaw step between samples) to ``δ``. Frame-based checks (ranges, shares, line of
sight) are evaluated at the acquisition frames.
Line of sight: a ray from the USV sensor (``sensor_height_m`` above the water) to the middle of the target's
above-water height, cast against the static map (terrain, structures, buoys, moored ships) in one batch.

World frame, metres, seconds. Each check returns None (pass) or a one-line reason. The checks the scenario editor
shows on its map (in water, clearances, separation, sensing range, cooperation, line of sight) also have
``findings(samples)``: every failure, one :class:`Finding` per vessel or pair, with where it happens; ``check`` is
the first of them, so the generator and the editor say the same thing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from scipy.ndimage import distance_transform_edt
from scipy.spatial import cKDTree

from mmusv.generate.hulls import axis_points, capsule, segment_distance
from mmusv.generate.mapctx import MapContext
from mmusv.generate.samples import Samples
from mmusv.generate.spec_constraints import (
    CooperationCheck,
    LineOfSightCheck,
    OcclusionCheck,
    RouteSeparationCheck,
    SensingRangeCheck,
    SeparationCheck,
    ShoreClearanceCheck,
    StructureClearanceCheck,
    TargetDensityCheck,
)
from mmusv.generate.spec_models import GenerationSpec

__all__ = [
    "Constraint",
    "Finding",
    "MooredHullsIntersect",
    "build_constraints",
    "first_failure",
    "separation_words",
]

_PAIR_BLOCK = 262_144
"""Pair samples (times x pairs) the separation check holds at once (a few tens of MB of temporaries)."""


@dataclass(frozen=True)
class Finding:
    """One failure of a check: ``message`` (the check's one-line reason), the ``vessels`` at fault (ids), a world
    ``point`` ``(x, y)`` metres where it happens (None when no single place says it) and, for the clearance checks,
    ``route``: per vessel id a ``(G,)`` bool mask over the route samples ``Samples.geo[:, v]`` that fail."""

    message: str
    vessels: tuple[str, ...]
    point: tuple[float, float] | None = None
    route: dict[str, np.ndarray] = field(default_factory=dict)


class Constraint(Protocol):
    """A named check: ``check(samples)`` returns None when satisfied, else a one-line reason."""

    name: str

    def check(self, s: Samples) -> str | None: ...


class _FindingsCheck:
    """A check that lists every failure (``findings``, for the editor's map); its ``check`` reason is the message
    of the first of them, so the generator and the editor say the same thing."""

    name: str

    def check(self, s: Samples) -> str | None:
        found = self.findings(s)
        return found[0].message if found else None

    def findings(self, s: Samples) -> list[Finding]:
        raise NotImplementedError


def _below(share: np.ndarray, need: float) -> list[int]:
    """Indices ``k`` of the ``(N,)`` float ``share`` (fractions of frames) with ``share[k] < need``, the lowest
    share first (a stable sort: on a tie, the lower index first)."""
    return [int(k) for k in np.argsort(share, kind="stable") if share[k] < need]


def _where(xy: np.ndarray) -> str:
    return f"({xy[0]:.0f}, {xy[1]:.0f})"


def _edge_nearer(ctx: MapContext, at: np.ndarray) -> bool:
    """Whether the map's edge is nearer to point ``at`` (metres) than any cell of the map that is not navigable
    water: what ``d_shore`` measured there is the edge (open sea beyond, no shore), to be called so."""
    if "d_inland" not in ctx.cache:
        water = ctx.priors.water_mask
        # Distances to the map's own land, shallows and structures (beyond the map counts as water here).
        ctx.cache["d_inland"] = (
            np.full(water.shape, np.inf) if water.all() else distance_transform_edt(water) * ctx.resolution
        )
    x0, y0 = ctx.origin
    x1, y1 = x0 + ctx.priors.shape[1] * ctx.resolution, y0 + ctx.priors.shape[0] * ctx.resolution
    edge = min(at[0] - x0, x1 - at[0], at[1] - y0, y1 - at[1])
    return bool(edge < float(ctx.lookup(ctx.cache["d_inland"], at)))


class _Clearance(_FindingsCheck):
    """Shared body of in_water / shore_clearance / structure_clearance: ``raster - cell slack - δ - hull >= need``
    at every sample of the vessel's centre (``hull=False``) or of its capsule axis (``hull=True``)."""

    name = "clearance"
    axis_spacing = 4.0

    def __init__(self, raster: str, need: float, hull: bool, what: str) -> None:
        self.raster, self.need, self.hull, self.what = raster, need, hull, what

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per failing vessel, at its first failing sample (route samples before motion samples);
        ordered by that sample, so the first is the reason :meth:`check` gives. ``route`` masks the failing route
        samples of each failing vessel."""
        raster = getattr(s.ctx, self.raster)
        runs = ((s.geo, s.geo_yaw, s.geo_slack, s.geo_turn), (s.motion, s.motion_yaw, s.motion_slack, s.motion_turn))
        first: dict[int, tuple[int, int, np.ndarray]] = {}
        route_bad: np.ndarray | None = None
        for r, (pts, yaw, slack, turn) in enumerate(runs):
            if self.hull:
                axis, axis_slack = axis_points(pts, yaw=yaw, half=s.half, spacing=self.axis_spacing)
                d = s.ctx.lookup(raster, axis).min(axis=2)
                margin = d - s.ctx.cell_slack - (slack + turn + s.radius + axis_slack)[None, :]
            else:
                margin = s.ctx.lookup(raster, pts) - s.ctx.cell_slack - slack[None, :]
            bad = margin < self.need if self.hull else margin <= 0.0
            if r == 0:
                route_bad = bad
            for vi in np.flatnonzero(bad.any(axis=0)):
                if int(vi) not in first:
                    k = int(np.argmax(bad[:, vi]))
                    first[int(vi)] = (r, k, pts[k, vi])
        out = []
        x0, y0 = s.ctx.origin  # the map's rectangle, rows along y
        x1, y1 = x0 + s.ctx.priors.shape[1] * s.ctx.resolution, y0 + s.ctx.priors.shape[0] * s.ctx.resolution
        for v, (_, _, at) in sorted(first.items(), key=lambda kv: (kv[1][0], kv[1][1], kv[0])):
            if self.hull and self.raster == "d_shore" and _edge_nearer(s.ctx, at):  # no shore there: the edge
                what = (
                    f"{s.ids[v]} comes within {self.need:g} m of the map's edge (hull) near {_where(at)} (the map "
                    f"spans x {x0:.0f}..{x1:.0f} m, y {y0:.0f}..{y1:.0f} m)"
                )
            elif self.hull:
                what = f"{s.ids[v]} comes within {self.need:g} m of {self.what} near {_where(at)}"
            elif not (x0 <= at[0] < x1 and y0 <= at[1] < y1):  # off the map, not on land: said so
                what = (
                    f"{s.ids[v]} leaves the map near {_where(at)} (the map spans x {x0:.0f}..{x1:.0f} m, "
                    f"y {y0:.0f}..{y1:.0f} m)"
                )
            else:
                what = f"{s.ids[v]} leaves {self.what} near {_where(at)}"
            mask = {s.ids[v]: route_bad[:, v].copy()} if route_bad is not None and route_bad[:, v].any() else {}
            out.append(Finding(what, (s.ids[v],), (float(at[0]), float(at[1])), mask))
        return out


class InWater(_Clearance):
    name = "in_water"

    def __init__(self) -> None:
        super().__init__("d_shore", 0.0, False, "navigable water (centre)")


class ShoreClearance(_Clearance):
    name = "shore_clearance"

    def __init__(self, cfg: ShoreClearanceCheck) -> None:
        super().__init__("d_shore", cfg.min_m, True, "the shore (hull)")


class StructureClearance(_Clearance):
    name = "structure_clearance"

    def __init__(self, cfg: StructureClearanceCheck) -> None:
        super().__init__("d_struct", cfg.min_m, True, "a port structure, buoy or moored ship (hull)")


def closest_hulls(s: Samples) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every pair ``(iu[j], ju[j])`` of vessels (``iu < ju``), the least distance ``hull[j]`` (metres; below 0 the
    capsules overlap by that much) between their hull capsules over the motion samples and the sample ``at[j]``
    where it is (the first, on a tie), worked out over blocks of times x pairs in bounded memory, once per
    ``s`` (kept in ``s.derived``: a few seconds at the sampling budget, and two checks read it)."""
    if "closest_hulls" not in s.derived:
        s.derived["closest_hulls"] = _closest_hulls(s)
    done: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] = s.derived["closest_hulls"]
    return done


def _closest_hulls(s: Samples) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    n = len(s.ids)
    iu, ju = np.triu_indices(n, 1)
    d = np.stack([np.cos(s.motion_yaw), np.sin(s.motion_yaw)], axis=-1) * s.half[None, :, None]
    p, q = s.motion - d, s.motion + d  # capsule axes (T, V, 2)
    reach = s.radius[iu] + s.radius[ju]
    worst = np.full(len(iu), np.inf)
    at = np.zeros(len(iu), dtype=np.int64)
    for c0 in range(0, len(iu), _PAIR_BLOCK):
        c = slice(c0, min(c0 + _PAIR_BLOCK, len(iu)))
        a_, b_, cols = iu[c], ju[c], np.arange(c.stop - c0)
        t_step = max(1, _PAIR_BLOCK // len(cols))
        for t0 in range(0, len(s.times), t_step):
            t = slice(t0, t0 + t_step)
            hull = segment_distance(p[t, a_], q[t, a_], p2=p[t, b_], q2=q[t, b_]) - reach[None, c]
            k = np.argmin(hull, axis=0)
            better = hull[k, cols] < worst[c]  # strictly: an earlier block keeps a tie, as argmin would
            worst[c] = np.where(better, hull[k, cols], worst[c])
            at[c] = np.where(better, t0 + k, at[c])
    return iu, ju, worst, at


class Separation(_FindingsCheck):
    name = "separation"

    def __init__(self, cfg: SeparationCheck) -> None:
        self.min_m = cfg.min_m

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per pair of vessels that come too close, at their closest moment; the tightest first. The
        hulls' distance at the samples must exceed ``min_m`` by both vessels' slack (how far each can move, and
        its capsule turn, between two samples), so that the separation holds at every instant; a message whose
        distance is above ``min_m`` says that slack."""
        if len(s.ids) < 2:
            return []
        iu, ju, hull, _ = closest_hulls(s)
        slack = s.motion_slack + s.motion_turn
        pair_slack = slack[iu] + slack[ju]
        worst = hull - pair_slack - self.min_m  # the slack is each vessel's own: the same closest moment

        def message(j: int, a: str, b: str, t: float, mid: np.ndarray) -> str:
            between = ""
            if hull[j] >= self.min_m:  # the samples pass: only the motion between them can come closer
                between = (
                    f", and between the samples checked they can come up to {float(pair_slack[j]):.1f} m closer "
                    "(their motion and turns from one sample to the next)"
                )
            return f"{a} and {b} {separation_words(float(hull[j]))} at t={t:.1f} s{between}; need {self.min_m:g} m"

        return _pair_findings(s, worst, message)


class HullsIntersect(_FindingsCheck):
    """Two vessels whose hulls run into each other at some sample: the capsules inscribed in their hull rectangles
    (the covering capsule's axis, radius ``B/2`` instead of ``B/√2``: :mod:`mmusv.generate.hulls`) overlap, so the
    rectangles surely do. Covering capsules that only overlap (two hulls alongside) are a close pass,
    :class:`Separation`'s. Every label of both is then wrong (a LiDAR inside the other hull sees only its inside),
    so :func:`mmusv.scenario_checks.check_routes` makes it an error."""

    name = "hulls_intersect"

    def findings(self, s: Samples) -> list[Finding]:
        if len(s.ids) < 2:
            return []
        iu, ju, hull, _ = closest_hulls(s)
        # The inscribed capsules' distance: the axes' distance less their radii, B/2 = r/√2 each.
        inner = hull + (s.radius[iu] + s.radius[ju]) * (1.0 - math.sqrt(0.5))
        return _pair_findings(
            s,
            inner,
            lambda j, a, b, t, mid: (
                f"the hulls of {a} and {b} intersect at t={t:.1f} s near {_where(mid)} "
                f"(by at least {-float(inner[j]):.1f} m)"
            ),
        )


class MooredHullsIntersect(_FindingsCheck):
    """A vessel whose hull runs into a ship moored in the map's port at some sample (motion samples): the capsules
    inscribed in the two hull rectangles overlap, as :class:`HullsIntersect` judges two of the scenario's vessels.
    The moored ships are vessels too (world state, boxes, LiDAR labels), so it is an error alike; the finding names
    the scenario's vessel (its route is what to move) and says which moored ship, where."""

    name = "hulls_intersect"

    def findings(self, s: Samples) -> list[Finding]:
        moored = s.ctx.world.moored
        if not moored or not s.ids:
            return []
        caps = np.array([capsule(asset) for asset, _ in moored])  # (M, 2): axis half-length, covering radius
        pose = np.array([berth for _, berth in moored])  # (M, 3): x, y, yaw
        d_m = np.column_stack([np.cos(pose[:, 2]), np.sin(pose[:, 2])]) * caps[:, :1]
        p2, q2 = pose[None, None, :, :2] - d_m, pose[None, None, :, :2] + d_m
        n_t, n_v = s.motion.shape[:2]
        worst = np.full((n_v, len(moored)), np.inf)  # the inscribed capsules' least distance, per vessel and ship
        when = np.zeros((n_v, len(moored)), dtype=np.int64)
        step = max(_PAIR_BLOCK // max(n_v * len(moored), 1), 1)  # time samples a block (bounded memory)
        for t0 in range(0, n_t, step):
            xy, yaw = s.motion[t0 : t0 + step], s.motion_yaw[t0 : t0 + step]
            d_v = np.stack([np.cos(yaw), np.sin(yaw)], axis=-1) * s.half[None, :, None]  # (T, V, 2)
            axis = segment_distance((xy - d_v)[:, :, None, :], (xy + d_v)[:, :, None, :], p2=p2, q2=q2)
            inner = axis - (s.radius[None, :, None] + caps[None, None, :, 1]) * math.sqrt(0.5)  # (T, V, M)
            k = inner.argmin(axis=0)
            low = np.take_along_axis(inner, k[None], axis=0)[0]
            better = low < worst
            worst[better], when[better] = low[better], (k + t0)[better]
        out = []
        for v, m in sorted(zip(*np.nonzero(worst < 0.0), strict=True), key=lambda vm: (float(worst[vm]), vm)):
            k = int(when[v, m])
            at = s.motion[k, v]
            asset, (x, y, _) = moored[m]
            out.append(
                Finding(
                    f"the hulls of {s.ids[v]} and moored_{m:02d} (a {asset} moored at {_where(np.array([x, y]))}, "
                    f"a ship of the map) intersect at t={float(s.times[k]):.1f} s near {_where(at)} (by at least "
                    f"{-float(worst[v, m]):.1f} m)",
                    (s.ids[v],),
                    (float(at[0]), float(at[1])),
                )
            )
        return out


def _pair_findings(
    s: Samples, score: np.ndarray, message: Callable[[int, str, str, float, np.ndarray], str]
) -> list[Finding]:
    """One :class:`Finding` per pair ``j`` of :func:`closest_hulls` whose ``score[j]`` is below 0, the lowest score
    first (the lower pair index on a tie), at the pair's closest sample: ``message(j, id_a, id_b, time, midpoint)``
    says it, and the point is the two vessels' midpoint then."""
    iu, ju, _, at = closest_hulls(s)
    out = []
    for j in sorted(np.flatnonzero(score < 0.0), key=lambda j: (float(score[j]), int(j))):
        k, a, b = int(at[j]), int(iu[j]), int(ju[j])
        mid = (s.motion[k, a] + s.motion[k, b]) / 2.0
        out.append(
            Finding(
                message(int(j), s.ids[a], s.ids[b], float(s.times[k]), mid),
                (s.ids[a], s.ids[b]),
                (float(mid[0]), float(mid[1])),
            )
        )
    return out


def separation_words(hull_m: float) -> str:
    """How two hulls ``hull_m`` metres apart (their covering capsules', :mod:`mmusv.generate.hulls`) are said:
    "come 3.2 m apart (hulls)", or, below 0, "pass with their hull capsules overlapping by 2.2 m" (a negative
    distance read as "come -2.2 m apart"; covering capsules overlap alongside, where the hulls need not:
    :class:`HullsIntersect` says when they do)."""
    if hull_m < 0.0:
        return f"pass with their hull capsules overlapping by {-hull_m:.1f} m"
    return f"come {hull_m:.1f} m apart (hulls)"


class RouteSeparation:
    name = "route_separation"

    def __init__(self, cfg: RouteSeparationCheck) -> None:
        self.min_m, self.pairs = cfg.min_m, set(cfg.pairs)

    def check(self, s: Samples) -> str | None:
        kind = ["usv" if u else "target" for u in s.is_usv]
        n = len(s.ids)
        for i in range(n):
            for j in range(i + 1, n):
                pair = "-".join(sorted((kind[i], kind[j]), key=("usv", "target").index))
                if pair not in self.pairs:
                    continue
                # The closest pair of route samples, through a k-d tree of one route's: O(G log G), not G x G.
                d, _ = cKDTree(s.geo[:, j, :]).query(s.geo[:, i, :])
                gap = float(d.min()) - s.geo_slack[i] - s.geo_slack[j]
                if gap < self.min_m:
                    return (
                        f"routes of {s.ids[i]} and {s.ids[j]} come within {max(gap, 0.0):.1f} m; need {self.min_m:g} m"
                    )
        return None


class TargetRange:
    name = "target_range"

    def check(self, s: Samples) -> str | None:
        lo, hi = s.meta.range_m
        e = s.index(s.meta.ego)
        for tid in s.meta.ranged:
            d = float(np.linalg.norm(s.frames[:, e] - s.frames[:, s.index(tid)], axis=-1).min())
            if not lo <= d <= hi:
                return f"closest approach of {tid} to the ego is {d:.0f} m, outside [{lo:g}, {hi:g}] m"
        return None


class SensingRange(_FindingsCheck):
    name = "sensing_range"

    def __init__(self, cfg: SensingRangeCheck) -> None:
        self.range_m, self.share, self.targets = cfg.range_m, cfg.min_share, cfg.targets

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per target too rarely within range of a USV, in target order (every target when there is
        no USV)."""
        tids = list(s.meta.targets) + (list(s.meta.distractors) if self.targets == "all" else [])
        u = np.asarray(s.usvs, dtype=np.int64)
        out = []
        for tid in tids:
            t = s.index(tid)
            share = 0.0
            if u.size:
                d = np.linalg.norm(s.frames[:, u, :] - s.frames[:, t, None, :], axis=-1).min(axis=1)
                share = float(np.mean(d <= self.range_m))
            if share < self.share:
                msg = f"{tid} is within {self.range_m:g} m of a USV in {share:.0%} of frames; need {self.share:.0%}"
                out.append(Finding(msg, (tid,)))
        return out


class TargetDensity:
    name = "target_density"

    def __init__(self, cfg: TargetDensityCheck) -> None:
        self.range_m, self.min_targets, self.share = cfg.range_m, cfg.min_targets, cfg.min_share

    def check(self, s: Samples) -> str | None:
        u = np.asarray(s.usvs)
        t = np.array([i for i in range(len(s.ids)) if not s.is_usv[i]], dtype=np.int64)
        if t.size == 0:
            return f"no targets: each USV needs {self.min_targets} within {self.range_m:g} m"
        d = np.linalg.norm(s.frames[:, u, None, :] - s.frames[:, None, t, :], axis=-1)  # (frames, usvs, targets)
        share = np.mean((d <= self.range_m).sum(axis=2) >= self.min_targets, axis=0)  # per USV
        worst = int(np.argmin(share))
        if share[worst] < self.share:
            return (
                f"{s.ids[int(u[worst])]} has {self.min_targets}+ targets within {self.range_m:g} m in "
                f"{share[worst]:.0%} of frames; need {self.share:.0%}"
            )
        return None


class Cooperation(_FindingsCheck):
    name = "cooperation"

    def __init__(self, cfg: CooperationCheck) -> None:
        self.lo, self.hi, self.share = cfg.min_m, cfg.max_m, cfg.min_share

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per USV whose nearest USV is too rarely in the distance band; the lowest share first."""
        u = np.asarray(s.usvs)
        if u.size < 2:
            return []
        p = s.frames[:, u, :]
        d = np.linalg.norm(p[:, :, None, :] - p[:, None, :, :], axis=-1)
        d[:, np.arange(u.size), np.arange(u.size)] = np.inf
        nearest = d.min(axis=2)
        share = np.mean((nearest >= self.lo) & (nearest <= self.hi), axis=0)
        return [
            Finding(
                f"{s.ids[u[k]]} has its nearest USV within [{self.lo:g}, {self.hi:g}] m in {share[k]:.0%} of frames;"
                f" need {self.share:.0%}",
                (s.ids[u[k]],),
            )
            for k in _below(share, self.share)
        ]


class LineOfSight(_FindingsCheck):
    name = "line_of_sight"

    def __init__(self, cfg: LineOfSightCheck) -> None:
        self.share = cfg.min_share

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per role target too rarely seen by a USV; the lowest share first (every target when there
        is no USV)."""
        if not s.meta.targets:
            return []
        seen = (~s.blocked() & s.in_range()).any(axis=1) if s.usvs else np.zeros((1, len(s.meta.targets)), bool)
        share = seen.mean(axis=0)  # (F, R) -> (R,)
        return [
            Finding(
                f"{s.meta.targets[k]} is seen by a USV in {share[k]:.0%} of frames; need {self.share:.0%}",
                (s.meta.targets[k],),
            )
            for k in _below(share, self.share)
        ]


class Occlusion:
    name = "occlusion"

    def __init__(self, cfg: OcclusionCheck) -> None:
        self.other = cfg.min_visible_other_share

    def check(self, s: Samples) -> str | None:
        need = s.meta.occlusion_share
        if need is None:
            return None
        usvs = s.usvs
        e = usvs.index(s.index(s.meta.ego))
        r = list(s.meta.targets).index(s.meta.primary)
        blocked = s.blocked()[:, :, r]
        occluded = blocked[:, e]
        share = float(occluded.mean())
        if share < need:
            return f"{s.meta.primary} is hidden from the ego in {share:.0%} of frames; need {need:.0%}"
        others = [i for i in range(len(usvs)) if i != e]
        seen = (~blocked[:, others] & s.in_range()[:, others, r]).any(axis=1) if others else np.zeros_like(occluded)
        other = float(seen[occluded].mean())
        if other < self.other:
            return (
                f"while hidden from the ego, {s.meta.primary} is seen by another USV in {other:.0%} of those frames;"
                f" need {self.other:.0%}"
            )
        return None


def build_constraints(spec: GenerationSpec) -> list[Constraint]:
    """The enabled constraints of a spec, in evaluation order (cheap first)."""
    c = spec.constraints
    out: list[Constraint] = []
    if c.in_water.enabled:
        out.append(InWater())
    if c.shore_clearance.enabled:
        out.append(ShoreClearance(c.shore_clearance))
    if c.structure_clearance.enabled:
        out.append(StructureClearance(c.structure_clearance))
    if c.separation.enabled:
        out.append(Separation(c.separation))
    if c.route_separation.enabled:
        out.append(RouteSeparation(c.route_separation))
    if c.target_range.enabled:
        out.append(TargetRange())
    if c.sensing_range.enabled:
        out.append(SensingRange(c.sensing_range))
    if c.target_density.enabled:
        out.append(TargetDensity(c.target_density))
    if c.cooperation.enabled:
        out.append(Cooperation(c.cooperation))
    if c.line_of_sight.enabled:
        out.append(LineOfSight(c.line_of_sight))
    if c.occlusion.enabled:
        out.append(Occlusion(c.occlusion))
    return out


def first_failure(constraints: list[Constraint], s: Samples) -> tuple[str, str] | None:
    """``(name, reason)`` of the first constraint that fails, or None when all pass."""
    for c in constraints:
        reason = c.check(s)
        if reason is not None:
            return c.name, reason
    return None
