"""Sensor rig configuration: what every instrumented USV carries, validated into frozen pydantic models.

A rig (``rigs:`` in a scenario) has a LiDAR, a radar, any number of pinhole cameras and a top-view camera;
every part has defaults, so ``usv_standard: {}`` is a complete rig: the paper's suite (surround-view RGB, depth
and semantic cameras, a top-view camera, a spinning LiDAR and a ray-cast radar, Sec. II-A), with the LiDAR the
paper states (64 channels, 5 Hz, 131,072 points/s, 200 m, Sec. III-C). The paper gives no other sensor value;
mmusv's own choices are the LiDAR's vertical field of view (−25° to 15°), four 640×480 surround cameras with a 90°
field of view, the top view (120 m up, 512 × 512 pixels at 0.5 m per pixel) and the radar (X band, 3 km).
131,072 points/s over 64 channels at 5 Hz is 409.6 columns a sweep; the LiDAR fires whole columns, 410
(26,240 rays a sweep, 131,200 rays/s, 0.1 % more); the points a sweep returns are the rays that hit something.
``null`` switches a sensor off (``radar: null``); ``cameras: []`` removes the cameras.
``preset: lidar_only`` starts from the LiDAR alone (no radar, cameras or top view; any of them can still be
added explicitly): the rig for detection datasets, where cameras would cost most of the time.
``quality: draft`` (or ``high``) on a rig sets the quality of every camera and top view that does not set its own.

Mounts: ``point`` names a mount point of the vessel asset (``lidar``, ``radar``, ``camera_front``, ...; see
``mmusv assets``); ``xyz`` (metres) and ``rpy_deg`` (degrees) are then relative to that point, in the point's own
frame (axes of the vessel body frame, x forward, y left, z up, turned by the point's rpy: on ``camera_left``, which
looks left, ``xyz: [1, 0, 0]`` moves the sensor 1 m to the left). Without ``point``, they are relative to the vessel
origin (midship, at the waterline), in the vessel body frame. On an asset without any mount point, a named point
falls back to 0.5 m above the top of the hull's bounding box over the vessel origin, looking where the name says
(``camera_left`` +90° yaw, ``camera_rear`` 180°, ``camera_right`` −90°, any other name ahead); a point an asset
with mount points lacks is refused. ``xyz`` is within ±100 km
(:data:`MAX_MOUNT_OFFSET_M`) and ``rpy_deg`` within ±360 degrees. Without a ``mount``, the LiDAR sits on ``lidar``,
the radar on ``radar`` and a camera on ``camera_<its name>``, else ``camera_front`` (a ``rear``, ``left`` or
``right`` camera: that fall-back, turned its way), else that fall-back (:func:`mmusv.sensors.mounts.camera_mount`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal, get_args

from pydantic import Field, ModelWrapValidatorHandler, ValidationInfo, field_validator, model_validator

from mmusv._native import core
from mmusv.strict import StrictModel

__all__ = [
    "RIG_PRESETS",
    "CameraConfig",
    "ExposureConfig",
    "LidarConfig",
    "Mount",
    "RadarConfig",
    "RigConfig",
    "TopViewConfig",
    "default_cameras",
]

RigPreset = Literal["full", "lidar_only"]
RIG_PRESETS: dict[str, dict[str, object]] = {
    "full": {},
    "lidar_only": {"radar": None, "cameras": [], "top_view": None},
}
"""Defaults each preset puts in place of the paper's full suite (keys given explicitly in the rig win)."""

CameraOutput = Literal["rgb", "depth", "semantic", "instance"]
TopViewOutput = Literal["rgb", "semantic", "instance"]
"""A top view's images: a camera's less ``depth`` (the recording has no top-view depth topic)."""
Quality = Literal["draft", "standard", "high"]
"""Work spent on a camera's RGB: ``draft`` one sample per pixel and water reflecting the sky along each pixel's
mirror direction; ``standard`` water reflections traced once per 2 × 2 block of water pixels (4 × 4 where the
water's glossy lobe spans many such blocks), each in a direction drawn from that lobe at its point and spread over
the rest of it, and 4 stratified samples on edge pixels (a change of instance, class or material, or a depth step off
the water); ``high`` reflections traced for every pixel (drawn and spread alike) and 16 samples on edges."""
_ALL_OUTPUTS: tuple[CameraOutput, ...] = ("rgb", "depth", "semantic", "instance")
_TOP_OUTPUTS: tuple[TopViewOutput, ...] = get_args(TopViewOutput)


class _Model(StrictModel):
    """The sensor configs' models: :class:`~mmusv.strict.StrictModel` (no unknown keys, NaN, infinity or booleans
    for numbers)."""


