"""Round 13 of the API review: what a perception researcher's script hands mmusv from numpy, and the public helpers'
refusals of input they cannot use."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from mmusv import frames
from mmusv.annotate import box_corners, footprint_in_range, in_target_range
from mmusv.config import load_scenario
from mmusv.errors import ConfigError, InputError
from tiny_scenario import lidar_scenario

# ------------------------------------------------------------------------------------ numpy values in a config


@pytest.mark.parametrize("seed", [np.int64(2**62 + 1), np.uint64(2**53 + 1), np.int64(2**63 - 1)])
def test_a_numpy_integer_seed_is_taken_exactly(seed: np.integer) -> None:
    """Pydantic read a numpy integer through a float: ``seed: np.int64(2**62 + 1)`` (drawn with ``rng.integers``)
    became ``2**62`` without a word (another scenario's seed, recorded in its manifest), and ``np.int64(2**63 -
    1)``, the largest seed allowed, was refused as 'Unable to parse input string as an integer'."""
    doc = lidar_scenario("np_seed", frames=1)
    doc["seed"] = seed
    doc["map"]["seed"] = seed
    sc = load_scenario(doc)
    assert sc.seed == int(seed) and type(sc.seed) is int
    assert sc.map.seed == int(seed)


@pytest.mark.parametrize(
    ("where", "field"),
    [
        (lambda d: d.__setitem__("seed", np.True_), "seed"),
        (lambda d: d["vessels"][0].__setitem__("speed_mps", np.True_), "vessels[0].speed_mps"),
        (lambda d: d["rigs"]["r"]["lidar"].__setitem__("channels", np.True_), "rigs.r.lidar.channels"),
        (lambda d: d["vessels"][0].__setitem__("route", [[np.False_, 0], [50, 0]]), "vessels[0].route"),
        (
            lambda d: d["rigs"]["r"]["lidar"].__setitem__("elevations_deg", np.array([True, False] * 4)),
            "rigs.r.lidar.elevations_deg",
        ),
    ],
)
def test_a_numpy_boolean_is_not_a_number(where: object, field: str) -> None:
    """``true`` is never read as a number (mmusv.strict), but numpy's ``np.True_`` was: a seed of 1, a USV at 1
    m/s, a LiDAR of 1 channel, and a boolean array of elevations said to 'repeat [0.0, 1.0]'."""
    doc = lidar_scenario("np_bool", frames=1)
    where(doc)  # type: ignore[operator]
    with pytest.raises(ConfigError, match=r"a number is expected, not true/false") as e:
        load_scenario(doc)
    assert f"{field} = " in str(e.value)


def test_numpy_values_that_are_numbers_still_load() -> None:
    """Numpy scalars and arrays where numbers go load as the numbers they hold."""
    doc = lidar_scenario("np_ok", frames=1)
    doc["acquisition"]["frames"] = np.int8(3)
    doc["acquisition"]["frequency_hz"] = np.float32(5.0)
    doc["vessels"][0]["route"] = np.array([[0, 0], [50, 0]], dtype=np.int64)
    doc["rigs"]["r"]["lidar"]["channels"] = np.uint16(8)
    sc = load_scenario(doc)
    assert sc.acquisition.frames == 3 and sc.acquisition.frequency_hz == 5.0
    assert sc.vessels[0].route == [(0.0, 0.0), (50.0, 0.0)]
    assert sc.rigs["r"].lidar is not None and sc.rigs["r"].lidar.channels == 8


# ------------------------------------------------------------------------------------------------ mmusv.frames


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: frames.carla_rotation(roll_deg="a", yaw_deg=0.0, pitch_deg=0.0), "roll_deg must be angles"),
        (lambda: frames.carla_rotation(roll_deg=0.0, yaw_deg=None, pitch_deg=0.0), "yaw_deg must be angles"),
        (lambda: frames.carla_rotation(roll_deg=[1.0, 2.0], yaw_deg=[1.0, 2.0, 3.0], pitch_deg=0.0), "broadcast"),
        (lambda: frames.wrap_deg("a"), "a must be angles in degrees"),
        (lambda: frames.wrap_deg(None), "a must be angles in degrees"),
        (lambda: frames.wrap_rad([1.0, None]), "a must be angles in radians"),
        (lambda: frames.pose_matrices([0.0, 0.0, 0.0, 0.0, 0.0, None]), "eta .* it holds None"),
        (lambda: frames.translation([True, False, True]), "v must be 3 numbers .* true/false"),
        (lambda: frames.translation(np.array([1.0, 2.0, 3.0]) + 1j), "complex"),
        (lambda: frames.body_rates([0.0, 1.0], np.zeros((2, 3, 3))), "rotations must be rotation matrices"),
    ],
)
def test_the_frames_helpers_refuse_what_is_not_a_real_number(call: Callable[[], Any], words: str) -> None:
    """mmusv.frames promises an InputError naming the argument for values that are not numbers: ``carla_rotation``,
    ``wrap_deg`` and ``wrap_rad`` raised numpy's bare ValueError for text ('could not convert string to float')
    and for angles of shapes that do not broadcast, and took ``None`` as NaN; the other helpers took ``None`` as
    NaN, ``True`` as 1 and a complex number as its real part (after a ComplexWarning); ``body_rates`` of a matrix
    that is no rotation ended in scipy's ValueError."""
    with pytest.raises(InputError, match=words):
        call()


