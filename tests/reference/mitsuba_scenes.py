"""Small scenes rendered by mmusv and by Mitsuba 3 (``scalar_rgb``), for the reference comparison of issue #28.

Both renderers get the same triangles (float32 vertices, flat face normals), the same pinhole camera, the same
sun (a directional light of irradiance ``env.sun_irradiance``, lux, linear sRGB) and the same environment
(``env.sky_radiance``: the Preetham sky above the horizon, mmusv's uniform "ground" below it, no sun disc) as a
lat-long ``envmap``. Radiance is compared linear (cd/m², before exposure and tone mapping).

Materials (mmusv's metallic workflow, ``crates/mmusv-core/src/sensors/shade/brdf.rs``) as Mitsuba BSDFs:

* the Lambert term ``(1 − metallic)·base/π`` is ``diffuse`` with reflectance ``(1 − metallic)·base``;
* the GGX/Smith specular (``α = roughness²``) is ``roughconductor`` (``distribution = ggx``, the separable Smith
  shadowing like mmusv's): for a dielectric ``eta = 1.5, k = 0`` (exact Fresnel, ``F0 = 0.04``; mmusv uses
  Schlick's approximation of it), for a metal Mitsuba's own ``Al`` ``eta``/``k`` (mmusv gets their normal
  incidence reflectance as base colour and uses Schlick);
* mmusv sums the two; Mitsuba has no additive BSDF, so a ``blendbsdf`` of weight 0.5 mixes the two with every
  reflectance doubled (raw bitmap textures): ``0.5·(2 f_d) + 0.5·(2 f_s) = f_d + f_s``;
* water (class 1, ``shade/water.rs``) is Mitsuba's smooth ``plastic`` (``int_ior = 1.33``, ``ext_ior = 1``,
  ``diffuse_reflectance`` = the water albedo, ``nonlinear = false``) without its mirror: the water body; the
  interface's reflection — mmusv's Cox–Munk sun glint and its glossy reflections alike — is a ``roughconductor``
  (``eta = 1.33, k = 0``: the exact dielectric Fresnel at the half vector; ``beckmann``, ``α`` = the Cox–Munk
  slope, the Gaussian slopes of ``shade/rough_water.rs``).

Light transport. mmusv shades direct light only: the sun with a shadow ray, and the environment as image-based
light *without* occlusion (an irradiance map and split-sum prefiltered maps; every surface sees the whole sky and
the uniform ground below the horizon, whatever stands around it); water adds the radiance along its traced mirror
ray (a surface hit there is shaded the same way). Mitsuba's ``path`` integrator renders exactly that as a sum of
layers, each composited on the pixels whose instance (mmusv's instance image) it stands for:

* ``sun``: the full scene lit by the sun alone, ``max_depth = 2`` (direct light, shadows): every surface and
  the water body;
* ``env:<object>``: one object alone in the scene lit by the environment alone, ``max_depth = 2``: its
  image-based light without occlusion, as mmusv's (for water, the body term alone: plastic without its mirror);
  the sky pixels come from one of these (the camera sees the envmap);
* ``mirror``: the full scene under sun and environment with the water its rough interface alone (the
  ``roughconductor`` above), ``max_depth = 3``: the sun's glint, and the water's glossy reflection of the sky
  and of the objects, lit directly (sun with shadows, environment). An object seen in
  the mirror has the water, not the envmap, below its horizon, and the water (no emission) is black at that
  depth: the water scenes therefore set ``ground_albedo = 0``, so that mmusv's lower hemisphere is black too.

Each mmusv image is rendered at ``ss × ss`` times the resolution and box-averaged (pixel ``(u, v)`` covers
``[u, u + 1) × [v, v + 1)`` in both renderers), so both give the mean over each pixel's area. Pixels at a
silhouette (an instance change inside the pixel or with a 4-neighbour), dilated by one pixel, are left out of
the error: there the compositing by instance is not defined.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import numpy.typing as npt
from mmusv import _core
from mmusv.sensors.camera import render as render_camera
from scipy import ndimage

#: Mitsuba's ``Al`` (its spectral data reduced to linear sRGB by Mitsuba in the ``scalar_rgb`` variant).
AL_ETA = (1.6575, 0.880405, 0.521244)
AL_K = (9.22381, 6.2695, 4.837)
#: Index of refraction of the dielectric specular layer (``F0 = 0.04``) and of sea water (mmusv's ``WATER_IOR``).
DIELECTRIC_IOR = 1.5
WATER_IOR = 1.33
#: Lat-long envmap resolution (columns, rows): 0.35° per column, 0.18° per row, so the horizon's step in
#: radiance (sky above, ground below, on a texel boundary) blurs only the directions within 0.09° of it.
ENVMAP_SIZE = (1024, 1024)
#: The envmap's frame: Mitsuba's is y-up (``u = atan2(x, −z) / 2π``, ``v = acos(y) / π``); this rotation takes
#: it to mmusv's z-up world (local y → world z, local x → world x, local z → world −y).
ENVMAP_TO_WORLD = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def conductor_f0(eta: tuple[float, float, float], k: tuple[float, float, float]) -> tuple[float, float, float]:
    """Normal-incidence reflectance ``((n − 1)² + k²) / ((n + 1)² + k²)`` per channel of a conductor."""
    r, g, b = (float(((n - 1) ** 2 + kk**2) / ((n + 1) ** 2 + kk**2)) for n, kk in zip(eta, k, strict=True))
    return (r, g, b)


@dataclass(frozen=True)
class Material:
    """mmusv's material: linear base colour, roughness, metallic 0 (dielectric, ``F0 = 0.04``) or 1 (metal,
    ``F0`` = base colour, here Mitsuba's ``Al``)."""

    base: tuple[float, float, float]
    roughness: float
    metallic: float = 0.0


