"""The material table of mmusv: a small named list of PBR materials, one id per face of every mesh.

A :class:`Material` is a metallic-roughness PBR description (the glTF 2.0 model): linear-RGB albedo ``base_color``
in [0, 1], perceptual ``roughness`` in [0.02, 1] (the GGX alpha is ``roughness**2``), ``metallic`` in [0, 1],
``emissive`` radiance (linear RGB, cd/m² scale; a lit masthead lamp is about 2.6e3, :data:`NAV_LAMP_RADIANCE`),
``nav_light`` (the lamp emits only on vessels under way, COLREG lights) and a lamp's horizontal ``arc_deg`` (centre
bearing and half-width in the vessel's body frame, 0 right ahead and +90 to port; COLREG 1972 Rule 21: masthead
225°, sidelights 112.5° each from right ahead to 22.5° abaft the beam, sternlight 135° about right astern). A
material's id is its index in the table; id 0 is ``class_default``: the shading falls back to the semantic class
colour (maps, user meshes without materials).

The built-in values are typical PBR values from common PBR charts (the Physically Based database,
physicallybased.info; the Substance/Allegorithmic PBR guide's albedo chart; glTF sample materials) converted to
linear RGB, rounded: dielectric paints and plastics have albedo 0.02-0.85 and metallic 0, bare metals their
measured specular colour with metallic 1. They are plausible, not measured on a particular ship.

User meshes (glTF/GLB through trimesh, :mod:`mmusv.world.vessels`) add theirs with :func:`register_material`;
:func:`material_table` is the ``(M, 11)`` float32 array the renderer takes (:meth:`mmusv.Scene.set_materials`).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from mmusv.errors import ConfigError

__all__ = [
    "BUILTIN_COUNT",
    "COLREG_INTENSITY_CD",
    "COLREG_RANGE_INTENSITY_CD",
    "LAMP_KINDS",
    "LANTERN_LENS_AREA_M2",
    "LANTERN_SIZE_M",
    "MATERIALS",
    "NAV_LAMP_RADIANCE",
    "Material",
    "all_materials",
    "colreg_range_nm",
    "lamp_ids",
    "lamp_material",
    "lamp_of",
    "lantern_lens_area",
    "material_id",
    "material_table",
    "register_material",
]

LANTERN_SIZE_M = 0.3
"""Height of a lantern of the default size (``NavLightsPart.size``), m."""

LANTERN_LENS_AREA_M2 = 2.0 * (0.36 * LANTERN_SIZE_M) * (0.57 * LANTERN_SIZE_M)
"""Projected area of the lens of a lantern of the default size (``NavLightsPart.size`` 0.3 m: a lens band of radius
0.36 and height 0.57 of the size, ``parts_super._lantern``) seen from the side, m²."""

COLREG_INTENSITY_CD = {"masthead": 94.0, "sidelight": 12.0, "sternlight": 12.0}
"""Luminous intensity of each built-in lamp material, cd: COLREG 1972 Annex I §8(b), the minimum for the ranges of
visibility Rule 22(a) asks of a vessel of 50 m or more (masthead light 6 nautical miles, sidelights and sternlight
3), on a lantern of the default size. A vessel's lanterns take :func:`lamp_material`: the intensity of its length
on its lantern's size."""


COLREG_RANGE_INTENSITY_CD = {1: 0.9, 2: 4.3, 3: 12.0, 4: 27.0, 5: 52.0, 6: 94.0}
"""COLREG 1972 Annex I §8(b): the minimum luminous intensity (cd) of a navigation light for its range of visibility
in nautical miles (the table of §8(a)'s ``I = 3.43·10⁶ · T · D² · K^−D``, ``T = 2·10⁻⁷`` lux, ``K = 0.8``)."""

LAMP_KINDS = {
    "nav_masthead_white": "masthead",
    "nav_port_red": "sidelight",
    "nav_starboard_green": "sidelight",
    "nav_stern_white": "sternlight",
}
"""The built-in navigation-lamp materials and the light each is under COLREG Rule 22."""


