"""Named, configurable constraints checked on a candidate scenario, vectorised (no Python call per sample).

One :class:`Samples` per candidate holds everything the checks read, from two fleet evaluations in Rust:

- *route geometry*: every route sampled along its whole length at a spacing of at most ``check_step_m`` (a
  second fleet whose vessels each cover their route in one second, evaluated at evenly spaced times);
- *motion*: all vessels at times ``0..t_last`` every ``dt = min(1/f, check_step_m / max speed)`` seconds;
- *frames*: all vessels at the acquisition times ``k / f``.

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
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from scipy.spatial import cKDTree

from mmusv._native import core
from mmusv.config import Scenario
from mmusv.errors import ConfigError
from mmusv.generate.hulls import axis_points, capsule, segment_distance
from mmusv.generate.mapctx import MapContext
from mmusv.generate.sampler import CandidateMeta
from mmusv.generate.spec import (
    CooperationCheck,
    GenerationSpec,
    LineOfSightCheck,
    OcclusionCheck,
    RouteSeparationCheck,
    SensingRangeCheck,
    SeparationCheck,
    ShoreClearanceCheck,
    StructureClearanceCheck,
)
from mmusv.generate.spec_constraints import TargetDensityCheck
from mmusv.motion import build_fleet
from mmusv.world.vessels import get_asset

__all__ = [
    "MAX_CHECK_PAIR_SAMPLES",
    "MAX_CHECK_SAMPLES",
    "Constraint",
    "Finding",
    "Samples",
    "budget_problem",
    "build_constraints",
    "first_failure",
    "sample_counts",
    "take_samples",
    "time_samples",
]

MAX_CHECK_SAMPLES = 5_000_000
"""The most samples (per-vessel samples, in time or along the routes, whichever is more, times the vessels) the
checks of one scenario take: about three minutes and a few GiB. :func:`take_samples` refuses more (a
:class:`~mmusv.errors.ConfigError`) instead of allocating them; the scenario editor checks at most as many."""

MAX_CHECK_PAIR_SAMPLES = 5_000_000
"""The most motion samples x pairs of vessels the separation check compares (every pair at every time): a few
seconds. Above, :func:`budget_problem` refuses, as a fleet of thousands of vessels would otherwise take minutes.
The comparison itself runs in blocks of :data:`_PAIR_BLOCK` pair samples, so its memory stays small at any size."""

_PAIR_BLOCK = 262_144
"""Pair samples (times x pairs) the separation check holds at once (a few tens of MB of temporaries)."""

_SATURATE = 2**62
"""A sample count past every budget, for counts that overflow (a non-finite time or route length)."""


@dataclass(frozen=True)
class Finding:
    """One failure of a check: ``message`` (the check's one-line reason), the ``vessels`` at fault (ids), a world
    ``point`` ``(x, y)`` metres where it happens (None when no single place says it) and, for the clearance checks,
    ``route``: per vessel id a ``(G,)`` bool mask over the route samples ``Samples.geo[:, v]`` that fail."""

    message: str
    vessels: tuple[str, ...]
    point: tuple[float, float] | None = None
    route: dict[str, np.ndarray] = field(default_factory=dict)


def _first(findings: list[Finding]) -> str | None:
    return findings[0].message if findings else None


@dataclass
class Samples:
    """Sampled positions of one candidate (see module docstring): positions ``(samples, vessels, 2)``, yaws
    ``(samples, vessels)``; ``half``/``radius`` the hull capsules; ``*_slack`` the per-vessel ``δ`` of the
    centre between samples and ``*_turn`` the extra motion of the capsule axis ends from turning (metres)."""

    ctx: MapContext
    meta: CandidateMeta
    ids: list[str]
    is_usv: np.ndarray
    half: np.ndarray
    radius: np.ndarray
    target_z: np.ndarray
    geo: np.ndarray
    geo_yaw: np.ndarray
    geo_slack: np.ndarray
    geo_turn: np.ndarray
    times: np.ndarray
    motion: np.ndarray
    motion_yaw: np.ndarray
    motion_slack: np.ndarray
    motion_turn: np.ndarray
    frames: np.ndarray
    sensor_height: float
    sensor_range: float
    _visible: dict[str, np.ndarray] = field(default_factory=dict)

    def index(self, vid: str) -> int:
        return self.ids.index(vid)

    @property
    def usvs(self) -> list[int]:
        return [int(i) for i in np.flatnonzero(self.is_usv)]

    def blocked(self) -> np.ndarray:
        """``(F, U, R)`` bool: the static map blocks the ray from USV ``u`` to role target ``r`` at frame ``f``
        (USVs in file order, role targets in ``meta.targets`` order); one batched ray cast, cached."""
        if "blocked" not in self._visible:
            u = np.asarray(self.usvs)
            r = np.asarray([self.index(t) for t in self.meta.targets])
            n_f = self.frames.shape[0]
            a = np.zeros((n_f, u.size, r.size, 3))
            b = np.zeros_like(a)
            a[..., :2] = self.frames[:, u, None, :]
            a[..., 2] = self.sensor_height
            b[..., :2] = self.frames[:, None, r, :]
            b[..., 2] = self.target_z[r][None, None, :]
            self._visible["blocked"] = self.ctx.blocked(a.reshape(-1, 3), b.reshape(-1, 3)).reshape(n_f, u.size, r.size)
        return self._visible["blocked"]

    def in_range(self) -> np.ndarray:
        """``(F, U, R)`` bool: role target ``r`` within ``sensor_range`` of USV ``u`` at frame ``f``."""
        u = np.asarray(self.usvs)
        r = np.asarray([self.index(t) for t in self.meta.targets])
        d = np.linalg.norm(self.frames[:, u, None, :] - self.frames[:, None, r, :], axis=-1)
        out: np.ndarray = d <= self.sensor_range
        return out


def _half_turn(yaw: np.ndarray) -> np.ndarray:
    """``(V,)`` half the largest yaw step (radians) between consecutive samples of ``yaw`` ``(N, V)``."""
    dy = np.abs((np.diff(yaw, axis=0) + np.pi) % (2.0 * np.pi) - np.pi)
    out: np.ndarray = dy.max(axis=0, initial=0.0) / 2.0
    return out


def _ceil_count(x: float) -> int:
    """``ceil(x) + 1`` samples, at least 2, saturated at :data:`_SATURATE` (``x`` infinite, NaN or huge)."""
    if not x < _SATURATE:  # also NaN
        return _SATURATE
    return max(math.ceil(x) + 1, 2)


def time_samples(frames: int, frequency_hz: float, step: float, max_speed_mps: float) -> int:
    """Motion samples per vessel over ``frames`` frames at ``frequency_hz``: at least one a frame, and one each
    ``step`` metres at ``max_speed_mps`` (saturated like every count here)."""
    t_last = (frames - 1) / frequency_hz
    dt = min(1.0 / frequency_hz, step / max(max_speed_mps, 1e-9))
    return _ceil_count(t_last / dt)


def _counts(scenario: Scenario, lengths: np.ndarray, step: float) -> tuple[int, int]:
    """``(motion samples, route samples)`` per vessel for route ``lengths`` (metres) at spacing ``step``; counts too
    large for any budget (or from non-finite inputs) saturate instead of overflowing."""
    acq = scenario.acquisition
    fastest = max(v.speed_mps for v in scenario.vessels)
    return time_samples(acq.frames, acq.frequency_hz, step, fastest), _ceil_count(float(lengths.max()) / step)


def _fmt(n: int) -> str:
    return f"{n:,}" if n < _SATURATE else f"over {_SATURATE:.1e}"


def budget_problem(scenario: Scenario, n_motion: int, n_route: int) -> str | None:
    """None when ``n_motion``/``n_route`` samples per vessel (:func:`sample_counts`) fit :data:`MAX_CHECK_SAMPLES`
    and the pairs of vessels at every motion sample fit :data:`MAX_CHECK_PAIR_SAMPLES`, else why not: the sample
    count, split into time and route samples, or the pair count (callers add what to do about it)."""
    n_v = len(scenario.vessels)
    total = max(n_motion, n_route) * n_v
    acq = scenario.acquisition
    if total > MAX_CHECK_SAMPLES:
        return (
            f"the route checks would take {_fmt(total)} samples ({_fmt(n_motion)} in time over {acq.frames:,} frames "
            f"at {acq.frequency_hz:g} Hz, {_fmt(n_route)} along the longest route, x {n_v} "
            f"vessel{'s' if n_v != 1 else ''}); they take at most {MAX_CHECK_SAMPLES:,}"
        )
    pairs = n_v * (n_v - 1) // 2
    if n_motion * pairs > MAX_CHECK_PAIR_SAMPLES:
        return (
            f"the route checks would compare {pairs:,} pairs of vessels ({n_v} vessels) at {_fmt(n_motion)} times "
            f"({_fmt(n_motion * pairs)} pair samples); they compare at most {MAX_CHECK_PAIR_SAMPLES:,}"
        )
    return None


def sample_counts(scenario: Scenario, spec: GenerationSpec) -> tuple[int, int]:
    """``(motion samples, route samples)`` per vessel that :func:`take_samples` would take (one cheap fleet build),
    so a caller can refuse a scenario whose checks would not fit in memory before sampling it."""
    return _counts(scenario, np.asarray(build_fleet(scenario).route_lengths(), dtype=np.float64), spec.check_step_m)


def take_samples(scenario: Scenario, meta: CandidateMeta, ctx: MapContext, spec: GenerationSpec) -> Samples:
    """Samples a candidate's routes, motion and frames (two fleet evaluations in Rust).

    Raises:
        ConfigError: the samples would exceed :data:`MAX_CHECK_SAMPLES` (:func:`budget_problem`); nothing is
            allocated.
    """
    step = spec.check_step_m
    vessels = scenario.vessels
    fleet = build_fleet(scenario)
    lengths = np.asarray(fleet.route_lengths(), dtype=np.float64)
    speeds = np.array([v.speed_mps for v in vessels], dtype=np.float64)
    acq = scenario.acquisition
    t_last = (acq.frames - 1) / acq.frequency_hz
    n_t, n_g = _counts(scenario, lengths, step)
    problem = budget_problem(scenario, n_t, n_g)
    if problem is not None:
        raise ConfigError(
            f"{problem}: lower acquisition.frames or acquisition.frequency_hz, shorten the routes or lower the speeds"
        )
    times = np.linspace(0.0, t_last, n_t)
    frame_times = np.arange(acq.frames, dtype=np.float64) / acq.frequency_hz
    poses = np.asarray(fleet.poses_at_times(np.concatenate([times, frame_times])))
    motion, frames = poses[:n_t, :, :2], poses[n_t:, :, :2]
    geo_fleet = core.Fleet(
        routes=[np.ascontiguousarray(v.route, dtype=np.float64) for v in vessels],
        end_behaviours=[v.end for v in vessels],
        speeds=lengths.copy(),
        start_offsets=np.zeros(len(vessels)),
        z_base=np.zeros(len(vessels)),
        dims=np.array(
            [[get_asset(v.asset).length, get_asset(v.asset).beam, get_asset(v.asset).height] for v in vessels]
        ),
        amplitudes=np.zeros((len(vessels), 3)),
        seed=0,
        wave="W0",
    )
    geo_poses = np.asarray(geo_fleet.poses_at_times(np.linspace(0.0, 1.0, n_g)))
    assets = [get_asset(v.asset) for v in vessels]
    caps = np.array([capsule(v.asset) for v in vessels])
    half = caps[:, 0]
    motion_yaw = poses[:n_t, :, 5]
    return Samples(
        ctx=ctx,
        meta=meta,
        ids=[v.id for v in vessels],
        is_usv=np.array([v.role == "usv" for v in vessels]),
        half=half,
        radius=caps[:, 1],
        target_z=np.array([max(a.height - a.draft, 0.2) / 2.0 for a in assets]),
        geo=geo_poses[:, :, :2],
        geo_yaw=geo_poses[:, :, 5],
        geo_slack=lengths / (n_g - 1) / 2.0,
        geo_turn=half * _half_turn(geo_poses[:, :, 5]),
        times=times,
        motion=motion,
        motion_yaw=motion_yaw,
        motion_slack=speeds * (t_last / (n_t - 1)) / 2.0,
        motion_turn=half * _half_turn(motion_yaw),
        frames=frames,
        sensor_height=spec.sensor_height_m,
        sensor_range=spec.constraints.sensing_range.range_m,
    )


class Constraint(Protocol):
    """A named check: ``check(samples)`` returns None when satisfied, else a one-line reason."""

    name: str

    def check(self, s: Samples) -> str | None: ...


def _where(xy: np.ndarray) -> str:
    return f"({xy[0]:.0f}, {xy[1]:.0f})"


class _Clearance:
    """Shared body of in_water / shore_clearance / structure_clearance: ``raster - cell slack - δ - hull >= need``
    at every sample of the vessel's centre (``hull=False``) or of its capsule axis (``hull=True``)."""

    name = "clearance"
    axis_spacing = 4.0

    def __init__(self, raster: str, need: float, hull: bool, what: str) -> None:
        self.raster, self.need, self.hull, self.what = raster, need, hull, what

    def check(self, s: Samples) -> str | None:
        return _first(self.findings(s))

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
                axis, axis_slack = axis_points(pts, yaw, s.half, self.axis_spacing)
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
        for v, (_, _, at) in sorted(first.items(), key=lambda kv: (kv[1][0], kv[1][1], kv[0])):
            what = (
                f"{s.ids[v]} leaves {self.what} near {_where(at)}"
                if not self.hull
                else f"{s.ids[v]} comes within {self.need:g} m of {self.what} near {_where(at)}"
            )
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


class Separation:
    name = "separation"

    def __init__(self, cfg: SeparationCheck) -> None:
        self.min_m = cfg.min_m

    def check(self, s: Samples) -> str | None:
        return _first(self.findings(s))

    def findings(self, s: Samples) -> list[Finding]:
        """One finding per pair of vessels that come too close, at their closest moment; the tightest first."""
        n = len(s.ids)
        if n < 2:
            return []
        iu, ju = np.triu_indices(n, 1)
        d = np.stack([np.cos(s.motion_yaw), np.sin(s.motion_yaw)], axis=-1) * s.half[None, :, None]
        p, q = s.motion - d, s.motion + d  # capsule axes (T, V, 2)
        slack = s.motion_slack + s.motion_turn
        reach = s.radius[iu] + s.radius[ju]
        pair_slack = slack[iu] + slack[ju]
        # Each pair's tightest moment (the first, on a tie), over blocks of times x pairs: the same values as one
        # (T, pairs) array, in bounded memory.
        worst = np.full(len(iu), np.inf)
        at = np.zeros(len(iu), dtype=np.int64)
        hull_at = np.zeros(len(iu))
        for c0 in range(0, len(iu), _PAIR_BLOCK):
            c = slice(c0, min(c0 + _PAIR_BLOCK, len(iu)))
            a_, b_, cols = iu[c], ju[c], np.arange(c.stop - c0)
            t_step = max(1, _PAIR_BLOCK // len(cols))
            for t0 in range(0, len(s.times), t_step):
                t = slice(t0, t0 + t_step)
                hull = segment_distance(p[t, a_], q[t, a_], p[t, b_], q[t, b_]) - reach[None, c]
                gap = hull - pair_slack[None, c] - self.min_m
                k = np.argmin(gap, axis=0)
                better = gap[k, cols] < worst[c]  # strictly: an earlier block keeps a tie, as argmin would
                worst[c] = np.where(better, gap[k, cols], worst[c])
                at[c] = np.where(better, t0 + k, at[c])
                hull_at[c] = np.where(better, hull[k, cols], hull_at[c])
        out = []
        for j in sorted(np.flatnonzero(worst < 0.0), key=lambda j: (float(worst[j]), int(j))):
            k = int(at[j])
            a, b = int(iu[j]), int(ju[j])
            mid = (s.motion[k, a] + s.motion[k, b]) / 2.0
            out.append(
                Finding(
                    f"{s.ids[a]} and {s.ids[b]} come {hull_at[j]:.1f} m apart (hulls) at t={s.times[k]:.1f} s; "
                    f"need {self.min_m:g} m",
                    (s.ids[a], s.ids[b]),
                    (float(mid[0]), float(mid[1])),
                )
            )
        return out


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


class SensingRange:
    name = "sensing_range"

    def __init__(self, cfg: SensingRangeCheck) -> None:
        self.range_m, self.share, self.targets = cfg.range_m, cfg.min_share, cfg.targets

    def check(self, s: Samples) -> str | None:
        return _first(self.findings(s))

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


class Cooperation:
    name = "cooperation"

    def __init__(self, cfg: CooperationCheck) -> None:
        self.lo, self.hi, self.share = cfg.min_m, cfg.max_m, cfg.min_share

    def check(self, s: Samples) -> str | None:
        return _first(self.findings(s))

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
            for k in np.argsort(share, kind="stable")
            if share[k] < self.share
        ]


class LineOfSight:
    name = "line_of_sight"

    def __init__(self, cfg: LineOfSightCheck) -> None:
        self.share = cfg.min_share

    def check(self, s: Samples) -> str | None:
        return _first(self.findings(s))

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
            for k in np.argsort(share, kind="stable")
            if share[k] < self.share
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
