"""The environment as the sensors see it: one :class:`mmusv._core.SensorEnv` per scenario, passed to every
LiDAR scan, camera render and radar sweep.

From a resolved :class:`~mmusv.world.environment.Environment`: the direction towards the sun (world frame;
below the horizon at night), the air's turbidity, the cloud cover, fog extinction σ = 3 / visibility (1/m),
rain (mm/h), the significant wave height H (m), the wind and the water's colour. The cameras turn these into
radiance with the physical models of the core (Preetham sky, ESRA sun, GGX surfaces, Cox–Munk water,
Monahan whitecaps: ``crates/mmusv-core/src/sensors/shade/``); the LiDAR uses the fog extinction (the visibility's, the
rain's drops included), the waves and the wind; the radar the rain rate and the waves.

* **Turbidity** from the meteorological visibility ``V``: ``T = 1.9 + 30 / V_km``, clamped to [1.9, 10], a
  monotone mapping chosen so that a clear 20 km day is T ≈ 3.4 and a 5 km haze T ≈ 7.9 (the range over which
  Preetham et al. 1999 fitted their model); any visibility under 3.7 km saturates it, the fog's default 500 m
  among them, and the rain's default 2.6 km (its air's 10 km with the drops of 4 mm/h: :mod:`mmusv.world.rain`);
  both skies are overcast, cloud cover 1, which leaves the clear sky, and with it the turbidity, out.
* **Wind** (m/s at 10 m), when the scenario does not give one: the wind of a fully developed Pierson–Moskowitz
  sea of the scenario's significant height. Pierson & Moskowitz (1964) give it at 19.5 m (their weather ships'
  anemometers), ``U₁₉.₅ = √(H g / 0.21)``; the whitecaps (Monahan) and the water's slopes (Cox & Munk) take the
  10 m wind, ``U₁₀ = U₁₉.₅ / 1.026`` (Stewart, R. H. (2008), *Introduction to Physical Oceanography*, §16.4, for a
  drag coefficient of 1.3·10⁻³; a neutral log profile of that drag coefficient would give 1.060 instead, 3 % less
  wind at 10 m: the published ratio is kept, as the oceanographic references quote it). Cox & Munk's fit was to
  the wind at 12.5 m (their anemometer), 1–2 % above the 10 m wind; taking it at 10 m makes their mean square
  slope about 2 % smaller (1.8–1.9 % at the W0–W3 seas' winds, for the log profile of that drag coefficient).
* **Water body**: diffuse reflectance (linear RGB) of clear open-ocean water, blue (Morel 1988's case-1 water:
  a few per cent in the blue, well under one in the red).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import ConfigError, InputError
from mmusv.scene import Scene
from mmusv.world.environment import Environment

__all__ = [
    "SEA_ALBEDO",
    "WATER_ALBEDO",
    "check_config",
    "check_env",
    "check_sensor",
    "check_sensor_args",
    "sensor_env",
    "turbidity_from_visibility",
    "wake_rows",
    "wind_from_wave_height",
]

SEA_ALBEDO = 0.06
"""Albedo of the sea surface under a high sun (Payne 1972): the lower hemisphere of the cameras' sky light."""

WATER_ALBEDO = (0.004, 0.018, 0.03)
"""Diffuse reflectance of the water body, linear RGB."""


def wake_rows(wakes: npt.ArrayLike | None) -> npt.NDArray[np.float32] | None:
    """The vessels under way as the core takes them: ``(K, 6)`` to ``(K, 9)`` float32 C-contiguous rows
    ``x, y, heading, speed, length, beam[, reach_m[, age_s[, displacement_m3]]]`` (world metres, radians, m/s, s,
    m³; ``reach_m`` how far behind the stern the path ran straight, unlimited when left out; with ``age_s``, the
    rows are the pieces of wakes that follow their vessels' bends, :meth:`mmusv.simulation.Simulation.wakes`: a
    piece's foam is ``age_s`` old at its start and ends at ``reach_m``, where the next piece goes on;
    ``displacement_m3``, the vessel's displaced volume, sets the Kelvin waves the cameras draw, none when left
    out). One row may be given flat; ``None`` stays ``None``."""
    if wakes is None:
        return None
    try:
        w = np.ascontiguousarray(wakes, dtype=np.float32)
    except (TypeError, ValueError) as exc:
        raise InputError(f"wakes = {arguments.shown(wakes)}: must be numeric rows ({exc})") from None
    if w.ndim == 1 and w.size in (6, 7, 8, 9):
        w = w.reshape(1, -1)
    if w.ndim != 2 or w.shape[1] not in (6, 7, 8, 9):
        raise InputError(
            "wakes must have shape (K, 6) to (K, 9): x, y, heading, speed, length, beam[, reach_m[, age_s[, "
            f"displacement_m3]]]; got {w.shape}"
        )
    return w


def check_env(env: Any) -> core.SensorEnv:
    """``env`` when it is the sensors' environment (a ``mmusv._core.SensorEnv``: :func:`sensor_env`), else an
    :class:`mmusv.InputError` saying where one comes from."""
    if not isinstance(env, core.SensorEnv):
        raise InputError(
            f"env = {arguments.shown(env)}: must be the sensors' environment, mmusv.sensors.env.sensor_env(...) (or "
            f"Simulation.sensor_env), not {type(env).__name__}"
        )
    return env


def check_sensor_args(scene: Any, *, env: Any, seed: Any) -> int:
    """Checks the arguments every sensor call (:func:`~mmusv.sensors.lidar.scan`,
    :func:`~mmusv.sensors.camera.render`, :func:`~mmusv.sensors.radar.radar_sweep`) shares, in this order:
    ``scene`` an :class:`mmusv.Scene`, ``env`` the sensors' environment (:func:`check_env`) and ``seed`` a whole
    number in ``0..2⁶⁴−1``; the first bad one raises :class:`mmusv.InputError` naming it. Returns the seed."""
    if not isinstance(scene, Scene):
        raise InputError(f"scene must be an mmusv.Scene, got {type(scene).__name__}")
    check_env(env)
    return arguments.whole(seed, name="seed", lo=0, hi=2**64 - 1, error=InputError)


