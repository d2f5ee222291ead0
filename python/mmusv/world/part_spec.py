"""The schema of a procedural vessel's superstructure parts: one frozen pydantic model per part ``type``.

Numbers are metres (degrees where the key ends in ``_deg``) in the vessel body frame (x forward, y left, z up,
z = 0 at the waterline, x from midship). ``base`` defaults to the deck height at the part's x, so a part's vertical
extent is checked against the deck by the mesh builder (:mod:`mmusv.world.vessel_shapes`), which also checks
``fit`` and the hull footprint; everything a part says about itself is checked here. The vocabulary is listed in
:mod:`mmusv.world.asset_spec`.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Sequence
from typing import Annotated, Literal

import numpy as np
from pydantic import BeforeValidator, Field, model_validator

from mmusv.errors import ConfigError
from mmusv.validation import (
    Fraction,
    Number,
    Spec,
    Vec3,
    Whole,
    invalid,
    invalid_field,
    sequence,
)
from mmusv.world.materials import material_id

__all__ = [
    "DEFAULT_MATERIALS",
    "MAX_EXTENT",
    "MAX_ITEMS",
    "MAX_PIECES",
    "MIN_SIZE",
    "PART_MODELS",
    "TAPER_RANGE",
    "AntennasPart",
    "BollardsPart",
    "BoxPart",
    "ContainersPart",
    "CranePart",
    "CylinderPart",
    "DomePart",
    "FendersPart",
    "FunnelPart",
    "GantryPart",
    "GunPart",
    "HatchesPart",
    "HcylinderPart",
    "HousePart",
    "HullBlockPart",
    "LifeboatsPart",
    "MastPart",
    "MaterialName",
    "NavLightsPart",
    "PartSpec",
    "PipesPart",
    "PlatePart",
    "RadarPart",
    "RailingPart",
    "RowPart",
    "StrutPart",
    "TubePart",
    "WinchPart",
    "WindowsPart",
    "profile_area",
]


def _material_name(value: object) -> object:
    if not isinstance(value, str):
        raise invalid(f"must be a material name (mmusv.world.materials), got {value!r}")
    try:
        material_id(value)
    except ConfigError as exc:
        raise invalid(str(exc)) from None
    return value


MaterialName = Annotated[str, BeforeValidator(_material_name)]
"""The name of a material of :mod:`mmusv.world.materials` (checked)."""

Side = Literal["both", "port", "starboard"]
"""Which side of the vessel a sided part goes on (port = +y)."""

MIN_SIZE = 0.001
"""The smallest size (metres) of a part: a radius, width, height, thickness, ... (1 mm; smaller pieces would have
near-zero-area faces)."""

MAX_EXTENT = 500.0
"""The largest coordinate or size (metres, either sign) of a part: the largest asset is 500 m
(:data:`mmusv.world.asset_spec.DIMENSION_RANGES`), so nothing beyond this can lie on a valid asset."""

TAPER_RANGE = (0.05, 2.0)
"""The allowed ``taper`` of a part (top size over base size)."""

MAX_PIECES = 20000
"""The most repeated pieces (boxes of a row, hatch covers, stanchions, windows, containers, supports, ...) one part
may make."""

MAX_ITEMS = 200
"""The most items of a part's list (``tiers``, ``heights``, ``points``, ``at``, ``masthead``, ``ys``): each item
is a piece (or a vertex), so an unbounded list would be an unbounded mesh."""

Coord = Annotated[Number, Field(ge=-MAX_EXTENT, le=MAX_EXTENT)]
"""A body-frame coordinate in metres, within :data:`MAX_EXTENT` of the origin."""
Size = Annotated[Number, Field(ge=MIN_SIZE, le=MAX_EXTENT)]
"""A length of a part in metres, :data:`MIN_SIZE` to :data:`MAX_EXTENT`."""
Gap = Annotated[Number, Field(ge=0.0, le=MAX_EXTENT)]
"""A clearance or inset in metres, 0 to :data:`MAX_EXTENT`."""
Angle = Annotated[Number, Field(ge=-360.0, le=360.0)]
"""An angle in degrees, -360 to 360."""
Taper = Annotated[Number, Field(ge=TAPER_RANGE[0], le=TAPER_RANGE[1])]
"""A part's taper (top over base size), within :data:`TAPER_RANGE`."""
Size2 = Annotated[tuple[Size, ...], sequence(2, 2, "a list of 2 sizes")]
"""Two sizes (a YAML list)."""
Point2 = Annotated[tuple[Coord, ...], sequence(2, 2, "a list of 2 numbers")]
"""A point ``[x, z]`` (a YAML list)."""
Point3 = Annotated[tuple[Coord, ...], sequence(3, 3, "a list of 3 numbers")]
"""A body-frame point ``[x, y, z]`` (a YAML list)."""

