"""The ROS 2 messages of the ``--to ros2`` export built from numpy values: headers, poses, transforms, point
clouds and images of a rosbags typestore (:func:`mmusv.export.ros2_types.typestore`). The writer is
:mod:`mmusv.export.ros2`."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["Msgs", "stamp"]


def stamp(ts: Any, t_ns: int) -> Any:
    return ts.types["builtin_interfaces/msg/Time"](sec=int(t_ns // 1_000_000_000), nanosec=int(t_ns % 1_000_000_000))


class Msgs:
    """Builds messages of the typestore ``ts`` from numpy values."""

    def __init__(self, ts: Any) -> None:
        self.ts = ts
        self.T = ts.types

    def header(self, t_ns: int, frame_id: str) -> Any:
        return self.T["std_msgs/msg/Header"](stamp=stamp(self.ts, t_ns), frame_id=frame_id)

    def vector3(self, v: Any) -> Any:
        return self.T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quaternion(self, q: Any) -> Any:
        return self.T["geometry_msgs/msg/Quaternion"](x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))

    def pose(self, m: np.ndarray) -> Any:
        t = m[:3, 3]
        return self.T["geometry_msgs/msg/Pose"](
            position=self.T["geometry_msgs/msg/Point"](x=float(t[0]), y=float(t[1]), z=float(t[2])),
            orientation=self.quaternion(Rotation.from_matrix(m[:3, :3]).as_quat()),
        )

    def transform(self, t_ns: int, *, parent: str, child: str, m: np.ndarray) -> Any:
        tr = self.T["geometry_msgs/msg/Transform"](
            translation=self.vector3(m[:3, 3]), rotation=self.quaternion(Rotation.from_matrix(m[:3, :3]).as_quat())
        )
        return self.T["geometry_msgs/msg/TransformStamped"](
            header=self.header(t_ns, parent), child_frame_id=child, transform=tr
        )

    def tf(self, transforms: list[Any]) -> Any:
        return self.T["tf2_msgs/msg/TFMessage"](transforms=transforms)

    def point_cloud(self, t_ns: int, frame_id: str, cloud: dict[str, np.ndarray], fields: list[str]) -> Any:
        """A dense ``PointCloud2`` (height 1, little-endian, fields packed in the order given)."""
        pf = self.T["sensor_msgs/msg/PointField"]
        codes = {
            np.dtype("int8"): pf.INT8,
            np.dtype("uint8"): pf.UINT8,
            np.dtype("int16"): pf.INT16,
            np.dtype("uint16"): pf.UINT16,
            np.dtype("int32"): pf.INT32,
            np.dtype("uint32"): pf.UINT32,
            np.dtype("float32"): pf.FLOAT32,
            np.dtype("float64"): pf.FLOAT64,
        }
        names = [f for f in fields if f in cloud]
        n = len(cloud[names[0]]) if names else 0
        dtype = np.dtype([(f, cloud[f].dtype.newbyteorder("<")) for f in names])
        packed = np.empty(n, dtype=dtype)
        for f in names:
            packed[f] = cloud[f]
        out_fields = [
            pf(name=f, offset=int(dtype.fields[f][1]), datatype=int(codes[np.dtype(cloud[f].dtype.name)]), count=1)
            for f in names
            if dtype.fields is not None
        ]
        return self.T["sensor_msgs/msg/PointCloud2"](
            header=self.header(t_ns, frame_id),
            height=1,
            width=n,
            fields=out_fields,
            is_bigendian=False,
            point_step=dtype.itemsize,
            row_step=dtype.itemsize * n,
            data=np.frombuffer(packed.tobytes(), dtype=np.uint8),
            is_dense=True,
        )

    def image(self, t_ns: int, frame_id: str, *, img: np.ndarray, encoding: str) -> Any:
        """A ``sensor_msgs/Image`` of ``img`` (``(H, W)`` or ``(H, W, 3)``, little-endian, rows top to bottom)."""
        a = np.ascontiguousarray(img)
        a = a.astype(a.dtype.newbyteorder("<"), copy=False)
        h, w = a.shape[:2]
        return self.T["sensor_msgs/msg/Image"](
            header=self.header(t_ns, frame_id),
            height=h,
            width=w,
            encoding=encoding,
            is_bigendian=0,
            step=int(a.strides[0]),
            data=np.frombuffer(a.tobytes(), dtype=np.uint8),
        )

    def compressed(self, t_ns: int, frame_id: str, *, data: bytes, fmt: str) -> Any:
        return self.T["sensor_msgs/msg/CompressedImage"](
            header=self.header(t_ns, frame_id), format=fmt, data=np.frombuffer(data, dtype=np.uint8)
        )
