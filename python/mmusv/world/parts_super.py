"""Superstructure part families of procedural vessels: deckhouses with window bands and bridge wings, window rows,
funnels with bands, masts with yards, radar scanners, antennas, COLREG navigation lights, deck cranes and domes.

Body frame and units as in :mod:`mmusv.world.vessel_shapes`; every builder takes its validated part and a
:class:`~mmusv.world.part_context.Ctx` and returns one :class:`~mmusv.world.primitives.TriMesh` of closed pieces,
built with the vectorised builders of :mod:`mmusv.world.primitives`.
"""

from __future__ import annotations

import math

import numpy as np

from mmusv.world.hull_form import half_width, half_widths, side_half_width
from mmusv.world.materials import lamp_material, material_id
from mmusv.world.part_context import Ctx, block
from mmusv.world.part_spec import (
    AntennasPart,
    BoxPart,
    CranePart,
    DomePart,
    FunnelPart,
    HousePart,
    MastPart,
    NavLightsPart,
    RadarPart,
    WindowsPart,
)
from mmusv.world.primitives import TriMesh, boxes, lathe, merge, transformed, tubes

__all__ = [
    "antennas_mesh",
    "box_mesh",
    "crane_mesh",
    "dome_mesh",
    "funnel_mesh",
    "house_mesh",
    "mast_mesh",
    "nav_lights_mesh",
    "radar_mesh",
    "window_panes",
    "windows_mesh",
]

_GLASS = "glass"
_FRAME = "aluminium"


def window_panes(
    *,
    centers: np.ndarray,
    yaw: np.ndarray,
    width: float,
    height: float,
    cls: int,
    round_: bool = False,
    pane: int | None = None,
) -> TriMesh:
    """Windows centred on a wall at ``centers`` ``(N, 3)``, the wall's outward normal at angle ``yaw + 90°``
    (``yaw`` ``(N,)`` radians is the wall's direction): a frame proud of the wall and raised glass inside it."""
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    n = c.shape[0]
    if n == 0:
        return TriMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0))
    yw = np.broadcast_to(np.asarray(yaw, dtype=np.float64).reshape(-1), (n,))
    frame = min(0.08, 0.12 * min(width, height))
    d = min(0.06, 0.25 * min(width, height))
    glass = material_id(_GLASS) if pane is None else pane
    alu = material_id(_FRAME)
    if round_:
        normal = np.column_stack([-np.sin(yw), np.cos(yw), np.zeros(n)])
        r = width / 2.0
        return merge(
            [
                tubes(starts=c - normal * d, ends=c + normal * d, radius=r + frame, cls=cls, material=alu, segments=12),
                tubes(starts=c - normal * d, ends=c + normal * 2 * d, radius=r, cls=cls, material=glass, segments=12),
            ]
        )
    return merge(
        [
            boxes(centers=c, sizes=(width + 2 * frame, d, height + 2 * frame), cls=cls, material=alu, yaw=yw),
            boxes(centers=c, sizes=(width, 2.2 * d, height), cls=cls, material=glass, yaw=yw),
        ]
    )


def _footprint_y(beam: float, width: float, height: float) -> float:
    """The largest wall ``|y|`` at which a window of that size stays inside the beam (it stands proud of the wall)."""
    d = min(0.06, 0.25 * min(width, height))
    return beam / 2.0 - 2.0 * d - 1e-6


