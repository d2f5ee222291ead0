"""The detection evaluator against values worked out by hand and against OpenCOOD's documented algorithm."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mmusv.studies.detection.evaluate import (
    FrameMatch,
    average_precision,
    bev_iou,
    match_frame,
    range_bin,
    summarize,
    voc_ap,
)


def box(x: float, y: float, length: float = 4.0, w: float = 2.0, yaw: float = 0.0) -> list[float]:
    return [x, y, 0.0, length, w, 1.5, yaw]


# ---- IoU ---------------------------------------------------------------------------------------------------------


def test_identical_boxes_iou_one_and_ap_one() -> None:
    b = np.array([box(10, 5, yaw=0.3), box(-20, 40, 6, 3, -1.0)])
    assert np.allclose(np.diag(bev_iou(b, b)), 1.0)
    fm = FrameMatch.evaluate(b, det_scores=np.array([0.9, 0.8]), gt_boxes=b)
    m = summarize([fm])
    assert m["ap30"] == m["ap50"] == m["ap70"] == 1.0
    assert m["precision50"] == m["recall50"] == 1.0


@pytest.mark.parametrize(
    ("dx", "dy", "expected"),
    [
        (1.0, 0.0, 6.0 / 10.0),  # 3 x 2 overlap of two 4 x 2 boxes: 6 / (8 + 8 - 6)
        (1.0, 0.5, 4.5 / 11.5),  # 3 x 1.5 overlap
        (0.0, 2.0, 0.0),  # touching edge
        (5.0, 0.0, 0.0),  # apart
    ],
)
def test_shifted_boxes_analytic_iou(dx: float, dy: float, expected: float) -> None:
    iou = bev_iou([box(0, 0)], [box(dx, dy)])[0, 0]
    assert iou == pytest.approx(expected, abs=1e-12)


def test_rotated_square_45_degrees_is_one_over_sqrt2() -> None:
    # Square of half side 1: the overlap is a regular octagon of area 8(√2 − 1); IoU = 1/√2.
    iou = bev_iou([box(3, -2, 2, 2, 0.0)], [box(3, -2, 2, 2, math.pi / 4)])[0, 0]
    assert iou == pytest.approx(1 / math.sqrt(2), abs=1e-12)


def test_rotated_90_degrees_and_180_degrees() -> None:
    # 4 x 2 box against itself turned 90°: 2 x 2 overlap, 4 / (8 + 8 - 4) = 1/3; turned 180° it is the same box.
    assert bev_iou([box(0, 0)], [box(0, 0, yaw=math.pi / 2)])[0, 0] == pytest.approx(1 / 3, abs=1e-12)
    assert bev_iou([box(0, 0)], [box(0, 0, yaw=math.pi)])[0, 0] == pytest.approx(1.0, abs=1e-12)


# ---- matching ----------------------------------------------------------------------------------------------------


def test_duplicate_detection_is_a_false_positive() -> None:
    gt = np.array([box(0, 0)])
    dets = np.array([box(0.2, 0), box(0.1, 0)])  # both overlap; the higher score takes the GT
    m = match_frame(dets, det_scores=np.array([0.9, 0.5]), gt_boxes=gt, iou_threshold=0.5)
    assert m.tolist() == [0, -1]
    # Score order decides, not IoU: the worse-overlapping but higher-scored box takes the GT.
    m = match_frame(dets, det_scores=np.array([0.5, 0.9]), gt_boxes=gt, iou_threshold=0.5)
    assert m.tolist() == [-1, 0]
    s = summarize([FrameMatch.evaluate(dets, det_scores=np.array([0.9, 0.5]), gt_boxes=gt)])
    assert s["precision50"] == 0.5 and s["recall50"] == 1.0
    assert s["ap50"] == 1.0  # PR points (1, 1), (1, 0.5): all-point area 1


def test_best_unmatched_gt_is_taken() -> None:
    gt = np.array([box(0, 0), box(1.0, 0)])  # det 0 overlaps gt 1 best (IoU 1), det 1 then gets gt 0
    dets = np.array([box(1.0, 0), box(0.3, 0)])
    assert match_frame(dets, det_scores=np.array([0.9, 0.8]), gt_boxes=gt, iou_threshold=0.5).tolist() == [1, 0]


def test_iou_threshold_is_inclusive_and_levels_differ() -> None:
    gt = np.array([box(0, 0)])
    det = np.array([box(1.0, 0)])  # IoU 0.6
    fm = FrameMatch.evaluate(det, det_scores=np.array([1.0]), gt_boxes=gt)
    assert fm.matches[0.3].tolist() == [0] and fm.matches[0.5].tolist() == [0] and fm.matches[0.7].tolist() == [-1]
    exact = np.array([box(0, 0, 4.0, 2.0)])
    half = np.array([box(0, 0, 2.0, 2.0)])  # inside: IoU exactly 0.5
    assert match_frame(half, det_scores=np.array([1.0]), gt_boxes=exact, iou_threshold=0.5).tolist() == [0]


def test_misses_lower_recall_and_ap() -> None:
    gt = np.array([box(0, 0), box(30, 0)])
    fm = FrameMatch.evaluate(np.array([box(0, 0)]), det_scores=np.array([0.7]), gt_boxes=gt)
    s = summarize([fm])
    assert s["recall50"] == 0.5 and s["precision50"] == 1.0 and s["ap50"] == pytest.approx(0.5)


def test_empty_frames() -> None:
    no_gt = FrameMatch.evaluate(np.array([box(5, 5)]), det_scores=np.array([0.9]), gt_boxes=np.zeros((0, 7)))
    no_det = FrameMatch.evaluate(np.zeros((0, 7)), det_scores=np.zeros(0), gt_boxes=np.array([box(0, 0)]))
    both = FrameMatch.evaluate(np.zeros((0, 7)), det_scores=np.zeros(0), gt_boxes=np.zeros((0, 7)))
    assert no_gt.matches[0.5].tolist() == [-1]
    assert math.isnan(summarize([no_gt])["ap50"])  # nothing to find: AP undefined
    assert summarize([no_det])["ap50"] == 0.0  # nothing found
    assert math.isnan(summarize([no_det])["precision50"])
    assert math.isnan(summarize([both])["ap50"])
    # A frame without ground truth adds its false positives to the others: one TP (0.8) and one FP (0.9).
    hit = FrameMatch.evaluate(np.array([box(0, 0)]), det_scores=np.array([0.8]), gt_boxes=np.array([box(0, 0)]))
    s = summarize([no_gt, hit, both])
    assert s["precision50"] == 0.5 and s["recall50"] == 1.0
    assert s["ap50"] == pytest.approx(0.5)  # PR: (0, 0) then (1, 0.5)
    assert math.isnan(summarize([])["ap50"])


# ---- AP ----------------------------------------------------------------------------------------------------------


def test_ap_interpolation_on_a_hand_computed_curve() -> None:
    # Scores descending: TP FP TP FP TP, 4 ground truths.
    # recall .25 .25 .5 .5 .75, precision 1 .5 2/3 .5 .6; interpolated precision at the recall steps:
    # .25 → 1, .5 → 2/3, .75 → .6, 1 → 0: AP = .25·(1 + 2/3 + .6) = 0.5666…
    expected = 0.25 * (1 + 2 / 3 + 0.6)
    assert average_precision(
        np.array([0.9, 0.8, 0.7, 0.6, 0.5]), tp=np.array([1, 0, 1, 0, 1], bool), n_gt=4
    ) == pytest.approx(expected, abs=1e-12)
    assert voc_ap(np.array([0.25, 0.25, 0.5, 0.5, 0.75]), np.array([1, 0.5, 2 / 3, 0.5, 0.6])) == pytest.approx(
        expected, abs=1e-12
    )
    # The same curve built from boxes over two frames (global sort by score across frames).
    gts = [np.array([box(0, 0), box(20, 0)]), np.array([box(0, 0), box(20, 0)])]
    f1 = FrameMatch.evaluate(
        np.array([box(0, 0), box(50, 50), box(20, 0)]), det_scores=np.array([0.9, 0.6, 0.5]), gt_boxes=gts[0]
    )
    f2 = FrameMatch.evaluate(np.array([box(60, 60), box(0, 0)]), det_scores=np.array([0.8, 0.7]), gt_boxes=gts[1])
    assert summarize([f1, f2])["ap50"] == pytest.approx(expected, abs=1e-12)


# ---- range bins --------------------------------------------------------------------------------------------------


def test_range_bins() -> None:
    xy = np.array([[0, 0], [49.9, 0], [50, 0], [0, -120], [141, 141], [200, 0], [250, 0]], dtype=float)
    assert range_bin(xy).tolist() == [0, 0, 1, 2, 3, -1, -1]


def test_ap_per_range_bin() -> None:
    gt = np.array([box(30, 0), box(0, 120), box(50.5, 0, 4, 2)])
    dets = np.array([box(30, 0), box(49.8, 0, 4, 2), box(170, 0)])  # TP (0-50), TP (its GT at 50.5), FP (150-200)
    fm = FrameMatch.evaluate(dets, det_scores=np.array([0.9, 0.8, 0.7]), gt_boxes=gt)
    assert fm.det_bins(0.5).tolist() == [0, 1, 3]
    s = summarize([fm])
    assert s["ap50_0-50"] == 1.0
    assert s["ap50_50-100"] == 1.0  # the TP counts in its GT's bin
    assert s["ap50_100-150"] == 0.0  # a GT, no detection
    assert math.isnan(s["ap50_150-200"])  # an FP, no GT


# ---- OpenCOOD's eval_utils, rewritten from its documented algorithm -----------------------------------------------


def _clip(subject: list[tuple[float, float]], clipper: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Sutherland–Hodgman clipping of a polygon by a convex counter-clockwise polygon (no shapely)."""
    out = subject
    for i in range(len(clipper)):
        a, b = clipper[i], clipper[(i + 1) % len(clipper)]

        def inside(p: tuple[float, float], a: tuple[float, float] = a, b: tuple[float, float] = b) -> bool:
            return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0

        def cut(
            p: tuple[float, float], q: tuple[float, float], a: tuple[float, float] = a, b: tuple[float, float] = b
        ) -> tuple[float, float]:
            d1 = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
            d2 = (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
            t = d1 / (d1 - d2)
            return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))

        inp, out = out, []
        for j in range(len(inp)):
            p, q = inp[j], inp[(j + 1) % len(inp)]
            if inside(q):
                if not inside(p):
                    out.append(cut(p, q))
                out.append(q)
            elif inside(p):
                out.append(cut(p, q))
        if not out:
            return []
    return out


