"""Procedural vessel geometry: a lofted hull plus a small vocabulary of superstructure parts.

A procedural vessel is a ``hull`` mapping and a ``parts`` list (the entries of ``vessel_catalog.yaml``, or a
user's YAML). Every number is in metres (angles in degrees where the key ends in ``_deg``), in the vessel body
frame: x forward (bow at +x), y left, z up, z = 0 at the waterline. The hull spans exactly
``x in [-length/2, length/2]``, ``y in [-beam/2, beam/2]`` and reaches down to ``z = -draft``; no part may stick
out of that x/y footprint (checked), so the body-frame origin stays the waterline centre of the bounding box.

Hull keys (``type: mono | twin``)::

    length, beam, draft, depth        overall length, beam, hull draft, keel-to-deck depth at midship
    demi_beam                         twin only: beam of each of the two demihulls
    bow=0.2, stern=0.1                fractions of the length over which the hull tapers at bow / stern
    bow_shape=pointed|round           plan form of the bow taper; bow_power=2.0 is its fullness (>= 1)
    bow_width=0                       half-width left at the stem (1 = square barge bow; needs bow=0)
    transom=0.9                       half-width fraction at the transom (must be 1 when stern=0)
    sheer=0                           deck rise at the stem above the midship deck, rising quadratically
    rake=0.05, overhang=0.0           fractions of length by which the keel is shorter at bow / stern
    bottom=0.8, flare=1.0             half-width fraction at the keel / at the waterline (deck is 1)

Part types (each ``{type: ..., ...}``; ``base`` defaults to the deck height at the part's x; vertical extent
is ``top`` (absolute z) or ``height`` (above ``base``); ``fit: m`` narrows a part so it stays ``m`` metres
inside the deck outline)::

    box        x, y=0, size [lx, ly], base, top|height, taper=1, yaw_deg=0, fit
    house      x, y=0, align=center|aft|fore, base, tiers [[lx, ly, h(, dx)], ...], taper=1, fit,
               wings [lx, ly] (bridge wings beside the top tier)
    hull_block x0, x1, inset=0, base, top|height, taper=1          (a block following the deck outline)
    row        x0, x1, count, gap=0, y=0, width, heights [h, ...] (cycled), base, fit  (hatches, stacks)
    funnel     x, y=0, size [lx, ly], base, top|height, shape=box|round, taper=0.9
    mast       x, y=0, base, top|height, width=0.3, yard=0, yard_at=0.8
    cylinder   x, y=0, radius, base, top|height, top_radius, segments=12
    hcylinder  x0, x1, y=0, z, radius, segments=12                 (axis along x)
    dome       x, y=0, radius, top, base, segments=16              (sphere cap on a skirt)
    strut      from [x, y, z], to [x, y, z], width, thickness=width (absolute coordinates)
    plate      y=0, thickness, points [[x, z], ...] (convex profile extruded across y)
    gantry     x, span, base, top|height, leg=0.5, lean=0           (A-frame / portal)
    crane      x, y=0, base, pedestal [radius, height], jib [length, elevation_deg, yaw_deg], width=0.6
    gun        x, y=0, base, radius, height, barrel, yaw_deg=0, elevation_deg=5

All parts are closed, outward-facing triangle meshes labelled with the vessel's semantic class; parts may
overlap (the union is what sensors see).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from mmusv.errors import ConfigError
from mmusv.world.primitives import TriMesh, box, merge, prism, transformed

__all__ = ["PART_TYPES", "AssetSpecError", "Fields", "HullSpec", "build_procedural", "parse_hull"]


class AssetSpecError(ConfigError, ValueError):
    """A vessel asset entry is invalid (a :class:`mmusv.ConfigError`, and a ``ValueError`` as before); ``field`` is the dotted path of the offending key (``tug_32m.hull.beam``)."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.reason = message

    def __reduce__(self) -> tuple[type[AssetSpecError], tuple[str, str]]:
        return (type(self), (self.field, self.reason))