def _slots(length: float, pitch: float, width: float) -> np.ndarray:
    """Centres (relative to the middle) of as many ``width`` windows every ``pitch`` as fit in ``length``."""
    k = int((length - 0.6 * pitch - width) // pitch) + 1 if length > width + 0.6 * pitch else 0
    return (np.arange(k) - (k - 1) / 2.0) * pitch


def _block_windows(
    *,
    x: float,
    y: float,
    lx: float,
    ly: float,
    z0: float,
    z1: float,
    taper: float,
    spec: tuple[float, ...],
    cls: int,
    bridge: bool,
    half_length: float,
) -> TriMesh:
    """A window band round the four walls of a block (``bridge``: a continuous band of tall windows in front);
    an end wall within a window's depth of the hull's ends (``half_length``) gets none."""
    w, h, pitch = spec
    hgt = z1 - z0
    h = min(h, 0.5 * hgt)
    w = min(w, pitch)
    zc = z0 + 0.55 * hgt
    shrink = 1.0 - (1.0 - taper) * 0.55
    hx, hy = lx / 2.0 * shrink, ly / 2.0 * shrink
    centers: list[np.ndarray] = []
    yaws: list[np.ndarray] = []
    for sgn in (1.0, -1.0):
        xs = x + _slots(2 * hx, pitch, w)
        centers.append(np.column_stack([xs, np.full_like(xs, y + sgn * hy), np.full_like(xs, zc)]))
        yaws.append(np.full(xs.shape[0], 0.0 if sgn > 0 else math.pi))
        if not (bridge and sgn > 0) and abs(x + sgn * hx) + 0.2 <= half_length:
            ys = y + _slots(2 * hy, pitch, w)
            centers.append(np.column_stack([np.full_like(ys, x + sgn * hx), ys, np.full_like(ys, zc)]))
            yaws.append(np.full(ys.shape[0], -math.pi / 2.0 if sgn > 0 else math.pi / 2.0))
    out = [window_panes(centers=np.vstack(centers), yaw=np.concatenate(yaws), width=w, height=h, cls=cls)]
    if bridge and abs(x + hx) + 0.2 <= half_length:
        bp = max(0.9, 0.55 * pitch)
        ys = y + _slots(2 * hy, bp, 0.85 * bp)
        c = np.column_stack([np.full_like(ys, x + hx), ys, np.full_like(ys, z0 + 0.6 * hgt)])
        out.append(
            window_panes(
                centers=c,
                yaw=np.full(ys.shape[0], -math.pi / 2.0),
                width=0.85 * bp,
                height=min(0.45 * hgt, 1.4 * h),
                cls=cls,
            )
        )
    return merge(out)


def box_mesh(p: BoxPart, ctx: Ctx) -> TriMesh:
    """A box (frustum with ``taper``), with a window band when ``windows`` is given."""
    x, y = p.x, p.y
    lx, ly = p.size
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=x)
    ly = ctx.fit_width(p.fit, x0=x - lx / 2, x1=x + lx / 2, y=y, width=ly)
    body = block(
        x=x, y=y, lx=lx, ly=ly, z0=z0, z1=z1, cls=ctx.cls, material=ctx.mat, taper=p.taper, yaw=math.radians(p.yaw_deg)
    )
    if p.windows is None:
        return body
    if p.yaw_deg != 0.0:
        raise ctx.error("windows", "windows need an unturned box (yaw_deg 0)")
    ctx.count(2.0 * (lx + ly) / p.windows[2], key="windows", what="windows")
    win = _block_windows(
        x=x,
        y=y,
        lx=lx,
        ly=ly,
        z0=z0,
        z1=z1,
        taper=p.taper,
        spec=p.windows,
        cls=ctx.cls,
        bridge=False,
        half_length=ctx.hull.length / 2.0,
    )
    return merge([body, win])


def house_mesh(p: HousePart, ctx: Ctx) -> TriMesh:
    """Stacked tiers (window bands on each; the top tier a bridge with a front band) and bridge wings."""
    x, y = p.x, p.y
    z = ctx.base(p.base, x)
    parts: list[TriMesh] = []
    xc = lx = ly = h = 0.0
    n = len(p.tiers)
    for k, t in enumerate(p.tiers):
        lx, ly, h = t[0], t[1], t[2]
        dx = t[3] if len(t) > 3 else 0.0
        xc = x + dx + {"center": 0.0, "aft": lx / 2.0, "fore": -lx / 2.0}[p.align]
        ly = ctx.fit_width(p.fit, x0=xc - lx / 2, x1=xc + lx / 2, y=y, width=ly)
        parts.append(block(x=xc, y=y, lx=lx, ly=ly, z0=z, z1=z + h, cls=ctx.cls, material=ctx.mat, taper=p.taper))
        if p.windows is not None:
            ctx.count(4.0 * (lx + ly) / p.windows[2], key="windows", what="windows")
            parts.append(
                _block_windows(
                    x=xc,
                    y=y,
                    lx=lx,
                    ly=ly,
                    z0=z,
                    z1=z + h,
                    taper=p.taper,
                    spec=p.windows,
                    cls=ctx.cls,
                    bridge=k == n - 1,
                    half_length=ctx.hull.length / 2.0,
                )
            )
        z += h
    if p.wings is not None:
        wx, wy = p.wings
        wxc = xc + lx / 2.0 - wx / 2.0
        wy = ctx.fit_width(p.fit, x0=wxc - wx / 2, x1=wxc + wx / 2, y=y, width=wy)
        parts.append(block(x=wxc, y=y, lx=wx, ly=wy, z0=z - h, z1=z - 0.15 * h, cls=ctx.cls, material=ctx.mat))
    return merge(parts)


