"""Cameras from Python: pinhole cameras and the top-view orthographic camera (lighting: :mod:`mmusv.sensors.env`).

Image conventions: row-major ``(H, W)``; ``u`` grows right, ``v`` down; depth is float32 metres along the
optical axis (``inf`` = sky), semantic uint16 class ids (0 = sky), instance int32 ids (−1 = sky), RGB uint8 sRGB.
A camera's body frame is x forward (optical axis), y left, z up; the optical frame used for projection is
x right, y down, z forward.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._equality import same
from mmusv._native import core
from mmusv.errors import InputError
from mmusv.frames import BODY_TO_OPTICAL
from mmusv.scene import Scene, _pose
from mmusv.sensors.config import CameraConfig, TopViewConfig
from mmusv.sensors.env import check_config, check_sensor, check_sensor_args, wake_rows

__all__ = ["BODY_TO_OPTICAL", "PIXEL_CENTRE", "CameraImages", "camera_from_config", "opencv_intrinsics", "render"]
__all__ += ["top_view_from_config"]

PIXEL_CENTRE = 0.5
"""Where mmusv's pixel coordinates put a pixel's centre (pixel ``(i, j)`` covers ``[i, i + 1) × [j, j + 1)``: its
intrinsics, 2D boxes); ROS, like OpenCV (``image_geometry``, ``depth_image_proc``, ``cv2.projectPoints``) and
Foxglove's ``CameraCalibration``, puts it at ``(i, j)``, so their principal point is mmusv's less this (Foxglove's
image annotations use mmusv's: origin at the top-left corner of the top-left pixel)."""


def opencv_intrinsics(intrinsics: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """``(fx, fy, cx, cy)`` pixels of mmusv's intrinsics (pixel centres at +0.5) in OpenCV's, ROS's and Foxglove's
    convention (pixel centres at whole numbers): the principal point less :data:`PIXEL_CENTRE`."""
    fx, fy, cx, cy = intrinsics
    return fx, fy, cx - PIXEL_CENTRE, cy - PIXEL_CENTRE


@dataclass(frozen=True, eq=False)
class CameraImages:
    """One camera's images (see the module docstring), ``(H, W)`` row-major: ``depth`` float32 metres along the
    optical axis (``inf`` = sky), ``semantic`` uint16 class ids, ``instance`` int32 scene instance ids (−1 = sky),
    ``rgb`` ``(H, W, 3)`` uint8 sRGB (``None`` for a camera without ``rgb`` output), ``radiance`` ``(H, W, 3)``
    float32 cd/m² (only when asked for: :func:`render`'s ``radiance``; else ``None``). Two compare equal (``==``)
    when their arrays are (dtype, shape and value)."""

    depth: npt.NDArray[np.float32]
    semantic: npt.NDArray[np.uint16]
    instance: npt.NDArray[np.int32]
    rgb: npt.NDArray[np.uint8] | None
    radiance: npt.NDArray[np.float32] | None = None

    @classmethod
    def from_native(cls, d: dict[str, npt.NDArray[Any]]) -> CameraImages:
        """The images from the dict of ``core.Camera.render`` (or of ``core.capture_frame``)."""
        return cls(
            depth=d["depth"],
            semantic=d["semantic"],
            instance=d["instance"],
            rgb=d.get("rgb"),
            radiance=d.get("radiance"),
        )

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]


def camera_from_config(cfg: CameraConfig) -> core.Camera:
    """The native pinhole camera for ``cfg``, a :class:`CameraConfig` (``CameraConfig(**fields)`` validates a dict;
    else :class:`mmusv.ConfigError`); shades RGB when ``rgb`` is among its outputs."""
    check_config(cfg, CameraConfig)
    w, h = cfg.resolution
    rgb = "rgb" in cfg.outputs
    noise = None if cfg.noise is None else (cfg.noise.full_well_e, cfg.noise.read_noise_e)
    return core.Camera(
        width=w,
        height=h,
        rgb=rgb,
        hfov=math.radians(cfg.hfov_deg),
        range_max=cfg.range_m,
        quality=cfg.quality,
        distortion=None if cfg.distortion is None else list(cfg.distortion),
        noise=noise,
        exposure=cfg.exposure.native(),
    )


def top_view_from_config(cfg: TopViewConfig) -> core.Camera:
    """The native orthographic camera of a top view, ``cfg`` a :class:`TopViewConfig` (else
    :class:`mmusv.ConfigError`)."""
    check_config(cfg, TopViewConfig)
    w, h = cfg.resolution
    rgb = "rgb" in cfg.outputs
    mpp, range_max = cfg.metres_per_pixel, cfg.altitude_m + 500.0
    return core.Camera(
        width=w,
        height=h,
        rgb=rgb,
        metres_per_pixel=mpp,
        range_max=range_max,
        quality=cfg.quality,
        exposure=cfg.exposure.native(),
    )


def render(
    camera: core.Camera,
    scene: Scene,
    *,
    pose: npt.ArrayLike,
    env: core.SensorEnv,
    seed: int,
    wakes: npt.ArrayLike | None = None,
    radiance: bool = False,
) -> CameraImages:
    """Renders ``scene`` (current state) with ``camera`` at ``pose`` (``(4, 4)`` camera body → world) in ``env``
    (:func:`mmusv.sensors.env.sensor_env`). ``wakes``: ``(K, 6)`` to ``(K, 9)`` rows ``x, y,
    heading, speed, length, beam[, reach_m[, age_s[, displacement_m3]]]`` (world metres, radians, m/s, s, m³;
    :func:`mmusv.sensors.env.wake_rows`) of the vessels under way; ``radiance`` also returns the linear radiance
    ``(H, W, 3)`` float32 in cd/m² (linear sRGB primaries, before sensor noise and exposure). ``seed`` is a whole
    number in ``0..2⁶⁴−1``; a bad seed, pose or scene raises :class:`mmusv.InputError` naming it."""
    check_sensor(
        camera,
        core.Camera,
        name="camera",
        made_by="camera_from_config(CameraConfig(...)), top_view_from_config(TopViewConfig(...)), or "
        "Simulation.agent(id).cameras[name][0]",
    )
    seed = check_sensor_args(scene, env=env, seed=seed)
    radiance = arguments.flag(radiance, name="radiance", error=InputError)
    p = _pose(pose, name="pose")
    w = wake_rows(wakes)
    out = camera.render(scene.native, pose=p, env=env, seed=seed, wakes=w, radiance=radiance)
    return CameraImages.from_native(out)
