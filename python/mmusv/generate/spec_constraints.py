"""The constraint block of a generation spec: one model per named constraint, with its thresholds.

Units: metres; shares are fractions of the acquisition frames in [0, 1]. Every constraint has ``enabled``;
:func:`mmusv.generate.checks.build_constraints` turns the enabled ones into checks, in the order of
:class:`Constraints` (cheap first).

Every check is on by default, except ``target_density`` and ``line_of_sight``, which are off while a spec does not
mention them. Writing a check's block turns it on, whatever fields it gives (``target_density: {min_targets: 2}``,
even ``line_of_sight: {}``), unless the block says ``enabled: false``: a block of thresholds is never dropped
without a word.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from mmusv.strict import StrictModel

__all__ = [
    "Constraints",
    "CooperationCheck",
    "InWaterCheck",
    "LineOfSightCheck",
    "OcclusionCheck",
    "PairKind",
    "RouteSeparationCheck",
    "SensingRangeCheck",
    "SeparationCheck",
    "ShoreClearanceCheck",
    "SpecModel",
    "StructureClearanceCheck",
    "TargetRangeCheck",
]

PairKind = Literal["usv-usv", "usv-target", "target-target"]

MAX_DISTANCE_M = 100_000.0
"""The largest distance threshold (clearance, separation, range, cooperation band) a constraint takes, metres."""


class SpecModel(StrictModel):
    """The base of the spec's models: :class:`~mmusv.strict.StrictModel` (no unknown keys, NaN, infinity or
    booleans for numbers, also inside a pair of numbers: Pydantic's lax mode read ``quota: true`` as 1 and
    ``speed_mps: [true, 5]`` as ``(1.0, 5.0)`` without a word)."""


_Model = SpecModel


class _Check(_Model):
    enabled: bool = True
    """On unless the block says ``enabled: false``; a check a spec does not mention keeps the default of
    :class:`Constraints` (on, except ``target_density`` and ``line_of_sight``)."""


class InWaterCheck(_Check):
    """Every route sample and every vessel position (centre) in navigable water."""


class ShoreClearanceCheck(_Check):
    """Hull at least ``min_m`` from non-navigable cells (land, shallows, structures, map edge). The hull is the
    capsule covering its rectangle at the vessel's yaw (:mod:`mmusv.generate.hulls`)."""

    min_m: float = Field(default=10.0, ge=0.0, le=MAX_DISTANCE_M)


class StructureClearanceCheck(_Check):
    """Hull (the capsule covering its rectangle at the vessel's yaw, :mod:`mmusv.generate.hulls`) at least
    ``min_m`` from port structures, buoys and moored ships."""

    min_m: float = Field(default=15.0, ge=0.0, le=MAX_DISTANCE_M)


class SeparationCheck(_Check):
    """Hull-to-hull distance at least ``min_m`` between every two vessels at every time, each hull the capsule
    covering its rectangle at the vessel's yaw (:mod:`mmusv.generate.hulls`)."""

    min_m: float = Field(default=15.0, ge=0.0, le=MAX_DISTANCE_M)


class RouteSeparationCheck(_Check):
    """Route centre lines of the vessel pairs of kinds ``pairs`` at least ``min_m`` apart everywhere."""

    min_m: float = Field(default=20.0, ge=0.0, le=MAX_DISTANCE_M)
    pairs: list[PairKind] = Field(default_factory=lambda: list[PairKind](["usv-usv"]))


class TargetRangeCheck(_Check):
    """Closest approach (over frames) of the ego to each ranged target within the difficulty's ``range_m``."""


class SensingRangeCheck(_Check):
    """Each target within ``range_m`` of at least one USV for at least ``min_share`` of the frames. A distance of
    the spec's own, not the rig's: the default 1000 m accepts targets that a 200 m LiDAR (the default rig's) never
    reaches, and a recording boxes only the vessels within its LiDAR's range (43 % of the targets of 100 scenarios
    so generated were never within 200 m of a USV); give the rig's range, as the bundled coop_detection specs do,
    for a batch whose targets are labelled."""

    range_m: float = Field(default=1000.0, gt=0.0, le=MAX_DISTANCE_M)
    min_share: float = Field(default=0.8, ge=0.0, le=1.0)
    targets: Literal["all", "role"] = "all"


class TargetDensityCheck(_Check):
    """Each USV has at least ``min_targets`` targets (role targets and distractors; other USVs do not count)
    within ``range_m`` (centre to centre, BEV) for at least ``min_share`` of the frames: datasets dense enough
    to learn detection from. Off while a spec does not mention it; on once it writes the block (module docs)."""

    range_m: float = Field(default=200.0, gt=0.0, le=MAX_DISTANCE_M)
    min_targets: int = Field(default=1, ge=1, le=64)
    min_share: float = Field(default=0.8, ge=0.0, le=1.0)


class CooperationCheck(_Check):
    """Each USV's nearest other USV between ``min_m`` and ``max_m`` for at least ``min_share`` of the frames
    (vacuous with one USV)."""

    min_m: float = Field(default=20.0, ge=0.0, le=MAX_DISTANCE_M)
    max_m: float = Field(default=800.0, gt=0.0, le=MAX_DISTANCE_M)
    min_share: float = Field(default=1.0, ge=0.0, le=1.0)

    @model_validator(mode="after")
    def _bounds(self) -> CooperationCheck:
        if self.min_m > self.max_m:
            raise ValueError(f"min_m ({self.min_m}) must not exceed max_m ({self.max_m})")
        return self


class LineOfSightCheck(_Check):
    """Each role target seen (ray cast against the static map, within sensing range) by at least one USV for
    at least ``min_share`` of the frames. Off while a spec does not mention it; on once it writes the block (module
    docs)."""

    min_share: float = Field(default=0.5, ge=0.0, le=1.0)


class OcclusionCheck(_Check):
    """For combinations that ask for occlusion: the primary target hidden from the ego by the static map for at
    least ``min_occluded_share`` of the frames (a difficulty's ``occluded_share`` overrides it), and during at
    least ``min_visible_other_share`` of those frames seen by another USV (line of sight and sensing range)."""

    min_occluded_share: float = Field(default=0.3, gt=0.0, le=1.0)
    min_visible_other_share: float = Field(default=0.5, ge=0.0, le=1.0)


class Constraints(_Model):
    """The named constraints, in evaluation order (cheap first); the first that fails rejects an attempt."""

    in_water: InWaterCheck = Field(default_factory=InWaterCheck)
    shore_clearance: ShoreClearanceCheck = Field(default_factory=ShoreClearanceCheck)
    structure_clearance: StructureClearanceCheck = Field(default_factory=StructureClearanceCheck)
    separation: SeparationCheck = Field(default_factory=SeparationCheck)
    route_separation: RouteSeparationCheck = Field(default_factory=RouteSeparationCheck)
    target_range: TargetRangeCheck = Field(default_factory=TargetRangeCheck)
    sensing_range: SensingRangeCheck = Field(default_factory=SensingRangeCheck)
    target_density: TargetDensityCheck = Field(default_factory=lambda: TargetDensityCheck(enabled=False))
    cooperation: CooperationCheck = Field(default_factory=CooperationCheck)
    line_of_sight: LineOfSightCheck = Field(default_factory=lambda: LineOfSightCheck(enabled=False))
    occlusion: OcclusionCheck = Field(default_factory=OcclusionCheck)
