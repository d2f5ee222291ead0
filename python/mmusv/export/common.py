"""What the dataset writers share: options, topic names, id scheme, image helpers and a byte-counting sink."""

from __future__ import annotations

import builtins
import io
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mmusv import arguments
from mmusv.errors import ConfigError

__all__ = [
    "BOXES",
    "BOX_DEFINITIONS",
    "CAV_ID_BASE",
    "DEFAULT_EXTRAS",
    "DEPTH_UNIT_M",
    "EXTRAS",
    "TARGETS",
    "Options",
    "Sink",
    "cav_id",
    "depth_metres",
    "depth_png",
    "depth_units_png",
    "dump_yaml",
    "mask_box",
    "parse_box",
    "parse_extras",
    "png_bytes",
    "rounded",
    "rounded_share",
    "top_view_entry",
    "top_view_png",
    "top_view_protocol",
    "wave_share",
]

TARGETS = ("opv2v", "kitti", "ros2", "coco", "yolo", "mastr", "semantickitti", "mot", "kitti_tracking")
EXTRAS = ("depth", "semantic", "instance", "radar", "top_view")
DEFAULT_EXTRAS = ("depth", "semantic", "radar", "top_view")
CAV_ID_BASE = 1000
DEPTH_UNIT_M = 0.01
"""The uint16 depth PNGs (:func:`depth_png`: KITTI's ``depth_2``, OPV2V's ``<ts>_depth_cm{i}.png``) are centimetres
along the optical axis: 0 = no hit (sky), 65535 = 655.35 m or farther. OPV2V's ``<ts>_depth{i}.png`` is HEAL's 8-bit
metres instead (:func:`mmusv.export.opv2v.heal_depth_png`)."""
BOXES = ("visible", "projected")
"""The 2D boxes the COCO, YOLO and MOT exports can write (``--box``; the first is the default)."""
BOX_DEFINITIONS = {
    "visible": "the tight box of the vessel's visible pixels: the instance image's pixels equal to its instance id "
    "(pixel edges: [x_min, y_min, x_max + 1, y_max + 1] of those pixels; COCO: pycocotools' toBbox of its "
    "segmentation)",
    "projected": "the recording's 2D box: the vessel's projected 3D box clipped to the image (amodal: it reaches down "
    "to the keel below the waterline and covers parts hidden by other objects)",
}
"""What each of :data:`BOXES` is, as the COCO ``info`` and the YOLO ``data.yaml`` say it."""


def cav_id(index: int) -> int:
    """Dataset id of the vessel in world-state row ``index`` (agents and targets alike): ``1000 + index``, so
    string order = numeric order = scenario order (for fewer than 9000 vessels)."""
    return CAV_ID_BASE + int(index)


def parse_extras(extras: Iterable[str] | str | None) -> tuple[str, ...]:
    """Validated extras (order of :data:`EXTRAS`) from a sequence or a comma-separated string."""
    if extras is None:
        return ()
    if isinstance(extras, str):
        items = [e.strip() for e in extras.split(",")]
    else:
        given = arguments.names(extras, name="extras", example="['depth', 'radar'] or 'depth,radar'")
        items = [e.strip() for e in given or ()]
    items = [e for e in items if e]
    bad = sorted(set(items) - set(EXTRAS))
    if bad:
        raise ConfigError(f"unknown extra(s) {', '.join(map(repr, bad))}; allowed: {', '.join(EXTRAS)}")
    return tuple(e for e in EXTRAS if e in items)


def parse_box(box: Any) -> str:
    """A validated ``box`` option (one of :data:`BOXES`); :class:`~mmusv.errors.ConfigError` in one line otherwise."""
    if isinstance(box, str) and box in BOXES:
        return box
    raise ConfigError(
        f"box = {arguments.shown(box)}: must be 'visible' (the tight box of the vessel's visible pixels, the default) "
        "or 'projected' (the recording's box: the vessel's projected 3D box clipped to the image)"
    )