def windows_mesh(p: WindowsPart, ctx: Ctx) -> TriMesh:
    """Rows of windows on a wall, the deck outline or the hull side (see :class:`WindowsPart`)."""
    hull = ctx.hull
    n = ctx.count(((p.x1 - p.x0 - p.width) // p.pitch + 1) * p.rows, key="pitch", what="windows") // p.rows
    xs = p.x0 + p.width / 2.0 + np.arange(n) * p.pitch
    out: list[TriMesh] = []
    sides = {"both": (1.0, -1.0), "port": (1.0,), "starboard": (-1.0,)}[p.side]
    for r in range(p.rows):
        zc = p.z + r * p.row_pitch + p.height / 2.0
        zz = np.full_like(xs, zc)
        if p.y is not None:
            yy = np.full_like(xs, p.y)
            ang = np.zeros_like(xs)
        else:
            if p.wall == "hull":
                yy = side_half_width(hull, x=xs, z=zz) - p.inset
                ahead = side_half_width(hull, x=xs + 0.1, z=zz) - p.inset
            else:
                yy = half_widths(hull, xs) - p.inset
                ahead = half_widths(hull, xs + 0.1) - p.inset
            ang = np.arctan2(ahead - yy, 0.1)
        yy = np.minimum(yy, _footprint_y(hull.beam, p.width, p.height) - (p.width / 2.0 + 0.08) * np.abs(np.sin(ang)))
        ok = yy > p.width
        for s in sides:
            c = np.column_stack([xs[ok], s * yy[ok], zz[ok]])
            yaw = s * ang[ok] + (0.0 if s > 0 else math.pi)
            out.append(
                window_panes(
                    centers=c,
                    yaw=yaw,
                    width=p.width,
                    height=p.height,
                    cls=ctx.cls,
                    round_=p.shape == "round",
                    pane=ctx.mat,
                )
            )
    if not out or sum(m.num_triangles for m in out) == 0:
        raise ctx.error("x0", "no window fits between x0 and x1")
    return merge([m for m in out if m.num_triangles])


def funnel_mesh(p: FunnelPart, ctx: Ctx) -> TriMesh:
    """A funnel casing (elliptic or square, tapering) with a company ``band`` and a black top, and exhaust pipes."""
    x, y = p.x, p.y
    lx, ly = p.size
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=x)
    h = z1 - z0
    pipe_out = min(0.08 * h, 1.0) if p.pipes else 0.0
    zt = z1 - pipe_out
    black = material_id("funnel_black")
    levels = [z0, z0 + 0.55 * (zt - z0), z0 + 0.75 * (zt - z0), z0 + 0.88 * (zt - z0), zt]
    band = material_id(p.band) if p.band is not None else ctx.mat
    mats = [ctx.mat, band, ctx.mat, black]
    prof = [(1.0 - (1.0 - p.taper) * (z - z0) / (zt - z0), z) for z in levels]
    if p.shape == "round":
        casing = lathe(prof, cls=ctx.cls, material=np.array(mats), segments=24, scale=(lx / 2.0, ly / 2.0))
    else:
        k = math.sqrt(2.0)
        casing = lathe(
            prof,
            cls=ctx.cls,
            material=np.array(mats),
            segments=4,
            scale=(k * lx / 2.0, k * ly / 2.0),
            phase=math.pi / 4,
        )
    out = [transformed(casing, translation=(x, y, 0.0))]
    if p.pipes:
        rp = min(0.12 * min(lx, ly), 0.6)
        offs = (np.arange(p.pipes) - (p.pipes - 1) / 2.0) * min(2.4 * rp, 0.7 * lx / max(p.pipes, 1))
        starts = np.column_stack([x + offs, np.full(p.pipes, y), np.full(p.pipes, zt - 2.0 * rp)])
        ends = starts + np.array([0.0, 0.0, z1 - (zt - 2.0 * rp)])
        out.append(tubes(starts=starts, ends=ends, radius=rp, cls=ctx.cls, material=black, segments=12))
    return merge(out)


def mast_mesh(p: MastPart, ctx: Ctx) -> TriMesh:
    """A tapered tubular mast (inside the square of side ``width``) with a crosswise yard."""
    x, y, w = p.x, p.y, p.width
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=x)
    out = [
        transformed(
            lathe([(w / 2.0, z0), (0.7 * w / 2.0, z1)], cls=ctx.cls, material=ctx.mat, segments=10),
            translation=(x, y, 0.0),
        )
    ]
    if p.yard > 0:
        zy = z0 + p.yard_at * (z1 - z0)
        zy = min(max(zy, z0 + w / 2), z1 - w / 2)
        ry = 0.35 * w
        out.append(
            tubes(
                starts=np.array([[x, y - p.yard / 2.0, zy]]),
                ends=np.array([[x, y + p.yard / 2.0, zy]]),
                radius=ry,
                cls=ctx.cls,
                material=ctx.mat,
                segments=8,
            )
        )
    return merge(out)


