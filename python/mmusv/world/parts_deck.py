"""Deck part families of procedural vessels: railings, container stacks, hatch covers, lifeboats and davits,
fenders, bollards, pipe racks, winches and round tubes.

Body frame and units as in :mod:`mmusv.world.vessel_shapes`; every builder takes its validated part and a
:class:`~mmusv.world.part_context.Ctx` and returns one :class:`~mmusv.world.primitives.TriMesh` of closed pieces,
built with the vectorised builders of :mod:`mmusv.world.primitives`.
"""

from __future__ import annotations

import math

import numpy as np

from mmusv.world.hull_form import _deck_z, half_width, half_widths, side_half_width
from mmusv.world.materials import material_id
from mmusv.world.part_context import Ctx
from mmusv.world.part_spec import (
    BollardsPart,
    ContainersPart,
    FendersPart,
    HatchesPart,
    LifeboatsPart,
    PipesPart,
    RailingPart,
    TubePart,
    WinchPart,
)
from mmusv.world.primitives import TriMesh, boxes, lathe, merge, placed, sweep, torus, transformed, tubes

__all__ = [
    "CONTAINER_COLOURS",
    "bollards_mesh",
    "containers_mesh",
    "fenders_mesh",
    "hatches_mesh",
    "lifeboats_mesh",
    "pipes_mesh",
    "railing_mesh",
    "tube_mesh",
    "winch_mesh",
]

CONTAINER_COLOURS = (
    "container_red",
    "container_blue",
    "container_green",
    "container_grey",
    "container_orange",
    "container_white",
    "container_brown",
    "container_yellow",
)
"""The materials container boxes are drawn from (one per box, by a fixed hash of its slot)."""

_SIDES = {"both": (1.0, -1.0), "port": (1.0,), "starboard": (-1.0,)}


def _half_widths(ctx: Ctx, xs: np.ndarray) -> np.ndarray:
    return half_widths(ctx.hull, xs)


def _rail_meshes(
    paths: list[tuple[np.ndarray, bool]], posts: np.ndarray, *, height: float, rails: int, radius: float, ctx: Ctx
) -> TriMesh:
    """Stanchions standing on ``posts`` ``(N, 3)`` (none when ``posts`` is empty) and ``rails`` rails along each
    ``(deck path, closed)``; thick rails alone (rubbing strakes) get 12-sided sections."""
    out = []
    if posts.shape[0]:
        top = posts + np.array([0.0, 0.0, height])
        out.append(tubes(starts=posts, ends=top, radius=radius, cls=ctx.cls, material=ctx.mat, segments=6))
    seg = 6 if posts.shape[0] else 12
    for path, closed in paths:
        for k in range(1, rails + 1):
            r = radius * (1.25 if k == rails and posts.shape[0] else 0.8 if posts.shape[0] else 1.0)
            lift = height * k / rails - (r if k == rails and posts.shape[0] else 0.0)
            up = path + np.array([0.0, 0.0, lift])
            out.append(sweep(up, radius=r, cls=ctx.cls, material=ctx.mat, segments=seg, closed=closed))
    return merge(out)


def _spaced(p0: np.ndarray, p1: np.ndarray, spacing: float, ctx: Ctx) -> np.ndarray:
    """Points from ``p0`` to ``p1`` (both included) about ``spacing`` apart."""
    n = max(1, ctx.count(math.ceil(float(np.linalg.norm(p1 - p0)) / spacing), key="spacing", what="stanchions"))
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    return np.asarray(p0 + t * (p1 - p0), dtype=np.float64)


def railing_mesh(p: RailingPart, ctx: Ctx) -> TriMesh:
    """Guard rails along the deck edge (or round a rectangle, with ``width``), raised by ``lift``; rails alone
    without ``posts``."""
    m = _railing(p, ctx)
    return transformed(m, translation=(0.0, 0.0, p.lift)) if p.lift else m


