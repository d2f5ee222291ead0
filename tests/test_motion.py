"""Vessel motion through the Python API: spline routes at nominal speed and wave perturbations."""

from __future__ import annotations

import math

import mmusv
import numpy as np
import pytest
from mmusv.config import load_scenario
from mmusv.motion import build_fleet, scenario_poses


def scenario(**kw: object) -> dict[str, object]:
    return {
        "seed": 3,
        "acquisition": {"frequency_hz": 10, "frames": 200},
        "environment": {"wave": kw.pop("wave", "W2")},
        "vessels": [
            {"id": "usv", "role": "usv", "asset": "usv_wamv", "speed_mps": 2.0, "route": [[0, 0], [60, 30], [120, 0]]},
            {"id": "big", "asset": "container_ship_300m", "speed_mps": 5.0, "route": [[0, 500], [2000, 500]]},
            {"id": "small", "asset": "jet_ski_3m", "speed_mps": 0.0, "route": [[10, 10], [20, 10]]},
        ],
    }


def test_distance_travelled_follows_speed_and_yaw_follows_tangent() -> None:
    poses = scenario_poses(load_scenario(scenario()))
    assert poses.shape == (200, 3, 6)
    xy = poses[:, 0, :2]
    travelled = np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1))
    assert travelled == pytest.approx(2.0 * 19.9, rel=5e-3)
    heading = np.arctan2(np.diff(xy[:, 1]), np.diff(xy[:, 0]))
    yaw = poses[:-1, 0, 5]
    err = np.angle(np.exp(1j * (heading - yaw)))
    assert np.max(np.abs(err)) < 0.05  # finite-difference heading vs analytic yaw at 10 Hz
    assert np.allclose(poses[:, 2, :2], [10, 10])  # speed 0 stays put


def test_small_vessels_move_more_than_large_ones_and_same_seed_same_poses() -> None:
    s = load_scenario(scenario())
    poses = scenario_poses(s)
    roll_rms = np.sqrt(np.mean(poses[:, :, 3] ** 2, axis=0))
    assert roll_rms[2] > roll_rms[0] > roll_rms[1]
    assert np.array_equal(poses, scenario_poses(load_scenario(scenario())))
    other = load_scenario({**scenario(), "seed": 4})
    assert not np.array_equal(poses, scenario_poses(other))


def test_fleet_rejects_bad_values_by_name() -> None:
    fleet = build_fleet(load_scenario(scenario()))
    with pytest.raises(mmusv.InputError):
        fleet.poses_at(-1.0)
    with pytest.raises(mmusv.ConfigError, match="W0"):
        build_fleet(load_scenario(scenario()), wave="W9")
    s = load_scenario(scenario())
    with pytest.raises(mmusv.ConfigError, match=r"vessels\[0\]"):
        # The Rust side validates too: a route doubling on a point is caught with the vessel named.
        build_fleet(
            s.model_copy(update={"vessels": [s.vessels[0].model_copy(update={"route": [(0.0, 0.0), (0.0, 0.0)]})]})
        )


def test_paper_motion_keeps_the_papers_formula() -> None:
    s = load_scenario({**scenario(), "environment": {"wave": "W2", "motion": "paper"}})
    fleet = build_fleet(s)
    assert not fleet.physical
    # Built exactly as before the physical sea existed: no sea, no hulls.
    from mmusv._native import core
    from mmusv.world.vessels import get_asset

    assets = [get_asset(v.asset) for v in s.vessels]
    legacy = core.Fleet(
        routes=[np.ascontiguousarray(v.route, dtype=np.float64) for v in s.vessels],
        end_behaviours=[v.end for v in s.vessels],
        speeds=np.array([v.speed_mps for v in s.vessels]),
        start_offsets=np.array([v.start_offset_m for v in s.vessels]),
        z_base=np.array([v.z_base_m for v in s.vessels]),
        dims=np.array([[a.length, a.beam, a.height] for a in assets]),
        amplitudes=np.tile(np.array(core.default_amplitudes()), (len(assets), 1)),
        seed=s.seed,
        wave="W2",
    )
    times = np.arange(50) / 10.0
    assert np.array_equal(fleet.poses_at_times(times), legacy.poses_at_times(times))
    assert build_fleet(load_scenario(scenario())).physical  # physical is the default


