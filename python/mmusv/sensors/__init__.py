"""Sensors of an instrumented USV: spinning LiDAR, marine radar with PPI, pinhole cameras and the top-view camera.

All of them run in the Rust core on one frozen scene state. Configuration lives in :mod:`mmusv.sensors.config`;
:class:`mmusv.Simulation` places them on vessels and captures frames; the functions here also work on any
:class:`mmusv.Scene` with a sensor pose given directly.
"""

from mmusv.sensors.camera import CameraImages, camera_from_config, render, shading_kwargs, top_view_from_config
from mmusv.sensors.config import CameraConfig, LidarConfig, Mount, RadarConfig, RigConfig, TopViewConfig
from mmusv.sensors.lidar import LidarPoints, lidar_from_config, scan

__all__ = [
    "CameraConfig",
    "CameraImages",
    "LidarConfig",
    "LidarPoints",
    "Mount",
    "RadarConfig",
    "RigConfig",
    "TopViewConfig",
    "camera_from_config",
    "lidar_from_config",
    "render",
    "scan",
    "shading_kwargs",
    "top_view_from_config",
]