@dataclass(frozen=True)
class Options:
    """Conversion options (see :func:`mmusv.export.convert`)."""

    to: str = "opv2v"
    eval_range_m: float = 200.0
    include_usvs: bool = False
    extras: tuple[str, ...] = DEFAULT_EXTRAS
    min_box_px: float = 0.0
    """COCO/YOLO/MOT: 2D boxes whose shorter side is under this many pixels are left out."""
    max_occlusion: float = 1.0
    """COCO/YOLO/MOT: 2D boxes whose occlusion (fraction hidden, 0..1) is above this are left out."""
    min_contrast: float | None = None
    """COCO/YOLO/MOT: 2D boxes whose apparent contrast in the RGB image
    (:func:`mmusv.export.contrast.apparent_contrast`, Weber, dimensionless) is under this are left out; ``None``: every
    box is kept."""
    box: str = "visible"
    """COCO/YOLO/MOT: the 2D box written (one of :data:`BOXES`): ``visible``, the tight box of the vessel's pixels in
    the instance image; ``projected``, the recording's box (the projected 3D box clipped to the image)."""
    agents: tuple[str, ...] | None = None
    """The agents (USV ids) to convert; ``None``: every agent the format uses."""
    frames: tuple[int, int | None] | None = None
    """The acquisition indices to convert, ``[start, stop)`` (``stop`` ``None``: to the end); ``None``: all."""
    kitti_class: str | None = None
    """KITTI tracking: the type written for every target (``Car``, which stock TrackEval and the KITTI devkit score);
    ``None``: each target's class name (``Vessel``, ``Usv``)."""
    oxts_origin: tuple[float, float] | None = None
    """KITTI tracking: the geodetic point (latitude, longitude, degrees) of the world origin in the ``oxts`` files;
    ``None``: :data:`mmusv.export.kitti_oxts.DEFAULT_ORIGIN`."""

    def wants_frame(self, index: int) -> bool:
        """Whether acquisition index ``index`` lies in :attr:`frames`."""
        if self.frames is None:
            return True
        start, stop = self.frames
        return index >= start and (stop is None or index < stop)


def naming(exc: OSError, path: Path) -> OSError:
    """``exc`` when it names a file, else the same error naming ``path``: the ``OSError`` of a write to an open file (a
    full disk) names none (only opening one does), so the command line said only "No space left on device"."""
    if exc.filename:
        return exc
    return OSError(exc.errno, exc.strerror or str(exc), str(path))


@dataclass
class Sink:
    """Writes files and counts them."""

    files: int = 0
    bytes: int = 0
    created: list[Path] = field(default_factory=list)

    def write(self, path: Path, data: builtins.bytes) -> None:
        """Writes ``data`` to ``path``. An ``OSError`` of the write itself (a full disk), which names no file (only
        opening one does), is raised again naming ``path``."""
        try:
            path.write_bytes(data)
        except OSError as exc:
            raise naming(exc, path) from exc
        self.files += 1
        self.bytes += len(data)

    def count(self, path: Path) -> None:
        """Counts a file another library wrote."""
        self.files += 1
        self.bytes += path.stat().st_size

    def mkdir(self, path: Path) -> Path:
        if not path.exists():
            path.mkdir(parents=True)
            self.created.append(path)
        return path


def png_bytes(msg: Any) -> bytes:
    """The PNG bytes of an image message: a ``foxglove.CompressedImage`` in PNG is copied as is, anything else
    is decoded and encoded (fixed settings, so the bytes are deterministic)."""
    if hasattr(msg, "format") and str(msg.format).lower() == "png":
        return bytes(msg.data)
    from mmusv.recording import decode_image

    return encode_png(decode_image(msg))