def test_the_frames_helpers_still_take_numbers_of_any_kind() -> None:
    """Ints, numpy floats and lists of them are real numbers."""
    np.testing.assert_allclose(frames.wrap_deg([540, np.float32(-190.0)]), [180.0, 170.0])
    np.testing.assert_allclose(frames.wrap_rad(np.int64(0)), 0.0)
    rot = frames.carla_rotation(roll_deg=[0, 0], yaw_deg=np.float32(90.0), pitch_deg=0)
    assert rot.shape == (2, 3, 3)
    np.testing.assert_allclose(frames.translation([1, np.float32(2.0), 3.0])[:3, 3], [1.0, 2.0, 3.0])


# ------------------------------------------------------------------------------------ mmusv.annotate's helpers


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: in_target_range(np.zeros((2, 3)), "200"), "range_m = '200': must be a number of metres"),
        (lambda: in_target_range(np.zeros((2, 3)), None), "range_m = None"),
        (lambda: in_target_range(np.zeros((2, 3)), float("nan")), "range_m = nan"),
        (lambda: in_target_range(np.zeros((2, 3)), -5.0), "range_m = -5.0: must be .* >= 0"),
        (lambda: in_target_range("ab", 200.0), "centres must be .* it holds text"),
        (lambda: footprint_in_range(np.eye(3), size=np.ones(3), range_m=200.0), r"box must be a \(4, 4\)"),
        (lambda: footprint_in_range(np.eye(4), size=[1.0], range_m=200.0), r"\(3,\) or \(2,\) size"),
        (lambda: footprint_in_range(np.eye(4), size=np.ones(3), range_m=float("nan")), "range_m = nan"),
        (lambda: box_corners("a", [1.0, 2.0, 3.0]), "matrix must be .* it holds text"),
        (lambda: box_corners(np.eye(4), [1.0, None, 3.0]), "size must be .* it holds None"),
    ],
)
def test_the_annotation_helpers_refuse_what_they_cannot_use(call: Callable[[], Any], words: str) -> None:
    """``in_target_range``, ``footprint_in_range`` and ``box_corners`` (mmusv.annotate's public target rules and
    box corners, which the exports and the detection study use) ended in numpy's bare UFuncTypeError for a range
    given as text, a TypeError for None, an IndexError for a (3, 3) box or a size of one entry, and a ValueError
    for text; a NaN or negative range put every target out of range without a word. Each is an InputError naming
    the argument."""
    with pytest.raises(InputError, match=words):
        call()


def test_the_annotation_helpers_still_take_what_they_document() -> None:
    """Lists, numpy numbers, an infinite range (every box) and a BEV size of two entries still work."""
    assert in_target_range([[1.0, 2.0, 3.0]], np.float32(5.0)).tolist() == [True]
    assert in_target_range(np.array([1e9, 0.0]), float("inf"))
    assert footprint_in_range(np.eye(4).tolist(), size=[4.0, 2.0], range_m=0)
    assert box_corners(np.eye(4).tolist(), [2, 2, 2]).shape == (8, 3)
