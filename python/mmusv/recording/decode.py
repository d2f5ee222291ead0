"""Messages of a recording as numpy arrays: Foxglove images (``RawImage``, PNG ``CompressedImage``) and point
clouds (``PointCloud``, packed fields), and mmusv's ``/world/state`` (:class:`WorldFrame`: per-vessel poses,
velocities and boxes in the world frame, metres, radians). Used by every reader of recordings (preview, export,
studies)."""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Any

import numpy as np
from PIL import Image

from mmusv.errors import InputError, IoError

__all__ = ["WorldFrame", "decode_image", "decode_point_cloud"]

_RAW = {
    "rgb8": np.uint8,
    "mono8": np.uint8,
    "8UC1": np.uint8,
    "16UC1": np.uint16,
    "mono16": np.uint16,
    "32FC1": np.float32,
    "32SC1": np.int32,
}
_NUMPY = {1: np.uint8, 2: np.int8, 3: np.uint16, 4: np.int16, 5: np.uint32, 6: np.int32, 7: np.float32, 8: np.float64}


def _need(msg: Any, fields: tuple[str, ...], what: str, caller: str) -> None:
    """``msg`` must have ``fields`` (a decoded message of kind ``what``), else an :class:`InputError` naming
    ``caller`` and the message given."""
    missing = [f for f in fields if not hasattr(msg, f)]
    if missing:
        kind = getattr(getattr(msg, "DESCRIPTOR", None), "full_name", None) or type(msg).__name__
        raise InputError(
            f"{caller} takes a decoded {what} message (from mmusv.recording.read_messages / frame_messages), got "
            f"{kind} without {', '.join(missing)}"
        )


