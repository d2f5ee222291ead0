"""CenterPoint's loss (Yin et al., CVPR 2021, Sec. 3, after CenterNet, Zhou et al. 2019): the penalty-reduced
focal loss on the centre heatmap (α = 2, β = 4) plus an L1 loss on the regression at the ground-truth centres,
weighted 0.25, both normalised by the number of objects in the batch.

Inputs are the head's outputs (:mod:`mmusv.learn.head`) and the batched targets (:mod:`mmusv.learn.targets`).
"""

from __future__ import annotations

from collections.abc import Sequence

import torch

__all__ = ["REG_WEIGHT", "centerpoint_loss", "focal_loss", "regression_loss"]

REG_WEIGHT = 0.25


def focal_loss(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Sum over cells of CenterNet's focal loss; ``logits`` and ``target`` ``(B, 1, H, W)``, target in [0, 1]
    with exactly 1 at the centres."""
    pred = torch.sigmoid(logits.float()).clamp(1e-4, 1 - 1e-4)
    pos = target.eq(1).float()
    neg = 1.0 - pos
    pos_loss = torch.log(pred) * (1 - pred) ** 2 * pos
    neg_loss = torch.log(1 - pred) * pred**2 * (1 - target) ** 4 * neg
    return -(pos_loss.sum() + neg_loss.sum())


def gather(feature: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
    """``(B, K, C)`` rows of ``feature`` ``(B, C, H, W)`` at flat cells ``index`` ``(B, K)``."""
    b, c, h, w = feature.shape
    flat = feature.reshape(b, c, h * w).permute(0, 2, 1)
    return flat.gather(1, index.unsqueeze(-1).expand(-1, -1, c))


def regression_loss(
    out: dict[str, torch.Tensor],
    *,
    index: torch.Tensor,
    weight: torch.Tensor,
    reg: torch.Tensor,
    code_weights: Sequence[float] | None = None,
) -> torch.Tensor:
    """Sum of the L1 errors of ``offset, z, size, rot`` at the target rows, each times its ``weight`` ``(B, K)``
    (a bool mask counts as 0/1) and its column's ``code_weights`` (CenterPoint's, default all 1)."""
    pred = torch.cat([gather(out[k].float(), index) for k in ("offset", "z", "size", "rot")], dim=-1)
    m = weight.unsqueeze(-1).float()
    err = torch.abs(pred - reg) * m
    if code_weights is not None:
        err = err * torch.as_tensor(code_weights, dtype=err.dtype, device=err.device)
    return err.sum()


def centerpoint_loss(
    out: dict[str, torch.Tensor],
    *,
    heatmap: torch.Tensor,
    index: torch.Tensor,
    mask: torch.Tensor,
    reg: torch.Tensor,
    weight: torch.Tensor | None = None,
    code_weights: Sequence[float] | None = None,
) -> dict[str, torch.Tensor]:
    """``{"loss", "heatmap", "regression"}``: total, focal and weighted L1 parts. The focal part is per object
    (``mask``: the centre rows); the L1 part per unit of row ``weight`` (default ``mask``: per object, as in
    CenterPoint); ``code_weights`` per column (:func:`regression_loss`)."""
    n = mask.sum().clamp(min=1).float()
    w = mask.float() if weight is None else weight.float()
    hm = focal_loss(out["heatmap"], heatmap) / n
    rg = (
        REG_WEIGHT
        * regression_loss(out, index=index, weight=w, reg=reg, code_weights=code_weights)
        / w.sum().clamp(min=1.0)
    )
    return {"loss": hm + rg, "heatmap": hm.detach(), "regression": rg.detach()}