def _railing(p: RailingPart, ctx: Ctx) -> TriMesh:
    hull = ctx.hull
    r = p.radius if p.radius is not None else 0.02 + 0.01 * p.height
    if p.width is not None:
        assert p.x0 is not None and p.x1 is not None and p.base is not None
        hy = p.width / 2.0
        corners = np.array([[p.x0, p.y - hy], [p.x1, p.y - hy], [p.x1, p.y + hy], [p.x0, p.y + hy]])
        pts = [
            _spaced(np.append(corners[i], p.base), np.append(corners[(i + 1) % 4], p.base), p.spacing, ctx)[:-1]
            for i in range(4)
        ]
        loop = np.vstack(pts)
        return _rail_meshes([(loop, True)], _posts(p, loop), height=p.height, rails=p.rails, radius=r, ctx=ctx)
    half_l = hull.length / 2.0
    x0 = -half_l + max(p.inset, r) + 0.05 if p.x0 is None else p.x0
    x1 = half_l - 0.05 if p.x1 is None else p.x1
    n = max(2, ctx.count(math.ceil((x1 - x0) / p.spacing) + 1, key="spacing", what="stanchions"))
    xs = np.linspace(x0, x1, n)
    ys = _half_widths(ctx, xs) - max(p.inset, r)
    ok = ys > max(2.0 * r, 0.02)
    if ok.sum() < 2:
        raise ctx.error("x0", "the deck is too narrow for a railing here")
    xs, ys = xs[ok], ys[ok]
    zs = _deck_z(hull, xs) if p.base is None else np.full_like(xs, p.base)
    sides = _SIDES[p.side]
    if p.side != "both" or not (p.bow or p.stern):
        paths = [(np.column_stack([xs, s * ys, zs]), False) for s in sides]
        return _rail_meshes(
            paths, _posts(p, np.vstack([q for q, _ in paths])), height=p.height, rails=p.rails, radius=r, ctx=ctx
        )
    stb = np.column_stack([xs, -ys, zs])
    port = np.column_stack([xs, ys, zs])[::-1]
    post_sets = [stb, port]
    if p.bow:
        post_sets.append(_spaced(stb[-1], port[0], p.spacing, ctx)[1:-1])
    if p.stern:
        post_sets.append(_spaced(port[-1], stb[0], p.spacing, ctx)[1:-1])
    if p.bow and p.stern:
        paths = [(np.vstack([stb, port]), True)]
    elif p.bow:
        paths = [(np.vstack([stb, port]), False)]
    else:
        paths = [(np.vstack([port, stb]), False)]
    return _rail_meshes(paths, _posts(p, np.vstack(post_sets)), height=p.height, rails=p.rails, radius=r, ctx=ctx)


def _posts(p: RailingPart, pts: np.ndarray) -> np.ndarray:
    return pts if p.posts else pts[:0]


