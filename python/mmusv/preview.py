"""``mmusv preview REC.mcap --frame K``: one picture of a recorded frame, in the spirit of Fig. 5 of the paper.

Panels for one agent: the surround RGB cameras (top row), their depth and semantic images, the radar PPI, the
top-view semantic rendering, and a bird's-eye view of the LiDAR points (x forward up, y left to the left) with
the agent's BEV boxes. Everything is read back from the recording (``mcap`` + ``mcap-protobuf-support``), so the
picture shows what a user of the file gets.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from mmusv.classes import palette_array
from mmusv.errors import ConfigError
from mmusv.recording.reader import decode_image, decode_point_cloud, frame_messages
from mmusv.recording import topics

__all__ = ["write_preview"]

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
    cams = sorted({t.split("/")[3] for t in msgs if t.startswith(topics.camera(a, ""))})
    tile = (320, 240)
    rows: list[list[Image.Image]] = [[], [], []]
    for c in cams:
        for r, kind in enumerate(("rgb", "depth", "semantic")):
            m = msgs.get(topics.camera(a, c, kind))
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
    ppi = msgs.get(topics.radar_ppi(a))
    extra.append(_panel(decode_image(ppi), sq) if ppi is not None else Image.new("RGB", sq))
    tv = msgs.get(topics.top_view(a, "semantic"))
    if tv is not None:
        extra.append(_panel(palette_array()[np.clip(decode_image(tv).astype(int), 0, 255)], sq))
    lidar = msgs.get(topics.lidar(a))
    ann = msgs.get(topics.annotations(a))
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
