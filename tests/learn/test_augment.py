"""Augmentation keeps points, boxes and neighbour poses consistent, and is seeded."""

from __future__ import annotations

import numpy as np
import shapely
from mmusv.learn.augment import Augmentation, apply, draw
from mmusv.learn.example import early_cloud
from mmusv.learn.presets import preset
from mmusv.studies.detection.evaluate import box_polygons

from learn.scenes import SCENES, scene


def _inside(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    polys = box_polygons(boxes)
    return np.array([shapely.contains_xy(poly, points[:, 0], points[:, 1]).sum() for poly in polys])


def test_points_stay_in_their_boxes() -> None:
    boxes = SCENES[0]
    pts = scene(boxes, 0)
    grown = boxes.copy()
    grown[:, 3:5] += 0.02  # points lie on the sides
    before = _inside(pts, grown)
    for a in (Augmentation(flip=True, angle=0.7, scale=1.05), Augmentation(angle=-2.0, scale=0.95)):
        p2, _, b2 = apply(a, ego=pts, neighbours=[], boxes=boxes)
        g2 = b2.copy()
        g2[:, 3:5] += 0.03
        assert (_inside(p2, g2) == before).all()


def test_neighbour_points_land_where_the_ego_sees_them() -> None:
    rng = np.random.default_rng(1)
    nb_pts = np.column_stack([rng.uniform(-20, 20, (50, 3)), rng.random(50)]).astype(np.float32)
    c, s = np.cos(0.4), np.sin(0.4)
    rel = np.array([[c, -s, 0, 30.0], [s, c, 0, -10.0], [0, 0, 1, 0.5], [0, 0, 0, 1]])
    ego = np.zeros((0, 4), np.float32)
    a = Augmentation(flip=True, angle=1.1, scale=1.04)
    want = early_cloud(*apply(a, ego=early_cloud(ego, [(nb_pts, rel)]), neighbours=[], boxes=np.zeros((0, 7)))[:1], [])
    e2, nbs2, _ = apply(a, ego=ego, neighbours=[(nb_pts, rel)], boxes=np.zeros((0, 7)))
    np.testing.assert_allclose(early_cloud(e2, nbs2), want, atol=1e-4)


def test_draws_are_seeded() -> None:
    p = preset("cpu")
    a = [draw(np.random.default_rng([0, 1, 5]), p) for _ in range(2)]
    b = draw(np.random.default_rng([0, 2, 5]), p)
    assert a[0] == a[1] and a[0] != b
