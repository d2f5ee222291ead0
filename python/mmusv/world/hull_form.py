"""The lofted hull of a procedural vessel: plan form, rounded sections, raked stem, sheer, transom, bulbous bow.

Body frame and units as in :mod:`mmusv.world.vessel_shapes` (x forward from midship, y left, z up from the
waterline, metres). Stations ``u`` run from the transom (0) to the stem (1); the deck outline's half-width is
``beam/2 * profile(u)`` (exactly, so parts can be fitted to it). A section's half-width at a height is the deck's
times a smooth section curve: ``bottom`` at the keel rising like ``1 - (1 - q)^3.3`` to ``flare`` at the
waterline, then to 1 at the deck; in the bow taper the bottom narrows (V forefoot) and the waterline draws in
(bow flare). The stem rakes back along a curve ``rake * length * (1 - t)^1.5`` below the deck (``t`` the height
fraction keel to deck), the transom ``overhang`` likewise. Rings follow the sheer. Faces carry materials by band:
antifouling below the boot-top, the boot-top band about the waterline, the hull's ``topside`` paint above and its
``deck`` material on the deck; a bulbous bow (``bulb``) is a separate closed body under the stem.
"""

from __future__ import annotations

import math

import numpy as np

from mmusv.world.asset_spec import HullSpec
from mmusv.world.materials import material_id
from mmusv.world.primitives import TriMesh, lathe, merge, transformed

__all__ = [
    "boot_top_band",
    "deck_z",
    "half_width",
    "half_widths",
    "hull_mesh",
    "profile",
    "resolution",
    "side_half_width",
    "stations",
]

_SECTION_POWER = math.log(0.1) / math.log(0.5)  # half the draft up, the section has 90 % of its rise


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


def _bow_progress(hull: HullSpec, u: np.ndarray) -> np.ndarray:
    """0 aft of the bow taper, rising to 1 at the stem."""
    if hull.bow <= 0:
        return np.zeros_like(u)
    return np.clip((u - (1.0 - hull.bow)) / hull.bow, 0.0, 1.0)


def resolution(hull: HullSpec) -> tuple[int, int, int, int]:
    """Stations in the bow taper, the stern taper and the parallel middle body, and levels keel to deck, used
    for lofting: the ends, where the hull curves in plan and section, get most of them; more for larger hulls."""
    if hull.length < 15.0:
        return 30, 14, 10, 22
    if hull.length < 80.0:
        return 36, 16, 12, 22
    return 52, 22, 16, 28


def stations(hull: HullSpec) -> np.ndarray:
    """Sorted station parameters ``(N,)`` used for lofting: cosine-spaced over the bow and stern tapers (dense at
    the stem and transom), evenly over the middle body (where only the sheer curves)."""
    n_bow, n_stern, n_mid, _ = resolution(hull)
    ub, us = 1.0 - hull.bow, hull.stern
    parts = [np.linspace(us, ub, n_mid + 1)]
    if hull.bow > 0:
        parts.append(ub + hull.bow * np.sin(np.linspace(0.0, 1.0, n_bow) * np.pi / 2.0))
    if hull.stern > 0:
        parts.append(hull.stern * (1.0 - np.cos(np.linspace(0.0, 1.0, n_stern) * np.pi / 2.0)))
    return np.unique(np.round(np.clip(np.concatenate([[0.0, 1.0], *parts]), 0.0, 1.0), 12))


def deck_z(hull: HullSpec, x: float) -> float:
    """Deck height above the waterline at body-frame ``x`` (metres), including sheer."""
    t = min(max(x / (hull.length / 2.0), 0.0), 1.0)
    return hull.freeboard + hull.sheer * t * t


def _deck_z(hull: HullSpec, x: np.ndarray) -> np.ndarray:
    t = np.clip(x / (hull.length / 2.0), 0.0, 1.0)
    return hull.freeboard + hull.sheer * t * t


def half_width(hull: HullSpec, x: float) -> float:
    """Outer half-width of the deck outline at body-frame ``x`` (metres; 0 beyond the ends)."""
    if abs(x) > hull.length / 2.0 + 1e-9:
        return 0.0
    w = float(profile(hull, np.array([(x + hull.length / 2.0) / hull.length]))[0])
    if hull.type == "twin":
        return (hull.beam - hull.demi_width) / 2.0 + hull.demi_width / 2.0 * w
    return hull.beam / 2.0 * w