MAX_IMAGE_PIXELS: int = core.MAX_IMAGE_PIXELS
"""Largest image of any camera: about 16.8 M pixels (a 4096 x 4096 frame takes ~0.6 GB of buffers per frame); the
core's own bound (``mmusv._core.MAX_IMAGE_PIXELS``), which ``Camera`` refuses beyond."""
MAX_LIDAR_RAYS = 1 << 22
"""Most LiDAR rays per sweep (4.2 M: ~0.3 GB of points per sweep)."""
MAX_RADAR_RAYS = 1 << 23
"""Most radar rays per sweep: azimuth_bins x rays_az x rays_el (8.4 M)."""


def _check_resolution(v: tuple[int, int]) -> tuple[int, int]:
    """An image ``[width, height]``: both in 1..16384 pixels, at most :data:`MAX_IMAGE_PIXELS` in all."""
    if not (1 <= v[0] <= 16384 and 1 <= v[1] <= 16384):
        raise ValueError("width and height must be in 1..16384 pixels")
    if v[0] * v[1] > MAX_IMAGE_PIXELS:
        raise ValueError(
            f"{v[0]} x {v[1]} = {v[0] * v[1]:,} pixels would take about {v[0] * v[1] * 36 / 1e9:.1f} GB per frame; "
            f"at most {MAX_IMAGE_PIXELS:,} pixels are allowed"
        )
    return v


def _check_outputs(v: Sequence[str], allowed: tuple[str, ...], drop: str) -> None:
    """``outputs`` of a camera or top view: at least one image (a sensor without any would be rendered for nothing
    and recorded nowhere), each once."""
    if not v:
        raise ValueError(f"must list at least one of {', '.join(allowed)}; {drop}")
    twice = sorted({o for o in v if v.count(o) > 1})
    if twice:
        # Each image is rendered and recorded once: a repeat would be a second topic of the same name.
        raise ValueError(f"lists {', '.join(twice)} more than once; list each output once (of {', '.join(allowed)})")


MIN_RANGE_M = 0.01
"""The shortest range a LiDAR, radar or camera takes, metres: the native sensors hold ranges as 32-bit floats, in
which a range of 1e-300 m is 0 (refused then as ``range_m = 0``, though the file said otherwise)."""

MAX_MOUNT_OFFSET_M = 100_000.0
"""The largest mount offset a sensor takes, metres (the longest sensor range, :attr:`LidarConfig.range_m`'s bound)."""


class Mount(_Model):
    """Where a sensor sits on its vessel (see the module docstring)."""

    point: str | None = None
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @field_validator("xyz", "rpy_deg")
    @classmethod
    def _finite(cls, v: tuple[float, float, float], info: ValidationInfo) -> tuple[float, float, float]:
        if not all(math.isfinite(x) for x in v):
            raise ValueError("must be three finite numbers")
        # An offset beyond any range the sensors reach (1e39 overflowed the core's floats: "invalid origins[0]:
        # [inf, 0.0, 0.0]", naming no field), and turns beyond a whole turn, are typing errors.
        bound, unit = (MAX_MOUNT_OFFSET_M, "m") if info.field_name == "xyz" else (360.0, "degrees")
        if any(abs(x) > bound for x in v):
            raise ValueError(f"must be three numbers within ±{bound:,.0f} {unit}")
        return v


