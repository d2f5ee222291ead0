"""One agent's annotations at one frame (:class:`Annotations`): the boxes :func:`mmusv.annotate.annotate_agent`
works out, held as lists while it goes, and their numpy columns, the groups ``Recording.annotations`` reads
(:meth:`Annotations.columns`). What each column means, and in which frame, is :mod:`mmusv.annotate`'s docstring.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mmusv._equality import same

__all__ = ["Annotations"]


@dataclass(eq=False)
class Annotations:
    """Columns of one agent's annotations at acquisition index ``frame``, ``time_s`` seconds (see
    :mod:`mmusv.annotate`), as lists, one entry per box, in the units and frames of :meth:`columns`. Lengths: ``n3d``
    for ``lidar_*``, ``n2d`` for ``cam_*``. Two compare equal (``==``) when they hold the same values (arrays by
    dtype, shape and value)."""

    agent: str
    frame: int
    time_s: float
    lidar_ids: list[str] = field(default_factory=list)
    lidar_instance: list[int] = field(default_factory=list)
    lidar_class: list[int] = field(default_factory=list)
    lidar_center: list[np.ndarray] = field(default_factory=list)
    lidar_size: list[np.ndarray] = field(default_factory=list)
    lidar_rotation: list[np.ndarray] = field(default_factory=list)
    lidar_yaw: list[float] = field(default_factory=list)
    lidar_points: list[int] = field(default_factory=list)
    lidar_range: list[float] = field(default_factory=list)
    lidar_role: list[str] = field(default_factory=list)
    lidar_static: list[bool] = field(default_factory=list)
    lidar_wave_occlusion: list[float] = field(default_factory=list)
    cam_ids: list[str] = field(default_factory=list)
    cam_camera: list[str] = field(default_factory=list)
    cam_box: list[np.ndarray] = field(default_factory=list)
    cam_truncation: list[float] = field(default_factory=list)
    cam_visible: list[int] = field(default_factory=list)
    cam_box_pixels: list[int] = field(default_factory=list)
    cam_occlusion: list[float] = field(default_factory=list)
    cam_role: list[str] = field(default_factory=list)
    cam_static: list[bool] = field(default_factory=list)
    cam_wave_occlusion: list[float] = field(default_factory=list)

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def columns(self) -> dict[str, Any]:
        """Numpy columns, the ``Recording.annotations`` groups: ``{"lidar", "bev", "camera"}``, each a dict of
        columns in the order the vessels are in the world state (``n3d`` rows for ``lidar``/``bev``, ``n2d`` for
        ``camera``, which goes vessel by vessel, camera by camera; ``role`` and ``static`` go to the Parquet tables
        only: the MCAP's ``AgentAnnotations`` has no such fields and ``Recording.annotations`` ignores them):

        - ``lidar`` (the agent's LiDAR frame, metres, radians): ``target_id``, ``role`` lists of str;
          ``instance_id``, ``semantic_class``, ``lidar_points`` ``(n3d,)`` uint32; ``center`` ``(n3d, 3)``,
          ``size`` ``(n3d, 3)`` length, beam, height, ``rotation`` ``(n3d, 4)`` quaternion x, y, z, w, ``yaw``,
          ``range_m`` (``|center|``), ``wave_occlusion`` ``(n3d,)`` float64; ``static`` ``(n3d,)`` bool;
        - ``bev``: ``target_id``; ``x``, ``y``, ``length``, ``width``, ``yaw`` ``(n3d,)`` float64 (the 3D box's
          footprint in the LiDAR frame's xy plane: ``lidar``'s ``center[:, :2]``, ``size[:, :2]`` and ``yaw``);
        - ``camera`` (pixels, origin top-left, clipped to the image): ``target_id``, ``camera``, ``role`` lists of
          str; ``x_min``, ``y_min``, ``x_max``, ``y_max``, ``truncation``, ``occlusion``, ``wave_occlusion``
          ``(n2d,)`` float64; ``visible_pixels``, ``box_pixels`` (the pixels the box touches, :mod:`mmusv.annotate`)
          ``(n2d,)`` uint32; ``static`` ``(n2d,)`` bool.
        """
        n = len(self.lidar_ids)
        centre = np.array(self.lidar_center, dtype=np.float64).reshape(n, 3)
        size = np.array(self.lidar_size, dtype=np.float64).reshape(n, 3)
        lidar = {
            "target_id": list(self.lidar_ids),
            "instance_id": np.array(self.lidar_instance, dtype=np.uint32),
            "semantic_class": np.array(self.lidar_class, dtype=np.uint32),
            "center": centre,
            "size": size,
            "rotation": np.array(self.lidar_rotation, dtype=np.float64).reshape(n, 4),
            "yaw": np.array(self.lidar_yaw, dtype=np.float64),
            "lidar_points": np.array(self.lidar_points, dtype=np.uint32),
            "range_m": np.array(self.lidar_range, dtype=np.float64),
            "role": list(self.lidar_role),
            "static": np.array(self.lidar_static, dtype=bool),
            "wave_occlusion": np.array(self.lidar_wave_occlusion, dtype=np.float64),
        }
        bev = {
            "target_id": list(self.lidar_ids),
            "x": centre[:, 0].copy(),
            "y": centre[:, 1].copy(),
            "length": size[:, 0].copy(),
            "width": size[:, 1].copy(),
            "yaw": np.array(self.lidar_yaw, dtype=np.float64),
        }
        m = len(self.cam_ids)
        box = np.array(self.cam_box, dtype=np.float64).reshape(m, 4)
        camera = {
            "target_id": list(self.cam_ids),
            "camera": list(self.cam_camera),
            "x_min": box[:, 0].copy(),
            "y_min": box[:, 1].copy(),
            "x_max": box[:, 2].copy(),
            "y_max": box[:, 3].copy(),
            "truncation": np.array(self.cam_truncation, dtype=np.float64),
            "visible_pixels": np.array(self.cam_visible, dtype=np.uint32),
            "box_pixels": np.array(self.cam_box_pixels, dtype=np.uint32),
            "occlusion": np.array(self.cam_occlusion, dtype=np.float64),
            "role": list(self.cam_role),
            "static": np.array(self.cam_static, dtype=bool),
            "wave_occlusion": np.array(self.cam_wave_occlusion, dtype=np.float64),
        }
        return {"lidar": lidar, "bev": bev, "camera": camera}
