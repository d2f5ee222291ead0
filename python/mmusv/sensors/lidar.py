"""The spinning LiDAR from Python: build it from a :class:`~mmusv.sensors.config.LidarConfig`, scan a scene.

Points are in the LiDAR frame (x forward, y left, z up, metres), in pattern order (azimuth column, then ring),
rays without a return left out. A sweep is one instant: every ray meets the scene as it is at ``pose`` (no
motion distortion; :class:`~mmusv.sensors.config.LidarConfig`). See ``mmusv_core::sensors::lidar`` for the
return, noise, water and weather model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv._equality import same
from mmusv._native import core
from mmusv.scene import Scene, _pose
from mmusv.sensors.config import LidarConfig
from mmusv.sensors.env import check_config, check_sensor, check_sensor_args, wake_rows

__all__ = ["LidarPoints", "lidar_from_config", "scan"]


@dataclass(frozen=True, eq=False)
class LidarPoints:
    """One sweep. All arrays have length N (points). Two sweeps compare equal (``==``) when their arrays are
    (dtype, shape and value).

    Attributes:
        xyz: ``(N, 3)`` float32, metres, LiDAR frame.
        range: ``(N,)`` float32, measured range in metres (noise included).
        intensity: ``(N,)`` float32 in [0, 1]: ``ρ(class) · |cos θ| · τ / (1 + (r / 100 m)²)`` (θ the incidence, τ
            the two-way transmission), the project's own law, neither a raw power nor a calibrated reflectivity;
            over the physical sea a water return's is its speckle draw (``mmusv_core::sensors::lidar``).
        ring: ``(N,)`` uint16 channel index.
        azimuth: ``(N,)`` float32 radians in [0, 2π), counter-clockwise from +x.
        semantic_class: ``(N,)`` uint16 class of the surface hit (:mod:`mmusv.classes`).
        instance: ``(N,)`` int32 scene instance id of the surface hit.
        ray_index: ``(N,)`` uint32 index of the ray in the full pattern (``column · channels + ring``).
    """

    xyz: npt.NDArray[np.float32]
    range: npt.NDArray[np.float32]
    intensity: npt.NDArray[np.float32]
    ring: npt.NDArray[np.uint16]
    azimuth: npt.NDArray[np.float32]
    semantic_class: npt.NDArray[np.uint16]
    instance: npt.NDArray[np.int32]
    ray_index: npt.NDArray[np.uint32]

    def __len__(self) -> int:
        return int(self.xyz.shape[0])

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]

    @classmethod
    def from_native(cls, d: dict[str, npt.NDArray[Any]]) -> LidarPoints:
        """The sweep from the dict of ``core.Lidar.scan`` (or of ``core.capture_frame``)."""
        return cls(
            xyz=d["xyz"],
            range=d["range"],
            intensity=d["intensity"],
            ring=d["ring"],
            azimuth=d["azimuth"],
            semantic_class=d["class"],
            instance=d["instance"],
            ray_index=d["ray_index"],
        )


def lidar_from_config(cfg: LidarConfig) -> core.Lidar:
    """The native LiDAR (pattern computed once) for ``cfg``, a :class:`LidarConfig` (``LidarConfig(**fields)``
    validates a dict), else :class:`mmusv.ConfigError`."""
    check_config(cfg, LidarConfig)
    return core.Lidar(
        elevations=cfg.elevations_rad(),
        azimuth_steps=cfg.azimuth_steps,
        range_min=cfg.range_min_m,
        range_max=cfg.range_m,
        range_noise_std=cfg.range_noise_std_m,
        dropout=cfg.dropout,
        water_probability=cfg.water_probability,
        water_probability_per_wave_m=cfg.water_probability_per_wave_m,
        water_range_m=cfg.water_range_m,
        water_range_per_wave_m=cfg.water_range_per_wave_m,
        beam_divergence=cfg.beam_divergence_mrad * 1e-3,
    )


def scan(
    lidar: core.Lidar,
    scene: Scene,
    *,
    pose: npt.ArrayLike,
    env: core.SensorEnv,
    seed: int,
    wakes: npt.ArrayLike | None = None,
) -> LidarPoints:
    """One sweep of ``lidar`` (from :func:`lidar_from_config`) at ``pose`` (``(4, 4)`` LiDAR → world) on the
    current state of ``scene`` in ``env`` (:func:`mmusv.sensors.env.sensor_env`: the fog extinction, the rain's drops
    included, the waves and the wind are used).
    ``seed`` drives noise, dropout and water returns. ``wakes``: ``(K, 6)`` to ``(K, 9)`` rows ``x, y,
    heading, speed, length, beam[, reach_m[, age_s[, displacement_m3]]]`` (world metres, radians, m/s, s, m³;
    :meth:`mmusv.simulation.Simulation.wakes`, :func:`mmusv.sensors.env.wake_rows`) of the vessels under way: over
    a wave surface, beams that meet their foam return from it (the foam the cameras draw). ``seed`` is a whole
    number in ``0..2⁶⁴−1``; a bad seed, pose or scene raises :class:`mmusv.InputError` naming it."""
    check_sensor(
        lidar, core.Lidar, name="lidar", made_by="lidar_from_config(LidarConfig(...)), or Simulation.agent(id).lidar"
    )
    seed = check_sensor_args(scene, env=env, seed=seed)
    p = _pose(pose, name="pose")
    w = wake_rows(wakes)
    return LidarPoints.from_native(lidar.scan(scene.native, pose=p, env=env, seed=seed, wakes=w))