def half_widths(hull: HullSpec, x: np.ndarray) -> np.ndarray:
    """:func:`half_width` at every body-frame ``x`` ``(N,)`` metres, vectorised: ``(N,)`` metres."""
    x = np.asarray(x, dtype=np.float64)
    w = profile(hull, np.clip((x + hull.length / 2.0) / hull.length, 0.0, 1.0))
    twin = hull.type == "twin"
    hw = (hull.beam - hull.demi_width) / 2.0 + hull.demi_width / 2.0 * w if twin else hull.beam / 2.0 * w
    return np.where(np.abs(x) > hull.length / 2.0 + 1e-9, 0.0, hw)


def boot_top_band(hull: HullSpec) -> tuple[float, float]:
    """The boot-top band ``(z_low, z_high)`` metres: from the light waterline below the design waterline to a
    stripe above it (ships about 1-3 m, small craft a stripe of a few centimetres)."""
    lo = -min(0.12 * hull.draft, 0.4 + 0.05 * hull.draft)
    hi = min(0.08 * hull.freeboard, 0.6)
    return lo, hi


def _section(hull: HullSpec, u: np.ndarray, z_frac: np.ndarray, below: bool) -> np.ndarray:
    """Section half-width fraction ``(N,)``: ``z_frac`` is q = (z + draft)/draft below the waterline, or the
    fraction of the local deck height above it."""
    tb = _bow_progress(hull, u)
    flare = hull.flare * (1.0 - 0.3 * tb**1.5)
    if below:
        bottom = np.minimum(hull.bottom * (1.0 - 0.75 * tb), flare)
        return bottom + (flare - bottom) * (1.0 - (1.0 - z_frac) ** _SECTION_POWER)
    return flare + (1.0 - flare) * z_frac ** (0.8 + 0.6 * tb)


def side_half_width(hull: HullSpec, *, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Half-width ``(N,)`` metres of the hull's side at body ``x`` and height ``z`` ``(N,)`` (one demihull's outer
    side for twins); an approximation near the raked ends."""
    x = np.asarray(x, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    u = np.clip((x + hull.length / 2.0) / hull.length, 0.0, 1.0)
    w = profile(hull, u)
    below = z < 0.0
    q = np.clip(np.where(below, (z + hull.draft) / hull.draft, z / _deck_z(hull, x)), 0.0, 1.0)
    s = np.where(below, _section(hull, u, q, True), _section(hull, u, q, False))
    if hull.type == "twin":
        return (hull.beam - hull.demi_width) / 2.0 + hull.demi_width / 2.0 * w * s
    return hull.beam / 2.0 * w * s


def _levels(hull: HullSpec) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Level heights: ``below`` (q fractions, keel to waterline) and ``above`` (deck fractions, waterline to
    deck) and the level indices where the boot-top band starts and ends."""
    n = resolution(hull)[3]
    lo, hi = boot_top_band(hull)
    nb = max(4, round(n * hull.draft / hull.depth))
    s = np.linspace(0.0, 1.0, nb)
    q = (1.0 - np.cos(np.pi * s / 2.0 * 1.0)) * 0.6 + 0.4 * s  # denser at the bilge
    q_bt = 1.0 + lo / hull.draft
    q = np.unique(np.round(np.concatenate([q[q < q_bt - 1e-6], [q_bt, 1.0]]), 12))
    na = max(3, n - nb)
    f_bt = hi / hull.freeboard
    f = np.linspace(0.0, 1.0, na)
    f = np.unique(np.round(np.concatenate([[0.0, f_bt], f[f > f_bt + 1e-6]]), 12))
    return q, f, int(np.argmax(np.isclose(q, q_bt))), len(q)  # ring index of z = hi: the first above-water ring


