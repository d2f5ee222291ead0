"""Decoding a perfect head output back to its boxes, and the rotated NMS after it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from mmusv.learn.decode import decode, peaks
from mmusv.learn.presets import preset
from mmusv.learn.targets import center_targets


def _perfect(boxes: np.ndarray, p) -> dict[str, torch.Tensor]:
    """Head outputs whose sigmoid is the target heatmap and whose maps hold the targets at the centres."""
    t = center_targets(boxes, p)
    nx, ny = p.out_grid
    heat = np.clip(t.heatmap, 1e-6, 1 - 1e-6)
    out = {
        "heatmap": np.log(heat / (1 - heat))[None],
        "offset": np.zeros((1, 2, ny, nx)),
        "z": np.zeros((1, 1, ny, nx)),
        "size": np.zeros((1, 3, ny, nx)),
        "rot": np.zeros((1, 2, ny, nx)),
    }
    for idx, row in zip(t.index[t.mask], t.reg[t.mask], strict=True):
        iy, ix = divmod(int(idx), nx)
        out["offset"][0, :, iy, ix] = row[:2]
        out["z"][0, 0, iy, ix] = row[2]
        out["size"][0, :, iy, ix] = row[3:6]
        out["rot"][0, :, iy, ix] = row[6:]
    return {k: torch.from_numpy(v.astype(np.float32)) for k, v in out.items()}


@pytest.mark.parametrize("yaw_double", [True, False])
def test_perfect_heatmap_decodes_to_its_boxes(yaw_double: bool) -> None:
    p = preset("tiny", yaw_double=yaw_double)
    boxes = np.array(
        [
            [2.25, -3.5, 1.0, 4.0, 2.0, 3.0, 0.5],
            [-20.3, 15.8, 2.5, 9.0, 3.0, 4.0, -1.2],
            [14.0, 14.0, 0.5, 3.0, 1.2, 1.0, 1.4],
        ]
    )
    got, scores = decode(_perfect(boxes, p), p)
    assert len(got) == 3 and np.allclose(scores, 1.0, atol=1e-5)
    order = [int(np.argmin(np.hypot(*(got[:, :2] - b[:2]).T))) for b in boxes]
    np.testing.assert_allclose(got[order, :6], boxes[:, :6], atol=1e-4)
    np.testing.assert_allclose(got[order, 6], boxes[:, 6], atol=1e-5)


def test_yaw_double_decodes_modulo_pi() -> None:
    p = preset("tiny")
    box = np.array([[0.0, 0.0, 0.0, 6.0, 2.0, 2.0, math.pi - 0.3]])
    got, _ = decode(_perfect(box, p), p)
    assert math.isclose(got[0, 6], -0.3, abs_tol=1e-5)  # the same BEV rectangle as pi - 0.3


def test_rotated_nms_drops_the_weaker_of_overlapping_boxes() -> None:
    p = preset("tiny", min_radius=0)
    # two peaks 2 cells apart on one long hull (a 10 m x 3 m box and a copy shifted 2 m along it overlap at
    # IoU 8/12 > 0.1), and a separate box
    boxes = np.array(
        [[0.5, 0.5, 0.0, 10.0, 3.0, 2.0, 0.0], [2.5, 0.5, 0.0, 10.0, 3.0, 2.0, 0.0], [20.5, 20.5, 0, 4, 2, 2, 0]]
    )
    out = _perfect(boxes, p)
    out["heatmap"][0, 0, 32, 34] = math.log(0.8 / 0.2)  # the shifted copy scores 0.8
    raw, _ = peaks(out, p)
    assert len(raw) == 3
    got, scores = decode(out, p)
    assert len(got) == 2
    np.testing.assert_allclose(sorted(scores), [1.0, 1.0], atol=1e-5)
    np.testing.assert_allclose(sorted(got[:, 0]), [0.5, 20.5], atol=1e-4)