def radar_mesh(p: RadarPart, ctx: Ctx) -> TriMesh:
    """A radar: pedestal, gearbox and an open-array antenna turned by ``yaw_deg``."""
    ln = p.length
    z = p.base
    grey = material_id("paint_grey")
    ped = transformed(
        lathe([(0.11 * ln, 0.0), (0.09 * ln, 0.2 * ln)], cls=ctx.cls, material=grey, segments=12),
        translation=(p.x, p.y, z),
    )
    gear = boxes(
        centers=[[p.x, p.y, z + 0.26 * ln]], sizes=[[0.3 * ln, 0.22 * ln, 0.12 * ln]], cls=ctx.cls, material=grey
    )
    yaw = math.radians(p.yaw_deg)
    arr = boxes(
        centers=[[p.x, p.y, z + 0.37 * ln]], sizes=[[0.1 * ln, ln, 0.1 * ln]], cls=ctx.cls, material=ctx.mat, yaw=yaw
    )
    return merge([ped, gear, arr])


def antennas_mesh(p: AntennasPart, ctx: Ctx) -> TriMesh:
    """Whip antennas on small base mounts."""
    at = np.array(p.at, dtype=np.float64)
    base = at[:, :3]
    top = base + np.column_stack([np.zeros((len(at), 2)), at[:, 3]])
    r = p.radius
    mounts = tubes(
        starts=base,
        ends=base + np.array([0.0, 0.0, 4 * r]),
        radius=2.5 * r,
        cls=ctx.cls,
        material=material_id("paint_grey"),
        segments=10,
    )
    whips = tubes(
        starts=base + np.array([0.0, 0.0, 4 * r]),
        ends=top,
        radius=r,
        end_radius=0.4 * r,
        cls=ctx.cls,
        material=ctx.mat,
        segments=6,
    )
    return merge([mounts, whips])


def _lantern(*, at: np.ndarray, size: float, lamp: int, housing: int, cls: int) -> TriMesh:
    s = size
    prof = [
        (0.45 * s, 0.0),
        (0.45 * s, 0.15 * s),
        (0.36 * s, 0.15 * s),
        (0.36 * s, 0.72 * s),
        (0.45 * s, 0.72 * s),
        (0.45 * s, 0.88 * s),
        (0.0, 0.98 * s),
    ]
    m = lathe(prof, cls=cls, material=np.array([housing, housing, lamp, housing, housing, housing]), segments=12)
    return transformed(m, translation=tuple(at))


def _lantern_post(*, top: np.ndarray, height: float, size: float, cls: int, material: int) -> TriMesh:
    """The post a lantern of ``size`` stands on: a 6-sided tube of radius ``0.1 · size`` from ``height`` below
    ``top`` (``(3,)`` float, body frame, metres: the foot of the lantern) up to ``top``."""
    return tubes(
        starts=[top - [0.0, 0.0, height]],
        ends=[top],
        radius=0.1 * size,
        cls=cls,
        material=material,
        segments=6,
    )


