"""What a :class:`~mmusv.simulation.Simulation` gives: the world state of one frame and every agent's capture.

Frames: world x east, y north, z up (metres); vessel/sensor body frames x forward, y left, z up. Poses are
``(4, 4)`` float64 sensor → world matrices. These types are re-exported by :mod:`mmusv.simulation`.

Two captures compare equal (``==``) when they hold the same values: arrays by dtype, shape and value, fields that
are for profiling only (``sensor_seconds``) left out; they are not hashable. A capture's arrays are its own
(writable: changing one changes neither the simulation nor its later captures), and a capture pickles (a
``DataLoader`` worker can return one).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mmusv._equality import same
from mmusv.sensors.camera import CameraImages
from mmusv.sensors.lidar import LidarPoints
from mmusv.sensors.radar import RadarReturns

__all__ = ["AgentCapture", "FrameCapture", "SensorMount", "VesselInfo", "WorldState"]


@dataclass(frozen=True, eq=False)
class VesselInfo:
    """A vessel of the world state: scenario vessels first (file order), then moored ships (port maps)."""

    id: str
    asset: str
    role: str  # "usv", "target" or "moored"
    semantic_class: int
    instance_id: int
    box_center_body: np.ndarray  # (3,) float64 box centre in the vessel body frame, metres (read-only)
    box_size: np.ndarray  # (3,) float64 length, beam, height, metres (read-only)
    static: bool = False  # never travels (moored ships, scenario vessels at speed 0: VesselConfig.static); rides waves

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class WorldState:
    """Every vessel at one frame (V vessels, in ``Simulation.vessels`` order), at acquisition index ``frame`` and
    time ``time_s`` (``k / f``, seconds). Arrays are float64: ``poses`` ``(V, 6)`` [x, y, z, roll, pitch, yaw] (m,
    rad, world), ``velocities`` ``(V, 3)`` m/s world, ``box_centers`` ``(V, 3)`` world metres (the bounding-box
    centres), ``matrices`` ``(V, 4, 4)`` vessel body → world."""

    frame: int
    time_s: float
    poses: np.ndarray
    velocities: np.ndarray
    box_centers: np.ndarray
    matrices: np.ndarray

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class SensorMount:
    """Where one sensor is at a frame: ``mount`` ``(4, 4)`` float64 sensor → vessel body, ``pose`` ``(4, 4)``
    float64 sensor → world (``body · mount``). Fixed for body-mounted sensors; for the level top view the mount
    is ``body⁻¹ · pose`` and changes with the vessel's attitude."""

    mount: np.ndarray
    pose: np.ndarray

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]


@dataclass(eq=False)
class AgentCapture:
    """Everything one USV's sensors produced at one frame, with the sensor poses (sensor → world).

    Poses (``lidar_pose``, ``camera_poses[name]``, ``top_view_pose``, ``radar_pose``) are ``(4, 4)`` float64 sensor
    → world, ``None`` for a sensor not captured; ``radar_ppi`` is the ``(S, S)`` float32 linear-intensity PPI of
    :func:`~mmusv.sensors.radar.ppi_image` (``S`` = the rig's ``ppi_size_px``; 0 where nothing).
    ``body`` is the USV's ``(4, 4)`` float64 body → world matrix and ``sensors`` every sensor of the USV (captured or
    not) as a :class:`SensorMount`, keyed ``lidar``, ``radar``, ``camera/<name>``, ``top_view``: read the mounts
    and poses there rather than recomputing ``body · mount``.
    """

    agent: str
    lidar: LidarPoints | None
    lidar_pose: np.ndarray | None
    cameras: dict[str, CameraImages]
    camera_poses: dict[str, np.ndarray]
    top_view: CameraImages | None
    top_view_pose: np.ndarray | None
    radar: RadarReturns | None = None
    radar_ppi: np.ndarray | None = None
    radar_pose: np.ndarray | None = None
    body: np.ndarray | None = None
    sensors: dict[str, SensorMount] = field(default_factory=dict)
    lidar_beams: np.ndarray | None = field(default=None, repr=False, compare=False)
    """``(M,)`` int32: per ray of the LiDAR's full pattern (pattern order, returned or not), the scene instance
    its cast met first within the range, -1 for none; what the annotations read to know which beams the water
    stopped. Not recorded."""

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]


@dataclass(eq=False)
class FrameCapture:
    """One acquisition index ``frame`` at ``time_s`` (``k / f``, seconds): the world state and every agent's
    capture, keyed by agent id."""

    frame: int
    time_s: float
    world: WorldState
    agents: dict[str, AgentCapture]
    sensor_seconds: dict[str, float] = field(default_factory=dict, compare=False)
    """Wall seconds each sensor's work took, keyed ``<agent>/<sensor>`` (``lidar``, ``camera/<name>``,
    ``top_view``, ``radar``, ``ppi``): for profiling only, never recorded."""

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]
