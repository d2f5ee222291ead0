"""Environment settings: time of day (sun), weather, and the wave setting.

They parameterise the motion model (wave height H scales heave, roll and pitch) and, later, the sensors
(camera shading and fog, LiDAR/radar attenuation and sea clutter).

* Time of day ``"HH:MM"`` → sun direction from a simple solar model (declination from ``day_of_year``,
  hour angle from local solar time, latitude ``latitude_deg``), sun colour warming near the horizon, and an
  ambient level; below the horizon the sun is off.
* Weather: ``clear``, ``overcast``, ``fog`` (with ``visibility_m``), ``rain`` (with ``rain_mm_per_h``); without
  ``visibility_m``, the rain's drops thin the sky's own visibility (:mod:`mmusv.world.rain`).
* Waves: presets ``W0``..``W3`` (H = 0.5, 1.5, 2.5, 3.5 m; amplitude A = H/2) or a free height in metres.

Frames: the sun direction is a unit vector in the world frame (x east, y north, z up) pointing *towards* the
sun.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Literal

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import ConfigError
from mmusv.world.rain import visibility_in_rain

__all__ = [
    "MAX_WAVE_HEIGHT_M",
    "WAVE_PRESETS",
    "Environment",
    "Sun",
    "Weather",
    "sun_at",
    "wave_height_m",
    "wave_problem",
]

WAVE_PRESETS: dict[str, float] = dict(core.wave_presets())
"""Wave height H in metres of each preset, in order W0..W3: the midpoint of the paper's interval (W0 0–1 m, W1
1–2 m, W2 2–3 m, W3 3–4 m; Sec. III-A and Table I), where H is "the simulator's geometric wave-height control" with
amplitude A = H/2, not a significant wave height. The paper's formula scales the motion by it; the physical sea
(``environment.motion: physical``) takes it as its significant height Hs (``docs/sea.md``), mmusv's choice. Read
from the core (``mmusv_core::kinematics::waves::WaveSetting::PRESETS``), their one definition."""

WeatherKind = Literal["clear", "overcast", "fog", "rain"]
_WEATHER: tuple[str, ...] = ("clear", "overcast", "fog", "rain")
_TIME_RE = re.compile(r"^([0-9]{1,2}):([0-9]{2})$")  # ASCII digits (\d would take "١٢:٠٠")


MAX_WAVE_HEIGHT_M: float = core.sea_limits()["hs_m"][1]
"""Highest wave height a scenario may give, metres: the physical sea's ``hs_m`` bound (``ocean::field::HS_RANGE_M``,
25 m)."""


def wave_problem(wave: object) -> str | None:
    """What is wrong with ``wave`` as ``environment.wave`` (what is allowed, for an error message, with the way out
    for a quoted height, ``null``, a list of choices and a sea state's mapping), or ``None`` when it is a preset name
    (``"W0"``..``"W3"``, any case) or a height in metres (a real number in ``0..MAX_WAVE_HEIGHT_M``; not
    ``True``/``False``)."""
    allowed = f"allowed presets are {', '.join(WAVE_PRESETS)} or a wave height in metres (0..{MAX_WAVE_HEIGHT_M:g})"
    if isinstance(wave, str):
        if wave.strip().upper() in WAVE_PRESETS:
            return None
        try:
            height = float(wave)
        except ValueError:
            return allowed
        if not math.isfinite(height):
            return allowed
        # a quoted height is text, not a preset (a height is a number: the schema and the editor say so too)
        return f"{allowed}; {wave!r:.30} is text: write the height as a number, wave: {height:g}"
    if wave is None:
        return f"{allowed}, not null: leave `wave` out for W0"
    if isinstance(wave, list | tuple):
        return f"{allowed}, not a list: one wave per scenario (a list of choices belongs in a generation spec)"
    if isinstance(wave, dict):
        return f"{allowed}, not a mapping: a physical sea (state, hs_m, tp_s, ...) goes under environment.sea"
    if not arguments.is_number(wave):
        return f"{allowed}, not {type(wave).__name__}"
    h = float(wave)
    if not (math.isfinite(h) and 0 <= h <= MAX_WAVE_HEIGHT_M):
        return (
            f"a wave height must be in 0..{MAX_WAVE_HEIGHT_M:g} metres (the significant height of the highest seas "
            "measured is about 19 m)"
        )
    return None


def wave_height_m(wave: str | float) -> float:
    """Wave height H (m) of a preset name (``"W0"``..``"W3"``, any case) or a height in metres (a real number ≥ 0;
    not ``True``/``False``); :class:`~mmusv.errors.ConfigError` naming ``environment.wave`` otherwise."""
    problem = wave_problem(wave)
    if problem is not None:
        raise ConfigError(f"invalid config environment.wave = {wave!r:.60}: {problem}")
    if isinstance(wave, str):
        return WAVE_PRESETS[wave.strip().upper()]
    return float(wave)


@dataclass(frozen=True)
class Sun:
    """Sun state. ``direction``: unit vector towards the sun (world frame); ``elevation_deg``/``azimuth_deg``
    (azimuth clockwise from north); ``color``: linear RGB in [0, 1]; ``intensity``: 0 at night, 1 at zenith
    in clear sky; ``ambient``: sky light level in [0, 1]."""

    direction: tuple[float, float, float]
    elevation_deg: float
    azimuth_deg: float
    color: tuple[float, float, float]
    intensity: float
    ambient: float


def _parse_time(text: str) -> float:
    if not isinstance(text, str):
        raise ConfigError(
            f'invalid config environment.time_of_day = {text!r:.60}: use 24-hour "HH:MM" as a string, e.g. "16:30"'
        )
    m = _TIME_RE.match(text.strip())
    if not m or int(m.group(1)) > 23 or int(m.group(2)) > 59:
        raise ConfigError(f'invalid config environment.time_of_day = {text!r}: use 24-hour "HH:MM", e.g. "16:30"')
    return int(m.group(1)) + int(m.group(2)) / 60.0


def sun_at(time_of_day: str, *, latitude_deg: float = 45.0, day_of_year: int = 172) -> Sun:
    """Sun direction, colour and light level at local solar time ``time_of_day`` (``"HH:MM"``), ``latitude_deg``
    (degrees, -90..90) and ``day_of_year`` (a whole number, 1..366)."""
    latitude_deg = arguments.real(latitude_deg, name="invalid config environment.latitude_deg", unit="degrees")
    day_of_year = arguments.whole(day_of_year, name="invalid config environment.day_of_year")
    if not -90.0 <= latitude_deg <= 90.0:
        raise ConfigError(f"invalid config environment.latitude_deg = {latitude_deg}: must be in [-90, 90]")
    if not 1 <= day_of_year <= 366:
        raise ConfigError(f"invalid config environment.day_of_year = {day_of_year}: must be in 1..366")
    hours = _parse_time(time_of_day)
    decl = math.radians(23.44) * math.sin(2 * math.pi * (284 + day_of_year) / 365.0)
    hour_angle = math.radians(15.0 * (hours - 12.0))
    lat = math.radians(latitude_deg)
    sin_el = math.sin(lat) * math.sin(decl) + math.cos(lat) * math.cos(decl) * math.cos(hour_angle)
    el = math.asin(max(-1.0, min(1.0, sin_el)))
    # Azimuth clockwise from north.
    az = math.atan2(
        -math.sin(hour_angle) * math.cos(decl),
        math.cos(lat) * math.sin(decl) - math.sin(lat) * math.cos(decl) * math.cos(hour_angle),
    ) % (2 * math.pi)
    direction = (math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el))
    up = max(0.0, math.sin(el))
    warm = 1.0 - min(1.0, up / 0.35)  # 1 at the horizon, 0 above ~20°
    color = (1.0, 1.0 - 0.35 * warm, 1.0 - 0.65 * warm)
    intensity = up**0.6 if el > 0 else 0.0
    ambient = 0.08 + 0.5 * (max(0.0, sin_el + 0.1) / 1.1) ** 0.5
    return Sun(direction, math.degrees(el), math.degrees(az), color, intensity, min(1.0, ambient))


@dataclass(frozen=True)
class Weather:
    """Weather: ``kind`` in {clear, overcast, fog, rain}; ``visibility_m`` (meteorological visibility, the
    distance at which contrast falls to 5 %); ``rain_mm_per_h``; ``cloud_cover`` in [0, 1].

    The visibility is the air's whole extinction for the cameras and the LiDAR, the rain's drops included (they
    dim 905 nm as they dim visible light): a visibility given is the one in the rain; left out, it follows from
    the rain rate (:meth:`make`, :mod:`mmusv.world.rain`) — Marshall–Palmer drops alone make it about
    3 / (0.365 R^0.63) km, 3.4 km at 4 mm/h, 1.9 km at 10, 0.7 km at 50. The rain rate
    itself sets the drops the cameras see near their lens (frozen dots by day, faint streaks in a long exposure:
    ``crates/mmusv-core/src/sensors/shade/rain.rs``), the radar's rain attenuation and clutter, and the drops that
    return in a LiDAR's beam (``crates/mmusv-core/src/sensors/lidar_rain.rs``); the LiDAR's attenuation is the
    visibility's alone (``crates/mmusv-core/src/sensors/lidar.rs``, step 4)."""

    kind: WeatherKind
    visibility_m: float
    rain_mm_per_h: float
    cloud_cover: float

    @property
    def extinction_per_m(self) -> float:
        """Atmospheric extinction coefficient σ (1/m) from visibility by Koschmieder's law, σ = 3.0 / V."""
        return 3.0 / self.visibility_m

    @classmethod
    def make(
        cls, kind: str = "clear", *, visibility_m: float | None = None, rain_mm_per_h: float | None = None
    ) -> Weather:
        """Weather of ``kind`` with sensible defaults: the air's visibility clear 20 km, overcast 10 km, fog 500 m,
        rain 10 km (an overcast sky's air) and a rain rate of 4 mm/h under ``rain`` (0 under the others). Without
        ``visibility_m`` the visibility is that air's with the rain's drops in it
        (:func:`mmusv.world.rain.visibility_in_rain`): 2.55 km in the default rain, 1.0 km at 25 mm/h, 437 m in
        fog with 4 mm/h falling; a visibility given is the one in the rain, its drops included, and is kept."""
        if kind not in _WEATHER:
            raise ConfigError(
                f"invalid config environment.weather = {kind!r}: allowed values are {', '.join(_WEATHER)}"
            )
        defaults = {
            "clear": (20000.0, 0.0, 0.1),
            "overcast": (10000.0, 0.0, 0.9),
            "fog": (500.0, 0.0, 1.0),
            "rain": (10000.0, 4.0, 1.0),
        }
        air, rain, cloud = defaults[kind]
        if rain_mm_per_h is not None:
            rain = arguments.real(rain_mm_per_h, name="invalid config environment.rain_mm_per_h", unit="mm/h")
        if not (math.isfinite(rain) and rain >= 0):
            raise ConfigError(f"invalid config environment.rain_mm_per_h = {rain_mm_per_h}: must be >= 0")
        if visibility_m is None:
            vis = visibility_in_rain(air, rain)
        else:
            vis = arguments.real(visibility_m, name="invalid config environment.visibility_m", unit="metres")
        if not (math.isfinite(vis) and vis > 0):
            raise ConfigError(f"invalid config environment.visibility_m = {visibility_m}: must be > 0 metres")
        return cls(kind, vis, rain, cloud)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Environment:
    """Resolved environment: sun, weather, wave height H (m) and, when a preset was named, its name."""

    time_of_day: str
    sun: Sun
    weather: Weather
    wave_height_m: float
    wave_preset: str | None

    @property
    def wave_amplitude_m(self) -> float:
        """Wave amplitude A = H / 2 in metres."""
        return self.wave_height_m / 2.0

    @classmethod
    def make(
        cls,
        *,
        time_of_day: str = "12:00",
        weather: str = "clear",
        visibility_m: float | None = None,
        rain_mm_per_h: float | None = None,
        wave: str | float = "W0",
        latitude_deg: float = 45.0,
        day_of_year: int = 172,
    ) -> Environment:
        """Resolves and validates an environment (errors name the ``environment.*`` field)."""
        preset = wave.strip().upper() if isinstance(wave, str) else None
        return cls(
            time_of_day=time_of_day,
            sun=sun_at(time_of_day, latitude_deg=latitude_deg, day_of_year=day_of_year),
            weather=Weather.make(weather, visibility_m=visibility_m, rain_mm_per_h=rain_mm_per_h),
            wave_height_m=wave_height_m(wave),
            wave_preset=preset,
        )