def nav_lights_mesh(p: NavLightsPart, ctx: Ctx) -> TriMesh:
    """COLREG lanterns: masthead white, port red (+y), starboard green (-y), stern white, with brackets; each lamp
    of the intensity Rule 22 and Annex I §8 ask of the hull's length (:func:`mmusv.world.materials.lamp_material`)."""
    hull, s = ctx.hull, p.size
    housing = ctx.mat
    steel = material_id("steel")
    screen = material_id("hull_black")
    out: list[TriMesh] = []
    masts = sorted(
        (q for q in ctx.parts if isinstance(q, MastPart)),
        key=lambda q: -ctx.zspan(base=q.base, top=q.top, height=q.height, x=q.x)[1],
    )
    if p.masthead is not None:
        heads = [np.array(v, dtype=np.float64) for v in p.masthead]
    elif masts:
        heads = []
        for q in masts[: 2 if hull.length >= 50.0 else 1]:
            z0, z1 = ctx.zspan(base=q.base, top=q.top, height=q.height, x=q.x)
            zl = z1 - 1.5 * s - max(0.0, 0.1 * (z1 - z0) if hull.length >= 50.0 else 0.0)
            heads.append(np.array([q.x + q.width / 2.0 + 0.6 * s, q.y, zl]))
            out.append(
                tubes(
                    starts=[[q.x, q.y, zl - 0.1 * s]],
                    ends=[[q.x + q.width / 2.0 + 0.6 * s, q.y, zl - 0.1 * s]],
                    radius=0.12 * s,
                    cls=ctx.cls,
                    material=steel,
                    segments=6,
                )
            )
    else:
        raise ctx.error("masthead", "the asset has no mast; give the masthead light's position [[x, y, z]]")
    length = float(hull.length)
    mast_mat = lamp_material("nav_masthead_white", length_m=length, lantern_size=s)
    for h in heads:
        out.append(_lantern(at=h, size=s, lamp=mast_mat, housing=housing, cls=ctx.cls))
    if p.sides is not None:
        sx, sy, sz = p.sides
        posts = False
    else:
        wings = [q for q in ctx.parts if isinstance(q, HousePart) and q.wings is not None]
        if wings:
            hp = wings[0]
            z = ctx.base(hp.base, hp.x)
            xc = lx = th = 0.0
            for t in hp.tiers:
                lx, th = t[0], t[2]
                xc = (
                    hp.x + (t[3] if len(t) > 3 else 0.0) + {"center": 0.0, "aft": lx / 2.0, "fore": -lx / 2.0}[hp.align]
                )
                z += th
            assert hp.wings is not None
            wx, wy = hp.wings
            wy = ctx.fit_width(hp.fit, x0=xc + lx / 2 - wx, x1=xc + lx / 2, y=hp.y, width=wy)
            sx, sy, sz = xc + lx / 2.0 - wx / 2.0, wy / 2.0 - 0.6 * s, z - 0.15 * th
            posts = False
        else:
            sx = hull.length / 2.0 - 0.22 * hull.length
            sy = max(half_width(hull, sx) - 0.15 - 0.6 * s, 0.6 * s)
            sz = float(ctx.base(None, sx)) + 0.35 * s + 0.1
            posts = True
    for sign, name in ((1.0, "nav_port_red"), (-1.0, "nav_starboard_green")):
        c = np.array([sx, sign * sy, sz])
        lamp = lamp_material(name, length_m=length, lantern_size=s)
        out.append(_lantern(at=c, size=s, lamp=lamp, housing=housing, cls=ctx.cls))
        out.append(
            boxes(
                centers=[c + np.array([0.0, -sign * 0.55 * s, 0.5 * s])],
                sizes=[[1.1 * s, 0.06 * s, 1.0 * s]],
                cls=ctx.cls,
                material=screen,
            )
        )
        if posts:
            out.append(_lantern_post(top=c, height=0.35 * s + 0.1, size=s, cls=ctx.cls, material=steel))
    if p.stern is not None:
        st = np.array(p.stern, dtype=np.float64)
    else:
        xs = -hull.length / 2.0 + 0.6 * s + 0.05
        st = np.array([xs, 0.0, ctx.base(None, xs) + 0.3 * s + 0.1])
        out.append(_lantern_post(top=st, height=0.3 * s + 0.1, size=s, cls=ctx.cls, material=steel))
    stern = lamp_material("nav_stern_white", length_m=length, lantern_size=s)
    out.append(_lantern(at=st, size=s, lamp=stern, housing=housing, cls=ctx.cls))
    return merge(out)