def colreg_range_nm(light: str, length_m: float) -> int:
    """The range of visibility (nautical miles) COLREG 1972 Rule 22 asks of a vessel ``length_m`` long for its
    ``light`` (``masthead``, ``sidelight`` or ``sternlight``): (a) 50 m or more 6, 3, 3; (b) 12 to 50 m 5 (3 under
    20 m), 2, 2; (c) under 12 m 2, 1, 2."""
    if light not in ("masthead", "sidelight", "sternlight"):
        raise ValueError(f"unknown navigation light {light!r}: masthead, sidelight or sternlight")
    if length_m >= 50.0:
        return {"masthead": 6, "sidelight": 3, "sternlight": 3}[light]
    if length_m >= 12.0:
        return {"masthead": 5 if length_m >= 20.0 else 3, "sidelight": 2, "sternlight": 2}[light]
    return {"masthead": 2, "sidelight": 1, "sternlight": 2}[light]


def lantern_lens_area(size: float) -> float:
    """Projected side area (m²) of the lens of a lantern ``size`` metres tall (:data:`LANTERN_LENS_AREA_M2` at the
    default 0.3 m; the lantern scales as a whole)."""
    return LANTERN_LENS_AREA_M2 * (size / LANTERN_SIZE_M) ** 2


def _lamp_radiance(
    colour: tuple[float, float, float], intensity_cd: float, area_m2: float = LANTERN_LENS_AREA_M2
) -> tuple[float, float, float]:
    """The lens radiance (linear sRGB, cd/m²) of the ``colour`` (relative channels) whose luminance, over a lens of
    projected area ``area_m2`` (the default lantern's), gives ``intensity_cd``."""
    luminance = 0.2126 * colour[0] + 0.7152 * colour[1] + 0.0722 * colour[2]
    k = intensity_cd / (area_m2 * luminance)
    return (k * colour[0], k * colour[1], k * colour[2])


_MASTHEAD = _lamp_radiance((1.0, 1.0, 0.92), COLREG_INTENSITY_CD["masthead"])

NAV_LAMP_RADIANCE = _MASTHEAD[0]
"""Emitted radiance of a lit masthead lamp's lens, cd/m² (about 2.6e3: :data:`COLREG_INTENSITY_CD` over
:data:`LANTERN_LENS_AREA_M2`); the other lamps are dimmer, as Annex I asks."""


