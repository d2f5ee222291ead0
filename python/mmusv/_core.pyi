"""Type stubs for the compiled extension ``mmusv._core`` (pyo3 bindings over the Rust crate ``mmusv-core``).

Arrays going in must already have the exact dtype and be C-contiguous (the :mod:`mmusv` package coerces before
calling); a wrong dtype raises ``TypeError``. Arrays coming out are freshly allocated, owned, C-contiguous and
writeable. World frame: right-handed, x east, y north, z up, metres. Sensor body frames: x forward, y left, z up.
"""

import os
from collections.abc import Mapping, Sequence
from typing import Any, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "MAX_DEMO_SIZE",
    "MAX_IMAGE_PIXELS",
    "MAX_SURFACE_TILES",
    "Camera",
    "ConfigError",
    "Fleet",
    "GeometryError",
    "InputError",
    "InternalError",
    "IoError",
    "Lidar",
    "MmusvError",
    "NotFoundError",
    "Radar",
    "Recorder",
    "Scene",
    "SensorEnv",
    "WaveField",
    "__version__",
    "_lidar_directions",
    "_pinhole_directions",
    "capture_frame",
    "default_amplitudes",
    "demo_scene",
    "dnv_gamma",
    "exposure_limits",
    "fully_developed",
    "hull_rao",
    "lidar_trace_order",
    "marshall_palmer",
    "pinhole_intrinsics",
    "reference_usv_dims",
    "response_variance",
    "sea_limits",
    "sea_presets",
    "sea_seed",
    "simd_level",
    "surface_tiles",
    "uniform_elevations",
    "wave_height",
    "wave_presets",
]

__version__: str
"""Version of the compiled core (the Cargo package version)."""

# --- errors ---

class MmusvError(Exception):
    """Base class of every mmusv error."""

class InputError(MmusvError):
    """An argument has the wrong shape, dtype or value."""

class GeometryError(MmusvError):
    """Mesh data that cannot be used (empty, NaN, bad indices)."""

class ConfigError(MmusvError):
    """A configuration value outside what is allowed."""

class NotFoundError(MmusvError):
    """An id, asset or name that does not exist."""

class IoError(MmusvError):
    """A file could not be read or written."""

class InternalError(MmusvError):
    """A bug in mmusv (an internal panic was caught)."""

# --- scene ---

