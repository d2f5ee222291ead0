"""Scenario family templates: where the vessels of one role combination start, go and meet.

A family turns drawn roles (ego USV, cooperating USVs, role targets, with assets and nominal speeds picked by
the sampler) into waypoint routes for an acquisition lasting ``duration`` seconds. World frame, metres, seconds,
radians (headings from +x, counter-clockwise).

Encounters are laid out in relative motion: a role target's closest point of approach (CPA) to the ego falls at
a time ``t_e`` inside the window, at a distance ``r`` drawn from the difficulty's ``range_m``. Routes are
straight tracks with a small lateral bend (three-waypoint spline) unless the family needs more (``convoy``: one
shared route with start offsets; ``port_entry``: a planned harbour approach). Templates check nothing; the named
constraints of :mod:`mmusv.generate.checks` decide. A template that cannot place its vessels at all raises
:class:`SamplingError`, counted as a rejection by ``sampling``.

Speeds: every USV sails within the spec's ``usv.speed_mps`` (a template that wants its USVs slow, port_entry's
waiting ego at 0.3-1 m/s, occluded_by_island's at 1.5 m/s at most, surround's group at 0.8 x a drawn speed, takes
the part of that band inside the range, or its nearest bound; a convoy slower than the range, a kayak's, is
passed by its USVs at speeds of their own). A target's speed is its size class's draw, except
where the family ties it to others: convoy (one speed for the line and the ego, the slowest member's top speed at
most), surround (the group's), overtaking (the ego's plus 1-3 m/s or minus 0.8-1.5 m/s), occluded_by_island's
primary (4 m/s at most) and port_entry's (5 m/s at most), so these may leave the class's ``speed_mps``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely

from mmusv.generate.layout import (
    FamilyInput,
    Layout,
    Role,
    SamplingError,
    Track,
    heading,
    perp,
    pick_best,
    straight_track,
    top_speed_mps,
    unit,
)
from mmusv.generate.planner import PlannerError, harbour_planner

__all__ = ["FAMILIES", "Family"]


@dataclass(frozen=True)
class Family:
    """A template: ``build`` lays out a :class:`Layout`; ``map_types`` it needs (empty = any); the fewest
    cooperating USVs it works with; whether it asks for the occlusion constraint."""

    name: str
    build: Callable[[FamilyInput], Layout]
    description: str
    map_types: tuple[str, ...] = ()
    min_cooperating: int = 0
    occlusion: bool = False


def _cpa_point(
    ego_at: np.ndarray, v_e: np.ndarray, v_t: np.ndarray, r: float, rng: np.random.Generator, *, ahead: bool
) -> np.ndarray:
    """Target position making ``ego_at`` -> target the CPA of their relative motion at distance ``r``; ``ahead``
    puts it in front of the ego (otherwise either side at random)."""
    w = v_t - v_e
    fwd = unit(v_e, heading(float(rng.uniform(0.0, 2.0 * math.pi))))
    n = unit(perp(w), perp(fwd))
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    if ahead:
        sign = 1.0 if float(n @ fwd) >= 0.0 else -1.0
    out: np.ndarray = ego_at + sign * r * n
    return out


def _escorts(inp: FamilyInput, anchor: np.ndarray, vel: np.ndarray, t_at: float) -> list[Track]:
    """Cooperating USVs spread around ``anchor`` (the ego's position at ``t_at``), sailing ~parallel to ``vel``."""
    rng, out = inp.rng, []
    n = len(inp.coops)
    base = float(rng.uniform(0.0, 2.0 * math.pi))
    for k, coop in enumerate(inp.coops):

        def make(k: int = k, coop: Role = coop) -> list[Track]:
            bearing = base + 2.0 * math.pi * k / n + float(rng.uniform(-0.5, 0.5))
            lo = max(inp.coop_m[0], inp.ego.radius + coop.radius + inp.separation_m) + 10.0
            hi = max(lo, min(0.6 * inp.coop_m[1], lo + 250.0))
            d = float(rng.uniform(lo, hi))
            turn = float(rng.uniform(-0.05, 0.05))
            c, s = math.cos(turn), math.sin(turn)
            v = np.array([c * vel[0] - s * vel[1], s * vel[0] + c * vel[1]])
            return [
                straight_track(coop, at=anchor + d * heading(bearing), vel=v, t_at=t_at, duration=inp.duration, rng=rng)
            ]

        out += pick_best(inp, make)
    return out


def _range(inp: FamilyInput) -> float:
    return float(inp.rng.uniform(*inp.range_m))


def _usv_band(inp: FamilyInput, lo: float, hi: float) -> tuple[float, float]:
    """The speeds ``[lo, hi]`` a template wants for its USVs (slow to wait or to stay behind an island), moved
    into the spec's ``usv.speed_mps``: the band's part inside it, or the spec's bound nearest the band. A template
    never sails a USV outside the range the spec gives (port_entry's 0.3-1 m/s under ``speed_mps: [2, 3]``)."""
    a, b = inp.usv_speed
    return min(max(lo, a), b), min(max(hi, a), b)


def _encounter(kind: str) -> Callable[[FamilyInput], Layout]:
    """crossing / head_on / overtaking: each role target meets the ego at its own CPA time and range."""

    def build(inp: FamilyInput) -> Layout:
        rng, big_t = inp.rng, inp.duration
        t0 = big_t * float(rng.uniform(0.35, 0.65))

        def make_ego() -> list[Track]:
            centre = inp.ctx.sample_points(1, min_clearance=inp.encounter_clearance, rng=rng)[0]
            theta = float(rng.uniform(0.0, 2.0 * math.pi))
            return [
                straight_track(inp.ego, at=centre, vel=inp.ego.speed * heading(theta), t_at=t0, duration=big_t, rng=rng)
            ]

        ego = pick_best(inp, make_ego)[0]
        v_e = ego.speed * unit(ego.route[-1] - ego.route[0], heading(0.0))
        theta = math.atan2(v_e[1], v_e[0])
        centre = ego.route[0] + v_e * t0 if ego.speed > 0 else ego.route[0]
        tracks = [ego]
        for k, tgt in enumerate(inp.targets):

            def make(k: int = k, tgt: Role = tgt) -> list[Track]:
                t_e = t0 if k == 0 else big_t * float(rng.uniform(0.25, 0.75))
                side = 1.0 if rng.uniform() < 0.5 else -1.0
                speed = tgt.speed
                if kind == "crossing":
                    psi = theta + side * (math.pi / 2.0 + float(rng.uniform(-0.44, 0.44)))
                elif kind == "head_on":
                    psi = theta + math.pi + float(rng.uniform(-0.17, 0.17))
                else:
                    psi = theta + float(rng.uniform(-0.14, 0.14))
                    if rng.uniform() < 0.5:
                        speed = inp.ego.speed + float(rng.uniform(1.0, 3.0))
                    else:
                        speed = max(0.5, inp.ego.speed - float(rng.uniform(0.8, 1.5)))
                    speed = min(speed, top_speed_mps(tgt.asset))
                v_t = speed * heading(psi)
                ego_at = centre + v_e * (t_e - t0)
                p = _cpa_point(ego_at, v_e, v_t, _range(inp), rng, ahead=kind == "crossing")
                return [straight_track(tgt, at=p, vel=v_t, t_at=t_e, duration=big_t, rng=rng)]

            tracks += pick_best(inp, make)
        tracks += _escorts(inp, centre, v_e, t0)
        return Layout(tracks, [t.id for t in inp.targets], centre)

    return build


def _convoy(inp: FamilyInput) -> Layout:
    """The role targets sail in line on one shared route (start offsets), the ego abeam of the lead (alongside it
    at the convoy's speed, or passing it at a speed of its own when the convoy is slower than ``usv.speed_mps``)."""
    rng, big_t = inp.rng, inp.duration
    # the convoy sails at its slowest member's top speed at most (a kayak is not towed along at the USV's speed)
    u = min([float(rng.uniform(*inp.usv_speed)), *(top_speed_mps(t.asset) for t in inp.targets)])
    # the ego keeps pace where the spec lets USVs sail that slowly; else it passes the line abeam of the lead
    u_e = u if u >= inp.usv_speed[0] else float(rng.uniform(*inp.usv_speed))
    t_e = big_t * float(rng.uniform(0.35, 0.65))
    gaps = [
        a.radius + b.radius + inp.separation_m + float(rng.uniform(15.0, 60.0))
        for a, b in zip(inp.targets[:-1], inp.targets[1:], strict=True)
    ]
    total = float(sum(gaps))

    def make() -> list[Track]:
        centre = inp.ctx.sample_points(1, min_clearance=inp.encounter_clearance, rng=rng)[0]
        fwd = heading(float(rng.uniform(0.0, 2.0 * math.pi)))
        side = 1.0 if rng.uniform() < 0.5 else -1.0
        lead_at = centre + side * _range(inp) * perp(fwd)
        start = lead_at - fwd * (total + u * t_e)
        end = lead_at + fwd * u * (big_t - t_e)
        mid = (start + end) / 2.0 + perp(fwd) * float(rng.uniform(-0.02, 0.02)) * float(np.hypot(*(end - start)))
        route = np.array([start, mid, end])
        out = [straight_track(inp.ego, at=centre, vel=u_e * fwd, t_at=t_e, duration=big_t, rng=rng)]
        offset = total
        for k, tgt in enumerate(inp.targets):
            out.append(Track(tgt, route.copy(), u, offset))
            if k < len(gaps):
                offset -= gaps[k]
        return out

    tracks = pick_best(inp, make)
    ego = tracks[0]
    fwd = unit(ego.route[-1] - ego.route[0], heading(0.0))
    centre = ego.route[0] + fwd * u_e * t_e
    tracks += _escorts(inp, centre, u_e * fwd, t_e)
    return Layout(tracks, [inp.targets[0].id], centre)


def _surround(inp: FamilyInput) -> Layout:
    """The USVs ring the primary target (other role targets close by), all sailing with it."""
    rng, big_t = inp.rng, inp.duration
    lo, hi = inp.usv_speed
    v = float(rng.uniform(*_usv_band(inp, 0.8 * lo, 0.8 * hi))) * heading(float(rng.uniform(0.0, 2.0 * math.pi)))
    t_e = big_t / 2.0
    primary = inp.targets[0]

    def make_group() -> list[Track]:
        centre = inp.ctx.sample_points(1, min_clearance=inp.encounter_clearance, rng=rng)[0]
        out = [straight_track(primary, at=centre, vel=v, t_at=t_e, duration=big_t, rng=rng)]
        for tgt in inp.targets[1:]:
            d = primary.radius + tgt.radius + inp.separation_m + float(rng.uniform(10.0, 60.0))
            at = centre + d * heading(float(rng.uniform(0.0, 2.0 * math.pi)))
            out.append(straight_track(tgt, at=at, vel=v, t_at=t_e, duration=big_t, rng=rng))
        return out

    target_tracks = pick_best(inp, make_group)
    centre = target_tracks[0].route[0] + v * t_e
    usvs = [inp.ego, *inp.coops]
    base = float(rng.uniform(0.0, 2.0 * math.pi))
    usv_tracks: list[Track] = []
    for k, usv in enumerate(usvs):

        def make(k: int = k, usv: Role = usv) -> list[Track]:
            bearing = base + 2.0 * math.pi * k / len(usvs) + float(rng.uniform(-0.3, 0.3))
            return [
                straight_track(
                    usv, at=centre + _range(inp) * heading(bearing), vel=v, t_at=t_e, duration=big_t, rng=rng
                )
            ]

        usv_tracks += pick_best(inp, make)
    return Layout(usv_tracks + target_tracks, [primary.id], centre)


def _occluded(inp: FamilyInput) -> Layout:
    """The primary target passes behind an island as seen from the ego; cooperating USVs watch from the flanks."""
    ctx, rng, big_t = inp.ctx, inp.rng, inp.duration
    limit = 0.9 * min(inp.range_m[1], inp.coop_m[1])
    cands = [o for o in ctx.occluders if o.diameter <= limit]
    if not cands:
        raise SamplingError(f"no island (occlusion region) on this map has a diameter under {limit:.0f} m")
    occ = cands[int(rng.integers(len(cands)))]
    primary = inp.targets[0]
    pad = inp.clearance_m + 10.0
    reach = occ.diameter * 1.5 + 200.0
    for _ in range(8):
        phi = float(rng.uniform(0.0, 2.0 * math.pi))
        behind = phi + math.pi + float(rng.uniform(-0.3, 0.3))
        e1 = ctx.ray_exit(occ.centre, angle=phi, need=inp.ego.radius + pad, max_len=reach)
        e2 = ctx.ray_exit(occ.centre, angle=behind, need=primary.radius + pad, max_len=reach)
        r = _range(inp)
        if e1 is None or e2 is None or r - e1 - e2 < 20.0:
            continue
        extra = r - e1 - e2
        d_e = extra * float(rng.uniform(0.2, 0.6))
        break
    else:
        raise SamplingError("found no side of the island with water in front and behind within the range")
    t_e = big_t * float(rng.uniform(0.4, 0.6))
    side = 1.0 if rng.uniform() < 0.5 else -1.0
    ego_at = occ.centre + (e1 + d_e) * heading(phi)
    tgt_at = occ.centre + (e2 + extra - d_e) * heading(behind)
    v_t = min(primary.speed, 4.0) * heading(behind + side * math.pi / 2.0)
    slow = _usv_band(inp, 0.0, 1.5)[1]  # slowly along the island's flank: 1.5 m/s, or the spec's lowest speed
    v_e = min(inp.ego.speed, slow) * heading(phi + side * math.pi / 2.0)
    tracks = [
        straight_track(inp.ego, at=ego_at, vel=v_e, t_at=t_e, duration=big_t, rng=rng),
        straight_track(primary, at=tgt_at, vel=v_t, t_at=t_e, duration=big_t, rng=rng),
    ]
    for k, coop in enumerate(inp.coops):

        def make_coop(k: int = k, coop: Role = coop) -> list[Track]:
            flank = (1.0 if k % 2 == 0 else -1.0) * (float(rng.uniform(1.05, 1.9)) + 0.3 * (k // 2))
            ang = behind + flank
            e = ctx.ray_exit(occ.centre, angle=ang, need=coop.radius + pad, max_len=reach)
            if e is None:
                return []
            at = occ.centre + (e + float(rng.uniform(20.0, 120.0))) * heading(ang)
            v_c = min(coop.speed, slow) * heading(ang + side * math.pi / 2.0)
            return [straight_track(coop, at=at, vel=v_c, t_at=t_e, duration=big_t, rng=rng)]

        placed = pick_best(inp, make_coop)
        if not placed:
            raise SamplingError("no water on the island's flanks for a cooperating USV")
        tracks += placed
    for tgt in inp.targets[1:]:

        def make_tgt(tgt: Role = tgt) -> list[Track]:
            v = tgt.speed * heading(float(rng.uniform(0.0, 2.0 * math.pi)))
            t_k = big_t * float(rng.uniform(0.25, 0.75))
            p = _cpa_point(ego_at + v_e * (t_k - t_e), v_e, v, _range(inp), rng, ahead=False)
            return [straight_track(tgt, at=p, vel=v, t_at=t_k, duration=big_t, rng=rng)]

        tracks += pick_best(inp, make_tgt)
    return Layout(tracks, [t.id for t in inp.targets], ego_at)


def _port_entry(inp: FamilyInput) -> Layout:
    """Role targets enter the harbour on planned approaches; the ego waits off the primary's track (0.3-1 m/s, moved
    into ``usv.speed_mps``)."""
    ctx, rng, big_t = inp.ctx, inp.rng, inp.duration
    try:
        planner = harbour_planner(ctx)
    except PlannerError as exc:
        raise SamplingError(str(exc)) from None
    target_tracks = []
    q = tdir = None
    for k, tgt in enumerate(inp.targets):
        u = min(tgt.speed, 5.0)
        frac = float(rng.uniform(0.3, 0.7)) if k == 0 else float(rng.uniform(0.1, 0.9))
        try:
            path = planner.approach(tgt.beam_r + inp.clearance_m + 10.0, entry_after_m=u * big_t * frac, rng=rng)
        except PlannerError as exc:
            raise SamplingError(f"{tgt.asset}: {exc}") from None
        target_tracks.append(Track(tgt, path, u))
        if k == 0:
            line = shapely.linestrings(path)
            s = u * big_t * frac
            a = np.asarray(shapely.get_coordinates(shapely.line_interpolate_point(line, s)))[0]
            b = np.asarray(shapely.get_coordinates(shapely.line_interpolate_point(line, s + 10.0)))[0]
            q, tdir = a, unit(b - a, heading(0.0))
    assert q is not None and tdir is not None
    t_e = big_t * 0.5
    need = inp.ego.radius + inp.clearance_m + 10.0
    for _ in range(24):
        # off the approach: seawards of the entrance point or inside the basin, up to 70 degrees off the track
        towards = -tdir if rng.uniform() < 0.5 else tdir
        turn = float(rng.uniform(-1.22, 1.22))
        c, s = math.cos(turn), math.sin(turn)
        at = q + _range(inp) * np.array([c * towards[0] - s * towards[1], s * towards[0] + c * towards[1]])
        if float(ctx.clearance(at[None, :])[0]) >= need:
            break
    else:
        raise SamplingError("no open water for the ego beside the primary target's harbour approach")
    v_e = float(rng.uniform(*_usv_band(inp, 0.3, 1.0))) * heading(float(rng.uniform(0.0, 2.0 * math.pi)))
    tracks = [straight_track(inp.ego, at=at, vel=v_e, t_at=t_e, duration=big_t, rng=rng), *target_tracks]
    tracks += _escorts(inp, at, v_e, t_e)
    return Layout(tracks, [inp.targets[0].id], q)


FAMILIES: dict[str, Family] = {
    f.name: f
    for f in (
        Family("crossing", _encounter("crossing"), "a target crosses ahead of the ego at 90 ± 25 degrees"),
        Family("head_on", _encounter("head_on"), "a target meets the ego on a reciprocal course"),
        Family(
            "overtaking", _encounter("overtaking"), "a target overtakes the ego or is overtaken on a parallel course"
        ),
        Family("convoy", _convoy, "the role targets sail in line; the ego keeps abeam of the lead"),
        Family("surround", _surround, "the USVs ring the primary target and sail with it"),
        Family(
            "occluded_by_island",
            _occluded,
            "the primary target passes behind an island seen from the ego; another USV watches it",
            min_cooperating=1,
            occlusion=True,
        ),
        Family(
            "port_entry", _port_entry, "targets enter the harbour; the ego waits off the approach", map_types=("port",)
        ),
    )
}
"""The family templates by name."""
