"""Foxglove messages of a recording as numpy arrays: images (``RawImage``, PNG ``CompressedImage``) and point
clouds (``PointCloud``, packed fields). Used by every reader of recordings (preview, export, studies)."""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from PIL import Image

from mmusv.errors import IoError

__all__ = ["decode_image", "decode_point_cloud"]

_NUMPY = {1: np.uint8, 2: np.int8, 3: np.uint16, 4: np.int16, 5: np.uint32, 6: np.int32, 7: np.float32, 8: np.float64}


def decode_image(msg: Any) -> np.ndarray:
    """A ``foxglove.RawImage`` or ``foxglove.CompressedImage`` (PNG) as a numpy array (``(H, W)`` or ``(H, W, 3)``)."""
    if hasattr(msg, "format"):
        return np.asarray(Image.open(io.BytesIO(msg.data)))
    enc = msg.encoding
    dtype = {
        "rgb8": np.uint8,
        "mono8": np.uint8,
        "8UC1": np.uint8,
        "16UC1": np.uint16,
        "mono16": np.uint16,
        "32FC1": np.float32,
        "32SC1": np.int32,
    }.get(enc)
    if dtype is None:
        raise IoError(f"unsupported image encoding {enc!r}")
    data = np.frombuffer(msg.data, dtype=np.dtype(dtype).newbyteorder("<"))
    ch = 3 if enc == "rgb8" else 1
    rows = data.reshape(msg.height, msg.step // np.dtype(dtype).itemsize)
    img = rows[:, : msg.width * ch]
    return img.reshape(msg.height, msg.width, 3) if ch == 3 else img


def decode_point_cloud(msg: Any) -> dict[str, np.ndarray]:
    """A ``foxglove.PointCloud`` as ``{field name: (N,) array}`` using the packed field offsets."""
    stride = msg.point_stride
    raw = np.frombuffer(msg.data, dtype=np.uint8)
    n = raw.size // stride if stride else 0
    rows = raw[: n * stride].reshape(n, stride)
    out: dict[str, np.ndarray] = {}
    for f in msg.fields:
        dt = np.dtype(_NUMPY[int(f.type)]).newbyteorder("<")
        out[f.name] = rows[:, f.offset : f.offset + dt.itemsize].copy().view(dt).reshape(n)
    return out