def decode_image(msg: Any) -> np.ndarray:
    """A ``foxglove.RawImage`` or ``foxglove.CompressedImage`` (PNG) as a new, writable numpy array, row 0 at the
    top. Another message is an :class:`~mmusv.errors.InputError`; image bytes that do not decode an
    :class:`~mmusv.errors.IoError`.

    What an mmusv recording's images decode to (``docs/recording.md``):

    - ``.../rgb`` (PNG) and ``.../radar/ppi`` (PNG): ``(H, W, 3)`` uint8 sRGB;
    - ``.../semantic`` (PNG): ``(H, W)`` uint16 class ids (:mod:`mmusv.classes`, 0 = sky);
    - ``.../instance`` (PNG): ``(H, W)`` uint16 scene instance ids, 65535 = sky (a capture's ``-1``);
    - ``.../depth`` (``RawImage`` ``32FC1``): ``(H, W)`` float32 metres along the optical axis, ``+inf`` = sky.

    A ``RawImage`` decodes by its encoding: ``rgb8`` ``(H, W, 3)`` uint8; ``mono8`` / ``8UC1`` ``(H, W)`` uint8;
    ``mono16`` / ``16UC1`` ``(H, W)`` uint16; ``32FC1`` ``(H, W)`` float32; ``32SC1`` ``(H, W)`` int32."""
    if hasattr(msg, "format"):
        _need(msg, ("data",), "foxglove.CompressedImage", "decode_image")
        try:
            return np.array(Image.open(io.BytesIO(msg.data)))
        except (OSError, ValueError, SyntaxError) as exc:
            raise IoError(f"a compressed image does not decode ({type(exc).__name__}: {exc})") from None
    _need(msg, ("encoding", "width", "height", "step", "data"), "foxglove.RawImage or CompressedImage", "decode_image")
    enc = msg.encoding
    dtype = _RAW.get(enc)
    if dtype is None:
        raise IoError(f"unsupported image encoding {enc!r}; encodings: {', '.join(_RAW)}")
    ch = 3 if enc == "rgb8" else 1
    size = np.dtype(dtype).itemsize
    w, h, step = int(msg.width), int(msg.height), int(msg.step)
    if step < w * ch * size or step % size or len(msg.data) != step * h:
        raise IoError(
            f"a {enc} image of {w} x {h} (step {step}) does not match its {len(msg.data)} bytes (needs step >= "
            f"{w * ch * size}, a multiple of {size}, and step x height bytes)"
        )
    rows = np.frombuffer(msg.data, dtype=np.dtype(dtype).newbyteorder("<")).reshape(h, step // size)
    img: np.ndarray = rows[:, : w * ch].copy()  # a writable array of its own, not a view of the message's bytes
    return img.reshape(h, w, 3) if ch == 3 else img


def decode_point_cloud(msg: Any) -> dict[str, np.ndarray]:
    """A ``foxglove.PointCloud`` as ``{field name: (N,) array}`` (new, writable arrays, in the message's field
    order, each of its field's type: FLOAT32 float32, UINT16 uint16, INT32 int32, ...) using the packed field
    offsets. Another message is an :class:`~mmusv.errors.InputError`; bytes that are not whole points, or fields
    that do not fit in a point, an :class:`~mmusv.errors.IoError`.

    An mmusv recording's ``/{agent}/lidar`` gives ``x``, ``y``, ``z`` (float32 metres, the LiDAR frame
    ``{agent}/lidar``), ``intensity`` (float32, 0..1), ``ring`` (uint16), ``azimuth`` (float32 radians, 0..2π,
    counter-clockwise from x), ``class`` (uint16, :mod:`mmusv.classes`), ``instance`` (int32);
    ``/{agent}/radar/returns`` gives ``x``, ``y``, ``z``, ``range`` (float32 metres, the radar frame),
    ``azimuth``, ``elevation`` (float32 radians), ``intensity`` (float32, linear) and ``instance`` (int32, -1:
    clutter). See ``docs/recording.md``."""
    _need(msg, ("point_stride", "data", "fields"), "foxglove.PointCloud", "decode_point_cloud")
    stride = int(msg.point_stride)
    raw = np.frombuffer(msg.data, dtype=np.uint8)
    if (stride == 0 and raw.size) or (stride and raw.size % stride):
        raise IoError(
            f"a point cloud of {raw.size} bytes is not a whole number of points of {stride} bytes (its stride)"
        )
    n = raw.size // stride if stride else 0
    rows = raw.reshape(n, stride)
    out: dict[str, np.ndarray] = {}
    for f in msg.fields:
        kind = _NUMPY.get(int(f.type))
        if kind is None:
            raise IoError(
                f"point cloud field {f.name!r} has type {int(f.type)}; types: {', '.join(map(str, _NUMPY))} "
                "(UINT8 .. FLOAT64)"
            )
        dt = np.dtype(kind).newbyteorder("<")
        if f.offset + dt.itemsize > stride:
            raise IoError(
                f"point cloud field {f.name!r} ({dt.itemsize} bytes at offset {f.offset}) does not fit in its "
                f"{stride}-byte points"
            )
        out[f.name] = rows[:, f.offset : f.offset + dt.itemsize].copy().view(dt).reshape(n)
    return out


@dataclass(frozen=True)
class WorldFrame:
    """One ``/world/state``: per vessel (V of them: scenario vessels in file order, then moored ships) its id,
    asset, role, class and instance, in the world frame (x east, y north, z up).

    Attributes:
        frame: the acquisition index; ``time_s``: its time ``k / f``, seconds.
        ids, assets, roles: ``V`` strings each (roles ``usv``, ``target``, ``moored``).
        classes: ``(V,)`` int64 semantic class (:mod:`mmusv.classes`); ``instance_ids``: ``(V,)`` int64 scene
            instance (what the LiDAR's ``instance`` field and the cameras' instance images hold).
        poses: ``(V, 6)`` float64 ``[x, y, z, roll, pitch, yaw]``, metres and radians (yaw counter-clockwise from
            east).
        velocities: ``(V, 3)`` float64, m/s, world frame.
        box_centers: ``(V, 3)`` float64, metres, world frame; ``box_sizes``: ``(V, 3)`` float64 length, beam,
            height, metres.
    """

    frame: int
    time_s: float
    ids: list[str]
    assets: list[str]
    roles: list[str]
    classes: np.ndarray
    instance_ids: np.ndarray
    poses: np.ndarray
    velocities: np.ndarray
    box_centers: np.ndarray
    box_sizes: np.ndarray

    @staticmethod
    def from_message(msg: Any) -> WorldFrame:
        """From a decoded ``mmusv.WorldState`` (another message is an :class:`~mmusv.errors.InputError`)."""
        _need(msg, ("vessels", "frame", "time_s"), "mmusv.WorldState", "WorldFrame.from_message")
        vs = list(msg.vessels)

        def rows(attr: str, k: int) -> np.ndarray:
            return np.array([list(getattr(v, attr)) for v in vs], dtype=np.float64).reshape(len(vs), k)

        return WorldFrame(
            frame=int(msg.frame),
            time_s=float(msg.time_s),
            ids=[v.id for v in vs],
            assets=[v.asset for v in vs],
            roles=[v.role for v in vs],
            classes=np.array([v.semantic_class for v in vs], dtype=np.int64),
            instance_ids=np.array([v.instance_id for v in vs], dtype=np.int64),
            poses=rows("pose", 6),
            velocities=rows("velocity", 3),
            box_centers=rows("box_center", 3),
            box_sizes=rows("box_size", 3),
        )