def test_reference_usvs_move_as_the_papers_reference_usv() -> None:
    """``reference_usvs`` (``mmusv study waves --usvs reference``): the paper's formula, ``S(H)·α_v·r·g(t)``, is
    linear in the size factor, so each USV's heave, roll and pitch about its route are its own divided by its
    ``α_v`` (that of the reference USV being 1); the route, yaw and every other vessel stay as they were."""
    s = load_scenario({**scenario(), "environment": {"wave": "W2", "motion": "paper"}})
    mine, ref = scenario_poses(s), scenario_poses(s, reference_usvs=True)
    alphas = build_fleet(s).alphas()
    assert alphas[0] != pytest.approx(1.0, abs=0.05)  # the WAM-V is not the reference size: the test can see it
    still = scenario_poses(s.with_wave(0.0))  # the same route at H = 0: the perturbation is what waves add
    np.testing.assert_allclose(ref[:, 0, 2:5] - still[:, 0, 2:5], (mine[:, 0, 2:5] - still[:, 0, 2:5]) / alphas[0])
    np.testing.assert_array_equal(ref[:, 0, [0, 1, 5]], mine[:, 0, [0, 1, 5]])
    np.testing.assert_array_equal(ref[:, 1:], mine[:, 1:])  # not USVs
    from mmusv._native import core

    assert core.reference_usv_dims() == (5.0, 2.5, 1.5)
    with pytest.raises(mmusv.ConfigError, match=r"environment\.motion = 'physical'.*motion: paper"):
        build_fleet(load_scenario(scenario()), reference_usvs=True)
    with pytest.raises(mmusv.ConfigError, match="reference_usvs"):
        build_fleet(s, reference_usvs="yes")  # type: ignore[arg-type]


LEGS = [("usv_wamv", 3.0, 2.3), ("tug_32m", 4.0, 0.9), ("bulk_carrier_190m", 6.0, 3.0)]
"""A 5 m USV, a 32 m tug and a 190 m bulk carrier: asset, speed m/s, heading rad."""


def _realised_variance(field: object, hull: list[float], yaw: float, u: float) -> np.ndarray:
    """(3,) exact long-run variance of one realisation: Σ |RAO(ωᵢ, βᵢ, ω_e,ᵢ)|² aᵢ²/2 over the field's components."""
    from mmusv._native import core

    c = field.components()  # type: ignore[attr-defined]
    a, w, k, th = (np.ascontiguousarray(c[:, j]) for j in range(4))
    h = core.hull_rao(hull=hull, omega=w, beta=th - yaw, omega_e=w - k * u * np.cos(th - yaw))
    return np.asarray((np.abs(h) ** 2 * a[:, None] ** 2 / 2).sum(axis=0))


