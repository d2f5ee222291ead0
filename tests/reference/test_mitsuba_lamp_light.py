"""The navigation lamps' light on a hull at night (``sensors/shade/lamp_light.rs``) against Mitsuba 3.

The scene: a lit lantern (a closed 0.2 × 0.2 × 0.3 m box of 2·10⁴ cd/m², mmusv's navigation-lamp radiance) 4 m
in front of a grey wall (a box face, mmusv's metallic workflow: Lambert under GGX, ``mitsuba_scenes.surface_bsdf``),
with a black post between them that shadows part of the wall, at night, seen by a camera off to the side.
Mitsuba's ``path`` integrator (``max_depth = 2``: direct light) samples the lantern, an ``area`` emitter, at every
wall point and traces the shadows, the night sky an ``envmap``; mmusv samples the lamp as a point source of the
lantern's intensity. The wall pixels where the light is more than 1 % of its brightest are compared in linear
radiance. Before the lamps lit hulls, mmusv's wall was as dark as the night sky left it.

The second scene stands the wall on calm water (1 m/s of wind, no water body) and looks at the water in front of
it: the lit wall's reflection and the lantern's glitter. Mitsuba renders the water as its rough interface alone
(``mitsuba_scenes.water_bsdf`` ``mirror``), ``max_depth = 3`` (camera, water, wall, lantern); mmusv adds the lamps'
light to what its traced reflections meet. Before, the water mirrored the wall unlit.
"""

from __future__ import annotations

import math
from pathlib import Path

import mitsuba_scenes as ms
import mmusv
import numpy as np
import numpy.typing as npt
import pytest
from mmusv import _core
from mmusv.sensors.camera import render as render_camera
from scipy import ndimage

#: Resolution, Mitsuba's samples per pixel, mmusv's supersampling.
WIDTH, HEIGHT, SPP, SS = 96, 64, 256, 4
#: The bound of issue #28 on a scene's mean relative error.
MAX_MEAN_ERROR = 0.03
LAMP_RADIANCE = 2.0e4
LANTERN = ((3.9, -0.1, 2.85), (4.1, 0.1, 3.15))
WALL = ((-0.5, -12.0, -2.0), (0.0, 12.0, 8.0))
POST = ((1.9, -1.3, -2.0), (2.1, -0.8, 8.0))
GREY = ms.Material((0.5, 0.45, 0.4), 0.6)
ENV = ms.Env(sun=ms.unit((0.3, 0.5, -0.4)))
#: A camera 6 m off the wall, 8 m to the side of the lantern (the post's shadow and the post apart in its view),
#: looking at the wall 1 m on the other side of the lantern.
POSE = ms.look_pose((6.0, 8.0, 3.0), math.atan2(-9.0, -6.0), math.radians(5.0))
HFOV = math.radians(70.0)


