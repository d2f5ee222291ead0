"""``mmusv preview REC.mcap --frame K``: one picture of a recorded frame, in the spirit of Fig. 5 of the paper.

Panels for one agent: the surround RGB cameras (top row), their depth and semantic images, the radar PPI, the
top-view semantic rendering, and a bird's-eye view of the LiDAR points (x forward up, y left to the left) with
the agent's BEV boxes. Everything is read back from the recording (``mcap`` + ``mcap-protobuf-support``), so the
picture shows what a user of the file gets.
"""

from __future__ import annotations

import io
import math
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from mmusv.classes import palette_array
from mmusv.errors import ConfigError, IoError

__all__ = ["decode_image", "decode_point_cloud", "frame_messages", "write_preview"]

_NUMPY = {1: np.uint8, 2: np.int8, 3: np.uint16, 4: np.int16, 5: np.uint32, 6: np.int32, 7: np.float32, 8: np.float64}


def decode_image(msg: Any) -> np.ndarray:
    """A ``foxglove.RawImage`` or ``foxglove.CompressedImage`` (PNG) as a numpy array (``(H, W)`` or ``(H, W, 3)``)."""
    if hasattr(msg, "format"):
        return np.asarray(Image.open(io.BytesIO(msg.data)))
    enc = msg.encoding
    dtype = {"rgb8": np.uint8, "mono8": np.uint8, "8UC1": np.uint8, "16UC1": np.uint16, "mono16": np.uint16, "32FC1": np.float32, "32SC1": np.int32}.get(enc)
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


def frame_messages(path: str | Path, frame: int) -> dict[str, Any]:
    """Every decoded message of acquisition index ``frame``, by topic (log time = frame / f)."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    p = Path(path)
    if not p.is_file():
        raise IoError(f"recording {p} does not exist")
    out: dict[str, Any] = {}
    with p.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        freq = float(meta.get("run", {}).get("frequency_hz", "0") or 0)
        if freq <= 0:
            raise IoError(f"{p} has no run metadata (frequency_hz); was it written by mmusv run?")
        t = round(frame / freq * 1e9)
        for _schema, channel, message, decoded in reader.iter_decoded_messages(start_time=t, end_time=t + 1):
            out[channel.topic] = decoded
            del message
    if not out:
        raise ConfigError(f"frame {frame} is not in {p}")
    return out


def _colour_depth(d: np.ndarray, max_m: float = 300.0) -> np.ndarray:
    import matplotlib

    finite = np.isfinite(d)
    x = np.clip(np.where(finite, d, max_m) / max_m, 0, 1) ** 0.5
    rgb = (matplotlib.colormaps["turbo"](x)[..., :3] * 255).astype(np.uint8)
    rgb[~finite] = 0
    return rgb


def _panel(img: np.ndarray, size: tuple[int, int]) -> Image.Image:
    return Image.fromarray(img).convert("RGB").resize(size, Image.Resampling.NEAREST)


def _bev(points: dict[str, np.ndarray], boxes: Any, extent: float = 100.0, px: int = 400) -> np.ndarray:
    img = np.zeros((px, px, 3), dtype=np.uint8)
    m = 2 * extent / px
    if points:
        x, y = points["x"], points["y"]
        u = (px / 2 - y / m).astype(int)
        v = (px / 2 - x / m).astype(int)
        ok = (u >= 0) & (u < px) & (v >= 0) & (v < px)
        cls = points.get("class", np.zeros_like(x, dtype=np.uint16)).astype(int)
        img[v[ok], u[ok]] = palette_array()[np.clip(cls[ok], 0, 255)]
    from PIL import ImageDraw

    pil = Image.fromarray(img)
    draw = ImageDraw.Draw(pil)
    for b in boxes:
        c, s = math.cos(b.yaw), math.sin(b.yaw)
        pts = []
        for dx, dy in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            bx = b.x + c * dx * b.length / 2 - s * dy * b.width / 2
            by = b.y + s * dx * b.length / 2 + c * dy * b.width / 2
            pts.append((px / 2 - by / m, px / 2 - bx / m))
        draw.polygon(pts, outline=(255, 60, 60))
    return np.asarray(pil)


def write_preview(path: str | Path, *, frame: int = 0, agent: str | None = None, output: str | Path | None = None) -> Path:
    """Writes the preview PNG of ``frame`` for ``agent`` (default: the first agent); returns its path."""
    msgs = frame_messages(path, frame)
    agents = sorted({t.split("/")[1] for t in msgs if t.count("/") >= 2 and not t.startswith("/world")})
    if not agents:
        raise ConfigError(f"frame {frame} of {path} has no agent topics")
    a = agent or agents[0]
    if a not in agents:
        raise ConfigError(f"no agent {a!r} in {path}; agents: {', '.join(agents)}")
    cams = sorted({t.split("/")[3] for t in msgs if t.startswith(f"/{a}/camera/")})
    tile = (320, 240)
    rows: list[list[Image.Image]] = [[], [], []]
    for c in cams:
        for r, kind in enumerate(("rgb", "depth", "semantic")):
            m = msgs.get(f"/{a}/camera/{c}/{kind}")
            if m is None:
                rows[r].append(Image.new("RGB", tile))
                continue
            img = decode_image(m)
            if kind == "depth":
                img = _colour_depth(img.astype(np.float32))
            elif kind == "semantic":
                img = palette_array()[np.clip(img.astype(int), 0, 255)]
            rows[r].append(_panel(img, tile))
    extra: list[Image.Image] = []
    sq = (tile[1], tile[1])
    ppi = msgs.get(f"/{a}/radar/ppi")
    extra.append(_panel(decode_image(ppi), sq) if ppi is not None else Image.new("RGB", sq))
    tv = msgs.get(f"/{a}/top_view/semantic")
    if tv is not None:
        extra.append(_panel(palette_array()[np.clip(decode_image(tv).astype(int), 0, 255)], sq))
    lidar = msgs.get(f"/{a}/lidar")
    ann = msgs.get(f"/{a}/annotations")
    pts = decode_point_cloud(lidar) if lidar is not None else {}
    extra.append(_panel(_bev(pts, list(ann.boxes_bev) if ann is not None else []), sq))
    width = max(tile[0] * max(len(cams), 1), sq[0] * len(extra))
    canvas = Image.new("RGB", (width, tile[1] * 3 + sq[1]), (20, 20, 20))
    for r, row in enumerate(rows):
        for i, im in enumerate(row):
            canvas.paste(im, (i * tile[0], r * tile[1]))
    for i, im in enumerate(extra):
        canvas.paste(im, (i * sq[0], 3 * tile[1]))
    out = Path(output) if output is not None else Path(path).with_name(f"{Path(path).stem}_frame{frame:06d}_{a}.png")
    canvas.save(out)
    return out
