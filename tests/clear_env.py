"""One clear, fog-free, windless sensor environment for the physics tests, every field explicit, and one LiDAR
without noise, dropout or water returns to measure in it."""

from __future__ import annotations

import numpy as np
from mmusv._native import core


def clear_env(sun: np.ndarray | tuple[float, float, float] = (0.3, 0.2, 0.93), **kw: object) -> core.SensorEnv:
    """A clear sky of turbidity 3, no fog, rain, waves or wind, black water; ``sun`` the unit direction towards the
    sun (world, z up); the keywords replace fields of :class:`mmusv._core.SensorEnv`."""
    args: dict[str, object] = {
        "sun_direction": [float(x) for x in sun],
        "turbidity": 3.0,
        "cloud_cover": 0.0,
        "ground_albedo": 0.06,
        "fog_extinction_per_m": 0.0,
        "rain_mm_per_h": 0.0,
        "wave_height_m": 0.0,
        "wind_speed_m_s": 0.0,
        "water_albedo": [0.0, 0.0, 0.0],
    }
    args.update(kw)
    return core.SensorEnv(**args)  # type: ignore[arg-type]


def clear_lidar(*, channels: int, azimuth_steps: int) -> core.Lidar:
    """A LiDAR of ``channels`` beams fanned over ±0.3° and ``azimuth_steps`` columns, 0.5–2,000 m, with no range
    noise, no dropout, no water returns and a line for a beam (no rain drop returns): every loss a test measures is
    the environment's."""
    return core.Lidar(
        elevations=list(core.uniform_elevations(channels=channels, lower=-0.3, upper=0.3)),
        azimuth_steps=azimuth_steps,
        range_min=0.5,
        range_max=2000.0,
        range_noise_std=0.0,
        dropout=0.0,
        water_probability=0.0,
        water_probability_per_wave_m=0.0,
        water_range_m=0.0,
        water_range_per_wave_m=0.0,
        beam_divergence=0.0,
    )