def check_config(cfg: Any, cls: type) -> None:
    """Checks that ``cfg``, the argument of a ``*_from_config`` builder, is a ``cls`` (a sensor config model of
    :mod:`mmusv.sensors.config`), else :class:`mmusv.ConfigError` naming the model that validates a dict."""
    if not isinstance(cfg, cls):
        raise ConfigError(
            f"cfg = {arguments.shown(cfg)}: must be a {cls.__name__} (mmusv.sensors.config.{cls.__name__}(**fields)), "
            f"not {type(cfg).__name__}"
        )


def check_sensor(sensor: Any, kind: type, *, name: str, made_by: str) -> None:
    """Checks that ``sensor``, the first argument of a sensor call, is a native ``kind`` (``core.Lidar``,
    ``core.Radar``, ``core.Camera``), else :class:`mmusv.InputError` naming the argument ``name`` (also the sensor's
    word, "lidar") and ``made_by``, the ways to get one."""
    if not isinstance(sensor, kind):
        raise InputError(
            f"{name} = {arguments.shown(sensor)}: must be a native {name} ({made_by}), not {type(sensor).__name__}"
        )


def turbidity_from_visibility(visibility_m: float) -> float:
    """Preetham turbidity (1.9..10) of air with meteorological visibility ``visibility_m`` (metres)."""
    return float(min(10.0, max(1.9, 1.9 + 30.0 / max(visibility_m / 1000.0, 1e-3))))


STANDARD_GRAVITY = 9.80665
"""g, m/s² (the core's wave field and sea-state presets use the same)."""
U19_5_PER_U10 = 1.026
"""Wind at 19.5 m over wind at 10 m above the sea (Stewart 2008, §16.4; see the module docstring)."""


def wind_from_wave_height(wave_height_m: float) -> float:
    """Wind speed (m/s) at 10 m of a fully developed Pierson–Moskowitz sea of significant height ``wave_height_m``
    (the module docstring: PM's 19.5 m wind divided by :data:`U19_5_PER_U10`)."""
    return math.sqrt(max(0.0, wave_height_m) * STANDARD_GRAVITY / 0.21) / U19_5_PER_U10


def sensor_env(
    environment: Environment | None = None,
    *,
    fog_extinction_per_m: float | None = None,
    rain_mm_per_h: float | None = None,
    wave_height_m: float | None = None,
    wind_speed_m_s: float | None = None,
    exposure_ev100: float | None = None,
    shadows: bool = True,
    water_multiple_scattering: bool = True,
) -> core.SensorEnv:
    """The sensors' view of ``environment`` (default: clear noon, ``Environment.make()``). The keyword values,
    when given, replace its fog extinction (1/m), rain (mm/h), wave height (m) and wind (m/s; default from the
    wave height), and fix the cameras' exposure (EV at ISO 100; default metered from the scene's light): for
    driving one sensor by hand. ``water_multiple_scattering=False`` leaves out the light reflected more than once
    between the sea's wave facets (single-scattering microfacet reflection alone, as renderers' rough BSDFs).
    Raises :class:`mmusv.ConfigError` naming ``env.<field>`` for a value out of range or of the wrong kind (a
    string or a boolean for a number, anything but ``True``/``False`` for a flag), or ``environment`` that is not
    an :class:`~mmusv.world.environment.Environment`."""
    if environment is not None and not isinstance(environment, Environment):
        raise ConfigError(
            f"environment = {arguments.shown(environment)}: must be an Environment (mmusv.world.environment."
            f"Environment.make(...), or Simulation.environment) or None, not {type(environment).__name__}"
        )
    given = {
        "fog_extinction_per_m": fog_extinction_per_m,
        "rain_mm_per_h": rain_mm_per_h,
        "wave_height_m": wave_height_m,
        "wind_speed_m_s": wind_speed_m_s,
        "exposure_ev100": exposure_ev100,
    }
    for name, value in given.items():
        if value is not None and not arguments.is_number(value):
            raise ConfigError(
                f"invalid config env.{name} = {arguments.shown(value)}: must be a number or None, "
                f"not {type(value).__name__}"
            )
    shadows = arguments.flag(shadows, name="invalid config env.shadows")
    water_multiple_scattering = arguments.flag(
        water_multiple_scattering, name="invalid config env.water_multiple_scattering"
    )
    env = environment if environment is not None else Environment.make()
    fog = env.weather.extinction_per_m if fog_extinction_per_m is None else fog_extinction_per_m
    rain = env.weather.rain_mm_per_h if rain_mm_per_h is None else rain_mm_per_h
    waves = env.wave_height_m if wave_height_m is None else wave_height_m
    wind = wind_from_wave_height(waves) if wind_speed_m_s is None else wind_speed_m_s
    return core.SensorEnv(
        sun_direction=[float(x) for x in env.sun.direction],
        turbidity=turbidity_from_visibility(env.weather.visibility_m),
        cloud_cover=float(env.weather.cloud_cover),
        ground_albedo=SEA_ALBEDO,
        fog_extinction_per_m=float(fog),
        rain_mm_per_h=float(rain),
        wave_height_m=float(waves),
        wind_speed_m_s=float(wind),
        water_albedo=list(WATER_ALBEDO),
        exposure_ev100=None if exposure_ev100 is None else float(exposure_ev100),
        shadows=shadows,
        water_multiple_scattering=water_multiple_scattering,
    )
