"""Marine radar: one revolution of a rotating ray-cast radar as sparse returns, and its PPI image.

The radar turns through ``azimuth_bins`` beams per revolution; each beam casts ``rays_az × rays_el`` rays
spread over its beamwidth and the elevation fan (all rays of a sweep go to the Rust core in one batch). Hits
are gathered per (azimuth bin, range bin) cell; a cell's intensity is the radar equation summed over its rays
(reflectivity by class × |cos incidence| × the ray's footprint, over range⁴, two-way rain attenuation), so
bigger and nearer targets are brighter. Hits on the sea (class WATER) are not targets: sea clutter is drawn
per cell instead, stronger and reaching farther for higher waves; rain adds a little clutter. The full model
is documented in the Rust module ``mmusv_core::sensors::radar_model``.

Intensity unit: linear, relative to the echo of a 1 m² target at 1 km in clear air (``0.01`` = −20 dB).
Frames: the sensor frame is x forward, y left, z up; azimuth 0 is forward, counter-clockwise, in ``[0, 2π)``.
Everything is deterministic for a given scene, pose, settings and ``seed`` (clutter and range noise are the
only random parts).

Example::

    ret = radar_sweep(scene, pose=mast_pose, settings=RadarSettings(range_m=2000), wave_height_m=1.25, seed=0)
    img = ppi_image(ret, size_px=512, metres_per_pixel=8.0)  # (512, 512) float32, north up
    ppi_png("ppi.png", img)
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from mmusv._native import core
from mmusv.errors import ConfigError, InputError
from mmusv.scene import Scene, _pose

__all__ = ["RadarSettings", "RadarReturns", "Orientation", "radar_sweep", "ppi_image", "ppi_colormap", "ppi_png"]

Orientation = Literal["north_up", "head_up"]
"""Which way is up in a PPI: world north, or the sensor's forward axis."""

# Core config field -> RadarSettings field, so that errors name the field the user set.
_SETTINGS_NAME = {
    "radar.range_max_m": "range_m",
    "radar.range_min_m": "min_range_m",
    "radar.beamwidth_az_rad": "beamwidth_deg",
    "radar.elevation_fan_rad": "elevation_fan_deg",
    "radar.horizon_band_rad": "horizon_band_deg",
    "radar.clutter.sea_sigma0_at_1m": "sea_clutter_sigma0",
    "radar.clutter.critical_range_per_m": "clutter_critical_range_per_m",
    "radar.clutter.sea_max_range_m": "sea_clutter_max_range_m",
    "radar.clutter.rain_eta_at_1mm_h": "rain_clutter_eta",
}


def _real(name: str, value: Any) -> float:
    """``value`` as a float, or a :class:`ConfigError` naming ``name`` (e.g. ``radar.range_m``)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(f"invalid config {name} = {value!r}: must be a real number")
    return float(value)


def _count(name: str, value: Any) -> int:
    """``value`` as a uint32, or a :class:`ConfigError` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= int(value) < 2**32:
        raise ConfigError(f"invalid config {name} = {value!r}: must be a non-negative integer below 2**32")
    return int(value)


