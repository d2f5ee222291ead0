"""Quick-look images of sensor outputs, for eyes rather than for training: every function returns an
``(H, W, 3)`` uint8 RGB array and :func:`save_png` writes one to disk.

* :func:`depth_image`: depth (metres) through a colour map, near = low end, sky black;
* :func:`semantic_image`: class ids through the fixed palette of :mod:`mmusv.classes`;
* :func:`instance_image`: one stable colour per instance id (a hash of the id), ``-1`` (nothing) black;
* :func:`lidar_bev_image`: a LiDAR sweep seen from above in the sensor frame (x forward = image up, y left =
  image left), coloured by intensity or class, with optional bird's-eye-view boxes.

Example::

    cap = sim.capture(0)
    a = cap.agents["usv_1"]
    save_png("front_depth.png", depth_image(a.cameras["front"].depth, max_m=200))
    save_png("bev.png", lidar_bev_image(a.lidar, extent_m=60, metres_per_pixel=0.2, color_by="class"))
"""

from __future__ import annotations

import os
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from mmusv.classes import palette_array
from mmusv.errors import InputError
from mmusv.sensors.lidar import LidarPoints

__all__ = ["BOX_COLOR", "depth_image", "instance_image", "lidar_bev_image", "save_png", "semantic_image"]

BOX_COLOR: tuple[int, int, int] = (255, 60, 60)
"""Outline colour of the boxes drawn by :func:`lidar_bev_image`."""

_MAX_SIDE = 16_384


@lru_cache(maxsize=8)
def _lut(name: str) -> npt.NDArray[np.uint8]:
    """``(256, 3)`` uint8 lookup table of a matplotlib colour map (``turbo``, ``viridis``, ...)."""
    import matplotlib

    try:
        cmap = matplotlib.colormaps[name]
    except KeyError:
        raise InputError(f"unknown colour map {name!r}; use e.g. 'turbo' or 'viridis'") from None
    rgba = np.asarray(cmap(np.linspace(0.0, 1.0, 256)), dtype=np.float64)
    lut: npt.NDArray[np.uint8] = np.round(rgba[:, :3] * 255.0).astype(np.uint8)
    lut.setflags(write=False)
    return lut


