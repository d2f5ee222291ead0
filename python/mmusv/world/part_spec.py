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
from pydantic import Field, model_validator

from mmusv.validation import (
    Fraction,
    NonNegative,
    Number,
    Positive,
    Spec,
    Vec2,
    Vec3,
    Whole,
    invalid_field,
    sequence,
)

__all__ = [
    "PART_MODELS",
    "BoxPart",
    "CranePart",
    "CylinderPart",
    "DomePart",
    "FunnelPart",
    "GantryPart",
    "GunPart",
    "HcylinderPart",
    "HousePart",
    "HullBlockPart",
    "MastPart",
    "PartSpec",
    "PlatePart",
    "RowPart",
    "StrutPart",
    "profile_area",
]


def profile_area(points: Sequence[Sequence[float]] | np.ndarray) -> float:
    """Signed area (m², > 0 anticlockwise) of a closed polygon ``points`` ``(N, 2)`` (shoelace formula)."""
    pts = np.asarray(points, dtype=np.float64)
    d = np.roll(pts, -1, axis=0)
    return 0.5 * float(np.sum(pts[:, 0] * d[:, 1] - d[:, 0] * pts[:, 1]))


class _Span(Spec):
    """A part standing from ``base`` (default: the deck at the part's x) up to ``top`` or ``base + height``."""

    base: Number | None = None
    top: Number | None = None
    height: Positive | None = None

    @model_validator(mode="after")
    def _one_top(self) -> _Span:
        if (self.top is None) == (self.height is None):
            raise invalid_field("top", "give exactly one of top (absolute z, m) or height (m above base)")
        if self.top is not None and self.base is not None and self.top <= self.base:
            raise invalid_field("top", f"top {self.top:g} m must be above the base {self.base:g} m")
        return self


class _Along(Spec):
    """A part spanning ``x0`` to ``x1`` along the hull (``x1 > x0``)."""

    x0: Number
    x1: Number

    @model_validator(mode="after")
    def _ordered(self) -> _Along:
        if self.x1 <= self.x0:
            raise invalid_field("x1", f"must be > x0 ({self.x0}), got {self.x1}")
        return self


class _Placed(Spec):
    """A part standing at ``(x, y)`` in the body frame (metres)."""

    x: Number
    y: Number = 0.0


class BoxPart(_Placed, _Span):
    """A box, optionally tapered towards the top and turned by ``yaw_deg``."""

    type: Literal["box"]
    size: Vec2
    fit: NonNegative | None = None
    taper: Positive = 1.0
    yaw_deg: Number = 0.0


class HousePart(_Placed):
    """A deckhouse of stacked tiers ``[lx, ly, h(, dx)]`` aligned at ``x``, with optional bridge ``wings``."""

    type: Literal["house"]
    align: Literal["center", "aft", "fore"] = "center"
    taper: Positive = 1.0
    tiers: Annotated[
        tuple[Annotated[tuple[Number, ...], sequence(3, 4, "a list of 3 to 4 numbers")], ...],
        sequence(1, None, "a non-empty list of lists"),
    ]
    base: Number | None = None
    fit: NonNegative | None = None
    wings: Vec2 | None = None


class HullBlockPart(_Along, _Span):
    """A block following the deck outline between ``x0`` and ``x1``, ``inset`` metres inside it (mono hulls)."""

    type: Literal["hull_block"]
    inset: NonNegative = 0.0
    taper: Positive = 1.0


class RowPart(_Along):
    """``count`` boxes in a row from ``x0`` to ``x1`` with ``gap`` between them, heights cycled from ``heights``."""

    type: Literal["row"]
    count: Annotated[Whole, Field(ge=1)]
    gap: NonNegative = 0.0
    y: Number = 0.0
    width: Positive
    heights: Annotated[tuple[Positive, ...], sequence(1, None, "a non-empty list of numbers")]
    base: Number | None = None
    fit: NonNegative | None = None

    @model_validator(mode="after")
    def _fits(self) -> RowPart:
        if self.x1 - self.x0 - self.gap * (self.count - 1) <= 0.0:
            raise invalid_field("count", f"{self.count} boxes with gap {self.gap:g} do not fit between x0 and x1")
        return self


