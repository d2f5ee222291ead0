"""``mmusv preview REC.mcap --frame K``: one picture of a recorded frame, in the spirit of Fig. 5 of the paper.

One sheet per agent and frame, every panel titled ``<USV> · <sensor> · <modality>``: the surround cameras (RGB with
the annotated 2D boxes, depth, semantic; one row each), then the radar PPI with range rings labelled in metres,
the top view (RGB, semantic) and a bird's-eye view of the LiDAR points (x forward up, y left to the left) with the
footprints of the annotated 3D boxes. Only panels the recording holds are drawn, so none is empty. Everything is
read back through the one reader (:mod:`mmusv.recording.info`, :mod:`mmusv.recording.messages`), so the picture
shows what a user of the file gets.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from mmusv.classes import palette_array
from mmusv.errors import ConfigError, IoError
from mmusv.recording import topics
from mmusv.recording.decode import decode_image, decode_point_cloud
from mmusv.recording.info import AgentInfo, read_info, recording_name
from mmusv.recording.messages import frame_messages
from mmusv.text import given

__all__ = ["BOX_COLOUR", "Panel", "compose_preview", "write_preview"]

BOX_COLOUR = (255, 0, 200)
"""RGB of the annotation boxes (2D on the camera images, 3D footprints in the LiDAR BEV)."""
_TITLE_H = 22
_BG = (24, 24, 28)
_TEXT = (235, 235, 235)
_RING = (120, 140, 120)
_TILE = (320, 240)
_DEPTH_MAX_M = 300.0
_BEV_HALF_M = 100.0


@dataclass(frozen=True)
class Panel:
    """One titled panel of the sheet: ``box`` = ``(left, top, right, bottom)`` pixels of the image area (the title
    strip is the ``_TITLE_H`` rows above it); ``scale`` = panel pixels per source pixel (cameras) or per metre (PPI,
    BEV)."""

    title: str
    box: tuple[int, int, int, int]
    scale: float


def _font(size: int = 14) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


def _colour_depth(d: np.ndarray, max_m: float = _DEPTH_MAX_M) -> np.ndarray:
    """``(H, W, 3)`` uint8 turbo rendering of a depth image in metres (sqrt scale to ``max_m``; sky black)."""
    import matplotlib

    finite = np.isfinite(d)
    x = np.clip(np.where(finite, d, max_m) / max_m, 0, 1) ** 0.5
    rgb = (matplotlib.colormaps["turbo"](x)[..., :3] * 255).astype(np.uint8)
    rgb[~finite] = 0
    return rgb


def _semantic(img: np.ndarray) -> np.ndarray:
    return np.asarray(palette_array()[np.clip(img.astype(int), 0, 255)], dtype=np.uint8)


def _fit(img: np.ndarray, size: tuple[int, int]) -> Image.Image:
    return Image.fromarray(img).convert("RGB").resize(size, Image.Resampling.BILINEAR)


def _nice_step(span_m: float) -> float:
    """A 1-2-5 step giving about four rings over ``span_m``."""
    raw = span_m / 4.0
    base = 10.0 ** math.floor(math.log10(raw))
    return next(base * k for k in (1.0, 2.0, 5.0, 10.0) if base * k >= raw)


def _rings(draw: ImageDraw.ImageDraw, *, centre: tuple[float, float], px_per_m: float, max_m: float) -> None:
    """Range rings every 1-2-5 step up to ``max_m``, each labelled with its range in metres on a black backing (a
    return under a label made a "1000 m" read "4000 m")."""
    step = _nice_step(max_m)
    font = _font(11)
    r_m = step
    while r_m <= max_m + 1e-9:
        r = r_m * px_per_m
        cx, cy = centre
        draw.ellipse((cx - r, cy - r, cx + r, cy + r), outline=_RING)
        label = f"{r_m:g} m"
        at = (cx + r * 0.7071 + 2, cy - r * 0.7071 - 12)
        x0, y0, x1, y1 = draw.textbbox(at, label, font=font)
        draw.rectangle((x0 - 1, y0 - 1, x1 + 1, y1 + 1), fill=(0, 0, 0))
        draw.text(at, label, fill=_RING, font=font)
        r_m += step


def _tile(img: np.ndarray) -> tuple[int, int]:
    """A camera panel's size: :data:`_TILE`'s width, the image's aspect ratio kept (a 16:9 camera resized to the
    4:3 tile came out a third taller than it is)."""
    h, w = img.shape[:2]
    return _TILE[0], max(round(_TILE[0] * h / w), 1)


def _camera_panel(img: np.ndarray, boxes: list[Any], size: tuple[int, int]) -> tuple[Image.Image, float]:
    """The image fitted to ``size`` with ``boxes`` (``mmusv.Box2D``, source pixels) drawn; returns the scale."""
    h, w = img.shape[:2]
    pil = _fit(img, size)
    sx, sy = size[0] / w, size[1] / h
    draw = ImageDraw.Draw(pil)
    font = _font(11)
    for b in boxes:
        x0, y0, x1, y1 = b.x_min * sx, b.y_min * sy, b.x_max * sx, b.y_max * sy
        draw.rectangle((x0, y0, x1, y1), outline=BOX_COLOUR, width=2)
        draw.text((x0, max(0.0, y0 - 13)), b.target_id, fill=BOX_COLOUR, font=font)
    return pil, sx


def _bev_panel(points: dict[str, np.ndarray], boxes: list[Any], px: int, half_m: float = _BEV_HALF_M) -> Image.Image:
    """LiDAR points (LiDAR frame) seen from above, x forward up, y left to the left, coloured by class, with the
    footprints of the 3D boxes (``mmusv.Box3D``: centre, size, yaw) and labelled range rings."""
    img = np.zeros((px, px, 3), dtype=np.uint8)
    img[:] = (10, 12, 16)
    m = 2 * half_m / px
    if points:
        x, y = points["x"], points["y"]
        u = np.round(px / 2 - y / m).astype(int)
        v = np.round(px / 2 - x / m).astype(int)
        ok = (u >= 0) & (u < px - 1) & (v >= 0) & (v < px - 1)
        cls = points.get("class", np.zeros_like(x, dtype=np.uint16)).astype(int)
        col = palette_array()[np.clip(cls[ok], 0, 255)]
        for du in (0, 1):
            for dv in (0, 1):
                img[v[ok] + dv, u[ok] + du] = col
    pil = Image.fromarray(img)
    draw = ImageDraw.Draw(pil)
    _rings(draw, centre=(px / 2, px / 2), px_per_m=1 / m, max_m=half_m)
    draw.polygon([(px / 2, px / 2 - 7), (px / 2 - 5, px / 2 + 5), (px / 2 + 5, px / 2 + 5)], fill=(255, 255, 255))
    font = _font(11)
    for b in boxes:
        cx, cy, length, width = b.center[0], b.center[1], b.size[0], b.size[1]
        c, s = math.cos(b.yaw), math.sin(b.yaw)
        pts = []
        for dx, dy in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            bx = cx + c * dx * length / 2 - s * dy * width / 2
            by = cy + s * dx * length / 2 + c * dy * width / 2
            pts.append((px / 2 - by / m, px / 2 - bx / m))
        draw.polygon(pts, outline=BOX_COLOUR, width=2)
        draw.text((px / 2 - cy / m + 4, px / 2 - cx / m + 4), b.target_id, fill=BOX_COLOUR, font=font)
    return pil


def _pictured(topic: str, agent: str) -> bool:
    """Whether ``topic`` is one of ``agent``'s that the sheet draws a panel of."""
    if topics.agent_of(topic) != agent:
        return False
    kind = topic.rsplit("/", 1)[1]
    return (
        ("/camera/" in topic and kind in ("rgb", "depth", "semantic"))
        or (topic.startswith(topics.top_view(agent)) and kind in ("rgb", "semantic"))
        or topic in (topics.radar_ppi(agent), topics.lidar(agent))
    )


