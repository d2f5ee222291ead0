"""The schema of the superstructure part families built by :mod:`mmusv.world.parts_super`: boxes, deckhouses,
funnels, masts, domes, deck cranes, window bands, navigation lights, radar scanners and antennas. Fields and
limits as in :mod:`mmusv.world.part_fields`; :mod:`mmusv.world.part_spec` joins every part model into one type.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from mmusv.validation import Fraction, Vec3, Whole, invalid_field, sequence
from mmusv.world.materials import LANTERN_SIZE_M
from mmusv.world.part_fields import (
    MAX_EXTENT,
    MAX_ITEMS,
    MIN_SIZE,
    Along,
    Angle,
    Coord,
    Gap,
    MaterialName,
    Part,
    Placed,
    Point3,
    Segments,
    Side,
    Size,
    Size2,
    Span,
    Taper,
    WindowBand,
)

__all__ = [
    "AntennasPart",
    "BoxPart",
    "CranePart",
    "DomePart",
    "FunnelPart",
    "HousePart",
    "MastPart",
    "NavLightsPart",
    "RadarPart",
    "WindowsPart",
]


class BoxPart(Placed, Span):
    """A box, optionally tapered towards the top and turned by ``yaw_deg``."""

    type: Literal["box"]
    size: Size2
    fit: Gap | None = None
    taper: Taper = 1.0
    yaw_deg: Angle = 0.0
    windows: WindowBand | None = None
    """``[width, height, pitch]`` of a window band round the box (not with ``yaw_deg``)."""


class HousePart(Placed):
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


class FunnelPart(Placed, Span):
    """A funnel, square (``shape: box``) or elliptic (``shape: round``) in plan, narrowing by ``taper``."""

    type: Literal["funnel"]
    size: Size2
    taper: Taper = 0.9
    shape: Literal["box", "round"] = "box"
    band: MaterialName | None = None
    """A company colour band around the upper funnel (below the black top)."""
    pipes: Annotated[Whole, Field(ge=0, le=6)] = 2
    """Exhaust pipes standing out of the top."""


class MastPart(Placed, Span):
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


class DomePart(Placed):
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


class CranePart(Placed):
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


class WindowsPart(Along):
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


class NavLightsPart(Part):
    """COLREG navigation lights as small lanterns: ``masthead`` white (a list of ``[x, y, z]``; default: below the
    top of the tallest mast, and of the second tallest too from 50 m of hull length, Rule 23(a)(ii); ``[]``: none,
    as a sailing vessel under sail, a vessel under oars or a towed one shows, Rules 24(e) and 25), ``sides`` red to
    port and green to starboard at ``[x, |y|, z]`` (default: on the bridge wings, else at the bow), ``stern`` white
    at ``[x, y, z]`` (default: on the transom); ``size`` is the lantern's height. Each lamp has the intensity COLREG
    Rule 22 and Annex I §8 ask of the hull's length, whatever the lantern's size (under 12 m: masthead 4.3 cd,
    sidelights 0.9, sternlight 4.3; 12–50 m: 12 cd under 20 m and 52 cd from 20 m, 4.3, 4.3; 50 m and over: 94,
    12, 12)."""

    type: Literal["nav_lights"]
    masthead: Annotated[tuple[Point3, ...], sequence(0, MAX_ITEMS, f"a list of 0 to {MAX_ITEMS} points")] | None = None
    sides: Point3 | None = None
    stern: Point3 | None = None
    size: Size = LANTERN_SIZE_M


class RadarPart(Placed):
    """A radar scanner: pedestal and gearbox on ``base`` with an open-array antenna ``length`` long turned by
    ``yaw_deg``."""

    type: Literal["radar"]
    base: Coord
    length: Size = 2.0
    yaw_deg: Angle = 0.0


class AntennasPart(Part):
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
            if a[3] <= 4.0 * self.radius:  # the whip rises from the top of its base mount, 4 radii tall
                raise invalid_field(
                    f"at[{i}][3]",
                    f"height {a[3]:g} m must be more than 4 x radius ({4.0 * self.radius:g} m, the height of the "
                    "antenna's base mount, above which the whip rises): a taller antenna or a smaller radius",
                )
        return self