@dataclass(frozen=True)
class RadarSettings:
    """Every knob of the radar, in user units. Validated when a sweep runs (a bad value raises
    :class:`mmusv.ConfigError` naming the field).

    Attributes:
        range_m: instrumented range, metres (``<= 100 km``).
        min_range_m: blind range, metres (hides the own ship), ``0 <= min_range_m < range_m``.
        range_resolution_m: range bin size, metres (``> 0``).
        azimuth_bins: beams per revolution (``1..65536``).
        beamwidth_deg: horizontal beamwidth, degrees, in ``(0, 90]``.
        elevation_fan_deg: vertical fan ``(lower, upper)``, degrees, strictly within ``(-90, 90)``.
        rays_az: rays per beam across the beamwidth (``>= 1``).
        rays_el: rays per beam over the elevation fan (``>= 1``); ``azimuth_bins · rays_az · rays_el <= 2²⁴``.
            Far, low targets are hit by few rays; raise it for steadier detection of small boats at km range.
        horizon_fraction: share of the elevation rays spread over the band around the sea horizon (which follows
            the sensor's roll and pitch), the rest over the remaining fan; ``0..1``, 0 = uniform over the fan.
            Rays are weighted by the fan height they stand for, so intensities do not depend on it.
        horizon_band_deg: half-height of that band, degrees (``0..45``).
        detection_threshold: smallest reported intensity (``>= 0``; 1.0 = a 1 m² target at 1 km).
        range_noise_std_m: Gaussian noise on the reported range, metres (``>= 0``).
        sea_clutter_sigma0: sea-clutter σ⁰ (m²/m²) at 1 m wave height (scales with height²); 0 disables.
        clutter_critical_range_per_m: metres of critical range per metre of wave height (sea clutter falls as
            r⁻⁷ beyond it, r⁻³ before).
        sea_clutter_max_range_m: no sea clutter beyond this range, metres.
        rain_clutter_eta: rain volume reflectivity (m²/m³) at 1 mm/h (scales with rate^1.6); 0 disables.
    """

    range_m: float = 3000.0
    min_range_m: float = 10.0
    range_resolution_m: float = 3.0
    azimuth_bins: int = 2048
    beamwidth_deg: float = 1.2
    elevation_fan_deg: tuple[float, float] = (-10.0, 10.0)
    rays_az: int = 3
    rays_el: int = 16
    horizon_fraction: float = 0.75
    horizon_band_deg: float = 1.0
    detection_threshold: float = 0.01
    range_noise_std_m: float = 0.0
    sea_clutter_sigma0: float = 4.0e-6
    clutter_critical_range_per_m: float = 300.0
    sea_clutter_max_range_m: float = 2500.0
    rain_clutter_eta: float = 5.0e-9

    def core_kwargs(self) -> dict[str, Any]:
        """The keyword arguments of ``mmusv._core.radar_sweep`` (SI units, radians)."""
        fan = self.elevation_fan_deg
        if not isinstance(fan, (tuple, list)) or len(fan) != 2:
            raise ConfigError(f"invalid config radar.elevation_fan_deg = {fan!r}: must be (lower, upper) degrees")
        return {
            "range_min_m": _real("radar.min_range_m", self.min_range_m),
            "range_max_m": _real("radar.range_m", self.range_m),
            "range_resolution_m": _real("radar.range_resolution_m", self.range_resolution_m),
            "azimuth_bins": _count("radar.azimuth_bins", self.azimuth_bins),
            "beamwidth_az_rad": math.radians(_real("radar.beamwidth_deg", self.beamwidth_deg)),
            "elevation_fan_rad": (
                math.radians(_real("radar.elevation_fan_deg", fan[0])),
                math.radians(_real("radar.elevation_fan_deg", fan[1])),
            ),
            "rays_az": _count("radar.rays_az", self.rays_az),
            "rays_el": _count("radar.rays_el", self.rays_el),
            "horizon_fraction": _real("radar.horizon_fraction", self.horizon_fraction),
            "horizon_band_rad": math.radians(_real("radar.horizon_band_deg", self.horizon_band_deg)),
            "detection_threshold": _real("radar.detection_threshold", self.detection_threshold),
            "range_noise_std_m": _real("radar.range_noise_std_m", self.range_noise_std_m),
            "sea_sigma0_at_1m": _real("radar.sea_clutter_sigma0", self.sea_clutter_sigma0),
            "critical_range_per_m": _real("radar.clutter_critical_range_per_m", self.clutter_critical_range_per_m),
            "sea_max_range_m": _real("radar.sea_clutter_max_range_m", self.sea_clutter_max_range_m),
            "rain_eta_at_1mm_h": _real("radar.rain_clutter_eta", self.rain_clutter_eta),
        }


