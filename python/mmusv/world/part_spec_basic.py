"""The schema of the basic superstructure parts, those the vessel assembly (:mod:`mmusv.world.vessel_shapes`) builds
itself: blocks following the deck, rows of boxes, vertical and horizontal cylinders, struts, plates, gantries and
gun turrets. Fields and limits as in :mod:`mmusv.world.part_fields`; :mod:`mmusv.world.part_spec` joins every
part model into one type.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from mmusv.validation import Whole, invalid_field, sequence
from mmusv.world.part_fields import (
    MAX_ITEMS,
    MAX_PIECES,
    Along,
    Angle,
    Coord,
    Gap,
    Part,
    Placed,
    Point2,
    Point3,
    Segments,
    Size,
    Span,
    Taper,
    profile_area,
)

__all__ = [
    "CylinderPart",
    "GantryPart",
    "GunPart",
    "HcylinderPart",
    "HullBlockPart",
    "PlatePart",
    "RowPart",
    "StrutPart",
]


class HullBlockPart(Along, Span):
    """A block following the deck outline between ``x0`` and ``x1``, ``inset`` metres inside it (mono hulls)."""

    type: Literal["hull_block"]
    inset: Gap = 0.0
    taper: Taper = 1.0


class RowPart(Along):
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


class CylinderPart(Placed, Span):
    """A vertical cylinder (a cone frustum with ``top_radius``)."""

    type: Literal["cylinder"]
    radius: Size
    top_radius: Size | None = None
    segments: Segments = 12


class HcylinderPart(Along):
    """A horizontal cylinder along x from ``x0`` to ``x1``, axis at ``(y, z)``."""

    type: Literal["hcylinder"]
    y: Coord = 0.0
    z: Coord
    radius: Size
    segments: Segments = 12


class StrutPart(Part):
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


class PlatePart(Part):
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


class GantryPart(Span):
    """An A-frame or portal of two legs ``span`` apart, leaning ``lean`` metres forward, and a crossbeam."""

    type: Literal["gantry"]
    x: Coord
    span: Size
    leg: Size = 0.5
    lean: Coord = 0.0


class GunPart(Placed):
    """A gun turret of ``radius`` and ``height`` with a ``barrel`` pointing along ``yaw_deg``/``elevation_deg``."""

    type: Literal["gun"]
    base: Coord | None = None
    radius: Size
    height: Size
    barrel: Size
    yaw_deg: Angle = 0.0
    elevation_deg: Angle = 5.0
