"""Sensors of an instrumented USV: spinning LiDAR, marine radar with PPI, pinhole cameras and the top-view camera.

All of them run in the Rust core on one frozen scene state. Configuration lives in :mod:`mmusv.sensors.config`;
:class:`mmusv.Simulation` places them on vessels and captures frames; the functions here also work on any
:class:`mmusv.Scene` with a sensor pose given directly.
"""

from mmusv.sensors.camera import CameraImages, camera_from_config, render, top_view_from_config
from mmusv.sensors.config import CameraConfig, LidarConfig, Mount, RadarConfig, RigConfig, TopViewConfig
from mmusv.sensors.env import sensor_env
from mmusv.sensors.lidar import LidarPoints, lidar_from_config, scan
from mmusv.sensors.radar import RadarReturns, ppi_image, radar_from_config, radar_sweep

__all__ = [
    "CameraConfig",
    "CameraImages",
    "LidarConfig",
    "LidarPoints",
    "Mount",
    "RadarConfig",
    "RadarReturns",
    "RigConfig",
    "TopViewConfig",
    "camera_from_config",
    "lidar_from_config",
    "ppi_image",
    "radar_from_config",
    "radar_sweep",
    "render",
    "scan",
    "sensor_env",
    "top_view_from_config",
]
