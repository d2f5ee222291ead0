"""Marine radar: one revolution of a rotating ray-cast radar as sparse returns, and its PPI image.

The radar turns through ``azimuth_bins`` beams per revolution; each beam casts ``rays_az × rays_el`` rays
spread over its beamwidth and the elevation fan (all rays of a sweep go to the Rust core in one batch). Hits
are gathered per (azimuth bin, range bin) cell; a cell's intensity is the radar equation summed over its rays
(reflectivity by class × |cos incidence| × the ray's footprint, over range⁴, weighted by the fan beam's two-way
Gaussian elevation gain, 1 on the fan's axis and ¼ at its edges, and by the two-way rain attenuation of ITU-R
P.838-3 at the radar's ``frequency_ghz`` and ``polarisation``), so bigger and nearer targets are brighter. Hits on
the sea (class WATER) are not targets: sea clutter is drawn per cell instead (the pulse-limited cell
``r θ_az Δr sec ψ``, weighted by the elevation gain where that water lies), stronger and reaching farther for
higher waves, from the water the beam sees (none over land or in the shadow of an island, a quay or a ship); rain
adds clutter of volume reflectivity ``rain_clutter_eta`` · R^1.6 (R in mm/h), scaled by λ⁻⁴ from 9.41 GHz to the
radar's frequency. The full model is documented in the Rust module ``mmusv_core::sensors::radar_model``.

Intensity unit: linear, relative to the echo of a 1 m² target at 1 km in clear air (``0.01`` = −20 dB).
Frames: the sensor frame is x forward, y left, z up; azimuth 0 is forward, counter-clockwise, in ``[0, 2π)``.
Everything is deterministic for a given scene, pose, configuration, environment and ``seed`` (clutter and
range noise are the only random parts).

Configuration: :class:`mmusv.sensors.config.RadarConfig` is the one definition of every knob, its defaults and
its limits; :func:`radar_from_config` binds it once to the core's radar.

Example::

    radar = radar_from_config(RadarConfig(range_m=2000))
    ret = radar_sweep(radar, scene, pose=mast_pose, env=sensor_env(wave_height_m=1.25), seed=0)
    img = ppi_image(ret, size_px=512, metres_per_pixel=8.0)  # (512, 512) float32, north up
    ppi_png("ppi.png", img)
"""

from __future__ import annotations

import copy
import math
import os
import tempfile
from dataclasses import dataclass, field, fields
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._equality import same
from mmusv._native import core
from mmusv.errors import ConfigError, InputError
from mmusv.scene import Scene, _pose
from mmusv.sensors.config import RadarConfig
from mmusv.sensors.env import check_config, check_sensor, check_sensor_args

__all__ = [
    "MAX_PPI_SIZE",
    "Orientation",
    "RadarReturns",
    "ppi_colormap",
    "ppi_image",
    "ppi_png",
    "ppi_request",
    "radar_from_config",
    "radar_sweep",
]

Orientation = Literal["north_up", "head_up"]
"""Which way is up in a PPI: world north, or the sensor's forward axis."""


def radar_from_config(cfg: RadarConfig) -> core.Radar:
    """The native radar for ``cfg`` (degrees become radians; the core checks everything again as a last guard,
    naming ``radar.<core field>``, which a validated ``cfg`` never trips). ``cfg`` must be a :class:`RadarConfig`
    (``RadarConfig(**fields)`` validates a dict), else :class:`mmusv.ConfigError`. ``sea_clutter_sigma0 = 0``
    becomes a sea-clutter range of 0 as well, so that it disables sea clutter over the physical sea too."""
    check_config(cfg, RadarConfig)
    lo, hi = cfg.elevation_fan_deg
    # σ⁰ = 0 disables sea clutter on the physical sea too, whose σ⁰ is the NRL model's (the core reads
    # `sea_sigma0_at_1m` on the flat sea only): no sea clutter at any range.
    sea_max_range_m = cfg.sea_clutter_max_range_m if cfg.sea_clutter_sigma0 > 0 else 0.0
    return core.Radar(
        range_min_m=cfg.min_range_m,
        range_max_m=cfg.range_m,
        range_resolution_m=cfg.range_resolution_m,
        azimuth_bins=cfg.azimuth_bins,
        beamwidth_az_rad=math.radians(cfg.beamwidth_deg),
        elevation_fan_rad=(math.radians(lo), math.radians(hi)),
        rays_az=cfg.rays_az,
        rays_el=cfg.rays_el,
        target_rays=cfg.target_rays,
        horizon_fraction=cfg.horizon_fraction,
        horizon_band_rad=math.radians(cfg.horizon_band_deg),
        detection_threshold=cfg.detection_threshold,
        range_noise_std_m=cfg.range_noise_std_m,
        sea_sigma0_at_1m=cfg.sea_clutter_sigma0,
        critical_range_per_m=cfg.clutter_critical_range_per_m,
        sea_max_range_m=sea_max_range_m,
        rain_eta_at_1mm_h=cfg.rain_clutter_eta,
        frequency_ghz=cfg.frequency_ghz,
        polarisation=cfg.polarisation,
    )


