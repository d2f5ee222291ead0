"""mmusv.recording.decode: Foxglove image and point-cloud messages to numpy, checked against arrays packed by hand."""

from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np
import pytest
from mmusv.errors import IoError
from mmusv.recording.decode import decode_image, decode_point_cloud
from PIL import Image


def test_raw_image_rows_with_padding_and_each_encoding() -> None:
    rng = np.random.default_rng(3)
    for enc, dtype, ch in [("rgb8", np.uint8, 3), ("mono16", np.uint16, 1), ("32FC1", np.float32, 1)]:
        img = rng.integers(0, 200, size=(5, 7, ch)).astype(dtype).reshape((5, 7, 3) if ch == 3 else (5, 7))
        row = img.reshape(5, -1).astype(np.dtype(dtype).newbyteorder("<"))
        pad = np.zeros((5, 3), dtype=row.dtype)  # three padding elements per row: step > width * channels
        data = np.concatenate([row, pad], axis=1).tobytes()
        msg = SimpleNamespace(encoding=enc, width=7, height=5, step=(7 * ch + 3) * row.itemsize, data=data)
        np.testing.assert_array_equal(decode_image(msg), img)


def test_png_image_and_unknown_encoding() -> None:
    img = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    np.testing.assert_array_equal(decode_image(SimpleNamespace(format="png", data=buf.getvalue())), img)
    with pytest.raises(IoError, match="unsupported image encoding 'bgr8'"):
        decode_image(SimpleNamespace(encoding="bgr8", width=1, height=1, step=3, data=b"\0\0\0"))


def test_point_cloud_fields_at_their_offsets() -> None:
    # x float32 at 0, intensity uint16 at 4, ring uint8 at 6, one padding byte: stride 8.
    xs = np.array([1.5, -2.25, 3.0], dtype="<f4")
    inten = np.array([7, 65535, 0], dtype="<u2")
    ring = np.array([0, 63, 9], dtype=np.uint8)
    raw = bytearray(8 * 3)
    for i in range(3):
        raw[8 * i : 8 * i + 4] = xs[i].tobytes()
        raw[8 * i + 4 : 8 * i + 6] = inten[i].tobytes()
        raw[8 * i + 6] = int(ring[i])
    fields = [
        SimpleNamespace(name="x", offset=0, type=7),
        SimpleNamespace(name="intensity", offset=4, type=3),
        SimpleNamespace(name="ring", offset=6, type=1),
    ]
    out = decode_point_cloud(SimpleNamespace(point_stride=8, data=bytes(raw), fields=fields))
    np.testing.assert_array_equal(out["x"], xs)
    np.testing.assert_array_equal(out["intensity"], inten)
    np.testing.assert_array_equal(out["ring"], ring)
    empty = decode_point_cloud(SimpleNamespace(point_stride=8, data=b"", fields=fields))
    assert {k: v.shape for k, v in empty.items()} == {"x": (0,), "intensity": (0,), "ring": (0,)}
