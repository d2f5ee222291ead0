"""No, late, early and intermediate fusion of LiDAR detections for one ego USV at one frame (ego LiDAR frame,
metres).

- ``none``: the detector on the ego's own cloud.
- ``late``: every USV runs the detector on its own cloud in its own LiDAR frame; the boxes are moved into the
  ego LiDAR frame (:func:`transform_boxes`) and merged with rotated NMS at BEV IoU 0.10 (:func:`rotated_nms`).
- ``early``: the neighbours' points are moved into the ego LiDAR frame and concatenated with the ego's; the
  detector runs once on the aggregate (cropped to ``crop_m`` around the ego). A detector with an ``early``
  method (a learned model trained on aggregated clouds, :class:`mmusv.learn.detector.LearnedDetector`) runs
  that instead.
- ``intermediate``: only for a detector with an ``intermediate(ego_points, [(points, rel)])`` method (a learned
  model): each neighbour's own cloud and its pose in the ego LiDAR frame go to the model, which fuses the
  neighbours' encoded features (:mod:`mmusv.learn.model`).

The neighbours' poses come from :class:`~mmusv.studies.detection.data.AgentFrame` as given: the robustness study
hands in delayed or noisy ones (:mod:`mmusv.studies.detection.robustness`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from mmusv.errors import InputError
from mmusv.frames import invert, transform_points
from mmusv.studies.detection.data import AgentFrame
from mmusv.studies.detection.detector import Detector
from mmusv.studies.detection.evaluate import bev_iou

__all__ = ["DEFAULT_MODES", "MODES", "NMS_IOU", "fuse", "parse_modes", "relative", "rotated_nms", "transform_boxes"]

MODES = ("none", "late", "early", "intermediate")
DEFAULT_MODES = ("none", "late", "early")
"""The modes any points → boxes detector can run (intermediate fusion needs a learned model)."""
NMS_IOU = 0.10
"""BEV IoU above which late fusion suppresses the lower-scored of two boxes."""

Boxes = tuple[np.ndarray, np.ndarray]


def parse_modes(text: str | Sequence[str]) -> tuple[str, ...]:
    """Validated fusion modes from ``"none,late,early"`` or a list, in :data:`MODES` order."""
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    bad = [s for s in items if s not in MODES]
    if bad or not items:
        raise InputError(f"--modes {','.join(items) or repr(text)}: unknown mode(s) {bad}; allowed: {', '.join(MODES)}")
    return tuple(m for m in MODES if m in items)


def relative(ego: AgentFrame, other: AgentFrame) -> np.ndarray:
    """``(4, 4)`` ``other``'s LiDAR frame → ``ego``'s LiDAR frame."""
    out: np.ndarray = invert(ego.lidar) @ other.lidar
    return out


def transform_boxes(m: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """``(M, 7)`` boxes moved by the rigid ``(4, 4)`` transform ``m``: centres transformed, yaw = heading of the
    transformed box x axis in the target xy plane; sizes unchanged."""
    b: np.ndarray = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    out: np.ndarray = b.copy()
    if b.shape[0] == 0:
        return out
    out[:, :3] = transform_points(m, b[:, :3])
    heading = np.column_stack([np.cos(b[:, 6]), np.sin(b[:, 6]), np.zeros(len(b))]) @ m[:3, :3].T
    out[:, 6] = np.arctan2(heading[:, 1], heading[:, 0])
    return out


def rotated_nms(boxes: np.ndarray, scores: np.ndarray, *, iou_threshold: float = NMS_IOU) -> np.ndarray:
    """Indices kept by greedy NMS on BEV rotated IoU, in descending score (stable): a box is dropped when its IoU
    with a kept, higher-scored box exceeds ``iou_threshold``."""
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    if s.size == 0:
        return np.zeros(0, dtype=np.int64)
    order = np.argsort(-s, kind="stable")
    iou = bev_iou(boxes[order], boxes[order])
    alive = np.ones(len(order), dtype=bool)
    keep: list[int] = []
    for i in range(len(order)):
        if not alive[i]:
            continue
        keep.append(int(order[i]))
        alive[i + 1 :] &= iou[i, i + 1 :] <= iou_threshold
    return np.array(keep, dtype=np.int64)


def early_points(ego: AgentFrame, neighbours: Sequence[AgentFrame], *, crop_m: float) -> np.ndarray:
    """``(N, 4)`` float32 the ego's points and the neighbours' moved into the ego LiDAR frame, cropped to BEV
    distance ``crop_m``."""
    parts = [ego.points.astype(np.float64)]
    for nb in neighbours:
        p = nb.points.astype(np.float64)
        q = np.column_stack([transform_points(relative(ego, nb), p[:, :3]), p[:, 3]]) if len(p) else p
        parts.append(q)
    allp = np.concatenate(parts, axis=0) if parts else np.zeros((0, 4))
    allp = allp[np.hypot(allp[:, 0], allp[:, 1]) <= crop_m]
    return allp.astype(np.float32)


def fuse(
    mode: str,
    ego: AgentFrame,
    neighbours: Sequence[AgentFrame],
    *,
    detector: Detector,
    own_detections: Callable[[AgentFrame], Boxes] | None = None,
    crop_m: float = 220.0,
) -> Boxes:
    """Boxes ``(M, 7)`` and scores ``(M,)`` in ``ego``'s LiDAR frame for fusion ``mode`` (module docstring).
    ``own_detections(agent)`` returns the detector's output on an agent's own cloud (a cache may back it)."""
    own = own_detections or (lambda a: _as_boxes(detector(a.points)))
    if mode == "none":
        return own(ego)
    if mode == "late":
        bs, ss = [own(ego)[0]], [own(ego)[1]]
        for nb in neighbours:
            b, s = own(nb)
            bs.append(transform_boxes(relative(ego, nb), b))
            ss.append(s)
        boxes, scores = np.concatenate(bs, axis=0), np.concatenate(ss)
        keep = rotated_nms(boxes, scores)
        return boxes[keep], scores[keep]
    if mode == "early":
        early = getattr(detector, "early", detector)
        return _as_boxes(early(early_points(ego, neighbours, crop_m=crop_m)))
    if mode == "intermediate":
        inter = getattr(detector, "intermediate", None)
        if inter is None:
            raise InputError("intermediate fusion needs a learned model (--model), not a points -> boxes detector")
        return _as_boxes(inter(ego.points, [(nb.points, relative(ego, nb)) for nb in neighbours]))
    raise InputError(f"fusion mode {mode!r}: allowed: {', '.join(MODES)}")


def _as_boxes(out: tuple[np.ndarray, np.ndarray]) -> Boxes:
    """A detector's output checked and as float64 ``(M, 7)``, ``(M,)``."""
    try:
        b, s = out
    except (TypeError, ValueError):
        raise InputError("the detector must return (boxes (M, 7), scores (M,))") from None
    boxes = np.asarray(b, dtype=np.float64).reshape(-1, 7) if np.size(b) else np.zeros((0, 7))
    scores = np.asarray(s, dtype=np.float64).reshape(-1)
    if boxes.shape[0] != scores.shape[0]:
        raise InputError(f"the detector returned {boxes.shape[0]} boxes but {scores.shape[0]} scores")
    return boxes, scores
