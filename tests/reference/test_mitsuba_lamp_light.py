"""The navigation lamps' light on a hull at night (``sensors/shade/lamp_light.rs``) against Mitsuba 3.

The scene: a lit lantern (a closed 0.2 × 0.2 × 0.3 m box of 2·10⁴ cd/m², mmusv's navigation-lamp radiance) 4 m
in front of a grey wall (a box face, mmusv's metallic workflow: Lambert under GGX, ``mitsuba_scenes.surface_bsdf``),
with a black post between them that shadows part of the wall, at night, seen by a camera off to the side.
Mitsuba's ``path`` integrator (``max_depth = 2``: direct light) samples the lantern, an ``area`` emitter, at every
wall point and traces the shadows, the night sky an ``envmap``; mmusv samples the lamp as a point source of the
lantern's intensity. The wall pixels where the light is more than 1 % of its brightest are compared in linear
radiance. Before the lamps lit hulls, mmusv's wall was as dark as the night sky left it.
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