class LidarConfig(_Model):
    """Spinning LiDAR. Columns per sweep = ``points_per_second / (rotation_hz · channels)`` (rounded, a half to
    the even number), column ``a`` at azimuth ``2π a / columns`` counter-clockwise from +x (the bow at the default
    mounts); ring ``i`` fires at ``elevations_deg[i]``, or uniformly over ``vertical_fov_deg`` from its lower end
    (ring 0) to its upper (one channel: its middle). At the defaults: 410 columns 0.88° apart, 64 rings 0.63° apart
    from −25° to 15°, 26,240 rays a sweep. No real sensor's pattern is the default; ``elevations_deg`` gives one.

    ``elevations_deg`` (one per channel, any order) replaces the uniform ``vertical_fov_deg`` pattern (given both,
    ``vertical_fov_deg`` must be the rings' span ``[min, max]``, or its default).

    A sweep is one instant: every ray of a frame's sweep meets the scene frozen at the frame's time (the vessels,
    the waves and the LiDAR's own pose), so the points carry no motion distortion (no rolling shutter: a real 5 Hz
    LiDAR on a USV at 5 m/s moves 1 m during its sweep) and need no de-skewing, and no time per point is
    recorded. ``rotation_hz`` sets the columns per sweep only: each frame (``acquisition.frequency_hz``) records
    one whole sweep whatever it is.

    One return per ray: the first surface the ray meets, a ray being a line for the surfaces it meets (its divergence
    is the rain's alone, below: a part thinner than the gap between rays, a railing, is met or missed whole; no
    second or last return). Fog and rain lose returns (two-way
    transmission). In rain (``environment.rain_mm_per_h`` > 0) the drops in the beam return too, LISA's model
    (Kilic et al. 2021; ``crates/mmusv-core/src/sensors/lidar_rain.rs``): the beam is a cone of full angle
    ``beam_divergence_mrad`` (3 mrad, LISA's; 0 meets no drop), its drops Marshall–Palmer's, and the strongest of
    them replaces the return where it outshines the surface and the receiver's threshold (a 0.9 reflector at
    ``range_m``). Such points lie within 0.15 ``range_m`` of the sensor, most within a few metres, with class 0
    (nothing) and instance -1: at 10 mm/h with the defaults about 1,800 a sweep on ``open_sea_convoy``, 7 % of the
    rays, half of them within 2.2 m (``docs/realism/README.md``, *The LiDAR's rain drops*). Fog adds no points of
    its own (no backscatter).

    Points on the USV's own hull are kept (their ``instance`` is the USV's ``instance_id``, their class
    ``usv``): the assets' ``lidar`` mount points see none of it (``tests/sensors/test_own_hull.py``), a mount
    lower on the hull may (on the patrol boat's deck 3 m below its ``lidar`` point, 4 of 5 points).

    Water returns on the flat sea (``environment.motion: paper``, or a simulation without its wave surface):
    probability ``water_probability + water_probability_per_wave_m · H`` within ``water_range_m +
    water_range_per_wave_m · H`` metres (H the wave height). On the physical sea (``motion: physical``, the default)
    the water returns follow the physical model (glints off the wave facets, whitecaps, the wakes' foam;
    ``sensors/lidar_water.rs``), and these four change nothing (``mmusv run`` warns about them,
    :func:`mmusv.scenario_checks.check_lidar_water`) but for ``water_probability`` and
    ``water_probability_per_wave_m`` both 0, which switch the water returns off on either sea: a dataset of
    targets only.
    """

    channels: int = Field(default=64, ge=1, le=1024)
    vertical_fov_deg: tuple[float, float] = (-25.0, 15.0)
    elevations_deg: list[float] | None = None
    points_per_second: float = Field(default=131_072.0, gt=0, le=1e10)
    rotation_hz: float = Field(default=5.0, ge=0.1, le=100)
    range_m: float = Field(default=200.0, ge=MIN_RANGE_M, le=100_000)
    range_min_m: float = Field(default=0.5, ge=0)
    range_noise_std_m: float = Field(default=0.02, ge=0, le=100)
    dropout: float = Field(default=0.0, ge=0, le=1)
    water_probability: float = Field(default=0.05, ge=0, le=1)
    water_probability_per_wave_m: float = Field(default=0.1, ge=0, le=100)
    water_range_m: float = Field(default=20.0, ge=0, le=100_000)
    water_range_per_wave_m: float = Field(default=10.0, ge=0, le=100_000)
    beam_divergence_mrad: float = Field(default=3.0, ge=0, le=100)
    mount: Mount = Mount(point="lidar")

    @field_validator("vertical_fov_deg")
    @classmethod
    def _fov(cls, v: tuple[float, float]) -> tuple[float, float]:
        lo, hi = v
        if not (-90 < lo <= hi < 90):
            raise ValueError("need -90 < lower <= upper < 90 degrees")
        return v

    @model_validator(mode="after")
    def _check(self) -> LidarConfig:
        if self.elevations_deg is not None:
            if len(self.elevations_deg) != self.channels:
                n = len(self.elevations_deg)
                raise ValueError(
                    f"elevations_deg has {n} entries for {self.channels} channels: give one elevation per channel "
                    f"(channels: {n} with these)"
                )
            if not all(-90 < e < 90 for e in self.elevations_deg):
                raise ValueError("every elevation must be strictly between -90 and 90 degrees")
            if len(set(self.elevations_deg)) != len(self.elevations_deg):
                twice = sorted({e for e in self.elevations_deg if self.elevations_deg.count(e) > 1})
                raise ValueError(f"elevations_deg repeats {twice}: two rings would fire the same rays")
            span = (min(self.elevations_deg), max(self.elevations_deg))
            default = type(self).model_fields["vertical_fov_deg"].default
            if tuple(self.vertical_fov_deg) not in (default, span):
                # elevations_deg replaces the uniform pattern: a vertical_fov_deg of its own would be ignored silently
                raise ValueError(
                    f"vertical_fov_deg {list(self.vertical_fov_deg)} and elevations_deg (rings from {span[0]:g} to "
                    f"{span[1]:g} degrees) are both given, and elevations_deg replaces vertical_fov_deg: give one or "
                    f"the other (or vertical_fov_deg [{span[0]:g}, {span[1]:g}], the rings' span)"
                )
        elif self.channels > 1 and self.vertical_fov_deg[0] == self.vertical_fov_deg[1]:
            raise ValueError(
                f"vertical_fov_deg {list(self.vertical_fov_deg)} spans no angle: its {self.channels} channels would "
                "all fire the same rays; give lower < upper, or channels: 1"
            )
        if self.range_min_m >= self.range_m:
            raise ValueError(f"range_min_m ({self.range_min_m}) must be below range_m ({self.range_m})")
        if not 1 <= self.azimuth_steps <= 65536:
            raise ValueError(
                f"points_per_second / (rotation_hz * channels) = {self.azimuth_steps} columns per sweep; "
                "must be 1..65536"
            )
        rays = self.azimuth_steps * self.channels
        if rays > MAX_LIDAR_RAYS:
            raise ValueError(
                f"{self.channels} channels x {self.azimuth_steps} columns = {rays:,} rays per sweep would take about "
                f"{rays * 64 / 1e9:.1f} GB per sweep; at most {MAX_LIDAR_RAYS:,} are allowed"
            )
        return self

    @property
    def azimuth_steps(self) -> int:
        """Columns per sweep (validated to 1..65536)."""
        return round(self.points_per_second / (self.rotation_hz * self.channels))

    def elevations_rad(self) -> list[float]:
        """Elevation of each ring, radians (ring ``i`` = entry ``i``)."""
        if self.elevations_deg is not None:
            return [math.radians(e) for e in self.elevations_deg]
        lo, hi = self.vertical_fov_deg
        if self.channels == 1:
            return [math.radians((lo + hi) / 2)]
        step = (hi - lo) / (self.channels - 1)
        return [math.radians(lo + i * step) for i in range(self.channels)]