@final
class Scene:
    """A ray-casting scene: meshes (each with a BVH built once) placed as instances under a top-level BVH."""

    def __init__(self) -> None:
        """An empty scene."""

    def add_mesh(
        self,
        vertices: npt.NDArray[np.float32],
        faces: npt.NDArray[np.int64],
        classes: npt.NDArray[np.uint16],
        name: str,
        materials: npt.NDArray[np.uint16] | None = None,
    ) -> int:
        """Adds a mesh: ``vertices`` (V, 3) float32 metres (mesh frame), ``faces`` (F, 3) int64 in ``0..V``,
        ``classes`` (1,) or (F,) uint16, ``materials`` None, (1,) or (F,) uint16 ids into the material table;
        returns the mesh id."""
    def set_materials(self, table: npt.NDArray[np.float32]) -> None:
        """Sets the material table (M, 11) float32: r, g, b, roughness, metallic, er, eg, eb, nav_light, arc centre
        and half-width (degrees, body frame: 0 right ahead, +90 to port; 180 all round)."""
    @property
    def num_materials(self) -> int:
        """Rows of the material table."""
    def set_lights(self, ids: npt.NDArray[np.uint32], on: bool) -> None:
        """Turns the navigation lights of instances ``ids`` on or off."""
    def set_seabed(
        self, z: npt.NDArray[np.float32] | None, *, x0: float = 0.0, y0: float = 0.0, spacing: float = 1.0
    ) -> None:
        """Seabed heights (ny, nx) float32 world z at (x0 + j·spacing, y0 + i·spacing), for shallow-water optics."""

    def add_instance(self, mesh_id: int, pose: npt.NDArray[np.float64], class_override: int | None = None) -> int:
        """Places mesh ``mesh_id`` at ``pose`` ((4, 4) float64 rigid body → world); ``class_override`` uint16 or None;
        returns the instance id."""

    def set_sea(self, surface: int, moving: npt.NDArray[np.uint32]) -> None:
        """Declares instance ``surface`` the sea surface (a horizontal plane) and ``moving`` (K,) uint32 the
        instances that will move: enables the exact sea and sky shortcuts."""

    def set_wave_surface(
        self,
        hs_m: float | None,
        *,
        tp_s: float = 8.0,
        gamma: float = 3.3,
        direction_rad: float = 0.0,
        spread_s: float = 10.0,
        scenario_seed: int = 0,
        time_s: float = 0.0,
        foci: npt.NDArray[np.float32] | None = None,
        level: float = 0.0,
        tile_m: float = 32.0,
        near_m: float = 40.0,
        radius_m: float = 320.0,
        taper_m: float = 60.0,
        detail: bool = False,
        slopes: bool = True,
        fine_m: float = 0.0,
    ) -> None:
        """Sets the displaced sea surface of the frame: the JONSWAP wave field of (hs_m, tp_s, gamma,
        direction_rad, spread_s) drawn from the scenario's sea seed, sampled at ``time_s`` around ``foci`` (F, 2)
        float32; ``hs_m=None`` clears it. ``detail``: the finest tiles also carry the short waves' slopes on a
        half-cell grid, for the cameras' shading; ``slopes``: the tiles carry the slopes the cameras shade with
        at all (off: heights alone, for frames nothing renders); ``fine_m`` (metres, >= 0): with ``detail``, the
        coarser tiles within this distance of a focus also carry the finest grid's slopes, so a top view shades
        every level alike. The geometry is the same either way."""

    def prefetch_wave_surface(
        self,
        hs_m: float | None,
        *,
        tp_s: float = 8.0,
        gamma: float = 3.3,
        direction_rad: float = 0.0,
        spread_s: float = 10.0,
        scenario_seed: int = 0,
        time_s: float = 0.0,
        foci: npt.NDArray[np.float32] | None = None,
        level: float = 0.0,
        tile_m: float = 32.0,
        near_m: float = 40.0,
        radius_m: float = 320.0,
        taper_m: float = 60.0,
        detail: bool = False,
        slopes: bool = True,
        fine_m: float = 0.0,
    ) -> None:
        """Starts sampling, on a thread of its own, the surface a later ``set_wave_surface`` with the same
        arguments will set; that call takes it instead of sampling it again (the same surface bit for bit), any
        other leaves it unused. Arguments checked as ``set_wave_surface`` checks them; ``hs_m=None`` drops it."""

    def wave_heights(self, xy: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        """Heights (N,) float32 of the displaced sea surface at ``xy`` (N, 2) float32 world x, y."""

    @property
    def wave_top(self) -> float | None:
        """The crest bound of the displaced sea surface, or None."""

    def clear_sea(self) -> None:
        """Forgets the sea surface: every ray is traced fully again."""

    @property
    def sea_instance(self) -> int | None:
        """The sea surface instance id, or None."""

    def set_poses(self, ids: npt.NDArray[np.uint32], poses: npt.NDArray[np.float64]) -> None:
        """Moves instances ``ids`` (K,) uint32 to ``poses`` (K, 4, 4) float64 rigid body → world; rebuilds only the
        top-level BVH."""

    def cast_rays(
        self,
        origins: npt.NDArray[np.float32],
        directions: npt.NDArray[np.float32],
        max_range: float,
    ) -> tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.int32],
        npt.NDArray[np.int32],
        npt.NDArray[np.float32],
        npt.NDArray[np.uint16],
        npt.NDArray[np.bool_],
    ]:
        """Casts N rays (``origins``, ``directions`` (N, 3) float32 world frame, ``max_range`` metres > 0); returns
        ``(distance (N,) f32 m / inf, instance_id (N,) i32 / -1, triangle_id (N,) i32 / -1, normal (N, 3) f32 unit
        world, semantic_class (N,) u16 / 0, backface (N,) bool)``."""

    def world_mesh(
        self,
    ) -> tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint16],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
    ]:
        """World triangles at the current poses: ``(vertices (V, 3) f32 world m, faces (F, 3) u32, classes (F,) u16,
        instance_ids (F,) u32, triangle_ids (F,) u32)``."""

    def export(self, path: str | os.PathLike[str]) -> None:
        """Writes the world triangles at the current poses to ``path`` (``.ply`` or ``.obj``, world frame, metres),
        atomically."""

    def instance_aabb(self, instance_id: int) -> npt.NDArray[np.float32]:
        """(2, 3) float32 world-frame AABB in metres of an instance at its current pose: min row, max row."""

    def instance_pose(self, instance_id: int) -> npt.NDArray[np.float64]:
        """(4, 4) float64 current body → world pose of an instance."""

    def instance_meshes(self) -> npt.NDArray[np.uint32]:
        """(K,) uint32 mesh id placed by each instance, indexed by instance id."""

    @property
    def num_meshes(self) -> int:
        """Number of meshes."""

    @property
    def num_instances(self) -> int:
        """Number of instances."""

    @property
    def num_world_triangles(self) -> int:
        """Number of triangles placed in the world (sum over instances of their mesh's triangles)."""

# --- sensors ---

def pinhole_intrinsics(*, width: int, height: int, hfov: float) -> npt.NDArray[np.float64]:
    """(4,) float64 ``[fx, fy, cx, cy]`` in pixels of a ``width × height`` pinhole camera with horizontal FOV ``hfov``
    radians."""

def _pinhole_directions(*, width: int, height: int, hfov: float) -> npt.NDArray[np.float32]:
    """Test helper, not API. (width·height, 3) float32 unit ray directions through pixel centres, camera body
    frame, row-major from top-left; ``width`` and ``height`` in 1..=16384."""

