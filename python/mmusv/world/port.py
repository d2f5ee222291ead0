"""Port layout: quay, piers, breakwaters with an entrance, container yard, gantry cranes, buildings,
channel buoys and berths for moored ships.

Everything here is built in the *canonical port frame*: land to the north (+y), open sea to the south, the quay
line at ``y = coast_offset_m``, map centred at the origin, metres. :mod:`mmusv.world.maps` rotates the result
to the requested ``coast_side``. All random draws come from the ``rng`` passed in, in a fixed order.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely
from shapely.geometry import Polygon

from mmusv.classes import SemanticClass
from mmusv.world.map_params import resolved
from mmusv.world.primitives import TriMesh, box, cylinder, merge, transformed

if TYPE_CHECKING:
    from mmusv.world.map_params import PortParams

__all__ = [
    "BUOY_FLOAT_RADIUS_M",
    "Berth",
    "PortPlan",
    "buoy_mesh",
    "plan_port",
    "port_structures",
    "port_terrain",
    "tapered_wall",
]

Ground = Callable[[np.ndarray], np.ndarray]
"""Terrain height (metres) at canonical points ``(N, 2)`` -> ``(N,)``."""

CONTAINER_L, CONTAINER_W, CONTAINER_H = 12.19, 2.44, 2.59
CRANE_GAUGE = 30.0
BREAKWATER_BOTTOM_W, BREAKWATER_TOP_W, BREAKWATER_CREST = 30.0, 8.0, 5.0


@dataclass(frozen=True)
class PortPlan:
    """Resolved port layout in the canonical frame (metres). ``quay_face`` is the seaward face of the quay."""

    half: float
    quay_y: float
    quay_face: float
    hw: float
    hd: float
    entrance_x: float
    entrance_w: float
    terminal_x1: float
    yard: tuple[float, float, float, float]
    land_h: float
    quay_h: float
    basin: float
    piers: tuple[tuple[float, float], ...]
    """``(centre x, length)`` of each pier."""
    hills_from: float
    """Inland distance (from the quay line) where hills may start inside the port zone."""


@dataclass(frozen=True)
class Berth:
    """A moored ship: library asset name, canonical pose ``(x, y, yaw)`` and its ``(length, beam)`` metres;
    ``face`` the unit vector (canonical frame) from its centre towards the quay or pier face it lies along."""

    asset: str
    pose: tuple[float, float, float]
    size: tuple[float, float]
    face: tuple[float, float] = (0.0, 1.0)

    def footprint(self) -> Polygon:
        """Hull rectangle (shapely, metres, canonical frame)."""
        x, y, yaw = self.pose
        l2, b2 = self.size[0] / 2.0, self.size[1] / 2.0
        c, s = np.cos(yaw), np.sin(yaw)
        pts = np.array([[-l2, -b2], [l2, -b2], [l2, b2], [-l2, b2]])
        return Polygon(pts @ np.array([[c, s], [-s, c]]) + (x, y))


def _smoothstep(e0: float | np.ndarray, e1: float | np.ndarray, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    out: np.ndarray = t * t * (3.0 - 2.0 * t)
    return out


def plan_port(p: PortParams, *, grid: float, rng: np.random.Generator) -> PortPlan:
    """Draws the layout (entrance position, pier lengths) for validated parameters ``p``."""
    half = p.extent_m / 2.0
    q = resolved(p.coast_offset_m)
    hw, hd, ew = resolved(p.harbour_width_m), resolved(p.harbour_depth_m), resolved(p.entrance_width_m)
    n_piers = resolved(p.n_piers)
    span = hw / 2.0 - ew / 2.0 - 80.0
    entrance_x = float(rng.uniform(-0.5, 0.5) * max(span, 0.0))
    terminal_x1 = -hw / 2.0 + (0.6 if n_piers > 0 else 1.0) * hw
    quay_face = q - grid - 1.0
    land_depth = half - q
    yard_y0 = quay_face + 6.0 + CRANE_GAUGE + 30.0
    yard_y1 = min(yard_y0 + 240.0, q + land_depth - 60.0)
    piers: list[tuple[float, float]] = []
    if n_piers:
        a, b = terminal_x1 + 30.0, hw / 2.0 - 30.0
        pitch = (b - a) / n_piers
        for k in range(n_piers):
            length = float(rng.uniform(*resolved(p.pier_length_m)))
            piers.append((a + (k + 0.5) * pitch, min(length, hd - 100.0)))
    return PortPlan(
        half=half,
        quay_y=q,
        quay_face=quay_face,
        hw=hw,
        hd=hd,
        entrance_x=entrance_x,
        entrance_w=ew,
        terminal_x1=terminal_x1,
        yard=(-hw / 2.0 + 30.0, yard_y0, terminal_x1 - 20.0, yard_y1),
        land_h=p.quay_height_m - 0.3,
        quay_h=p.quay_height_m,
        basin=p.basin_depth_m,
        piers=tuple(piers),
        hills_from=max(yard_y1 - q, 260.0) + 60.0,
    )


def port_terrain(
    plan: PortPlan, *, x: np.ndarray, y: np.ndarray, coast_noise: np.ndarray, hill_noise: np.ndarray, hill_m: float
) -> np.ndarray:
    """Canonical-frame terrain heights (metres, shape of ``x``).

    Inside the port zone (``|x| <= harbour_width/2 + 60``) the land is flat at ``quay_height - 0.3`` and the
    water dredged to ``-basin_depth``, with the step hidden under the quay; outside it a natural coast with
    beaches (slope 1:20) and a shelf (slope 8 %) blends in. Hills (``hill_m`` high, from ``hill_noise`` in
    [-1, 1]) rise inland. ``coast_noise`` (in [-1, 1], shape of ``x``) wiggles the natural coastline.
    """
    w = 1.0 - _smoothstep(plan.hw / 2.0 + 60.0, plan.hw / 2.0 + 220.0, np.abs(x))
    coast = plan.quay_y + (1.0 - w) * (35.0 + 55.0 * coast_noise)
    d = y - coast
    start = w * plan.hills_from + (1.0 - w) * 90.0
    hills = hill_m * np.clip(0.5 + 0.6 * hill_noise, 0.0, 1.0) ** 1.5 * _smoothstep(start, start + 220.0, d)
    z_port = np.where(d >= 0.0, plan.land_h, -plan.basin)
    z_nat = np.where(d >= 0.0, np.minimum(0.05 * d, plan.land_h + 1.0), np.maximum(-25.0, 0.08 * d))
    out: np.ndarray = w * z_port + (1.0 - w) * z_nat + np.where(d > 0.0, hills, 0.0)
    return out


def tapered_wall(
    p0: tuple[float, float],
    p1: tuple[float, float],
    *,
    bottom_w: float,
    top_w: float,
    z0: float,
    z1: float,
    extend: float,
    cls: int,
) -> TriMesh:
    """A wall along segment ``p0 -> p1`` (extended by ``extend`` at both ends) with a trapezoidal section."""
    a, b = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    length = float(np.linalg.norm(b - a)) + 2.0 * extend
    yaw = float(np.arctan2(b[1] - a[1], b[0] - a[0]))
    base = box(center=(0.0, 0.0, 0.0), size=(length, bottom_w, z1 - z0), cls=cls)
    v = base.vertices.copy()
    top = v[:, 2] > 0.0
    v[top, 1] *= top_w / bottom_w
    mid = (a + b) / 2.0
    return transformed(
        TriMesh(v, base.faces, base.classes), rotation=_rz(yaw), translation=(mid[0], mid[1], (z0 + z1) / 2.0)
    )


def _rz(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


BUOY_FLOAT_RADIUS_M = 1.2
"""The radius of a buoy's float (:func:`buoy_mesh`), metres: the waterplane over which it rides the waves
(:mod:`mmusv.world.buoys`)."""


def buoy_mesh(x: float, y: float) -> TriMesh:
    """A navigation buoy (class BUOY): a 1.2 m radius float with a conical top mark, 3.8 m above water."""
    cls = int(SemanticClass.BUOY)
    body = cylinder(center=(x, y, -1.0), radius=BUOY_FLOAT_RADIUS_M, height=3.0, cls=cls, segments=10)
    mark = cylinder(center=(x, y, 2.0), radius=0.6, height=1.8, cls=cls, segments=6, top_radius=0.05)
    return merge([body, mark])


def _sts_crane(x: float, face: float, base: float) -> TriMesh:
    """Ship-to-shore gantry crane (class CRANE) with its boom raised, legs on rails behind the quay face."""
    c = int(SemanticClass.CRANE)
    ws, ls = face + 6.0, face + 6.0 + CRANE_GAUGE
    top = base + 42.0
    parts = []
    for dx in (-9.0, 9.0):
        for yy in (ws, ls):
            parts.append(box(center=(x + dx, yy, (base + top) / 2.0), size=(1.6, 1.6, top - base), cls=c))
        parts.append(box(center=(x + dx, (ws + ls) / 2.0, base + 12.0), size=(1.2, CRANE_GAUGE, 1.6), cls=c))
        parts.append(box(center=(x + dx, (ws + ls) / 2.0 + 2.0, top + 1.5), size=(2.0, CRANE_GAUGE + 8.0, 3.0), cls=c))
    for yy in (ws, ls):
        parts.append(box(center=(x, yy, top + 1.5), size=(19.6, 2.0, 3.0), cls=c))
    parts.append(box(center=(x, ls + 8.0, top + 6.5), size=(12.0, 14.0, 7.0), cls=c))
    parts.append(box(center=(x, ls - 4.0, top + 14.0), size=(3.0, 3.0, 22.0), cls=c))
    boom_len, angle = 55.0, np.deg2rad(84.0)
    axis = np.array([0.0, -np.cos(angle), np.sin(angle)])
    hinge = np.array([x, ws, top + 3.0])
    boom = box(center=(0.0, 0.0, 0.0), size=(3.5, boom_len, 2.5), cls=c)
    parts.append(transformed(boom, rotation=_rx(np.pi - angle), translation=hinge + axis * boom_len / 2.0))
    return merge(parts)


def _container_block(
    x0: float, y0: float, base: float, *, rng: np.random.Generator, fill: float, tiers: int
) -> TriMesh | None:
    """5 bays x 6 rows of container stacks (class CONTAINER) with random heights; ``None`` when empty."""
    parts = []
    for row in range(6):
        for bay in range(5):
            n = int(rng.integers(1, tiers + 1))
            if rng.uniform() >= fill:
                continue
            cx = x0 + bay * (CONTAINER_L + 0.6) + CONTAINER_L / 2.0
            cy = y0 + row * (CONTAINER_W + 0.4) + CONTAINER_W / 2.0
            h = n * CONTAINER_H
            parts.append(
                box(
                    center=(cx, cy, base + h / 2.0),
                    size=(CONTAINER_L, CONTAINER_W, h),
                    cls=int(SemanticClass.CONTAINER),
                )
            )
    return merge(parts) if parts else None


@dataclass(frozen=True)
class PortStructures:
    """Canonical-frame result of :func:`port_structures`: structure parts (each one footprint unit),
    channel buoy positions (pairs, two by two: as many as fit, up to ``n_channel_buoy_pairs``) and berths."""

    parts: list[TriMesh]
    buoys: list[tuple[float, float]]
    berths: list[Berth]


def port_structures(p: PortParams, plan: PortPlan, *, ground: Ground, rng: np.random.Generator) -> PortStructures:
    """Builds quay, piers, breakwaters (+ head lights), cranes, container yard, buildings, channel buoys and
    berths. Each returned part is one rigid piece whose convex footprint is used for the priors."""
    ps = int(SemanticClass.PORT_STRUCTURE)
    q, face, hw, hd = plan.quay_y, plan.quay_face, plan.hw, plan.hd
    parts: list[TriMesh] = []
    # Quay apron along the whole harbour front, hiding the land/basin step of the terrain.
    parts.append(
        box(
            center=(0.0, (face + q + 30.0) / 2.0, (plan.quay_h - plan.basin) / 2.0),
            size=(hw, q + 30.0 - face, plan.quay_h + plan.basin),
            cls=ps,
        )
    )
    pier_w = p.pier_width_m
    for px, plen in plan.piers:
        parts.append(
            box(
                center=(px, face - plen / 2.0 + 0.5, (plan.quay_h - 3.0) / 2.0),
                size=(pier_w, plen + 1.0, plan.quay_h + 3.0),
                cls=ps,
            )
        )
    # Breakwaters: west and east arms, each a root leg and a head leg, leaving the entrance between heads.
    y_out = q - hd
    z0 = -plan.basin - 1.0
    ex0, ex1 = plan.entrance_x - plan.entrance_w / 2.0, plan.entrance_x + plan.entrance_w / 2.0
    heads = []
    for root_x, head_x in ((-hw / 2.0, ex0 + BREAKWATER_BOTTOM_W / 2.0), (hw / 2.0, ex1 - BREAKWATER_BOTTOM_W / 2.0)):
        for a, b in (((root_x, q + 10.0), (root_x, y_out)), ((root_x, y_out), (head_x, y_out))):
            parts.append(
                tapered_wall(
                    a,
                    b,
                    bottom_w=BREAKWATER_BOTTOM_W,
                    top_w=BREAKWATER_TOP_W,
                    z0=z0,
                    z1=BREAKWATER_CREST,
                    extend=BREAKWATER_TOP_W / 2.0,
                    cls=ps,
                )
            )
        heads.append(head_x)
    for hx in heads:
        parts.append(
            cylinder(
                center=(hx, y_out, BREAKWATER_CREST - 0.5),
                radius=2.5,
                height=11.0,
                cls=int(SemanticClass.BUILDING),
                segments=10,
            )
        )
    # Gantry cranes along the terminal quay.
    t0, t1 = -hw / 2.0 + 40.0, plan.terminal_x1 - 20.0
    n_cranes = resolved(p.n_cranes)
    if n_cranes:
        pitch = (t1 - t0) / n_cranes
        for k in range(n_cranes):
            cx = t0 + (k + 0.5) * pitch + float(rng.uniform(-0.15, 0.15)) * max(pitch - 30.0, 0.0)
            parts.append(_sts_crane(cx, face, plan.quay_h))
    # Container yard: blocks of 5 x 6 stacks with driving lanes.
    yx0, yy0, yx1, yy1 = plan.yard
    bl, bw = 5 * CONTAINER_L + 4 * 0.6, 6 * CONTAINER_W + 5 * 0.4
    nx_b, ny_b = int((yx1 - yx0 + 15.0) // (bl + 15.0)), int((yy1 - yy0 + 12.0) // (bw + 12.0))
    occupied = (
        [shapely.box(yx0 - 5.0, yy0 - 5.0, yx0 + nx_b * (bl + 15.0), yy0 + ny_b * (bw + 12.0))] if nx_b * ny_b else []
    )
    for i in range(ny_b):
        for j in range(nx_b):
            blk = _container_block(
                yx0 + j * (bl + 15.0),
                yy0 + i * (bw + 12.0),
                plan.land_h - 0.1,
                rng=rng,
                fill=p.container_fill,
                tiers=p.max_container_tiers,
            )
            if blk is not None:
                parts.append(blk)
    # Buildings: warehouses and offices behind the pier section and behind the yard, on land.
    zones = [
        (plan.terminal_x1 + 10.0, q + 45.0, hw / 2.0 + 40.0, q + 280.0),
        (-hw / 2.0, yy1 + 25.0, plan.terminal_x1, min(yy1 + 220.0, plan.half - 40.0)),
    ]
    zones = [z for z in zones if z[2] - z[0] > 40.0 and z[3] - z[1] > 40.0]
    placed = 0
    for _ in range(40 * p.n_buildings):
        if placed >= p.n_buildings or not zones:
            break
        zx0, zy0, zx1, zy1 = zones[int(rng.integers(len(zones)))]
        if rng.uniform() < 0.5:
            sx, sy, h = rng.uniform(50.0, 120.0), rng.uniform(25.0, 45.0), rng.uniform(8.0, 16.0)
        else:
            sx, sy, h = rng.uniform(15.0, 35.0), rng.uniform(15.0, 35.0), rng.uniform(12.0, 40.0)
        if sx > zx1 - zx0 or sy > zy1 - zy0:
            continue
        cx, cy = rng.uniform(zx0 + sx / 2.0, zx1 - sx / 2.0), rng.uniform(zy0 + sy / 2.0, zy1 - sy / 2.0)
        fp = shapely.box(cx - sx / 2.0, cy - sy / 2.0, cx + sx / 2.0, cy + sy / 2.0)
        if any(fp.buffer(10.0).intersects(o) for o in occupied):
            continue
        corners = np.array(fp.exterior.coords[:4])
        zg = ground(corners)
        if not np.all(zg > 0.5):
            continue
        zb = float(zg.min()) - 0.5
        zt = float(zg.max()) + float(h)
        parts.append(box(center=(cx, cy, (zb + zt) / 2.0), size=(sx, sy, zt - zb), cls=int(SemanticClass.BUILDING)))
        occupied.append(fp)
        placed += 1
    # Channel buoys: pairs marking the fairway from the entrance out to sea.
    buoys: list[tuple[float, float]] = []
    for k in range(p.n_channel_buoy_pairs):
        by = y_out - 70.0 - 150.0 * k
        if by < -plan.half + 40.0:
            break
        for side in (-1.0, 1.0):
            buoys.append((plan.entrance_x + side * (plan.entrance_w / 2.0 - 15.0), by))
    berths = _berths(p, plan, parts, rng=rng)
    return PortStructures(parts=parts, buoys=buoys, berths=berths)


def _afloat(berth: Berth, p: PortParams) -> Berth | None:
    """``berth`` where its ship floats in the basin (its draft, from its hull particulars as the ``under_keel``
    check reads them, below ``basin_depth_m``), else the same berth holding the longest ship of ``p.moored_assets``
    that fits its length and beam and floats (None where none does)."""
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    def floats(name: str) -> bool:
        return hull_particulars(get_asset(name))[2] < p.basin_depth_m

    if floats(berth.asset):
        return berth
    length, beam = berth.size
    fits = [a for a in p.moored_assets if a[1] <= length and a[2] <= beam and floats(a[0])]
    if not fits:
        return None
    name, ship_length, ship_beam = max(fits, key=lambda a: (a[1], a[2]))
    shift = (beam - ship_beam) / 2.0  # alongside the same face, as far off it as the berth's own ship lay
    x, y, yaw = berth.pose
    pose = (x + shift * berth.face[0], y + shift * berth.face[1], yaw)
    return Berth(name, pose, (ship_length, ship_beam), berth.face)


def _berths(p: PortParams, plan: PortPlan, parts: list[TriMesh], *, rng: np.random.Generator) -> list[Berth]:
    """Candidate berths along the terminal quay and both sides of every pier; ``n_moored`` of them chosen, or every
    free one when fewer fit (:func:`mmusv.world.maps.generate_port` then refuses the map). A ship chosen for a
    berth whose draft reaches the basin's floor (``basin_depth_m``: the 300 m container ship's 14.5 m in the default
    14 m) gives way to the longest ship of ``moored_assets`` that fits the berth and floats, at the same berth (where
    none does, the berth is passed over): until 2026-12-06 the default ports of 7 of the seeds 0-11 moored it with
    its keel in the floor. No draw of its own: the ports whose ships floated are as they were."""
    if p.n_moored == 0:
        return []
    assets = p.moored_assets
    cands: list[Berth] = []
    x, x_end = -plan.hw / 2.0 + 30.0, plan.terminal_x1 - 15.0
    while True:
        fits = [a for a in assets if a[1] <= x_end - x]
        if not fits:
            break
        weights = np.array([a[1] for a in fits])  # the terminal quay favours large ships
        name, length, beam = fits[int(rng.choice(len(fits), p=weights / weights.sum()))]
        yaw = 0.0 if rng.uniform() < 0.5 else float(np.pi)
        cands.append(Berth(name, (x + length / 2.0, plan.quay_face - 3.0 - beam / 2.0, yaw), (length, beam)))
        x += length + float(rng.uniform(15.0, 40.0))
    for px, plen in plan.piers:
        for side in (-1.0, 1.0):
            fits = [a for a in assets if a[1] <= plen - 10.0]
            if not fits:
                continue
            name, length, beam = fits[int(rng.integers(len(fits)))]
            yaw = float(np.pi / 2.0 if rng.uniform() < 0.5 else -np.pi / 2.0)
            bx = px + side * (p.pier_width_m / 2.0 + 3.0 + beam / 2.0)
            face = (-side, 0.0)  # the pier lies on the other side of the ship
            cands.append(Berth(name, (bx, plan.quay_face - 5.0 - length / 2.0, yaw), (length, beam), face))
    hulls = shapely.union_all([shapely.convex_hull(shapely.multipoints(m.vertices[:, :2])) for m in parts])
    chosen: list[Berth] = []
    taken: list[Polygon] = []
    for k in rng.permutation(len(cands)):
        b = cands[int(k)]
        fp = b.footprint()
        if fp.intersects(hulls) or any(fp.buffer(4.0).intersects(t) for t in taken):
            continue
        afloat = _afloat(b, p)
        if afloat is None:
            continue
        chosen.append(afloat)
        taken.append(fp)
        if len(chosen) == p.n_moored:
            break
    return chosen