@dataclass(frozen=True)
class Object:
    """A mesh placed at identity: ``(V, 3)`` float32 vertices (m, world), ``(F, 3)`` int32 faces wound
    counter-clockwise seen from outside; ``material`` ``None`` for water (class 1)."""

    name: str
    vertices: npt.NDArray[np.float32]
    faces: npt.NDArray[np.int32]
    material: Material | None

    @property
    def is_water(self) -> bool:
        """Whether this is the sea surface (class 1, mmusv's water shading)."""
        return self.material is None


@dataclass(frozen=True)
class Env:
    """The environment: unit vector towards the sun (world, z up), turbidity, ground albedo, wind (m/s), cloud
    cover (0 clear, Preetham; 1 overcast, the CIE overcast sky, no direct sun)."""

    sun: tuple[float, float, float]
    turbidity: float = 3.0
    ground_albedo: float = 0.0
    wind_speed_m_s: float = 0.0
    water_albedo: tuple[float, float, float] = (0.004, 0.018, 0.03)
    cloud: float = 0.0

    def sensor_env(self, *, fog_extinction_per_m: float = 0.0) -> Any:
        """The mmusv ``SensorEnv``: the cloud cover ``cloud``, no rain or waves, no fog unless
        ``fog_extinction_per_m`` (1/m), shadows on; the water's single scattering alone (Mitsuba's ``roughconductor``
        reflects once; the multiple scattering is checked against its own reference, ``sensors/shade/sea_ms.rs``)."""
        s = np.asarray(self.sun, dtype=np.float64)
        s = s / np.linalg.norm(s)
        return _core.SensorEnv(
            sun_direction=[float(x) for x in s],
            turbidity=self.turbidity,
            cloud_cover=self.cloud,
            ground_albedo=self.ground_albedo,
            fog_extinction_per_m=fog_extinction_per_m,
            rain_mm_per_h=0.0,
            wave_height_m=0.0,
            wind_speed_m_s=self.wind_speed_m_s,
            water_albedo=list(self.water_albedo),
            shadows=True,
            water_multiple_scattering=False,
        )


