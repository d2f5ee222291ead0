"""A procedural hull whose draft plus freeboard rounds past its depth (draft 0.6, depth 1.8: 0.6 + 1.2 / 1.8 is
1.0000000000000002) was refused as 'mesh has non-finite vertices', with two numpy RuntimeWarnings: the rake's
(1 - t) ** 1.5 at the deck was NaN. It builds now, its deck at its depth."""

from __future__ import annotations

import numpy as np
import pytest
from mmusv.world.vessels import load_asset_file


@pytest.mark.parametrize(("draft", "depth"), [(0.6, 1.8), (0.3, 0.9), (1.2, 3.6), (0.6, 1.8000000000000003)])
def test_a_hull_whose_freeboard_rounds_past_its_depth_builds(draft: float, depth: float) -> None:
    asset = load_asset_file({"name": "h", "hull": {"length": 12.0, "beam": 4.0, "draft": draft, "depth": depth}})
    assert np.isfinite(asset.mesh.vertices).all()
    assert asset.length == pytest.approx(12.0) and asset.height == pytest.approx(depth)


def test_every_whole_decimetre_hull_builds() -> None:
    for draft in np.arange(1, 20) / 10:
        for depth in np.arange(int(draft * 10) + 1, 40, 3) / 10:
            hull = {"length": 12.0, "beam": 4.0, "draft": float(draft), "depth": float(depth), "rake": 0.1}
            assert np.isfinite(load_asset_file({"name": "h", "hull": hull}).mesh.vertices).all(), hull