def _loft(hull: HullSpec, *, y0: float, half: float, cls: int, mats: tuple[int, int, int, int]) -> TriMesh:
    antifouling, boot, topside, deck = mats
    u = stations(hull)
    n = u.shape[0]
    w = profile(hull, u)
    tip = bool(w[-1] < 1e-6)
    if tip:
        w[-1] = 0.0  # a stem that closes to (nearly) nothing closes to a point
    length, draft, depth = hull.length, hull.draft, hull.depth
    q, f, k_lo, k_hi = _levels(hull)
    x_deck = -length / 2.0 + u * length
    dz = _deck_z(hull, x_deck)
    rings = []
    for below, fracs in ((True, q), (False, f[1:])):
        for fr in fracs:
            if below:
                z = np.full(n, -draft + fr * draft)
                t = fr * draft / depth
            else:
                z = fr * dz
                # at most 1: draft + (depth - draft) rounds past depth for 42 of 3,626 hulls of whole decimetres
                # (draft 0.6, depth 1.8), and (1 - t) ** 1.5 of a negative 1 - t was NaN, the stem's x at the deck
                t = min(1.0, (draft + fr * hull.freeboard) / depth)
            x_bow = length / 2.0 - hull.rake * length * (1.0 - t) ** 1.5
            x_stern = -length / 2.0 + hull.overhang * length * (1.0 - t) ** 1.2
            x = x_stern + u * (x_bow - x_stern)
            hw = half * w * _section(hull, u, np.full(n, fr), below)
            stb = np.column_stack([x, y0 - hw, z])
            port = np.column_stack([x, y0 + hw, z])[::-1]
            rings.append(np.vstack([stb, port[1:] if tip else port]))
    m = rings[0].shape[0]
    a = np.arange(m)
    b = (a + 1) % m
    nl = len(rings)
    k = np.arange(nl - 1)[:, None]
    lo, hi = k * m, (k + 1) * m
    sides = np.stack([lo + a, lo + b, hi + b, lo + a, hi + b, hi + a], axis=2).reshape(-1, 3)
    band = np.where(k[:, 0] < k_lo, antifouling, np.where(k[:, 0] < k_hi, boot, topside))
    side_m = np.repeat(band, 2 * m)
    cap = _strip_cap(n, tip)
    faces = np.vstack([sides, cap[:, ::-1], cap + (nl - 1) * m])
    materials = np.concatenate([side_m, np.full(cap.shape[0], antifouling), np.full(cap.shape[0], deck)])
    return TriMesh(np.vstack(rings), faces, np.array([cls]), materials)


def _strip_cap(n: int, tip: bool) -> np.ndarray:
    """Top-facing triangles ``(F, 3)`` closing a hull ring of ``n`` stations (ring = starboard fwd, port aft)."""
    s = np.arange(n)
    p = (2 * n - 2 - s) if tip else (2 * n - 1 - s)
    if tip:
        p[n - 1] = n - 1
    t = np.stack(
        [
            np.column_stack([s[:-1], s[1:], p[1:]]),
            np.column_stack([s[:-1], p[1:], p[:-1]]),
        ],
        axis=1,
    ).reshape(-1, 3)
    ok = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return np.asarray(t[ok], dtype=np.int64)


def _bulb(hull: HullSpec, cls: int, material: int) -> TriMesh:
    """A bulbous bow: an ellipsoid-like body of revolution along x, centred low under the stem."""
    length, draft, depth = hull.length, hull.draft, hull.depth
    zc = -0.55 * draft
    t = (zc + draft) / depth
    x_stem = length / 2.0 - hull.rake * length * (1.0 - t) ** 1.5
    room = length / 2.0 - x_stem
    half = hull.bulb * hull.beam / 2.0
    rz = 0.28 * draft
    ahead = min(0.92 * room, 2.2 * half)
    back = max(4.0 * half, 0.06 * length)
    s = np.linspace(0.0, 1.0, 14)
    xs = x_stem + ahead - s * (ahead + back)  # tip (s=0) to the back (s=1)
    r = np.where(
        s < 0.35, np.sqrt(np.clip(1.0 - ((0.35 - s) / 0.35) ** 2, 0.0, 1.0)), 1.0 - 0.7 * ((s - 0.35) / 0.65) ** 2
    )
    prof = np.column_stack([r, xs])[::-1]  # bottom (aft) to top (tip) along the lathe axis
    prof[0, 0] = 0.0
    prof[-1, 0] = 0.0
    m = lathe(prof, cls=cls, material=material, segments=16, scale=(rz, half))
    rot = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # local z -> body x, local x -> body -z
    return transformed(m, rotation=rot, translation=(0.0, 0.0, zc))


def hull_mesh(hull: HullSpec, cls: int) -> TriMesh:
    """The closed hull mesh (one lofted body or two demihulls, plus a bulb when the hull has one), labelled
    ``cls``, with antifouling, boot-top, topside and deck materials by band."""
    mats = (material_id("antifouling_red"), material_id("boot_top"), material_id(hull.topside), material_id(hull.deck))
    if hull.type == "twin":
        off = (hull.beam - hull.demi_width) / 2.0
        return merge(
            [
                _loft(hull, y0=-off, half=hull.demi_width / 2.0, cls=cls, mats=mats),
                _loft(hull, y0=off, half=hull.demi_width / 2.0, cls=cls, mats=mats),
            ]
        )
    meshes = [_loft(hull, y0=0.0, half=hull.beam / 2.0, cls=cls, mats=mats)]
    if hull.bulb > 0:
        meshes.append(_bulb(hull, cls, mats[0]))
    return merge(meshes)
