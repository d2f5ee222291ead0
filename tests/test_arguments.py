"""``mmusv.arguments``: the checks of the plain arguments the Python API takes; here the callbacks'."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mmusv import arguments
from mmusv.errors import ConfigError


def test_a_callback_of_the_wrong_arity_is_said_to_take_fewer_or_need_more() -> None:
    # "must take 2 positional arguments (too many positional arguments)" read as if it took too many
    with pytest.raises(ConfigError, match=r"progress = .*: must take 2 positional arguments; it takes fewer$"):
        arguments.callback(lambda done: None, name="progress", nargs=2)
    with pytest.raises(ConfigError, match=r"want = .*: must take 1 positional arguments; it needs others$"):
        arguments.callback(lambda a, b: True, name="want", nargs=1)
    assert arguments.callback(lambda a, b=0: True, name="want", nargs=1) is not None
    assert arguments.callback(None, name="want", nargs=1) is None


def test_a_frame_stream_checks_its_want_before_reading(tmp_path: Path) -> None:
    """``FrameStream(info, lambda: True)`` was a bare TypeError once it began reading."""
    from mmusv.acquire import run
    from mmusv.recording import read_info
    from mmusv.recording.stream import FrameStream
    from tiny_scenario import lidar_scenario

    rec = run(lidar_scenario("want", frames=1), out_dir=tmp_path).recording
    with pytest.raises(ConfigError, match=r"want = .*: must take 1 positional arguments; it takes fewer"):
        FrameStream(read_info(rec), lambda: True)  # type: ignore[arg-type,misc]
    assert len(list(FrameStream(read_info(rec), lambda topic: False))) == 1


def test_rows_takes_numbers_of_the_given_trailing_shape_only() -> None:
    a = arguments.rows([[1, 2, 3]], name="points", dtype=np.float32, tail=(3,))
    assert a.dtype == np.float32 and a.shape == (1, 3) and a.flags.c_contiguous
    big = arguments.rows([[1e39, 0.0]], name="xy", dtype=np.float32, tail=(2,))
    assert np.isinf(big[0, 0])  # past float32: inf, for the caller's finiteness check to name
    for value, err in [
        ([[True, False]], r"xy must be numeric, got dtype bool"),
        ([["1", "2"]], r"xy must be numeric"),
        ([[1j, 2]], r"xy must be real, got complex"),
        ([1.0, 2.0], r"xy must have shape \(N, 2\), got \(2,\)"),
        ([[1.0, 2.0, 3.0]], r"xy must have shape \(N, 2\), got \(1, 3\)"),
    ]:
        with pytest.raises(ConfigError, match=err):
            arguments.rows(value, name="xy", dtype=np.float64, tail=(2,))
    with pytest.raises(ConfigError, match=r"faces must be an integer array, got dtype float64"):
        arguments.rows([[0.0, 1.0, 2.0]], name="faces", dtype=np.int64, tail=(3,))


def test_rows_takes_an_empty_list_as_no_rows_when_asked() -> None:
    for value in ([], (), np.zeros(0)):
        got = arguments.rows(value, name="xy", dtype=np.float32, tail=(2,), empty=True)
        assert got.shape == (0, 2) and got.dtype == np.float32
        with pytest.raises(ConfigError, match=r"xy must have shape \(N, 2\), got \(0,\)"):
            arguments.rows(value, name="xy", dtype=np.float32, tail=(2,))
