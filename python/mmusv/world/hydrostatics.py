"""Hull particulars for the physical sea response: length, beam, draft, block coefficient and metacentric height.

The vessel response to waves (:mod:`mmusv_core::ocean::response`, Jensen, Mansour & Olsen (2004) closed-form
heave and pitch, a one-degree-of-freedom roll oscillator) needs, per asset, ``L``, ``B``, ``T``, ``Cb`` and ``GM``:

* ``L``, ``B``, ``T`` are the asset's own dimensions (its mesh's bounding box: length overall, beam, draft below
  the waterline). Keel-deep sailing yachts use their canoe-body draft (a ``draft_factor`` of the keel draft).
* ``Cb`` and ``GM`` come from the table below, one row per catalogue category, ``GM`` as a fraction of the beam
  so that larger and smaller assets of one type scale. They are representative design values by ship type, not
  data of particular ships: block coefficients as tabulated by ship type in Schneekluth, H. & Bertram, V. (1998),
  "Ship Design for Efficiency and Economy", 2nd ed., §1.2 (full tankers and bulk carriers 0.80–0.85, container
  ships 0.60–0.68, ferries and cruise ships 0.55–0.65, tugs and fishing vessels 0.50–0.58, fast small craft
  0.35–0.45); loaded metacentric heights in the ranges quoted by Barrass, C. B. & Derrett, D. R. (2012), "Ship
  Stability for Masters and Mates", 7th ed. (at least the IMO minimum of 0.15 m; dry cargo and container ships
  about 0.3–2 m, tankers and bulk carriers larger; small craft and catamarans very stiff, GM a sizeable fraction
  of the beam).

A catamaran's GM comes mostly from its hulls' spread: ``BM = I_T/∇ ≈ (s/2)² C_wp/(C_b T)`` for hulls ``s`` apart
(each hull's waterplane ``s/2`` off the centreline, its own inertia small: the parallel-axis theorem), a sizeable
fraction of the overall beam: for the WAM-V 16 (hull centres about 1.9 m apart, the 2.44 m beam less a pontoon's
width; T = 0.35 m, C_wp ≈ (1 + 2 C_b)/3) BM ≈ 1.5 B. The catalogue's catamarans take ``GM = 0.6 B``; ``usv_wamv``,
a catamaran in the category of monohull USVs, takes it too (:data:`ASSET_HULL_FORMS`; before 2026-12-06 it had
the monohulls' 0.3 B).

Units: metres. :func:`hull_particulars` returns ``(length, beam, draft, block_coefficient, gm)``, the row layout
the core's ``Fleet(hulls=...)``, ``WaveField.hull_response`` and ``hull_rao`` take.
"""

from __future__ import annotations

from typing import NamedTuple

from mmusv.world.vessels import VesselAsset

__all__ = ["ASSET_HULL_FORMS", "HULL_FORMS", "HullForm", "hull_particulars"]


class HullForm(NamedTuple):
    """Per category: block coefficient ``cb``, ``gm_over_beam`` (GM / B) and ``draft_factor`` (hull draft / draft
    of the mesh, below 1 where a keel reaches deeper than the hull)."""

    cb: float
    gm_over_beam: float
    draft_factor: float = 1.0


HULL_FORMS: dict[str, HullForm] = {
    "barge": HullForm(0.90, 0.25),
    "bulk_carrier": HullForm(0.83, 0.08),
    "car_carrier": HullForm(0.58, 0.05),
    "catamaran_ferry": HullForm(0.45, 0.60),
    "chemical_tanker": HullForm(0.78, 0.08),
    "container_ship": HullForm(0.63, 0.04),
    "crew_transfer_vessel": HullForm(0.45, 0.60),
    "cruise_ship": HullForm(0.65, 0.06),
    "dredger": HullForm(0.78, 0.08),
    "ferry": HullForm(0.58, 0.08),
    "fireboat": HullForm(0.50, 0.10),
    "fishing_boat": HullForm(0.55, 0.10),
    "general_cargo": HullForm(0.70, 0.05),
    "hovercraft": HullForm(0.60, 0.30),
    "kayak": HullForm(0.45, 0.10),
    "lng_carrier": HullForm(0.75, 0.06),
    "motor_yacht": HullForm(0.42, 0.12),
    "naval_frigate": HullForm(0.48, 0.07),
    "offshore_supply_vessel": HullForm(0.68, 0.08),
    "patrol_boat": HullForm(0.45, 0.12),
    "personal_watercraft": HullForm(0.45, 0.20),
    "pilot_boat": HullForm(0.42, 0.15),
    "research_vessel": HullForm(0.57, 0.08),
    "rib": HullForm(0.40, 0.30),
    "roro": HullForm(0.60, 0.06),
    "sailing_catamaran": HullForm(0.40, 0.60),
    "sailing_yacht": HullForm(0.35, 0.10, draft_factor=0.3),
    "speedboat": HullForm(0.38, 0.25),
    "tanker": HullForm(0.82, 0.10),
    "trawler": HullForm(0.55, 0.10),
    "tug": HullForm(0.52, 0.10),
    "usv": HullForm(0.45, 0.30),
}
"""Hull form by catalogue category (see the module docstring for the sources of the values)."""

ASSET_HULL_FORMS: dict[str, HullForm] = {
    "usv_wamv": HullForm(0.45, 0.60),
}
"""Per asset name, where an asset's hull differs from its category's: the WAM-V is a catamaran (two pontoons) in the
``usv`` category of monohull USVs, so it takes the catamarans' GM of 0.6 B (the ``usv`` row's 0.3 B is a
monohull's; see the module docstring)."""

DEFAULT_HULL_FORM = HullForm(0.55, 0.10)
"""For categories not in the table (user assets, ``custom``): a generic displacement monohull."""

MIN_DRAFT_M = 0.05
"""Smallest draft used (a hovercraft on its cushion or a very flat mesh still gets a finite one)."""


def hull_particulars(asset: VesselAsset) -> tuple[float, float, float, float, float]:
    """``(length, beam, draft, block_coefficient, gm)`` of ``asset`` in metres (Cb dimensionless)."""
    form = ASSET_HULL_FORMS.get(asset.name) or HULL_FORMS.get(asset.category, DEFAULT_HULL_FORM)
    draft = max(asset.draft * form.draft_factor, MIN_DRAFT_M)
    return (float(asset.length), float(asset.beam), float(draft), form.cb, form.gm_over_beam * float(asset.beam))