def containers_mesh(p: ContainersPart, ctx: Ctx) -> TriMesh:
    """Container stacks, every box a closed box of its own colour."""
    lb = (p.x1 - p.x0 - p.gap * (p.bays - 1)) / p.bays
    if lb <= 1.0:
        raise ctx.error("bays", f"{p.bays} bays with gap {p.gap:g} leave {lb:.2f} m per bay")
    n_long = max(
        1,
        ctx.count(round(lb / 12.5) * p.bays * p.rows * max(p.tiers), key="x1", what="containers")
        // (p.bays * p.rows * max(p.tiers)),
    )
    cl = (lb - 0.25 * (n_long - 1)) / n_long
    cw = (p.width - 0.08 * (p.rows - 1)) / p.rows
    if cw < 0.1:
        raise ctx.error(
            "width",
            f"{p.rows} rows 0.08 m apart leave {cw:.3g} m per container; width must be >= {0.18 * p.rows - 0.08:g} m",
        )
    ch = p.height
    bay, lon, row, tier, base = [], [], [], [], []
    for b in range(p.bays):
        nt = p.tiers[b % len(p.tiers)]
        xb = p.x0 + b * (lb + p.gap)
        z0 = ctx.base(p.base, xb + lb / 2.0)
        rows = np.arange(p.rows, dtype=np.float64)
        if p.fit is not None:
            room = min(half_width(ctx.hull, xb), half_width(ctx.hull, xb + lb)) - p.fit
            keep = int((2.0 * room + 0.08) // (cw + 0.08))
            drop = max(0, p.rows - keep)
            rows = rows[(drop + 1) // 2 : p.rows - drop // 2] if drop < p.rows else rows[:0]
            if drop % 2:  # an odd number dropped: shift the bay by half a row to keep it centred
                rows = rows - 0.5
        g = np.stack(np.meshgrid(np.arange(n_long), rows, np.arange(nt), indexing="ij"), axis=-1).reshape(-1, 3)
        bay.append(np.full(g.shape[0], b))
        lon.append(g[:, 0])
        row.append(g[:, 1])
        tier.append(g[:, 2])
        base.append(np.full(g.shape[0], z0))
    bi, li, ri, ti, zb = (np.concatenate(a) for a in (bay, lon, row, tier, base))
    if bi.shape[0] == 0:
        raise ctx.error("fit", "no container row fits inside the deck outline")
    bi, li, ti = bi.astype(np.int64), li.astype(np.int64), ti.astype(np.int64)
    cx = p.x0 + bi * (lb + p.gap) + li * (cl + 0.25) + cl / 2.0
    cy = -p.width / 2.0 + cw / 2.0 + ri * (cw + 0.08)
    cz = zb + ti * (ch + 0.03) + ch / 2.0
    key = (bi.astype(np.uint64) * np.uint64(73856093)) ^ (np.floor(ri * 2).astype(np.uint64) * np.uint64(19349663))
    key ^= ti.astype(np.uint64) * np.uint64(83492791)
    key ^= li.astype(np.uint64) * np.uint64(2654435761)
    key ^= np.uint64(p.seed) * np.uint64(97531)
    key = (key * np.uint64(0x9E3779B1)) >> np.uint64(7)
    palette = np.array([material_id(n) for n in CONTAINER_COLOURS])
    mats = palette[(key % np.uint64(len(palette))).astype(np.int64)]
    sizes = np.broadcast_to([cl, cw, ch], (cx.shape[0], 3))
    return boxes(centers=np.column_stack([cx, cy, cz]), sizes=sizes, cls=ctx.cls, material=mats)


def hatches_mesh(p: HatchesPart, ctx: Ctx) -> TriMesh:
    """Hatch covers on coamings, each with transverse stiffener ribs; top at ``base + height``."""
    ctx.count(p.count * (p.ribs + 2), key="count", what="hatch pieces")
    lx = (p.x1 - p.x0 - p.gap * (p.count - 1)) / p.count
    if lx <= 0.5:
        raise ctx.error("count", f"{p.count} hatches do not fit between x0 and x1")
    xc = p.x0 + lx / 2.0 + np.arange(p.count) * (lx + p.gap)
    steel = material_id("paint_grey")
    out = []
    for x in xc:
        w = ctx.fit_width(p.fit, x0=x - lx / 2, x1=x + lx / 2, y=0.0, width=p.width)
        if w < 0.4:
            key = "width" if w == p.width else "fit"
            raise ctx.error(
                key, f"leaves a hatch cover {w:.3g} m wide at x={x:g}; it must be >= 0.4 m (coaming inside)"
            )
        z0 = ctx.base(p.base, x)
        rib = min(0.25, 0.15 * p.height)
        hc = 0.55 * p.height
        out.append(
            boxes(centers=[[x, 0.0, z0 + hc / 2.0]], sizes=[[lx - 0.3, w - 0.3, hc]], cls=ctx.cls, material=steel)
        )
        hcov = p.height - hc - rib
        out.append(
            boxes(centers=[[x, 0.0, z0 + hc + hcov / 2.0]], sizes=[[lx, w, hcov]], cls=ctx.cls, material=ctx.mat)
        )
        if p.ribs:
            rx = x - lx / 2.0 + (np.arange(p.ribs) + 0.5) * lx / p.ribs
            c = np.column_stack([rx, np.zeros(p.ribs), np.full(p.ribs, z0 + p.height - rib / 2.0)])
            out.append(boxes(centers=c, sizes=[0.2, w - 0.2, rib], cls=ctx.cls, material=ctx.mat))
    return merge(out)


def _boat(length: float, *, cls: int, hull_mat: int, canopy_mat: int) -> TriMesh:
    """An enclosed lifeboat along +x centred at its keel midpoint: a blunt body of revolution, hull and canopy."""
    s = np.linspace(0.0, 1.0, 13)
    r = np.sqrt(np.clip(1.0 - np.abs(2.0 * s - 1.0) ** 2.5, 0.0, 1.0))
    z = -length / 2.0 + s * length
    prof = np.column_stack([r, z])
    prof[0, 0] = prof[-1, 0] = 0.0
    body = lathe(prof, cls=cls, material=hull_mat, segments=16, scale=(0.2 * length, 0.17 * length))
    rot = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    body = transformed(body, rotation=rot, translation=(0.0, 0.0, 0.2 * length))
    hatch = boxes(
        centers=[[0.1 * length, 0.0, 0.4 * length]],
        sizes=[[0.25 * length, 0.12 * length, 0.06 * length]],
        cls=cls,
        material=canopy_mat,
    )
    return merge([body, hatch])


def lifeboats_mesh(p: LifeboatsPart, ctx: Ctx) -> TriMesh:
    """Enclosed lifeboats with davit pairs (or a free-fall boat on a stern ramp)."""
    ln = p.length
    orange = ctx.mat
    steel = material_id("steel")
    boat = _boat(ln, cls=ctx.cls, hull_mat=orange, canopy_mat=material_id("superstructure_white"))
    if p.kind == "freefall":
        a = math.radians(35.0)
        pitch_down = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])
        rot = np.diag([-1.0, -1.0, 1.0]) @ pitch_down  # bow aft and 35 degrees down
        b = transformed(boat, rotation=rot, translation=(p.x, p.y, p.z))
        d = rot @ np.array([1.0, 0.0, 0.0])
        rails = []
        for sy in (-0.12 * ln, 0.12 * ln):
            s0 = np.array([p.x, p.y + sy, p.z]) - d * 0.55 * ln
            rails.append((s0, s0 + d * 1.1 * ln))
        st = np.array([q[0] for q in rails])
        en = np.array([q[1] for q in rails])
        deck = ctx.base(None, p.x)
        legs_s = np.vstack([en, st])
        legs_e = legs_s.copy()
        legs_e[:, 2] = deck
        keep = legs_s[:, 2] - legs_e[:, 2] > 0.05
        parts = [b, tubes(starts=st, ends=en, radius=0.03 * ln, cls=ctx.cls, material=steel, segments=8)]
        if keep.any():
            parts.append(
                tubes(starts=legs_e[keep], ends=legs_s[keep], radius=0.03 * ln, cls=ctx.cls, material=steel, segments=8)
            )
        return merge(parts)
    xs = p.x - np.arange(p.count) * p.pitch
    out = []
    for s in _SIDES[p.side]:
        yb = s * p.y
        out.append(
            placed(
                boat,
                rotations=np.zeros(p.count),
                translations=np.column_stack([xs, np.full(p.count, yb), np.full(p.count, p.z)]),
            )
        )
        ax = np.concatenate([xs - 0.3 * ln, xs + 0.3 * ln])
        deck_z = np.array([ctx.base(None, float(x)) for x in ax])
        ztop = p.z + 0.6 * ln
        yin = yb - s * 0.3 * ln
        posts0 = np.column_stack([ax, np.full_like(ax, yin), np.minimum(deck_z, ztop - 0.2)])
        posts1 = np.column_stack([ax, np.full_like(ax, yin), np.full_like(ax, ztop)])
        arm1 = np.column_stack([ax, np.full_like(ax, yb), np.full_like(ax, ztop + 0.05 * ln)])
        rr = 0.025 * ln
        out.append(tubes(starts=posts0, ends=posts1, radius=rr, cls=ctx.cls, material=steel, segments=8))
        out.append(tubes(starts=posts1, ends=arm1, radius=0.8 * rr, cls=ctx.cls, material=steel, segments=8))
        wire0 = arm1 - [0.0, 0.0, 0.02 * ln]
        wire1 = np.column_stack([ax, np.full_like(ax, yb), np.full_like(ax, p.z + 0.38 * ln)])
        out.append(
            tubes(
                starts=wire1,
                ends=wire0,
                radius=0.006 * ln,
                cls=ctx.cls,
                material=material_id("rope_canvas"),
                segments=4,
            )
        )
    return merge(out)