def _number(value: object, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise AssetSpecError(path, f"must be a number, got {value!r}")
    f = float(value)
    if not math.isfinite(f):
        raise AssetSpecError(path, f"must be finite, got {value!r}")
    return f


class Fields:
    """Typed, path-aware access to one mapping of an asset entry; :meth:`finish` rejects keys never read."""

    def __init__(self, data: object, path: str) -> None:
        if not isinstance(data, Mapping):
            raise AssetSpecError(path, f"must be a mapping, got {type(data).__name__}")
        self._data: dict[str, object] = {str(k): v for k, v in data.items()}
        self._used: set[str] = set()
        self.path = path

    def at(self, key: str) -> str:
        """Dotted path of ``key`` below this mapping."""
        return f"{self.path}.{key}" if self.path else key

    def keys(self) -> list[str]:
        """The keys present in this mapping, in order (marks nothing as read)."""
        return list(self._data)

    def has(self, key: str) -> bool:
        """Whether ``key`` is present and not null (marks it as read)."""
        self._used.add(key)
        return self._data.get(key) is not None

    def raw(self, key: str) -> object:
        """The value of ``key`` as parsed (``None`` when absent)."""
        self._used.add(key)
        return self._data.get(key)

    def _check(self, key: str, f: float, minimum: float | None, maximum: float | None, exclusive: bool) -> float:
        if minimum is not None and (f < minimum or (exclusive and f <= minimum)):
            raise AssetSpecError(self.at(key), f"must be {'>' if exclusive else '>='} {minimum}, got {f}")
        if maximum is not None and f > maximum:
            raise AssetSpecError(self.at(key), f"must be <= {maximum}, got {f}")
        return f

    def num(
        self,
        key: str,
        default: float | None = None,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        exclusive: bool = False,
    ) -> float:
        """A number; required when ``default`` is ``None``. ``exclusive`` makes ``minimum`` a strict bound."""
        v = self.raw(key)
        if v is None:
            if default is None:
                raise AssetSpecError(self.at(key), "is required")
            return default
        return self._check(key, _number(v, self.at(key)), minimum, maximum, exclusive)

    def opt_num(
        self, key: str, *, minimum: float | None = None, maximum: float | None = None, exclusive: bool = False
    ) -> float | None:
        """An optional number (``None`` when absent)."""
        v = self.raw(key)
        if v is None:
            return None
        return self._check(key, _number(v, self.at(key)), minimum, maximum, exclusive)

    def vec(self, key: str, n: int, default: tuple[float, ...] | None = None) -> tuple[float, ...]:
        """A list of exactly ``n`` numbers; required when ``default`` is ``None``."""
        v = self.raw(key)
        if v is None:
            if default is None:
                raise AssetSpecError(self.at(key), f"is required (a list of {n} numbers)")
            return default
        if not isinstance(v, (list, tuple)) or len(v) != n:
            raise AssetSpecError(self.at(key), f"must be a list of {n} numbers, got {v!r}")
        return tuple(_number(x, f"{self.at(key)}[{i}]") for i, x in enumerate(v))

    def numbers(self, key: str) -> list[float]:
        """A non-empty list of numbers (required)."""
        v = self.raw(key)
        if not isinstance(v, (list, tuple)) or not v:
            raise AssetSpecError(self.at(key), f"must be a non-empty list of numbers, got {v!r}")
        return [_number(x, f"{self.at(key)}[{i}]") for i, x in enumerate(v)]

    def rows(self, key: str, n_min: int, n_max: int) -> list[tuple[float, ...]]:
        """A non-empty list of number lists, each with ``n_min`` to ``n_max`` entries (required)."""
        v = self.raw(key)
        if not isinstance(v, (list, tuple)) or not v:
            raise AssetSpecError(self.at(key), f"must be a non-empty list of lists, got {v!r}")
        out = []
        for i, row in enumerate(v):
            p = f"{self.at(key)}[{i}]"
            if not isinstance(row, (list, tuple)) or not n_min <= len(row) <= n_max:
                raise AssetSpecError(p, f"must be a list of {n_min} to {n_max} numbers, got {row!r}")
            out.append(tuple(_number(x, f"{p}[{j}]") for j, x in enumerate(row)))
        return out

    def text(self, key: str, default: str | None = None, *, choices: Sequence[str] | None = None) -> str:
        """A string; required when ``default`` is ``None``; optionally one of ``choices``."""
        v = self.raw(key)
        if v is None:
            if default is None:
                raise AssetSpecError(self.at(key), "is required")
            return default
        if not isinstance(v, str) or not v:
            raise AssetSpecError(self.at(key), f"must be a non-empty string, got {v!r}")
        if choices is not None and v not in choices:
            raise AssetSpecError(self.at(key), f"must be one of {', '.join(choices)}; got {v!r}")
        return v

    def finish(self) -> None:
        """Raises :class:`AssetSpecError` naming the first key that was never read (a typo or unsupported key)."""
        unknown = sorted(set(self._data) - self._used)
        if unknown:
            known = ", ".join(sorted(self._used))
            raise AssetSpecError(self.at(unknown[0]), f"unknown key (known here: {known})")


@dataclass(frozen=True)
class HullSpec:
    """Parsed hull parameters (see the module docstring); lengths in metres, the rest dimensionless."""

    kind: str
    length: float
    beam: float
    draft: float
    depth: float
    demi_beam: float
    bow: float
    stern: float
    bow_power: float
    bow_shape: str
    bow_width: float
    transom: float
    sheer: float
    rake: float
    overhang: float
    bottom: float
    flare: float

    @property
    def freeboard(self) -> float:
        """Deck height above the waterline at midship, metres."""
        return self.depth - self.draft

    def profile(self, u: np.ndarray) -> np.ndarray:
        """Relative half-width ``(N,)`` in ``[0, 1]`` at stations ``u`` ``(N,)`` (0 = transom, 1 = stem)."""
        u = np.asarray(u, dtype=np.float64)
        w = np.ones_like(u)
        if self.stern > 0:
            m = u < self.stern
            t = u[m] / self.stern
            w[m] = self.transom + (1.0 - self.transom) * (1.0 - (1.0 - t) ** 2)
        if self.bow > 0:
            ub = 1.0 - self.bow
            m = u > ub
            t = np.clip((u[m] - ub) / self.bow, 0.0, 1.0)
            p = self.bow_power
            if self.bow_shape == "round":
                w[m] = self.bow_width + (1.0 - self.bow_width) * (1.0 - t**p) ** (1.0 / p)
            else:
                w[m] = 1.0 - (1.0 - self.bow_width) * t**p
        return w

    def stations(self) -> np.ndarray:
        """Sorted station parameters ``(N,)`` used for lofting, denser where the outline curves."""
        us = [0.0, 1.0]
        if self.stern > 0:
            us += [self.stern / 3.0, 2.0 * self.stern / 3.0, self.stern]
        if self.bow > 0:
            s = np.linspace(0.0, 1.0, 9)
            us += list(1.0 - self.bow + self.bow * np.sin(s * np.pi / 2.0))
        return np.unique(np.round(np.clip(us, 0.0, 1.0), 12))

    def deck_z(self, x: float) -> float:
        """Deck height above the waterline at body-frame ``x`` (metres), including sheer."""
        t = min(max(x / (self.length / 2.0), 0.0), 1.0)
        return self.freeboard + self.sheer * t * t

    def half_width(self, x: float) -> float:
        """Outer half-width of the deck outline at body-frame ``x`` (metres; 0 beyond the ends)."""
        if abs(x) > self.length / 2.0 + 1e-9:
            return 0.0
        w = float(self.profile(np.array([(x + self.length / 2.0) / self.length]))[0])
        if self.kind == "twin":
            return (self.beam - self.demi_beam) / 2.0 + self.demi_beam / 2.0 * w
        return self.beam / 2.0 * w

    def mesh(self, cls: int) -> TriMesh:
        """The closed hull mesh (one lofted body, or two demihulls), labelled ``cls``."""
        if self.kind == "twin":
            off = (self.beam - self.demi_beam) / 2.0
            return merge(
                [
                    self._loft(y0=-off, half=self.demi_beam / 2.0, cls=cls),
                    self._loft(y0=off, half=self.demi_beam / 2.0, cls=cls),
                ]
            )
        return self._loft(y0=0.0, half=self.beam / 2.0, cls=cls)

    def _loft(self, *, y0: float, half: float, cls: int) -> TriMesh:
        u = self.stations()
        n = u.shape[0]
        w = self.profile(u)
        tip = bool(w[-1] < 1e-9)
        length, draft = self.length, self.draft
        levels = [
            (-draft, self.bottom),
            (-0.5 * draft, self.bottom + 0.9 * (self.flare - self.bottom)),
            (0.0, self.flare),
            (self.freeboard, 1.0),
        ]
        rings = []
        for k, (z, scale) in enumerate(levels):
            s = (z + draft) / self.depth
            x_bow = length / 2.0 - self.rake * length * (1.0 - s)
            x_stern = -length / 2.0 + self.overhang * length * (1.0 - s)
            if k == 3:
                x_bow, x_stern = length / 2.0, -length / 2.0
            x = x_stern + u * (x_bow - x_stern)
            hw = half * scale * w
            zz = np.array([self.deck_z(float(xi)) for xi in x]) if k == 3 else np.full(n, z)
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


def parse_hull(data: object, *, path: str) -> HullSpec:
    """Validates a ``hull`` mapping (see the module docstring) into a :class:`HullSpec`."""
    f = Fields(data, path)
    kind = f.text("type", "mono", choices=("mono", "twin"))
    length = f.num("length", minimum=0.0, exclusive=True)
    beam = f.num("beam", minimum=0.0, exclusive=True)
    draft = f.num("draft", minimum=0.0, exclusive=True)
    depth = f.num("depth", minimum=draft, exclusive=True)
    demi = f.num("demi_beam", minimum=0.0, maximum=beam / 2.0, exclusive=True) if kind == "twin" else beam
    bow = f.num("bow", 0.2, minimum=0.0, maximum=0.95)
    stern = f.num("stern", 0.1, minimum=0.0, maximum=0.95)
    if bow + stern > 1.0:
        raise AssetSpecError(f.at("stern"), f"bow + stern must be <= 1, got {bow} + {stern}")
    bow_width = f.num("bow_width", 0.0 if bow > 0 else 1.0, minimum=0.0, maximum=1.0)
    transom = f.num("transom", 0.9 if stern > 0 else 1.0, minimum=0.02, maximum=1.0)
    if bow == 0 and bow_width != 1.0:
        raise AssetSpecError(f.at("bow_width"), "must be 1 when bow is 0 (no taper)")
    if stern == 0 and transom != 1.0:
        raise AssetSpecError(f.at("transom"), "must be 1 when stern is 0 (no taper)")
    rake = f.num("rake", 0.05, minimum=0.0, maximum=0.45)
    overhang = f.num("overhang", 0.0, minimum=0.0, maximum=0.45)
    spec = HullSpec(
        kind=kind,
        length=length,
        beam=beam,
        draft=draft,
        depth=depth,
        demi_beam=demi,
        bow=bow,
        stern=stern,
        bow_power=f.num("bow_power", 2.0, minimum=1.0, maximum=8.0),
        bow_shape=f.text("bow_shape", "pointed", choices=("pointed", "round")),
        bow_width=bow_width,
        transom=transom,
        sheer=f.num("sheer", 0.0, minimum=0.0),
        rake=rake,
        overhang=overhang,
        bottom=f.num("bottom", 0.8, minimum=0.02, maximum=1.0),
        flare=f.num("flare", 1.0, minimum=0.02, maximum=1.0),
    )
    f.finish()
    return spec


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


def _zspan(f: Fields, hull: HullSpec, x: float) -> tuple[float, float]:
    base = f.opt_num("base")
    z0 = hull.deck_z(x) if base is None else base
    top = f.opt_num("top")
    height = f.opt_num("height", minimum=0.0, exclusive=True)
    if (top is None) == (height is None):
        raise AssetSpecError(f.at("top"), "give exactly one of top (absolute z, m) or height (m above base)")
    z1 = top if top is not None else z0 + (height or 0.0)
    if z1 <= z0:
        raise AssetSpecError(f.at("top"), f"top {z1:g} m must be above the base {z0:g} m")
    return z0, z1


def _fit_width(f: Fields, hull: HullSpec, *, x0: float, x1: float, y: float, width: float) -> float:
    """``width`` narrowed (when the ``fit`` key is given) to stay ``fit`` metres inside the deck outline."""
    margin = f.opt_num("fit", minimum=0.0)
    if margin is None:
        return width
    room = min(hull.half_width(x0), hull.half_width(x1)) - margin - abs(y)
    if room <= 0.0:
        raise AssetSpecError(f.at("fit"), f"no room inside the deck outline between x={x0:g} and x={x1:g}")
    return min(width, 2.0 * room)


def _part_box(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    lx, ly = f.vec("size", 2)
    z0, z1 = _zspan(f, hull, x)
    ly = _fit_width(f, hull, x0=x - lx / 2, x1=x + lx / 2, y=y, width=ly)
    taper = f.num("taper", 1.0, minimum=0.0, exclusive=True)
    return _block(x=x, y=y, lx=lx, ly=ly, z0=z0, z1=z1, cls=cls, taper=taper, yaw=math.radians(f.num("yaw_deg", 0.0)))


def _part_house(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    align = f.text("align", "center", choices=("center", "aft", "fore"))
    taper = f.num("taper", 1.0, minimum=0.0, exclusive=True)
    tiers = f.rows("tiers", 3, 4)
    base = f.opt_num("base")
    z = hull.deck_z(x) if base is None else base
    parts: list[TriMesh] = []
    xc = lx = ly = h = 0.0
    for t in tiers:
        lx, ly, h = t[0], t[1], t[2]
        dx = t[3] if len(t) > 3 else 0.0
        xc = x + dx + {"center": 0.0, "aft": lx / 2.0, "fore": -lx / 2.0}[align]
        ly = _fit_width(f, hull, x0=xc - lx / 2, x1=xc + lx / 2, y=y, width=ly)
        parts.append(_block(x=xc, y=y, lx=lx, ly=ly, z0=z, z1=z + h, cls=cls, taper=taper))
        z += h
    if f.has("wings"):
        wx, wy = f.vec("wings", 2)
        wxc = xc + lx / 2.0 - wx / 2.0
        wy = _fit_width(f, hull, x0=wxc - wx / 2, x1=wxc + wx / 2, y=y, width=wy)
        parts.append(_block(x=wxc, y=y, lx=wx, ly=wy, z0=z - h, z1=z - 0.15 * h, cls=cls))
    return merge(parts)


def _part_hull_block(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    if hull.kind != "mono":
        raise AssetSpecError(f.at("type"), "hull_block needs a mono hull")
    half_l = hull.length / 2.0
    x0 = f.num("x0", minimum=-half_l, maximum=half_l)
    x1 = f.num("x1", minimum=x0, maximum=half_l, exclusive=True)
    inset = f.num("inset", 0.0, minimum=0.0)
    z0, z1 = _zspan(f, hull, (x0 + x1) / 2.0)
    taper = f.num("taper", 1.0, minimum=0.0, exclusive=True)
    u0, u1 = (x0 + half_l) / hull.length, (x1 + half_l) / hull.length
    st = hull.stations()
    u = np.unique(np.concatenate([[u0, u1], st[(st > u0 + 1e-9) & (st < u1 - 1e-9)]]))
    hw = hull.beam / 2.0 * hull.profile(u) - inset
    if float(hw.min()) < 0.01:
        raise AssetSpecError(f.at("x1"), "block reaches where the deck is narrower than twice the inset")
    xs = -half_l + u * hull.length
    outline = np.vstack([np.column_stack([xs, -hw]), np.column_stack([xs, hw])[::-1]])
    return prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=taper)


def _part_row(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x0, x1 = f.num("x0"), f.num("x1")
    count = int(f.num("count", minimum=1.0))
    gap = f.num("gap", 0.0, minimum=0.0)
    y = f.num("y", 0.0)
    width = f.num("width", minimum=0.0, exclusive=True)
    heights = f.numbers("heights")
    base = f.opt_num("base")
    lx = (x1 - x0 - gap * (count - 1)) / count
    if lx <= 0.0:
        raise AssetSpecError(f.at("count"), f"{count} boxes with gap {gap:g} do not fit between x0 and x1")
    parts = []
    for i in range(count):
        a = x0 + i * (lx + gap)
        xc = a + lx / 2.0
        w = _fit_width(f, hull, x0=a, x1=a + lx, y=y, width=width)
        z0 = hull.deck_z(xc) if base is None else base
        h = heights[i % len(heights)]
        if h <= 0:
            raise AssetSpecError(f.at("heights"), "heights must be > 0")
        parts.append(_block(x=xc, y=y, lx=lx, ly=w, z0=z0, z1=z0 + h, cls=cls))
    return merge(parts)


def _part_funnel(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    lx, ly = f.vec("size", 2)
    z0, z1 = _zspan(f, hull, x)
    taper = f.num("taper", 0.9, minimum=0.0, exclusive=True)
    if f.text("shape", "box", choices=("box", "round")) == "box":
        return _block(x=x, y=y, lx=lx, ly=ly, z0=z0, z1=z1, cls=cls, taper=taper)
    a = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    outline = np.column_stack([x + lx / 2.0 * np.cos(a), y + ly / 2.0 * np.sin(a)])
    return prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=taper)


def _part_mast(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    z0, z1 = _zspan(f, hull, x)
    w = f.num("width", 0.3, minimum=0.0, exclusive=True)
    parts = [_block(x=x, y=y, lx=w, ly=w, z0=z0, z1=z1, cls=cls)]
    yard = f.num("yard", 0.0, minimum=0.0)
    if yard > 0:
        zy = z0 + f.num("yard_at", 0.8, minimum=0.0, maximum=1.0) * (z1 - z0)
        zy = min(max(zy, z0 + w / 2), z1 - w / 2)
        parts.append(_block(x=x, y=y, lx=w, ly=yard, z0=zy - w / 2, z1=zy + w / 2, cls=cls))
    return merge(parts)


def _part_cylinder(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    r = f.num("radius", minimum=0.0, exclusive=True)
    z0, z1 = _zspan(f, hull, x)
    rt = f.opt_num("top_radius", minimum=0.0, exclusive=True)
    seg = int(f.num("segments", 12.0, minimum=3.0, maximum=64.0))
    return _lathe([(r, z0), (r if rt is None else rt, z1)], cx=x, cy=y, segments=seg, cls=cls)


def _part_hcylinder(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x0 = f.num("x0")
    x1 = f.num("x1", minimum=x0, exclusive=True)
    y, z = f.num("y", 0.0), f.num("z")
    r = f.num("radius", minimum=0.0, exclusive=True)
    seg = int(f.num("segments", 12.0, minimum=3.0, maximum=64.0))
    m = _lathe([(r, x0), (r, x1)], cx=0.0, cy=0.0, segments=seg, cls=cls)
    return transformed(m, rotation=_ROT_Y90, translation=(0.0, y, z))


def _part_dome(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    r = f.num("radius", minimum=0.0, exclusive=True)
    top = f.num("top")
    base = f.opt_num("base")
    z0 = hull.deck_z(x) if base is None else base
    seg = int(f.num("segments", 16.0, minimum=3.0, maximum=64.0))
    c = top - r
    if z0 >= top:
        raise AssetSpecError(f.at("top"), f"top {top:g} m must be above the base {z0:g} m")
    theta0 = math.asin(min(max((z0 - c) / r, 0.0), 1.0))
    profile: list[tuple[float, float]] = [] if z0 >= c else [(r, z0)]
    for th in np.linspace(theta0, math.pi / 2.0, 5):
        profile.append((0.0 if th >= math.pi / 2.0 - 1e-12 else r * math.cos(th), c + r * math.sin(th)))
    profile[0] = (profile[0][0], max(profile[0][1], z0))
    return _lathe(profile, cx=x, cy=y, segments=seg, cls=cls)


def _part_strut(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    p0, p1 = np.array(f.vec("from", 3)), np.array(f.vec("to", 3))
    if float(np.linalg.norm(p1 - p0)) <= 1e-9:
        raise AssetSpecError(f.at("to"), "must differ from 'from'")
    w = f.num("width", minimum=0.0, exclusive=True)
    t = f.num("thickness", w, minimum=0.0, exclusive=True)
    return _strut(p0, p1, width=w, thickness=t, cls=cls)


def _part_plate(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    y = f.num("y", 0.0)
    t = f.num("thickness", minimum=0.0, exclusive=True)
    pts = np.array(f.rows("points", 2, 2))
    if pts.shape[0] < 3:
        raise AssetSpecError(f.at("points"), "needs at least 3 [x, z] points")
    d = np.roll(pts, -1, axis=0)
    area = 0.5 * float(np.sum(pts[:, 0] * d[:, 1] - d[:, 0] * pts[:, 1]))
    if abs(area) < 1e-9:
        raise AssetSpecError(f.at("points"), "profile has zero area")
    if area < 0:
        pts = pts[::-1]
    m = prism(outline=pts, z0=-t / 2.0, z1=t / 2.0, cls=cls)
    return transformed(m, rotation=_ROT_X90, translation=(0.0, y, 0.0))


def _part_gantry(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x = f.num("x")
    span = f.num("span", minimum=0.0, exclusive=True)
    z0, z1 = _zspan(f, hull, x)
    leg = f.num("leg", 0.5, minimum=0.0, exclusive=True)
    lean = f.num("lean", 0.0)
    parts = []
    for side in (-1.0, 1.0):
        yy = side * span / 2.0
        parts.append(
            _strut(np.array([x, yy, z0]), np.array([x + lean, yy, z1 - leg / 2.0]), width=leg, thickness=leg, cls=cls)
        )
    parts.append(_block(x=x + lean, y=0.0, lx=leg, ly=span + leg, z0=z1 - leg, z1=z1, cls=cls))
    return merge(parts)


def _part_crane(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    base = f.opt_num("base")
    z0 = hull.deck_z(x) if base is None else base
    r, ph = f.vec("pedestal", 2)
    jl, elev, yaw = f.vec("jib", 3)
    w = f.num("width", 0.6, minimum=0.0, exclusive=True)
    if r <= 0 or ph <= 0 or jl <= 0:
        raise AssetSpecError(f.at("pedestal"), "pedestal radius/height and jib length must be > 0")
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


def _part_gun(f: Fields, hull: HullSpec, cls: int) -> TriMesh:
    x, y = f.num("x"), f.num("y", 0.0)
    base = f.opt_num("base")
    z0 = hull.deck_z(x) if base is None else base
    r = f.num("radius", minimum=0.0, exclusive=True)
    h = f.num("height", minimum=0.0, exclusive=True)
    barrel = f.num("barrel", minimum=0.0, exclusive=True)
    a, e = math.radians(f.num("yaw_deg", 0.0)), math.radians(f.num("elevation_deg", 5.0))
    d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    p0 = np.array([x, y, z0 + 0.55 * h])
    turret = _lathe([(r, z0), (0.75 * r, z0 + h)], cx=x, cy=y, segments=10, cls=cls)
    return merge(
        [
            turret,
            _strut(p0 + 0.5 * r * d, p0 + (r + barrel) * d, width=0.12 * r + 0.05, thickness=0.12 * r + 0.05, cls=cls),
        ]
    )


PartBuilder = Callable[[Fields, HullSpec, int], TriMesh]

PART_TYPES: dict[str, PartBuilder] = {
    "box": _part_box,
    "house": _part_house,
    "hull_block": _part_hull_block,
    "row": _part_row,
    "funnel": _part_funnel,
    "mast": _part_mast,
    "cylinder": _part_cylinder,
    "hcylinder": _part_hcylinder,
    "dome": _part_dome,
    "strut": _part_strut,
    "plate": _part_plate,
    "gantry": _part_gantry,
    "crane": _part_crane,
    "gun": _part_gun,
}
"""Part type name -> builder ``(fields, hull, class_id) -> TriMesh``."""


def build_procedural(*, hull: object, parts: object, path: str, cls: int) -> TriMesh:
    """Builds a vessel mesh from a ``hull`` mapping and a ``parts`` list (module docstring), labelled ``cls``.

    Returns a :class:`TriMesh` in the body frame whose x/y bounding box is exactly the hull's
    (``[-length/2, length/2] x [-beam/2, beam/2]``). Raises :class:`AssetSpecError` naming the offending
    key (``<path>.hull.beam``, ``<path>.parts[3].top``, ...) on invalid input or a part outside the footprint.
    """
    spec = parse_hull(hull, path=f"{path}.hull")
    meshes = [spec.mesh(cls)]
    if parts is None:
        parts = []
    if not isinstance(parts, (list, tuple)):
        raise AssetSpecError(f"{path}.parts", f"must be a list of part mappings, got {type(parts).__name__}")
    lim = np.array([spec.length / 2.0, spec.beam / 2.0])
    tol = 1e-9 * max(1.0, spec.length)
    for i, item in enumerate(parts):
        f = Fields(item, f"{path}.parts[{i}]")
        kind = f.text("type", choices=tuple(sorted(PART_TYPES)))
        m = PART_TYPES[kind](f, spec, cls)
        f.finish()
        if not np.all(np.isfinite(m.vertices)):
            raise AssetSpecError(f.path, f"{kind} produced non-finite vertices")
        b = m.bounds
        if np.any(b[0, :2] < -lim - tol) or np.any(b[1, :2] > lim + tol):
            raise AssetSpecError(
                f.path,
                f"{kind} spans x [{b[0, 0]:.3f}, {b[1, 0]:.3f}] y [{b[0, 1]:.3f}, {b[1, 1]:.3f}] m, outside the hull "
                f"footprint x [{-lim[0]:g}, {lim[0]:g}] y [{-lim[1]:g}, {lim[1]:g}] m",
            )
        meshes.append(m)
    return merge(meshes)