def test_physical_motion_rms_matches_the_spectral_prediction() -> None:
    """Three hulls on straight legs at constant speed in the W2 sea. (1) The poses the motion pipeline produces over
    20 minutes have the RMS of the realised sea's components through the RAOs (within 10 %). (2) Over ten seeds
    the realised variances average to ∫∫|RAO|² S D, the core's quadrature independent of the sampled components
    (within 10 %; 5.6 % worst, the bulk carrier's heave): the sampler is unbiased. One realisation of 256
    components can miss by more for a hull whose response hangs on a few components (a 190 m ship's heave in 8 s
    waves comes from the near-beam ones)."""
    from mmusv._native import core
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    doc = {
        "seed": 21,
        "acquisition": {"frequency_hz": 2, "frames": 2400},
        "environment": {"wave": "W2"},
        "vessels": [
            {
                "id": f"v{i}",
                "role": "usv" if i == 0 else "target",
                "asset": asset,
                "speed_mps": u,
                "route": [[0, 500 * i], [20_000 * math.cos(yaw), 500 * i + 20_000 * math.sin(yaw)]],
            }
            for i, (asset, u, yaw) in enumerate(LEGS)
        ],
    }
    s = load_scenario(doc)
    poses = scenario_poses(s)
    sea = s.environment.sea_spec()
    for i, (asset, u, yaw) in enumerate(LEGS):
        hull = list(hull_particulars(get_asset(asset)))
        z = poses[:, i, 2] - s.vessels[i].z_base_m
        got = np.array([np.mean(z**2), np.mean(poses[:, i, 3] ** 2), np.mean(poses[:, i, 4] ** 2)])
        realised = _realised_variance(sea.field(scenario_seed=s.seed), hull, yaw, u)
        np.testing.assert_allclose(np.sqrt(got), np.sqrt(realised), rtol=0.10, err_msg=asset)
        want = core.response_variance(
            hull=hull,
            hs_m=sea.hs_m,
            tp_s=sea.tp_s,
            gamma=sea.gamma,
            direction_rad=sea.direction_rad,
            spread_s=sea.spread_s,
            yaw=yaw,
            speed_mps=u,
        )
        mean = np.mean([_realised_variance(sea.field(scenario_seed=seed), hull, yaw, u) for seed in range(10)], axis=0)
        np.testing.assert_allclose(np.sqrt(mean), np.sqrt(want), rtol=0.10, err_msg=asset)


def _jmo_amplitudes(hull: tuple[float, ...], omega: np.ndarray, beta: float, u: float) -> np.ndarray:
    """Jensen, Mansour & Olsen (2004) heave and pitch amplitudes and the 1-DOF roll amplitude, in numpy."""
    length, beam, draft, cb, gm = hull
    k = omega**2 / 9.80665
    alpha = 1 - u / np.sqrt(9.80665 * length) * np.sqrt(k * length) * np.cos(beta)
    ke = np.abs(k * np.cos(beta))
    b = cb * beam
    a = 2 * np.sin(k * b * alpha**2 / 2) * np.exp(-k * draft * alpha**2)
    f = np.sqrt((1 - k * draft) ** 2 + (a**2 / (k * b * np.abs(alpha) ** 3)) ** 2)
    sig = ke * length / 2
    eta = 1 / np.sqrt((1 - 2 * k * draft * alpha**2) ** 2 + (a**2 / (k * b * alpha**2)) ** 2)
    heave = eta * np.abs(np.exp(-ke * draft) * f * np.sin(sig) / sig)
    pitch = eta * np.abs(
        np.exp(-ke * draft) * f * 24 / ((ke * length) ** 2 * length) * (np.sin(sig) - sig * np.cos(sig))
    )
    wn = np.sqrt(9.80665 * gm) / (0.39 * beam)
    lam = np.abs(alpha * omega) / wn
    sy = k * abs(np.sin(beta)) * beam / 2
    r = 3 * (np.sin(sy) - sy * np.cos(sy)) / sy**3
    roll = k * abs(np.sin(beta)) * np.exp(-k * draft) * np.abs(r) / np.sqrt((1 - lam**2) ** 2 + (0.2 * lam) ** 2)
    return np.stack([heave, roll, pitch], axis=1)


@pytest.mark.parametrize("asset", ["usv_wamv", "tug_32m", "bulk_carrier_190m"])
def test_hull_raos_are_the_closed_forms(asset: str) -> None:
    from mmusv._native import core
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    hull = hull_particulars(get_asset(asset))
    omega = np.linspace(0.25, 3.0, 40)
    for beta, u in [(0.4, 3.0), (1.7, 5.0), (2.9, 6.0)]:
        k = omega**2 / 9.80665
        rao = core.hull_rao(
            hull=list(hull), omega=omega, beta=np.full(40, beta), omega_e=omega - k * u * math.cos(beta)
        )
        np.testing.assert_allclose(np.abs(rao), _jmo_amplitudes(hull, omega, beta, u), rtol=1e-9, atol=1e-12)


