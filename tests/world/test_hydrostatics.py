"""Hull particulars of every catalogue asset (mmusv.world.hydrostatics): complete, valid for the core's RAOs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mmusv._native import core
from mmusv.world.hydrostatics import HULL_FORMS, hull_particulars
from mmusv.world.vessels import library


def test_every_asset_has_valid_particulars_and_a_plausible_roll_period() -> None:
    assets = library()
    assert {a.category for a in assets} <= set(HULL_FORMS)
    for a in assets:
        length, beam, draft, cb, gm = hull_particulars(a)
        assert (length, beam) == (a.length, a.beam) and 0 < draft <= a.draft
        assert 0.3 <= cb <= 0.95 and gm >= 0.04 * beam
        # Natural roll period 2π·0.39 B / √(g GM): seconds for small craft, up to ~25 s for big ships.
        period = 2 * math.pi * 0.39 * beam / math.sqrt(9.80665 * gm)
        assert 0.5 < period < 30, (a.name, period)
        rao = core.hull_rao(
            hull=[length, beam, draft, cb, gm], omega=np.array([0.02]), beta=np.array([0.5]), omega_e=np.array([0.02])
        )
        assert abs(rao[0, 0]) == pytest.approx(1.0, abs=1e-3), a.name  # long waves are followed