def _area(poly: list[tuple[float, float]]) -> float:
    return (
        0.5
        * abs(
            sum(
                poly[i][0] * poly[(i + 1) % len(poly)][1] - poly[(i + 1) % len(poly)][0] * poly[i][1]
                for i in range(len(poly))
            )
        )
        if len(poly) >= 3
        else 0.0
    )


def _corners(b: np.ndarray) -> list[tuple[float, float]]:
    c, s = math.cos(b[6]), math.sin(b[6])
    return [
        (b[0] + c * dx - s * dy, b[1] + s * dx + c * dy)
        for dx, dy in ((b[3] / 2, b[4] / 2), (-b[3] / 2, b[4] / 2), (-b[3] / 2, -b[4] / 2), (b[3] / 2, -b[4] / 2))
    ]


def _ref_iou(a: np.ndarray, b: np.ndarray) -> float:
    pa, pb = _corners(a), _corners(b)
    inter = _area(_clip(pa, pb))
    return inter / (_area(pa) + _area(pb) - inter)


def _ref_ap(frames: list[tuple[np.ndarray, np.ndarray, np.ndarray]], thr: float) -> float:
    """OpenCOOD: per frame, detections by descending score; each takes the max-IoU ground truth left in the list
    (popped) when that IoU ≥ thr, else is an FP. Then every detection sorted globally by score, cumulative TP/FP,
    recall = TP/GT, precision = TP/(TP+FP); VOC 2010 AP (pad, make precision monotone, sum over recall steps)."""
    tps: list[int] = []
    scores: list[float] = []
    n_gt = 0
    for dets, sc, gts in frames:
        n_gt += len(gts)
        remaining = list(gts)
        for i in sorted(range(len(dets)), key=lambda k: -sc[k]):
            ious = [_ref_iou(dets[i], g) for g in remaining]
            if not remaining or max(ious) < thr:
                tps.append(0)
            else:
                tps.append(1)
                remaining.pop(int(np.argmax(ious)))
            scores.append(float(sc[i]))
    order = sorted(range(len(scores)), key=lambda k: -scores[k])
    tp_c = fp_c = 0
    rec, prec = [], []
    for k in order:
        tp_c += tps[k]
        fp_c += 1 - tps[k]
        rec.append(tp_c / n_gt)
        prec.append(tp_c / (tp_c + fp_c))
    mrec = [0.0, *rec, 1.0]
    mpre = [0.0, *prec, 0.0]
    for i in range(len(mpre) - 2, -1, -1):
        mpre[i] = max(mpre[i], mpre[i + 1])
    return sum((mrec[i] - mrec[i - 1]) * mpre[i] for i in range(1, len(mrec)) if mrec[i] != mrec[i - 1])