def encode_png(img: np.ndarray, *, compress_level: int = 6) -> bytes:
    """PNG of an ``(H, W)`` uint8/uint16 or ``(H, W, 3)`` uint8 image."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img)).save(buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


def depth_png(msg: Any) -> bytes:
    """A depth image message (metres, float; +inf or 0 = no hit) as a uint16 PNG in units of
    :data:`DEPTH_UNIT_M` (0 = no hit, 65535 = saturated): :func:`depth_metres` then :func:`depth_units_png`."""
    return depth_units_png(depth_metres(msg))


def depth_metres(msg: Any) -> np.ndarray:
    """A depth image message decoded: ``(H, W)`` float64 metres along the optical axis (+inf or 0 = no hit)."""
    from mmusv.recording import decode_image

    return np.asarray(decode_image(msg), dtype=np.float64)


def depth_units_png(d: np.ndarray) -> bytes:
    """``(H, W)`` depths in metres (+inf or 0 = no hit) as a uint16 PNG in units of :data:`DEPTH_UNIT_M` (0 = no
    hit, 65535 = saturated)."""
    units = np.where(np.isfinite(d) & (d > 0), np.clip(np.rint(d / DEPTH_UNIT_M), 1, 65535), 0).astype(np.uint16)
    return encode_png(units, compress_level=1)


_KITTI_PIXELS = (
    "pixel (u, v) (column, row from the top-left corner) has its centre (W/2 - u - 0.5) * metres_per_pixel to the "
    "left of the vessel and (H/2 - v - 0.5) * metres_per_pixel ahead of it, W x H the resolution, level (its roll and "
    "pitch left out), the vessel's origin (midship, at the waterline) at {body} (vessel body -> world) of (0, 0, 0): "
    "heading_up, ahead = along its heading (body x) and left = its port side; north_up, ahead = north (world y) and "
    "left = west (world -x)"
)
TOP_VIEW_PIXELS = {
    "carla": "pixel (u, v) (column, row from the top-left corner) has its centre (u + 0.5 - W/2) * metres_per_pixel "
    "to the right of the ego and (H/2 - v - 0.5) * metres_per_pixel ahead of it, W x H the resolution, level (the "
    "ego's roll and pitch left out), the ego at true_ego_pos (x, y): heading_up, ahead = along its yaw (its x) and "
    "right = its y (starboard); north_up, ahead = north (the world's -y) and right = east (the world's x)",
    "kitti": _KITTI_PIXELS.format(body="pose * Tr_imu_to_velo"),
    "kitti_tracking": _KITTI_PIXELS.format(body="the frame's line of pose/<seq>.txt * Tr_imu_velo"),
}
"""How a top-view pixel lies on the water, for :func:`top_view_png` (``carla``: OPV2V's frames; ``kitti`` and
``kitti_tracking``: the KITTI exports', whose LiDAR and world frames are mmusv's)."""


def top_view_entry(top_view: dict[str, Any]) -> dict[str, Any]:
    """A recorded rig's ``top_view`` as the exports describe it: ``resolution`` [W, H] pixels, ``metres_per_pixel``,
    ``orientation``, ``altitude_m``."""
    return {
        "resolution": [int(x) for x in top_view["resolution"]],
        "metres_per_pixel": float(top_view["metres_per_pixel"]),
        "orientation": str(top_view["orientation"]),
        "altitude_m": float(top_view["altitude_m"]),
    }


def top_view_png(*, frame: str, files: str) -> dict[str, Any]:
    """What the exported top-view images are: ``files``, what they hold and where each pixel lies
    (:data:`TOP_VIEW_PIXELS` of ``frame``)."""
    return {
        "files": files,
        "rgb": "8-bit sRGB",
        "semantic": "uint16 class ids (mmusv.classes: 1 water, 2 terrain, 3 vegetation, ..., 10 vessel, 11 usv)",
        "camera": "orthographic, looking straight down from altitude_m over the vessel's origin; what rises above "
        "altitude_m is cut there (the camera sees the decks below it)",
        "pixel": TOP_VIEW_PIXELS[frame],
    }


def top_view_protocol(agents: Iterable[Any], *, frame: str, files: str) -> dict[str, Any]:
    """What places the exported top-view images: ``top_views``, each agent's top view by ``cav_id`` as its rig
    records it (:func:`top_view_entry`; agents without one left out), and ``top_view_png`` (:func:`top_view_png`).
    Empty when no agent has a top view."""
    views = {cav_id(a.index): top_view_entry(a.rig["top_view"]) for a in agents if a.rig.get("top_view")}
    if not views:
        return {}
    return {"top_views": views, "top_view_png": top_view_png(frame=frame, files=files)}


def rounded(values: Iterable[float], nd: int = 6) -> list[float]:
    """Python floats rounded to ``nd`` decimals, with ``-0.0`` written as ``0.0``."""
    return [round(float(v), nd) + 0.0 for v in values]


_Dumper: Any = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def dump_yaml(data: Any) -> bytes:
    """YAML bytes with sorted keys, block style (as OpenCDA writes its files)."""
    text: str = yaml.dump(data, Dumper=_Dumper, default_flow_style=False, sort_keys=True, allow_unicode=False)
    return text.encode("utf-8")


def mask_box(instance: np.ndarray, instance_id: int) -> tuple[int, int, int, int] | None:
    """The tight box ``(x_min, y_min, x_max, y_max)`` of ``instance``'s pixels equal to ``instance_id`` in pixel-edge
    coordinates (the last pixel's far edge: ``x_max`` = last column + 1), or ``None`` when there is none."""
    mask = np.asarray(instance) == instance_id
    cols = np.flatnonzero(mask.any(axis=0))
    if cols.size == 0:
        return None
    rows = np.flatnonzero(mask.any(axis=1))
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def wave_share(box: Any) -> float | None:
    """A recorded box's ``wave_occlusion`` (a ``Box2D`` or ``Box3D`` annotation message: the share, 0..1, of the
    vessel's part above the still level that the waves hide from that sensor, :mod:`mmusv.wave_occlusion`; 0 over a
    flat sea), ``None`` for a box of a recording made before the field existed (its embedded schema lacks it)."""
    share = getattr(box, "wave_occlusion", None)
    return None if share is None else float(share)


def rounded_share(share: float | None) -> float | None:
    """A wave-occlusion share (:func:`wave_share`) as the exports write it: 6 decimals, ``None`` kept (a recording
    made before the field existed)."""
    return None if share is None else round(share, 6) + 0.0
