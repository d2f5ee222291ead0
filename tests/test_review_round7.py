"""Review round 7 (keyword-only parameters, docstrings of shapes, dtypes, units and frames): what a review found."""

from __future__ import annotations

import numpy as np
import pytest
from mmusv.studies.detection.data import AgentFrame
from mmusv.studies.detection.fusion import fuse


def _agent(name: str, x: float) -> AgentFrame:
    body = np.eye(4)
    body[0, 3] = x
    return AgentFrame(name, np.zeros((1, 4), dtype=np.float32), body, np.eye(4))


@pytest.mark.parametrize(("mode", "merge"), [("none", "nms"), ("late", "nms"), ("late", "wbf")])
def test_fuse_returns_float64_whatever_own_detections_gives(mode: str, merge: str) -> None:
    """``fuse`` with float32 own detections: ``none`` returned them as float32, ``late`` the neighbours' boxes moved
    to float64 beside float32 scores (``wbf``: float64 both), while the docstring promised one dtype. Float64 in
    every mode now, the boxes where they were."""

    def own(agent: AgentFrame) -> tuple[np.ndarray, np.ndarray]:
        box = np.array([[1.0, 2.0, 0.0, 4.0, 2.0, 1.0, 0.1]], dtype=np.float32)
        return box, np.array([0.9 if agent.id == "a" else 0.8], dtype=np.float32)

    def detector(_: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise AssertionError("own_detections given: the detector is not run")

    boxes, scores = fuse(
        mode, _agent("a", 0.0), [_agent("b", 100.0)], detector=detector, own_detections=own, late_merge=merge
    )
    assert boxes.dtype == np.float64 and scores.dtype == np.float64
    expected = [[1.0, 2.0, 0.0, 4.0, 2.0, 1.0, 0.1]] + (
        [] if mode == "none" else [[101.0, 2.0, 0.0, 4.0, 2.0, 1.0, 0.1]]
    )
    np.testing.assert_allclose(boxes[np.argsort(boxes[:, 0])], expected, atol=1e-6)