@dataclass(frozen=True)
class RefScene:
    """One comparison scene: objects, environment, camera pose (``(4, 4)`` body → world, body x forward,
    y left, z up) and horizontal field of view (radians)."""

    name: str
    title: str
    objects: tuple[Object, ...]
    env: Env
    pose: npt.NDArray[np.float64]
    hfov: float
    notes: str = ""
    extra: dict[str, Any] = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------------- geometry


def uv_sphere(
    center: tuple[float, float, float], radius: float, *, n_lon: int = 64, n_lat: int = 32
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """A UV sphere: ``n_lon`` segments in longitude, ``n_lat`` rings in latitude, poles as single vertices;
    faces wound counter-clockwise seen from outside."""
    verts = [(0.0, 0.0, 1.0)]
    for i in range(1, n_lat):
        th = math.pi * i / n_lat
        for j in range(n_lon):
            ph = 2.0 * math.pi * j / n_lon
            verts.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
    verts.append((0.0, 0.0, -1.0))
    faces: list[tuple[int, int, int]] = []

    def ring(i: int, j: int) -> int:
        return 1 + (i - 1) * n_lon + (j % n_lon)

    bottom = len(verts) - 1
    for j in range(n_lon):
        faces.append((0, ring(1, j), ring(1, j + 1)))
        faces.append((bottom, ring(n_lat - 1, j + 1), ring(n_lat - 1, j)))
    for i in range(1, n_lat - 1):
        for j in range(n_lon):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            faces.append((a, c, d))
            faces.append((a, d, b))
    v = np.asarray(verts, dtype=np.float64) * radius + np.asarray(center, dtype=np.float64)
    return v.astype(np.float32), np.asarray(faces, dtype=np.int32)


def box(
    lo: tuple[float, float, float], hi: tuple[float, float, float]
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """An axis-aligned box from corner ``lo`` to ``hi`` (m), 12 outward-wound triangles."""
    x = (lo[0], hi[0])
    y = (lo[1], hi[1])
    z = (lo[2], hi[2])
    v = np.array([(x[i & 1], y[(i >> 1) & 1], z[(i >> 2) & 1]) for i in range(8)], dtype=np.float32)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = []
    for a, b, c, d in quads:
        faces += [(a, b, c), (a, c, d)]
    return v, np.asarray(faces, dtype=np.int32)


def square(half: float, z: float = 0.0) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """A horizontal square of half-side ``half`` (m) at height ``z``, facing up."""
    v = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]], dtype=np.float32)
    return v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)


def look_pose(position: tuple[float, float, float], yaw: float, pitch_down: float) -> npt.NDArray[np.float64]:
    """Camera body → world: at ``position`` (m), heading ``yaw`` (rad, counter-clockwise from +x), nose down by
    ``pitch_down`` (rad)."""
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch_down), math.sin(pitch_down)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    t = np.eye(4)
    t[:3, :3] = rz @ ry
    t[:3, 3] = position
    return t


def unit(v: tuple[float, float, float]) -> tuple[float, float, float]:
    """``v`` normalised."""
    n = math.sqrt(sum(x * x for x in v))
    return (v[0] / n, v[1] / n, v[2] / n)


# ------------------------------------------------------------------------------------------------------ scenes

AL = Material(base=conductor_f0(AL_ETA, AL_K), roughness=0.4, metallic=1.0)


