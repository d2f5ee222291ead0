"""Navigation lamps smaller than a pixel (``sensors/camera/lamp_points.rs``): each delivers its light, and only its
light, to the pixel it projects into, at every resolution and quality.

Before, the pixel-centre ray found such a lamp by chance: a 90 m ferry under way 130 m off at midnight left a
320 × 240 frame black (its brightest pixel 1 of 255), and a lamp that was hit filled its pixel with the lens's
radiance.
"""

from __future__ import annotations

import math

import mmusv
import numpy as np
import numpy.typing as npt
import pytest
from mmusv import _core
from mmusv.sensors.camera import render as render_camera
from reference import mitsuba_scenes as ms
from test_lamp_glitter import _front, _night

#: A lit lantern: a closed box (m) of this lens radiance (cd/m²) in every channel, all round.
LANTERN = ((299.9, -0.1, 9.85), (300.1, 0.1, 10.15))
LAMP_RADIANCE = 2.0e4
HFOV = math.radians(40.0)
#: Night: the sun 20° below the horizon; no fog.
ENV = ms.Env(sun=ms.unit((0.3, 0.5, -0.4)))


def _render(width: int, quality: str, *, lights: bool, screen: bool = False) -> npt.NDArray[np.float64]:
    """Radiance ``(H, W, 3)`` of the lantern 300 m ahead of a camera 2 m up, looking level along +x."""
    s = mmusv.Scene()
    e = LAMP_RADIANCE
    s.set_materials(np.array([[0.0] * 9, [0, 0, 0, 0.5, 0, e, e, e, 1], [0, 0, 0, 1.0, 0, 0, 0, 0, 0]], np.float32))
    lantern = s.add_instance(s.add_mesh(*ms.box(*LANTERN), classes=4, name="lantern", materials=1))
    if screen:
        s.add_instance(
            s.add_mesh(*ms.box((150.0, -5.0, 0.0), (150.2, 5.0, 12.0)), classes=4, name="screen", materials=2)
        )
    s.set_lights([lantern], on=lights)
    cam = _core.Camera(width=width, height=width * 3 // 4, rgb=True, hfov=HFOV, quality=quality)
    env = ms.Env(sun=ENV.sun).sensor_env()
    out = render_camera(cam, s, pose=ms.look_pose((0.0, 0.0, 2.0), 0.0, 0.0), env=env, seed=0, radiance=True)
    assert out.radiance is not None
    return out.radiance.astype(np.float64)


def _pixel_solid_angles(width: int, height: int) -> npt.NDArray[np.float64]:
    """Solid angle (sr) of each pixel of an undistorted pinhole camera: ``cos³θ / f²`` at its centre."""
    f = width / (2.0 * math.tan(HFOV / 2.0))
    u, v = np.meshgrid(np.arange(width) + 0.5 - width / 2.0, np.arange(height) + 0.5 - height / 2.0)
    return np.asarray((1.0 + (u / f) ** 2 + (v / f) ** 2) ** -1.5 / f**2)


def _expected_illuminance() -> float:
    """The lantern's illuminance at the camera (lux per channel): its radiance times its projected area seen from
    the camera (a box: the three face pairs, each by the direction cosine across it), over the squared distance."""
    lo, hi = np.array(LANTERN[0]), np.array(LANTERN[1])
    to = (lo + hi) / 2.0 - np.array([0.0, 0.0, 2.0])
    r = float(np.linalg.norm(to))
    w = np.abs(to / r)
    size = hi - lo
    area = w[0] * size[1] * size[2] + w[1] * size[0] * size[2] + w[2] * size[0] * size[1]
    return LAMP_RADIANCE * area / r**2


@pytest.mark.parametrize("quality", ["draft", "standard", "high"])
@pytest.mark.parametrize("width", [160, 320, 640])
def test_a_lamp_smaller_than_a_pixel_delivers_its_light(width: int, quality: str) -> None:
    lit = _render(width, quality, lights=True)
    dark = _render(width, quality, lights=False)
    omega = _pixel_solid_angles(lit.shape[1], lit.shape[0])
    flux = ((lit - dark)[..., 0] * omega).sum()
    want = _expected_illuminance()
    assert flux == pytest.approx(want, rel=0.02), (flux, want)
    # All of it in one pixel.
    assert ((lit - dark)[..., 0] > 0).sum() == 1


def test_a_lamp_behind_a_screen_delivers_nothing() -> None:
    lit = _render(320, "standard", lights=True, screen=True)
    dark = _render(320, "standard", lights=False, screen=True)
    assert np.array_equal(lit, dark)


def test_the_ferrys_lamps_show_at_320_by_240() -> None:
    # The sweep's midnight ferry: before, the frame was black (brightest pixel 1).
    for quality in ("draft", "standard"):
        rgb, sem, _ = _front(_night(quality=quality))
        assert (rgb.max(axis=2)[sem != 1] > 100).sum() >= 2, quality
