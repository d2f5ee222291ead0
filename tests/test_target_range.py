"""The one target-selection rule (:func:`mmusv.annotate.in_target_range`): BEV distance from the ego LiDAR."""

from __future__ import annotations

import numpy as np
from mmusv.boxes3d import in_target_range


def test_bev_distance_not_a_square_window_and_height_ignored() -> None:
    centres = np.array(
        [
            [39.0, 0.0, 0.0],  # inside
            [30.0, 30.0, 0.0],  # inside the square |x|, |y| <= 40, but 42.4 m away: out
            [0.0, -40.0, 0.0],  # on the boundary: in
            [24.0, 32.0, 500.0],  # 40 m in BEV, far above: in (height is not part of the rule)
            [-40.0, 0.1, 0.0],  # just beyond: out
        ]
    )
    assert in_target_range(centres, 40.0).tolist() == [True, False, True, True, False]
    assert in_target_range(centres[0], 40.0).shape == ()
    assert in_target_range(centres.reshape(5, 1, 3), 40.0).shape == (5, 1)


def test_agrees_with_a_brute_force_hypot() -> None:
    rng = np.random.default_rng(3)
    pts = rng.uniform(-300.0, 300.0, size=(2000, 3))
    want = [float(np.sqrt(x * x + y * y)) <= 200.0 for x, y, _ in pts]
    assert in_target_range(pts, 200.0).tolist() == want