WindowBand = Annotated[tuple[Size, ...], sequence(3, 3, "a list of 3 numbers > 0: [width, height, pitch]")]
"""``[width, height, pitch]`` of a window band, metres."""


def profile_area(points: Sequence[Sequence[float]] | np.ndarray) -> float:
    """Signed area (m², > 0 anticlockwise) of a closed polygon ``points`` ``(N, 2)`` (shoelace formula)."""
    pts = np.asarray(points, dtype=np.float64)
    d = np.roll(pts, -1, axis=0)
    return 0.5 * float(np.sum(pts[:, 0] * d[:, 1] - d[:, 0] * pts[:, 1]))


class _Part(Spec):
    """Every part: ``material`` (a name of :mod:`mmusv.world.materials`; default: :data:`DEFAULT_MATERIALS`)."""

    material: MaterialName | None = None


class _Span(_Part):
    """A part standing from ``base`` (default: the deck at the part's x) up to ``top`` or ``base + height``."""

    base: Coord | None = None
    top: Coord | None = None
    height: Size | None = None

    @model_validator(mode="after")
    def _one_top(self) -> _Span:
        if (self.top is None) == (self.height is None):
            raise invalid_field("top", "give exactly one of top (absolute z, m) or height (m above base)")
        if self.top is not None and self.base is not None and self.top <= self.base:
            raise invalid_field("top", f"top {self.top:g} m must be above the base {self.base:g} m")
        return self


class _Along(_Part):
    """A part spanning ``x0`` to ``x1`` along the hull (``x1 > x0``)."""

    x0: Coord
    x1: Coord

    @model_validator(mode="after")
    def _ordered(self) -> _Along:
        if self.x1 <= self.x0:
            raise invalid_field("x1", f"must be > x0 ({self.x0}), got {self.x1}")
        return self


class _Placed(_Part):
    """A part standing at ``(x, y)`` in the body frame (metres)."""

    x: Coord
    y: Coord = 0.0


class BoxPart(_Placed, _Span):
    """A box, optionally tapered towards the top and turned by ``yaw_deg``."""

    type: Literal["box"]
    size: Size2
    fit: Gap | None = None
    taper: Taper = 1.0
    yaw_deg: Angle = 0.0
    windows: WindowBand | None = None
    """``[width, height, pitch]`` of a window band round the box (not with ``yaw_deg``)."""


class HousePart(_Placed):
    """A deckhouse of stacked tiers ``[lx, ly, h(, dx)]`` aligned at ``x``, with optional bridge ``wings``."""

    type: Literal["house"]
    align: Literal["center", "aft", "fore"] = "center"
    windows: WindowBand | None = None
    """``[width, height, pitch]`` of the window bands on every tier (the top tier's front gets a bridge band)."""
    taper: Taper = 1.0
    tiers: Annotated[
        tuple[Annotated[tuple[Coord, ...], sequence(3, 4, "a list of 3 to 4 numbers")], ...],
        sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} lists"),
    ]
    base: Coord | None = None
    fit: Gap | None = None
    wings: Size2 | None = None

    @model_validator(mode="after")
    def _tier_sizes(self) -> HousePart:
        for i, tier in enumerate(self.tiers):
            for j, what in enumerate(("lx", "ly", "h")):
                if not MIN_SIZE <= tier[j] <= MAX_EXTENT:
                    raise invalid_field(
                        f"tiers[{i}][{j}]", f"{what} must be {MIN_SIZE:g} to {MAX_EXTENT:g} m, got {tier[j]:g}"
                    )
        return self