def crane_mesh(p: CranePart, ctx: Ctx) -> TriMesh:
    """A deck crane: pedestal, slewing deck, cab with windows, a lattice jib, hoist wire and hook block."""
    x, y, w = p.x, p.y, p.width
    z0 = ctx.base(p.base, x)
    r, ph = p.pedestal
    jl, elev, yaw = p.jib
    top = z0 + ph
    cls, mat = ctx.cls, ctx.mat
    ped = transformed(
        lathe([(1.15 * r, 0.0), (r, 0.15 * ph), (r, ph)], cls=cls, material=mat, segments=16), translation=(x, y, z0)
    )
    deck = boxes(centers=[[x, y, top + 0.1 * r]], sizes=[[2.0 * r, 2.0 * r, 0.2 * r]], cls=cls, material=mat)
    a = math.radians(yaw)
    side = np.array([-math.sin(a), math.cos(a), 0.0])
    cab_c = np.array([x, y, top + 0.2 * r + 0.6 * r]) + side * 0.45 * r
    cab = boxes(centers=[cab_c], sizes=[[1.4 * r, 0.9 * r, 1.2 * r]], cls=cls, material=mat, yaw=a)
    fwd = np.array([math.cos(a), math.sin(a), 0.0])
    win = window_panes(
        centers=np.array([cab_c + fwd * 0.7 * r]),
        yaw=np.array([a - math.pi / 2.0]),
        width=0.6 * r,
        height=0.45 * r,
        cls=cls,
    )
    e = math.radians(elev)
    d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    p0 = np.array([x, y, top + 0.6 * r])
    up = np.cross(side, d)
    nb = int(min(16, max(4, jl / (2.0 * w))))
    t = np.linspace(0.0, 1.0, nb + 1)
    rc = max(0.08 * w, 0.02)
    half_side = (w / 2.0) * (1.0 - 0.55 * t)[:, None]  # the jib narrows in plan towards its tip
    half_up = w / 2.0 - rc  # and keeps its depth, so its top stays that of a w x w box
    axis = p0 + t[:, None] * jl * d
    corners = [axis + sa * half_side * side + sb * half_up * up for sa, sb in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    chords = tubes(
        starts=np.vstack([c[:-1] for c in corners]),
        ends=np.vstack([c[1:] for c in corners]),
        radius=rc,
        cls=cls,
        material=mat,
        segments=6,
    )
    starts, ends = [], []
    for i in range(4):
        c0, c1 = corners[i], corners[(i + 1) % 4]
        starts.append(c0[:-1])
        ends.append(c1[1:])
    diag = tubes(starts=np.vstack(starts), ends=np.vstack(ends), radius=0.6 * rc, cls=cls, material=mat, segments=6)
    tip = p0 + jl * d
    drop = min(0.5 * jl * math.sin(e) + 0.2 * ph, tip[2] - top)
    wire = tubes(
        starts=[tip],
        ends=[tip - [0.0, 0.0, drop]],
        radius=max(0.015, 0.03 * w),
        cls=cls,
        material=material_id("steel"),
        segments=6,
    )
    hook = boxes(
        centers=[tip - [0.0, 0.0, drop + 0.2 * w]],
        sizes=[[0.5 * w, 0.5 * w, 0.4 * w]],
        cls=cls,
        material=material_id("paint_yellow"),
    )
    return merge([ped, deck, cab, win, chords, diag, wire, hook])


def dome_mesh(p: DomePart, ctx: Ctx) -> TriMesh:
    """A sphere cap of ``radius`` with its top at ``top``, on a skirt down to ``base``."""
    r, top = p.radius, p.top
    z0 = ctx.base(p.base, p.x)
    c = top - r
    if z0 >= top:
        raise ctx.error("top", f"top {top:g} m must be above the base {z0:g} m")
    theta0 = math.asin(min(max((z0 - c) / r, 0.0), 1.0))
    prof: list[tuple[float, float]] = [] if z0 >= c else [(r, z0)]
    for th in np.linspace(theta0, math.pi / 2.0, 9):
        prof.append((0.0 if th >= math.pi / 2.0 - 1e-12 else r * math.cos(th), c + r * math.sin(th)))
    prof[0] = (prof[0][0], max(prof[0][1], z0))
    return transformed(
        lathe(prof, cls=ctx.cls, material=ctx.mat, segments=max(p.segments, 24)), translation=(p.x, p.y, 0.0)
    )
