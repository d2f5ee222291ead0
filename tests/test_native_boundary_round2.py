"""The native boundary, second hostile round (a sweep of ``mmusv._core`` and the API over it). What it found:

- Two recordings opened on one name each wrote its ``.partial``: the second truncated the first's, the first's
  ``finish`` said it held every message and renamed an MCAP that no longer read into place, and the second's
  ``finish`` failed with "No such file or directory".
- ``Camera(width=16384, height=16384)`` (both sides allowed) allocated its rays, some 7 GB, and rendering would
  want 33 GB: under a memory limit the process aborted in Rust's allocator.
- ``Scene.prefetch_wave_surface`` promised ``set_wave_surface``'s checks but took ``hs_m=NaN`` or ``-5`` without a
  word (the sea was checked on the sampling thread, so the error came later or never).

Each allocation-sized case runs in a subprocess under a 4 GiB address space (tests/test_native_fuzz_round.py's
harness), so a regression is a failed test rather than a dead test run.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
from mcap.reader import make_reader
from mmusv._native import core
from mmusv.recording.writer import Recording
from mmusv.sensors.config import MAX_IMAGE_PIXELS
from test_native_fuzz_round import _refused, _run


def _count(path: Path) -> int:
    with path.open("rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages())


def _write(rec: Recording, n: int) -> None:
    for i in range(n):
        rec.raw_image("/img", log_time_ns=i, frame_id="c", image=np.full((8, 8), i % 255, np.uint8))


def test_a_second_recording_on_a_name_being_written_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    first = Recording(path)
    _write(first, 20)
    with pytest.raises(mmusv.IoError, match=r"x\.mcap\.partial.*another recorder"):
        Recording(path, overwrite=True)
    _write(first, 20)  # the refusal left the first one's file alone
    assert first.finish()["messages"] == 40
    assert _count(path) == 40
    # Finished, the name is free: a new recording replaces it (with overwrite), and reads back whole.
    again = Recording(path, overwrite=True)
    _write(again, 3)
    again.finish()
    assert _count(path) == 3


def test_a_dropped_or_abandoned_recording_frees_its_name(tmp_path: Path) -> None:
    path = tmp_path / "y.mcap"
    rec = Recording(path)
    _write(rec, 2)
    del rec  # dropped unfinished: its .partial is left (readable), and unlocked
    rec = Recording(path)
    _write(rec, 2)
    rec._rec.abandon()
    rec = Recording(path)
    _write(rec, 1)
    rec.finish()
    assert _count(path) == 1


def test_a_camera_of_more_pixels_than_an_image_may_hold_is_refused_not_aborted() -> None:
    assert MAX_IMAGE_PIXELS == core.MAX_IMAGE_PIXELS == 4096 * 4096  # one bound, the core's
    _refused(
        "_core.Camera(width=16384, height=16384, rgb=True, hfov=1.0)",
        "ConfigError",
        "camera.resolution",
        "16777216",
    )
    _refused("_core.Camera(width=4097, height=4096, rgb=True, hfov=1.0)", "ConfigError", "camera.resolution")
    r = _run("assert _core.Camera(width=16384, height=4, rgb=True, hfov=1.0).resolution == (16384, 4)")
    assert r["outcome"] == "ok", r


@pytest.mark.parametrize(("kwargs", "field"), [({"hs_m": float("nan")}, "hs_m"), ({"hs_m": -5.0}, "hs_m")])
def test_sampling_ahead_checks_the_sea_as_setting_it_does(kwargs: dict[str, float], field: str) -> None:
    scene, ids = core.demo_scene(extent=200.0, terrain_cells=8, vessels=1)
    scene.set_sea(1, np.array(ids, np.uint32))
    foci = np.zeros((1, 2), np.float32)
    with pytest.raises(mmusv.ConfigError, match=field):
        scene.set_wave_surface(**kwargs, foci=foci)
    with pytest.raises(mmusv.ConfigError, match=field):
        scene.prefetch_wave_surface(**kwargs, foci=foci)
    with pytest.raises(mmusv.ConfigError, match="tp_s"):
        scene.prefetch_wave_surface(1.0, tp_s=0.0, foci=foci)


def test_a_wave_surface_on_a_scene_without_a_sea_is_refused() -> None:
    scene, _ = core.demo_scene(extent=200.0, terrain_cells=8, vessels=1)
    with pytest.raises(mmusv.InputError, match="no sea surface; declare it with set_sea"):
        scene.set_wave_surface(1.0, foci=np.zeros((1, 2), np.float32), radius_m=3000.0)
    assert scene.wave_top is None


def test_huge_numbers_in_messages_are_written_short() -> None:
    """A translation of 1e300 was said as 301 digits, hiding what was allowed (Rust prints floats in full)."""
    scene, _ = core.demo_scene(extent=200.0, terrain_cells=8, vessels=1)
    pose = np.eye(4)
    pose[0, 3] = 1e300
    with pytest.raises(mmusv.InputError) as info:
        scene.add_instance(0, pose)
    msg = str(info.value)
    assert "1e300" in msg and len(msg) < 200 and "0" * 40 not in msg, msg


def _env(**change: Any) -> Any:
    kw: dict[str, Any] = {
        "sun_direction": [0.0, 0.6, 0.8],
        "turbidity": 3.0,
        "cloud_cover": 0.0,
        "ground_albedo": 0.1,
        "fog_extinction_per_m": 0.0,
        "rain_mm_per_h": 0.0,
        "wave_height_m": 0.5,
        "wind_speed_m_s": 5.0,
        "water_albedo": [0.02, 0.03, 0.04],
    }
    return core.SensorEnv(**{**kw, **change})


def test_the_environment_takes_a_cameras_exposure_range_and_unit_directions() -> None:
    """``SensorEnv(exposure_ev100=1e9)`` was taken (every image black) where a camera refuses it; ``sky_radiance``
    read a NaN or zero direction as the ground's radiance."""
    assert _env(exposure_ev100=15.0) is not None
    for ev in (1e9, -7.0, float("inf")):
        with pytest.raises(mmusv.ConfigError, match=r"env\.exposure_ev100 = .*: must be a finite EV100 in \[-6, 20\]"):
            _env(exposure_ev100=ev)
    env = _env()
    up = np.asarray(env.sky_radiance(np.array([[0.0, 0.0, 1.0]], np.float32)))
    assert up.shape == (1, 3) and np.isfinite(up).all()
    for bad in ([np.nan, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]):
        with pytest.raises(mmusv.InputError, match=r"dirs\[1\] = .*must be a unit vector"):
            env.sky_radiance(np.array([[0.0, 0.0, 1.0], bad], np.float32))