class HullBlockPart(_Along, _Span):
    """A block following the deck outline between ``x0`` and ``x1``, ``inset`` metres inside it (mono hulls)."""

    type: Literal["hull_block"]
    inset: Gap = 0.0
    taper: Taper = 1.0


class RowPart(_Along):
    """``count`` boxes in a row from ``x0`` to ``x1`` with ``gap`` between them, heights cycled from ``heights``."""

    type: Literal["row"]
    count: Annotated[Whole, Field(ge=1, le=MAX_PIECES)]
    gap: Gap = 0.0
    y: Coord = 0.0
    width: Size
    heights: Annotated[tuple[Size, ...], sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} numbers")]
    base: Coord | None = None
    fit: Gap | None = None

    @model_validator(mode="after")
    def _fits(self) -> RowPart:
        if self.x1 - self.x0 - self.gap * (self.count - 1) <= 0.0:
            raise invalid_field("count", f"{self.count} boxes with gap {self.gap:g} do not fit between x0 and x1")
        return self


class FunnelPart(_Placed, _Span):
    """A funnel, square (``shape: box``) or elliptic (``shape: round``) in plan, narrowing by ``taper``."""

    type: Literal["funnel"]
    size: Size2
    taper: Taper = 0.9
    shape: Literal["box", "round"] = "box"
    band: MaterialName | None = None
    """A company colour band around the upper funnel (below the black top)."""
    pipes: Annotated[Whole, Field(ge=0, le=6)] = 2
    """Exhaust pipes standing out of the top."""


class MastPart(_Placed, _Span):
    """A square mast of side ``width``, with a crosswise ``yard`` at fraction ``yard_at`` of its height."""

    type: Literal["mast"]
    width: Size = 0.3
    yard: Gap = 0.0
    yard_at: Fraction = 0.8

    @model_validator(mode="after")
    def _yard(self) -> MastPart:
        if 0.0 < self.yard < MIN_SIZE:
            raise invalid_field("yard", f"must be 0 (no yard) or {MIN_SIZE:g} to {MAX_EXTENT:g} m, got {self.yard:g}")
        return self


Segments = Annotated[Whole, Field(ge=3, le=64)]
"""Facets around a round part."""


class CylinderPart(_Placed, _Span):
    """A vertical cylinder (a cone frustum with ``top_radius``)."""

    type: Literal["cylinder"]
    radius: Size
    top_radius: Size | None = None
    segments: Segments = 12


class HcylinderPart(_Along):
    """A horizontal cylinder along x from ``x0`` to ``x1``, axis at ``(y, z)``."""

    type: Literal["hcylinder"]
    y: Coord = 0.0
    z: Coord
    radius: Size
    segments: Segments = 12


class DomePart(_Placed):
    """A sphere cap of ``radius`` with its top at ``top``, on a skirt down to ``base``."""

    type: Literal["dome"]
    radius: Size
    top: Coord
    base: Coord | None = None
    segments: Segments = 16

    @model_validator(mode="after")
    def _above_base(self) -> DomePart:
        if self.base is not None and self.base >= self.top:
            raise invalid_field("top", f"top {self.top:g} m must be above the base {self.base:g} m")
        return self


class StrutPart(_Part):
    """A beam of ``width`` x ``thickness`` from ``from`` to ``to`` (absolute body-frame points)."""

    type: Literal["strut"]
    start: Point3 = Field(alias="from")
    end: Point3 = Field(alias="to")
    width: Size
    thickness: Size | None = None
    """Default: ``width``."""

    @model_validator(mode="after")
    def _long(self) -> StrutPart:
        if math.dist(self.start, self.end) <= 1e-9:
            raise invalid_field("to", "must differ from 'from'")
        return self


class PlatePart(_Part):
    """A convex ``[x, z]`` profile ``points`` extruded ``thickness`` across y, centred at ``y``."""

    type: Literal["plate"]
    y: Coord = 0.0
    thickness: Size
    points: Annotated[tuple[Point2, ...], sequence(3, MAX_ITEMS, f"a list of 3 to {MAX_ITEMS} [x, z] points")]

    @model_validator(mode="after")
    def _area(self) -> PlatePart:
        if abs(profile_area(self.points)) < 1e-9:
            raise invalid_field("points", "profile has zero area")
        return self


