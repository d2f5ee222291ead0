"""No, late, early and intermediate fusion of LiDAR detections for one ego USV at one frame (ego LiDAR frame,
metres).

- ``none``: the detector on the ego's own cloud.
- ``late``: every USV runs the detector on its own cloud in its own LiDAR frame; the boxes are moved into the
  ego LiDAR frame (:func:`transform_boxes`) and merged with rotated NMS at BEV IoU 0.10 (:func:`rotated_nms`,
  ``late_merge="nms"``, the default) or by score-weighted box fusion (:func:`fuse_boxes`, ``late_merge="wbf"``:
  a vessel that several USVs detect gets one averaged box whose score rises with their agreement).
- ``early``: the neighbours' points are moved into the ego LiDAR frame and concatenated with the ego's; the
  detector runs once on the aggregate (cropped to ``crop_m`` around the ego). For the baseline detector each
  agent's cloud first leaves out its rain drops in its own frame (:func:`~mmusv.studies.detection.detector.rain_free`:
  in rain the drops about a neighbour's sensor made a box there, scored 0.97–0.99, which the evaluation ignores as
  it ignores every box centred on a USV). A detector with an ``early``
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
from mmusv.studies.detection.detector import Detector, baseline_detect, rain_free
from mmusv.studies.detection.evaluate import bev_iou
from mmusv.text import given, named

__all__ = [
    "DEFAULT_MODES",
    "LATE_MERGES",
    "MODES",
    "NMS_IOU",
    "WBF_IOU",
    "detector_name",
    "fuse",
    "fuse_boxes",
    "parse_modes",
    "relative",
    "rotated_nms",
    "transform_boxes",
]

MODES = ("none", "late", "early", "intermediate")
DEFAULT_MODES = ("none", "late", "early")
"""The modes any points → boxes detector can run (intermediate fusion needs a learned model)."""
NMS_IOU = 0.10
"""BEV IoU above which late fusion suppresses the lower-scored of two boxes."""
WBF_IOU = 0.3
"""BEV IoU above which :func:`fuse_boxes` takes two boxes for the same vessel (chosen on the validation split of the
bundled dataset from 0.1, 0.2, 0.3 and 0.5; docs/studies/detection.md)."""
LATE_MERGES = ("nms", "wbf")
"""How late fusion merges the USVs' boxes: rotated NMS or score-weighted box fusion."""

Boxes = tuple[np.ndarray, np.ndarray]


def parse_modes(text: str | Sequence[str]) -> tuple[str, ...]:
    """Validated fusion modes from ``"none,late,early"`` or a list, in :data:`MODES` order; an
    :class:`~mmusv.errors.InputError` names ``text`` (``--modes`` in ``mmusv study``, :func:`mmusv.text.given`)."""
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    bad = [s for s in items if s not in MODES]
    if bad or not items:
        what = f"unknown mode(s) {bad}" if bad else "no mode"
        raise InputError(f"{given('text', text)}: {what}; allowed: {', '.join(MODES)}")
    return tuple(m for m in MODES if m in items)


def relative(ego: AgentFrame, other: AgentFrame) -> np.ndarray:
    """``(4, 4)`` float64 transform, ``other``'s LiDAR frame → ``ego``'s LiDAR frame (metres)."""
    out: np.ndarray = invert(ego.lidar) @ other.lidar
    return out