def _image_2d(a: npt.ArrayLike, *, name: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise InputError(f"{name} must be a non-empty (H, W) image, got shape {arr.shape}")
    return arr


def _integers(a: np.ndarray, *, name: str) -> np.ndarray:
    if not (np.issubdtype(a.dtype, np.integer) or a.dtype == np.bool_):
        raise InputError(f"{name} must hold integer ids, got dtype {a.dtype}")
    return a.astype(np.int64, copy=False)


def _scaled(values: np.ndarray, vmax: float, lut: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """Colours of ``values`` in ``[0, vmax]`` (clipped) through ``lut``: ``(..., 3)`` uint8."""
    idx = np.clip(np.nan_to_num(values / vmax, nan=0.0) * 255.0 + 0.5, 0, 255).astype(np.intp)
    out: npt.NDArray[np.uint8] = lut[idx]
    return out


def depth_image(depth: npt.ArrayLike, *, max_m: float | None = None, colormap: str = "turbo") -> npt.NDArray[np.uint8]:
    """Colour-mapped depth.

    Args:
        depth: ``(H, W)`` float depth in metres (``inf`` or ``nan`` = nothing hit).
        max_m: depth mapped to the top of the colour map (farther is clipped to it); default the largest
            finite depth of the image.
        colormap: a matplotlib colour map name (``turbo``, ``viridis``, ...).

    Returns:
        ``(H, W, 3)`` uint8 RGB; 0 m is the low end of the map, ``max_m`` the high end, sky pixels black.
    """
    d = _image_2d(depth, name="depth")
    if not np.issubdtype(d.dtype, np.number) or np.iscomplexobj(d):
        raise InputError(f"depth must be a real float image in metres, got dtype {d.dtype}")
    d = d.astype(np.float64, copy=False)
    finite = np.isfinite(d)
    if max_m is None:
        vmax = float(d[finite].max()) if finite.any() else 1.0
    else:
        vmax = float(max_m)
        if not (np.isfinite(vmax) and vmax > 0):
            raise InputError(f"max_m must be a finite number of metres > 0, got {max_m!r}")
    vmax = vmax if vmax > 0 else 1.0
    out = _scaled(np.where(finite, np.maximum(d, 0.0), 0.0), vmax, _lut(colormap))
    out[~finite] = 0
    return out


def semantic_image(semantic: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """Class ids through the fixed palette (:func:`mmusv.classes.palette_array`).

    Args:
        semantic: ``(H, W)`` integer class ids (0 = sky / nothing, black).

    Returns:
        ``(H, W, 3)`` uint8 RGB; ids without a palette entry (and ids outside 0..255) are magenta.
    """
    s = _integers(_image_2d(semantic, name="semantic"), name="semantic")
    lut = palette_array()
    out: npt.NDArray[np.uint8] = lut[np.clip(s, 0, 255)]
    out[(s < 0) | (s > 255)] = (255, 0, 255)
    return out


def _hash_colors(ids: npt.NDArray[np.int64]) -> npt.NDArray[np.uint8]:
    """``(..., 3)`` uint8 colours of ids: a SplitMix64 hash of the id, each channel in 40..255."""
    with np.errstate(over="ignore"):
        z = ids.astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    channels = [((z >> np.uint64(s)) & np.uint64(0xFF)).astype(np.uint16) for s in (0, 8, 16)]
    rgb = np.stack(channels, axis=-1)
    out: npt.NDArray[np.uint8] = (40 + (rgb * 215) // 255).astype(np.uint8)
    return out


def instance_image(instance: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """One stable colour per instance id.

    Args:
        instance: ``(H, W)`` integer instance ids (``-1`` = nothing hit).

    Returns:
        ``(H, W, 3)`` uint8 RGB. A given id always gets the same colour (a hash of the id, every channel in
        40..255, so never black, in every image and every run); negative ids are black.
    """
    ids = _integers(_image_2d(instance, name="instance"), name="instance")
    uniq, inverse = np.unique(ids, return_inverse=True)
    colors = _hash_colors(uniq)
    colors[uniq < 0] = 0
    out: npt.NDArray[np.uint8] = colors[inverse.reshape(ids.shape)]
    return out


def _box_corners(boxes: np.ndarray) -> np.ndarray:
    """``(N, 4, 2)`` corners (x, y) of BEV boxes ``(N, 5)`` [x, y, length, width, yaw]."""
    x, y, length, width, yaw = (boxes[:, k] for k in range(5))
    c, s = np.cos(yaw), np.sin(yaw)
    hl = np.array([1.0, 1.0, -1.0, -1.0])[None, :] * (length / 2)[:, None]
    hw = np.array([1.0, -1.0, -1.0, 1.0])[None, :] * (width / 2)[:, None]
    cx = x[:, None] + hl * c[:, None] - hw * s[:, None]
    cy = y[:, None] + hl * s[:, None] + hw * c[:, None]
    return np.stack([cx, cy], axis=-1)


def lidar_bev_image(
    xyz: LidarPoints | npt.ArrayLike,
    *,
    extent_m: float,
    metres_per_pixel: float,
    color_by: Literal["intensity", "class"] = "intensity",
    intensity: npt.ArrayLike | None = None,
    semantic_class: npt.ArrayLike | None = None,
    intensity_max: float | None = None,
    boxes: npt.ArrayLike | None = None,
    colormap: str = "viridis",
) -> npt.NDArray[np.uint8]:
    """A LiDAR sweep seen from above, in the LiDAR (or any body) frame.

    The image covers ``[-extent_m, extent_m]`` metres in x and y around the sensor, ``S = ceil(2 · extent_m /
    metres_per_pixel)`` pixels a side: x (forward) points up the image, y (left) to the left, so point
    ``(x, y)`` falls in row ``floor((extent_m − x) / m)``, column ``floor((extent_m − y) / m)``. Where several
    points share a pixel the highest (largest z) wins. Empty pixels are black.

    Args:
        xyz: a :class:`~mmusv.sensors.lidar.LidarPoints` (its intensity and classes are used) or ``(N, 3)``
            float points in metres.
        extent_m: half the side of the square shown, metres (> 0).
        metres_per_pixel: metres per pixel (> 0).
        color_by: ``"intensity"`` (``colormap`` over ``[0, intensity_max]``) or ``"class"`` (the semantic palette).
        intensity: ``(N,)`` intensities in [0, 1] when ``xyz`` is an array and ``color_by="intensity"``.
        semantic_class: ``(N,)`` integer class ids when ``xyz`` is an array and ``color_by="class"``.
        intensity_max: intensity shown at the top of the colour map; default the largest intensity (so weak
            returns stay visible).
        boxes: optional ``(K, 5)`` BEV boxes ``[x, y, length, width, yaw]`` (metres, radians counter-clockwise
            from +x) in the same frame, drawn as outlines in :data:`BOX_COLOR`.
        colormap: matplotlib colour map name for intensities.

    Returns:
        ``(S, S, 3)`` uint8 RGB.
    """
    if isinstance(xyz, LidarPoints):
        pts = np.asarray(xyz.xyz, dtype=np.float64)
        if intensity is None:
            intensity = xyz.intensity
        if semantic_class is None:
            semantic_class = xyz.semantic_class
    else:
        pts = np.asarray(xyz, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InputError(f"xyz must have shape (N, 3), got {pts.shape}")
    extent = float(extent_m)
    mpp = float(metres_per_pixel)
    if not (np.isfinite(extent) and extent > 0):
        raise InputError(f"extent_m must be a finite number of metres > 0, got {extent_m!r}")
    if not (np.isfinite(mpp) and mpp > 0):
        raise InputError(f"metres_per_pixel must be a finite number of metres > 0, got {metres_per_pixel!r}")
    side = int(np.ceil(2 * extent / mpp - 1e-9))
    if side > _MAX_SIDE:
        raise InputError(f"the image would be {side} pixels a side (at most {_MAX_SIDE}); raise metres_per_pixel")
    n = pts.shape[0]
    if color_by == "intensity":
        if intensity is None:
            raise InputError("color_by='intensity' needs intensity= (or LidarPoints)")
        values = np.asarray(intensity, dtype=np.float64).reshape(-1)
        if values.shape[0] != n:
            raise InputError(f"intensity has {values.shape[0]} values for {n} points")
        if intensity_max is None:
            vmax = float(np.nanmax(values)) if n else 1.0
            vmax = vmax if np.isfinite(vmax) and vmax > 0 else 1.0
        else:
            vmax = float(intensity_max)
            if not (np.isfinite(vmax) and vmax > 0):
                raise InputError(f"intensity_max must be finite and > 0, got {intensity_max!r}")
        colors = _scaled(np.maximum(values, 0.0), vmax, _lut(colormap))
    elif color_by == "class":
        if semantic_class is None:
            raise InputError("color_by='class' needs semantic_class= (or LidarPoints)")
        cls = _integers(np.asarray(semantic_class).reshape(-1), name="semantic_class")
        if cls.shape[0] != n:
            raise InputError(f"semantic_class has {cls.shape[0]} values for {n} points")
        colors = palette_array()[np.clip(cls, 0, 255)]
    else:
        raise InputError(f"color_by must be 'intensity' or 'class', got {color_by!r}")

    img = np.zeros((side, side, 3), dtype=np.uint8)
    ok = np.all(np.isfinite(pts), axis=1)
    row = np.floor((extent - pts[:, 0]) / mpp)
    col = np.floor((extent - pts[:, 1]) / mpp)
    ok &= (row >= 0) & (row < side) & (col >= 0) & (col < side)
    order = np.flatnonzero(ok)
    order = order[np.argsort(pts[order, 2], kind="stable")]  # lowest first: the highest point is drawn last
    img[row[order].astype(np.intp), col[order].astype(np.intp)] = colors[order]

    if boxes is not None:
        b = np.asarray(boxes, dtype=np.float64)
        if b.size == 0:
            return img
        if b.ndim != 2 or b.shape[1] != 5:
            raise InputError(f"boxes must have shape (K, 5) [x, y, length, width, yaw], got {b.shape}")
        if not np.isfinite(b).all():
            raise InputError("boxes must be finite")
        from PIL import Image, ImageDraw

        canvas = Image.fromarray(img)
        draw = ImageDraw.Draw(canvas)
        for corners in _box_corners(b):
            # Continuous pixel coordinates (column, row) of the corners; PIL addresses pixel centres at integers.
            poly = [((extent - cy) / mpp - 0.5, (extent - cx) / mpp - 0.5) for cx, cy in corners]
            draw.polygon(poly, outline=BOX_COLOR)
        img = np.asarray(canvas, dtype=np.uint8).copy()
    return img


def save_png(path: str | os.PathLike[str], image: npt.ArrayLike) -> Path:
    """Writes ``image`` (``(H, W, 3)`` RGB, ``(H, W, 4)`` RGBA or ``(H, W)`` grey, uint8) as a PNG at ``path``
    (parent folders created, written atomically) and returns the path."""
    from PIL import Image

    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        raise InputError(f"image must be uint8, got dtype {arr.dtype}")
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[2] in (3, 4))) or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise InputError(f"image must be (H, W), (H, W, 3) or (H, W, 4), got shape {arr.shape}")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            Image.fromarray(np.ascontiguousarray(arr)).save(fh, format="PNG")
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out