def _lidar_directions(
    *, elevations: Sequence[float] | npt.NDArray[np.floating[Any]], azimuth_steps: int
) -> npt.NDArray[np.float32]:
    """Test helper, not API. (azimuth_steps·len(elevations), 3) float32 unit directions of one sweep (elevations
    in radians), LiDAR frame, azimuth-major."""

def uniform_elevations(*, channels: int, lower: float, upper: float) -> npt.NDArray[np.float64]:
    """(channels,) float64 elevation angles in radians, lowest first, spread uniformly over ``[lower, upper]``;
    ``channels`` in 1..=1024."""

def lidar_trace_order(*, channels: int, azimuth_steps: int, block: int = 8) -> npt.NDArray[np.uint32]:
    """(channels·azimuth_steps,) uint32 packet-friendly trace order: indices into ``_lidar_directions``' azimuth-major
    order."""

@final
class SensorEnv:
    """The physical environment every sensor sees: sun direction (world unit vector towards it), Preetham
    turbidity (1.7..10), cloud cover and ground albedo in [0, 1], fog extinction 1/m, rain mm/h, significant wave
    height m, wind m/s, the water body's linear RGB albedo, a fixed exposure (EV100 in [-6, 20], as a camera's) or
    None for metered, whether cameras cast shadow rays, and whether the water keeps the light reflected more than
    once between its wave facets (off: single-scattering microfacet reflection alone, as a renderer's rough BSDF).
    A value out of range raises ``ConfigError`` naming ``env.<field>``."""

    def __new__(
        cls,
        *,
        sun_direction: Sequence[float],
        turbidity: float,
        cloud_cover: float,
        ground_albedo: float,
        fog_extinction_per_m: float,
        rain_mm_per_h: float,
        wave_height_m: float,
        wind_speed_m_s: float,
        water_albedo: Sequence[float],
        exposure_ev100: float | None = None,
        shadows: bool = True,
        water_multiple_scattering: bool = True,
    ) -> SensorEnv: ...
    @property
    def exposure(self) -> tuple[float, float]:
        """(horizontal illuminance of sun and sky in lux, exposure scale from cd/m² to the tone curve's input)."""
    def sky_radiance(self, dirs: npt.NDArray[np.float32], *, sun_disc: bool = False) -> npt.NDArray[np.float32]:
        """Sky radiance (N, 3) float32 cd/m² along unit world directions ``dirs`` (N, 3) (ground below the
        horizon), with the sun's disc when ``sun_disc``; a direction whose length is not 1 (within 1e-3) raises
        ``InputError`` naming it."""
    @property
    def sun_irradiance(self) -> list[float]:
        """Direct-normal irradiance of the sun, lux (linear RGB, a list of 3); zero at night."""
    @property
    def fog_extinction_per_m(self) -> float:
        """Atmospheric extinction, 1/m."""
    @property
    def rain_mm_per_h(self) -> float:
        """Rain rate, mm/h."""
    @property
    def wave_height_m(self) -> float:
        """Significant wave height, metres."""

@final
class Lidar:
    """A spinning multi-channel LiDAR with its ray pattern computed once."""

    def __new__(
        cls,
        *,
        elevations: Sequence[float],
        azimuth_steps: int,
        range_min: float,
        range_max: float,
        range_noise_std: float,
        dropout: float,
        water_probability: float,
        water_probability_per_wave_m: float,
        water_range_m: float,
        water_range_per_wave_m: float,
        beam_divergence: float,
    ) -> Lidar: ...
    @property
    def num_rays(self) -> int:
        """Rays per sweep (channels × azimuth steps)."""
    def pattern(self) -> npt.NDArray[np.float32]:
        """(channels·azimuth_steps, 3) float32 unit directions, LiDAR frame, azimuth-major."""
    def scan(
        self,
        scene: Scene,
        *,
        pose: npt.NDArray[np.float64],
        env: SensorEnv,
        seed: int,
        wakes: npt.NDArray[np.float32] | None = None,
    ) -> dict[str, npt.NDArray[Any]]:
        """One sweep: xyz (N,3) f32 LiDAR frame, range, intensity, ring, azimuth, class (0: a rain drop), instance
        (-1: a rain drop), ray_index; and beam_instance (M,) i32, per ray of the full pattern the instance its cast
        met first (-1: none). ``wakes`` (K, 6) to (K, 9) float32
        ``x, y, heading, speed, length, beam[, reach_m[, age_s[, displacement_m3]]]`` rows (see ``Camera.render``):
        vessels under way, whose wake foam returns over a wave surface."""