@dataclass(frozen=True)
class Material:
    """One PBR material (module docstring); checked on construction (``ConfigError`` naming the field)."""

    name: str
    base_color: tuple[float, float, float]
    """Linear RGB albedo in [0, 1]."""
    roughness: float
    """Perceptual roughness in [0.02, 1] (GGX alpha = roughness**2)."""
    metallic: float
    """0 (dielectric) .. 1 (metal)."""
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Emitted radiance, linear RGB, cd/m² scale (a lit masthead lamp is about 2.6e3, :data:`NAV_LAMP_RADIANCE`)."""
    nav_light: bool = False
    """True: emits only on vessels under way (COLREG lights)."""
    arc_deg: tuple[float, float] = (0.0, 180.0)
    """A lamp's horizontal arc: centre bearing in [-180, 180] and half-width in (0, 180] degrees, body frame (0
    right ahead, +90 to port); (0, 180) is all round. Read for ``nav_light`` materials only."""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ConfigError(f"material.name: must be a non-empty string, got {self.name!r}")
        where = f"material {self.name!r}"
        base = _triple(self.base_color, f"{where}.base_color")
        if any(not 0.0 <= c <= 1.0 for c in base):
            raise ConfigError(f"{where}.base_color: must be linear RGB in [0, 1], got {list(base)}")
        emis = _triple(self.emissive, f"{where}.emissive")
        if any(c < 0.0 for c in emis):
            raise ConfigError(f"{where}.emissive: must be >= 0 (cd/m²), got {list(emis)}")
        rough = _number(self.roughness, f"{where}.roughness")
        if not 0.02 <= rough <= 1.0:
            raise ConfigError(f"{where}.roughness: must be in [0.02, 1], got {rough}")
        metal = _number(self.metallic, f"{where}.metallic")
        if not 0.0 <= metal <= 1.0:
            raise ConfigError(f"{where}.metallic: must be in [0, 1], got {metal}")
        object.__setattr__(self, "base_color", base)
        object.__setattr__(self, "emissive", emis)
        object.__setattr__(self, "roughness", rough)
        object.__setattr__(self, "metallic", metal)
        object.__setattr__(self, "nav_light", bool(self.nav_light))
        try:
            centre, half = (_number(v, f"{where}.arc_deg") for v in self.arc_deg)
        except (TypeError, ValueError):
            raise ConfigError(f"{where}.arc_deg: must be [centre, half-width] degrees, got {self.arc_deg!r}") from None
        if not (-180.0 <= centre <= 180.0 and 0.0 < half <= 180.0):
            raise ConfigError(
                f"{where}.arc_deg: centre must be in [-180, 180] and half-width in (0, 180] degrees, got "
                f"{[centre, half]}"
            )
        object.__setattr__(self, "arc_deg", (centre, half))

    def row(self) -> tuple[float, ...]:
        """The material as the 11 numbers of a :func:`material_table` row."""
        nav = 1.0 if self.nav_light else 0.0
        return (*self.base_color, self.roughness, self.metallic, *self.emissive, nav, *self.arc_deg)


def _number(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ConfigError(f"{where}: must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ConfigError(f"{where}: must be finite, got {x}")
    return x


def _triple(value: object, where: str) -> tuple[float, float, float]:
    try:
        items = list(value)  # type: ignore[call-overload]
    except TypeError:
        raise ConfigError(f"{where}: must be three numbers, got {value!r}") from None
    if len(items) != 3:
        raise ConfigError(f"{where}: must be three numbers, got {value!r}")
    a, b, c = (_number(v, where) for v in items)
    return (a, b, c)


def _m(
    name: str,
    rgb: tuple[float, float, float],
    roughness: float,
    metallic: float = 0.0,
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0),
    nav: bool = False,
    arc_deg: tuple[float, float] = (0.0, 180.0),
) -> Material:
    return Material(name, rgb, roughness, metallic, emissive, nav, arc_deg)


_RED = _lamp_radiance((1.0, 0.0, 0.0), COLREG_INTENSITY_CD["sidelight"])
_GREEN = _lamp_radiance((0.0, 1.0, 0.3), COLREG_INTENSITY_CD["sidelight"])
_STERN = _lamp_radiance((1.0, 1.0, 0.92), COLREG_INTENSITY_CD["sternlight"])

# Typical PBR values (linear RGB albedo, roughness, metallic) after the common PBR charts named in the module
# docstring: marine paints are semi-gloss dielectrics (roughness 0.35-0.6), antifouling is matt, bare metals use
# their measured specular colour (aluminium 0.91/0.92/0.92, steel 0.56/0.57/0.58).
MATERIALS: tuple[Material, ...] = (
    _m("class_default", (0.5, 0.5, 0.5), 0.5),
    # hull paint, topsides
    _m("hull_black", (0.025, 0.025, 0.027), 0.4),
    _m("hull_navy", (0.018, 0.035, 0.10), 0.4),
    _m("hull_blue", (0.02, 0.09, 0.30), 0.4),
    _m("hull_white", (0.80, 0.80, 0.78), 0.35),
    _m("hull_grey", (0.22, 0.24, 0.26), 0.5),  # naval haze grey
    _m("hull_red", (0.38, 0.02, 0.02), 0.4),
    _m("hull_green", (0.02, 0.16, 0.06), 0.4),
    _m("hull_orange", (0.85, 0.22, 0.015), 0.4),  # pilot/rescue/tug orange
    # below and at the waterline
    _m("antifouling_red", (0.30, 0.035, 0.02), 0.75),
    _m("boot_top", (0.015, 0.015, 0.015), 0.5),
    # superstructure and decks
    _m("superstructure_white", (0.78, 0.78, 0.75), 0.4),
    _m("paint_cream", (0.70, 0.62, 0.45), 0.45),
    _m("paint_grey", (0.35, 0.36, 0.37), 0.5),
    _m("paint_yellow", (0.80, 0.55, 0.02), 0.45),  # cranes, safety yellow
    _m("paint_orange", (0.85, 0.30, 0.02), 0.45),
    _m("paint_red", (0.50, 0.03, 0.02), 0.45),
    _m("paint_blue", (0.03, 0.12, 0.40), 0.45),
    _m("paint_green", (0.03, 0.20, 0.06), 0.45),
    _m("deck_steel", (0.16, 0.17, 0.17), 0.7),
    _m("deck_green", (0.04, 0.14, 0.06), 0.7),  # green non-slip deck paint
    _m("deck_red", (0.22, 0.04, 0.03), 0.7),  # red-oxide deck paint
    _m("deck_wood", (0.28, 0.15, 0.07), 0.75),  # teak
    _m("glass", (0.02, 0.025, 0.03), 0.05),
    _m("rubber", (0.02, 0.02, 0.02), 0.9),  # fenders, tyres
    _m("inflatable_grey", (0.13, 0.14, 0.15), 0.6),  # hypalon tubes and pontoons
    _m("aluminium", (0.91, 0.92, 0.92), 0.35, 1.0),
    _m("steel", (0.56, 0.57, 0.58), 0.45, 1.0),
    _m("fibreglass_white", (0.82, 0.82, 0.80), 0.25),  # gelcoat
    # containers
    _m("container_red", (0.40, 0.05, 0.03), 0.6),
    _m("container_blue", (0.03, 0.10, 0.35), 0.6),
    _m("container_green", (0.04, 0.22, 0.08), 0.6),
    _m("container_grey", (0.40, 0.41, 0.42), 0.6),
    _m("container_orange", (0.75, 0.25, 0.03), 0.6),
    _m("container_white", (0.75, 0.75, 0.72), 0.6),
    _m("container_brown", (0.20, 0.08, 0.04), 0.6),
    _m("container_yellow", (0.75, 0.55, 0.03), 0.6),
    # funnel bands
    _m("funnel_black", (0.02, 0.02, 0.02), 0.6),  # soot band
    _m("funnel_red", (0.55, 0.03, 0.02), 0.45),
    _m("funnel_blue", (0.02, 0.10, 0.40), 0.45),
    _m("funnel_yellow", (0.80, 0.60, 0.03), 0.45),
    # lifesaving, rigging
    _m("lifeboat_orange", (0.90, 0.25, 0.02), 0.5),
    _m("sail_cloth", (0.85, 0.84, 0.80), 0.8),
    _m("rope_canvas", (0.50, 0.45, 0.35), 0.9),
    # sensors
    _m("sensor_housing", (0.06, 0.06, 0.065), 0.35),  # dark plastic radome / LiDAR housing
    # COLREG navigation lights: emissive only on vessels under way, across their Rule 21 arcs
    _m("nav_masthead_white", (0.80, 0.80, 0.80), 0.1, 0.0, _MASTHEAD, True, (0.0, 112.5)),
    # COLREG sidelights: red, and a bluish green inside Annex I §7's green area (CIE x, y = 0.265, 0.475), with no
    # light at all in the other channels (a faint share there would still saturate under a night exposure and draw
    # the lamp white).
    _m("nav_port_red", (0.60, 0.02, 0.02), 0.1, 0.0, _RED, True, (56.25, 56.25)),
    _m("nav_starboard_green", (0.02, 0.50, 0.20), 0.1, 0.0, _GREEN, True, (-56.25, 56.25)),
    _m("nav_stern_white", (0.80, 0.80, 0.80), 0.1, 0.0, _STERN, True, (180.0, 67.5)),
)
"""The built-in materials; a material's id is its index (:func:`all_materials` adds the registered ones)."""

