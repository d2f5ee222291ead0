"""Cameras from Python: pinhole cameras and the top-view orthographic camera, and the lighting they shade with.

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

from mmusv._native import core
from mmusv.frames import BODY_TO_OPTICAL
from mmusv.scene import Scene
from mmusv.sensors.config import CameraConfig, TopViewConfig
from mmusv.world.environment import Environment

__all__ = ["CameraImages", "camera_from_config", "top_view_from_config", "shading_kwargs", "render", "BODY_TO_OPTICAL"]


@dataclass(frozen=True)
class CameraImages:
    """One camera's images (see the module docstring); ``rgb`` is ``None`` unless requested."""

    depth: npt.NDArray[np.float32]
    semantic: npt.NDArray[np.uint16]
    instance: npt.NDArray[np.int32]
    rgb: npt.NDArray[np.uint8] | None


def camera_from_config(cfg: CameraConfig) -> Any:
    """The native pinhole camera for ``cfg``."""
    w, h = cfg.resolution
    return core.Camera(width=w, height=h, hfov=math.radians(cfg.hfov_deg), range_max=cfg.range_m)


def top_view_from_config(cfg: TopViewConfig) -> Any:
    """The native orthographic camera of a top view."""
    w, h = cfg.resolution
    return core.Camera(width=w, height=h, metres_per_pixel=cfg.metres_per_pixel, range_max=cfg.altitude_m + 500.0)


def shading_kwargs(env: Environment) -> dict[str, Any]:
    """Lighting keywords of ``Camera.render`` for an environment: sun, sky gradient by sun height and cloud cover,
    fog colour and extinction, rain, wave height."""
    sun = env.sun
    cloud = env.weather.cloud_cover
    elev = max(0.0, math.sin(math.radians(sun.elevation_deg)))
    zen_clear = np.array([0.10, 0.28, 0.70]) * (0.3 + 0.7 * elev) + np.array([0.02, 0.02, 0.05])
    hor_clear = np.array([0.62, 0.70, 0.82]) * (0.4 + 0.6 * elev) + np.array([0.25, 0.1, 0.0]) * (1 - elev) * sun.intensity
    grey = np.array([0.55, 0.57, 0.6])
    zenith = zen_clear * (1 - cloud) + grey * cloud
    horizon = hor_clear * (1 - cloud) + grey * 1.05 * cloud
    direct = sun.intensity * (1.0 - 0.85 * cloud)
    return {
        "sun_direction": [float(x) for x in sun.direction],
        "sun_color": [float(x) for x in sun.color],
        "sun_intensity": float(direct),
        "ambient": float(sun.ambient),
        "sky_zenith": [float(x) for x in zenith],
        "sky_horizon": [float(x) for x in horizon],
        "fog_extinction_per_m": float(env.weather.extinction_per_m),
        "fog_color": [0.72, 0.75, 0.78],
        "rain_mm_per_h": float(env.weather.rain_mm_per_h),
        "wave_height_m": float(env.wave_height_m),
    }


def render(
    camera: Any,
    scene: Scene,
    *,
    pose: npt.ArrayLike,
    seed: int,
    rgb: bool = True,
    lighting: dict[str, Any] | None = None,
) -> CameraImages:
    """Renders ``scene`` (current state) with ``camera`` at ``pose`` (``(4, 4)`` camera body → world).
    ``lighting`` is :func:`shading_kwargs` of an environment (default: clear noon)."""
    light = lighting if lighting is not None else shading_kwargs(Environment.make())
    p = np.ascontiguousarray(pose, dtype=np.float64).reshape(4, 4)
    d = camera.render(scene.native, pose=p, rgb=bool(rgb), seed=int(seed), **light)
    return CameraImages(depth=d["depth"], semantic=d["semantic"], instance=d["instance"], rgb=d.get("rgb"))
