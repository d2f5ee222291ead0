"""The schema of a procedural vessel's superstructure parts: one frozen pydantic model per part ``type``.

Numbers are metres (degrees where the key ends in ``_deg``) in the vessel body frame (x forward, y left, z up,
z = 0 at the waterline, x from midship). ``base`` defaults to the deck height at the part's x, so a part's vertical
extent is checked against the deck by the mesh builder (:mod:`mmusv.world.vessel_shapes`), which also checks
``fit`` and the hull footprint; everything a part says about itself is checked here. The vocabulary is listed in
:mod:`mmusv.world.asset_spec`.

The models live by family, in :mod:`mmusv.world.part_spec_basic` (what the assembly builds itself),
:mod:`mmusv.world.part_spec_super` (superstructure) and :mod:`mmusv.world.part_spec_deck` (deck gear), written
in the field types and limits of :mod:`mmusv.world.part_fields`; this module joins them into :data:`PartSpec`
and gives each type its default material.
"""

from __future__ import annotations

import typing
from typing import Annotated

from pydantic import Field

from mmusv.validation import Spec
from mmusv.world.part_fields import (
    MAX_EXTENT,
    MAX_ITEMS,
    MAX_PIECES,
    MIN_SIZE,
    TAPER_RANGE,
    MaterialName,
    profile_area,
)

# the field types, importable from here as before the split into modules
from mmusv.world.part_fields import Angle as Angle
from mmusv.world.part_fields import Coord as Coord
from mmusv.world.part_fields import Gap as Gap
from mmusv.world.part_fields import Point2 as Point2
from mmusv.world.part_fields import Point3 as Point3
from mmusv.world.part_fields import Segments as Segments
from mmusv.world.part_fields import Side as Side
from mmusv.world.part_fields import Size as Size
from mmusv.world.part_fields import Size2 as Size2
from mmusv.world.part_fields import Taper as Taper
from mmusv.world.part_fields import WindowBand as WindowBand
from mmusv.world.part_spec_basic import (
    CylinderPart,
    GantryPart,
    GunPart,
    HcylinderPart,
    HullBlockPart,
    PlatePart,
    RowPart,
    StrutPart,
)
from mmusv.world.part_spec_deck import (
    BollardsPart,
    ContainersPart,
    FendersPart,
    HatchesPart,
    LifeboatsPart,
    PipesPart,
    RailingPart,
    TubePart,
    WinchPart,
)
from mmusv.world.part_spec_super import (
    AntennasPart,
    BoxPart,
    CranePart,
    DomePart,
    FunnelPart,
    HousePart,
    MastPart,
    NavLightsPart,
    RadarPart,
    WindowsPart,
)

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