def test_scenario_poses_in_batches_are_the_same_poses(monkeypatch: pytest.MonkeyPatch) -> None:
    # A long scenario's poses are asked in batches (the core bounds one call: 7 vessels x 10^7 frames, which the
    # scenario schema allows, were refused naming `times`, an argument the user never gave); same values either way.
    import mmusv.motion as motion
    from tiny_scenario import lidar_scenario

    scenario = load_scenario({**lidar_scenario("batches", frames=23), "environment": {"motion": "physical"}})
    whole = motion.scenario_poses(scenario)
    monkeypatch.setattr(motion, "POSE_BATCH", 7)  # 3 times a call with 2 vessels
    batched = motion.scenario_poses(scenario)
    assert whole.shape == batched.shape == (23, 2, 6)
    assert np.array_equal(whole, batched)


PORT = {
    "name": "moored_waves",
    "seed": 5,
    "map": {"type": "port", "seed": 3},
    "acquisition": {"frequency_hz": 5, "frames": 12},
    "environment": {"wave": "W3"},
    "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
    "vessels": [
        {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]}
    ],
}


def test_moored_ships_ride_the_physical_sea_as_vessels_at_speed_0() -> None:
    """The moored ships of a port map stood fixed at the still level while the physical sea rose and fell along
    their hulls (W3: metres). Each now heaves, rolls and pitches as a scenario vessel of its asset at speed 0 at its
    berth and heading does, in the same wave field (its lines hold it in surge, sway and yaw), and the scene moves
    its instance with it; with ``motion: paper`` the moored ships stay fixed (the paper's bytes)."""
    from mmusv.simulation import Simulation

    sim = Simulation(PORT)
    n = len(sim.scenario.vessels)
    moored = sim.world.moored
    assert len(moored) >= 3
    twins = [  # a scenario vessel of each moored ship's asset at speed 0, at its berth, heading its way
        {
            "id": f"twin{k}",
            "asset": name,
            "speed_mps": 0,
            "route": [[x, y], [x + 10 * math.cos(yaw), y + 10 * math.sin(yaw)]],
        }
        for k, (name, (x, y, yaw)) in enumerate(moored)
    ]
    twin_poses = scenario_poses(load_scenario({**PORT, "vessels": [*PORT["vessels"], *twins]}))[:, n:]
    heave = []
    for k in range(sim.frames):
        state = sim.world_state(k)
        got = state.poses[n:]
        assert np.allclose(got[:, :5], twin_poses[k, :, :5], atol=1e-9), (k, got, twin_poses[k])
        assert np.allclose(np.angle(np.exp(1j * (got[:, 5] - [m[1][2] for m in moored]))), 0.0, atol=1e-9)
        assert np.allclose(got[:, :2], [m[1][:2] for m in moored], atol=1e-9)  # held at the berth
        heave.append(got[:, 2])
    spread = np.ptp(np.array(heave), axis=0)
    assert (spread > 0.05).all(), spread  # every ship heaves over the 12 frames at W3
    state = sim.set_frame(7)
    for inst, m in zip(sim.ws.moored_instances, state.matrices[n:], strict=True):
        assert np.allclose(sim.ws.scene.instance_pose(inst), m, atol=1e-6)
    paper = Simulation({**PORT, "environment": {"wave": "W3", "motion": "paper"}})
    for k in (0, 6):
        fixed = paper.world_state(k).poses[n:]
        assert (fixed[:, 2:5] == 0.0).all() and np.allclose(fixed[:, :2], [m[1][:2] for m in moored])