class GantryPart(_Span):
    """An A-frame or portal of two legs ``span`` apart, leaning ``lean`` metres forward, and a crossbeam."""

    type: Literal["gantry"]
    x: Coord
    span: Size
    leg: Size = 0.5
    lean: Coord = 0.0


class CranePart(_Placed):
    """A deck crane: ``pedestal [radius, height]``, a cab, and a ``jib [length, elevation_deg, yaw_deg]``."""

    type: Literal["crane"]
    base: Coord | None = None
    pedestal: Size2
    jib: Vec3
    width: Size = 0.6

    @model_validator(mode="after")
    def _jib(self) -> CranePart:
        if not MIN_SIZE <= self.jib[0] <= MAX_EXTENT:
            raise invalid_field("jib", f"jib length must be {MIN_SIZE:g} to {MAX_EXTENT:g} m, got {self.jib[0]:g}")
        if not all(-360.0 <= a <= 360.0 for a in self.jib[1:]):
            raise invalid_field("jib", f"jib elevation_deg and yaw_deg must be -360 to 360, got {list(self.jib[1:])}")
        return self


class GunPart(_Placed):
    """A gun turret of ``radius`` and ``height`` with a ``barrel`` pointing along ``yaw_deg``/``elevation_deg``."""

    type: Literal["gun"]
    base: Coord | None = None
    radius: Size
    height: Size
    barrel: Size
    yaw_deg: Angle = 0.0
    elevation_deg: Angle = 5.0


class RailingPart(_Part):
    """Guard rails of stanchions and ``rails`` horizontal rails, ``height`` tall: along the deck edge (``inset``
    inside it) between ``x0`` and ``x1`` (default: the whole hull), joined round the ``bow``/across the ``stern``
    when asked; or, with ``width``, round a rectangle ``x0..x1`` by ``width`` centred at ``y`` on ``base``."""

    type: Literal["railing"]
    x0: Coord | None = None
    x1: Coord | None = None
    side: Side = "both"
    inset: Gap = 0.1
    height: Size = 1.0
    spacing: Size = 1.5
    rails: Annotated[Whole, Field(ge=1, le=5)] = 2
    base: Coord | None = None
    width: Size | None = None
    y: Coord = 0.0
    bow: bool = False
    stern: bool = False
    radius: Size | None = None
    """Tube radius (default ``0.02 + 0.01 * height``)."""
    posts: bool = True
    """False: rails alone (a rubbing strake or fender band along the sheer, with ``lift`` below the deck edge)."""
    lift: Coord = 0.0
    """Metres the whole railing is raised above (negative: lowered below) its deck line or ``base``."""

    @model_validator(mode="after")
    def _span(self) -> RailingPart:
        if self.x0 is not None and self.x1 is not None and self.x1 <= self.x0:
            raise invalid_field("x1", f"must be > x0 ({self.x0}), got {self.x1}")
        if self.width is not None and (self.x0 is None or self.x1 is None or self.base is None):
            raise invalid_field("width", "a rectangular railing needs x0, x1 and base")
        return self


class WindowsPart(_Along):
    """A band of windows (raised glass in a frame) from ``x0`` to ``x1``: ``rows`` rows ``row_pitch`` apart from
    ``z`` (bottom of the lowest row), each window ``width`` x ``height`` every ``pitch`` metres, on a wall at
    ``|y| = y`` or, without ``y``, on the deck outline ``inset`` inside it (``wall: outline``) or on the hull's side
    (``wall: hull``); ``shape: round`` makes portholes."""

    type: Literal["windows"]
    z: Coord
    width: Size
    height: Size
    pitch: Size
    rows: Annotated[Whole, Field(ge=1, le=40)] = 1
    row_pitch: Size = 2.8
    side: Side = "both"
    y: Size | None = None
    inset: Gap = 0.0
    wall: Literal["outline", "hull"] = "outline"
    shape: Literal["rect", "round"] = "rect"

    @model_validator(mode="after")
    def _pitch(self) -> WindowsPart:
        if self.pitch < self.width:
            raise invalid_field("pitch", f"must be >= width ({self.width}), got {self.pitch}")
        return self


