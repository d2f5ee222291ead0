"""Procedural vessel meshes: a lofted hull plus superstructure parts, from a validated asset spec.

The vocabulary (hull keys, part types and what each key means) is the schema in :mod:`mmusv.world.asset_spec`;
this module turns a :class:`~mmusv.world.asset_spec.HullSpec` and its parts into one closed, outward-facing
triangle mesh in the vessel body frame (x forward, bow at +x; y left; z up; z = 0 at the waterline; metres). The
hull spans exactly ``x in [-length/2, length/2]``, ``y in [-beam/2, beam/2]`` and reaches down to ``z = -draft``;
no part may stick out of that x/y footprint (checked), so the body-frame origin stays the waterline centre of the
bounding box. Checks that need the hull's shape (a part's base on the deck, ``fit``, the footprint, a
``hull_block`` on a twin hull) are made here and raise :class:`~mmusv.world.asset_spec.AssetSpecError` with the
part's path. All parts are labelled with the vessel's semantic class; parts may overlap (the union is what
sensors see).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np

from mmusv.world.asset_spec import AssetSpecError, HullSpec
from mmusv.world.part_spec import (
    BoxPart,
    CranePart,
    CylinderPart,
    DomePart,
    FunnelPart,
    GantryPart,
    GunPart,
    HcylinderPart,
    HousePart,
    HullBlockPart,
    MastPart,
    PartSpec,
    PlatePart,
    RowPart,
    StrutPart,
    profile_area,
)
from mmusv.world.primitives import TriMesh, box, merge, prism, transformed

__all__ = ["build_procedural", "deck_z", "half_width", "hull_mesh", "profile", "stations"]


def profile(hull: HullSpec, u: np.ndarray) -> np.ndarray:
    """Relative half-width ``(N,)`` in ``[0, 1]`` at stations ``u`` ``(N,)`` (0 = transom, 1 = stem)."""
    u = np.asarray(u, dtype=np.float64)
    w = np.ones_like(u)
    if hull.stern > 0:
        m = u < hull.stern
        t = u[m] / hull.stern
        transom = hull.transom_width
        w[m] = transom + (1.0 - transom) * (1.0 - (1.0 - t) ** 2)
    if hull.bow > 0:
        ub = 1.0 - hull.bow
        m = u > ub
        t = np.clip((u[m] - ub) / hull.bow, 0.0, 1.0)
        p, stem = hull.bow_power, hull.stem_width
        if hull.bow_shape == "round":
            w[m] = stem + (1.0 - stem) * (1.0 - t**p) ** (1.0 / p)
        else:
            w[m] = 1.0 - (1.0 - stem) * t**p
    return w


def stations(hull: HullSpec) -> np.ndarray:
    """Sorted station parameters ``(N,)`` used for lofting, denser where the outline curves."""
    us = [0.0, 1.0]
    if hull.stern > 0:
        us += [hull.stern / 3.0, 2.0 * hull.stern / 3.0, hull.stern]
    if hull.bow > 0:
        s = np.linspace(0.0, 1.0, 9)
        us += list(1.0 - hull.bow + hull.bow * np.sin(s * np.pi / 2.0))
    return np.unique(np.round(np.clip(us, 0.0, 1.0), 12))


def deck_z(hull: HullSpec, x: float) -> float:
    """Deck height above the waterline at body-frame ``x`` (metres), including sheer."""
    t = min(max(x / (hull.length / 2.0), 0.0), 1.0)
    return hull.freeboard + hull.sheer * t * t


def half_width(hull: HullSpec, x: float) -> float:
    """Outer half-width of the deck outline at body-frame ``x`` (metres; 0 beyond the ends)."""
    if abs(x) > hull.length / 2.0 + 1e-9:
        return 0.0
    w = float(profile(hull, np.array([(x + hull.length / 2.0) / hull.length]))[0])
    if hull.type == "twin":
        return (hull.beam - hull.demi_width) / 2.0 + hull.demi_width / 2.0 * w
    return hull.beam / 2.0 * w


def hull_mesh(hull: HullSpec, cls: int) -> TriMesh:
    """The closed hull mesh (one lofted body, or two demihulls), labelled ``cls``."""
    if hull.type == "twin":
        off = (hull.beam - hull.demi_width) / 2.0
        return merge(
            [
                _loft(hull, y0=-off, half=hull.demi_width / 2.0, cls=cls),
                _loft(hull, y0=off, half=hull.demi_width / 2.0, cls=cls),
            ]
        )
    return _loft(hull, y0=0.0, half=hull.beam / 2.0, cls=cls)


def _loft(hull: HullSpec, *, y0: float, half: float, cls: int) -> TriMesh:
    u = stations(hull)
    n = u.shape[0]
    w = profile(hull, u)
    tip = bool(w[-1] < 1e-9)
    length, draft = hull.length, hull.draft
    levels = [
        (-draft, hull.bottom),
        (-0.5 * draft, hull.bottom + 0.9 * (hull.flare - hull.bottom)),
        (0.0, hull.flare),
        (hull.freeboard, 1.0),
    ]
    rings = []
    for k, (z, scale) in enumerate(levels):
        s = (z + draft) / hull.depth
        x_bow = length / 2.0 - hull.rake * length * (1.0 - s)
        x_stern = -length / 2.0 + hull.overhang * length * (1.0 - s)
        if k == 3:
            x_bow, x_stern = length / 2.0, -length / 2.0
        x = x_stern + u * (x_bow - x_stern)
        hw = half * scale * w
        zz = np.array([deck_z(hull, float(xi)) for xi in x]) if k == 3 else np.full(n, z)
        stb = np.column_stack([x, y0 - hw, zz])
        port = np.column_stack([x, y0 + hw, zz])[::-1]
        rings.append(np.vstack([stb, port[1:] if tip else port]))
    m = rings[0].shape[0]
    a = np.arange(m)
    b = (a + 1) % m
    faces = []
    for k in range(3):
        lo, hi = k * m, (k + 1) * m
        faces.append(np.column_stack([lo + a, lo + b, hi + b]))
        faces.append(np.column_stack([lo + a, hi + b, hi + a]))
    cap = _strip_cap(n, tip)
    faces.append(cap[:, ::-1])
    faces.append(cap + 3 * m)
    return TriMesh(np.vstack(rings), np.vstack(faces), np.array([cls]))


def _strip_cap(n: int, tip: bool) -> np.ndarray:
    """Top-facing triangles ``(F, 3)`` closing a hull ring of ``n`` stations (ring = starboard fwd, port aft)."""
    s = np.arange(n)
    p = (2 * n - 2 - s) if tip else (2 * n - 1 - s)
    if tip:
        p[n - 1] = n - 1
    tris = []
    for i in range(n - 1):
        for t in ((s[i], s[i + 1], p[i + 1]), (s[i], p[i + 1], p[i])):
            if len({int(t[0]), int(t[1]), int(t[2])}) == 3:
                tris.append(t)
    return np.array(tris, dtype=np.int64)


# ---------------------------------------------------------------------------------------------- part helpers


def _block(
    *, x: float, y: float, lx: float, ly: float, z0: float, z1: float, cls: int, taper: float = 1.0, yaw: float = 0.0
) -> TriMesh:
    if taper == 1.0:
        return box(center=(x, y, (z0 + z1) / 2.0), size=(lx, ly, z1 - z0), cls=cls, yaw=yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([[-lx, -ly], [lx, -ly], [lx, ly], [-lx, ly]]) / 2.0
    outline = local @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    return prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=taper)


def _strut(p0: np.ndarray, p1: np.ndarray, *, width: float, thickness: float, cls: int) -> TriMesh:
    d = p1 - p0
    n = float(np.linalg.norm(d))
    e1 = d / n
    ref = np.array([0.0, 0.0, 1.0]) if abs(e1[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    e2 = np.cross(ref, e1)
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(e1, e2)
    b = box(center=(0.0, 0.0, 0.0), size=(n, width, thickness), cls=cls)
    return transformed(b, rotation=np.column_stack([e1, e2, e3]), translation=(p0 + p1) / 2.0)


def _lathe(profile: Sequence[tuple[float, float]], *, cx: float, cy: float, segments: int, cls: int) -> TriMesh:
    """Closed surface of revolution about a vertical axis; ``profile`` is ``(r, z)`` bottom to top, r=0 = pole."""
    ang = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ca, sa = np.cos(ang), np.sin(ang)
    verts: list[np.ndarray] = []
    starts: list[tuple[int, bool]] = []
    count = 0
    for r, z in profile:
        if r <= 0.0:
            verts.append(np.array([[cx, cy, z]]))
            starts.append((count, True))
            count += 1
        else:
            verts.append(np.column_stack([cx + r * ca, cy + r * sa, np.full(segments, z)]))
            starts.append((count, False))
            count += segments
    i = np.arange(segments)
    j = (i + 1) % segments
    faces: list[np.ndarray] = []
    (s0, pole0), (s1, pole1) = starts[0], starts[-1]
    if not pole0:
        verts.append(np.array([[cx, cy, profile[0][1]]]))
        faces.append(np.column_stack([np.full(segments, count), s0 + j, s0 + i]))
        count += 1
    if not pole1:
        verts.append(np.array([[cx, cy, profile[-1][1]]]))
        faces.append(np.column_stack([np.full(segments, count), s1 + i, s1 + j]))
        count += 1
    for (lo, lo_pole), (hi, hi_pole) in itertools.pairwise(starts):
        if lo_pole:
            faces.append(np.column_stack([np.full(segments, lo), hi + j, hi + i]))
        elif hi_pole:
            faces.append(np.column_stack([lo + i, lo + j, np.full(segments, hi)]))
        else:
            faces.append(np.column_stack([lo + i, lo + j, hi + j]))
            faces.append(np.column_stack([lo + i, hi + j, hi + i]))
    return TriMesh(np.vstack(verts), np.vstack(faces), np.array([cls]))


_ROT_X90 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # (x, y, z) -> (x, -z, y)
_ROT_Y90 = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # (x, y, z) -> (z, y, -x)


def _base(base: float | None, hull: HullSpec, x: float) -> float:
    """``base``, or the deck height at ``x`` when it is not given (metres)."""
    return deck_z(hull, x) if base is None else base


def _zspan(
    p: BoxPart | HullBlockPart | FunnelPart | MastPart | CylinderPart | GantryPart, hull: HullSpec, x: float, where: str
) -> tuple[float, float]:
    z0 = _base(p.base, hull, x)
    z1 = p.top if p.top is not None else z0 + (p.height or 0.0)
    if z1 <= z0:
        raise AssetSpecError(f"{where}.top", f"top {z1:g} m must be above the base {z0:g} m")
    return z0, z1


def _fit_width(fit: float | None, hull: HullSpec, *, x0: float, x1: float, y: float, width: float, where: str) -> float:
    """``width`` narrowed (when ``fit`` is given) to stay ``fit`` metres inside the deck outline."""
    if fit is None:
        return width
    room = min(half_width(hull, x0), half_width(hull, x1)) - fit - abs(y)
    if room <= 0.0:
        raise AssetSpecError(f"{where}.fit", f"no room inside the deck outline between x={x0:g} and x={x1:g}")
    return min(width, 2.0 * room)


def _box(p: BoxPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x, y = p.x, p.y
    lx, ly = p.size
    z0, z1 = _zspan(p, hull, x, where)
    ly = _fit_width(p.fit, hull, x0=x - lx / 2, x1=x + lx / 2, y=y, width=ly, where=where)
    return _block(x=x, y=y, lx=lx, ly=ly, z0=z0, z1=z1, cls=cls, taper=p.taper, yaw=math.radians(p.yaw_deg))


def _house(p: HousePart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x, y = p.x, p.y
    z = _base(p.base, hull, x)
    parts: list[TriMesh] = []
    xc = lx = ly = h = 0.0
    for t in p.tiers:
        lx, ly, h = t[0], t[1], t[2]
        dx = t[3] if len(t) > 3 else 0.0
        xc = x + dx + {"center": 0.0, "aft": lx / 2.0, "fore": -lx / 2.0}[p.align]
        ly = _fit_width(p.fit, hull, x0=xc - lx / 2, x1=xc + lx / 2, y=y, width=ly, where=where)
        parts.append(_block(x=xc, y=y, lx=lx, ly=ly, z0=z, z1=z + h, cls=cls, taper=p.taper))
        z += h
    if p.wings is not None:
        wx, wy = p.wings
        wxc = xc + lx / 2.0 - wx / 2.0
        wy = _fit_width(p.fit, hull, x0=wxc - wx / 2, x1=wxc + wx / 2, y=y, width=wy, where=where)
        parts.append(_block(x=wxc, y=y, lx=wx, ly=wy, z0=z - h, z1=z - 0.15 * h, cls=cls))
    return merge(parts)


def _hull_block(p: HullBlockPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    if hull.type != "mono":
        raise AssetSpecError(f"{where}.type", "hull_block needs a mono hull")
    half_l = hull.length / 2.0
    x0, x1 = p.x0, p.x1
    if not -half_l <= x0 <= half_l:
        raise AssetSpecError(f"{where}.x0", f"must be within the hull, [{-half_l:g}, {half_l:g}] m; got {x0}")
    if x1 > half_l:
        raise AssetSpecError(f"{where}.x1", f"must be <= {half_l:g} m (the stem), got {x1}")
    z0, z1 = _zspan(p, hull, (x0 + x1) / 2.0, where)
    u0, u1 = (x0 + half_l) / hull.length, (x1 + half_l) / hull.length
    st = stations(hull)
    u = np.unique(np.concatenate([[u0, u1], st[(st > u0 + 1e-9) & (st < u1 - 1e-9)]]))
    hw = hull.beam / 2.0 * profile(hull, u) - p.inset
    if float(hw.min()) < 0.01:
        raise AssetSpecError(f"{where}.x1", "block reaches where the deck is narrower than twice the inset")
    xs = -half_l + u * hull.length
    outline = np.vstack([np.column_stack([xs, -hw]), np.column_stack([xs, hw])[::-1]])
    return prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=p.taper)


def _row(p: RowPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x0, count, gap, y = p.x0, p.count, p.gap, p.y
    lx = (p.x1 - x0 - gap * (count - 1)) / count
    parts = []
    for i in range(count):
        a = x0 + i * (lx + gap)
        xc = a + lx / 2.0
        w = _fit_width(p.fit, hull, x0=a, x1=a + lx, y=y, width=p.width, where=where)
        z0 = _base(p.base, hull, xc)
        h = p.heights[i % len(p.heights)]
        parts.append(_block(x=xc, y=y, lx=lx, ly=w, z0=z0, z1=z0 + h, cls=cls))
    return merge(parts)


def _funnel(p: FunnelPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x, y = p.x, p.y
    lx, ly = p.size
    z0, z1 = _zspan(p, hull, x, where)
    if p.shape == "box":
        return _block(x=x, y=y, lx=lx, ly=ly, z0=z0, z1=z1, cls=cls, taper=p.taper)
    a = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    outline = np.column_stack([x + lx / 2.0 * np.cos(a), y + ly / 2.0 * np.sin(a)])
    return prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=p.taper)


def _mast(p: MastPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x, y, w = p.x, p.y, p.width
    z0, z1 = _zspan(p, hull, x, where)
    parts = [_block(x=x, y=y, lx=w, ly=w, z0=z0, z1=z1, cls=cls)]
    if p.yard > 0:
        zy = z0 + p.yard_at * (z1 - z0)
        zy = min(max(zy, z0 + w / 2), z1 - w / 2)
        parts.append(_block(x=x, y=y, lx=w, ly=p.yard, z0=zy - w / 2, z1=zy + w / 2, cls=cls))
    return merge(parts)


def _cylinder(p: CylinderPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    r, rt = p.radius, p.top_radius
    z0, z1 = _zspan(p, hull, p.x, where)
    return _lathe([(r, z0), (r if rt is None else rt, z1)], cx=p.x, cy=p.y, segments=p.segments, cls=cls)


def _hcylinder(p: HcylinderPart, cls: int) -> TriMesh:
    m = _lathe([(p.radius, p.x0), (p.radius, p.x1)], cx=0.0, cy=0.0, segments=p.segments, cls=cls)
    return transformed(m, rotation=_ROT_Y90, translation=(0.0, p.y, p.z))


def _dome(p: DomePart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    r, top = p.radius, p.top
    z0 = _base(p.base, hull, p.x)
    c = top - r
    if z0 >= top:
        raise AssetSpecError(f"{where}.top", f"top {top:g} m must be above the base {z0:g} m")
    theta0 = math.asin(min(max((z0 - c) / r, 0.0), 1.0))
    profile: list[tuple[float, float]] = [] if z0 >= c else [(r, z0)]
    for th in np.linspace(theta0, math.pi / 2.0, 5):
        profile.append((0.0 if th >= math.pi / 2.0 - 1e-12 else r * math.cos(th), c + r * math.sin(th)))
    profile[0] = (profile[0][0], max(profile[0][1], z0))
    return _lathe(profile, cx=p.x, cy=p.y, segments=p.segments, cls=cls)


def _strut_part(p: StrutPart, cls: int) -> TriMesh:
    w = p.width
    t = w if p.thickness is None else p.thickness
    return _strut(np.array(p.start), np.array(p.end), width=w, thickness=t, cls=cls)


def _plate(p: PlatePart, cls: int) -> TriMesh:
    pts = np.array(p.points)
    if profile_area(pts) < 0:
        pts = pts[::-1]
    m = prism(outline=pts, z0=-p.thickness / 2.0, z1=p.thickness / 2.0, cls=cls)
    return transformed(m, rotation=_ROT_X90, translation=(0.0, p.y, 0.0))


def _gantry(p: GantryPart, hull: HullSpec, cls: int, where: str) -> TriMesh:
    x, span, leg, lean = p.x, p.span, p.leg, p.lean
    z0, z1 = _zspan(p, hull, x, where)
    parts = []
    for side in (-1.0, 1.0):
        yy = side * span / 2.0
        parts.append(
            _strut(np.array([x, yy, z0]), np.array([x + lean, yy, z1 - leg / 2.0]), width=leg, thickness=leg, cls=cls)
        )
    parts.append(_block(x=x + lean, y=0.0, lx=leg, ly=span + leg, z0=z1 - leg, z1=z1, cls=cls))
    return merge(parts)


def _crane(p: CranePart, hull: HullSpec, cls: int) -> TriMesh:
    x, y, w = p.x, p.y, p.width
    z0 = _base(p.base, hull, x)
    r, ph = p.pedestal
    jl, elev, yaw = p.jib
    top = z0 + ph
    cab = _block(x=x, y=y, lx=1.6 * r, ly=1.6 * r, z0=top, z1=top + 1.2 * r, cls=cls)
    e, a = math.radians(elev), math.radians(yaw)
    p0 = np.array([x, y, top + 0.6 * r])
    p1 = p0 + jl * np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    return merge(
        [
            _lathe([(r, z0), (r, top)], cx=x, cy=y, segments=10, cls=cls),
            cab,
            _strut(p0, p1, width=w, thickness=w, cls=cls),
        ]
    )


def _gun(p: GunPart, hull: HullSpec, cls: int) -> TriMesh:
    x, y, r, h = p.x, p.y, p.radius, p.height
    z0 = _base(p.base, hull, x)
    a, e = math.radians(p.yaw_deg), math.radians(p.elevation_deg)
    d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    p0 = np.array([x, y, z0 + 0.55 * h])
    turret = _lathe([(r, z0), (0.75 * r, z0 + h)], cx=x, cy=y, segments=10, cls=cls)
    barrel = p.barrel
    return merge(
        [
            turret,
            _strut(p0 + 0.5 * r * d, p0 + (r + barrel) * d, width=0.12 * r + 0.05, thickness=0.12 * r + 0.05, cls=cls),
        ]
    )


def _part_mesh(p: PartSpec, hull: HullSpec, cls: int, where: str) -> TriMesh:
    """The mesh of one part; ``where`` is its path for errors (``tug_32m.parts[3]``)."""
    match p:
        case BoxPart():
            return _box(p, hull, cls, where)
        case HousePart():
            return _house(p, hull, cls, where)
        case HullBlockPart():
            return _hull_block(p, hull, cls, where)
        case RowPart():
            return _row(p, hull, cls, where)
        case FunnelPart():
            return _funnel(p, hull, cls, where)
        case MastPart():
            return _mast(p, hull, cls, where)
        case CylinderPart():
            return _cylinder(p, hull, cls, where)
        case HcylinderPart():
            return _hcylinder(p, cls)
        case DomePart():
            return _dome(p, hull, cls, where)
        case StrutPart():
            return _strut_part(p, cls)
        case PlatePart():
            return _plate(p, cls)
        case GantryPart():
            return _gantry(p, hull, cls, where)
        case CranePart():
            return _crane(p, hull, cls)
        case GunPart():
            return _gun(p, hull, cls)


def build_procedural(*, hull: HullSpec, parts: Sequence[PartSpec], path: str, cls: int) -> TriMesh:
    """Builds a vessel mesh from a validated ``hull`` and ``parts`` (:mod:`mmusv.world.asset_spec`), labelled ``cls``.

    Returns a :class:`TriMesh` in the body frame whose x/y bounding box is exactly the hull's
    (``[-length/2, length/2] x [-beam/2, beam/2]``). Raises :class:`AssetSpecError` naming the offending
    key (``<path>.parts[3].top``, ...) where a part does not fit the hull or leaves its footprint.
    """
    meshes = [hull_mesh(hull, cls)]
    lim = np.array([hull.length / 2.0, hull.beam / 2.0])
    tol = 1e-9 * max(1.0, hull.length)
    for i, part in enumerate(parts):
        where = f"{path}.parts[{i}]" if path else f"parts[{i}]"
        m = _part_mesh(part, hull, cls, where)
        if not np.all(np.isfinite(m.vertices)):
            raise AssetSpecError(where, f"{part.type} produced non-finite vertices")
        b = m.bounds
        if np.any(b[0, :2] < -lim - tol) or np.any(b[1, :2] > lim + tol):
            raise AssetSpecError(
                where,
                f"{part.type} spans x [{b[0, 0]:.3f}, {b[1, 0]:.3f}] y [{b[0, 1]:.3f}, {b[1, 1]:.3f}] m, outside the "
                f"hull footprint x [{-lim[0]:g}, {lim[0]:g}] y [{-lim[1]:g}, {lim[1]:g}] m",
            )
        meshes.append(m)
    return merge(meshes)