def scenes() -> dict[str, RefScene]:
    """The comparison scenes by name (see ``docs/realism/mitsuba.md``)."""
    plane = Object("plane", *square(100.0), Material(base=(0.35, 0.3, 0.22), roughness=0.8))
    metal = Object("aluminium sphere", *uv_sphere((0.0, 1.25, 1.0), 1.0), AL)
    plastic = Object("plastic sphere", *uv_sphere((0.0, -1.25, 1.0), 1.0), Material((0.6, 0.12, 0.08), 0.5))
    spheres = RefScene(
        name="spheres",
        title="diffuse plane, rough aluminium and rough plastic spheres, sun and sky",
        objects=(plane, metal, plastic),
        env=Env(sun=unit((-0.45, 0.55, 0.7)), ground_albedo=0.3),
        pose=look_pose((-6.5, 0.0, 3.2), 0.0, math.radians(24.0)),
        hfov=math.radians(50.0),
        notes="plane 200 m square; spheres of radius 1 m, 64×32 UV meshes; ground albedo 0.3",
    )
    sea = Object("water", *square(20_000.0), None)
    hull = Object("hull", *box((15.0, -2.0, -0.6), (29.0, 3.0, 2.4)), Material((0.62, 0.62, 0.64), 0.5))
    cabin = Object("cabin", *box((17.0, -1.2, 2.4), (22.0, 2.2, 5.0)), Material((0.1, 0.22, 0.45), 0.35))
    water = RefScene(
        name="water",
        title="flat water reflecting a vessel-like box and the sky",
        objects=(sea, hull, cabin),
        env=Env(sun=unit((-0.55, -0.6, 0.58))),
        pose=look_pose((0.0, 0.0, 4.0), 0.0, math.radians(8.0)),
        hfov=math.radians(50.0),
        notes="water 40 km square, calm (wave height 0, wind 0: Cox–Munk α = 0.055); ground albedo 0",
    )
    far_hull = Object("far hull", *box((70.0, 2.0, -1.0), (90.0, 8.0, 6.0)), Material((0.55, 0.1, 0.06), 0.5))
    grazing = RefScene(
        name="grazing",
        title="grazing view of the sea near the horizon, low sun",
        objects=(sea, far_hull),
        env=Env(sun=unit((0.1, 0.97, 0.26))),
        pose=look_pose((0.0, 0.0, 2.5), 0.0, math.radians(1.0)),
        hfov=math.radians(40.0),
        notes="camera 2.5 m above the water, 1° down; sun 15° high, 84° to the left of the view; ground albedo 0",
    )
    return {s.name: s for s in (spheres, water, grazing)}


# ------------------------------------------------------------------------------------------------------- mmusv


@dataclass(frozen=True)
class MmusvImage:
    """mmusv's render: ``radiance`` ``(H, W, 3)`` float32 cd/m² (pixel-area means), ``instance`` ``(H, W)``
    int32 at the pixel centres (−1 sky), ``mixed`` ``(H, W)`` bool (an instance change inside the pixel), and
    the unit world ray directions ``(H, W, 3)`` of the pixel centres."""

    radiance: npt.NDArray[np.float32]
    instance: npt.NDArray[np.int32]
    mixed: npt.NDArray[np.bool_]
    dirs: npt.NDArray[np.float32]
    exposure: float
    seconds: float


def mmusv_scene(scene: RefScene) -> mmusv.Scene:
    """The mmusv scene: one mesh and one instance per object, instance ids in object order."""
    s = mmusv.Scene()
    table = [[0.0] * 9]
    for obj in scene.objects:
        if obj.material is not None:
            m = obj.material
            table.append([*m.base, m.roughness, m.metallic, 0.0, 0.0, 0.0, 0.0])
    s.set_materials(np.asarray(table, dtype=np.float32))
    row = 0
    for obj in scene.objects:
        if obj.material is None:
            mid = s.add_mesh(obj.vertices, obj.faces, classes=1, name=obj.name)
        else:
            row += 1
            mid = s.add_mesh(obj.vertices, obj.faces, classes=4, name=obj.name, materials=row)
        s.add_instance(mid)
    return s