class FunnelPart(_Placed, _Span):
    """A funnel, square (``shape: box``) or elliptic (``shape: round``) in plan, narrowing by ``taper``."""

    type: Literal["funnel"]
    size: Vec2
    taper: Positive = 0.9
    shape: Literal["box", "round"] = "box"


class MastPart(_Placed, _Span):
    """A square mast of side ``width``, with a crosswise ``yard`` at fraction ``yard_at`` of its height."""

    type: Literal["mast"]
    width: Positive = 0.3
    yard: NonNegative = 0.0
    yard_at: Fraction = 0.8


Segments = Annotated[Whole, Field(ge=3, le=64)]
"""Facets around a round part."""


class CylinderPart(_Placed, _Span):
    """A vertical cylinder (a cone frustum with ``top_radius``)."""

    type: Literal["cylinder"]
    radius: Positive
    top_radius: Positive | None = None
    segments: Segments = 12


class HcylinderPart(_Along):
    """A horizontal cylinder along x from ``x0`` to ``x1``, axis at ``(y, z)``."""

    type: Literal["hcylinder"]
    y: Number = 0.0
    z: Number
    radius: Positive
    segments: Segments = 12


class DomePart(_Placed):
    """A sphere cap of ``radius`` with its top at ``top``, on a skirt down to ``base``."""

    type: Literal["dome"]
    radius: Positive
    top: Number
    base: Number | None = None
    segments: Segments = 16

    @model_validator(mode="after")
    def _above_base(self) -> DomePart:
        if self.base is not None and self.base >= self.top:
            raise invalid_field("top", f"top {self.top:g} m must be above the base {self.base:g} m")
        return self


class StrutPart(Spec):
    """A beam of ``width`` x ``thickness`` from ``from`` to ``to`` (absolute body-frame points)."""

    type: Literal["strut"]
    start: Vec3 = Field(alias="from")
    end: Vec3 = Field(alias="to")
    width: Positive
    thickness: Positive | None = None
    """Default: ``width``."""

    @model_validator(mode="after")
    def _long(self) -> StrutPart:
        if math.dist(self.start, self.end) <= 1e-9:
            raise invalid_field("to", "must differ from 'from'")
        return self


class PlatePart(Spec):
    """A convex ``[x, z]`` profile ``points`` extruded ``thickness`` across y, centred at ``y``."""

    type: Literal["plate"]
    y: Number = 0.0
    thickness: Positive
    points: Annotated[tuple[Vec2, ...], sequence(3, None, "a list of at least 3 [x, z] points")]

    @model_validator(mode="after")
    def _area(self) -> PlatePart:
        if abs(profile_area(self.points)) < 1e-9:
            raise invalid_field("points", "profile has zero area")
        return self


class GantryPart(_Span):
    """An A-frame or portal of two legs ``span`` apart, leaning ``lean`` metres forward, and a crossbeam."""

    type: Literal["gantry"]
    x: Number
    span: Positive
    leg: Positive = 0.5
    lean: Number = 0.0


class CranePart(_Placed):
    """A deck crane: ``pedestal [radius, height]``, a cab, and a ``jib [length, elevation_deg, yaw_deg]``."""

    type: Literal["crane"]
    base: Number | None = None
    pedestal: Vec2
    jib: Vec3
    width: Positive = 0.6

    @model_validator(mode="after")
    def _positive(self) -> CranePart:
        if self.pedestal[0] <= 0 or self.pedestal[1] <= 0 or self.jib[0] <= 0:
            raise invalid_field("pedestal", "pedestal radius/height and jib length must be > 0")
        return self


class GunPart(_Placed):
    """A gun turret of ``radius`` and ``height`` with a ``barrel`` pointing along ``yaw_deg``/``elevation_deg``."""

    type: Literal["gun"]
    base: Number | None = None
    radius: Positive
    height: Positive
    barrel: Positive
    yaw_deg: Number = 0.0
    elevation_deg: Number = 5.0


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
    | GunPart,
    Field(discriminator="type"),
]
"""One superstructure part, chosen by its ``type``."""

PART_MODELS: dict[str, type[Spec]] = {
    typing.get_args(m.model_fields["type"].annotation)[0]: m for m in typing.get_args(typing.get_args(PartSpec)[0])
}
"""Part ``type`` -> its model."""
