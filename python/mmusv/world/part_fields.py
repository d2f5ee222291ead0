"""The vocabulary every superstructure part model of :mod:`mmusv.world.part_spec` is written in: the limits of a
part (:data:`MIN_SIZE`, :data:`MAX_EXTENT`, :data:`MAX_PIECES`, ...), its field types (coordinates, sizes, gaps,
angles, tapers, points; checked material names) and the base models the part types share (a ``material``; a
vertical span, a span along the hull, a place on deck).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Literal

import numpy as np
from pydantic import BeforeValidator, Field, model_validator

from mmusv.errors import ConfigError
from mmusv.validation import Number, Spec, Whole, invalid, invalid_field, sequence
from mmusv.world.materials import material_id

__all__ = [
    "MAX_EXTENT",
    "MAX_ITEMS",
    "MAX_PIECES",
    "MIN_SIZE",
    "TAPER_RANGE",
    "Along",
    "Angle",
    "Coord",
    "Gap",
    "MaterialName",
    "Part",
    "Placed",
    "Point2",
    "Point3",
    "Segments",
    "Side",
    "Size",
    "Size2",
    "Span",
    "Taper",
    "WindowBand",
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

Segments = Annotated[Whole, Field(ge=3, le=64)]
"""Facets around a round part."""


def profile_area(points: Sequence[Sequence[float]] | np.ndarray) -> float:
    """Signed area (m², > 0 anticlockwise) of a closed polygon ``points`` ``(N, 2)`` (shoelace formula)."""
    pts = np.asarray(points, dtype=np.float64)
    d = np.roll(pts, -1, axis=0)
    return 0.5 * float(np.sum(pts[:, 0] * d[:, 1] - d[:, 0] * pts[:, 1]))


class Part(Spec):
    """Every part: ``material`` (a name of :mod:`mmusv.world.materials`; default:
    :data:`~mmusv.world.part_spec.DEFAULT_MATERIALS`)."""

    material: MaterialName | None = None


class Span(Part):
    """A part standing from ``base`` (default: the deck at the part's x) up to ``top`` or ``base + height``."""

    base: Coord | None = None
    top: Coord | None = None
    height: Size | None = None

    @model_validator(mode="after")
    def _one_top(self) -> Span:
        if (self.top is None) == (self.height is None):
            raise invalid_field("top", "give exactly one of top (absolute z, m) or height (m above base)")
        if self.top is not None and self.base is not None and self.top <= self.base:
            raise invalid_field("top", f"top {self.top:g} m must be above the base {self.base:g} m")
        return self


class Along(Part):
    """A part spanning ``x0`` to ``x1`` along the hull (``x1 > x0``)."""

    x0: Coord
    x1: Coord

    @model_validator(mode="after")
    def _ordered(self) -> Along:
        if self.x1 <= self.x0:
            raise invalid_field("x1", f"must be > x0 ({self.x0}), got {self.x1}")
        return self


class Placed(Part):
    """A part standing at ``(x, y)`` in the body frame (metres)."""

    x: Coord
    y: Coord = 0.0