# Round half sides of the BEV square per decade: at most a quarter wider than what they hold (1-2-5 steps left a
# 200 m LiDAR's points in the middle fifth of a ±500 m square).
_BEV_STEPS = (1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0)


def _bev_half_extent(boxes: list[Any]) -> float:
    """Half side (m) of the BEV square: ``_BEV_HALF_M``, widened to the least round value (``_BEV_STEPS`` per
    decade) that holds every box centre with a tenth to spare, at most 1,000 m."""
    reach = max([max(abs(b.center[0]), abs(b.center[1])) * 1.1 for b in boxes] + [_BEV_HALF_M])
    base = 10.0 ** math.floor(math.log10(reach))
    return min(next(base * k for k in _BEV_STEPS if base * k >= reach), 1000.0)


def _ppi_panel(img: np.ndarray, px: int, metres_per_pixel: float | None) -> tuple[Image.Image, float]:
    """The colour-mapped PPI fitted to ``px`` square with labelled range rings centred on the ego (the centre of
    source pixel ``(h // 2, h // 2)``, half a source pixel off the middle of an even-sized PPI); returns panel pixels
    per metre."""
    h = img.shape[0]
    pil = _fit(img, (px, px))
    if metres_per_pixel is None:
        return pil, 0.0
    px_per_m = px / (h * metres_per_pixel)
    ego = (h // 2 + 0.5) * px / h
    _rings(ImageDraw.Draw(pil), centre=(ego, ego), px_per_m=px_per_m, max_m=h * metres_per_pixel / 2)
    return pil, px_per_m


def compose_preview(path: str | Path, *, frame: int = 0, agent: str | None = None) -> tuple[Image.Image, list[Panel]]:
    """The preview sheet of ``frame`` for ``agent`` (default: the first agent) and its panels, in drawing order."""
    info = read_info(path)
    msgs = frame_messages(path, frame)
    agents = {a.id: a for a in info.agents if any(topics.agent_of(t) == a.id for t in msgs)}
    if not agents:
        raise ConfigError(f"frame {frame} of {path} has no agent topics")
    drawn = [i for i in agents if any(_pictured(t, i) for t in msgs)]  # agents with something to draw
    a_id = (drawn or list(agents))[0] if agent is None else agent
    if a_id not in agents:
        raise ConfigError(f"no agent {a_id!r} in {path}; agents: {', '.join(agents)}")
    if a_id not in drawn:  # a rig without cameras, radar, top view and LiDAR: an empty sheet, no panel to name
        raise ConfigError(
            f"agent {a_id!r} recorded no picture in frame {frame} of {path} (no camera, radar PPI, top view or "
            "LiDAR)" + (f"; agents with pictures: {', '.join(drawn)}" if drawn else "")
        )
    a: AgentInfo = agents[a_id]
    ann = msgs.get(topics.agent_annotations(a_id))
    boxes2d = list(ann.boxes_camera) if ann is not None else []
    boxes3d = list(ann.boxes_lidar) if ann is not None else []

    rows: list[list[tuple[str, Image.Image, float]]] = []
    for kind in ("rgb", "depth", "semantic"):
        row = []
        for cam in sorted(a.cameras):
            m = msgs.get(topics.camera(a_id, cam, kind=kind))
            if m is None:
                continue
            img = decode_image(m)
            if kind == "rgb":
                pil, scale = _camera_panel(img, [b for b in boxes2d if b.camera == cam], _tile(img))
                row.append((f"{a_id} · {cam} camera · RGB + 2D boxes", pil, scale))
            elif kind == "depth":
                pil = _fit(_colour_depth(img.astype(np.float32)), _tile(img))
                row.append((f"{a_id} · {cam} camera · depth 0-{_DEPTH_MAX_M:g} m", pil, _TILE[0] / img.shape[1]))
            else:
                pil = _fit(_semantic(img), _tile(img))
                row.append((f"{a_id} · {cam} camera · semantic", pil, _TILE[0] / img.shape[1]))
        if row:
            rows.append(row)
    width = max([_TILE[0] * len(r) for r in rows] + [4 * _TILE[0]])

    bottom: list[tuple[str, Any]] = []
    if topics.radar_ppi(a_id) in msgs:
        bottom.append(("ppi", msgs[topics.radar_ppi(a_id)]))
    for kind in ("rgb", "semantic"):
        if topics.top_view(a_id, kind) in msgs:
            bottom.append((f"top_{kind}", msgs[topics.top_view(a_id, kind)]))
    if topics.lidar(a_id) in msgs:
        bottom.append(("bev", msgs[topics.lidar(a_id)]))
    sq = width // max(len(bottom), 1)
    last: list[tuple[str, Image.Image, float]] = []
    for kind, m in bottom:
        if kind == "ppi":
            orient = str((a.rig.get("radar") or {}).get("ppi_orientation", "")).replace("_", "-")
            pil, scale = _ppi_panel(decode_image(m), sq, a.ppi_metres_per_pixel)
            last.append((f"{a_id} · radar · PPI ({orient})", pil, scale))
        elif kind.startswith("top_"):
            img = decode_image(m)
            img = _semantic(img) if kind == "top_semantic" else img
            tv = a.rig.get("top_view") or {}
            # One scale both ways, the longer side the square's: a portrait or landscape top view resized to the
            # square made its hulls and distances wider than long (or the reverse).
            scale = sq / max(img.shape[0], img.shape[1])
            pil = _fit(img, (max(round(img.shape[1] * scale), 1), max(round(img.shape[0] * scale), 1)))
            orient = str(tv.get("orientation", "")).replace("_", "-")
            last.append((f"{a_id} · top view · {kind[4:]} ({orient})", pil, scale))
        else:
            half = _bev_half_extent(boxes3d)
            pil = _bev_panel(decode_point_cloud(m), boxes3d, sq, half)
            last.append((f"{a_id} · LiDAR · BEV ±{half:g} m + 3D boxes", pil, sq / (2 * half)))
    if last:
        rows.append(last)

    height = sum(_TITLE_H + max(p.height for _, p, _ in r) for r in rows)
    canvas = Image.new("RGB", (width, height), _BG)
    draw = ImageDraw.Draw(canvas)
    font = _font(13)
    panels: list[Panel] = []
    top = 0
    for r in rows:
        left = 0
        for title, pil, scale in r:
            draw.text((left + 6, top + 4), title, fill=_TEXT, font=font)
            canvas.paste(pil, (left, top + _TITLE_H))
            panels.append(
                Panel(
                    title=title, box=(left, top + _TITLE_H, left + pil.width, top + _TITLE_H + pil.height), scale=scale
                )
            )
            left += pil.width
        top += _TITLE_H + max(p.height for _, p, _ in r)
    return canvas, panels


def write_preview(
    path: str | Path, *, frame: int = 0, agent: str | None = None, output: str | Path | None = None
) -> Path:
    """Writes the preview PNG of ``frame`` for ``agent`` (default: the first agent); returns its path. ``output``:
    the picture's path (``.png``, ``.jpg`` or ``.jpeg``), or an existing folder to write it into under its
    default name; anything else is a :class:`~mmusv.errors.ConfigError`, checked before the frame is read."""
    target = Path(output) if output is not None else None
    said_folder = output is not None and str(output).endswith(("/", os.sep))  # `-o previews/`: a folder
    if target is not None and said_folder and not target.is_dir():
        if target.exists():
            raise ConfigError(f"{given('output', str(output))}: {target} is a file, not a folder")
        raise ConfigError(f"{given('output', str(output))}: the folder {target} does not exist; create it first")
    if target is not None and not target.is_dir() and target.suffix.lower() not in _PICTURE_SUFFIXES:
        raise ConfigError(
            f"{given('output', str(output))}: give a picture path ending in {', '.join(_PICTURE_SUFFIXES)}, or a folder"
        )
    canvas, panels = compose_preview(path, frame=frame, agent=agent)
    a = panels[0].title.split(" · ")[0]
    name = f"{recording_name(path)}_frame{frame:06d}_{a}.png"
    out = Path(path).with_name(name) if target is None else target / name if target.is_dir() else target
    import io

    from mmusv.jsonio import write_bytes_atomic

    data = io.BytesIO()
    canvas.save(data, format="PNG" if out.suffix.lower() == ".png" else "JPEG")
    try:  # through a temporary file and a rename: a full disk or a kill left a cut picture over the one before
        write_bytes_atomic(out, data.getvalue())
    except OSError as exc:
        raise IoError(f"cannot write the preview {out}: {exc.strerror or exc}") from None
    return out


_PICTURE_SUFFIXES = (".png", ".jpg", ".jpeg")
"""What :func:`write_preview` writes (Pillow picks the format from the suffix)."""