def test_abandon_after_close_returns_where_the_file_is(tmp_path: Path) -> None:
    """``abandon()`` once closed is a no-op that names the file that exists: the final name after ``finish()`` (it
    named the ``.partial``, gone by then), the ``.partial`` after an abandon or an exception in ``with``."""
    done = Recording(tmp_path / "done.mcap")
    _write(done, 2)
    done.finish()
    assert done.abandon() == tmp_path / "done.mcap" and done.abandon().is_file()
    with Recording(tmp_path / "clean.mcap") as clean:
        _write(clean, 1)
    assert clean.abandon() == tmp_path / "clean.mcap" and clean.abandon().is_file()
    left = Recording(tmp_path / "left.mcap")
    _write(left, 1)
    first = left.abandon()
    assert first == tmp_path / "left.mcap.partial" and first.is_file() and left.abandon() == first
    with pytest.raises(RuntimeError), Recording(tmp_path / "failed.mcap") as failed:
        _write(failed, 1)
        raise RuntimeError("stop")
    assert failed.abandon() == tmp_path / "failed.mcap.partial" and failed.abandon().is_file()


_HULL = [5.0, 2.5, 0.5, 0.5, 1.0]
_ONE = np.ones(1)


def _field() -> Any:
    return core.WaveField(hs_m=2.0, tp_s=8.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, seed=1)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda f: f.elevation(np.array([np.nan]), _ONE, 1.0),
            r"invalid x\[0\]: NaN is not allowed; give a finite number",
        ),
        (lambda f: f.slope(np.ones(2), np.array([1.0, np.inf]), 1.0), r"invalid y\[1\]: inf is not allowed"),
        (
            lambda f: f.elevation(_ONE, _ONE, float("nan")),
            r"invalid t: NaN is not allowed; give a finite time in seconds",
        ),
        (
            lambda f: f.orbital_velocity(np.array([[0.0, 0.0, -np.inf]]), 1.0),
            r"invalid points\[0\]\[2\]: -inf is not allowed",
        ),
        (lambda f: f.orbital_velocity(np.zeros((1, 3)), float("inf")), r"invalid t: inf is not allowed"),
        (lambda f: _response(positions=np.nan), r"invalid positions\[0\]\[0\]: NaN is not allowed"),
        (lambda f: _response(yaw=np.inf), r"invalid yaw\[0\]: inf is not allowed"),
        (lambda f: _response(velocities=-np.inf), r"invalid velocities\[0\]\[0\]: -inf is not allowed"),
        (lambda f: _response(times=np.nan), r"invalid times\[0\]: NaN is not allowed"),
        (lambda f: _rao(beta=np.nan), r"invalid beta\[0\]: NaN is not allowed"),
        (
            lambda f: _rao(omega_e=np.inf),
            r"invalid omega_e\[0\]: inf is not allowed; give an encounter frequency within ±1e6 rad/s",
        ),
        (
            lambda f: _rao(omega=1e300, omega_e=1.0),
            r"invalid omega\[0\]: 1e300 is not allowed; give a wave frequency within \[1e-6, 1e6\] rad/s",
        ),
        (
            lambda f: _rao(omega=1e-300, omega_e=1e-300),
            r"invalid omega\[0\]: 1e-300 is not allowed; give a wave frequency within \[1e-6, 1e6\] rad/s$",
        ),
        (lambda f: _variance(yaw=float("nan")), r"yaw = NaN: must be a finite heading in radians"),
        (lambda f: _variance(speed_mps=1e200), r"speed_mps = 1e200: must be a speed within \[0, 1e6\] m/s"),
    ],
)
def test_the_wave_fields_and_hulls_queries_refuse_what_they_would_answer_nan(call: Any, match: str) -> None:
    """The private wave field's point queries, the hull's RAOs and its response variances refused nothing but
    mismatched lengths (and omega <= 0): a NaN or infinite point, heading, velocity or time, a frequency past 1e77
    rad/s or below 1e-155, an encounter frequency of 1e300, a speed of 1e200 m/s all answered NaN without a word,
    which every sum over them carries. Each is refused now, naming the argument, its index and the range allowed."""
    with pytest.raises((mmusv.InputError, mmusv.ConfigError), match=match):
        call(_field())