def render_mmusv(
    scene: RefScene, width: int, height: int, *, ss: int = 4, seed: int = 0, quality: str = "standard"
) -> MmusvImage:
    """Renders ``scene`` with mmusv at ``ss`` times the resolution (``quality``: ``standard``, the default, traces
    one water reflection per 2×2 block of water pixels, 4×4 where the water's glossy lobe spans many such blocks,
    ``high`` every pixel's) and box-averages ``ss × ss`` blocks."""
    t0 = time.perf_counter()
    s = mmusv_scene(scene)
    env = scene.env.sensor_env()
    cam = _core.Camera(width=width * ss, height=height * ss, rgb=True, hfov=scene.hfov, quality=quality)
    out = render_camera(cam, s, pose=scene.pose, env=env, seed=seed, radiance=True)
    assert out.radiance is not None
    big = out.radiance.astype(np.float64).reshape(height, ss, width, ss, 3)
    rad = big.mean(axis=(1, 3)).astype(np.float32)
    inst = out.instance.reshape(height, ss, width, ss)
    mixed = (inst != inst[:, :1, :, :1]).any(axis=(1, 3))
    seconds = time.perf_counter() - t0
    centre = _core.Camera(width=width, height=height, rgb=False, hfov=scene.hfov)
    c = render_camera(centre, s, pose=scene.pose, env=env, seed=seed)
    _, dirs = centre.world_rays(np.ascontiguousarray(scene.pose))
    return MmusvImage(
        radiance=rad,
        instance=c.instance,
        mixed=mixed,
        dirs=np.asarray(dirs, dtype=np.float32).reshape(height, width, 3),
        exposure=float(env.exposure[1]),
        seconds=seconds,
    )


def excluded(img: MmusvImage) -> npt.NDArray[np.bool_]:
    """Silhouette pixels: an instance change inside the pixel or with a 4-neighbour, dilated by one pixel."""
    inst = img.instance
    edge = img.mixed.copy()
    dx = inst[:, 1:] != inst[:, :-1]
    dy = inst[1:, :] != inst[:-1, :]
    edge[:, 1:] |= dx
    edge[:, :-1] |= dx
    edge[1:, :] |= dy
    edge[:-1, :] |= dy
    return np.asarray(ndimage.binary_dilation(edge, structure=np.ones((3, 3), bool)), dtype=bool)


# ----------------------------------------------------------------------------------------------------- Mitsuba


def _mi() -> Any:
    import mitsuba as mi

    if mi.variant() != "scalar_rgb":
        mi.set_variant("scalar_rgb")
    return mi


