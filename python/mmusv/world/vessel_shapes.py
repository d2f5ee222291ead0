"""Procedural vessel meshes: a lofted hull plus superstructure parts, from a validated asset spec.

The vocabulary (hull keys, part types and what each key means) is the schema in :mod:`mmusv.world.asset_spec`;
this module turns a :class:`~mmusv.world.asset_spec.HullSpec` and its parts into one triangle mesh of closed,
outward-facing pieces in the vessel body frame (x forward, bow at +x; y left; z up; z = 0 at the waterline;
metres). The hull (:mod:`mmusv.world.hull_form`) spans exactly ``x in [-length/2, length/2]``,
``y in [-beam/2, beam/2]`` and reaches down to ``z = -draft``; no part may stick out of that x/y footprint
(checked), so the body-frame origin stays the waterline centre of the bounding box. Checks that need the hull's
shape (a part's base on the deck, ``fit``, the footprint, a ``hull_block`` on a twin hull) are made here and raise
:class:`~mmusv.world.asset_spec.AssetSpecError` with the part's path. All parts are labelled with the vessel's
semantic class and carry materials (:mod:`mmusv.world.materials`: the part's ``material`` or its type's default,
:data:`~mmusv.world.part_spec.DEFAULT_MATERIALS`); parts may overlap (the union is what sensors see). The part
families live in :mod:`mmusv.world.parts_super` (superstructure) and :mod:`mmusv.world.parts_deck` (deck gear).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mmusv.world.asset_spec import DIMENSION_RANGES, AssetSpecError, HullSpec
from mmusv.world.hull_form import deck_z, half_width, hull_mesh, profile, stations
from mmusv.world.part_context import Ctx, block, material_of
from mmusv.world.part_spec import (
    AntennasPart,
    BollardsPart,
    BoxPart,
    ContainersPart,
    CranePart,
    CylinderPart,
    DomePart,
    FendersPart,
    FunnelPart,
    GantryPart,
    GunPart,
    HatchesPart,
    HcylinderPart,
    HousePart,
    HullBlockPart,
    LifeboatsPart,
    MastPart,
    NavLightsPart,
    PartSpec,
    PipesPart,
    PlatePart,
    RadarPart,
    RailingPart,
    RowPart,
    StrutPart,
    TubePart,
    WinchPart,
    WindowsPart,
    profile_area,
)
from mmusv.world.parts_deck import (
    bollards_mesh,
    containers_mesh,
    fenders_mesh,
    hatches_mesh,
    lifeboats_mesh,
    pipes_mesh,
    railing_mesh,
    tube_mesh,
    winch_mesh,
)
from mmusv.world.parts_super import (
    antennas_mesh,
    box_mesh,
    crane_mesh,
    dome_mesh,
    funnel_mesh,
    house_mesh,
    mast_mesh,
    nav_lights_mesh,
    radar_mesh,
    windows_mesh,
)
from mmusv.world.primitives import TriMesh, box, lathe, merge, prism, transformed, tubes

__all__ = ["build_parts", "build_procedural", "deck_z", "half_width", "hull_mesh", "profile", "stations"]


_ROT_X90 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # (x, y, z) -> (x, -z, y)
_ROT_Y90 = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # (x, y, z) -> (z, y, -x)


def _strut(p0: np.ndarray, p1: np.ndarray, *, width: float, thickness: float, cls: int, material: int) -> TriMesh:
    d = p1 - p0
    n = float(np.linalg.norm(d))
    e1 = d / n
    ref = np.array([0.0, 0.0, 1.0]) if abs(e1[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    e2 = np.cross(ref, e1)
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(e1, e2)
    b = box(center=(0.0, 0.0, 0.0), size=(n, width, thickness), cls=cls)
    b = TriMesh(b.vertices, b.faces, b.classes, np.array([material]))
    return transformed(b, rotation=np.column_stack([e1, e2, e3]), translation=(p0 + p1) / 2.0)


def _hull_block(p: HullBlockPart, ctx: Ctx) -> TriMesh:
    hull = ctx.hull
    if hull.type != "mono":
        raise ctx.error("type", "hull_block needs a mono hull")
    half_l = hull.length / 2.0
    x0, x1 = p.x0, p.x1
    if not -half_l <= x0 <= half_l:
        raise ctx.error("x0", f"must be within the hull, [{-half_l:g}, {half_l:g}] m; got {x0}")
    if x1 > half_l:
        raise ctx.error("x1", f"must be <= {half_l:g} m (the stem), got {x1}")
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=(x0 + x1) / 2.0)
    u0, u1 = (x0 + half_l) / hull.length, (x1 + half_l) / hull.length
    st = stations(hull)
    u = np.unique(np.concatenate([[u0, u1], st[(st > u0 + 1e-9) & (st < u1 - 1e-9)]]))
    hw = hull.beam / 2.0 * profile(hull, u) - p.inset
    if float(hw.min()) < 0.01:
        raise ctx.error("x1", "block reaches where the deck is narrower than twice the inset")
    xs = -half_l + u * hull.length
    outline = np.vstack([np.column_stack([xs, -hw]), np.column_stack([xs, hw])[::-1]])
    m = prism(outline=outline, z0=z0, z1=z1, cls=ctx.cls, top_scale=p.taper)
    return TriMesh(m.vertices, m.faces, m.classes, np.array([ctx.mat]))


def _row(p: RowPart, ctx: Ctx) -> TriMesh:
    x0, count, gap, y = p.x0, p.count, p.gap, p.y
    lx = (p.x1 - x0 - gap * (count - 1)) / count
    parts = []
    for i in range(count):
        a = x0 + i * (lx + gap)
        xc = a + lx / 2.0
        w = ctx.fit_width(p.fit, x0=a, x1=a + lx, y=y, width=p.width)
        z0 = ctx.base(p.base, xc)
        h = p.heights[i % len(p.heights)]
        parts.append(block(x=xc, y=y, lx=lx, ly=w, z0=z0, z1=z0 + h, cls=ctx.cls, material=ctx.mat))
    return merge(parts)


def _cylinder(p: CylinderPart, ctx: Ctx) -> TriMesh:
    r, rt = p.radius, p.top_radius
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=p.x)
    m = lathe([(r, z0), (r if rt is None else rt, z1)], cls=ctx.cls, material=ctx.mat, segments=p.segments)
    return transformed(m, translation=(p.x, p.y, 0.0))


def _hcylinder(p: HcylinderPart, ctx: Ctx) -> TriMesh:
    m = lathe([(p.radius, p.x0), (p.radius, p.x1)], cls=ctx.cls, material=ctx.mat, segments=p.segments)
    return transformed(m, rotation=_ROT_Y90, translation=(0.0, p.y, p.z))


def _strut_part(p: StrutPart, ctx: Ctx) -> TriMesh:
    w = p.width
    t = w if p.thickness is None else p.thickness
    return _strut(np.array(p.start), np.array(p.end), width=w, thickness=t, cls=ctx.cls, material=ctx.mat)


def _plate(p: PlatePart, ctx: Ctx) -> TriMesh:
    pts = np.array(p.points)
    if profile_area(pts) < 0:
        pts = pts[::-1]
    m = prism(outline=pts, z0=-p.thickness / 2.0, z1=p.thickness / 2.0, cls=ctx.cls)
    m = TriMesh(m.vertices, m.faces, m.classes, np.array([ctx.mat]))
    return transformed(m, rotation=_ROT_X90, translation=(0.0, p.y, 0.0))


def _gantry(p: GantryPart, ctx: Ctx) -> TriMesh:
    x, span, leg, lean = p.x, p.span, p.leg, p.lean
    z0, z1 = ctx.zspan(base=p.base, top=p.top, height=p.height, x=x)
    cls, mat = ctx.cls, ctx.mat
    parts = []
    for side in (-1.0, 1.0):
        yy = side * span / 2.0
        parts.append(
            _strut(
                np.array([x, yy, z0]),
                np.array([x + lean, yy, z1 - leg / 2.0]),
                width=leg,
                thickness=leg,
                cls=cls,
                material=mat,
            )
        )
    parts.append(block(x=x + lean, y=0.0, lx=leg, ly=span + leg, z0=z1 - leg, z1=z1, cls=cls, material=mat))
    sheave = np.array([[x + lean, -0.25 * span, z1 - leg - 0.4 * leg], [x + lean, 0.25 * span, z1 - leg - 0.4 * leg]])
    parts.append(
        tubes(
            starts=sheave - np.array([0.0, 0.15 * leg, 0.0]),
            ends=sheave + np.array([0.0, 0.15 * leg, 0.0]),
            radius=0.4 * leg,
            cls=cls,
            material=mat,
            segments=12,
        )
    )
    return merge(parts)


def _gun(p: GunPart, ctx: Ctx) -> TriMesh:
    x, y, r, h = p.x, p.y, p.radius, p.height
    z0 = ctx.base(p.base, x)
    a, e = math.radians(p.yaw_deg), math.radians(p.elevation_deg)
    d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    p0 = np.array([x, y, z0 + 0.55 * h])
    turret = lathe([(r, 0.0), (0.97 * r, 0.5 * h), (0.75 * r, h)], cls=ctx.cls, material=ctx.mat, segments=20)
    bw = 0.06 * r + 0.025
    barrel = tubes(
        starts=[p0 + 0.5 * r * d],
        ends=[p0 + (r + p.barrel) * d],
        radius=bw,
        end_radius=0.8 * bw,
        cls=ctx.cls,
        material=ctx.mat,
        segments=12,
    )
    return merge([transformed(turret, translation=(x, y, z0)), barrel])


def _part_mesh(p: PartSpec, ctx: Ctx) -> TriMesh:
    """The mesh of one part."""
    match p:
        case BoxPart():
            return box_mesh(p, ctx)
        case HousePart():
            return house_mesh(p, ctx)
        case HullBlockPart():
            return _hull_block(p, ctx)
        case RowPart():
            return _row(p, ctx)
        case FunnelPart():
            return funnel_mesh(p, ctx)
        case MastPart():
            return mast_mesh(p, ctx)
        case CylinderPart():
            return _cylinder(p, ctx)
        case HcylinderPart():
            return _hcylinder(p, ctx)
        case DomePart():
            return dome_mesh(p, ctx)
        case StrutPart():
            return _strut_part(p, ctx)
        case PlatePart():
            return _plate(p, ctx)
        case GantryPart():
            return _gantry(p, ctx)
        case CranePart():
            return crane_mesh(p, ctx)
        case GunPart():
            return _gun(p, ctx)
        case RailingPart():
            return railing_mesh(p, ctx)
        case WindowsPart():
            return windows_mesh(p, ctx)
        case ContainersPart():
            return containers_mesh(p, ctx)
        case HatchesPart():
            return hatches_mesh(p, ctx)
        case LifeboatsPart():
            return lifeboats_mesh(p, ctx)
        case FendersPart():
            return fenders_mesh(p, ctx)
        case NavLightsPart():
            return nav_lights_mesh(p, ctx)
        case RadarPart():
            return radar_mesh(p, ctx)
        case AntennasPart():
            return antennas_mesh(p, ctx)
        case BollardsPart():
            return bollards_mesh(p, ctx)
        case TubePart():
            return tube_mesh(p, ctx)
        case PipesPart():
            return pipes_mesh(p, ctx)
        case WinchPart():
            return winch_mesh(p, ctx)


def build_procedural(*, hull: HullSpec, parts: Sequence[PartSpec], path: str, cls: int) -> TriMesh:
    """Builds a vessel mesh from a validated ``hull`` and ``parts`` (:mod:`mmusv.world.asset_spec`), labelled ``cls``.

    Returns a :class:`TriMesh` in the body frame whose x/y bounding box is exactly the hull's
    (``[-length/2, length/2] x [-beam/2, beam/2]``), materials per face. Raises :class:`AssetSpecError` naming the
    offending key (``<path>.parts[3].top``, ...) where a part does not fit the hull or leaves its footprint.
    """
    return build_parts(hull=hull, parts=parts, path=path, cls=cls)[0]


def build_parts(*, hull: HullSpec, parts: Sequence[PartSpec], path: str, cls: int) -> tuple[TriMesh, np.ndarray]:
    """:func:`build_procedural`'s mesh and ``(F,)`` int32, the part each face comes from (-1 = the hull)."""
    meshes = [hull_mesh(hull, cls)]
    lim = np.array([hull.length / 2.0, hull.beam / 2.0])
    tol = 1e-9 * max(1.0, hull.length)
    max_height = DIMENSION_RANGES["height"][1]
    z_lo, z_hi = (float(z) for z in meshes[0].bounds[:, 2])
    if z_hi - z_lo > max_height:
        raise AssetSpecError(
            f"{path}.hull" if path else "hull",
            f"spans z [{z_lo:.6g}, {z_hi:.6g}] m (keel to deck at the stem, with sheer): {z_hi - z_lo:.6g} m is more "
            f"than the largest asset height, {max_height:g} m",
        )
    all_parts = tuple(parts)
    for i, part in enumerate(parts):
        where = f"{path}.parts[{i}]" if path else f"parts[{i}]"
        ctx = Ctx(hull=hull, cls=cls, where=where, mat=material_of(part, hull), parts=all_parts)
        m = _part_mesh(part, ctx)
        if not np.all(np.isfinite(m.vertices)):
            raise AssetSpecError(where, f"{part.type} produced non-finite vertices")
        b = m.bounds
        if np.any(b[0, :2] < -lim - tol) or np.any(b[1, :2] > lim + tol):
            raise AssetSpecError(
                where,
                f"{part.type} spans x [{b[0, 0]:.3f}, {b[1, 0]:.3f}] y [{b[0, 1]:.3f}, {b[1, 1]:.3f}] m, outside the "
                f"hull footprint x [{-lim[0]:g}, {lim[0]:g}] y [{-lim[1]:g}, {lim[1]:g}] m",
            )
        z_lo, z_hi = min(z_lo, float(b[0, 2])), max(z_hi, float(b[1, 2]))
        if z_hi - z_lo > max_height:
            raise AssetSpecError(
                where,
                f"{part.type} spans z [{b[0, 2]:.6g}, {b[1, 2]:.6g}] m, making the vessel {z_hi - z_lo:.6g} m tall; "
                f"the largest asset height is {max_height:g} m",
            )
        meshes.append(m)
    origin = np.concatenate([np.full(m.num_triangles, i - 1, dtype=np.int32) for i, m in enumerate(meshes)])
    return merge(meshes), origin
