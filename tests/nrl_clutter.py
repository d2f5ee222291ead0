"""The NRL sea-clutter model, written from its source, and the pair of sweeps that measures mmusv's against it:
one copy for both independent physics tests."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from mmusv.world.sea_state import sea_spec_for_height

NRL = {
    "HH": (-73.0, 20.781, 7.351, 25.65, 0.0054),
    "VV": (-50.796, 25.93, 0.7093, 21.588, 0.00211),
}
"""Gregers-Hansen & Mital (2012), the 0.1°–60° fit: c1..c5 as in the NRL memo's code (``NRL_SigmaSea.m``, V.
Gregers-Hansen 2010); the paper's table prints them rounded (HH c2 20.78; VV c1 −50.79, c4 21.58: ≤ 0.03 dB)."""


def nrl_sigma0(pol: str, f_ghz: float, ss: np.ndarray | float, psi_deg: np.ndarray) -> np.ndarray:
    """Gregers-Hansen & Mital (2012): σ⁰(dB) = c1 + c2 log10 sin ψ + (27.5 + c3 ψ) log10 f / (1 + 0.95 ψ)
    + c4 (SS + 1)^(1/(2 + 0.085 ψ + 0.033 SS)) + c5 ψ² (ψ in degrees, f in GHz, SS the sea state), linear."""
    c1, c2, c3, c4, c5 = NRL[pol]
    db = (
        c1
        + c2 * np.log10(np.sin(np.radians(psi_deg)))
        + (27.5 + c3 * psi_deg) * math.log10(f_ghz) / (1 + 0.95 * psi_deg)
        + c4 * (ss + 1) ** (1 / (2 + 0.085 * psi_deg + 0.033 * ss))
        + c5 * psi_deg**2
    )
    return np.asarray(10 ** (db / 10))


def fixed_and_physical_sweeps(
    scene: Any, radars: list[Any], pose: np.ndarray, env: Any, *, seed: int = 5
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """``radars[0]``'s sweep over ``scene``'s sea without a wave surface (the fixed clutter model, σ⁰_1m H²), then
    each radar's over a physical wave surface round the origin (the NRL model): with one seed every cell draws the
    same number in both, so a cell's ratio is the ratio of the two models' σ⁰. Returns (fixed, [physical, ...])."""
    scene.set_wave_surface(None, scenario_seed=1, time_s=0.0, foci=[[0.0, 0.0]])
    fixed = radars[0].sweep(scene.native, pose=pose, env=env, seed=seed)
    scene.set_wave_surface(
        sea_spec_for_height(1.0),
        scenario_seed=1,
        time_s=0.0,
        foci=[[0.0, 0.0]],
        radius_m=200.0,
        detail=False,
        slopes=False,
    )
    return fixed, [radar.sweep(scene.native, pose=pose, env=env, seed=seed) for radar in radars]