def _mmusv(lamp_radiance: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """mmusv's radiance ``(H, W, 3)`` (pixel-area means) and the instances ``(H, W, SS, SS)`` of the samples."""
    s = mmusv.Scene()
    e = lamp_radiance
    g = GREY
    s.set_materials(
        np.array(
            [
                [0.0] * 9,
                [0, 0, 0, 0.5, 0, e, e, e, 1],
                [0, 0, 0, 1.0, 0, 0, 0, 0, 0],
                [*g.base, g.roughness, 0, 0, 0, 0, 0],
            ],
            np.float32,
        )
    )
    s.add_instance(s.add_mesh(*ms.box(*WALL), classes=4, name="wall", materials=3))
    s.add_instance(s.add_mesh(*ms.box(*POST), classes=4, name="post", materials=2))
    lantern = s.add_instance(s.add_mesh(*ms.box(*LANTERN), classes=4, name="lantern", materials=1))
    s.set_lights([lantern], on=True)
    cam = _core.Camera(width=WIDTH * SS, height=HEIGHT * SS, rgb=True, hfov=HFOV, quality="standard")
    out = render_camera(cam, s, pose=POSE, env=ENV.sensor_env(), seed=0, radiance=True)
    assert out.radiance is not None
    rad = out.radiance.astype(np.float64).reshape(HEIGHT, SS, WIDTH, SS, 3).mean(axis=(1, 3))
    return rad, out.instance.reshape(HEIGHT, SS, WIDTH, SS)


def _mitsuba(workdir: Path) -> npt.NDArray[np.float64]:
    """Mitsuba's radiance ``(H, W, 3)``: the wall lit by the lantern (an area emitter) and the night sky."""
    mi = ms._mi()
    env = ENV.sensor_env()
    wall = ms.Object("wall", *ms.box(*WALL), GREY)
    scene = ms.RefScene("lamp_light", "lamp light", (wall,), ENV, POSE, HFOV)
    layer = ms.Layer("lamp", (0,), False, True, "body", 2, SPP, (0,))
    d = ms.mitsuba_dict(scene, layer, WIDTH, HEIGHT, workdir, 0, mi.Bitmap(ms.envmap_bitmap(env)))
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    for name, (lo, hi) in (("lantern", LANTERN), ("post", POST)):
        path = workdir / f"lamp_light_{name}.ply"
        ms.write_ply(path, *ms.box(lo, hi))
        d[name] = {"type": "ply", "filename": str(path), "face_normals": True, "bsdf": black}
    d["lantern"]["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [LAMP_RADIANCE] * 3}}
    return np.asarray(mi.render(mi.load_dict(d), seed=0), dtype=np.float64)[..., :3]


@pytest.fixture(scope="module")
def rendered(tmp_path_factory: pytest.TempPathFactory) -> tuple[npt.NDArray[np.float64], ...]:
    a, inst = _mmusv(LAMP_RADIANCE)
    b = _mitsuba(tmp_path_factory.mktemp("mitsuba_lamp_light"))
    # The wall (instance 0) in every sample of the pixel and of its neighbours two pixels round.
    wall = ndimage.binary_erosion((inst == 0).all(axis=(1, 3)), iterations=2)
    lit = wall & (b.sum(axis=-1) > 0.01 * b.sum(axis=-1)[wall].max())
    return a, b, wall, lit


MIRROR_SPP = 1024
MIRROR_ENV = ms.Env(sun=ms.unit((0.3, 0.5, -0.4)), wind_speed_m_s=1.0, water_albedo=(0.0, 0.0, 0.0))
#: A camera 1.5 m up, 16 m off the wall, looking at the water in front of it.
MIRROR_POSE = ms.look_pose((16.0, 4.0, 1.5), math.atan2(-4.0, -16.0), math.radians(6.0))
MIRROR_HFOV = math.radians(60.0)


def _mmusv_mirror() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """The second scene by mmusv: radiance ``(H, W, 3)`` and the instances ``(H, W, SS, SS)`` (0 the water)."""
    s = mmusv.Scene()
    e, g = LAMP_RADIANCE, GREY
    s.set_materials(
        np.array([[0.0] * 9, [0, 0, 0, 0.5, 0, e, e, e, 1], [*g.base, g.roughness, 0, 0, 0, 0, 0]], np.float32)
    )
    s.add_instance(s.add_mesh(*ms.square(20_000.0), classes=1, name="water"))
    s.add_instance(s.add_mesh(*ms.box(*WALL), classes=4, name="wall", materials=2))
    lantern = s.add_instance(s.add_mesh(*ms.box(*LANTERN), classes=4, name="lantern", materials=1))
    s.set_lights([lantern], on=True)
    cam = _core.Camera(width=WIDTH * SS, height=HEIGHT * SS, rgb=True, hfov=MIRROR_HFOV, quality="standard")
    out = render_camera(cam, s, pose=MIRROR_POSE, env=MIRROR_ENV.sensor_env(), seed=0, radiance=True)
    assert out.radiance is not None
    rad = out.radiance.astype(np.float64).reshape(HEIGHT, SS, WIDTH, SS, 3).mean(axis=(1, 3))
    return rad, out.instance.reshape(HEIGHT, SS, WIDTH, SS)


def _mitsuba_mirror(workdir: Path) -> npt.NDArray[np.float64]:
    """The second scene by Mitsuba: the water's rough interface and the wall, the lantern, the night sky."""
    mi = ms._mi()
    sea = ms.Object("water", *ms.square(20_000.0), None)
    wall = ms.Object("wall", *ms.box(*WALL), GREY)
    scene = ms.RefScene("lamp_mirror", "lamp light mirrored", (sea, wall), MIRROR_ENV, MIRROR_POSE, MIRROR_HFOV)
    layer = ms.Layer("mirror", (0, 1), False, True, "mirror", 3, MIRROR_SPP, (0, 1))
    envmap = mi.Bitmap(ms.envmap_bitmap(MIRROR_ENV.sensor_env()))
    d = ms.mitsuba_dict(scene, layer, WIDTH, HEIGHT, workdir, 0, envmap)
    path = workdir / "lamp_mirror_lantern.ply"
    ms.write_ply(path, *ms.box(*LANTERN))
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    d["lantern"] = {"type": "ply", "filename": str(path), "face_normals": True, "bsdf": black}
    d["lantern"]["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [LAMP_RADIANCE] * 3}}
    return np.asarray(mi.render(mi.load_dict(d), seed=0), dtype=np.float64)[..., :3]


def _errors(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64], keep: npt.NDArray[np.bool_]) -> tuple[float, float]:
    """Mean per-pixel relative error and the relative error of the sums over ``keep``."""
    diff = np.abs(a - b).sum(axis=-1)[keep]
    ref = b.sum(axis=-1)[keep]
    return float((diff / ref).mean()), float(diff.sum() / ref.sum())


def test_lamp_light_on_a_wall_matches_mitsuba(rendered: tuple[npt.NDArray[np.float64], ...]) -> None:
    a, b, wall, lit = rendered
    # The lamp lights most of the wall in view, the post's shadow cuts it, and mmusv's light matches.
    assert lit.sum() >= 0.5 * wall.sum(), (lit.sum(), wall.sum())
    shadow = wall & ~lit
    assert shadow.sum() >= 20, shadow.sum()
    mean, total = _errors(a, b, lit)
    assert mean <= MAX_MEAN_ERROR, mean
    assert total <= 0.015, total


def test_the_comparison_sees_a_lamp_ten_percent_too_bright(rendered: tuple[npt.NDArray[np.float64], ...]) -> None:
    _, b, _, lit = rendered
    a, _ = _mmusv(1.1 * LAMP_RADIANCE)
    mean, _ = _errors(a, b, lit)
    assert mean > MAX_MEAN_ERROR, mean


def test_the_lit_wall_mirrors_lit_in_the_water(tmp_path: Path) -> None:
    a, inst = _mmusv_mirror()
    b = _mitsuba_mirror(tmp_path)
    water = ndimage.binary_erosion((inst == 0).all(axis=(1, 3)), iterations=2)
    keep = water & (b.sum(axis=-1) > 0.01 * b.sum(axis=-1)[water].max())
    assert keep.sum() >= 800, keep.sum()
    mean, total = _errors(a, b, keep)
    # Measured on this build: 3.1 % per pixel, 1.6 % over the sum (the build before, whose reflections met the
    # wall unlit: 74 % and 19 %). The bound is test_mitsuba's for the objects' glossy reflections, 8 %, and 3 % of
    # the sum.
    assert mean <= 0.08, mean
    assert total <= 0.03, total