def fenders_mesh(p: FendersPart, ctx: Ctx) -> TriMesh:
    """Tyres or rubber cylinders hung on the hull side, inside the beam."""
    hull = ctx.hull
    xs = np.linspace(p.x0, p.x1, p.count)
    zs = np.full(p.count, p.z)
    hw = side_half_width(hull, x=xs, z=zs)
    if p.kind == "tyre":
        minor = 0.32 * p.radius
        tyre = torus(major=p.radius - minor, minor=minor, cls=ctx.cls, material=ctx.mat, segments=(16, 8))
        yc = np.minimum(hw + 0.6 * minor, hull.beam / 2.0 - minor)
    else:
        minor = p.radius
        tyre = tubes(
            starts=[[0.0, 0.0, -1.5 * p.radius]],
            ends=[[0.0, 0.0, 1.5 * p.radius]],
            radius=p.radius,
            cls=ctx.cls,
            material=ctx.mat,
            segments=12,
        )
        yc = np.minimum(hw + 0.5 * minor, hull.beam / 2.0 - minor)
    out = []
    for s in _SIDES[p.side]:
        # tyre axis across the ship (local z -> body y): rotation about x by -90 degrees, then the side sign
        rot = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, s], [0.0, -s, 0.0]]) if p.kind == "tyre" else np.eye(3)
        rots = np.broadcast_to(rot, (p.count, 3, 3))
        out.append(placed(tyre, rotations=np.ascontiguousarray(rots), translations=np.column_stack([xs, s * yc, zs])))
    return merge(out)