class RadarConfig(_Model):
    """Rotating marine radar (ray cast) and its PPI image at a fixed metres-per-pixel scale: the one definition of
    the radar's knobs, defaults and limits (the core's ``RadarConfig`` has no defaults; the binding
    ``mmusv._core.Radar`` requires every field, see :func:`mmusv.sensors.radar.radar_from_config`). The model is
    in :mod:`mmusv.sensors.radar`.

    Attributes:
        range_m: instrumented range, metres (``<= 100 km``).
        min_range_m: blind range, metres (hides the own ship), ``0 <= min_range_m < range_m``.
        range_resolution_m: range bin size, metres (``> 0``; at most 2²⁰ bins over ``range_m``).
        azimuth_bins: beams per revolution (``1..65536``).
        beamwidth_deg: horizontal beamwidth, degrees, in ``(0, 90]``.
        elevation_fan_deg: vertical fan ``(lower, upper)``, degrees, strictly within ``(-90, 90)``: the rays span it,
            and it is the half-power beamwidth of the beam's Gaussian elevation pattern centred on it (two-way gain
            1 on its axis, ¼ at its edges), which weights targets, sea clutter and rain (``radar/pattern.rs``).
        rays_az: rays per beam across the beamwidth (``1..64``).
        rays_el: rays per beam over the elevation fan (``1..256``); ``azimuth_bins · rays_az · rays_el <= 2²³``.
        target_rays: rays cast straight at each object in range per beam spacing its angular box spans in azimuth
            (``0..1024``; at most 32 spacings' worth an object), besides the fan's, and combined with them by
            multiple importance sampling (Veach & Guibas 1995, ``radar/targets.rs``): unbiased, and where no object
            is the fan's rays weigh what they weighed alone. 0: the fan's rays alone, which hit a target smaller
            than the patch one ray samples (``beamwidth_deg / rays_az`` by the fan height a ray stands for) or miss
            it, and credit a hit with the whole patch. From a 5.3 m mast, of 12 boats with a 2 m × 0.9 m face (1.8
            at 1 km by the radar equation, six times the threshold), the defaults see all 12 at every range from
            150 m to 1 km, their brightest cell 0.74-1.16 times the radar equation, lit over the beamwidth plus their
            width, and none at 2.5 km (0.05 by the radar equation); with ``target_rays`` 0 they saw 9 at 150 m, 5
            at 200 m, 12 at 300 m, 9 at 600 m, 6 at 1 km (about 11 times too bright, lit in one 0.18° beam of the
            seven the 1.2° beamwidth spans) and 1 at 2.5 km, 71 times too bright (``tests/test_radar_user_round.py``).
            It costs a few per cent of the sweep (``port_entry``: 212 ms a frame for three radars, 198 without).
        horizon_fraction: share of the elevation rays spread over the band around the sea horizon (which follows
            the sensor's roll and pitch), the rest over the remaining fan; ``0..1``, 0 = uniform over the fan.
            Rays are weighted by the fan height they stand for, so intensities do not depend on it.
        horizon_band_deg: half-height of that band, degrees (``0..45``).
        detection_threshold: smallest reported intensity (``>= 0``; 1.0 = a 1 m² target at 1 km).
        range_noise_std_m: Gaussian noise on the reported range, metres (``0..100 km``).
        sea_clutter_sigma0: sea-clutter σ⁰ (m²/m²) at 1 m wave height (scales with height², ``0..1``) on the
            paper's flat sea (``environment.motion: paper``); 0 disables sea clutter, on the physical sea (the
            default motion) too, where σ⁰ is otherwise the NRL model's (frequency, polarisation, grazing angle and
            sea state; ``tests/nrl_clutter.py``) whatever this value is.
        clutter_critical_range_per_m: metres of critical range per metre of wave height (sea clutter falls as
            r⁻⁷ beyond it, r⁻³ before); the flat sea's only (the NRL model has its own low-grazing fall).
        sea_clutter_max_range_m: no sea clutter beyond this range, metres.
        rain_clutter_eta: rain volume reflectivity (m²/m³) at 1 mm/h for a 9.41 GHz radar (scales with rate^1.6
            and, by Rayleigh scattering's λ⁻⁴, with ``(frequency_ghz / 9.41)⁴``; ``0..1``); 0 disables. Marshall–Palmer
            rain (η = π⁵|K|²Z/λ⁴, Z = 200 R^1.6) is 5.5e-8 at 9.41 GHz; the default is 10.4 dB below it.
        frequency_ghz: carrier frequency, GHz (``0.5..35``, the NRL sea-clutter model's range; 9.41 = X band,
            3.05 = S band): sea clutter's σ⁰ (NRL model, over the physical sea), rain clutter (λ⁻⁴) and rain
            attenuation (ITU-R P.838-3) follow it.
        polarisation: ``"HH"`` (marine radars) or ``"VV"``: sea clutter's σ⁰ (NRL model) and rain attenuation
            (ITU-R P.838-3) follow it.
        ppi_size_px, ppi_metres_per_pixel, ppi_orientation: the PPI image; ``ppi_metres_per_pixel`` defaults to
            ``range_m / (ppi_size_px // 2)`` (:func:`mmusv.sensors.radar.ppi_request`: the range from the ego's
            pixel to the edge of an odd size too).

    Why ``detection_threshold`` 0.3 and ``sea_clutter_sigma0`` 4e-7 (and not the 0.01 / 4e-6 the core's unit
    tests use): these are the values every scenario and recording has always been made with, and they keep a
    sweep's returns about targets. Measured on a sea plane with a 10 m box at 1.2 km (``tests/sensors``' scene):
    with 0.3 / 4e-7, sea clutter reaches ≈40 m at W0 and ≈140 m at W3 (99th percentile of the clutter ranges;
    10,819 → 55,466 clutter cells, still growing with every sea state); with 0.01 / 4e-6 it reaches ≈180 m /
    ≈930 m with 92,871 → 404,373 cells (8.9 MB of return arrays at 22 bytes a return, per USV per frame at W3).
    The box gives the same 7 cells with both. (Measured before 2026-12-01, when the sea behind the box stopped
    drawing clutter, `radar/shadow.rs`, and the fan beam got its elevation pattern, `radar/pattern.rs`, which
    weakens the clutter close in: the counts are lower now, not measured again here.) Over the physical sea (the
    default motion), σ⁰ is the NRL model's and the threshold alone bounds the clutter: from the 12 m patrol boat's
    radar (5.3 m up) on the open sea, 100,919 clutter cells reaching 227 m (99th percentile) at W0, 229,375
    reaching 497 m at W3 (measured 2026-12-06).
    """

    range_m: float = Field(default=3000.0, ge=MIN_RANGE_M, le=100_000)
    min_range_m: float = Field(default=10.0, ge=0)
    range_resolution_m: float = Field(default=3.0, ge=1e-6, le=100_000)
    azimuth_bins: int = Field(default=2048, ge=1, le=65536)
    beamwidth_deg: float = Field(default=1.2, gt=0, le=90)
    elevation_fan_deg: tuple[float, float] = (-10.0, 10.0)
    rays_az: int = Field(default=3, ge=1, le=64)
    rays_el: int = Field(default=16, ge=1, le=256)
    target_rays: int = Field(default=16, ge=0, le=1024)
    horizon_fraction: float = Field(default=0.75, ge=0, le=1)
    horizon_band_deg: float = Field(default=1.0, ge=0, le=45)
    detection_threshold: float = Field(default=0.3, ge=0)
    range_noise_std_m: float = Field(default=0.0, ge=0, le=100_000)
    sea_clutter_sigma0: float = Field(default=4.0e-7, ge=0, le=1)
    clutter_critical_range_per_m: float = Field(default=300.0, ge=0, le=100_000)
    sea_clutter_max_range_m: float = Field(default=2500.0, ge=0, le=100_000)
    rain_clutter_eta: float = Field(default=5.0e-9, ge=0, le=1)
    frequency_ghz: float = Field(default=9.41, ge=0.5, le=35)
    polarisation: Literal["HH", "VV"] = "HH"
    ppi_size_px: int = Field(default=512, ge=16, le=8192)
    ppi_metres_per_pixel: float | None = Field(default=None, ge=0.01, le=1000)
    ppi_orientation: Literal["north_up", "head_up"] = "north_up"
    mount: Mount = Mount(point="radar")

    @model_validator(mode="after")
    def _check(self) -> RadarConfig:
        lo, hi = self.elevation_fan_deg
        if not (-90 < lo <= hi < 90):
            raise ValueError("elevation_fan_deg needs -90 < lower <= upper < 90 degrees")
        if self.min_range_m >= self.range_m:
            raise ValueError(f"min_range_m ({self.min_range_m}) must be below range_m ({self.range_m})")
        if self.range_resolution_m > self.range_m - self.min_range_m:
            # A bin longer than the span it measures reports its echoes at a range outside it: a radar of no return.
            raise ValueError(
                f"range_resolution_m ({self.range_resolution_m:g}) must be at most range_m - min_range_m "
                f"({self.range_m - self.min_range_m:g} m): a coarser range bin reports no echo within the range"
            )
        bins = math.ceil(self.range_m / self.range_resolution_m)
        if bins > 2**20:
            raise ValueError(
                f"range_m / range_resolution_m = {bins:,} range bins; at most {2**20:,} (raise range_resolution_m)"
            )
        rays = self.azimuth_bins * self.rays_az * self.rays_el
        if rays > MAX_RADAR_RAYS:
            raise ValueError(
                f"azimuth_bins x rays_az x rays_el = {rays:,} rays per sweep would take about "
                f"{rays * 48 / 1e9:.1f} GB; "
                f"at most {MAX_RADAR_RAYS:,} are allowed"
            )
        return self