@dataclass(frozen=True, eq=False)
class RadarReturns:
    """The returns of one sweep (N of them), sorted by (azimuth bin, range bin), at most one per cell.

    Attributes:
        range: ``(N,)`` float32, metres: the range-bin centre plus the optional range noise.
        azimuth: ``(N,)`` float32, radians in ``[0, 2π)``, sensor frame, 0 = forward, counter-clockwise (the
            beam's centre azimuth).
        elevation: ``(N,)`` float32, radians, sensor frame: echo-weighted elevation of the rays in the cell
            (clutter: the sea surface's elevation at that range, for a level sensor).
        intensity: ``(N,)`` float32, linear, relative to a 1 m² target at 1 km; ``>= detection_threshold``.
        instance_id: ``(N,)`` int32, scene instance of the strongest echo in the cell; ``-1`` for clutter.
        semantic_class: ``(N,)`` uint16, class of that echo (:mod:`mmusv.classes`); WATER (1) for sea
            clutter, NONE (0) for rain clutter.
        pose: ``(4, 4)`` float64 sensor → world pose of the sweep.
        settings: the settings of the sweep.
    """

    range: npt.NDArray[np.float32]
    azimuth: npt.NDArray[np.float32]
    elevation: npt.NDArray[np.float32]
    intensity: npt.NDArray[np.float32]
    instance_id: npt.NDArray[np.int32]
    semantic_class: npt.NDArray[np.uint16]
    pose: npt.NDArray[np.float64]
    settings: RadarSettings

    def __len__(self) -> int:
        return int(self.range.shape[0])

    @property
    def is_clutter(self) -> npt.NDArray[np.bool_]:
        """``(N,)`` bool, True for clutter returns (no scene object)."""
        return self.instance_id < 0

    @property
    def sensor_yaw(self) -> float:
        """World yaw of the sensor's forward axis, radians (counter-clockwise from east)."""
        return math.atan2(float(self.pose[1, 0]), float(self.pose[0, 0]))

    def points(self, frame: Literal["sensor", "world"] = "sensor") -> npt.NDArray[np.float32]:
        """``(N, 3)`` float32 positions of the returns (range, azimuth, elevation) in metres, in the sensor
        frame or the world frame."""
        r = self.range.astype(np.float64)
        a = self.azimuth.astype(np.float64)
        e = self.elevation.astype(np.float64)
        p = np.stack([r * np.cos(e) * np.cos(a), r * np.cos(e) * np.sin(a), r * np.sin(e)], axis=1)
        if frame == "world":
            p = p @ self.pose[:3, :3].T + self.pose[:3, 3]
        elif frame != "sensor":
            raise InputError(f"frame must be 'sensor' or 'world', got {frame!r}")
        return p.astype(np.float32)


