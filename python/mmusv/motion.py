"""Vessel motion for a scenario: the Rust fleet (spline routes + wave motion) built from the config.

Poses are ``η = [x, y, z, roll, pitch, yaw]`` in the world frame (metres, radians), equation (3) of the paper
(Sec. II-C; equation (1) is the spline route, equation (2) the heave, roll and pitch perturbation).
Heave, roll and pitch come, with ``environment.motion: physical`` (the default), from each hull's response to the
scenario's wave field (closed-form RAOs from the asset's length, beam, draft, block coefficient and GM:
:mod:`mmusv.world.hydrostatics`, :mod:`mmusv.world.sea_state`); with ``motion: paper``, from the paper's formula
``S_wave(H)·α_v·r·g(t)`` (the vessel size factor α_v from each asset's bounding box: length, beam, height).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.config import Scenario
from mmusv.errors import ConfigError
from mmusv.world.hydrostatics import hull_particulars
from mmusv.world.vessels import get_asset

__all__ = ["POSE_BATCH", "build_fleet", "build_moored_fleet", "fleet_poses", "scenario_poses"]


def build_fleet(scenario: Scenario, *, wave: str | float | None = None, reference_usvs: bool = False) -> Any:
    """The ``mmusv._core.Fleet`` of ``scenario`` (vessel ``i`` = ``scenario.vessels[i]``), optionally with another
    wave setting (``wave`` drives the paper's formula, and the physical sea when ``environment.sea`` is not set).
    Wave phases and frequencies come from ``scenario.seed``. ``reference_usvs``: the paper's formula takes every
    vessel with ``role: usv`` at the size of the paper's reference USV (``core.reference_usv_dims()``, 5 × 2.5 ×
    1.5 m, ``α_v = 1``: the USV the amplitudes are calibrated on, which Table I describes) instead of its asset's
    box; only with ``motion: paper`` (the physical response reads the hulls themselves)."""
    vessels = _scenario(scenario).vessels
    assets = [get_asset(v.asset) for v in vessels]
    dims = np.array([[a.length, a.beam, a.height] for a in assets], dtype=np.float64)
    env = scenario.environment if wave is None else scenario.with_wave(wave).environment
    if arguments.flag(reference_usvs, name="reference_usvs"):
        if env.motion != "paper":
            raise ConfigError(
                f"environment.motion = {env.motion!r}: USVs of the paper's reference size are a setting of the "
                "paper's formula (motion: paper); the physical response reads each hull's own particulars"
            )
        dims[[i for i, v in enumerate(vessels) if v.role == "usv"]] = core.reference_usv_dims()
    return _core_fleet(
        scenario,
        env,
        assets,
        dims,
        routes=[np.ascontiguousarray(v.route, dtype=np.float64) for v in vessels],
        ends=[v.end for v in vessels],
        speeds=np.array([v.speed_mps for v in vessels], dtype=np.float64),
        offsets=np.array([v.start_offset_m for v in vessels], dtype=np.float64),
        z_base=np.array([v.z_base_m for v in vessels], dtype=np.float64),
    )


def _core_fleet(
    scenario: Scenario,
    env: Any,
    assets: list[Any],
    dims: np.ndarray,
    *,
    routes: list[np.ndarray],
    ends: list[str],
    speeds: np.ndarray,
    offsets: np.ndarray,
    z_base: np.ndarray,
) -> Any:
    """The ``mmusv._core.Fleet`` of vessels of ``assets`` (box ``dims``) on ``routes``, moved by the paper's formula
    or, with ``env.motion`` physical, by the scenario's sea through each hull's particulars."""
    physical: dict[str, Any] = {}
    if env.motion == "physical":
        physical["sea"] = env.sea_spec().field(scenario_seed=scenario.seed)
        physical["hulls"] = np.array([hull_particulars(a) for a in assets], dtype=np.float64).reshape(-1, 5)
    return core.Fleet(
        routes=routes,
        end_behaviours=ends,
        speeds=speeds,
        start_offsets=offsets,
        z_base=z_base,
        dims=dims,
        amplitudes=np.tile(np.array(core.default_amplitudes(), dtype=np.float64), (len(assets), 1)),
        seed=scenario.seed,
        wave=env.wave,
        **physical,
    )


MOORED_ROUTE_M = 10.0
"""The length of the route a moored ship's fleet is given along its heading (it does not sail it: speed 0)."""