class ContainersPart(_Along):
    """Container stacks: ``bays`` bays from ``x0`` to ``x1`` (``gap`` between bays), ``rows`` containers across a
    stack ``width`` wide, ``tiers`` high per bay (cycled), each box its own colour (a fixed hash of its slot and
    ``seed``); ``height`` is one container's (2.59 m standard); ``fit`` drops outer rows where the hull narrows."""

    type: Literal["containers"]
    bays: Annotated[Whole, Field(ge=1, le=60)]
    rows: Annotated[Whole, Field(ge=1, le=30)]
    tiers: Annotated[
        tuple[Annotated[Whole, Field(ge=1, le=12)], ...],
        sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} whole numbers"),
    ]
    width: Size
    base: Coord | None = None
    gap: Gap = 0.6
    height: Size = 2.59
    seed: Annotated[Whole, Field(ge=0, le=2**32 - 1)] = 0
    fit: Gap | None = None
    """Drop outer rows of a bay (keeping it centred) until it stays ``fit`` metres inside the deck outline."""


class HatchesPart(_Along):
    """``count`` hatch covers on coamings from ``x0`` to ``x1`` (``gap`` apart), ``width`` across (narrowed by
    ``fit``), ``height`` from ``base`` to the cover top, each cover with ``ribs`` transverse stiffeners."""

    type: Literal["hatches"]
    count: Annotated[Whole, Field(ge=1, le=MAX_PIECES)]
    gap: Gap = 0.0
    width: Size
    height: Size
    base: Coord | None = None
    fit: Gap | None = None
    ribs: Annotated[Whole, Field(ge=0, le=40)] = 6


class LifeboatsPart(_Placed):
    """``count`` enclosed lifeboats ``length`` long every ``pitch`` metres aft from ``x`` at ``|y| = y`` with the
    keel at ``z`` and a davit pair each (``kind: davit``); or one free-fall boat on a stern ramp at ``x``
    (``kind: freefall``, on the centreline)."""

    type: Literal["lifeboats"]
    z: Coord
    length: Size
    count: Annotated[Whole, Field(ge=1, le=12)] = 1
    pitch: Gap = 0.0
    side: Side = "both"
    kind: Literal["davit", "freefall"] = "davit"


class FendersPart(_Along):
    """``count`` fenders hung on the hull side between ``x0`` and ``x1`` with their centres at ``z``: tyres
    (``kind: tyre``, outer ``radius``) or rubber cylinders (``kind: cylinder``); all within the beam."""

    type: Literal["fenders"]
    count: Annotated[Whole, Field(ge=1, le=80)]
    z: Coord
    radius: Size
    side: Side = "both"
    kind: Literal["tyre", "cylinder"] = "tyre"


class NavLightsPart(_Part):
    """COLREG navigation lights as small lanterns: ``masthead`` white (a list of ``[x, y, z]``; default: below the
    top of the tallest mast, and of the second tallest too from 50 m of hull length, Rule 23(a)(ii); ``[]``: none,
    as a sailing vessel under sail, a vessel under oars or a towed one shows, Rules 24(e) and 25), ``sides`` red to
    port and green to starboard at ``[x, |y|, z]`` (default: on the bridge wings, else at the bow), ``stern`` white
    at ``[x, y, z]`` (default: on the transom); ``size`` is the lantern's height."""

    type: Literal["nav_lights"]
    masthead: Annotated[tuple[Point3, ...], sequence(0, MAX_ITEMS, f"a list of 0 to {MAX_ITEMS} points")] | None = None
    sides: Point3 | None = None
    stern: Point3 | None = None
    size: Size = 0.3


class RadarPart(_Placed):
    """A radar scanner: pedestal and gearbox on ``base`` with an open-array antenna ``length`` long turned by
    ``yaw_deg``."""

    type: Literal["radar"]
    base: Coord
    length: Size = 2.0
    yaw_deg: Angle = 0.0