class SensorNoiseConfig(_Model):
    """Shot and read noise of an image sensor: ``full_well_e`` electrons at full scale (before the tone curve)
    and ``read_noise_e`` electrons RMS."""

    full_well_e: float = Field(default=10000.0, ge=1, le=1e7)
    read_noise_e: float = Field(default=3.0, ge=0, le=1e5)


_EXPOSURE = core.exposure_limits()
"""The exposure settings' ranges, as the core defines and checks them (``tonemap::Exposure``)."""


class ExposureConfig(_Model):
    """How a camera exposes its RGB (``crates/mmusv-core/src/sensors/shade/tonemap.rs``). Automatic by default:
    an incident reading of the scene's light with a highlight limit, ``compensation_ev`` stops brighter (+) or
    darker (−), adapting down to the light at which the camera reaches ``max_iso`` at f/1.4 and 1/30 s (ISO 6 400:
    3.46 lux, the end of civil twilight; each doubling of ``max_iso`` halves it). Or fixed at ``ev100`` (manual
    exposure at ISO 100, e.g. 15 for full sun, 12 for an overcast day): every frame shows the light as it is,
    without the automatic exposure's adaptation."""

    ev100: float | None = Field(default=None, ge=_EXPOSURE["ev100"][0], le=_EXPOSURE["ev100"][1])
    compensation_ev: float = Field(default=0.0, ge=_EXPOSURE["compensation_ev"][0], le=_EXPOSURE["compensation_ev"][1])
    max_iso: float = Field(default=_EXPOSURE["default_max_iso"], ge=_EXPOSURE["max_iso"][0], le=_EXPOSURE["max_iso"][1])

    @model_validator(mode="after")
    def _one_mode(self) -> ExposureConfig:
        if self.ev100 is not None and self.compensation_ev != 0.0:
            raise ValueError(
                "compensation_ev applies to the automatic exposure only; give ev100 (fixed) or compensation_ev"
            )
        return self

    def native(self) -> tuple[float | None, float, float]:
        """``(ev100, compensation_ev, max_iso)`` for :class:`mmusv._core.Camera`."""
        return (self.ev100, self.compensation_ev, self.max_iso)