def _scenario(value: Any) -> Scenario:
    """``value`` when it is a :class:`~mmusv.config.Scenario`, else a :class:`ConfigError` saying how to get one."""
    if not isinstance(value, Scenario):
        raise ConfigError(
            f"scenario = {arguments.shown(value)}: must be a mmusv.config.Scenario (mmusv.config.load_scenario(path "
            f"or dict) gives one), not {type(value).__name__}"
        )
    return value


def build_moored_fleet(scenario: Scenario, moored: list[tuple[str, tuple[float, float, float]]]) -> Any | None:
    """The ``mmusv._core.Fleet`` of a port map's moored ships ``(asset_name, (x, y, yaw))`` (world metres, radians),
    or ``None`` where they stay fixed at the still level: with ``motion: paper`` (the paper's ships at the quays do
    not move, and its bytes stay as published), with a sea of no height, or without moored ships. Over a physical
    sea each ship heaves, rolls and pitches in the scenario's wave field at speed 0 through its own RAOs, as a
    scenario vessel at speed 0 does (its lines hold it in surge, sway and yaw), at its berth and heading."""
    env = _scenario(scenario).environment
    if env.motion != "physical" or not moored or env.sea_spec().hs_m <= 0.0:
        return None
    assets = [get_asset(name) for name, _ in moored]
    routes = [
        np.array([[x, y], [x + MOORED_ROUTE_M * np.cos(yaw), y + MOORED_ROUTE_M * np.sin(yaw)]], dtype=np.float64)
        for _, (x, y, yaw) in moored
    ]
    zeros = np.zeros(len(moored), dtype=np.float64)
    dims = np.array([[a.length, a.beam, a.height] for a in assets], dtype=np.float64)
    ends = ["stop"] * len(moored)
    return _core_fleet(scenario, env, assets, dims, routes=routes, ends=ends, speeds=zeros, offsets=zeros, z_base=zeros)


POSE_BATCH = 1 << 14
"""Most poses (times × vessels) mmusv asks the core for in one call (:func:`fleet_poses`): more times are taken in
batches, the same values either way. A stop (Ctrl-C, the editor's Stop) ends a command only between native calls,
and a pose of the physical motion takes 30–70 µs of CPU (on a 2-core EPYC): the route checks of a long scenario
asked for up to 5 M poses in one call, minutes during which Ctrl-C did nothing. About half a second a call."""


def fleet_poses(fleet: Any, times: npt.NDArray[np.float64], *, vessels: int) -> npt.NDArray[np.float64]:
    """``(T, V, 6)`` float64 poses ``[x, y, z, roll, pitch, yaw]`` (world frame, metres, radians) of ``fleet`` (a
    ``core.Fleet`` of ``vessels`` vessels) at ``times`` ``(T,)`` (seconds): ``fleet.poses_at_times`` asked for at
    most :data:`POSE_BATCH` poses a call, so that a stop ends the work within a call's time."""
    step = max(1, POSE_BATCH // max(1, vessels))
    if len(times) <= step:
        return np.asarray(fleet.poses_at_times(times))
    return np.concatenate([np.asarray(fleet.poses_at_times(times[k : k + step])) for k in range(0, len(times), step)])


def scenario_poses(
    scenario: Scenario, *, wave: str | float | None = None, reference_usvs: bool = False
) -> npt.NDArray[np.float64]:
    """``(frames, vessels, 6)`` float64 poses ``[x, y, z, roll, pitch, yaw]`` (world frame, metres, radians) of
    ``scenario.vessels`` at every acquisition time t_k = k / f (``wave``, ``reference_usvs``: as
    :func:`build_fleet`)."""
    fleet = build_fleet(scenario, wave=wave, reference_usvs=reference_usvs)
    times = np.arange(scenario.acquisition.frames, dtype=np.float64) / scenario.acquisition.frequency_hz
    return fleet_poses(fleet, times, vessels=len(scenario.vessels))