@dataclass(frozen=True, eq=False)
class RadarReturns:
    """The returns of one sweep (N of them), sorted by (azimuth bin, range bin), at most one per cell.

    Two sweeps compare equal (``==``) when their arrays and pose are (dtype, shape and value). A sweep pickles
    when it knows the :class:`RadarConfig` its radar was made from (``config``: every sweep of
    :meth:`mmusv.Simulation.capture`), its native radar rebuilt from it; copies share the native radar.

    Attributes:
        range: ``(N,)`` float32, metres: the range-bin centre plus the optional range noise.
        azimuth: ``(N,)`` float32, radians in ``[0, 2π)``, sensor frame, 0 = forward, counter-clockwise (the
            beam's centre azimuth).
        elevation: ``(N,)`` float32, radians, sensor frame: echo-weighted elevation of the rays in the cell
            (clutter: where the still sea level, world z = 0, lies at that range and azimuth seen from the sensor's
            height: the sea horizon's elevation in the sensor frame, tilted as the sensor is, less
            ``atan(height / range)``; the waves are not in it).
        intensity: ``(N,)`` float32, linear, relative to a 1 m² target at 1 km; ``>= detection_threshold``.
        instance_id: ``(N,)`` int32, scene instance of the strongest echo in the cell; ``-1`` for clutter.
        semantic_class: ``(N,)`` uint16, class of that echo (:mod:`mmusv.classes`); WATER (1) for sea
            clutter, NONE (0) for rain clutter.
        pose: ``(4, 4)`` float64 sensor → world pose of the sweep.
        radar: the radar that swept (its range and bins size the PPI).
        config: the :class:`RadarConfig` ``radar`` was made from (:func:`radar_from_config`), when known
            (``None`` for a sweep of :func:`radar_sweep`); what a pickled sweep rebuilds its radar from.
    """

    range: npt.NDArray[np.float32]
    azimuth: npt.NDArray[np.float32]
    elevation: npt.NDArray[np.float32]
    intensity: npt.NDArray[np.float32]
    instance_id: npt.NDArray[np.int32]
    semantic_class: npt.NDArray[np.uint16]
    pose: npt.NDArray[np.float64]
    radar: core.Radar = field(compare=False)
    config: RadarConfig | None = field(default=None, repr=False, compare=False)

    def __len__(self) -> int:
        return int(self.range.shape[0])

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`); not the native radar."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its arrays, pose and ``config``, from which the native radar (which does not pickle) is
        rebuilt; a sweep without ``config`` is refused with :class:`mmusv.InputError`."""
        if self.config is None:
            raise InputError(
                "this RadarReturns cannot be pickled: its radar is a native mmusv._core.Radar, which pickles only as "
                "the RadarConfig it was made from, and this sweep does not know it (a sweep of "
                "Simulation.capture does); give it one with dataclasses.replace(returns, config=cfg)"
            )
        values = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "radar"}
        return (_unpickled_returns, (values,))

    def __copy__(self) -> RadarReturns:
        return type(self)(**{f.name: getattr(self, f.name) for f in fields(self)})

    def __deepcopy__(self, memo: dict[int, Any]) -> RadarReturns:
        """The arrays copied; the native radar (configured once, never changed) shared."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return type(self)(**{k: v if k == "radar" else copy.deepcopy(v, memo) for k, v in values.items()})

    @classmethod
    def from_native(
        cls,
        d: dict[str, npt.NDArray[Any]],
        *,
        pose: npt.NDArray[np.float64],
        radar: core.Radar,
        config: RadarConfig | None = None,
    ) -> RadarReturns:
        """The returns from the dict of ``core.Radar.sweep`` (or of ``core.capture_frame``) swept at ``pose`` by
        ``radar`` (made from ``config``, when known: see the class docstring)."""
        return cls(
            range=d["range"],
            azimuth=d["azimuth"],
            elevation=d["elevation"],
            intensity=d["intensity"],
            instance_id=d["instance"],
            semantic_class=d["class"],
            pose=pose,
            radar=radar,
            config=config,
        )

    @property
    def is_clutter(self) -> npt.NDArray[np.bool_]:
        """``(N,)`` bool, True for clutter returns (no scene object)."""
        return self.instance_id < 0

    @property
    def sensor_yaw(self) -> float:
        """World yaw of the sensor's forward axis, radians (counter-clockwise from east)."""
        return _yaw(self.pose)

    def points(self, *, frame: Literal["sensor", "world"] = "sensor") -> npt.NDArray[np.float32]:
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


def _unpickled_returns(values: dict[str, Any]) -> RadarReturns:
    """A pickled :class:`RadarReturns` (:meth:`RadarReturns.__reduce__`), its radar rebuilt from its config."""
    return RadarReturns(**values, radar=radar_from_config(values["config"]))


def radar_sweep(
    radar: core.Radar, scene: Scene, *, pose: npt.ArrayLike, env: core.SensorEnv, seed: int
) -> RadarReturns:
    """One full revolution of ``radar`` (:func:`radar_from_config`) at ``pose`` (``(4, 4)`` sensor → world;
    sensor x forward, y left, z up) in ``scene``, with sea clutter for the wave height of ``env``
    (:func:`mmusv.sensors.env.sensor_env`; 0..30 m, e.g. W0 = 0.5, W3 = 3.5) and its rain (0..500 mm/h).
    Releases the GIL and uses every core.

    Raises :class:`mmusv.ConfigError` for waves or rain out of range, :class:`mmusv.InputError` for a bad radar,
    scene, pose, environment or seed.
    """
    check_sensor(
        radar, core.Radar, name="radar", made_by="radar_from_config(RadarConfig(...)), or Simulation.agent(id).radar"
    )
    seed = check_sensor_args(scene, env=env, seed=seed)
    p = _pose(pose, name="pose")
    return RadarReturns.from_native(radar.sweep(scene.native, pose=p, env=env, seed=seed), pose=p, radar=radar)


def ppi_image(
    returns: RadarReturns,
    *,
    size_px: int = 512,
    metres_per_pixel: float | None = None,
    orientation: Orientation = "north_up",
    sensor_yaw: float | None = None,
) -> npt.NDArray[np.float32]:
    """The ``(size_px, size_px)`` float32 plan-position image of ``returns``: ego at pixel
    ``(size_px // 2, size_px // 2)``, row 0 at the top (north for ``"north_up"``, ahead for ``"head_up"``),
    each return painted over its range-bin × azimuth-bin polar cell with max compositing; 0 where nothing.

    The scale is fixed: a return at range R lies ``R / metres_per_pixel`` pixels from the centre in every
    frame. ``metres_per_pixel`` defaults to the radar's range over ``size_px // 2`` (the full range fills the
    image); ``sensor_yaw`` (radians, for north-up) defaults to the sweep pose's yaw. Bad values raise
    :class:`mmusv.ConfigError` naming ``ppi.<field>``; ``returns`` that are not a :class:`RadarReturns`
    :class:`mmusv.InputError`.
    """
    if not isinstance(returns, RadarReturns):
        raise InputError(
            f"returns = {arguments.shown(returns)}: must be a RadarReturns (radar_sweep(...), or the radar of a "
            f"Simulation.capture), not {type(returns).__name__}"
        )
    size, mpp, orient, yaw = ppi_request(
        returns.radar,
        pose=returns.pose,
        size_px=size_px,
        metres_per_pixel=metres_per_pixel,
        orientation=orientation,
        sensor_yaw=sensor_yaw,
    )
    return np.asarray(
        returns.radar.ppi_image(
            range=np.ascontiguousarray(returns.range, dtype=np.float32),
            azimuth=np.ascontiguousarray(returns.azimuth, dtype=np.float32),
            intensity=np.ascontiguousarray(returns.intensity, dtype=np.float32),
            size_px=size,
            metres_per_pixel=mpp,
            orientation=orient,
            sensor_yaw=yaw,
        )
    )


def ppi_request(
    radar: core.Radar,
    *,
    pose: npt.NDArray[np.float64],
    size_px: int = 512,
    metres_per_pixel: float | None = None,
    orientation: Orientation = "north_up",
    sensor_yaw: float | None = None,
) -> tuple[int, float, str, float]:
    """``(size_px, metres_per_pixel, orientation, sensor_yaw)`` of the PPI :func:`ppi_image` draws for a sweep of
    ``radar`` at ``pose`` (``(4, 4)`` sensor → world), with its defaults filled in; the same tuple is the ``ppi``
    of a radar task of ``core.capture_frame``. ``size_px`` is a whole number in ``1..MAX_PPI_SIZE``,
    ``metres_per_pixel`` and ``sensor_yaw`` numbers (not strings or booleans), else :class:`mmusv.ConfigError`
    naming ``ppi.<field>`` (:class:`mmusv.InputError` for ``sensor_yaw``, as the core's own check)."""
    size = arguments.whole(size_px, name="invalid config ppi.size_px", lo=1, hi=MAX_PPI_SIZE, error=ConfigError)
    if metres_per_pixel is None:
        mpp = radar.range_max_m / max(size // 2, 1)
    else:
        mpp = _number(metres_per_pixel, "invalid config ppi.metres_per_pixel", "a number of metres > 0", ConfigError)
    if not isinstance(orientation, str):
        raise ConfigError(
            f'invalid config ppi.orientation = {arguments.shown(orientation)}: must be "north_up" or "head_up"'
        )
    yaw = _yaw(pose) if sensor_yaw is None else _number(sensor_yaw, "sensor_yaw", "an angle in radians", InputError)
    return size, mpp, orientation, yaw


MAX_PPI_SIZE = 8192
"""Largest PPI side, pixels (the core's ``sensors::ppi::MAX_PPI_SIZE``, which it checks itself)."""


def _number(value: Any, name: str, what: str, error: type[Exception]) -> float:
    """``value`` as a float when it is a real number (not a string, not a boolean), else ``error`` naming
    ``name``; its range is the core's to check (as it names it)."""
    if not arguments.is_number(value):
        raise error(f"{name} = {arguments.shown(value)}: must be {what}, not {type(value).__name__}")
    return float(value)


def _yaw(pose: npt.NDArray[np.float64]) -> float:
    """World yaw of the forward axis of a ``(4, 4)`` sensor → world pose, radians (counter-clockwise from east)."""
    return math.atan2(float(pose[1, 0]), float(pose[0, 0]))


def ppi_colormap(img: npt.ArrayLike, *, vmin_db: float = -20.0, vmax_db: float = 30.0) -> npt.NDArray[np.uint8]:
    """``(H, W, 3)`` uint8 radar-green rendering of a PPI: intensity in dB (``10·log10``) mapped linearly from
    ``vmin_db`` (dark green) to ``vmax_db`` (near white); pixels ``<= 0`` are black. Fixed limits by default,
    so frames are comparable. Only the lit pixels are computed (a PPI is mostly empty): per pixel, the same
    operations as over the whole image."""
    vmin_db = arguments.real(vmin_db, name="vmin_db", unit="dB", error=InputError)
    vmax_db = arguments.real(vmax_db, name="vmax_db", unit="dB", error=InputError)
    try:
        a = np.asarray(img, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"img = {arguments.shown(img)}: must be a (H, W) array of intensities ({exc})") from None
    if a.ndim != 2:
        raise InputError(f"img must be a (H, W) intensity image, got shape {a.shape}")
    if not vmax_db > vmin_db:
        raise InputError(f"need vmax_db > vmin_db, got {vmin_db} and {vmax_db}")
    lit = a > 0
    db = 10.0 * np.log10(a[lit])
    t = np.clip((db - vmin_db) / (vmax_db - vmin_db), 0.0, 1.0)
    rgb = np.stack([255.0 * t**3, 50.0 + 205.0 * t**0.6, 30.0 * t + 200.0 * t**4], axis=-1)
    out = np.zeros((*a.shape, 3), dtype=np.uint8)
    out[lit] = np.rint(rgb).astype(np.uint8)
    return out


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
