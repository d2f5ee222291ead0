"""``mmusv assets --render DIR``: a close-up of every vessel asset, and a contact sheet of them all.

Each asset is rendered alone (no water, so the whole hull shows) by mmusv's own pinhole camera
(:mod:`mmusv.sensors.camera` over a :class:`mmusv.Scene`) in a clear-noon environment, from a three-quarter view
above the port bow, framed to the asset's bounding box. The sheet is a grid of ``cols`` columns (``ceil(sqrt(N))``)
of those tiles, each under a strip labelled with the asset's name and triangle count. Same assets, same pictures:
nothing here is random.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.scene import Scene
from mmusv.sensors.camera import render
from mmusv.sensors.config import MAX_IMAGE_PIXELS
from mmusv.world.materials import material_table
from mmusv.world.vessels import VesselAsset, get_asset

__all__ = [
    "LABEL_H",
    "MAX_SIDE_PX",
    "SheetLayout",
    "camera_pose",
    "render_asset",
    "sheet_files",
    "sheet_layout",
    "write_contact_sheet",
]

LABEL_H = 22
"""Height in pixels of the label strip above each tile."""
_BG = (24, 24, 28)
_TEXT = (235, 235, 235)
_HFOV_DEG = 40.0
_AZIMUTH_DEG = 35.0  # from the bow towards port
_ELEVATION_DEG = 24.0
MAX_SIDE_PX = 16384
"""The widest and tallest a close-up, a tile or the sheet may be, in pixels (a camera's largest image side)."""


@dataclass(frozen=True)
class SheetLayout:
    """The sheet's grid: ``cols`` x ``rows`` cells of ``tile`` ``(width, height)`` pixels plus a label strip."""

    cols: int
    rows: int
    tile: tuple[int, int]

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)`` of the sheet in pixels."""
        return self.cols * self.tile[0], self.rows * (self.tile[1] + LABEL_H)


def sheet_layout(n: int, tile: tuple[int, int]) -> SheetLayout:
    """The grid for ``n`` tiles: ``ceil(sqrt(n))`` columns and as many rows as needed."""
    if n < 1:
        raise ConfigError("a contact sheet needs at least one asset")
    cols = math.ceil(math.sqrt(n))
    return SheetLayout(cols=cols, rows=math.ceil(n / cols), tile=tile)


def camera_pose(bbox: np.ndarray, *, size: tuple[int, int], hfov_deg: float = _HFOV_DEG) -> np.ndarray:
    """``(4, 4)`` camera body → asset frame pose looking at the centre of ``bbox`` ``(2, 3)`` (metres) from the
    three-quarter view, as close as keeps all eight corners of the box inside the picture (5 % margin)."""
    lo, hi = np.asarray(bbox, dtype=np.float64)
    centre = (lo + hi) / 2.0
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    w, h = size
    tan_h = math.tan(math.radians(hfov_deg) / 2.0) * 0.95
    tan_v = tan_h * h / w
    az, el = math.radians(_AZIMUTH_DEG), math.radians(_ELEVATION_DEG)
    back = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    fwd = -back
    left = np.cross([0.0, 0.0, 1.0], fwd)
    left /= np.linalg.norm(left)
    up = np.cross(fwd, left)
    rel = corners - centre
    # corner k at distance d: depth d + rel.fwd, sideways rel.left, up rel.up; the closest d that fits them all
    depth0, side, rise = rel @ fwd, np.abs(rel @ left), np.abs(rel @ up)
    dist = float(np.max(np.maximum(side / tan_h, rise / tan_v) - depth0))
    dist = max(dist, float(np.max(-depth0)) + 1e-3)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = fwd, left, up, centre + dist * back
    return pose


def _scene_of(asset: VesselAsset) -> Scene:
    scene = Scene()
    m = asset.mesh
    extra: dict[str, Any] = {}
    if hasattr(scene, "set_materials"):  # the material-aware scene (issue #28): the table before the meshes
        scene.set_materials(material_table())
    if "materials" in inspect.signature(Scene.add_mesh).parameters:
        extra["materials"] = m.materials
    mid = scene.add_mesh(m.vertices, m.faces, classes=m.classes, name=asset.name, **extra)
    scene.add_instance(mid)
    return scene


def render_asset(asset: VesselAsset, *, size: tuple[int, int] = (640, 480)) -> np.ndarray:
    """``(H, W, 3)`` uint8 sRGB close-up of ``asset`` (module docstring)."""
    from mmusv._native import core
    from mmusv.sensors.env import sensor_env

    w, h = size
    cam = core.Camera(width=w, height=h, rgb=True, hfov=math.radians(_HFOV_DEG), range_max=20000.0)
    pose = camera_pose(asset.bbox, size=size)
    images = render(cam, _scene_of(asset), pose=pose, env=sensor_env(), seed=0)
    assert images.rgb is not None
    return np.asarray(images.rgb, dtype=np.uint8)


def _label(asset: VesselAsset) -> str:
    return f"{asset.name}  {asset.num_triangles:,} tris"


def write_contact_sheet(
    out_dir: str | os.PathLike[str],
    *,
    names: list[str] | None = None,
    assets: Sequence[VesselAsset] | None = None,
    tile: tuple[int, int] = (320, 240),
    asset_size: tuple[int, int] = (640, 480),
    overwrite: bool = False,
) -> Path:
    """Renders every asset of ``names`` (default: the whole library), or the assets ``assets`` (built and not
    registered, e.g. by :func:`~mmusv.world.vessels.load_asset_file`, as ``mmusv assets FILE --render DIR`` does;
    not with ``names``, and no two of one name), to ``<out_dir>/<name>.png`` at ``asset_size`` and writes the grid
    of them, ``tile`` pixels each, to ``<out_dir>/contact_sheet.png`` (returned). Raises
    :class:`mmusv.ConfigError` if ``out_dir`` is a file, ``names`` is not a list of asset names, ``assets`` not a
    list of :class:`~mmusv.world.vessels.VesselAsset` of distinct names, or a size is not ``(width, height)`` in
    whole pixels (1..:data:`MAX_SIDE_PX` each; a close-up at most a camera's ``MAX_IMAGE_PIXELS``, the sheet at most
    :data:`MAX_SIDE_PX` a side), and :class:`mmusv.NotFoundError` for a name the library does not hold, all before
    anything is written; :class:`mmusv.IoError` naming the file that cannot be written, and, unless ``overwrite``,
    naming the files of those names already in ``out_dir`` (an earlier sheet's, or a user's own
    ``contact_sheet.png``), before anything is written."""
    from mmusv.cli_paths import refuse_replacing
    from mmusv.recording.guard import file_in_the_way
    from mmusv.world.vessels import asset_names

    out = arguments.path(out_dir, name="out_dir")
    overwrite = arguments.flag(overwrite, name="overwrite")
    if isinstance(names, Iterator):  # a generator of names, read once (an ordered iterable, as before)
        names = list(names)
    if names is not None:  # a bare string was read as its letters ('u' is not an asset)
        arguments.names(names, name="names", example="['usv_wamv']")
    given = None if assets is None else _assets(assets, names)
    chosen = [a.name for a in given] if given is not None else asset_names() if names is None else list(names)
    tile = _size(tile, "tile")
    asset_size = _size(asset_size, "asset_size")
    if asset_size[0] * asset_size[1] > MAX_IMAGE_PIXELS:
        raise ConfigError(
            f"asset_size = {asset_size}: {asset_size[0] * asset_size[1]:,} pixels, more than a camera's "
            f"{MAX_IMAGE_PIXELS:,} (mmusv.sensors.config.MAX_IMAGE_PIXELS)"
        )
    # an unknown name is named before any file is written
    drawn = given if given is not None else [get_asset(name) for name in chosen]
    layout = sheet_layout(len(chosen), tile)
    if max(layout.size) > MAX_SIDE_PX:
        raise ConfigError(
            f"tile = {tile}: the sheet of {len(chosen)} assets would be {layout.size[0]} x {layout.size[1]} pixels, "
            f"more than {MAX_SIDE_PX} a side: give smaller tiles"
        )
    blocking = file_in_the_way(out)  # out, or a folder above it, is a file (mkdir's bare OSError)
    if blocking is not None:
        where = "a file" if blocking == out else f"{str(blocking)!r} is a file"
        raise ConfigError(f"out_dir = {str(out)!r}: {where}, not a folder")
    refuse_replacing(out, sheet_files(chosen), overwrite=overwrite, flag="out_dir", how="pass overwrite=True")
    out.mkdir(parents=True, exist_ok=True)
    sheet = Image.new("RGB", layout.size, _BG)
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=13)
    for k, (name, asset) in enumerate(zip(chosen, drawn, strict=True)):
        img = Image.fromarray(render_asset(asset, size=asset_size))
        _save(img, out / f"{name}.png")
        col, row = k % layout.cols, k // layout.cols
        x0, y0 = col * tile[0], row * (tile[1] + LABEL_H)
        draw.text((x0 + 6, y0 + 4), _label(asset), fill=_TEXT, font=font)
        sheet.paste(img.resize(tile, Image.Resampling.LANCZOS), (x0, y0 + LABEL_H))
    path = out / "contact_sheet.png"
    _save(sheet, path)
    return path


def sheet_files(names: Sequence[str]) -> list[str]:
    """The names of the files :func:`write_contact_sheet` writes for the assets ``names``: one PNG each and
    ``contact_sheet.png``."""
    return [*(f"{n}.png" for n in names), "contact_sheet.png"]


def _assets(assets: object, names: object) -> list[VesselAsset]:
    """``assets`` as a list of :class:`VesselAsset` of distinct names, else a ConfigError saying why."""
    if names is not None:
        raise ConfigError("give names (assets of the library) or assets (VesselAsset objects), not both")
    if isinstance(assets, (str, bytes, Mapping)) or not isinstance(assets, Iterable):
        raise ConfigError(f"assets = {arguments.shown(assets)}: must be a list of VesselAsset (load_asset_file)")
    out = list(assets)
    seen: dict[str, int] = {}
    for i, a in enumerate(out):
        if not isinstance(a, VesselAsset):
            raise ConfigError(f"assets[{i}] = {arguments.shown(a)}: must be a VesselAsset (load_asset_file)")
        if a.name in seen:
            j = seen[a.name]
            raise ConfigError(
                f"assets[{i}] ({a.source}) and assets[{j}] ({out[j].source}) are both named {a.name!r}: each is "
                f"written to {a.name}.png; render them into different folders"
            )
        seen[a.name] = i
    return out


def _size(value: Any, name: str) -> tuple[int, int]:
    """``value`` as ``(width, height)``, whole numbers of pixels in 1..:data:`MAX_SIDE_PX`; else a ConfigError
    naming ``name``."""
    if isinstance(value, np.ndarray) and value.ndim == 1:  # np.array([320, 240]): numpy integers, checked below
        value = tuple(value)
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != 2:
        raise ConfigError(f"{name} = {arguments.shown(value)}: must be (width, height) in pixels, e.g. (320, 240)")
    w, h = (arguments.whole(v, name=f"{name}[{i}]", lo=1, hi=MAX_SIDE_PX) for i, v in enumerate(value))
    return w, h


def _save(img: Image.Image, path: Path) -> None:
    """``img`` written as the PNG ``path`` through a temporary file beside it (never a half-written PNG); an
    :class:`mmusv.IoError` naming ``path`` when it cannot be written, the temporary file removed."""
    tmp = path.with_name(f".{path.name}.part")
    try:
        img.save(tmp, format="PNG")
        tmp.replace(path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        where = f" ({exc.filename})" if exc.filename and exc.filename != str(path) else ""
        raise IoError(f"cannot write {path}: {exc.strerror or exc}{where}") from None