@final
class Camera:
    """A pinhole (``hfov``) or orthographic (``metres_per_pixel``) camera with its rays computed once; ``rgb``:
    whether it shades colour (depth, semantic and instance images always come). ``exposure``: ``(ev100,
    compensation_ev, max_iso)``, a fixed EV at ISO 100 (``None``: automatic), the stops added to the automatic
    exposure, and the highest ISO it reaches (default ``(None, 0.0, 6400.0)``)."""

    def __new__(
        cls,
        *,
        width: int,
        height: int,
        rgb: bool,
        hfov: float | None = None,
        metres_per_pixel: float | None = None,
        range_max: float = ...,
        quality: str = "standard",
        distortion: Sequence[float] | None = None,
        noise: tuple[float, float] | None = None,
        exposure: tuple[float | None, float, float] | None = None,
    ) -> Camera: ...
    @property
    def rgb(self) -> bool:
        """Whether render shades an RGB image."""
    @property
    def distortion(self) -> list[float] | None:
        """Brown–Conrady ``[k1, k2, p1, p2, k3]`` (OpenCV order; a list of 5) or None."""
    @property
    def intrinsics(self) -> list[float] | None:
        """``[fx, fy, cx, cy]`` pixels (pinhole; a list of 4) or None (orthographic)."""
    @property
    def resolution(self) -> tuple[int, int]:
        """(width, height) pixels."""
    def distort(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """Distorted normalised image coordinates (N, 2) float64 of undistorted ones (N, 2) float64 (Brown–Conrady,
        the render's own model); the points themselves without distortion."""
    def world_rays(self, pose: npt.NDArray[np.float64]) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """World ray origins and unit directions (H·W, 3) float32, row-major."""
    def pixel_rays(
        self, pose: npt.NDArray[np.float64], pixels: npt.NDArray[np.int64]
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """World ray origins and unit directions (N, 3) float32 of the row-major pixel indices ``pixels`` (N,)
        int64, in that order: the rows of ``world_rays`` for those pixels."""
    def render(
        self,
        scene: Scene,
        *,
        pose: npt.NDArray[np.float64],
        env: SensorEnv,
        seed: int,
        wakes: npt.NDArray[np.float32] | None = None,
        radiance: bool = False,
    ) -> dict[str, npt.NDArray[Any]]:
        """depth (H,W) f32, semantic (H,W) u16, instance (H,W) i32 and, for an rgb camera, rgb (H,W,3) u8; with
        ``radiance``, radiance (H,W,3) f32 cd/m². ``wakes`` (K, 6) to (K, 9) f32: x, y, heading, speed, length, beam[,
        reach_m[, age_s[, displacement_m3]]] (how far behind the stern the path ran straight, inf when not given; with
        age_s, pieces of wakes that follow their vessels' bends: the foam age_s old at the piece's start, ending at
        reach_m where the next piece goes on; a vessel's pieces one after another, newest first, the Kelvin arms bent
        along them; displacement_m3, m³, sets the vessel's Kelvin waves, none without it)."""

# --- radar ---

@final
class Radar:
    """A rotating marine radar, configured once (metres, radians). Every field is required: the defaults live in
    ``mmusv.sensors.config.RadarConfig``. A bad value raises ``ConfigError`` naming ``radar.<field>``."""

    def __new__(
        cls,
        *,
        range_min_m: float,
        range_max_m: float,
        range_resolution_m: float,
        azimuth_bins: int,
        beamwidth_az_rad: float,
        elevation_fan_rad: tuple[float, float],
        rays_az: int,
        rays_el: int,
        target_rays: int,
        horizon_fraction: float,
        horizon_band_rad: float,
        detection_threshold: float,
        range_noise_std_m: float,
        sea_sigma0_at_1m: float,
        critical_range_per_m: float,
        sea_max_range_m: float,
        rain_eta_at_1mm_h: float,
        frequency_ghz: float,
        polarisation: str,
    ) -> Radar: ...
    @property
    def frequency_ghz(self) -> float:
        """Carrier frequency, GHz."""
    @property
    def polarisation(self) -> str:
        """Polarisation, ``"HH"`` or ``"VV"``."""
    @property
    def range_max_m(self) -> float:
        """Instrumented range, metres."""
    @property
    def range_resolution_m(self) -> float:
        """Range bin size, metres."""
    @property
    def azimuth_bins(self) -> int:
        """Beams per revolution."""
    @property
    def detection_threshold(self) -> float:
        """Smallest reported intensity."""
    @property
    def sea_sigma0_at_1m(self) -> float:
        """Sea-clutter σ⁰ at 1 m wave height."""
    @property
    def num_rays(self) -> int:
        """Rays per sweep."""
    def sweep(
        self, scene: Scene, *, pose: npt.NDArray[np.float64], env: SensorEnv, seed: int
    ) -> dict[str, npt.NDArray[Any]]:
        """One revolution from ``pose`` ((4, 4) float64 sensor → world); GIL released. Returns equal-length
        arrays sorted by (azimuth bin, range bin): ``range`` (N,) f32 m, ``azimuth`` (N,) f32 rad sensor frame in
        [0, 2π), ``elevation`` (N,) f32 rad, ``intensity`` (N,) f32 (1.0 = a 1 m² target at 1 km), ``instance``
        (N,) i32 (-1 = clutter), ``class`` (N,) u16."""
    def ppi_image(
        self,
        *,
        range: npt.NDArray[np.float32],
        azimuth: npt.NDArray[np.float32],
        intensity: npt.NDArray[np.float32],
        size_px: int,
        metres_per_pixel: float,
        orientation: str,
        sensor_yaw: float,
    ) -> npt.NDArray[np.float32]:
        """(size_px, size_px) float32 PPI of this radar's returns (``range`` m, ``azimuth`` rad sensor frame,
        ``intensity``; (N,) float32 each): ego at pixel (size_px // 2, size_px // 2), row 0 at the top, a return at
        range R exactly R / metres_per_pixel px from it; ``orientation`` "north_up" (rotated by ``sensor_yaw``
        rad) or "head_up"."""

# --- one frame of every sensor ---

_CaptureTask = (
    tuple[Lidar | Camera | Radar, npt.NDArray[np.float64], int]
    | tuple[Radar, npt.NDArray[np.float64], int, tuple[int, float, str, float] | None]
)

def capture_frame(
    scene: Scene,
    *,
    env: SensorEnv,
    tasks: Sequence[_CaptureTask],
    wakes: npt.NDArray[np.float32] | None = None,
) -> list[tuple[dict[str, npt.NDArray[Any]], float, float]]:
    """Every sensor task of a frame on the current state of ``scene``, concurrently over all cores, GIL released.
    A task is ``(sensor, pose, seed)`` (pose (4, 4) float64 sensor → world) or ``(radar, pose, seed, ppi)`` with
    ``ppi = (size_px, metres_per_pixel, orientation, sensor_yaw)`` or None. Returns, in task order,
    ``(outputs, seconds, ppi_seconds)``: the dict ``scan``/``render``/``sweep`` return (bit-identical to those
    calls; a radar's has ``ppi`` (size_px, size_px) f32 when asked for) and the task's wall seconds (profiling)."""

MAX_DEMO_SIZE: int
"""Largest ``terrain_cells`` (a side) and ``vessels`` of ``demo_scene`` (mmusv_core::demo::MAX_DEMO_SIZE)."""

MAX_IMAGE_PIXELS: int
"""Most pixels of one camera image (4096 x 4096; mmusv_core::sensors::camera::MAX_PIXELS); ``Camera`` refuses more."""

MAX_SURFACE_TILES: int
"""Most tiles one displaced sea surface may hold (2**22; mmusv_core::sea::MAX_TILES)."""

def surface_tiles(foci: npt.NDArray[np.float32], *, radius_m: float = 320.0, tile_m: float = 32.0) -> int:
    """Tiles the displaced sea surface around ``foci`` (F, 2) float32 (world x, y, metres) out to ``radius_m`` holds, in
    tiles of ``tile_m`` (saturated; 0 without foci): ``Scene.set_wave_surface`` refuses more than
    ``MAX_SURFACE_TILES``."""

# --- simd ---

def simd_level() -> str:
    """The core's code paths in this process: ``"avx2"`` (AVX2 + FMA, picked where the CPU has them) or
    ``"portable"`` (any x86-64, or forced by ``MMUSV_SIMD=portable`` in the environment before the first call).
    Every level gives the same bytes; benchmarks report it."""

# --- demo ---

def demo_scene(
    *, seed: int = 1, extent: float = 2000.0, terrain_cells: int = 512, vessels: int = 48
) -> tuple[Scene, list[int]]:
    """The synthetic maritime scene (terrain instance 0, water plane instance 1, vessels; ``extent`` metres, at least
    100; ``terrain_cells`` 1..4096 a side, ``vessels`` at most 4096); returns ``(scene, vessel_instance_ids)``."""

# --- kinematics ---

@final
class Fleet:
    """Vessels on arc-length spline routes with wave heave/roll/pitch (paper eq. 1–3). Poses are
    ``[x, y, z, roll, pitch, yaw]`` in the world frame (metres, radians)."""

    def __new__(
        cls,
        *,
        routes: Sequence[npt.NDArray[np.float64]],
        end_behaviours: Sequence[str],
        speeds: npt.NDArray[np.float64],
        start_offsets: npt.NDArray[np.float64],
        z_base: npt.NDArray[np.float64],
        dims: npt.NDArray[np.float64],
        amplitudes: npt.NDArray[np.float64],
        seed: int,
        wave: str | float,
        sea: WaveField | None = None,
        hulls: npt.NDArray[np.float64] | None = None,
    ) -> Fleet:
        """Per vessel i: routes[i] (K,2) m, end_behaviours[i] in {stop, loop, ping_pong}, speeds (V,) m/s,
        start_offsets (V,) m, z_base (V,) m, dims (V,3) length/beam/height m, amplitudes (V,3) heave m/roll rad/pitch
        rad. With ``sea`` the vessels move physically (heave/roll/pitch through closed-form RAOs of ``hulls``, (V,5)
        length, beam, draft m, block coefficient, GM m) instead of by the paper's formula."""
    @property
    def physical(self) -> bool:
        """Whether the fleet moves physically in a wave field."""
    def __len__(self) -> int:
        """Number of vessels."""
    @property
    def wave_height_m(self) -> float:
        """Wave height H in metres."""
    def route_lengths(self) -> npt.NDArray[np.float64]:
        """(V,) float64 route lengths in metres."""
    def alphas(self) -> npt.NDArray[np.float64]:
        """(V,) float64 size factors α_v."""
    def poses_at(self, t: float) -> npt.NDArray[np.float64]:
        """(V, 6) float64 poses at time t seconds."""
    def velocities_at(self, t: float) -> npt.NDArray[np.float64]:
        """(V, 3) float64 world-frame velocities (m/s) at time t seconds."""
    def wake_pieces(self, t: float, tolerances_m: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """(M, 6) float64 rows ``vessel, x, y, heading, reach_m, age_s``: the path behind each vessel at time t (s)
        as straight pieces, newest first: where each starts (metres, radians), how far back from there the path ran
        straight within ``tolerances_m`` (V,) of that line (inf: on to the wake's end), how long ago the vessel
        passed there (s); out to its wake's reach, at most 32 pieces a vessel; a vessel at rest at a stop route's
        end keeps those it had on arriving, each older by the time since (none if parked there from the start)."""
    def poses_at_times(self, times: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """(T, V, 6) float64 poses at each time (seconds), at most 2**26 poses (T·V) a call; GIL released."""

def default_amplitudes() -> tuple[float, float, float]:
    """Default base amplitudes (heave m, roll rad, pitch rad), calibrated on the reference 5 m USV."""

def reference_usv_dims() -> tuple[float, float, float]:
    """(length m, beam m, height m) of the paper's reference USV (α_v = 1), on which the default amplitudes are
    calibrated."""

def wave_height(wave: str | float) -> float:
    """Wave height H in metres of a preset "W0".."W3" or a height in metres (validated)."""

def exposure_limits() -> dict[str, Any]:
    """The camera exposure settings' ranges: ``ev100``, ``compensation_ev``, ``max_iso`` as ``(lo, hi)`` and
    ``default_max_iso`` (the core's tonemap constants, their one definition)."""

def marshall_palmer() -> tuple[float, tuple[float, float]]:
    """The Marshall–Palmer drop-size law ``(N0, (c, e))``: ``N(D) = N0 e^(−Λ D)`` drops per m³ per mm of diameter
    ``D`` (mm), ``Λ = c R^e`` per mm in rain of ``R`` mm/h (the core's one definition: the cameras' drops and
    :mod:`mmusv.world.rain` read it)."""

def wave_presets() -> list[tuple[str, float]]:
    """``[(name, H metres), ...]`` of the presets W0..W3 in order (the one definition of the presets)."""

# --- ocean ---

@final
class WaveField:
    """A seeded sum of linear deep-water waves realising a directional JONSWAP spectrum (world frame, z up, m, s)."""

    def __new__(
        cls, *, hs_m: float, tp_s: float, gamma: float, direction_rad: float, spread_s: float, seed: int
    ) -> WaveField:
        """Hs (m), Tp (s), peak enhancement γ, mean travel direction (rad), cos-2s exponent, seed."""
    @property
    def spec(self) -> tuple[float, float, float, float, float]:
        """(hs_m, tp_s, gamma, direction_rad, spread_s)."""
    @property
    def seed(self) -> int:
        """The seed of the components."""
    @property
    def max_elevation(self) -> float:
        """Hard bound on |elevation| (m): the sum of the amplitudes."""
    @property
    def max_slope(self) -> float:
        """Hard bound on the slope magnitude."""
    def components(self) -> npt.NDArray[np.float64]:
        """(N, 5) float64: amplitude m, ω rad/s, k rad/m, direction rad, phase rad."""
    def elevation(self, x: npt.NDArray[np.float64], y: npt.NDArray[np.float64], t: float) -> npt.NDArray[np.float64]:
        """(N,) float64 elevations (m) at (N,) world x, y (m), time t (s)."""
    def slope(self, x: npt.NDArray[np.float64], y: npt.NDArray[np.float64], t: float) -> npt.NDArray[np.float64]:
        """(N, 2) float64 slopes [dη/dx, dη/dy]."""
    def orbital_velocity(self, points: npt.NDArray[np.float64], t: float) -> npt.NDArray[np.float64]:
        """(N, 3) float64 orbital velocities (m/s) at (N, 3) world points (m)."""
    def elevation_grid(self, *, x0: float, y0: float, dx: float, nx: int, ny: int, t: float) -> npt.NDArray[np.float32]:
        """(ny, nx) float32 elevations (m); [j, i] at (x0 + i·dx, y0 + j·dx)."""
    def hull_response(
        self,
        *,
        hull: Sequence[float] | npt.NDArray[np.float64],
        positions: npt.NDArray[np.float64],
        yaw: npt.NDArray[np.float64],
        velocities: npt.NDArray[np.float64],
        times: npt.NDArray[np.float64],
    ) -> npt.NDArray[np.float64]:
        """(T, 3) float64 [heave m, roll rad, pitch rad] of a hull [length, beam, draft, Cb, GM] at (T, 2) positions,
        (T,) headings, (T, 2) velocities and (T,) times; GIL released."""

def sea_seed(scenario_seed: int) -> int:
    """The seed of a scenario's wave field."""

def sea_presets() -> list[tuple[str, str, float, float, float, float]]:
    """[(name, description, hs_m, tp_s, gamma, wind_mps), ...]: WMO codes "0".."9", then "W0".."W3"."""

def sea_limits() -> dict[str, tuple[float, float]]:
    """``{"hs_m": (lo, hi), "tp_s": (lo, hi)}``: the significant heights (m) and peak periods (s) a sea takes."""

def fully_developed(hs_m: float) -> tuple[float, float]:
    """(tp_s, wind_mps) of a fully developed Pierson–Moskowitz sea of significant height ``hs_m`` (m): the peak
    period (s) and the wind at 19.5 m, ``√(g·hs_m/0.21)`` (m/s); the 10 m wind mmusv's sensors take is that /
    1.026."""

def dnv_gamma(hs_m: float, tp_s: float) -> float:
    """DNV-RP-C205 peak enhancement for Hs, Tp."""

def hull_rao(
    *,
    hull: Sequence[float] | npt.NDArray[np.float64],
    omega: npt.NDArray[np.float64],
    beta: npt.NDArray[np.float64],
    omega_e: npt.NDArray[np.float64],
) -> npt.NDArray[np.complex128]:
    """(N, 3) complex128 RAOs (heave m/m, roll rad/m, pitch rad/m) of a hull ``[length, beam, draft,
    block_coefficient, gm]`` (m, m, m, 1, m) for waves of frequency ``omega`` (rad/s), heading ``beta`` relative to
    the hull (rad: 0 following, π/2 beam, π head) and encounter frequency ``omega_e`` (rad/s), all ``(N,)``.
    Raises InputError for ``omega`` outside [1e-6, 1e6] rad/s, ``|omega_e|`` past 1e6 or a ``beta`` that is not
    finite."""

def response_variance(
    *,
    hull: Sequence[float] | npt.NDArray[np.float64],
    hs_m: float,
    tp_s: float,
    gamma: float,
    direction_rad: float,
    spread_s: float,
    yaw: float,
    speed_mps: float,
) -> tuple[float, float, float]:
    """Spectral prediction (heave m², roll rad², pitch rad²) at heading ``yaw`` (rad, finite) and speed
    ``speed_mps`` (within [0, 1e6] m/s; a ConfigError names either otherwise)."""

# --- record ---

@final
class Recorder:
    """Streams messages into one MCAP file (zstd chunks, deterministic bytes), written as ``<path>.partial`` and
    renamed to ``path`` by :meth:`finish`. Times are simulation times in integer nanoseconds (log = publish time).
    Every method releases the GIL while it encodes and writes. Use :class:`mmusv.recording.Recording` instead."""

    def __new__(cls, path: str | os.PathLike[str], *, overwrite: bool = False) -> Recorder:
        """Starts a recording; an existing ``path`` raises ``IoError`` unless ``overwrite`` (replaced only on
        finish), and so does a ``path`` whose ``.partial`` another recorder is still writing (it is locked)."""

    @property
    def path(self) -> str:
        """The final file name."""

    @property
    def partial_path(self) -> str:
        """``<path>.partial``, written to until :meth:`finish`."""

    @property
    def closed(self) -> bool:
        """True once :meth:`finish` or :meth:`abandon` ran."""

    def point_cloud(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        names: Sequence[str],
        columns: Sequence[npt.NDArray[Any]],
        pose: Sequence[float] | None = None,
    ) -> None:
        """``foxglove.PointCloud``: ``columns[i]`` is a C-contiguous 1-D array (one value per point) of uint8, int8,
        uint16, int16, uint32, int32, float32 or float64 named ``names[i]``, packed row-interleaved little-endian in
        the order given; ``pose`` = ``(x, y, z, qx, qy, qz, qw)`` of the cloud origin in ``frame_id`` or None
        (identity)."""

    def raw_image(self, topic: str, *, log_time_ns: int, frame_id: str, image: npt.NDArray[Any]) -> None:
        """``foxglove.RawImage``: (H, W) uint8 → mono8, (H, W, 3) uint8 → rgb8, (H, W) uint16 → 16UC1, (H, W) float32 →
        32FC1; C-contiguous."""

    def png_image(self, topic: str, *, log_time_ns: int, frame_id: str, image: npt.NDArray[Any]) -> None:
        """``foxglove.CompressedImage`` format png of a C-contiguous (H, W) uint8, (H, W, 3) uint8 or (H, W) uint16
        image."""

    def images(
        self,
        *,
        log_time_ns: int,
        topics: Sequence[str],
        frame_ids: Sequence[str],
        images: Sequence[npt.NDArray[Any]],
        formats: Sequence[str],
    ) -> tuple[float, float]:
        """Image ``i`` to ``topics[i]`` in ``frame_ids[i]`` as ``formats[i]`` (``"png"`` like :meth:`png_image`,
        ``"raw"`` like :meth:`raw_image`): all encoded in parallel before the recorder is locked, then written in
        list order (the bytes of one call per image). Returns (encode seconds, write seconds), for profiling."""

    def frame_transforms(
        self,
        topic: str,
        *,
        log_time_ns: int,
        parents: Sequence[str],
        children: Sequence[str],
        translations: npt.NDArray[np.float64],
        rotations: npt.NDArray[np.float64],
    ) -> None:
        """``foxglove.FrameTransforms``: pose of ``children[i]`` in ``parents[i]``, ``translations`` (N, 3) float64
        metres, ``rotations`` (N, 4) float64 unit quaternions x, y, z, w."""

    def camera_calibration(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        width: int,
        height: int,
        intrinsics: tuple[float, float, float, float],
        distortion: tuple[float, float, float, float, float],
    ) -> None:
        """``foxglove.CameraCalibration`` of a ``width`` x ``height`` pinhole camera in ``frame_id`` (its optical
        frame): ``intrinsics`` ``(fx, fy, cx, cy)`` pixels in OpenCV's convention (pixel centres at whole numbers),
        ``distortion`` ``(k1, k2, p1, p2, k3)`` (``plumb_bob``); R = I, P = [K | 0]."""

    def image_boxes(
        self,
        topic: str,
        *,
        log_time_ns: int,
        corners: npt.NDArray[np.float64],
        colors: npt.NDArray[np.float32],
        labels: Sequence[str],
    ) -> None:
        """``foxglove.ImageAnnotations`` of 2D boxes: ``corners`` (N, 4) float64 ``[x0, y0, x1, y1]`` pixels (origin
        at the top-left corner of the top-left pixel), ``colors`` (N, 4) float32 RGBA 0..1, ``labels`` N strings
        (a non-empty one drawn at the box's top-left corner)."""

    def boxes(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        entity_id: str,
        ids: Sequence[str],
        centers: npt.NDArray[np.float64],
        quaternions: npt.NDArray[np.float64],
        sizes: npt.NDArray[np.float64],
        colors: npt.NDArray[np.float32],
        labels: Sequence[str],
    ) -> None:
        """``foxglove.SceneUpdate`` with one frame-locked entity ``entity_id`` in ``frame_id``: one cube per box
        (``centers`` (N, 3) m, ``quaternions`` (N, 4) x, y, z, w, ``sizes`` (N, 3) m, ``colors`` (N, 4) float32 RGBA
        0..1) and a text per non-empty label; ``ids`` unique."""

    def world_state(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame: int,
        time_s: float,
        ids: Sequence[str],
        assets: Sequence[str],
        roles: Sequence[str],
        classes: npt.NDArray[np.uint32],
        instance_ids: npt.NDArray[np.uint32],
        poses: npt.NDArray[np.float64],
        velocities: npt.NDArray[np.float64],
        box_centers: npt.NDArray[np.float64],
        box_sizes: npt.NDArray[np.float64],
    ) -> None:
        """``mmusv.WorldState``, one vessel per row: ``classes``/``instance_ids`` (N,) uint32, ``poses`` (N, 6) x, y,
        z, roll, pitch, yaw (world, m, rad), ``velocities`` (N, 3) m/s, ``box_centers`` (N, 3) m, ``box_sizes`` (N,
        3) length, beam, height m."""

    def annotations(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame: int,
        time_s: float,
        agent_id: str,
        lidar_ids: Sequence[str],
        lidar_ints: npt.NDArray[np.uint32],
        lidar_values: npt.NDArray[np.float64],
        bev_ids: Sequence[str],
        bev_values: npt.NDArray[np.float64],
        camera_ids: Sequence[str],
        camera_names: Sequence[str],
        camera_ints: npt.NDArray[np.uint32],
        camera_values: npt.NDArray[np.float64],
    ) -> None:
        """``mmusv.AgentAnnotations`` from packed columns: ``lidar_ints`` (N, 3) [instance_id, semantic_class,
        lidar_points], ``lidar_values`` (N, 13) [center xyz, size lwh, rotation xyzw, yaw, range_m, wave_occlusion];
        ``bev_values`` (M, 5) [x, y, length, width, yaw]; ``camera_ints`` (K, 2) [visible_pixels, box_pixels],
        ``camera_values`` (K, 7) [x_min, y_min, x_max, y_max, truncation, occlusion, wave_occlusion]."""

    def metadata(self, name: str, mapping: Mapping[str, str]) -> None:
        """An MCAP metadata record ``name`` holding ``mapping``."""

    def attachment(self, name: str, *, media_type: str, data: bytes, log_time_ns: int = 0) -> None:
        """An MCAP attachment (log and create time ``log_time_ns``)."""

    def finish(self) -> dict[str, Any]:
        """Completes the file and renames it to ``path``; returns ``{"path", "messages", "channels", "bytes"}``."""

    def abandon(self) -> str:
        """Completes the file but keeps the ``.partial`` name; returns that path (once closed, a no-op returning where
        the file is: its final name after ``finish()``)."""

    def __enter__(self) -> Recorder: ...
    def __exit__(self, exc_type: object = None, exc_value: object = None, traceback: object = None) -> bool:
        """Finishes on a clean exit; after an exception completes the file under ``.partial`` and re-raises."""
