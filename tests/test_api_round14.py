"""Round 14 of the API review: the public geometry helpers' refusals of input they cannot use (mmusv.annotate's
box helpers, mmusv.image_boxes, ...), each an InputError naming the argument and what is allowed."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from mmusv.annotate import box_corners, footprint_in_range
from mmusv.errors import InputError

# ------------------------------------------------------------------------------------ a box's size


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: box_corners(np.eye(4), [-4.0, 2.0, 1.0]), r"size must be .* finite metres >= 0 .* \[-4.0, 2.0, 1.0\]"),
        (lambda: box_corners(np.eye(4), [4.0, np.nan, 1.0]), r"size must be .* got \[4.0, nan, 1.0\]"),
        (lambda: box_corners(np.eye(4), [4.0, 2.0, np.inf]), r"size must be .* got \[4.0, 2.0, inf\]"),
        (lambda: footprint_in_range(np.eye(4), size=[-400.0, 2.0], range_m=10.0), r"size must be .* >= 0"),
        (
            lambda: footprint_in_range(np.eye(4), size=[np.nan, 2.0, 1.0], range_m=10.0),
            r"size must be .* got \[nan, 2.0, 1.0\]",
        ),
        (
            lambda: footprint_in_range(np.full((4, 4), np.nan), size=[4.0, 2.0], range_m=10.0),
            r"box must be a \(4, 4\) box -> ego LiDAR transform of finite numbers",
        ),
    ],
)
def test_a_box_of_negative_or_nan_size_is_refused(call: Callable[[], Any], words: str) -> None:
    """A negative extent is no box: ``box_corners`` gave corners in mirrored order (corner 0 at +x for a negative
    length, breaking the documented corner bits the image boxes' faces rely on) and ``footprint_in_range`` read a
    length of -400 m as a 400 m footprint; a NaN size gave NaN corners, and a NaN size or box 'not in range',
    without a word. Each is an InputError naming the argument (nothing in mmusv passes such a size: vessels' boxes
    are their meshes' extents)."""
    with pytest.raises(InputError, match=words):
        call()


def test_a_box_of_zero_size_still_has_corners() -> None:
    """A flat box (size 0 along an axis) is still a box: its corners, in order, and its footprint."""
    c = box_corners(np.eye(4), [2.0, 0.0, 0.0])
    np.testing.assert_array_equal(c[:, 0], [-1.0, 1.0] * 4)
    assert not c[:, 1:].any()
    assert footprint_in_range(np.eye(4), size=np.zeros(3), range_m=0.0)