class AntennasPart(_Part):
    """Whip antennas: one per ``[x, y, z, height]`` of ``at`` (standing on z), tube ``radius``."""

    type: Literal["antennas"]
    at: Annotated[
        tuple[Annotated[tuple[Coord, ...], sequence(4, 4, "[x, y, z, height]")], ...],
        sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} items"),
    ]
    radius: Size = 0.03

    @model_validator(mode="after")
    def _heights(self) -> AntennasPart:
        for i, a in enumerate(self.at):
            if not MIN_SIZE <= a[3] <= MAX_EXTENT:
                raise invalid_field(f"at[{i}][3]", f"height must be {MIN_SIZE:g} to {MAX_EXTENT:g} m, got {a[3]:g}")
        return self


class BollardsPart(_Along):
    """``count`` double bollards per side from ``x0`` to ``x1``, ``inset`` inside the deck edge, post ``radius``."""

    type: Literal["bollards"]
    count: Annotated[Whole, Field(ge=1, le=40)]
    inset: Gap = 0.8
    radius: Size = 0.2
    side: Side = "both"


class TubePart(_Part):
    """A round tube (``segments``-gon) of ``radius`` (to ``end_radius``) from ``from`` to ``to`` (absolute points):
    booms, derricks, pipes, bow fenders."""

    type: Literal["tube"]
    start: Point3 = Field(alias="from")
    end: Point3 = Field(alias="to")
    radius: Size
    end_radius: Size | None = None
    segments: Segments = 12

    @model_validator(mode="after")
    def _long(self) -> TubePart:
        if math.dist(self.start, self.end) <= 1e-9:
            raise invalid_field("to", "must differ from 'from'")
        return self


class PipesPart(_Along):
    """A pipe rack: pipes along x at each of ``ys`` at height ``z`` on supports every ``support`` metres."""

    type: Literal["pipes"]
    ys: Annotated[tuple[Coord, ...], sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} numbers")]
    z: Coord
    radius: Size = 0.2
    support: Size = 6.0
    base: Coord | None = None


class WinchPart(_Placed):
    """A winch: a drum of ``radius`` and ``width`` (across y) between two cheek plates on ``base``."""

    type: Literal["winch"]
    base: Coord | None = None
    radius: Size
    width: Size


PartSpec = Annotated[
    BoxPart
    | HousePart
    | HullBlockPart
    | RowPart
    | FunnelPart
    | MastPart
    | CylinderPart
    | HcylinderPart
    | DomePart
    | StrutPart
    | PlatePart
    | GantryPart
    | CranePart
    | GunPart
    | RailingPart
    | WindowsPart
    | ContainersPart
    | HatchesPart
    | LifeboatsPart
    | FendersPart
    | NavLightsPart
    | RadarPart
    | AntennasPart
    | BollardsPart
    | TubePart
    | PipesPart
    | WinchPart,
    Field(discriminator="type"),
]
"""One superstructure part, chosen by its ``type``."""

PART_MODELS: dict[str, type[Spec]] = {
    typing.get_args(m.model_fields["type"].annotation)[0]: m for m in typing.get_args(typing.get_args(PartSpec)[0])
}
"""Part ``type`` -> its model."""

DEFAULT_MATERIALS: dict[str, str] = {
    "box": "superstructure_white",
    "house": "superstructure_white",
    "hull_block": "<topside>",
    "row": "paint_grey",
    "funnel": "superstructure_white",
    "mast": "paint_cream",
    "cylinder": "paint_grey",
    "hcylinder": "paint_grey",
    "dome": "fibreglass_white",
    "strut": "steel",
    "plate": "paint_grey",
    "gantry": "paint_orange",
    "crane": "paint_yellow",
    "gun": "hull_grey",
    "railing": "steel",
    "windows": "glass",
    "containers": "<per box>",
    "hatches": "paint_red",
    "lifeboats": "lifeboat_orange",
    "fenders": "rubber",
    "nav_lights": "<per lamp>",
    "radar": "superstructure_white",
    "antennas": "fibreglass_white",
    "bollards": "hull_black",
    "tube": "steel",
    "pipes": "steel",
    "winch": "paint_grey",
}
"""Part ``type`` -> the material of its main body when ``material`` is not given. ``<topside>`` is the hull's
topside paint; containers take a colour per box and navigation lights their COLREG lamp materials (their
``material`` is the lantern housing's). Secondary pieces have fixed materials: window frames aluminium, funnel tops
funnel_black, davits steel, crane cab windows glass, radar pedestals paint_grey."""
