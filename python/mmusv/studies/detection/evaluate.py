"""Scoring 3D detections the way OpenCOOD's ``opencood/utils/eval_utils.py`` does, on BEV rotated boxes.

Boxes are ``(M, 7)`` float64 rows ``x, y, z, l, w, h, yaw`` (metres, radians) in one frame (the ego LiDAR frame);
only the bird's-eye-view rectangle (``x, y, l, w, yaw``) enters the IoU, computed on shapely polygons.

Per frame (:func:`match_frame`): detections are taken in descending score and each is matched to the
ground-truth box of highest IoU among those still unmatched; it is a true positive when that IoU reaches the
threshold, and that ground truth is then used up; otherwise it is a false positive. Over a dataset
(:func:`summarize`) every detection of every frame is sorted once by score (OpenCOOD's ``global_sort_detections``),
precision and recall are accumulated, and AP is the VOC all-point interpolated area (precision made monotone from
the right, summed over the recall steps). P and R are over every detection kept (no extra score threshold).

Range bins: a detection's ego-centric range is the BEV distance ``hypot(x, y)`` of its matched ground truth when
it is a true positive and of its own centre otherwise; a ground truth's is its own. AP per bin uses the detections
and ground truths of that bin, with the matches made on the whole frame (so no match is lost at a bin edge).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import Polygon

__all__ = [
    "BOX_COLUMNS",
    "IOU_THRESHOLDS",
    "RANGE_BINS",
    "FrameMatch",
    "average_precision",
    "bev_iou",
    "bin_label",
    "box_polygons",
    "match_frame",
    "range_bin",
    "summarize",
    "voc_ap",
]

IOU_THRESHOLDS = (0.3, 0.5, 0.7)
"""The IoU thresholds of Table III."""
RANGE_BINS: tuple[tuple[float, float], ...] = ((0.0, 50.0), (50.0, 100.0), (100.0, 150.0), (150.0, 200.0))
"""Ego-centric range bins (metres, ``lo <= r < hi``) of the per-range AP@0.5."""
BOX_COLUMNS = ("x", "y", "z", "l", "w", "h", "yaw")
"""The columns of a box row: centre (metres), length, width, height (metres), yaw (radians), ego LiDAR frame."""


def _boxes(a: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    b = np.asarray(a, dtype=np.float64)
    if b.size == 0:
        return np.zeros((0, 7))
    if b.ndim != 2 or b.shape[1] != 7:
        raise ValueError(f"boxes must be (M, 7) x, y, z, l, w, h, yaw; got shape {b.shape}")
    return b


def box_polygons(boxes: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    """``(M,)`` object array of shapely polygons: the BEV rectangles (x, y metres, in the boxes' frame) of
    ``(M, 7)`` boxes (corners counter-clockwise)."""
    b = _boxes(boxes)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=np.float64) * 0.5
    local = half[None, :, :] * b[:, None, 3:5]  # (M, 4, 2)
    c, s = np.cos(b[:, 6])[:, None], np.sin(b[:, 6])[:, None]
    xs = b[:, None, 0] + c * local[:, :, 0] - s * local[:, :, 1]
    ys = b[:, None, 1] + s * local[:, :, 0] + c * local[:, :, 1]
    return np.array([Polygon(np.column_stack([x, y])) for x, y in zip(xs, ys, strict=True)], dtype=object)


def bev_iou(a: np.ndarray | Sequence[Sequence[float]], b: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    """``(A, B)`` float64 BEV rotated IoU in [0, 1] between the boxes of ``a`` ``(A, 7)`` and ``b`` ``(B, 7)``
    (one frame)."""
    pa, pb = box_polygons(a), box_polygons(b)
    if pa.size == 0 or pb.size == 0:
        return np.zeros((pa.size, pb.size))
    inter = shapely.area(shapely.intersection(pa[:, None], pb[None, :]))
    area_a = shapely.area(pa)[:, None]
    area_b = shapely.area(pb)[None, :]
    union = area_a + area_b - inter
    out: np.ndarray = np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)
    return out


def match_frame(
    det_boxes: np.ndarray,
    *,
    det_scores: np.ndarray,
    gt_boxes: np.ndarray,
    iou_threshold: float,
    iou: np.ndarray | None = None,
) -> np.ndarray:
    """The ground-truth index each detection is matched to (``-1``: false positive), ``(D,)`` int64 in the input
    order; see the module docstring. ``iou`` (``(D, G)``) may be passed when already computed."""
    d = _boxes(det_boxes)
    g = _boxes(gt_boxes)
    scores = np.asarray(det_scores, dtype=np.float64).reshape(-1)
    if scores.shape[0] != d.shape[0]:
        raise ValueError(f"{d.shape[0]} detections but {scores.shape[0]} scores")
    m = bev_iou(d, g) if iou is None else iou
    out = np.full(d.shape[0], -1, dtype=np.int64)
    free = np.ones(g.shape[0], dtype=bool)
    for i in np.argsort(-scores, kind="stable"):
        if not free.any():
            continue
        row = np.where(free, m[i], -1.0)
        j = int(np.argmax(row))
        if row[j] >= iou_threshold:
            out[i] = j
            free[j] = False
    return out


def voc_ap(recall: np.ndarray, precision: np.ndarray) -> float:
    """VOC all-point interpolated AP of a PR curve given point by point (detections in descending score):
    pad recall with 0 and 1 and precision with 0 and 0, make precision non-increasing from the right, sum
    ``(r_i − r_{i−1})·p_i`` over the points where recall changes."""
    mrec = np.concatenate([[0.0], np.asarray(recall, dtype=np.float64), [1.0]])
    mpre = np.concatenate([[0.0], np.asarray(precision, dtype=np.float64), [0.0]])
    mpre = np.maximum.accumulate(mpre[::-1])[::-1]
    steps = np.nonzero(mrec[1:] != mrec[:-1])[0] + 1
    return float(np.sum((mrec[steps] - mrec[steps - 1]) * mpre[steps]))


def average_precision(scores: np.ndarray, *, tp: np.ndarray, n_gt: int) -> float:
    """AP of detections with ``scores`` ``(D,)`` float and true-positive flags ``tp`` ``(D,)`` bool against ``n_gt``
    ground truths: NaN when there is no ground truth, 0 when there are no detections."""
    if n_gt == 0:
        return math.nan
    if len(scores) == 0:
        return 0.0
    s = np.asarray(scores, dtype=np.float64)
    order = np.argsort(-s, kind="stable")
    t = np.asarray(tp, dtype=bool)[order]
    ctp = np.cumsum(t)
    cfp = np.cumsum(~t)
    # Detections of equal score have no order: the curve takes a point only after the last of each tie, so the
    # AP does not depend on the order the detections came in.
    ss = s[order]
    last = np.append(ss[1:] != ss[:-1], True)
    ctp, cfp = ctp[last], cfp[last]
    return voc_ap(ctp / n_gt, ctp / (ctp + cfp))


def range_bin(xy: np.ndarray) -> np.ndarray:
    """``(M,)`` int64 range-bin index of BEV positions ``(M, 2)`` (x, y metres, ego LiDAR frame; the bin of the
    distance ``hypot(x, y)``), ``-1`` outside :data:`RANGE_BINS`."""
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    r = np.hypot(p[:, 0], p[:, 1])
    out = np.full(r.shape[0], -1, dtype=np.int64)
    for k, (lo, hi) in enumerate(RANGE_BINS):
        out[(r >= lo) & (r < hi)] = k
    return out


def bin_label(k: int) -> str:
    """``"0-50"`` etc. for bin ``k``; ``"out"`` for -1."""
    if k < 0:
        return "out"
    lo, hi = RANGE_BINS[k]
    return f"{lo:g}-{hi:g}"


@dataclass
class FrameMatch:
    """One evaluated frame: float64 boxes ``(D, 7)`` / ``(G, 7)`` (:data:`BOX_COLUMNS`), float64 scores ``(D,)``,
    and per IoU threshold the ``(D,)`` int64 matched ground-truth index of every detection (``-1``: FP)."""

    det_boxes: np.ndarray
    det_scores: np.ndarray
    gt_boxes: np.ndarray
    matches: dict[float, np.ndarray] = field(default_factory=dict)

    @staticmethod
    def evaluate(
        det_boxes: np.ndarray,
        *,
        det_scores: np.ndarray,
        gt_boxes: np.ndarray,
        thresholds: Sequence[float] = IOU_THRESHOLDS,
    ) -> FrameMatch:
        """Matches one frame at every threshold."""
        d, g = _boxes(det_boxes), _boxes(gt_boxes)
        s = np.asarray(det_scores, dtype=np.float64).reshape(-1)
        iou = bev_iou(d, g)
        return FrameMatch(
            d, s, g, {t: match_frame(d, det_scores=s, gt_boxes=g, iou_threshold=t, iou=iou) for t in thresholds}
        )

    def det_bins(self, threshold: float = 0.5) -> np.ndarray:
        """``(D,)`` int64 range bin of each detection (:func:`range_bin`; its matched ground truth's when a TP at
        ``threshold``)."""
        m = self.matches[threshold]
        xy = self.det_boxes[:, :2].copy()
        hit = m >= 0
        xy[hit] = self.gt_boxes[m[hit], :2]
        return range_bin(xy)

    def gt_matched(self, threshold: float = 0.5) -> np.ndarray:
        """``(G,)`` bool: whether each ground truth is matched at ``threshold``."""
        out = np.zeros(self.gt_boxes.shape[0], dtype=bool)
        m = self.matches[threshold]
        out[m[m >= 0]] = True
        return out


def summarize(frames: Sequence[FrameMatch]) -> dict[str, float]:
    """Metrics over ``frames``: ``ap30, ap50, ap70`` (AP at IoU 0.3/0.5/0.7), ``precision50, recall50``,
    ``ap50_<bin>`` per range bin, and the counts ``ego_frames`` (one per element of ``frames``: an ego USV at a
    frame), ``gt``, ``det``. NaN where undefined (no ground truth, or no detection for precision)."""
    out: dict[str, float] = {}
    scores = np.concatenate([f.det_scores for f in frames]) if frames else np.zeros(0)
    n_gt = int(sum(f.gt_boxes.shape[0] for f in frames))
    for t in IOU_THRESHOLDS:
        tp = np.concatenate([f.matches[t] >= 0 for f in frames]) if frames else np.zeros(0, dtype=bool)
        out[f"ap{round(t * 100)}"] = average_precision(scores, tp=tp, n_gt=n_gt)
        if t == 0.5:
            n_tp = int(tp.sum())
            out["precision50"] = n_tp / len(tp) if len(tp) else math.nan
            out["recall50"] = n_tp / n_gt if n_gt else math.nan
    if frames:
        tp50 = np.concatenate([f.matches[0.5] >= 0 for f in frames])
        dbin = np.concatenate([f.det_bins(0.5) for f in frames])
        gbin = np.concatenate([range_bin(f.gt_boxes[:, :2]) for f in frames])
    else:
        tp50 = np.zeros(0, dtype=bool)
        dbin = gbin = np.zeros(0, dtype=np.int64)
    for k in range(len(RANGE_BINS)):
        sel = dbin == k
        out[f"ap50_{bin_label(k)}"] = average_precision(scores[sel], tp=tp50[sel], n_gt=int((gbin == k).sum()))
    out["ego_frames"] = float(len(frames))
    out["gt"] = float(n_gt)
    out["det"] = float(len(scores))
    return out
