"""Arrays the bindings borrow (``crates/mmusv-py/src/native.rs``): only row-major (C-contiguous) arrays are read.

numpy's Fortran-ordered arrays are contiguous too, and the numpy crate lends them as a slice in memory order: read
as row-major, a ``(4, 4)`` pose would be its transpose and ``(N, K)`` rows its columns, without an error. Every
entry point of ``mmusv._core`` that borrows a 2-D or 3-D array must refuse one, naming the argument, and give the
same answer as before for the same values in C order. (The Python wrappers convert with ``np.ascontiguousarray``
before calling; these tests call ``_core`` directly, as a user of the low-level API may.)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv import _core

# A rigid pose that is not symmetric: its transpose is another (valid) rotation with the translation moved into
# the bottom row, which a check of the bottom row catches only by accident.
_C, _S = np.cos(0.3), np.sin(0.3)
POSE = np.array([[_C, -_S, 0.0, 5.0], [_S, _C, 0.0, -2.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]])


def _box_scene() -> _core.Scene:
    v = np.array(
        [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)],
        dtype=np.float32,
    )
    f = np.array(
        [
            [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
            [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
        ],
        dtype=np.int64,
    )  # fmt: skip
    s = _core.Scene()
    s.add_instance(s.add_mesh(v, f, np.array([3], dtype=np.uint16), "box"), np.eye(4))
    return s


def _env() -> Any:
    return _core.SensorEnv(
        sun_direction=[0.3, 0.2, 0.93],
        turbidity=3.0,
        cloud_cover=0.0,
        ground_albedo=0.1,
        fog_extinction_per_m=0.0,
        rain_mm_per_h=0.0,
        wave_height_m=0.0,
        wind_speed_m_s=0.0,
        water_albedo=[0.004, 0.018, 0.03],
        shadows=True,
    )


def _refused(call: Callable[[], object], name: str) -> None:
    with pytest.raises(_core.InputError, match=rf"{name}.*C-contiguous"):
        call()


def test_a_fortran_ordered_pose_is_refused_not_read_transposed() -> None:
    cam = _core.Camera(width=8, height=6, rgb=False, hfov=1.2)
    o, _ = cam.world_rays(POSE)
    assert np.allclose(o[0], POSE[:3, 3])
    _refused(lambda: cam.world_rays(np.asfortranarray(POSE)), "pose")
    s = _box_scene()
    _refused(lambda: s.add_instance(0, np.asfortranarray(POSE)), "pose")
    _refused(lambda: s.set_poses(np.array([0], dtype=np.uint32), np.asfortranarray(POSE[None])), "poses")


def test_fortran_ordered_rows_are_refused_naming_the_argument() -> None:
    s = _box_scene()
    origins = np.array([[-5.0, 0.1, 0.2], [-5.0, 0.5, 3.0], [0.0, -6.0, 0.0]], dtype=np.float32)
    dirs = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], dtype=np.float32)
    dist = s.cast_rays(origins, dirs, 100.0)[0]
    assert np.allclose(dist, [4.0, np.inf, 5.0])
    _refused(lambda: s.cast_rays(np.asfortranarray(origins), dirs, 100.0), "origins")
    _refused(lambda: s.cast_rays(origins, np.asfortranarray(dirs), 100.0), "directions")
    _refused(lambda: s.set_seabed(np.asfortranarray(np.zeros((3, 4), np.float32))), "seabed heights")
    v = np.asfortranarray(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32))
    _refused(lambda: s.add_mesh(v, np.array([[0, 1, 2]]), np.array([1], dtype=np.uint16), "tri"), "vertices")


def test_fortran_ordered_wakes_are_refused() -> None:
    cam = _core.Camera(width=8, height=6, rgb=True, hfov=1.2)
    wakes = np.array([[0, 0, 0, 5, 10, 3], [50, 0, 1, 5, 10, 3]], dtype=np.float32)
    pose = np.eye(4)
    pose[2, 3] = 3.0
    scene = _box_scene()
    out = cam.render(scene, pose=pose, env=_env(), seed=1, wakes=wakes)
    assert out["rgb"].shape == (6, 8, 3)
    _refused(lambda: cam.render(scene, pose=pose, env=_env(), seed=1, wakes=np.asfortranarray(wakes)), "wakes")


def test_a_fortran_ordered_route_is_refused() -> None:
    route = np.array([[0.0, 0.0], [100.0, 0.0], [200.0, 0.0]])

    def fleet(r: np.ndarray) -> Any:
        one = np.ones(1)
        return _core.Fleet(
            routes=[r],
            end_behaviours=["stop"],
            speeds=one,
            start_offsets=np.zeros(1),
            z_base=np.zeros(1),
            dims=np.array([[10.0, 3.0, 2.0]]),
            amplitudes=np.zeros((1, 3)),
            seed=0,
            wave="W0",
        )

    assert np.isclose(fleet(route).route_lengths()[0], 200.0, rtol=1e-6)
    _refused(lambda: fleet(np.asfortranarray(route)), r"vessels\[0\]\.route")
    with pytest.raises(_core.InputError, match=r"vessels\[0\]\.route must have shape \(N, 2\)"):
        fleet(np.zeros((4, 3)))


def test_a_fortran_ordered_image_is_refused_and_the_recording_kept(tmp_path: Path) -> None:
    rec = _core.Recorder(tmp_path / "a.mcap")
    img = np.arange(6, dtype=np.uint8).reshape(2, 3)
    rec.raw_image("/cam", log_time_ns=1, frame_id="cam", image=img)
    _refused(lambda: rec.raw_image("/cam", log_time_ns=2, frame_id="cam", image=np.asfortranarray(img)), "image")
    rec.finish()
    assert (tmp_path / "a.mcap").stat().st_size > 0
