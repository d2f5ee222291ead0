"""The environment as the sensors see it: one :class:`mmusv._core.SensorEnv` per scenario, passed to every
LiDAR scan, camera render and radar sweep.

From a resolved :class:`~mmusv.world.environment.Environment`: the sun (direction towards it, world frame;
colour; intensity dimmed by clouds), a sky gradient from the sun height and cloud cover (linear RGB), fog
extinction σ = 3 / visibility (1/m), rain (mm/h) and the significant wave height H (m). Cameras use all of it;
the LiDAR fog, rain and waves; the radar rain and waves.
"""

from __future__ import annotations

import math

import numpy as np

from mmusv._native import core
from mmusv.world.environment import Environment

__all__ = ["FOG_COLOR", "sensor_env"]

FOG_COLOR = (0.72, 0.75, 0.78)
"""Linear RGB that distant surfaces fade to in fog."""


def sensor_env(
    environment: Environment | None = None,
    *,
    fog_extinction_per_m: float | None = None,
    rain_mm_per_h: float | None = None,
    wave_height_m: float | None = None,
    shadows: bool = True,
) -> core.SensorEnv:
    """The sensors' view of ``environment`` (default: clear noon, ``Environment.make()``). The keyword values,
    when given, replace its fog extinction (1/m), rain (mm/h) and wave height (m): for driving one sensor by
    hand. Raises :class:`mmusv.ConfigError` naming ``env.<field>`` for a negative or non-finite value."""
    env = environment if environment is not None else Environment.make()
    sun = env.sun
    cloud = env.weather.cloud_cover
    elev = max(0.0, math.sin(math.radians(sun.elevation_deg)))
    zen_clear = np.array([0.10, 0.28, 0.70]) * (0.3 + 0.7 * elev) + np.array([0.02, 0.02, 0.05])
    dusk = np.array([0.25, 0.1, 0.0]) * (1 - elev) * sun.intensity
    hor_clear = np.array([0.62, 0.70, 0.82]) * (0.4 + 0.6 * elev) + dusk
    grey = np.array([0.55, 0.57, 0.6])
    zenith = zen_clear * (1 - cloud) + grey * cloud
    horizon = hor_clear * (1 - cloud) + grey * 1.05 * cloud
    direct = sun.intensity * (1.0 - 0.85 * cloud)
    fog = env.weather.extinction_per_m if fog_extinction_per_m is None else fog_extinction_per_m
    rain = env.weather.rain_mm_per_h if rain_mm_per_h is None else rain_mm_per_h
    waves = env.wave_height_m if wave_height_m is None else wave_height_m
    return core.SensorEnv(
        sun_direction=[float(x) for x in sun.direction],
        sun_color=[float(x) for x in sun.color],
        sun_intensity=float(direct),
        ambient=float(sun.ambient),
        sky_zenith=[float(x) for x in zenith],
        sky_horizon=[float(x) for x in horizon],
        fog_extinction_per_m=float(fog),
        fog_color=list(FOG_COLOR),
        rain_mm_per_h=float(rain),
        wave_height_m=float(waves),
        shadows=shadows,
    )
