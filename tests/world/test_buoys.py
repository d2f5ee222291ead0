"""The map's buoys: each its own instance, riding the physical sea (:mod:`mmusv.world.buoys`).

Before, every buoy of a map was one merged static mesh (one instance id for all of them in the instance images)
standing still at the still-water level while waves of 0.5–3.5 m passed through it: at W3 the floats drowned under
the crests and hung in the air over the troughs. The checks here are independent of the model's code: the water
a buoy rides is worked out from the field's elevation sampled over the float's waterplane (a polar quadrature:
Gauss–Legendre in radius, uniform in angle) and fitted with a plane by least squares, not from the field's
components and the Bessel weights the model uses; the buoys' heights come from rays cast down on them in the
simulation's scene.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from mmusv.classes import SemanticClass
from mmusv.errors import InputError
from mmusv.simulation import Simulation
from mmusv.world.buoys import buoy_matrices, buoy_poses, waterplane_weights
from mmusv.world.sea_state import sea_spec_for_preset

MARK_TOP_M = 3.8
"""Height of a buoy's top mark above its waterline (``mmusv.world.port.buoy_mesh``: "3.8 m above water")."""


def _scenario(*, motion: str) -> dict[str, Any]:
    return {
        "name": "buoys",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0, "n_buoys": 4}},
        "environment": {"time_of_day": "11:00", "weather": "clear", "wave": "W3", "motion": motion},
        "acquisition": {"frequency_hz": 2, "frames": 8},
        "rigs": {"r": {"preset": "lidar_only"}},
        "vessels": [{"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0,
                     "route": [[0, -200], [100, -200]]}],
    }  # fmt: skip


FLOAT_R_M = 1.2
"""The float's radius (``buoy_mesh``: a 1.2 m radius float)."""


def _waterplane_fit(
    field: Any, xy: np.ndarray, t: float, *, radius: float = FLOAT_R_M
) -> tuple[np.ndarray, np.ndarray]:
    """The plane fitted by least squares to the field's elevation over the disc of ``radius`` round each of ``xy``
    ``(N, 2)`` at ``t``: ``(N,)`` its height at the centre (the disc's mean elevation) and ``(N, 3)`` its unit
    normal. A polar quadrature of 48 Gauss–Legendre radii by 128 angles, exact to rounding for the waves of these
    seas (the shortest, 0.2 m, turn through 38 radians across the disc)."""
    r, wr = np.polynomial.legendre.leggauss(48)
    r, wr = radius * (r + 1.0) / 2.0, wr * radius / 2.0 * radius * (r + 1.0) / 2.0  # dA = r dr dθ
    th = np.arange(128) * (2.0 * np.pi / 128)
    dx = (r[:, None] * np.cos(th)[None, :]).ravel()
    dy = (r[:, None] * np.sin(th)[None, :]).ravel()
    w = np.repeat(wr, th.size)
    heights, normals = [], []
    for x0, y0 in xy:
        eta = field.elevation(x0 + dx, y0 + dy, t)
        design = np.column_stack([np.ones_like(dx), dx, dy]) * np.sqrt(w)[:, None]
        (c, sx, sy), *_ = np.linalg.lstsq(design, eta * np.sqrt(w), rcond=None)
        n = np.array([-sx, -sy, 1.0])
        heights.append(c)
        normals.append(n / np.linalg.norm(n))
    return np.array(heights), np.array(normals)


def test_a_buoy_stands_on_the_plane_fitted_to_the_water_over_its_waterplane() -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform(-400.0, 400.0, size=(24, 2))
    for wave in ("W0", "W3"):
        field = sea_spec_for_preset(wave).field(scenario_seed=3)
        for t in (0.0, 7.3, 61.0):
            poses = buoy_poses(field, xy, t)
            assert poses.shape == (24, 6) and np.array_equal(poses[:, :2], xy) and not poses[:, 5].any()
            height, normal = _waterplane_fit(field, xy, t)
            np.testing.assert_allclose(poses[:, 2], height, atol=1e-9)
            axis = buoy_matrices(field, xy, t)[:, :3, 2]
            np.testing.assert_allclose(axis, normal, atol=1e-9)
            # not the point's own surface: the ripples move the water at the centre, not the float
            point = field.elevation(xy[:, 0].copy(), xy[:, 1].copy(), t)
            assert np.abs(point - height).max() > 0.01
    rest = buoy_matrices(None, xy, 5.0)
    assert np.array_equal(rest[:, :3, :3], np.broadcast_to(np.eye(3), (24, 3, 3)))
    assert np.array_equal(rest[:, :2, 3], xy) and not rest[:, 2, 3].any()


def test_a_buoy_tilts_with_the_long_waves_and_not_with_the_ripples() -> None:
    # Before, the axis was the surface normal at the buoy's centre: a 2.4 m float tilted 8 degrees rms (up to 27)
    # at every sea state alike, most of it from waves shorter than 12 m. Its tilt now grows with the sea state and
    # is that of the waves longer than the float, within a fifth (their rms slope, from the linear sea's sum of
    # a^2 k^2 / 2 over the components at least twice the float's diameter long).
    xy = np.random.default_rng(1).uniform(-400.0, 400.0, size=(200, 2))
    rms = {}
    for wave in ("W0", "W1", "W2", "W3"):
        field = sea_spec_for_preset(wave).field(scenario_seed=7)
        a, _, k, _, _ = np.asarray(field.components()).T
        long = 2.0 * np.pi / k >= 4.0 * FLOAT_R_M
        expected = np.degrees(np.sqrt(np.sum((a**2 * k**2 / 2.0)[long])))
        tilt = np.concatenate(
            [np.degrees(np.arccos(buoy_matrices(field, xy, t)[:, 2, 2])) for t in np.arange(0.0, 20.0, 0.4)]
        )
        rms[wave] = float(np.sqrt(np.mean(tilt**2)))
        assert 0.8 * expected < rms[wave] < 1.2 * expected, (wave, rms[wave], expected)
    assert rms["W0"] < rms["W1"] < rms["W2"] < rms["W3"], rms


