"""Decoding the CenterPoint head into boxes (Yin et al., CVPR 2021, Sec. 3): heatmap peaks (a cell that is the
maximum of its 3×3 neighbourhood, the max-pool "NMS" of CenterNet), the ``top_k`` strongest above
``score_threshold``, each read as ``x = x0 + (ix + dx) · cell``, ``y = y0 + (iy + dy) · cell``, ``z``,
``l, w, h = exp(log size)``, ``yaw = atan2(sin, cos)`` (halved with the preset's ``yaw_double``); then greedy
rotated NMS on BEV IoU
(:func:`mmusv.studies.detection.fusion.rotated_nms`, the detection study's own, at the preset's ``nms_iou``).

Output: boxes ``(M, 7)`` float64 ``x, y, z, l, w, h, yaw`` in the LiDAR frame (metres, radians) and scores
``(M,)`` float64 in (0, 1), by descending score.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from mmusv.learn.presets import Preset

__all__ = ["decode", "peaks"]


def peaks(out: dict[str, torch.Tensor], p: Preset) -> tuple[np.ndarray, np.ndarray]:
    """Boxes ``(M, 7)`` and scores ``(M,)`` of the heatmap peaks of one sample's head outputs (each ``(1, C,
    H, W)``), before rotated NMS."""
    heat = torch.sigmoid(out["heatmap"][0, 0].float())
    w = heat.shape[1]
    keep = F.max_pool2d(heat[None, None], 3, stride=1, padding=1)[0, 0] == heat
    scores = torch.where(keep, heat, torch.zeros_like(heat)).reshape(-1)
    k = min(p.top_k, scores.numel())
    top, idx = torch.topk(scores, k)
    sel = top >= p.score_threshold
    top, idx = top[sel], idx[sel]
    iy, ix = idx // w, idx % w
    cell = p.pillar_m * p.out_stride

    def at(name: str) -> np.ndarray:
        t = out[name][0].float().reshape(out[name].shape[1], -1)[:, idx]
        arr: np.ndarray = t.detach().cpu().numpy().astype(np.float64)
        return arr

    off, z, size, rot = at("offset"), at("z"), at("size"), at("rot")
    x = p.x_range[0] + (ix.cpu().numpy() + off[0]) * cell
    y = p.y_range[0] + (iy.cpu().numpy() + off[1]) * cell
    dims = np.exp(np.clip(size, -5.0, 7.0))
    yaw = np.arctan2(rot[0], rot[1]) / (2.0 if p.yaw_double else 1.0)
    boxes = np.column_stack([x, y, z[0], dims[0], dims[1], dims[2], yaw]) if len(x) else np.zeros((0, 7))
    return boxes, top.detach().cpu().numpy().astype(np.float64)


def decode(out: dict[str, torch.Tensor], p: Preset) -> tuple[np.ndarray, np.ndarray]:
    """Boxes and scores of one sample (module docstring)."""
    from mmusv.studies.detection.fusion import rotated_nms

    boxes, scores = peaks(out, p)
    keep = rotated_nms(boxes, scores, iou_threshold=p.nms_iou)
    return boxes[keep], scores[keep]