def radar_sweep(
    scene: Scene,
    *,
    pose: npt.ArrayLike,
    settings: RadarSettings | None = None,
    wave_height_m: float = 0.0,
    rain_mm_per_h: float = 0.0,
    seed: int,
) -> RadarReturns:
    """One full revolution of the radar at ``pose`` (``(4, 4)`` sensor → world; sensor x forward, y left,
    z up) in ``scene``, with sea clutter for waves of ``wave_height_m`` metres (0..30; e.g. W0 = 0.5,
    W3 = 3.5) and rain of ``rain_mm_per_h`` (0..500). Releases the GIL and uses every core.

    Raises :class:`mmusv.ConfigError` naming the field for bad settings, :class:`mmusv.InputError` for a
    bad pose or seed.
    """
    s = RadarSettings() if settings is None else settings
    if not isinstance(s, RadarSettings):
        raise InputError(f"settings must be a RadarSettings, got {type(s).__name__}")
    if not isinstance(scene, Scene):
        raise InputError(f"scene must be an mmusv.Scene, got {type(scene).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**64:
        raise InputError(f"seed must be an integer in 0..2**64, got {seed!r}")
    p = _pose(pose, name="pose")
    kwargs = s.core_kwargs()
    waves = _real("radar.wave_height_m", wave_height_m)
    rain = _real("radar.rain_mm_per_h", rain_mm_per_h)
    try:
        out = core.radar_sweep(scene.native, pose=p, **kwargs, wave_height_m=waves, rain_mm_per_h=rain, seed=int(seed))
    except ConfigError as exc:
        msg = str(exc)
        for core_name, name in _SETTINGS_NAME.items():
            if core_name in msg:
                raise ConfigError(f"RadarSettings.{name}: {msg}") from None
        raise
    return RadarReturns(
        range=out["range"],
        azimuth=out["azimuth"],
        elevation=out["elevation"],
        intensity=out["intensity"],
        instance_id=out["instance"],
        semantic_class=out["class"],
        pose=p,
        settings=s,
    )


def ppi_image(
    returns: RadarReturns,
    *,
    size_px: int = 512,
    metres_per_pixel: float | None = None,
    orientation: Orientation = "north_up",
    sensor_yaw: float | None = None,
    settings: RadarSettings | None = None,
) -> npt.NDArray[np.float32]:
    """The ``(size_px, size_px)`` float32 plan-position image of ``returns``: ego at pixel
    ``(size_px // 2, size_px // 2)``, row 0 at the top (north for ``"north_up"``, ahead for ``"head_up"``),
    each return painted over its range-bin × azimuth-bin polar cell with max compositing; 0 where nothing.

    The scale is fixed: a return at range R lies ``R / metres_per_pixel`` pixels from the centre in every
    frame. ``metres_per_pixel`` defaults to ``settings.range_m / (size_px // 2)`` (the full range fills the
    image); ``sensor_yaw`` (radians, for north-up) defaults to the sweep pose's yaw; ``settings`` (cell
    size) to the sweep's.
    """
    s = returns.settings if settings is None else settings
    size = _count("ppi.size_px", size_px)
    mpp = s.range_m / max(size // 2, 1) if metres_per_pixel is None else _real("ppi.metres_per_pixel", metres_per_pixel)
    yaw = returns.sensor_yaw if sensor_yaw is None else _real("sensor_yaw", sensor_yaw)
    kw = s.core_kwargs()
    return np.asarray(
        core.ppi_image(
            range=np.ascontiguousarray(returns.range, dtype=np.float32),
            azimuth=np.ascontiguousarray(returns.azimuth, dtype=np.float32),
            intensity=np.ascontiguousarray(returns.intensity, dtype=np.float32),
            size_px=size,
            metres_per_pixel=mpp,
            orientation=orientation,
            sensor_yaw=yaw,
            range_resolution_m=kw["range_resolution_m"],
            azimuth_bins=kw["azimuth_bins"],
        )
    )


def ppi_colormap(img: npt.ArrayLike, *, vmin_db: float = -20.0, vmax_db: float = 30.0) -> npt.NDArray[np.uint8]:
    """``(H, W, 3)`` uint8 radar-green rendering of a PPI: intensity in dB (``10·log10``) mapped linearly from
    ``vmin_db`` (dark green) to ``vmax_db`` (near white); pixels ``<= 0`` are black. Fixed limits by default,
    so frames are comparable."""
    a = np.asarray(img, dtype=np.float64)
    if a.ndim != 2:
        raise InputError(f"img must be a (H, W) intensity image, got shape {a.shape}")
    if not vmax_db > vmin_db:
        raise InputError(f"need vmax_db > vmin_db, got {vmin_db} and {vmax_db}")
    with np.errstate(divide="ignore", invalid="ignore"):
        db = 10.0 * np.log10(a)
    t = np.clip((db - vmin_db) / (vmax_db - vmin_db), 0.0, 1.0)
    rgb = np.stack([255.0 * t**3, 50.0 + 205.0 * t**0.6, 30.0 * t + 200.0 * t**4], axis=-1)
    rgb[~(a > 0)] = 0.0
    return np.ascontiguousarray(np.rint(rgb), dtype=np.uint8)


def ppi_png(path: str | os.PathLike[str], img: npt.ArrayLike, **colormap: float) -> None:
    """Writes a PPI to ``path`` as PNG (atomically): a ``(H, W)`` intensity image goes through
    :func:`ppi_colormap` (``colormap`` are its keyword arguments), a ``(H, W, 3)`` uint8 image is written as is."""
    from PIL import Image

    a = np.asarray(img)
    rgb = ppi_colormap(a, **colormap) if a.ndim == 2 else a
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise InputError(f"img must be (H, W) float or (H, W, 3) uint8, got {a.shape} {a.dtype}")
    target = os.fspath(path)
    fd, tmp = tempfile.mkstemp(suffix=".png", dir=os.path.dirname(os.path.abspath(target)))
    os.close(fd)
    try:
        Image.fromarray(rgb, "RGB").save(tmp, format="PNG")
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