def bollards_mesh(p: BollardsPart, ctx: Ctx) -> TriMesh:
    """Double bollards on base plates along the deck edge."""
    r = p.radius
    post = lathe(
        [(r, 0.0), (0.9 * r, 2.2 * r), (1.35 * r, 2.3 * r), (1.35 * r, 2.7 * r), (0.0, 2.8 * r)],
        cls=ctx.cls,
        material=ctx.mat,
        segments=12,
    )
    pair = merge(
        [
            transformed(post, translation=(-1.3 * r, 0.0, 0.3 * r)),
            transformed(post, translation=(1.3 * r, 0.0, 0.3 * r)),
            boxes(centers=[[0.0, 0.0, 0.15 * r]], sizes=[[5.0 * r, 2.4 * r, 0.3 * r]], cls=ctx.cls, material=ctx.mat),
        ]
    )
    xs = np.linspace(p.x0, p.x1, p.count)
    ys = _half_widths(ctx, xs) - p.inset
    if np.any(ys < 1.2 * r):
        raise ctx.error("inset", "a bollard would stand outside the deck")
    zs = _deck_z(ctx.hull, xs)
    t = [np.column_stack([xs, s * ys, zs]) for s in _SIDES[p.side]]
    tr = np.vstack(t)
    return placed(pair, rotations=np.zeros(tr.shape[0]), translations=tr)


def pipes_mesh(p: PipesPart, ctx: Ctx) -> TriMesh:
    """Pipes along x on transverse supports."""
    ys = np.array(p.ys, dtype=np.float64)
    starts = np.column_stack([np.full_like(ys, p.x0), ys, np.full_like(ys, p.z)])
    ends = starts + np.array([p.x1 - p.x0, 0.0, 0.0])
    pipes = tubes(starts=starts, ends=ends, radius=p.radius, cls=ctx.cls, material=ctx.mat, segments=12)
    n = max(2, ctx.count((p.x1 - p.x0) // p.support + 1, key="support", what="pipe supports"))
    sx = np.linspace(p.x0 + 0.3, p.x1 - 0.3, n)
    z0 = _deck_z(ctx.hull, sx) if p.base is None else np.full(n, p.base)
    top = p.z - p.radius
    if np.any(top - z0 <= 0.05):
        raise ctx.error("z", f"pipes at z={p.z:g} m leave no room for supports above the deck")
    yc = (ys.min() + ys.max()) / 2.0
    wy = ys.max() - ys.min() + 2.0 * p.radius + 0.2
    legs = boxes(
        centers=np.column_stack([sx, np.full(n, yc), (z0 + top) / 2.0]),
        sizes=np.column_stack([np.full(n, 0.2), np.full(n, wy), top - z0]),
        cls=ctx.cls,
        material=material_id("paint_grey"),
    )
    return merge([pipes, legs])


def winch_mesh(p: WinchPart, ctx: Ctx) -> TriMesh:
    """A winch drum between cheek plates on a base block."""
    z0 = ctx.base(p.base, p.x)
    r, w = p.radius, p.width
    zc = z0 + 1.6 * r
    y0, y1 = p.y - w / 2.0, p.y + w / 2.0
    drum = tubes(
        starts=[[p.x, y0, zc]],
        ends=[[p.x, y1, zc]],
        radius=r,
        cls=ctx.cls,
        material=material_id("rope_canvas"),
        segments=16,
    )
    cheeks = tubes(
        starts=[[p.x, y0 - 0.08 * r, zc], [p.x, y1 - 0.1 * r, zc]],
        ends=[[p.x, y0 + 0.1 * r, zc], [p.x, y1 + 0.08 * r, zc]],
        radius=1.5 * r,
        cls=ctx.cls,
        material=ctx.mat,
        segments=16,
    )
    base = boxes(centers=[[p.x, p.y, z0 + 0.5 * r]], sizes=[[2.4 * r, w + 0.4 * r, r]], cls=ctx.cls, material=ctx.mat)
    return merge([drum, cheeks, base])


def tube_mesh(p: TubePart, ctx: Ctx) -> TriMesh:
    """One round tube."""
    return tubes(
        starts=[p.start],
        ends=[p.end],
        radius=p.radius,
        end_radius=p.end_radius,
        cls=ctx.cls,
        material=ctx.mat,
        segments=p.segments,
    )