BUILTIN_COUNT = len(MATERIALS)
"""Number of built-in materials (ids ``0 .. BUILTIN_COUNT-1``)."""

_lock = threading.Lock()
_all: list[Material] = list(MATERIALS)
_ids: dict[str, int] = {m.name: i for i, m in enumerate(MATERIALS)}
_MAX = 65535


def all_materials() -> tuple[Material, ...]:
    """Every material of this process, built-in then registered; a material's id is its index."""
    with _lock:
        return tuple(_all)


def material_id(name: str) -> int:
    """The id of the material called ``name``; an unknown name raises :class:`mmusv.ConfigError` listing them."""
    with _lock:
        if name in _ids:
            return _ids[name]
        known = ", ".join(m.name for m in _all)
    raise ConfigError(f"unknown material {name!r}; known materials: {known}")


def register_material(m: Material) -> int:
    """Adds ``m`` to the table (user meshes, glTF PBR) and returns its id; the same material again returns the
    same id. A different material under a name already taken raises :class:`mmusv.ConfigError`."""
    if not isinstance(m, Material):
        raise TypeError(f"register_material() takes a Material, got {type(m).__name__}")
    with _lock:
        if m.name in _ids:
            i = _ids[m.name]
            if _all[i] == m:
                return i
            raise ConfigError(f"material {m.name!r} is already registered with other values")
        if len(_all) > _MAX:
            raise ConfigError(f"the material table is full ({_MAX + 1} materials)")
        _all.append(m)
        _ids[m.name] = len(_all) - 1
        return len(_all) - 1


