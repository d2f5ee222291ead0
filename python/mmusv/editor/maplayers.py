"""What the editor draws of a map, from the map's own priors and terrain (:mod:`mmusv.world.priors`).

:func:`map_layers` returns one JSON-ready dict per map (cached by kind, seed and parameters, like
:func:`mmusv.generate.mapctx.map_context`): a north-up PNG of the terrain (water shaded by depth, land by height
with hill shading, water a vessel may not sail on, i.e. shallows, tinted) covering the priors' square, and the
vector layers on top: shoreline polylines, port structure and buoy footprints, moored ships (asset, pose, hull
outline) and buoy positions. World frame, metres (x east, y north); coordinates rounded to centimetres.
"""

from __future__ import annotations

import base64
import io
import json
import math
from functools import lru_cache
from typing import Any

import numpy as np
from PIL import Image
from shapely.geometry import Polygon

from mmusv.generate.mapctx import MapContext, map_context
from mmusv.world.vessels import get_asset

__all__ = ["MAX_IMAGE_PX", "map_layers", "terrain_rgb"]

MAX_IMAGE_PX = 1024
"""Largest side of the terrain image in pixels (it is drawn at twice the priors' resolution up to this)."""

_DEEP, _SHALLOW, _SHOAL = np.array([27, 72, 128]), np.array([120, 190, 222]), np.array([186, 222, 214])
_LAND = np.array([[0.0, 222, 208, 160], [3.0, 150, 178, 112], [15.0, 104, 140, 86], [40.0, 140, 132, 110]])


def _rounded(xy: np.ndarray) -> list[list[float]]:
    return np.round(np.asarray(xy, dtype=np.float64), 2).tolist()  # type: ignore[no-any-return]


def terrain_rgb(ctx: MapContext, px: int) -> np.ndarray:
    """``(px, px, 3)`` uint8 north-up picture of the priors' square: row 0 is the northern edge."""
    pri = ctx.priors
    h, w = pri.shape
    size_x, size_y = w * pri.resolution, h * pri.resolution
    xs = pri.origin[0] + (np.arange(px) + 0.5) * size_x / px
    ys = pri.origin[1] + size_y - (np.arange(px) + 0.5) * size_y / px  # north first
    gx, gy = np.meshgrid(xs, ys)
    z = ctx.world.heightfield.sample(np.column_stack([gx.ravel(), gy.ravel()])).reshape(px, px)
    z = np.nan_to_num(z, nan=-25.0)
    depth = np.clip(-z / 25.0, 0.0, 1.0)[..., None] ** 0.6
    rgb = _SHALLOW * (1.0 - depth) + _DEEP * depth
    rows = np.clip(np.floor((gy - pri.origin[1]) / pri.resolution).astype(np.int64), 0, h - 1)
    cols = np.clip(np.floor((gx - pri.origin[0]) / pri.resolution).astype(np.int64), 0, w - 1)
    navigable = pri.water_mask[rows, cols]
    shoal = (z < 0.0) & ~navigable
    rgb[shoal] = rgb[shoal] * 0.35 + _SHOAL * 0.65
    land = z >= 0.0
    if land.any():
        colour = np.stack([np.interp(z, _LAND[:, 0], _LAND[:, c]) for c in (1, 2, 3)], axis=-1)
        step = size_x / px
        dzdy, dzdx = np.gradient(z, step)
        # light from the north-west, 45 degrees up; rows run southwards, so north is -dzdy here
        nx, ny, nz = -dzdx, dzdy, np.ones_like(z)
        light = np.array([-1.0, 1.0, math.sqrt(2.0)]) / 2.0
        shade = np.clip((nx * light[0] + ny * light[1] + nz * light[2]) / np.sqrt(nx**2 + ny**2 + 1.0), 0.0, 1.0)
        colour = colour * (0.55 + 0.45 * shade[..., None])
        rgb[land] = colour[land]
    out: np.ndarray = np.clip(rgb, 0, 255).astype(np.uint8)
    return out


def _rings(poly: Polygon) -> list[list[list[float]]]:
    return [_rounded(np.asarray(poly.exterior.coords)[:, :2])] + [
        _rounded(np.asarray(r.coords)[:, :2]) for r in poly.interiors
    ]


def _layers(ctx: MapContext) -> dict[str, Any]:
    pri = ctx.priors
    h, w = pri.shape
    px = int(min(MAX_IMAGE_PX, 2 * max(h, w)))
    buf = io.BytesIO()
    Image.fromarray(terrain_rgb(ctx, px)).save(buf, format="PNG", optimize=True)
    moored = []
    for (asset, (x, y, yaw)), fp in zip(ctx.world.moored, pri.moored_footprints, strict=True):
        a = get_asset(asset)
        moored.append(
            {
                "asset": asset,
                "x": round(x, 2),
                "y": round(y, 2),
                "yaw": round(yaw, 6),
                "length": round(a.length, 2),
                "beam": round(a.beam, 2),
                "outline": _rings(fp)[0],
            }
        )
    return {
        "kind": ctx.world.kind,
        "seed": ctx.world.seed,
        "extent": round(ctx.extent, 3),
        "bounds": [
            pri.origin[0],
            pri.origin[1],
            pri.origin[0] + w * pri.resolution,
            pri.origin[1] + h * pri.resolution,
        ],
        "resolution": pri.resolution,
        "image": "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii"),
        "shoreline": [_rounded(line) for line in pri.shoreline],
        "structures": [_rings(p) for p in pri.structure_boundaries],
        "moored": moored,
        "buoys": _rounded(pri.buoys),
    }


@lru_cache(maxsize=8)
def _cached(kind: str, seed: int, params_json: str) -> str:
    return json.dumps(_layers(map_context(kind, seed=seed, params=json.loads(params_json))), separators=(",", ":"))


def map_layers(kind: str, *, seed: int, params: dict[str, Any]) -> str:
    """The layers of the map ``kind``/``seed``/``params`` (the given map parameters) as a JSON text (see the module
    docstring), cached."""
    return _cached(kind, int(seed), json.dumps(params, sort_keys=True))