def _marks(sim: Simulation, frame: int, above: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays straight down on the points ``above`` ``(B, 2)`` after ``set_frame(frame)``: the instance and class
    hit and the height of the hit."""
    sim.set_frame(frame)
    origins = np.column_stack([above, np.full(len(above), 60.0)])
    down = np.tile([0.0, 0.0, -1.0], (len(above), 1))
    hits = sim.ws.scene.cast_rays(origins, down)
    return hits.instance_id, hits.semantic_class, 60.0 - hits.distance


@pytest.mark.parametrize("motion", ["physical", "paper"])
def test_each_buoy_is_its_own_instance_and_rides_the_sea(motion: str) -> None:
    sim = Simulation(_scenario(motion=motion))
    xy = sim.world.priors.buoys
    assert len(xy) >= 2
    ids = np.asarray(sim.ws.buoy_instances)
    assert len(np.unique(ids)) == len(xy)  # one instance id a buoy, not one for all of them
    others = set(sim.ws.static_instances.values()) | set(sim.ws.vessel_instances.tolist())
    assert not set(ids.tolist()) & others
    field = sim.scenario.environment.sea_spec().field(scenario_seed=sim.scenario.seed)
    tops, shares = [], []
    for frame in (0, 3, 7):
        t = frame / 2.0
        if motion == "physical":
            # The mark's tip stands its height above the water over the float, along that water's plane's normal;
            # where the sensed surface tapers its waves to the still level (260-320 m from the USV: buoy 3 here,
            # buoy 2 beyond it), that plane's height and slopes taper alike.
            height, normal = _waterplane_fit(field, xy, t)
            usv = sim.world_state(frame).poses[0, :2]
            share = np.clip((320.0 - np.linalg.norm(xy - usv, axis=1)) / 60.0, 0.0, 1.0)
            shares.append(share)
            slopes = -normal[:, :2] / normal[:, 2:] * share[:, None]
            normal = np.column_stack([-slopes, np.ones(len(xy))])
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
            tip = np.column_stack([xy, share * height]) + MARK_TOP_M * normal
        else:  # the paper's flat water: at rest
            tip = np.column_stack([xy, np.full(len(xy), MARK_TOP_M)])
        inst, cls, z = _marks(sim, frame, tip[:, :2])
        assert np.array_equal(inst, ids) and (cls == int(SemanticClass.BUOY)).all()
        np.testing.assert_allclose(z, tip[:, 2], atol=0.05)
        tops.append(z)
    moved = np.ptp(np.array(tops), axis=0).max()
    assert moved > 0.5 if motion == "physical" else moved == 0.0
    if motion == "physical":  # buoys in the full waves, in the taper and beyond it
        kinds = {("full" if v == 1.0 else "still" if v == 0.0 else "taper") for v in np.concatenate(shares)}
        assert kinds == {"full", "taper", "still"}


@pytest.mark.parametrize(
    ("args", "kw", "err"),
    [
        ((None, "abc", 0.0), {}, r"xy must be numeric"),
        ((None, [[0.0, 0.0, 0.0]], 0.0), {}, r"xy must have shape \(N, 2\), got \(1, 3\)"),
        ((None, [[np.nan, 0.0]], 0.0), {}, r"xy: every rest position must be a finite world x, y"),
        ((None, [[0.0, 0.0]], "1"), {}, r"t = '1': must be a finite number of seconds"),
        ((None, [[0.0, 0.0]], np.inf), {}, r"t = inf"),
        ((None, [[0.0, 0.0]], 0.0), {"radius_m": 0.0}, r"radius_m = 0.0: must be .* > 0"),
        ((None, [[0.0, 0.0]], 0.0), {"taper": [0.5, 0.5]}, r"taper: must be 1 shares in \[0, 1\]"),
        ((None, [[0.0, 0.0]], 0.0), {"taper": [1.5]}, r"taper: must be 1 shares in \[0, 1\]"),
        ((object(), [[0.0, 0.0]], 0.0), {}, r"field = .*: must be a wave field"),
    ],
)
def test_buoy_poses_names_a_bad_argument(args: tuple[Any, ...], kw: dict[str, Any], err: str) -> None:
    """They were a bare ValueError from numpy, or numbers out of nothing (a NaN position, a negative radius)."""
    with pytest.raises(InputError, match=err):
        buoy_poses(*args, **kw)


def test_waterplane_weights_name_a_bad_argument() -> None:
    with pytest.raises(InputError, match=r"radius_m = -1: must be .* > 0"):
        waterplane_weights([0.1, 0.2], -1)
    with pytest.raises(InputError, match=r"k: every wavenumber must be a finite number of rad/m >= 0"):
        waterplane_weights([-0.1], 1.2)
    assert buoy_poses(None, [], 0.0).shape == (0, 6)