def _response(*, positions: float = 0.0, yaw: float = 0.0, velocities: float = 1.0, times: float = 1.0) -> Any:
    return _field().hull_response(
        hull=_HULL,
        positions=np.full((1, 2), positions),
        yaw=np.array([yaw]),
        velocities=np.full((1, 2), velocities),
        times=np.array([times]),
    )


def _rao(*, omega: float = 1.0, beta: float = 0.0, omega_e: float = 1.0) -> Any:
    return core.hull_rao(hull=_HULL, omega=np.array([omega]), beta=np.array([beta]), omega_e=np.array([omega_e]))


def _variance(*, yaw: float = 0.0, speed_mps: float = 3.0) -> Any:
    return core.response_variance(
        hull=_HULL, hs_m=2.0, tp_s=8.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, yaw=yaw, speed_mps=speed_mps
    )


def test_the_wave_frequencies_a_hull_takes_give_finite_raos() -> None:
    """Over the whole range ``hull_rao`` takes — ω in [1e-6, 1e6] rad/s, encounter frequencies within ±1e6 of
    either sign and any heading — every RAO of three hulls (3 m to 330 m) is finite: the range refuses nothing the
    closed forms can answer, and answers nothing they cannot."""
    w = np.logspace(-6, 6, 49)
    ww, we = np.meshgrid(w, np.concatenate([-w[::-1], [0.0], w]))
    for hull in ([3.0, 1.2, 0.3, 0.4, 0.3], _HULL, [330.0, 60.0, 22.0, 0.85, 5.0]):
        for beta in (-7.0, 0.0, 0.4, np.pi / 2, np.pi, 1e6):
            r = core.hull_rao(hull=hull, omega=ww.ravel(), beta=np.full(ww.size, beta), omega_e=we.ravel())
            assert np.isfinite(r).all(), (hull, beta)
