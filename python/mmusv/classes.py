"""Semantic classes shared by every mesh, sensor and annotation, with a fixed colour palette.

Class ids are ``uint16`` in Rust and in the sensors' numpy arrays (the annotation columns widen them to uint32, the
Parquet tables and :class:`~mmusv.recording.decode.WorldFrame` to int64). ``0`` means "nothing hit" (sky, no
return; the radar's rain clutter has it too, and so do the LiDAR's returns from rain drops, the only LiDAR points
of class 0). The palette is the one the quick-look images use (``mmusv preview``'s
semantic panels, SemanticKITTI's ``color_map``): ``PALETTE[class_id]`` is an ``(R, G, B)`` uint8 triple. The
recorded semantic images are not coloured: their PNGs hold the class ids themselves, 16-bit gray
(``docs/recording.md``).
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from mmusv import arguments
from mmusv.errors import InputError

__all__ = ["PALETTE", "ROLE_COLOURS", "SemanticClass", "class_name", "palette_array"]


class SemanticClass(IntEnum):
    """Semantic class ids (stable: they are written into recordings), and what of the world carries each:

    ==================  =========================================================================================
    ``NONE`` 0          nothing hit: the sky, no return (and the radar's rain clutter, the LiDAR's rain drops)
    ``WATER`` 1         the sea's surface, flat or displaced, on the map and past its edge (and the radar's sea
                        clutter)
    ``TERRAIN`` 2       the land, and the seabed of the terrain cells that reach less than 2 m under the surface
                        (cells wholly deeper are left out: ``mmusv.world.maps.TERRAIN_MESH_MIN_Z``)
    ``VEGETATION`` 3    terrain on gentle slopes (surface normal at least 0.6 upwards) in patches, above 4 m on an
                        island map, 3 m on an open-sea islet, 2.5 m above a port's land; none with the map's
                        ``vegetation: false``
    ``PORT_STRUCTURE``  a port's quay, piers and breakwaters
    4
    ``CONTAINER`` 5     the container stacks of a port's yard (the containers a ship carries are the ship's)
    ``CRANE`` 6         a port's ship-to-shore gantry cranes
    ``BUOY`` 7          a map's buoys: a port's channel buoys and the free-standing ones (``n_buoys``)
    ``BUILDING`` 8      a port's warehouses and offices, and the lights on its breakwater heads
    ``VESSEL`` 10       every vessel but the USVs: the targets and the ships moored in a port
    ``USV`` 11          the USVs (``role: usv``, whatever their asset), and any vessel of a USV asset
                        (``usv_wamv``, ``usv_patrol_12m``)
    ==================  =========================================================================================
    """

    NONE = 0
    WATER = 1
    TERRAIN = 2
    VEGETATION = 3
    PORT_STRUCTURE = 4
    CONTAINER = 5
    CRANE = 6
    BUOY = 7
    BUILDING = 8
    VESSEL = 10
    USV = 11


PALETTE: dict[int, tuple[int, int, int]] = {
    SemanticClass.NONE: (0, 0, 0),
    SemanticClass.WATER: (30, 90, 160),
    SemanticClass.TERRAIN: (150, 120, 80),
    SemanticClass.VEGETATION: (60, 140, 60),
    SemanticClass.PORT_STRUCTURE: (170, 170, 170),
    SemanticClass.CONTAINER: (200, 80, 40),
    SemanticClass.CRANE: (230, 200, 40),
    SemanticClass.BUOY: (255, 100, 180),
    SemanticClass.BUILDING: (120, 100, 140),
    SemanticClass.VESSEL: (240, 240, 240),
    SemanticClass.USV: (40, 220, 220),
}


def palette_array() -> np.ndarray:
    """The palette as a ``(256, 3)`` uint8 lookup table indexed by class id (unknown ids are magenta)."""
    lut = np.full((256, 3), (255, 0, 255), dtype=np.uint8)
    for k, rgb in PALETTE.items():
        lut[int(k)] = rgb
    return lut


def class_name(class_id: int) -> str:
    """Lower-case name of a class id, e.g. ``class_name(10) == "vessel"``; ``"unknown_<id>"`` otherwise. A class id
    is a whole number (``int`` or numpy integer); anything else (a float, true/false, text, None) is a
    :class:`mmusv.InputError`."""
    class_id = arguments.whole(class_id, name="class_id", error=InputError)
    try:
        return SemanticClass(class_id).name.lower()
    except ValueError:
        return f"unknown_{class_id}"


ROLE_COLOURS: dict[str, tuple[float, float, float, float]] = {
    "usv": (0.2, 0.9, 0.9, 0.5),
    "target": (1.0, 0.3, 0.2, 0.5),
    "moored": (1.0, 0.8, 0.2, 0.5),
}
"""Box colour ``(r, g, b, a)`` in ``[0, 1]`` per vessel role, as 3D viewers draw the boxes: the recording's Foxglove
scene entities and the ROS 2 export's RViz markers."""