def envmap_bitmap(env: Any, size: tuple[int, int] = ENVMAP_SIZE) -> npt.NDArray[np.float32]:
    """The environment (``env.sky_radiance``, no sun disc) as Mitsuba's lat-long envmap ``(rows, cols, 3)``
    float32, texel centres in Mitsuba's local frame taken to the world by :data:`ENVMAP_TO_WORLD`."""
    w, h = size
    if h % 2:
        raise ValueError("the envmap needs an even number of rows (the horizon on a texel boundary)")
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h // 2) + 0.5) / h
    phi, theta = np.meshgrid(2.0 * np.pi * u, np.pi * v)
    local = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)
    world = local.reshape(-1, 3) @ ENVMAP_TO_WORLD.T
    sky = np.asarray(env.sky_radiance(np.ascontiguousarray(world, dtype=np.float32), sun_disc=False))
    # Below the horizon (every texel centre of the lower half) the environment is the uniform ground.
    ground = np.asarray(env.sky_radiance(np.array([[0.0, 0.0, -1.0]], dtype=np.float32), sun_disc=False))
    out = np.empty((h, w, 3), dtype=np.float32)
    out[: h // 2] = sky.reshape(h // 2, w, 3)
    out[h // 2 :] = ground.reshape(1, 1, 3)
    return out


def _const(mi: Any, rgb: Sequence[float] | float) -> dict[str, Any]:
    """A constant texture that may exceed 1 (a raw 1×1 bitmap; Mitsuba's ``rgb`` reflectance must be ≤ 1)."""
    a = np.ones((1, 1, 3), dtype=np.float32) * np.asarray(rgb, dtype=np.float32)
    return {"type": "bitmap", "bitmap": mi.Bitmap(a), "raw": True, "filter_type": "nearest"}


def surface_bsdf(mi: Any, m: Material) -> dict[str, Any]:
    """mmusv's ``f_d + f_s`` as a Mitsuba BSDF (see the module docstring)."""
    alpha = max(m.roughness * m.roughness, 1e-3)
    if m.metallic >= 1.0:
        return {
            "type": "roughconductor",
            "distribution": "ggx",
            "alpha": alpha,
            "eta": {"type": "rgb", "value": list(AL_ETA)},
            "k": {"type": "rgb", "value": list(AL_K)},
        }
    if m.metallic > 0.0:
        raise ValueError("only metallic 0 or 1 is modelled here")
    return {
        "type": "blendbsdf",
        "weight": 0.5,
        "diffuse": {"type": "diffuse", "reflectance": _const(mi, [2.0 * c for c in m.base])},
        "specular": {
            "type": "roughconductor",
            "distribution": "ggx",
            "alpha": alpha,
            "eta": DIELECTRIC_IOR,
            "k": 0.0,
            "specular_reflectance": _const(mi, 2.0),
        },
    }


def water_bsdf(mi: Any, env: Env, part: str) -> dict[str, Any]:
    """The water as Mitsuba sees it in one layer: ``body`` (the plastic without its mirror), ``mirror`` (the
    rough interface alone: Beckmann of mmusv's Cox–Munk ``α = √(0.003 + 5.12·10⁻³ U)``, exact Fresnel; under the
    sun, the glint), ``smooth`` (the whole smooth plastic, mirror and body; no glint: for full path tracing)."""
    if part not in ("body", "mirror", "smooth"):
        raise ValueError(f"unknown water part {part!r}")
    if part == "mirror":
        # The rough interface's reflection alone (a rough conductor with k = 0 has the exact dielectric Fresnel):
        # under the sun, the glint; under the sky and of the other objects, the glossy reflection.
        alpha = math.sqrt(0.003 + 5.12e-3 * max(env.wind_speed_m_s, 0.0))
        return {"type": "roughconductor", "distribution": "beckmann", "alpha": alpha, "eta": WATER_IOR, "k": 0.0}
    d: dict[str, Any] = {
        "type": "plastic",
        "int_ior": WATER_IOR,
        "ext_ior": 1.0,
        "nonlinear": False,
        "diffuse_reflectance": {"type": "rgb", "value": list(env.water_albedo)},
    }
    if part == "body":
        d["specular_reflectance"] = {"type": "rgb", "value": [0.0, 0.0, 0.0]}
    return d


@dataclass(frozen=True)
class Layer:
    """One Mitsuba render of a decomposition: which objects, which lights, the water's part, the path depth,
    samples per pixel, and the instances (−1 the sky) whose pixels it stands for."""

    name: str
    objects: tuple[int, ...]
    sun: bool
    sky: bool
    water: str
    max_depth: int
    spp: int
    pixels: tuple[int, ...]


def layers(scene: RefScene, spp: int) -> list[Layer]:
    """The decomposition of ``scene`` into Mitsuba renders (module docstring); ``spp`` for the environment
    layers, fewer where the light is the sun's alone (no Monte Carlo noise beyond the pixel area)."""
    n = len(scene.objects)
    everything = tuple(range(n))
    water = [i for i, o in enumerate(scene.objects) if o.is_water]
    out = [Layer("sun", everything, True, False, "body", 2, max(16, spp // 4), everything)]
    if water:
        out.append(Layer("mirror", everything, True, True, "mirror", 3, spp, tuple(water)))
    for i, o in enumerate(scene.objects):
        sky = (-1,) if i == 0 else ()
        out.append(Layer(f"env:{o.name}", (i,), False, True, "body", 2, spp, (i, *sky)))
    return out


def mitsuba_dict(
    scene: RefScene,
    layer: Layer,
    width: int,
    height: int,
    workdir: Path,
    seed: int,
    envmap: Any,
    crop: tuple[int, int, int, int] | None = None,
) -> dict[str, Any]:
    """The Mitsuba scene dict of one layer (meshes as PLY files in ``workdir``); ``crop`` ``(x, y, w, h)``
    renders only that window of the ``width × height`` image."""
    mi = _mi()
    r = scene.pose[:3, :3]
    t = scene.pose[:3, 3]
    d: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": layer.max_depth, "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov": math.degrees(scene.hfov),
            "fov_axis": "x",
            "near_clip": 0.01,
            "far_clip": 1e6,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=t.tolist(), target=(t + r[:, 0]).tolist(), up=r[:, 2].tolist()
            ),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
                "sample_border": False,
                **(
                    {}
                    if crop is None
                    else {
                        "crop_offset_x": crop[0],
                        "crop_offset_y": crop[1],
                        "crop_width": crop[2],
                        "crop_height": crop[3],
                    }
                ),
            },
            "sampler": {"type": "multijitter", "sample_count": layer.spp, "seed": seed},
        },
    }
    if layer.sun:
        e = scene.env.sensor_env()
        sun = np.asarray(scene.env.sun, dtype=np.float64)
        d["sun"] = {
            "type": "directional",
            "direction": (-sun / np.linalg.norm(sun)).tolist(),
            "irradiance": {"type": "rgb", "value": list(e.sun_irradiance)},
        }
    if layer.sky:
        d["sky"] = {
            "type": "envmap",
            "bitmap": envmap,
            "to_world": mi.ScalarTransform4f(
                np.block([[ENVMAP_TO_WORLD, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]).tolist()
            ),
        }
    for i in layer.objects:
        o = scene.objects[i]
        path = workdir / f"{scene.name}_{i}.ply"
        if not path.exists():
            write_ply(path, o.vertices, o.faces)
        bsdf = water_bsdf(mi, scene.env, layer.water) if o.material is None else surface_bsdf(mi, o.material)
        d[f"obj{i}"] = {"type": "ply", "filename": str(path), "face_normals": True, "bsdf": bsdf}
    return d


def write_ply(path: Path, vertices: npt.NDArray[np.float32], faces: npt.NDArray[np.int32]) -> None:
    """A binary little-endian PLY of float32 vertices and int32 triangle faces."""
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    tri = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    tri["n"] = 3
    tri["i"] = faces
    path.write_bytes(head + np.ascontiguousarray(vertices, dtype="<f4").tobytes() + tri.tobytes())


@dataclass(frozen=True)
class MitsubaImage:
    """Mitsuba's composite ``(H, W, 3)`` float32 cd/m², its layers and the seconds each took."""

    radiance: npt.NDArray[np.float32]
    layers: dict[str, npt.NDArray[np.float32]]
    seconds: dict[str, float]


def render_layer(
    scene: RefScene,
    layer: Layer,
    width: int,
    height: int,
    *,
    seed: int,
    workdir: Path,
    envmap: Any,
    only: npt.NDArray[np.bool_] | None = None,
) -> npt.NDArray[np.float32]:
    """One Mitsuba layer ``(H, W, 3)`` float32; with ``only`` ``(H, W)``, just the window around those pixels
    (zero elsewhere)."""
    mi = _mi()
    crop = None
    if only is not None:
        rows, cols = np.nonzero(only)
        x0, y0 = int(cols.min()), int(rows.min())
        crop = (x0, y0, int(cols.max()) + 1 - x0, int(rows.max()) + 1 - y0)
    sc = mi.load_dict(mitsuba_dict(scene, layer, width, height, workdir, seed, envmap, crop))
    window = np.asarray(mi.render(sc, seed=seed), dtype=np.float32)[..., :3]
    if crop is None:
        return window
    img = np.zeros((height, width, 3), dtype=np.float32)
    img[crop[1] : crop[1] + crop[3], crop[0] : crop[0] + crop[2]] = window
    return img


def render_path_traced(
    scene: RefScene, width: int, height: int, *, spp: int, seed: int, workdir: Path, max_depth: int = 8
) -> npt.NDArray[np.float32]:
    """Mitsuba's full path tracing of ``scene`` (every object together under sun and sky, paths up to
    ``max_depth``: occlusion of the sky, interreflections; the water smooth plastic without the sun's glint):
    what mmusv's direct-light model leaves out, for information (not the test's reference)."""
    mi = _mi()
    envmap = mi.Bitmap(envmap_bitmap(scene.env.sensor_env()))
    everything = tuple(range(len(scene.objects)))
    layer = Layer("path traced", everything, True, True, "smooth", max_depth, spp, (*everything, -1))
    return render_layer(scene, layer, width, height, seed=seed, workdir=workdir, envmap=envmap)


def render_mitsuba(
    scene: RefScene, instance: npt.NDArray[np.int32], width: int, height: int, *, spp: int, seed: int, workdir: Path
) -> MitsubaImage:
    """Renders the layers of ``scene`` with Mitsuba and composites them by mmusv's ``instance`` image."""
    mi = _mi()
    envmap = mi.Bitmap(envmap_bitmap(scene.env.sensor_env()))
    total = np.zeros((height, width, 3), dtype=np.float64)
    images: dict[str, npt.NDArray[np.float32]] = {}
    seconds: dict[str, float] = {}
    for k, layer in enumerate(layers(scene, spp)):
        t0 = time.perf_counter()
        mask = np.isin(instance, layer.pixels)
        if not mask.any():
            continue
        img = render_layer(scene, layer, width, height, seed=seed + 101 * k, workdir=workdir, envmap=envmap, only=mask)
        seconds[layer.name] = time.perf_counter() - t0
        images[layer.name] = img
        # (np.where, not a product: a NaN sample outside the layer's pixels must not reach the composite.)
        total += np.where(mask[..., None], img, 0.0)
    return MitsubaImage(radiance=total.astype(np.float32), layers=images, seconds=seconds)


# ---------------------------------------------------------------------------------------------------- metrics


def relative_error(a: npt.NDArray[np.floating[Any]], b: npt.NDArray[np.floating[Any]]) -> npt.NDArray[np.float64]:
    """Per-pixel relative error ``Σ_c |a_c − b_c| / max(Σ_c b_c, ε)`` of ``(H, W, 3)`` radiances against the
    reference ``b`` (``ε`` = 10⁻⁶ of the image's mean, against division by zero)."""
    a64 = np.asarray(a, dtype=np.float64)
    b64 = np.asarray(b, dtype=np.float64)
    den = np.maximum(b64.sum(axis=-1), 1e-6 * max(float(b64.sum(axis=-1).mean()), 1e-30))
    return np.asarray(np.abs(a64 - b64).sum(axis=-1) / den, dtype=np.float64)


@dataclass(frozen=True)
class Comparison:
    """One scene compared: both images, the per-pixel relative error, the pixels kept, the mean error."""

    scene: RefScene
    mmusv: MmusvImage
    mitsuba: MitsubaImage
    error: npt.NDArray[np.float64]
    keep: npt.NDArray[np.bool_]

    @property
    def mean_error(self) -> float:
        """Mean relative error over the kept pixels."""
        return float(self.error[self.keep].mean())


def compare(
    scene: RefScene, width: int, height: int, *, spp: int, workdir: Path, seed: int = 0, ss: int = 4
) -> Comparison:
    """Renders ``scene`` with both renderers and compares them (silhouettes excluded)."""
    a = render_mmusv(scene, width, height, ss=ss, seed=seed)
    b = render_mitsuba(scene, a.instance, width, height, spp=spp, seed=seed, workdir=workdir)
    err = relative_error(a.radiance, b.radiance)
    keep = ~excluded(a)
    return Comparison(scene=scene, mmusv=a, mitsuba=b, error=err, keep=keep)


def timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    """``fn()`` and the seconds it took."""
    t0 = time.perf_counter()
    r = fn()
    return r, time.perf_counter() - t0
