"""CenterPoint targets for a hand-worked scene."""

from __future__ import annotations

import math

import numpy as np
from mmusv.learn.presets import preset
from mmusv.learn.targets import center_targets, draw_gaussian, gaussian_radius, points_in_boxes
from mmusv.studies.detection.study import gt_visibility

from learn.scenes import SCENES


def test_gaussian_radius_by_hand() -> None:
    # l = 4, w = 2 cells, overlap 0.1: the three cases give 4.5667, 8.6833 and 1.2 (worked on paper);
    # the third, r3 = (-1.2 + sqrt(1.44 + 4 * 0.4 * 7.2)) / 2 = (-1.2 + 3.6) / 2, is the smallest
    assert math.isclose(gaussian_radius(4.0, 2.0, min_overlap=0.1), 1.2, rel_tol=1e-12)


def test_draw_gaussian_values_and_clipping() -> None:
    h = np.zeros((5, 5), np.float32)
    draw_gaussian(h, (0, 1), 1)  # sigma = 0.5, clipped on the left edge
    assert h[1, 0] == 1.0
    assert math.isclose(h[1, 1], math.exp(-1 / (2 * 0.25)), rel_tol=1e-6)
    assert math.isclose(h[0, 1], math.exp(-2 / (2 * 0.25)), rel_tol=1e-6)
    assert h[:, 2:].sum() == 0 and h[3:].sum() == 0


def test_center_targets_for_a_hand_worked_scene() -> None:
    # tiny preset: 1 m cells over [-32, 32) m, output stride 1, least radius 1
    p = preset("tiny")
    boxes = np.array(
        [
            [2.25, -3.5, 1.0, 4.0, 2.0, 3.0, math.pi / 6],  # cell (ix 34, iy 28), offset (0.25, 0.5)
            [40.0, 0.0, 0.0, 4.0, 2.0, 2.0, 0.0],  # off the grid: no target
            [-31.9, 31.9, 2.0, 8.0, 3.0, 2.0, -math.pi / 2],  # corner cell (0, 63)
        ]
    )
    t = center_targets(boxes, p, max_objects=4)
    nx, _ = p.out_grid
    assert t.mask.tolist() == [True, True, False, False]
    assert t.index[:2].tolist() == [28 * nx + 34, 63 * nx + 0]
    a = 2 * math.pi / 6  # the preset regresses twice the yaw
    np.testing.assert_allclose(
        t.reg[0], [0.25, 0.5, 1.0, math.log(4), math.log(2), math.log(3), math.sin(a), math.cos(a)], atol=1e-6
    )
    np.testing.assert_allclose(t.reg[1, :2], [0.1, 0.9], atol=1e-5)
    np.testing.assert_allclose(t.reg[1, 6:], [math.sin(-math.pi), math.cos(-math.pi)], atol=1e-6)
    heat = t.heatmap[0]
    assert heat[28, 34] == 1.0 and heat[63, 0] == 1.0
    # radius of box 1: gaussian_radius(4, 2) = 1.2 -> 1 cell, sigma 0.5: neighbours at exp(-2), corners exp(-4)
    assert math.isclose(heat[28, 35], math.exp(-2), rel_tol=1e-6)
    assert math.isclose(heat[29, 35], math.exp(-4), rel_tol=1e-6)
    assert heat[28, 36] == 0.0
    # box 3 (8 x 3 cells): radius floor(2.04) = 2, its 5x5 patch clipped by the corner to 3 rows x 3 columns
    assert math.isclose(heat[61, 2], math.exp(-8 / (2 * (5 / 6) ** 2)), rel_tol=1e-6)
    assert np.count_nonzero(heat) == 9 + 9


def test_dense_regression_rows_around_the_centre() -> None:
    # tiny preset with reg_radius 1: the box's 3x3 cells get rows; each row's offset is the centre minus that
    # cell's corner, its weight the box's Gaussian there; a cell held by another box's centre is skipped
    p = preset("tiny", reg_radius=1)
    boxes = np.array(
        [
            [2.25, -3.5, 1.0, 4.0, 2.0, 3.0, 0.0],  # centre cell (ix 34, iy 28), offset (0.25, 0.5), radius 1
            [3.5, -3.5, 1.0, 4.0, 2.0, 3.0, 0.0],  # centre cell (35, 28): inside the first box's 3x3
        ]
    )
    t = center_targets(boxes, p, max_objects=2)
    nx, _ = p.out_grid
    assert t.index.shape == (2 * 9,) and t.weight.shape == (2 * 9,)
    assert t.mask.tolist() == [True, True] + [False] * 16  # the centre rows mark the objects
    assert t.index[:2].tolist() == [28 * nx + 34, 28 * nx + 35]
    np.testing.assert_allclose(t.weight[:2], [1.0, 1.0])
    rows = {int(i): (r, w) for i, r, w in zip(t.index[2:], t.reg[2:], t.weight[2:], strict=True) if w > 0}
    # box 1: 8 neighbours minus (35, 28), box 2's centre (7 rows); box 2: its 8 minus (34, 28) and the four
    # cells box 1 took (3 rows)
    first = {(iy * nx + ix) for iy in (27, 28, 29) for ix in (33, 34, 35)} - {28 * nx + 34, 28 * nx + 35}
    second = {(iy * nx + ix) for iy in (27, 28, 29) for ix in (36,)}
    assert set(rows) == first | second
    r, w = rows[29 * nx + 33]  # box 1, one cell up-left: offset (0.25 + 1, 0.5 - 1), weight exp(-2 / (2 * 0.25))
    np.testing.assert_allclose(r[:2], [1.25, -0.5], atol=1e-6)
    assert math.isclose(w, math.exp(-4.0), rel_tol=1e-6)
    r, w = rows[28 * nx + 36]  # box 2, one cell right: offset (0.5 - 1, 0.5)
    np.testing.assert_allclose(r[:2], [-0.5, 0.5], atol=1e-6)
    assert math.isclose(w, math.exp(-2.0), rel_tol=1e-6)
    np.testing.assert_allclose(t.reg[2:][t.weight[2:] > 0][:, 2:6], [[1.0, math.log(4), math.log(2), math.log(3)]] * 10)


def test_points_in_boxes_matches_the_study_visibility_rule() -> None:
    # the numpy count against the detection study's shapely count: random points (none on a box's boundary,
    # where the two may round differently) in rotated boxes, one of them flat at the water line
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-30, 30, (20000, 2)), rng.uniform(-4, 6, 20000), rng.random(20000)])
    for boxes in SCENES:
        b = np.concatenate([boxes, [[0.0, 0.0, -2.5, 40.0, 20.0, 1.0, 0.4]]])
        got = points_in_boxes(pts, b)
        np.testing.assert_array_equal(got, gt_visibility(b, pts))
        assert (got > 0).all()
