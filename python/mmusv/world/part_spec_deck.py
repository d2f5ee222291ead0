"""The schema of the deck gear built by :mod:`mmusv.world.parts_deck`: railings, container stacks, hatch covers,
lifeboats, fenders, bollards, round tubes, pipe racks and winches. Fields and limits as in
:mod:`mmusv.world.part_fields`; :mod:`mmusv.world.part_spec` joins every part model into one type.
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
    Coord,
    Gap,
    Part,
    Placed,
    Point3,
    Segments,
    Side,
    Size,
)

__all__ = [
    "BollardsPart",
    "ContainersPart",
    "FendersPart",
    "HatchesPart",
    "LifeboatsPart",
    "PipesPart",
    "RailingPart",
    "TubePart",
    "WinchPart",
]


class RailingPart(Part):
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


class ContainersPart(Along):
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


class HatchesPart(Along):
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


class LifeboatsPart(Placed):
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


class FendersPart(Along):
    """``count`` fenders hung on the hull side between ``x0`` and ``x1`` with their centres at ``z``: tyres
    (``kind: tyre``, outer ``radius``) or rubber cylinders (``kind: cylinder``); all within the beam."""

    type: Literal["fenders"]
    count: Annotated[Whole, Field(ge=1, le=80)]
    z: Coord
    radius: Size
    side: Side = "both"
    kind: Literal["tyre", "cylinder"] = "tyre"


class BollardsPart(Along):
    """``count`` double bollards per side from ``x0`` to ``x1``, ``inset`` inside the deck edge, post ``radius``."""

    type: Literal["bollards"]
    count: Annotated[Whole, Field(ge=1, le=40)]
    inset: Gap = 0.8
    radius: Size = 0.2
    side: Side = "both"


class TubePart(Part):
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


class PipesPart(Along):
    """A pipe rack: pipes along x at each of ``ys`` at height ``z`` on supports every ``support`` metres."""

    type: Literal["pipes"]
    ys: Annotated[tuple[Coord, ...], sequence(1, MAX_ITEMS, f"a list of 1 to {MAX_ITEMS} numbers")]
    z: Coord
    radius: Size = 0.2
    support: Size = 6.0
    base: Coord | None = None


class WinchPart(Placed):
    """A winch: a drum of ``radius`` and ``width`` (across y) between two cheek plates on ``base``."""

    type: Literal["winch"]
    base: Coord | None = None
    radius: Size
    width: Size
