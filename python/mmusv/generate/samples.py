"""What the generator's checks read of one candidate scenario: its routes, motion and frames sampled by two fleet
evaluations in Rust (:class:`Samples`, :func:`take_samples`), and the bounds on how many samples the checks may
take (:func:`budget_problem`), so that a scenario too large to check is refused before anything is allocated.

- *route geometry*: every route sampled along its whole length at a spacing of at most ``check_step_m`` (a
  second fleet whose vessels each cover their route in one second, evaluated at evenly spaced times);
- *motion*: all vessels at times ``0..t_last`` every ``dt = min(1/f, check_step_m / max speed)`` seconds;
- *frames*: all vessels at the acquisition times ``k / f``.

Between two samples a vessel is within ``δ`` of one (``*_slack``: half the route spacing, or ``speed·dt/2`` in
time) and its hull capsule's axis ends move by at most ``*_turn`` more from turning; the checks
(:mod:`mmusv.generate.checks`) subtract both. World frame, metres, seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mmusv._native import core
from mmusv.config import Scenario
from mmusv.errors import ConfigError
from mmusv.generate.hulls import capsule
from mmusv.generate.mapctx import MapContext
from mmusv.generate.sampler import CandidateMeta
from mmusv.generate.spec_models import GenerationSpec
from mmusv.motion import build_fleet, fleet_poses
from mmusv.world.vessels import get_asset

__all__ = [
    "MAX_CHECK_PAIR_SAMPLES",
    "MAX_CHECK_SAMPLES",
    "Samples",
    "budget_problem",
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
The comparison itself runs in blocks (:mod:`mmusv.generate.checks`), so its memory stays small at any size."""

_SATURATE = 2**62
"""A sample count past every budget, for counts that overflow (a non-finite time or route length)."""


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
    frames_yaw: np.ndarray
    """``(frames, vessels)`` the vessels' headings (rad) at the acquisition frames, beside :attr:`frames`."""
    sensor_height: float
    sensor_range: float
    derived: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)
    """What checks work out from the samples and share, once per candidate (:func:`mmusv.generate.checks.closest_hulls`:
    the separation and the hulls' intersection both read it)."""
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


FEWER_TIMES = "lower acquisition.frames or raise acquisition.frequency_hz (a shorter acquisition)"
"""What takes fewer samples in time (:func:`time_samples`): fewer frames, or the same frames over a shorter time. A
lower rate never helps: over the same frames the acquisition lasts longer and the vessels sail further."""


def time_samples(frames: int, *, frequency_hz: float, step: float, max_speed_mps: float) -> int:
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
    return time_samples(acq.frames, frequency_hz=acq.frequency_hz, step=step, max_speed_mps=fastest), _ceil_count(
        float(lengths.max()) / step
    )


def _fmt(n: int) -> str:
    return f"{n:,}" if n < _SATURATE else f"over {_SATURATE:.1e}"


def budget_problem(scenario: Scenario, *, n_motion: int, n_route: int) -> str | None:
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
    problem = budget_problem(scenario, n_motion=n_t, n_route=n_g)
    if problem is not None:
        raise ConfigError(f"{problem}: {FEWER_TIMES}, shorten the routes or lower the speeds")
    times = np.linspace(0.0, t_last, n_t)
    frame_times = np.arange(acq.frames, dtype=np.float64) / acq.frequency_hz
    poses = fleet_poses(fleet, np.concatenate([times, frame_times]), vessels=len(vessels))  # Ctrl-C between batches
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
    geo_poses = fleet_poses(geo_fleet, np.linspace(0.0, 1.0, n_g), vessels=len(vessels))
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
        frames_yaw=poses[n_t:, :, 5],
        sensor_height=spec.sensor_height_m,
        sensor_range=spec.constraints.sensing_range.range_m,
    )
