"""Pillarization and scatter against a plain-Python reference (one point at a time)."""

from __future__ import annotations

import numpy as np
import torch
from mmusv.learn.pillars import pillar_centres, pillarize, scatter, scatter_max
from mmusv.learn.presets import preset


def _reference(points: np.ndarray, p) -> dict[tuple[int, int], list[np.ndarray]]:
    cells: dict[tuple[int, int], list[np.ndarray]] = {}
    for q in points:
        ix = int(np.floor((q[0] - p.x_range[0]) / p.pillar_m))
        iy = int(np.floor((q[1] - p.y_range[0]) / p.pillar_m))
        nx, ny = p.grid
        if 0 <= ix < nx and 0 <= iy < ny and p.z_range[0] <= q[2] < p.z_range[1]:
            cells.setdefault((iy, ix), []).append(q)
    return cells


def test_pillarize_matches_a_point_by_point_reference() -> None:
    p = preset("tiny", max_points=4, max_pillars=10_000)
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-40, 40, (3000, 2)), rng.uniform(-8, 18, 3000), rng.random(3000)])
    pts = pts.astype(np.float32)
    got = pillarize(pts, p)
    ref = _reference(pts, p)
    assert sorted(map(tuple, got.coords.tolist())) == sorted(ref)
    for feats, mask, (iy, ix) in zip(got.features, got.mask, got.coords, strict=True):
        members = np.array(ref[(int(iy), int(ix))], dtype=np.float64)
        kept = members[: p.max_points]  # the first points, in cloud order
        assert mask.sum() == len(kept)
        mean = kept[:, :3].mean(axis=0)
        cx = p.x_range[0] + (ix + 0.5) * p.pillar_m
        cy = p.y_range[0] + (iy + 0.5) * p.pillar_m
        want = np.column_stack(
            [
                kept[:, 0] / 100,
                kept[:, 1] / 100,
                kept[:, 2] / 10,
                kept[:, 3],
                kept[:, :3] - mean,
                kept[:, 0] - cx,
                kept[:, 1] - cy,
            ]
        )
        np.testing.assert_allclose(feats[: len(kept)], want, atol=2e-5)
        assert not feats[len(kept) :].any()


def test_pillarize_keeps_the_fullest_pillars() -> None:
    p = preset("tiny", max_pillars=2)
    pts = np.array([[0.5, 0.5, 0, 0]] * 3 + [[5.5, 5.5, 0, 0]] + [[-5.5, 2.5, 0, 0]] * 2, dtype=np.float32)
    got = pillarize(pts, p)
    centres = pillar_centres(got.coords, p)
    assert sorted(map(tuple, centres.round(2).tolist())) == [(-5.5, 2.5), (0.5, 0.5)]


def test_scatter_and_scatter_max_against_numpy() -> None:
    rng = np.random.default_rng(0)
    grid = (6, 5)  # nx, ny
    coords = np.array([[0, 0], [4, 5], [2, 3], [1, 1]])
    batch = np.array([0, 0, 1, 1])
    feats = rng.random((4, 3)).astype(np.float32)
    canvas = scatter(
        torch.from_numpy(feats), coords=torch.from_numpy(coords), batch=torch.from_numpy(batch), size=2, grid=grid
    )
    want = np.zeros((2, 3, 5, 6), np.float32)
    for f, (iy, ix), b in zip(feats, coords, batch, strict=True):
        want[b, :, iy, ix] = f
    np.testing.assert_array_equal(canvas.numpy(), want)
    # two more features land in (0, 0) of sample 0 and one in an empty cell of sample 1: element-wise max
    more = rng.random((3, 3)).astype(np.float32)
    cells = np.array([[0, 0], [0, 0], [3, 2]])
    mb = np.array([0, 0, 1])
    fused = scatter_max(
        canvas, features=torch.from_numpy(more), cells=torch.from_numpy(cells), batch=torch.from_numpy(mb)
    )
    for f, (iy, ix), b in zip(more, cells, mb, strict=True):
        want[b, :, iy, ix] = np.maximum(want[b, :, iy, ix], f)
    np.testing.assert_array_equal(fused.numpy(), want)
