"""What every part builder of a procedural vessel shares: the hull, the class, the part's path and material.

Used by :mod:`mmusv.world.vessel_shapes` and the part families (:mod:`mmusv.world.parts_super`,
:mod:`mmusv.world.parts_deck`). Body frame and units as in :mod:`mmusv.world.vessel_shapes`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmusv.world.asset_spec import AssetSpecError, HullSpec
from mmusv.world.hull_form import deck_z, half_width
from mmusv.world.materials import material_id
from mmusv.world.part_spec import DEFAULT_MATERIALS, MAX_PIECES, PartSpec
from mmusv.world.primitives import TriMesh, box, prism

__all__ = ["MAX_PIECES", "Ctx", "block", "material_of"]


def material_of(part: PartSpec, hull: HullSpec) -> int:
    """The id of ``part``'s main material: its ``material``, else :data:`DEFAULT_MATERIALS` of its type."""
    name = part.material or DEFAULT_MATERIALS[part.type]
    if name == "<topside>":
        name = hull.topside
    elif name.startswith("<"):
        name = "paint_grey"
    return material_id(name)


@dataclass(frozen=True)
class Ctx:
    """One part's build context: ``hull``, semantic class ``cls``, the part's path ``where`` (for errors),
    its main material id ``mat`` and every part of the asset (``parts``, for parts placed relative to others)."""

    hull: HullSpec
    cls: int
    where: str
    mat: int
    parts: tuple[PartSpec, ...] = ()

    def base(self, base: float | None, x: float) -> float:
        """``base``, or the deck height at ``x`` when it is not given (metres)."""
        return deck_z(self.hull, x) if base is None else base

    def zspan(self, *, base: float | None, top: float | None, height: float | None, x: float) -> tuple[float, float]:
        """The vertical extent ``(z0, z1)`` of a part standing on ``base`` up to ``top`` or ``base + height``."""
        z0 = self.base(base, x)
        z1 = top if top is not None else z0 + (height or 0.0)
        if z1 <= z0:
            raise AssetSpecError(f"{self.where}.top", f"top {z1:g} m must be above the base {z0:g} m")
        return z0, z1

    def fit_width(self, fit: float | None, *, x0: float, x1: float, y: float, width: float) -> float:
        """``width`` narrowed (when ``fit`` is given) to stay ``fit`` metres inside the deck outline."""
        if fit is None:
            return width
        room = min(half_width(self.hull, x0), half_width(self.hull, x1)) - fit - abs(y)
        if room <= 0.0:
            raise AssetSpecError(f"{self.where}.fit", f"no room inside the deck outline between x={x0:g} and x={x1:g}")
        return min(width, 2.0 * room)

    def count(self, n: float, *, key: str, what: str) -> int:
        """``n`` as the number of pieces a part makes, checked against :data:`MAX_PIECES` (an error at ``key``)."""
        if not n <= MAX_PIECES:  # also catches nan
            raise self.error(key, f"would make {n:.3g} {what}; at most {MAX_PIECES} per part")
        return int(n)

    def error(self, key: str, message: str) -> AssetSpecError:
        """An :class:`AssetSpecError` at ``<where>.<key>``."""
        return AssetSpecError(f"{self.where}.{key}" if key else self.where, message)


def block(
    *,
    x: float,
    y: float,
    lx: float,
    ly: float,
    z0: float,
    z1: float,
    cls: int,
    material: int,
    taper: float = 1.0,
    yaw: float = 0.0,
) -> TriMesh:
    """A box (or a frustum narrowing by ``taper``) ``lx`` x ``ly`` centred at ``(x, y)`` from ``z0`` to ``z1``."""
    if taper == 1.0:
        m = box(center=(x, y, (z0 + z1) / 2.0), size=(lx, ly, z1 - z0), cls=cls, yaw=yaw)
    else:
        c, s = math.cos(yaw), math.sin(yaw)
        local = np.array([[-lx, -ly], [lx, -ly], [lx, ly], [-lx, ly]]) / 2.0
        outline = local @ np.array([[c, s], [-s, c]]) + np.array([x, y])
        m = prism(outline=outline, z0=z0, z1=z1, cls=cls, top_scale=taper)
    return TriMesh(m.vertices, m.faces, m.classes, np.array([material]))
