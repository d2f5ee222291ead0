"""Building blocks of the family templates: roles, tracks, layouts, straight tracks and prior-guided proposals.

World frame, metres, seconds, radians (headings from +x, counter-clockwise).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mmusv.errors import MmusvError
from mmusv.generate.mapctx import MapContext
from mmusv.world.vessels import get_asset

__all__ = [
    "TOP_SPEED_MPS",
    "FamilyInput",
    "Layout",
    "Role",
    "SamplingError",
    "Track",
    "heading",
    "perp",
    "pick_best",
    "straight_track",
    "top_speed_mps",
    "track_clearance",
    "unit",
]


TOP_SPEED_MPS: dict[str, float] = {
    "kayak": 3.0,
    "sailing_yacht": 4.4,
    "barge": 4.0,
}
"""The most a vessel of these catalogue categories makes through the water (m/s): a target's speed is drawn from
its size class's range cut to ``[min(low, top / 2), min(high, top)]`` (other categories: the class's range). A sea
kayak is paddled at 1.5-2 m/s (3-4 kn) on a tour, 3 m/s is a strong sprint; a 12 m cruising sloop's displacement
hull speed is 1.34 kn·√(LWL in ft) (Froude number 0.4: 4.1 m/s for its 10.7 m waterline); a deck barge is towed
at 5-8 kn (2.5-4 m/s)."""


def top_speed_mps(asset: str) -> float:
    """The highest speed (m/s) a target of library asset ``asset`` is given (:data:`TOP_SPEED_MPS` of its category,
    else infinity)."""
    return TOP_SPEED_MPS.get(get_asset(asset).category, math.inf)


class SamplingError(MmusvError):
    """A template could not place its vessels (the message says why)."""


@dataclass(frozen=True)
class Role:
    """A vessel to place: ``id``, ``role`` (usv/target), library ``asset``, nominal ``speed`` (m/s), the
    ``radius`` of its hull's bounding circle (half the length-beam diagonal, metres) and ``beam_r``, the radius
    of its hull capsule (beam/√2, :mod:`mmusv.generate.hulls`): the clearance it needs sailing straight."""

    id: str
    role: str
    asset: str
    speed: float
    radius: float
    beam_r: float


@dataclass
class Track:
    """A placed vessel: waypoints ``route`` ``(K, 2)``, ``speed`` m/s and ``start_offset`` m along the route."""

    role: Role
    route: np.ndarray
    speed: float
    start_offset: float = 0.0


@dataclass
class Layout:
    """A family's output: the tracks (ego first), the ids of the targets whose closest approach to the ego must
    lie in the difficulty range, and the encounter centre (distractors are scattered around it)."""

    tracks: list[Track]
    ranged: list[str]
    centre: np.ndarray


@dataclass
class FamilyInput:
    """What a template gets: the map, its random generator and the drawn roles and bounds (metres, m/s, s).

    Encounter centres are drawn from the map priors' open water (``encounter_clearance`` metres from shore if
    the map has room). ``proposals`` is how
    many random layouts of one vessel a template may draw to keep the one whose waypoint polyline stays
    farthest from obstacles (map priors), stopping at the first with comfortable clearance.
    """

    ctx: MapContext
    rng: np.random.Generator
    duration: float
    ego: Role
    coops: list[Role]
    targets: list[Role]
    range_m: tuple[float, float]
    coop_m: tuple[float, float]
    usv_speed: tuple[float, float]
    separation_m: float
    clearance_m: float
    encounter_clearance: float = 100.0
    proposals: int = 6


def heading(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])


def perp(v: np.ndarray) -> np.ndarray:
    return np.array([-v[1], v[0]])


def unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = float(np.hypot(v[0], v[1]))
    return v / n if n > 1e-9 else fallback


def straight_track(
    role: Role, *, at: np.ndarray, vel: np.ndarray, t_at: float, duration: float, rng: np.random.Generator
) -> Track:
    """A track passing ``at`` at time ``t_at`` with velocity ``vel`` (m/s), covering ``[0, duration]``, with a
    middle waypoint bent sideways by up to 3 % of its length; at rest (speed 0) when it would move under 1 m."""
    speed = float(np.hypot(vel[0], vel[1]))
    bend = float(rng.uniform(-0.03, 0.03))
    if speed * duration < 1.0:
        u = unit(vel, heading(float(rng.uniform(0.0, 2.0 * math.pi))))
        return Track(role, np.array([at, at + u]), 0.0)
    u = vel / speed
    start = at - vel * t_at
    end = at + vel * (duration - t_at)
    length = speed * duration
    mid = (start + end) / 2.0 + perp(u) * bend * length
    return Track(role, np.array([start, mid, end]), speed)


def track_clearance(ctx: MapContext, track: Track) -> float:
    """Smallest conservative clearance (metres) minus hull radius along a track's waypoint polyline, sampled
    every 10 m: a cheap proposal score (the constraints do the exact checks)."""
    pts = [track.route[:1]]
    for a, b in zip(track.route[:-1], track.route[1:], strict=True):
        n = max(int(float(np.hypot(*(b - a))) // 10.0), 1)
        f = np.arange(1, n + 1)[:, None] / n
        pts.append(a + f * (b - a))
    return float(ctx.clearance(np.vstack(pts)).min()) - track.role.radius


def pick_best(inp: FamilyInput, make: Callable[[], list[Track]]) -> list[Track]:
    """Best of up to ``inp.proposals`` calls of ``make`` by :func:`track_clearance` (maximin over its tracks),
    stopping early at the first with ``clearance_m + 20`` metres to spare."""
    best: list[Track] = []
    best_score = -math.inf
    for _ in range(max(inp.proposals, 1)):
        tracks = make()
        score = min((track_clearance(inp.ctx, t) for t in tracks), default=math.inf) if tracks else -math.inf
        if score > best_score:
            best, best_score = tracks, score
        if score >= inp.clearance_m + 20.0:
            break
    return best
