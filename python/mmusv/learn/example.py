"""One training or inference example per fusion mode, and batches of them.

- ``single`` (no and late fusion): the ego's own cloud;
- ``early``: the neighbours' points moved into the ego LiDAR frame and joined to the ego's (the study's
  :func:`~mmusv.studies.detection.fusion.early_points` rule; the pillar grid crops to the preset's range);
- ``intermediate``: the ego's pillars plus every neighbour's pillars, encoded in the neighbour's own frame and
  grid, whose centres are moved into the ego frame and assigned to the ego grid cell they fall in (cells off the
  grid are dropped); the model max-fuses them into the ego canvas (F-Cooper, Chen et al., SEC 2019). A centre is
  taken at the neighbour's LiDAR height (z = 0 of its frame), so a relative roll or pitch between the two USVs
  places a pillar whose points lie z metres above or below that sensor about z·sin(tilt) off in x, y (metres at
  W3 for tall hulls, docs/studies/detection.md); ``early`` moves every point in 3D.

Inputs: ego points ``(N, 4)`` float32 and ``[(points (N_i, 4), rel (4, 4) neighbour LiDAR → ego LiDAR)]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from mmusv.learn._errors import input_error
from mmusv.learn.modes import MODELS
from mmusv.learn.pillars import FEATURES, Pillars, pillar_centres, pillarize
from mmusv.learn.presets import Preset
from mmusv.learn.targets import Targets, center_targets

__all__ = ["MODES", "Batch", "Example", "collate", "early_cloud", "make_example", "message_bytes"]

MODES = MODELS
"""The three models (:data:`mmusv.learn.modes.MODELS`): ``single`` serves no and late fusion."""


@dataclass(frozen=True)
class Example:
    """The ego's pillars, the neighbours' pillars with their ego-grid cells ``nb_cells`` ``(Q, 2)`` (``None``
    unless intermediate), and the targets (``None`` at inference)."""

    pillars: Pillars
    nb: Pillars | None
    nb_cells: np.ndarray | None
    targets: Targets | None


@dataclass
class Batch:
    """Collated examples as tensors (``size`` examples)."""

    size: int
    features: torch.Tensor
    mask: torch.Tensor
    coords: torch.Tensor
    batch: torch.Tensor
    nb_features: torch.Tensor
    nb_mask: torch.Tensor
    nb_cells: torch.Tensor
    nb_batch: torch.Tensor
    heatmap: torch.Tensor | None = None
    index: torch.Tensor | None = None
    reg_mask: torch.Tensor | None = None
    reg: torch.Tensor | None = None
    reg_weight: torch.Tensor | None = None

    def to(self, device: torch.device | str) -> Batch:
        """The batch on ``device``."""
        moved: dict[str, Any] = {
            k: (v.to(device, non_blocking=True) if isinstance(v, torch.Tensor) else v) for k, v in vars(self).items()
        }
        return Batch(**moved)


def early_cloud(ego: np.ndarray, neighbours: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """``(N, 4)`` float32 the ego's points and every neighbour's moved into the ego frame by its ``rel``."""
    parts = [np.asarray(ego, dtype=np.float32)]
    for pts, rel in neighbours:
        q = np.asarray(pts, dtype=np.float32).copy()
        if len(q):
            q[:, :3] = (q[:, :3].astype(np.float64) @ rel[:3, :3].T + rel[:3, 3]).astype(np.float32)
        parts.append(q)
    return np.concatenate(parts, axis=0)


def _nb_pillars(neighbours: Sequence[tuple[np.ndarray, np.ndarray]], p: Preset) -> tuple[Pillars, np.ndarray]:
    nx, ny = p.grid
    feats, masks, coords, cells = [], [], [], []
    for pts, rel in neighbours:
        pl = pillarize(pts, p)
        if len(pl.coords) == 0:
            continue
        xy = pillar_centres(pl.coords, p)
        e = xy @ rel[:2, :2].T + rel[:2, 3]
        ix = np.floor((e[:, 0] - p.x_range[0]) / p.pillar_m).astype(np.int64)
        iy = np.floor((e[:, 1] - p.y_range[0]) / p.pillar_m).astype(np.int64)
        ok = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
        feats.append(pl.features[ok])
        masks.append(pl.mask[ok])
        coords.append(pl.coords[ok])
        cells.append(np.column_stack([iy[ok], ix[ok]]))
    if not feats:
        m = p.max_points
        empty = Pillars(np.zeros((0, m, FEATURES), np.float32), np.zeros((0, m), bool), np.zeros((0, 2), np.int64))
        return empty, np.zeros((0, 2), np.int64)
    return Pillars(np.concatenate(feats), np.concatenate(masks), np.concatenate(coords)), np.concatenate(cells)


def message_bytes(nb: Pillars, channels: int) -> int:
    """Bytes a neighbour sends for intermediate fusion: per pillar its ``channels`` float32 features and two
    uint16 grid indices."""
    return len(nb.coords) * (4 * channels + 4)


def make_example(
    ego: np.ndarray,
    *,
    neighbours: Sequence[tuple[np.ndarray, np.ndarray]],
    boxes: np.ndarray | None,
    mode: str,
    p: Preset,
) -> Example:
    """The example of ``mode`` (module docstring); ``boxes`` ``(G, 7)`` ego frame for the targets, or ``None``."""
    if mode not in MODES:
        raise input_error(f"mode {mode!r}: allowed: {', '.join(MODES)}")
    targets = center_targets(boxes, p) if boxes is not None else None
    if mode == "single":
        return Example(pillarize(ego, p), None, None, targets)
    if mode == "early":
        return Example(pillarize(early_cloud(ego, neighbours), p), None, None, targets)
    nb, cells = _nb_pillars(neighbours, p)
    return Example(pillarize(ego, p), nb, cells, targets)


def collate(examples: Sequence[Example]) -> Batch:
    """The examples stacked: pillars concatenated with their example's index, targets stacked."""
    t = torch.from_numpy

    def cat(parts: list[np.ndarray], shape: tuple[int, ...], dtype: type) -> torch.Tensor:
        return t(np.concatenate(parts) if parts else np.zeros(shape, dtype=dtype))

    m = examples[0].pillars.mask.shape[1] if examples else 1
    ego = [e.pillars for e in examples]
    nbs = [(i, e.nb, e.nb_cells) for i, e in enumerate(examples) if e.nb is not None and e.nb_cells is not None]
    b = Batch(
        size=len(examples),
        features=cat([x.features for x in ego], (0, m, FEATURES), np.float32),
        mask=cat([x.mask for x in ego], (0, m), np.bool_),
        coords=cat([x.coords for x in ego], (0, 2), np.int64),
        batch=cat([np.full(len(x.coords), i, np.int64) for i, x in enumerate(ego)], (0,), np.int64),
        nb_features=cat([n.features for _, n, _ in nbs], (0, m, FEATURES), np.float32),
        nb_mask=cat([n.mask for _, n, _ in nbs], (0, m), np.bool_),
        nb_cells=cat([c for _, _, c in nbs], (0, 2), np.int64),
        nb_batch=cat([np.full(len(c), i, np.int64) for i, _, c in nbs], (0,), np.int64),
    )
    tg = [e.targets for e in examples]
    if tg and all(x is not None for x in tg):
        b.heatmap = t(np.stack([x.heatmap for x in tg]))  # type: ignore[union-attr]
        b.index = t(np.stack([x.index for x in tg]))  # type: ignore[union-attr]
        b.reg_mask = t(np.stack([x.mask for x in tg]))  # type: ignore[union-attr]
        b.reg = t(np.stack([x.reg for x in tg]))  # type: ignore[union-attr]
        b.reg_weight = t(np.stack([x.weight for x in tg]))  # type: ignore[union-attr]
    return b