def material_table() -> np.ndarray:
    """``(M, 11)`` float32, one row per material id: r, g, b (linear albedo), roughness, metallic, er, eg, eb
    (emitted radiance, cd/m² scale), nav_light (0/1), arc centre and half-width (degrees, body frame)."""
    with _lock:
        rows = [m.row() for m in _all]
    return np.asarray(rows, dtype=np.float32).reshape(-1, 11)


def lamp_material(lamp: str, *, length_m: float, lantern_size: float) -> int:
    """The id of built-in navigation lamp ``lamp`` (a name of :data:`LAMP_KINDS`) as a vessel ``length_m`` long
    shows it on a lantern ``lantern_size`` metres tall: its lens radiance gives the COLREG Annex I §8 intensity of
    the range Rule 22 asks of that length (:func:`colreg_range_nm`) over that lantern's lens, so a lamp's intensity
    follows the vessel's length and not its lantern's size. The built-in material itself where that is its own
    (50 m or more on the default 0.3 m lantern); otherwise a material ``"<lamp>@<cd>cd/<size>m"`` registered once
    per process (its id may differ between processes; its values never do)."""
    if lamp not in LAMP_KINDS:
        raise ValueError(f"unknown navigation lamp {lamp!r}: one of {', '.join(LAMP_KINDS)}")
    base = MATERIALS[_ids[lamp]]
    cd = COLREG_RANGE_INTENSITY_CD[colreg_range_nm(LAMP_KINDS[lamp], length_m)]
    if lantern_size == LANTERN_SIZE_M and cd == COLREG_INTENSITY_CD[LAMP_KINDS[lamp]]:
        return _ids[lamp]
    e = base.emissive
    peak = max(e)
    colour = (e[0] / peak, e[1] / peak, e[2] / peak)
    return register_material(
        Material(
            f"{lamp}@{cd:g}cd/{lantern_size:g}m",
            base.base_color,
            base.roughness,
            base.metallic,
            _lamp_radiance(colour, cd, lantern_lens_area(lantern_size)),
            True,
            base.arc_deg,
        )
    )


def lamp_of(m: Material) -> str | None:
    """The built-in navigation lamp (a name of :data:`LAMP_KINDS`) that ``m`` is or is a variant of
    (:func:`lamp_material`), else ``None``."""
    name = m.name.split("@", 1)[0]
    return name if m.nav_light and name in LAMP_KINDS else None


def lamp_ids(lamp: str) -> tuple[int, ...]:
    """The ids of every material of this process that is built-in navigation lamp ``lamp`` or a variant of it
    (:func:`lamp_of`), sorted: ``numpy.isin(mesh.materials, lamp_ids(lamp))`` marks a mesh's faces of that lamp."""
    with _lock:
        table = list(_all)
    return tuple(i for i, m in enumerate(table) if lamp_of(m) == lamp)
