"""The IoU-aware rescoring (mmusv.learn.scorer): features by hand, the blend, and a scorer fitted on synthetic
detections that learns which boxes are tight (refined on their hull's points) and ranks them first."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from mmusv.errors import InputError
from mmusv.learn.refine import RefineParams, surface_points
from mmusv.learn.scorer import (
    FEATURES,
    IoUScorer,
    blend,
    box_features,
    fit_scorer,
    load_scorer,
    second_stage,
)

from learn.test_refine import WATER_Z, faces, iou, water


def test_features_of_a_hand_built_box() -> None:
    p = RefineParams()
    box = np.array([[50.0, 0.0, 0.0, 10.0, 4.0, 3.0, 0.0]])
    net = np.array([[51.0, 0.0, 0.0, 8.0, 4.0, 3.0, 0.3]])
    # 9 points inside (x 46..54 step 1, y = 1), 2 in the margins only (x 58, 59), 1 far away.
    xy = np.array([[46.0 + i, 1.0] for i in range(9)] + [[58.0, 0.0], [59.0, 0.0], [150.0, 0.0]])
    f = box_features(xy, net_boxes=net, boxes=box, scores=np.array([0.8]), p=p)[0]
    want = {
        "score_logit": np.log(0.8 / 0.2),
        "log_length": np.log(10.0),
        "log_beam": np.log(4.0),
        "log_height": np.log(3.0),
        "range_hm": 0.5,
        "log1p_points_in": np.log(10.0),
        "log1p_points_around": np.log(12.0),
        "length_span": 8.0 / 10.0,
        "beam_span": 0.0,
        "log_length_change": np.log(10.0 / 8.0),
        "log_beam_change": 0.0,
        "log1p_centre_shift": np.log(2.0),
        "yaw_change": 0.3,
    }
    assert list(want) == list(FEATURES)
    np.testing.assert_allclose(f, np.array(list(want.values()), dtype=np.float32), rtol=1e-5, atol=1e-6)
    # A heading turned by π is the same heading.
    flipped = box_features(
        xy, net_boxes=net, boxes=box + np.array([0, 0, 0, 0, 0, 0, np.pi]), scores=np.array([0.8]), p=p
    )[0]
    assert flipped[12] == pytest.approx(0.3, abs=1e-5)


def test_blend_is_the_score_at_beta_zero_and_the_iou_at_one() -> None:
    s, q = np.array([0.9, 0.5, 0.2]), np.array([0.1, 0.8, 0.0])
    np.testing.assert_allclose(blend(s, q, 0.0), s)
    np.testing.assert_allclose(blend(s, q, 1.0), [0.1, 0.8, 1e-3])
    np.testing.assert_allclose(blend(s, q, 0.5), np.sqrt(s * np.maximum(q, 1e-3)))


def _scene(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sample ``k``: four hulls, two of them with points on their near faces; a loose network box (1.5 m off,
    a wrong length) on each hull and two boxes on open water, all with random scores."""
    rng = np.random.default_rng(k)
    gt, boxes = [], []
    pts = [water(rng, 1500)]
    for i in range(4):
        r, bearing = rng.uniform(30.0, 140.0), rng.uniform(-np.pi, np.pi)
        ln = rng.uniform(12.0, 50.0)
        g = np.array([r * np.cos(bearing), r * np.sin(bearing), WATER_Z + 2.0, ln, ln / 4, 4.0, rng.uniform(0, np.pi)])
        gt.append(g)
        off = rng.normal(0.0, 1.0, 2)
        off *= 1.5 / np.linalg.norm(off)
        boxes.append(g + np.array([off[0], off[1], 0.0, rng.uniform(-0.25, 0.25) * ln, 0.0, 0.0, 0.0]))
        if i < 2:
            pts.append(faces(g, spacing=0.5))
    for _ in range(2):
        r, bearing = rng.uniform(30.0, 140.0), rng.uniform(-np.pi, np.pi)
        boxes.append(np.array([r * np.cos(bearing), r * np.sin(bearing), WATER_Z + 2.0, 20.0, 5.0, 4.0, 0.0]))
    scores = rng.uniform(0.2, 0.9, len(boxes))
    return np.concatenate(pts).astype(np.float32), np.array(boxes), scores, np.array(gt)


def test_fitted_scorer_ranks_the_tight_boxes_first(tmp_path: Path) -> None:
    p = RefineParams()
    ks = list(range(60))
    scorer, fit = fit_scorer(_scene, samples=ks, groups=[k // 3 for k in ks], refine=p, nms_iou=0.1, seed=0, epochs=300)
    # The refined boxes on seen hulls are tight (the rule of mmusv.learn.refine), the others loose.
    pts, boxes, scores, gt = _scene(1000)
    xy = surface_points(pts, p)
    out_b, out_s = second_stage(pts, boxes=boxes, scores=scores, refine=p, scorer=scorer, nms_iou=0.1)
    seen = [i for i in range(len(out_b)) if max(iou(out_b[i], g) for g in gt[:2]) > 0.8]
    others = [i for i in range(len(out_b)) if i not in seen]
    assert len(seen) == 2 and others
    q = scorer.iou(box_features(xy, net_boxes=out_b, boxes=out_b, scores=out_s, p=p))
    assert min(q[seen]) > max(q[others]) + 0.1, (q, seen)
    # On the held-out sequences, ranking by the predicted IoU beats the network's (random) scores at AP@0.7.
    by_beta = {b: (a5, a7) for b, a5, a7 in fit.held_out}
    assert fit.beta > 0 and by_beta[fit.beta][1] > by_beta[0.0][1] + 0.15, fit
    # Saved and read back: the same predictions; the same seed gives the same weights.
    path = scorer.save(tmp_path / "scorer.pt", {"note": "test"})
    again = load_scorer(path)
    f = box_features(xy, net_boxes=boxes, boxes=boxes, scores=scores, p=p)
    np.testing.assert_array_equal(again.iou(f), scorer.iou(f))
    assert again.beta == scorer.beta
    twin, _ = fit_scorer(_scene, samples=ks, groups=[k // 3 for k in ks], refine=p, nms_iou=0.1, seed=0, epochs=300)
    assert all(torch.equal(a, b) for a, b in zip(twin.state_dict().values(), scorer.state_dict().values(), strict=True))


def test_too_few_boxes_and_foreign_files_are_clear_errors(tmp_path: Path) -> None:
    def empty(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return np.zeros((0, 4), np.float32), np.zeros((0, 7)), np.zeros(0), np.zeros((1, 7))

    with pytest.raises(InputError, match="found 0 boxes"):
        fit_scorer(empty, samples=list(range(10)), groups=list(range(10)), refine=RefineParams(), nms_iou=0.1)
    bad = tmp_path / "scorer.pt"
    torch.save({"features": ["other"], "state": {}, "beta": 0.5}, bad)
    with pytest.raises(InputError, match=r"not an mmusv\.learn scorer"):
        load_scorer(bad)
    n = len(FEATURES)
    m = IoUScorer(np.zeros(n), np.ones(n), beta=0.0)
    s = np.array([0.3, 0.7])
    np.testing.assert_allclose(m.rescore(np.zeros((2, n), np.float32), s), s)
