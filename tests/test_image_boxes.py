"""The image geometry of the 2D boxes (:mod:`mmusv.image_boxes`) against independent computations: the part of a
box above a level as scipy's half-space intersection gives it, the image of that part inside the image against
densely sampled points projected here, and bad input refused by name."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from mmusv.boxes3d import box_corners
from mmusv.errors import InputError
from mmusv.image_boxes import clip_box, faces_above, faces_in_image_box, in_image_box, pinhole_truncation, project_box
from scipy.spatial import ConvexHull, HalfspaceIntersection
from scipy.spatial.transform import Rotation

K = (100.0, 100.0, 80.0, 60.0)


def _box(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("xyz", rng.uniform(-0.4, 0.4, 3) * [1, 1, 8]).as_matrix()
    m[:3, 3] = rng.uniform(-2.0, 2.0, 3)
    size = rng.uniform(0.5, 6.0, 3)
    return m, size


def test_the_part_above_a_level_is_the_half_space_intersection() -> None:
    rng = np.random.default_rng(7)
    straddling = 0
    for _ in range(200):
        m, size = _box(rng)
        level = float(rng.uniform(-1.0, 1.0))
        faces = faces_above(box_corners(m, size), level=level)
        c = box_corners(m, size)
        if c[:, 2].min() >= level:
            assert len(faces) == 6
        if c[:, 2].max() <= level:
            assert faces == []
            continue
        # independent: the box's six half-spaces and z >= level (scipy's Ax + b <= 0), about an inside point
        r, t = m[:3, :3], m[:3, 3]
        hs = [np.r_[s * r[:, k], -(s * r[:, k] @ t) - size[k] / 2] for k in range(3) for s in (1.0, -1.0)]
        hs.append(np.array([0.0, 0.0, -1.0, level]))
        top = c[np.argmax(c[:, 2])]
        inside = top + (t - top) * 1e-3 + np.array([0, 0, -1e-4])
        inside = inside if inside[2] > level else top + (t - top) * 1e-6
        if inside[2] <= level + 1e-9:
            continue  # a sliver too thin for a strictly inside point
        want = ConvexHull(HalfspaceIntersection(np.array(hs), inside).intersections).volume
        got = ConvexHull(np.concatenate(faces)).volume
        assert got == pytest.approx(want, rel=1e-9, abs=1e-12)
        assert all(f[:, 2].min() >= level - 1e-9 for f in faces)
        if c[:, 2].min() < level:  # the cap: in the plane, its corners in turn round it (a simple polygon)
            cap = faces[-1]
            assert np.allclose(cap[:, 2], level)
            x, y = cap[:, 0], cap[:, 1]
            shoelace = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
            assert shoelace == pytest.approx(ConvexHull(cap[:, :2]).volume, rel=1e-9)
            straddling += 1
    assert straddling > 50


def test_the_image_of_the_part_above_the_water_against_sampled_points() -> None:
    """The pixel box of the part of a box above z = 0 inside a 160 x 120 pinhole image: its points sampled densely
    and projected here bound it (within the sampling's reach)."""
    rng = np.random.default_rng(3)
    checked = 0
    s, t = (x.ravel() for x in np.meshgrid(np.linspace(0.0, 1.0, 121), np.linspace(0.0, 1.0, 121)))
    for _ in range(60):
        m, size = _box(rng)
        m[:3, 3] += [0.0, 0.0, rng.uniform(4.0, 12.0)]  # in front of a camera looking along z (optical frame)
        c = box_corners(m, size)
        level = float(np.median(c[:, 1]))  # the part on one side of a plane y = level (optical y)
        swap = np.eye(3)[[0, 2, 1]]  # y and z swapped, so that the plane is a z level for faces_above
        faces = [f @ swap for f in faces_above(c @ swap, level=level)]
        got = faces_in_image_box(faces, intrinsics=K, lens=None, width=160, height=120)
        # independent: the box's surface sampled on each face (corner bit k fixed), kept where y >= level
        pts = []
        for k in range(3):
            a, b = [j for j in range(3) if j != k]
            for side in (0, 1):
                q = {(i >> a & 1, i >> b & 1): c[i] for i in range(8) if (i >> k & 1) == side}
                pts.append(
                    np.outer((1 - s) * (1 - t), q[0, 0]) + np.outer(s * (1 - t), q[1, 0])
                    + np.outer((1 - s) * t, q[0, 1]) + np.outer(s * t, q[1, 1])
                )  # fmt: skip
        p = np.concatenate(pts)
        p = p[(p[:, 1] >= level) & (p[:, 2] > 0.05)]
        u, v = K[0] * p[:, 0] / p[:, 2] + K[2], K[1] * p[:, 1] / p[:, 2] + K[3]
        inside = (u >= 0) & (u <= 160) & (v >= 0) & (v <= 120)
        if got is None:
            assert not inside.any()
            continue
        if not inside.any():
            continue  # a sliver in the image between the samples
        want = np.array([u[inside].min(), v[inside].min(), u[inside].max(), v[inside].max()])
        assert np.all(got[:2] <= want[:2] + 1e-6) and np.all(got[2:] >= want[2:] - 1e-6)  # it bounds every point
        assert np.abs(got - want).max() < 2.0, (got, want)  # and not more (the samples' spacing)
        checked += 1
    assert checked > 30


def test_a_whole_box_is_in_image_box_of_its_six_faces() -> None:
    rng = np.random.default_rng(11)
    for _ in range(30):
        m, size = _box(rng)
        m[:3, 3] += [0.0, 0.0, 6.0]
        c = box_corners(m, size)
        whole = faces_above(c, level=c[:, 2].min() - 1.0)
        a = in_image_box(c, intrinsics=K, lens=None, width=160, height=120)
        b = faces_in_image_box(whole, intrinsics=K, lens=None, width=160, height=120)
        assert (a is None) == (b is None)
        if a is not None and b is not None:
            np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda f: f["project_box"](np.zeros((3, 3)), intrinsics=K), "corners_opt must be a box's (8, 3) corners"),
        (lambda f: f["project_box"](np.full((8, 3), np.nan), intrinsics=K), "corners_opt must be"),
        (lambda f: f["project_box"](np.ones((8, 3)), intrinsics=(0.0, 1.0, 0.0, 0.0)), "fx and fy > 0"),
        (lambda f: f["project_box"](np.ones((8, 3)), intrinsics=(1.0, 2.0)), "intrinsics must be (fx, fy, cx, cy)"),
        (lambda f: f["clip_box"]([0, 0, 1], width=4, height=4), "box must be a pixel box"),
        (lambda f: f["clip_box"]([0, 0, 1, 1], width=0, height=4), "width"),
        (lambda f: f["faces_above"](np.zeros((8, 2))), "corners_world must be a box's (8, 3) corners"),
        (lambda f: f["faces_above"](np.zeros((8, 3)), level=np.inf), "level"),
        (lambda f: f["pinhole_truncation"]("abc", intrinsics=K, width=4, height=4), "corners_opt must be"),
        (lambda f: f["in_image_box"](np.ones((8, 3)), intrinsics=K, lens=None, width=-1, height=4), "width"),
    ],
)
def test_bad_input_is_refused_by_name(call: Any, words: str) -> None:
    funcs = {
        "project_box": project_box,
        "clip_box": clip_box,
        "faces_above": faces_above,
        "pinhole_truncation": pinhole_truncation,
        "in_image_box": in_image_box,
    }
    with pytest.raises(InputError, match=None) as err:
        call(funcs)
    assert words in str(err.value), str(err.value)