@pytest.mark.parametrize("seed", range(8))
def test_matches_opencood_algorithm_on_random_cases(seed: int) -> None:
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(int(rng.integers(1, 6))):
        n = int(rng.integers(0, 6))
        gts = np.column_stack(
            [
                rng.uniform(-60, 60, (n, 2)),
                np.zeros(n),
                rng.uniform(3, 15, n),
                rng.uniform(1.5, 5, n),
                np.full(n, 2.0),
                rng.uniform(-np.pi, np.pi, n),
            ]
        )
        hit = gts[rng.random(n) < 0.8].copy()
        hit[:, :2] += rng.normal(0, 0.8, (len(hit), 2))
        hit[:, 3:5] *= rng.uniform(0.7, 1.3, (len(hit), 2))
        hit[:, 6] += rng.normal(0, 0.2, len(hit))
        dup = hit[: int(rng.integers(0, len(hit) + 1))].copy()
        dup[:, :2] += rng.normal(0, 0.5, (len(dup), 2))
        k = int(rng.integers(0, 4))
        fps = np.column_stack(
            [
                rng.uniform(-60, 60, (k, 2)),
                np.zeros(k),
                rng.uniform(3, 15, k),
                rng.uniform(1.5, 5, k),
                np.full(k, 2.0),
                rng.uniform(-np.pi, np.pi, k),
            ]
        )
        dets = np.concatenate([hit, dup, fps]).reshape(-1, 7)
        frames.append(
            (
                dets,
                rng.permutation(len(dets)) / 10.0 + rng.random() * 1e-3 + rng.random(len(dets)) * 1e-4,
                gts.reshape(-1, 7),
            )
        )
    got = summarize([FrameMatch.evaluate(d, det_scores=s, gt_boxes=g) for d, s, g in frames])
    if sum(len(g) for _, _, g in frames) == 0:
        assert math.isnan(got["ap50"])
        return
    for thr, key in ((0.3, "ap30"), (0.5, "ap50"), (0.7, "ap70")):
        assert got[key] == pytest.approx(_ref_ap(frames, thr), abs=1e-9)


def test_reference_iou_agrees_with_shapely_on_random_boxes() -> None:
    rng = np.random.default_rng(7)
    a = np.column_stack(
        [rng.uniform(-3, 3, (30, 2)), np.zeros(30), rng.uniform(1, 8, (30, 2)), np.ones(30), rng.uniform(-4, 4, 30)]
    )
    b = a.copy()
    b[:, :2] += rng.normal(0, 1.5, (30, 2))
    b[:, 6] += rng.normal(0, 0.7, 30)
    got = bev_iou(a, b)
    for i in range(30):
        assert got[i, i] == pytest.approx(_ref_iou(a[i], b[i]), abs=1e-9)