def transform_boxes(m: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """``(M, 7)`` float64 boxes ``x, y, z, l, w, h, yaw`` (metres, radians) moved by the rigid ``(4, 4)``
    transform ``m`` (source frame → target frame): centres transformed, yaw = heading of the transformed box x
    axis in the target xy plane, in [-π, π]; sizes unchanged."""
    b: np.ndarray = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    out: np.ndarray = b.copy()
    if b.shape[0] == 0:
        return out
    out[:, :3] = transform_points(m, b[:, :3])
    heading = np.column_stack([np.cos(b[:, 6]), np.sin(b[:, 6]), np.zeros(len(b))]) @ m[:3, :3].T
    out[:, 6] = np.arctan2(heading[:, 1], heading[:, 0])
    return out


def rotated_nms(boxes: np.ndarray, scores: np.ndarray, *, iou_threshold: float = NMS_IOU) -> np.ndarray:
    """``(K,)`` int64 indices into ``boxes`` ``(M, 7)`` kept by greedy NMS on BEV rotated IoU, in descending
    ``scores`` ``(M,)`` (stable): a box is dropped when its IoU with a kept, higher-scored box exceeds
    ``iou_threshold``."""
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


def fuse_boxes(boxes: np.ndarray, *, scores: np.ndarray, agents: np.ndarray, iou_threshold: float = WBF_IOU) -> Boxes:
    """Score-weighted box fusion of several USVs' boxes ``(M, 7)`` (one frame), ``scores`` ``(M,)`` in [0, 1] and
    the ``agents`` ``(M,)`` that made them. After weighted boxes fusion (Solovyev, Wang and Gabruseva, "Weighted
    boxes fusion: ensembling boxes from different object detection models", Image Vision Comput. 107, 2021),
    greedy in descending score (stable): the highest-scored unused box and every unused box with BEV IoU above
    ``iou_threshold`` with it form a group; of each agent the group keeps its best box; the fused box is the
    score-weighted mean of those in ``x, y, z, l, w, h`` and in heading (as ``2ψ``: a BEV box is the same at ψ
    and ψ + π), its score the noisy-OR ``1 − Π(1 − s)`` of theirs (independent agents that agree make a
    detection likelier; one agent alone keeps its score and box). Returns the fused boxes ``(K, 7)`` float64 (in
    the frame of ``boxes``, metres, radians) and scores ``(K,)`` float64 by descending score (stable)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    ag = np.asarray(agents).reshape(-1)
    if s.size == 0:
        return np.zeros((0, 7)), np.zeros(0)
    order = np.argsort(-s, kind="stable")
    iou = bev_iou(b, b)
    used = np.zeros(len(s), dtype=bool)
    out_b: list[np.ndarray] = []
    out_s: list[float] = []
    for i in order:
        if used[i]:
            continue
        group = order[(~used[order]) & (iou[i, order] > iou_threshold)]
        group = np.unique(np.r_[i, group])
        group = group[np.argsort(-s[group], kind="stable")]
        used[group] = True
        _, first = np.unique(ag[group], return_index=True)
        members = group[np.sort(first)]
        w = s[members] / max(float(s[members].sum()), 1e-12)
        fused = b[i].copy()
        if len(members) > 1:
            fused[:6] = w @ b[members, :6]
            fused[6] = 0.5 * np.arctan2(w @ np.sin(2 * b[members, 6]), w @ np.cos(2 * b[members, 6]))
        out_b.append(fused)
        out_s.append(float(1.0 - np.prod(1.0 - s[members])))
    fb, fs = np.array(out_b), np.array(out_s)
    rank = np.argsort(-fs, kind="stable")
    return fb[rank], fs[rank]


def early_points(
    ego: AgentFrame,
    neighbours: Sequence[AgentFrame],
    *,
    crop_m: float,
    prepare: Callable[[np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:
    """``(N, 4)`` float32 the ego's points and the neighbours' moved into the ego LiDAR frame, cropped to BEV
    distance ``crop_m``; each agent's cloud first through ``prepare`` (``(N, 4)`` in its own LiDAR frame → the
    points to keep), where given."""
    own = prepare or (lambda p: p)
    parts = [own(ego.points).astype(np.float64)]
    for nb in neighbours:
        p = own(nb.points).astype(np.float64)
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
    late_merge: str = "nms",
) -> Boxes:
    """Boxes ``(M, 7)`` ``x, y, z, l, w, h, yaw`` (metres, radians) and scores ``(M,)`` in ``ego``'s LiDAR frame
    for fusion ``mode`` (module docstring), float64 in every mode.
    ``own_detections(agent)`` returns the detector's output on an agent's own cloud (a cache may back it; checked
    and made float64 as the detector's is); ``late_merge``: one of :data:`LATE_MERGES`."""
    who = detector_name(detector)
    # A given own_detections was returned as it came for `none` (float32 stayed float32) while `late` moved the
    # neighbours' boxes to float64 and kept the scores': one dtype whatever the mode and the source.
    source = own_detections or (lambda a: detector(a.points))

    def own(agent: AgentFrame) -> Boxes:
        return _as_boxes(source(agent), who)

    if mode == "none":
        return own(ego)
    if mode == "late":
        if late_merge not in LATE_MERGES:
            raise InputError(f"late merge {late_merge!r}: allowed: {', '.join(LATE_MERGES)}")
        b0, s0 = own(ego)
        bs, ss = [b0], [s0]
        for nb in neighbours:
            b, s = own(nb)
            bs.append(transform_boxes(relative(ego, nb), b))
            ss.append(s)
        boxes, scores = np.concatenate(bs, axis=0), np.concatenate(ss)
        if late_merge == "wbf":
            agents = np.concatenate([np.full(len(x), k) for k, x in enumerate(ss)])
            return fuse_boxes(boxes, scores=scores, agents=agents)
        keep = rotated_nms(boxes, scores)
        return boxes[keep], scores[keep]
    if mode == "early":
        early = getattr(detector, "early", detector)
        # The baseline's rain step needs the sensor at the origin: each cloud leaves its drops out in its own frame.
        prepare = rain_free if early is baseline_detect else None
        return _as_boxes(early(early_points(ego, neighbours, crop_m=crop_m, prepare=prepare)), who)
    if mode == "intermediate":
        inter = getattr(detector, "intermediate", None)
        if inter is None:
            learned = named("model") if named("model") != "model" else "mmusv.learn.detector.load_models"
            raise InputError(f"intermediate fusion needs a learned model ({learned}), not a points -> boxes detector")
        return _as_boxes(inter(ego.points, [(nb.points, relative(ego, nb)) for nb in neighbours]), who)
    raise InputError(f"fusion mode {mode!r}: allowed: {', '.join(MODES)}")


def detector_name(detector: object) -> str:
    """How errors name ``detector``: a user's detector as its ``spec`` was given (``spec = 'pkg.mod:fn'``, ``--detector
    pkg.mod:fn`` from ``mmusv study``: :func:`mmusv.text.given`), else "the detector"."""
    spec = getattr(detector, "spec", None)
    return given("spec", spec) if isinstance(spec, str) else "the detector"


def _as_boxes(out: tuple[np.ndarray, np.ndarray], who: str = "the detector") -> Boxes:
    """A detector's output checked and as float64 ``(M, 7)``, ``(M,)``: finite boxes and scores (a NaN box was a
    shapely traceback, a NaN score ranked anyhow), ``who`` naming the detector in the error."""
    expected = "expected boxes (M, 7) x, y, z, l, w, h, yaw and scores (M,), finite numbers"
    try:
        b, s = out
        boxes = np.asarray(b, dtype=np.float64)
        scores = np.asarray(s, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{who} must return (boxes (M, 7), scores (M,)); {expected}") from None
    if boxes.size == 0:
        boxes = np.zeros((0, 7))
    elif boxes.shape == (7,):  # one box, as a row
        boxes = boxes.reshape(1, 7)
    elif boxes.ndim != 2 or boxes.shape[1] != 7:
        raise InputError(f"{who} returned boxes of shape {boxes.shape}; {expected}")
    if boxes.shape[0] != scores.shape[0]:
        raise InputError(f"{who} returned {boxes.shape[0]} boxes but {scores.shape[0]} scores")
    if not (np.isfinite(boxes).all() and np.isfinite(scores).all()):
        bad = "boxes" if not np.isfinite(boxes).all() else "scores"
        raise InputError(f"{who} returned {bad} that are not finite (NaN or inf); {expected}")
    if (boxes[:, 3:6] < 0).any():  # scored without a word
        raise InputError(f"{who} returned a box of negative size (l, w or h); {expected}, sizes not negative")
    return boxes, scores
