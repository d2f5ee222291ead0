"""A learned third stage for the learned detector: IoU-aware rescoring of the refined boxes.

The network's heatmap score says how sure it is that a vessel is there, not how well its box fits it. At the
strict threshold (AP@0.7) a confident but loose box ranks above a tight one, and every such box is a false positive
there. This stage predicts, for every refined box, the BEV IoU it has with the vessel it found, from what the
detector knows of that box, and ranks the boxes by ``score^(1−β) · IoU_pred^β``.

Model: IoU prediction as localisation confidence (B. Jiang, R. Luo, J. Mao, T. Xiao & Y. Jiang, "Acquisition of
Localization Confidence for Accurate Object Detection", ECCV 2018), and for LiDAR detectors the IoU-aware score
rectification ``score · IoU^β`` (W. Zheng, W. Tang, S. Chen, L. Jiang & C.-W. Fu, "CIA-SSD: Confident IoU-Aware
Single-Stage Object Detector From Point Cloud", AAAI 2021). Here the IoU comes from a small multilayer perceptron
(:class:`IoUScorer`, two hidden layers of 32) on the box's features (:data:`FEATURES`): the network's score, the
refined box's size and range, the surface points in and around it and how far they span it, and how far the
geometric refinement (:mod:`mmusv.learn.refine`) moved the network's box (the points and the network disagree
where a box is loose). It is trained with binary cross-entropy against the true IoU (0 for a box on no vessel)
of the model's own refined boxes on the training split (:func:`fit_scorer`); ``β`` is chosen on a held-out fifth
of the training sequences, from 0 (the network's score: rescoring can only be as bad as none) to 1.

:func:`second_stage` is the one place the refinement, the rescoring and the final rotated NMS are applied, for
:class:`mmusv.learn.detector.LearnedDetector` and :mod:`mmusv.learn.replay` alike.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from mmusv.learn._errors import input_error
from mmusv.learn.checkpoint import load_checkpoint, save_checkpoint
from mmusv.learn.refine import RefineParams, refine_on, surface_points
from mmusv.studies.detection.evaluate import average_precision, bev_iou, match_frame
from mmusv.studies.detection.fusion import rotated_nms

__all__ = [
    "BETAS",
    "FEATURES",
    "IoUScorer",
    "ScorerFit",
    "box_features",
    "fit_scorer",
    "load_scorer",
    "second_stage",
]

FEATURES: tuple[str, ...] = (
    "score_logit",
    "log_length",
    "log_beam",
    "log_height",
    "range_hm",
    "log1p_points_in",
    "log1p_points_around",
    "length_span",
    "beam_span",
    "log_length_change",
    "log_beam_change",
    "log1p_centre_shift",
    "yaw_change",
)
"""Per box (:func:`box_features`): logit of the network's score; log of the refined length, beam and height (m);
range from the sensor (hectometres); log(1 + surface points in the refined box) and in the box grown by the
refinement's margins; the points' span along the length and across the beam over the box's extent (0 with fewer than
two points); log of refined over network length and beam; log(1 + the centre's shift, m); the heading's change
(radians, folded into [0, π/2])."""

BETAS: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
"""The exponents ``β`` tried on the held-out sequences (:func:`fit_scorer`)."""

MIN_BOXES = 20
"""Fewest boxes :func:`fit_scorer` fits a scorer on."""

SCORER_FILE = "scorer.pt"
"""The file name a model folder's scorer is saved under, beside its ``model.pt``."""


def box_features(
    xy: np.ndarray, *, net_boxes: np.ndarray, boxes: np.ndarray, scores: np.ndarray, p: RefineParams
) -> np.ndarray:
    """``(M, len(FEATURES))`` float32 features (:data:`FEATURES`) of the refined ``boxes`` ``(M, 7)`` made from
    ``net_boxes`` ``(M, 7)`` (``x, y, z, l, w, h, yaw``, the points' frame, metres and radians) with network
    ``scores`` ``(M,)``, on the cloud's surface points ``xy`` ``(K, 2)`` (:func:`mmusv.learn.refine.surface_points`)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    nb = np.asarray(net_boxes, dtype=np.float64).reshape(-1, 7)
    s = np.clip(np.asarray(scores, dtype=np.float64).reshape(-1), 1e-4, 1 - 1e-4)
    out = np.zeros((len(b), len(FEATURES)), dtype=np.float64)
    out[:, 0] = np.log(s / (1 - s))
    out[:, 1:4] = np.log(np.maximum(b[:, 3:6], 0.1))
    out[:, 4] = np.hypot(b[:, 0], b[:, 1]) / 100.0
    for i, row in enumerate(b):
        c, sn = np.cos(row[6]), np.sin(row[6])
        d = xy - row[:2]
        along, across = d @ np.array([c, sn]), d @ np.array([-sn, c])
        half_l, half_w = row[3] / 2.0, row[4] / 2.0
        inside = (np.abs(along) <= half_l) & (np.abs(across) <= half_w)
        around = (np.abs(along) <= half_l + p.margin_length_m) & (np.abs(across) <= half_w + p.margin_m)
        out[i, 5] = np.log1p(inside.sum())
        out[i, 6] = np.log1p(around.sum())
        if inside.sum() >= 2:
            out[i, 7] = np.ptp(along[inside]) / max(row[3], 0.1)
            out[i, 8] = np.ptp(across[inside]) / max(row[4], 0.1)
    out[:, 9] = np.log(np.maximum(b[:, 3], 0.1) / np.maximum(nb[:, 3], 0.1))
    out[:, 10] = np.log(np.maximum(b[:, 4], 0.1) / np.maximum(nb[:, 4], 0.1))
    out[:, 11] = np.log1p(np.hypot(b[:, 0] - nb[:, 0], b[:, 1] - nb[:, 1]))
    dyaw = np.abs((b[:, 6] - nb[:, 6] + np.pi / 2) % np.pi - np.pi / 2)
    out[:, 12] = dyaw
    return out.astype(np.float32)


class IoUScorer(nn.Module):
    """The IoU predictor (module docstring): standardised :data:`FEATURES` → 32 → 32 → 1 (ReLU; a sigmoid gives
    the IoU in [0, 1]), with its rescoring exponent ``beta``."""

    def __init__(self, mean: np.ndarray, std: np.ndarray, *, beta: float = 0.5) -> None:
        super().__init__()
        n = len(FEATURES)
        self.mean: torch.Tensor
        self.std: torch.Tensor
        self.register_buffer("mean", torch.as_tensor(np.asarray(mean, dtype=np.float32).reshape(n)))
        self.register_buffer("std", torch.as_tensor(np.maximum(np.asarray(std, dtype=np.float32).reshape(n), 1e-3)))
        self.net = nn.Sequential(nn.Linear(n, 32), nn.ReLU(), nn.Linear(32, 32), nn.ReLU(), nn.Linear(32, 1))
        self.beta = float(beta)
        self.info: dict[str, Any] = {}
        """What the fit saved beside the weights (``mmusv train``: the digest of the model it was fitted for
        under ``"model"``, :func:`mmusv.learn.checkpoint.weights_digest`); empty for a scorer not loaded."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Logits ``(M,)`` of the IoU for features ``x`` ``(M, len(FEATURES))``."""
        out: torch.Tensor = self.net((x - self.mean) / self.std).squeeze(-1)
        return out

    def iou(self, features: np.ndarray) -> np.ndarray:
        """``(M,)`` float64 predicted BEV IoU of boxes with ``features`` ``(M, len(FEATURES))``."""
        if len(features) == 0:
            return np.zeros(0)
        with torch.no_grad():
            x = torch.as_tensor(np.asarray(features, dtype=np.float32))
            return torch.sigmoid(self(x)).double().numpy()

    def rescore(self, features: np.ndarray, scores: np.ndarray) -> np.ndarray:
        """``(M,)`` float64 ``score^(1−β) · IoU_pred^β`` of boxes with ``features`` and network ``scores``."""
        s = np.asarray(scores, dtype=np.float64).reshape(-1)
        return blend(s, self.iou(features), self.beta)

    def save(self, path: str | Path, info: dict[str, Any]) -> Path:
        """Writes the scorer (weights, standardisation, ``beta``) and ``info`` to ``path``
        (:func:`mmusv.learn.checkpoint.save_checkpoint`: a temporary name, then renamed, so a killed save leaves no
        file that looks complete, and a failed one no temporary file)."""
        obj = {"features": list(FEATURES), "state": self.state_dict(), "beta": self.beta, "info": info}
        return save_checkpoint(obj, path)


def blend(scores: np.ndarray, iou: np.ndarray, beta: float) -> np.ndarray:
    """``scores^(1−β) · iou^β`` (``iou`` floored at 10⁻³), float64."""
    s = np.asarray(scores, dtype=np.float64)
    return np.asarray(s ** (1.0 - beta) * np.maximum(np.asarray(iou, dtype=np.float64), 1e-3) ** beta)


def load_scorer(path: str | Path) -> IoUScorer:
    """The :class:`IoUScorer` saved at ``path``; raises ``InputError`` naming the file when it is not one."""
    p = Path(path)
    ck = load_checkpoint(p, what=f"{p}: not an mmusv.learn scorer")
    try:
        if list(ck["features"]) != list(FEATURES):
            raise ValueError(f"features {ck['features']} are not this version's {list(FEATURES)}")
        n = len(FEATURES)
        m = IoUScorer(np.zeros(n), np.ones(n), beta=float(ck["beta"]))
        m.load_state_dict(ck["state"])
        info = ck.get("info", {})
        m.info = dict(info) if isinstance(info, dict) else {}
    except (OSError, KeyError, TypeError, RuntimeError, ValueError) as exc:
        raise input_error(f"{p}: not an mmusv.learn scorer ({type(exc).__name__}: {exc})") from None
    m.eval()
    return m


def second_stage(
    points: np.ndarray,
    *,
    boxes: np.ndarray,
    scores: np.ndarray,
    refine: RefineParams | None,
    scorer: IoUScorer | None,
    nms_iou: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The decoded ``boxes`` ``(M, 7)`` and ``scores`` ``(M,)`` of one cloud ``points`` ``(N, ≥3)`` (same frame)
    refined on the points (``refine``), rescored (``scorer``, which needs ``refine``) and put through the rotated
    NMS at ``nms_iou`` again (two proposals on one hull can grow into the same box); as given when ``refine`` is
    ``None``."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    if refine is None or len(b) == 0:
        return b, s
    xy = surface_points(points, refine)
    ref = refine_on(xy, boxes=b, p=refine)
    if scorer is not None:
        s = scorer.rescore(box_features(xy, net_boxes=b, boxes=ref, scores=s, p=refine), s)
    keep = rotated_nms(ref, s, iou_threshold=nms_iou)
    return ref[keep], s[keep]


@dataclass(frozen=True)
class ScorerFit:
    """What :func:`fit_scorer` measured: boxes and ego-frames used, the chosen ``beta``, and per ``β`` tried the
    held-out AP@0.5 and AP@0.7 (``(beta, ap50, ap70)``)."""

    boxes: int
    frames: int
    beta: float
    held_out: tuple[tuple[float, float, float], ...]


Frame = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""One ego-frame's refined boxes ``(M, 7)``, network scores ``(M,)``, features ``(M, F)`` and ground truth
``(G, 7)``."""


def _frames(
    sample: Callable[[int], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    samples: Sequence[int],
    refine: RefineParams,
    nms_iou: float,
) -> list[Frame]:
    out: list[Frame] = []
    for k in samples:
        points, boxes, scores, gt = sample(k)
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
        s = np.asarray(scores, dtype=np.float64).reshape(-1)
        if len(b):
            xy = surface_points(points, refine)
            ref = refine_on(xy, boxes=b, p=refine)
            f = box_features(xy, net_boxes=b, boxes=ref, scores=s, p=refine)
            # The boxes the rescored detector would keep whatever the new scores: the NMS of the refined boxes by
            # the network's scores (the final NMS removes only boxes that grew onto one hull).
            keep = rotated_nms(ref, s, iou_threshold=nms_iou)
            ref, s, f = ref[keep], s[keep], f[keep]
        else:
            ref, s, f = b, s, np.zeros((0, len(FEATURES)), np.float32)
        out.append((ref, s, f, np.asarray(gt, dtype=np.float64).reshape(-1, 7)))
    return out


def _ap(frames: Sequence[Frame], scores: Sequence[np.ndarray], thr: float) -> float:
    all_s, all_tp = [], []
    n_gt = 0
    for (b, _, _, gt), s in zip(frames, scores, strict=True):
        n_gt += len(gt)
        if len(b) == 0:
            continue
        m = match_frame(b, det_scores=s, gt_boxes=gt, iou_threshold=thr) if len(gt) else np.full(len(b), -1)
        all_s.append(s)
        all_tp.append(m >= 0)
    if not all_s:
        return 0.0
    return average_precision(np.concatenate(all_s), tp=np.concatenate(all_tp), n_gt=n_gt)


def fit_scorer(
    sample: Callable[[int], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    *,
    samples: Sequence[int],
    groups: Sequence[object],
    refine: RefineParams,
    nms_iou: float,
    seed: int = 0,
    epochs: int = 300,
) -> tuple[IoUScorer, ScorerFit]:
    """Trains an :class:`IoUScorer` on the training samples ``samples``: ``sample(k)`` gives sample ``k``'s model
    input cloud ``(N, ≥3)``, its decoded boxes ``(M, 7)`` and scores ``(M,)`` (before the second stage), and its
    ground truth ``(G, 7)`` (same frame). ``groups`` (one per sample, e.g. its sequence) decide the held-out
    fifth (every group whose rank is 4 mod 5) on which ``β`` is chosen (the best mean of AP@0.5 and AP@0.7 over
    :data:`BETAS`); the network trains on the rest. Full-batch Adam (lr 10⁻², ``epochs`` steps), seeded:
    deterministic on a CPU. Raises ``InputError`` when the model found fewer than :data:`MIN_BOXES` boxes."""
    frames = _frames(sample, samples, refine, nms_iou)
    ranks = {g: i for i, g in enumerate(sorted(set(groups), key=str))}
    held = np.array([ranks[g] % 5 == 4 for g in groups])
    if held.all() or not held.any():
        held = np.arange(len(frames)) % 5 == 4
    feats, target = [], []
    for (b, _, f, gt), h in zip(frames, held, strict=True):
        if h or len(b) == 0:
            continue
        iou = bev_iou(b, gt).max(axis=1) if len(gt) else np.zeros(len(b))
        feats.append(f)
        target.append(iou)
    x = np.concatenate(feats).astype(np.float32) if feats else np.zeros((0, len(FEATURES)), np.float32)
    if len(x) < MIN_BOXES or not held.any():
        raise input_error(
            f"fitting the IoU scorer: the model found {len(x)} boxes on the training part of the samples (at least "
            f"{MIN_BOXES} needed) and {int(held.sum())} held-out ego-frames"
        )
    y = np.concatenate(target).astype(np.float32)
    torch.manual_seed(seed)
    model = IoUScorer(x.mean(axis=0), x.std(axis=0))
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    xt, yt = torch.as_tensor(x), torch.as_tensor(y)
    loss_fn = nn.BCEWithLogitsLoss()
    model.train()
    for _ in range(epochs):
        opt.zero_grad()
        loss = loss_fn(model(xt), yt)
        loss.backward()
        opt.step()
    model.eval()
    test = [fr for fr, h in zip(frames, held, strict=True) if h]
    pred = [model.iou(f) for _, _, f, _ in test]
    tried = []
    for beta in BETAS:
        sc = [blend(s, q, beta) for (_, s, _, _), q in zip(test, pred, strict=True)]
        tried.append((beta, _ap(test, sc, 0.5), _ap(test, sc, 0.7)))
    best = max(tried, key=lambda t: (t[1] + t[2], -t[0]))
    model.beta = best[0]
    return model, ScorerFit(boxes=len(x), frames=len(frames), beta=best[0], held_out=tuple(tried))
