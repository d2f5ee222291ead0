"""A sweep of the public API's docstrings against what the code returns (shape, dtype, unit, frame, range), on a tiny
scenario: one USV with a LiDAR, a small camera and a top view, one fishing boat ahead; one frame captured and one
recorded. Each test pins a docstring that said something the code does not do."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import mmusv.classes
import numpy as np
import pytest
from mmusv import Simulation, run
from mmusv.recording import decode_image
from mmusv.recording.info import read_info
from mmusv.recording.stream import FrameStream


def _scenario() -> dict[str, Any]:
    rig = {
        "preset": "lidar_only",
        "lidar": {"channels": 8, "points_per_second": 8 * 360 * 5},
        "cameras": [{"name": "front", "resolution": [48, 32], "mount": {"point": "camera_front"}}],
        "top_view": {"resolution": [32, 32], "metres_per_pixel": 0.5},
    }
    return {
        "name": "docstrings",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": 1},
        "environment": {"motion": "paper"},
        "rigs": {"r": rig},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 1, "route": [[30, -10], [30, 50]]},
        ],
    }


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return run(_scenario(), out_dir=tmp_path_factory.mktemp("rec")).recording


def _frame0(path: Path) -> Any:
    return next(iter(FrameStream(read_info(path), lambda topic: True)))


def test_recorded_semantic_images_are_class_ids_not_the_palette(recorded: Path) -> None:
    """``mmusv.classes`` said the palette is the one "semantic camera PNGs use"; the recorded semantic PNGs hold
    the class ids themselves, 16-bit gray (docs/recording.md), and the palette colours only the quick-look images."""
    sim = Simulation(_scenario())
    cap = sim.capture(0, sensors=["cameras", "top_view"])
    fr = _frame0(recorded)
    for topic, images in (
        ("/u/camera/front/semantic", cap.agents["u"].cameras["front"]),
        ("/u/top_view/semantic", cap.agents["u"].top_view),
    ):
        assert images is not None
        img = decode_image(fr.messages[topic])
        assert img.dtype == np.uint16 and img.ndim == 2, topic
        np.testing.assert_array_equal(img, images.semantic)
    doc = inspect.getdoc(mmusv.classes) or ""
    assert "semantic camera PNGs use" not in doc
    assert "class ids themselves" in doc