class CameraConfig(_Model):
    """A pinhole camera: ``resolution`` ``[width, height]`` pixels, horizontal field of view ``hfov_deg`` (<
    180), the images to produce, and its mount (optical axis = the mount's x axis; without one, or with the
    default one, the asset's mount point ``camera_<name>``, else its ``camera_front`` but for a ``rear``, ``left`` or
    ``right`` camera: :func:`mmusv.sensors.mounts.camera_mount`).
    ``quality`` (:data:`Quality`) sets the RGB's anti-aliasing and reflections; ``distortion`` is
    Brown–Conrady ``[k1, k2, p1, p2, k3]`` in OpenCV's order (none by default); ``noise`` adds seeded shot and
    read noise (none by default); ``exposure`` (:class:`ExposureConfig`) is automatic unless fixed. Depth,
    semantic and instance images always come from the pixel centres. ``range_m`` (metres) is how far the
    camera traces surfaces: a vessel or island beyond it is not seen (a vessel wholly beyond it gets no 2D
    box, the part of one beyond it neither ``visible`` nor hidden by the waves), while the sea beyond it is
    still drawn, labelled water and given its still water's depth (so depth is +inf, and the instance -1,
    exactly where the pixel sees the sky)."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    resolution: tuple[int, int] = (640, 480)
    hfov_deg: float = Field(default=90.0, ge=0.1, lt=180)
    outputs: list[CameraOutput] = Field(
        default_factory=lambda: list(_ALL_OUTPUTS), json_schema_extra={"uniqueItems": True}
    )
    range_m: float = Field(default=5000.0, ge=MIN_RANGE_M, le=1e6)
    mount: Mount = Mount()
    quality: Quality = "standard"
    distortion: tuple[float, float, float, float, float] | None = None
    noise: SensorNoiseConfig | None = None
    exposure: ExposureConfig = ExposureConfig()

    _res = field_validator("resolution")(_check_resolution)

    @field_validator("outputs")
    @classmethod
    def _outputs(cls, v: list[CameraOutput]) -> list[CameraOutput]:
        _check_outputs(v, _ALL_OUTPUTS, "to drop the camera, leave it out of cameras (cameras: [] for none)")
        return v

    @field_validator("distortion")
    @classmethod
    def _finite_distortion(
        cls, v: tuple[float, float, float, float, float] | None
    ) -> tuple[float, float, float, float, float] | None:
        if v is not None and not all(math.isfinite(x) for x in v):
            raise ValueError("every coefficient must be finite")
        return v


class TopViewConfig(_Model):
    """A level orthographic camera ``altitude_m`` above the water over the USV, looking straight down:
    ``resolution`` pixels at ``metres_per_pixel``; ``heading_up`` puts the USV's bow at the top of the image,
    ``north_up`` puts north there; ``outputs`` any of ``rgb``, ``semantic``, ``instance`` (no ``depth``);
    ``exposure`` as a camera's (:class:`ExposureConfig`). Pixel ``(u, v)``'s centre lies ``(u + 0.5 − W/2) · m`` to
    the right of the USV's origin and ``(H/2 − v − 0.5) · m`` ahead of it (``m`` = ``metres_per_pixel``, ``W × H`` =
    ``resolution``; right = starboard or east). Its rays start ``altitude_m`` up: a ship alongside taller than the top
    view is cut there, and the camera sees its decks below, still that ship's class and instance; the USV's own hull
    must stay below it (else refused), and so must the land in its view (``mmusv run`` refuses a top view lower than
    the land it sees, which it drew as water: :func:`mmusv.scenario_checks.check_top_view_land`)."""

    altitude_m: float = Field(default=120.0, gt=0, le=20_000)
    resolution: tuple[int, int] = (512, 512)
    metres_per_pixel: float = Field(default=0.5, ge=0.001, le=1000)
    orientation: Literal["heading_up", "north_up"] = "heading_up"
    outputs: list[TopViewOutput] = Field(
        default_factory=lambda: list(_TOP_OUTPUTS), json_schema_extra={"uniqueItems": True}
    )
    quality: Quality = "standard"
    exposure: ExposureConfig = ExposureConfig()

    _res = field_validator("resolution")(_check_resolution)

    @field_validator("outputs")
    @classmethod
    def _outputs(cls, v: list[TopViewOutput]) -> list[TopViewOutput]:
        _check_outputs(v, _TOP_OUTPUTS, "to drop the top view, set top_view: null")
        return v


_QUALITIES: tuple[str, ...] = get_args(Quality)


def _with_quality(rig: dict[str, object], quality: str) -> dict[str, object]:
    """``rig`` (a rig's fields, before validation) with ``quality`` given to every camera and to the top view that
    do not set their own; the default cameras and top view when the rig leaves them out. Entries of another kind
    are left as they are, for the rig's validation to name."""

    def given(item: object) -> object:
        if isinstance(item, dict) and "quality" not in item:
            return {**item, "quality": quality}
        if isinstance(item, (CameraConfig, TopViewConfig)) and "quality" not in item.model_fields_set:
            return item.model_copy(update={"quality": quality})
        return item

    out = dict(rig)
    cameras = rig.get("cameras", default_cameras())
    out["cameras"] = [given(c) for c in cameras] if isinstance(cameras, list) else cameras
    out["top_view"] = given(rig.get("top_view", {}))
    return out


def _sets_quality(item: object) -> bool:
    """Whether a camera's or top view's entry in a rig's input sets its own ``quality``."""
    if isinstance(item, dict):
        return "quality" in item
    return isinstance(item, (CameraConfig, TopViewConfig)) and "quality" in item.model_fields_set


def default_cameras(resolution: tuple[int, int] = (640, 480)) -> list[CameraConfig]:
    """The surround rig: front, left, rear, right, 90° each, on the asset's ``camera_*`` mount points."""
    return [
        CameraConfig(name=n, resolution=resolution, mount=Mount(point=f"camera_{n}"))
        for n in ("front", "left", "rear", "right")
    ]


class RigConfig(_Model):
    """The sensors of one instrumented USV; every part defaults to the paper's suite, or to ``preset``'s
    (:data:`RIG_PRESETS`): ``full`` (the default) or ``lidar_only``. ``quality`` (:data:`Quality`), when given,
    is the quality of every camera and of the top view that does not set its own (``quality: draft`` on the rig
    renders the whole suite at ``draft`` without listing its cameras)."""

    preset: RigPreset = "full"
    quality: Quality | None = None
    lidar: LidarConfig | None = Field(default_factory=LidarConfig)
    radar: RadarConfig | None = Field(default_factory=RadarConfig)
    cameras: list[CameraConfig] = Field(default_factory=default_cameras)
    top_view: TopViewConfig | None = Field(default_factory=TopViewConfig)

    @model_validator(mode="wrap")
    @classmethod
    def _apply_preset(cls, data: object, handler: ModelWrapValidatorHandler[RigConfig]) -> RigConfig:
        """Puts the preset's defaults and the rig's quality in place (the quality passed down to every camera and
        the top view that do not set their own), validates, and leaves in ``model_fields_set`` only what ``data``
        gave: not the preset's keys, nor a quality passed down (the editor writes a rig back as it was given)."""
        if not isinstance(data, dict):
            return handler(data)
        given = data
        preset = data.get("preset", "full")
        if isinstance(preset, str) and preset in RIG_PRESETS:
            data = {**RIG_PRESETS[preset], **data}
        quality = data.get("quality")
        if isinstance(quality, str) and quality in _QUALITIES:
            data = _with_quality(data, quality)
        rig = handler(data)
        rig.__pydantic_fields_set__ = {k for k in given if k in type(rig).model_fields}
        if rig.quality is not None:
            raw = given.get("cameras")
            items = raw if isinstance(raw, list) else []  # the default cameras set no quality of their own
            for i, cam in enumerate(rig.cameras):
                if not _sets_quality(items[i] if i < len(items) else None):
                    cam.__pydantic_fields_set__.discard("quality")
            if rig.top_view is not None and not _sets_quality(given.get("top_view")):
                rig.top_view.__pydantic_fields_set__.discard("quality")
        return rig

    def mounts(self) -> list[tuple[str, Mount]]:
        """``(field path within the rig, mount)`` of every sensor the rig has: ``lidar.mount``, ``radar.mount``,
        ``cameras[i].mount`` (the top view sits above the USV and has no mount)."""
        out = [
            (f"{name}.mount", s.mount) for name, s in (("lidar", self.lidar), ("radar", self.radar)) if s is not None
        ]
        return out + [(f"cameras[{i}].mount", c.mount) for i, c in enumerate(self.cameras)]

    @model_validator(mode="after")
    def _unique(self) -> RigConfig:
        names = [c.name for c in self.cameras]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"camera names must be unique; repeated: {', '.join(dup)}")
        # the exports name files and folders after them (train/<scenario>.<usv>.<camera>): front and FRONT would be
        # one folder on a file system that ignores case (macOS, Windows), as vessel ids would
        folded: dict[str, str] = {}
        for n in names:
            other = folded.setdefault(n.casefold(), n)
            if other != n:
                raise ValueError(
                    f"camera names must differ in more than case: {other!r} and {n!r} (the exports name files and "
                    "folders after them, one on a file system that ignores case)"
                )
        return self
