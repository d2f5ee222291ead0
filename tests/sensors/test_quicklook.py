"""Quick-look images (:mod:`mmusv.sensors.quicklook`): shapes, dtypes, colours, orientation, PNG round trip."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mmusv.classes import PALETTE, SemanticClass, palette_array
from mmusv.errors import InputError
from mmusv.sensors import LidarPoints
from mmusv.sensors.quicklook import (
    BOX_COLOR,
    depth_image,
    instance_image,
    lidar_bev_image,
    save_png,
    semantic_image,
)
from mmusv.simulation import Simulation
from PIL import Image


def test_depth_image_colours_and_sky() -> None:
    depth = np.array([[0.0, 25.0, 50.0, np.inf], [100.0, 200.0, np.nan, 10.0]], dtype=np.float32)
    img = depth_image(depth, max_m=100.0)
    assert img.shape == (2, 4, 3) and img.dtype == np.uint8
    assert np.all(img[0, 3] == 0) and np.all(img[1, 2] == 0), "sky is black"
    assert np.array_equal(img[1, 0], img[1, 1]), "beyond max_m clips to the top colour"
    assert len({tuple(img[0, k]) for k in range(3)}) == 3, "distinct depths, distinct colours"
    # Default scale: the largest finite depth is the top of the map.
    auto = depth_image(depth)
    assert np.array_equal(auto[1, 1], img[1, 0])
    # The same depth maps to the same colour as its position on the map says (turbo LUT).
    import matplotlib

    want = np.round(np.asarray(matplotlib.colormaps["turbo"](round(0.5 * 255) / 255))[:3] * 255)
    np.testing.assert_allclose(img[0, 2], want, atol=1)
    assert np.all(depth_image(np.full((3, 3), np.inf)) == 0)
    with pytest.raises(InputError, match="max_m"):
        depth_image(depth, max_m=0.0)
    with pytest.raises(InputError, match="depth"):
        depth_image(np.zeros(5))


def test_semantic_image_uses_the_palette() -> None:
    sem = np.array([[0, 1, 2], [10, 11, 99]], dtype=np.uint16)
    img = semantic_image(sem)
    assert img.shape == (2, 3, 3) and img.dtype == np.uint8
    assert tuple(img[0, 0]) == (0, 0, 0)
    assert tuple(img[0, 1]) == PALETTE[SemanticClass.WATER]
    assert tuple(img[1, 0]) == PALETTE[SemanticClass.VESSEL]
    assert tuple(img[1, 1]) == PALETTE[SemanticClass.USV]
    assert tuple(img[1, 2]) == tuple(palette_array()[99]) == (255, 0, 255)
    assert tuple(semantic_image(np.array([[300]]))[0, 0]) == (255, 0, 255)
    with pytest.raises(InputError, match="integer"):
        semantic_image(np.zeros((2, 2), dtype=np.float32))


def test_instance_image_is_stable_and_never_black() -> None:
    inst = np.array([[-1, 0, 1], [2, 1, 7]], dtype=np.int32)
    img = instance_image(inst)
    assert img.shape == (2, 3, 3) and img.dtype == np.uint8
    assert np.all(img[0, 0] == 0)
    assert np.array_equal(img[0, 2], img[1, 1]), "same id, same colour"
    colours = {tuple(img[0, 1]), tuple(img[0, 2]), tuple(img[1, 0]), tuple(img[1, 2])}
    assert len(colours) == 4
    # Stable: an id's colour does not depend on the other ids in the image.
    alone = instance_image(np.array([[7]], dtype=np.int64))
    assert np.array_equal(alone[0, 0], img[1, 2])
    many = instance_image(np.arange(1000).reshape(20, 50))
    assert many.reshape(-1, 3).min(axis=1).min() >= 40, "ids >= 0 are never black"
    assert len({tuple(c) for c in many.reshape(-1, 3)}) > 990


def test_lidar_bev_orientation_and_boxes() -> None:
    # x forward → up, y left → left.
    xyz = np.array([[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [-10.0, -10.0, 0.0], [0.0, 0.0, 0.0]])
    img = lidar_bev_image(xyz, extent_m=20.0, metres_per_pixel=1.0, intensity=[1.0, 0.5, 0.25, 0.0])
    assert img.shape == (40, 40, 3) and img.dtype == np.uint8
    lit = {(int(r), int(c)) for r, c in zip(*np.nonzero(img.any(axis=2)))}
    assert (10, 20) in lit  # 10 m ahead: row (20 − 10) / 1
    assert (20, 10) in lit  # 10 m left: column (20 − 10) / 1
    assert (30, 30) in lit  # behind-right
    assert (20, 20) in lit
    assert len(lit) == 4
    # The highest point wins a pixel; classes use the palette.
    stack = np.array([[5.0, 5.0, 0.0], [5.2, 5.2, 3.0], [5.4, 5.4, 1.0]])
    cls = lidar_bev_image(stack, extent_m=10, metres_per_pixel=1.0, color_by="class", semantic_class=[1, 10, 2])
    assert tuple(cls[4, 4]) == PALETTE[SemanticClass.VESSEL]
    # A box 8 m × 4 m at (10, 5) turned 90°: spans x 8..12, y 1..9 → rows 8..12, columns 11..19.
    boxed = lidar_bev_image(
        np.zeros((0, 3)), extent_m=20.0, metres_per_pixel=1.0, intensity=np.zeros(0), boxes=[[10.0, 5.0, 8.0, 4.0, math.pi / 2]]
    )
    on = np.all(boxed == np.array(BOX_COLOR, dtype=np.uint8), axis=2)
    rows, cols = np.nonzero(on)
    assert rows.min() >= 7 and rows.max() <= 12 and cols.min() >= 10 and cols.max() <= 19
    assert rows.max() - rows.min() >= 3 and cols.max() - cols.min() >= 7, "long side across the image (yaw 90°)"
    assert not on[10, 15], "outline only"
    with pytest.raises(InputError, match="boxes"):
        lidar_bev_image(xyz, extent_m=20, metres_per_pixel=1, intensity=np.zeros(4), boxes=[[1, 2, 3]])
    with pytest.raises(InputError, match="intensity"):
        lidar_bev_image(xyz, extent_m=20, metres_per_pixel=1)
    with pytest.raises(InputError, match="metres_per_pixel"):
        lidar_bev_image(xyz, extent_m=20, metres_per_pixel=0, intensity=np.zeros(4))


def test_quicklook_of_a_capture_round_trips_png(sim: Simulation, tmp_path: Path) -> None:
    cap = sim.capture(1, agents=["usv_a"], radar=False)
    a = cap.agents["usv_a"]
    assert isinstance(a.lidar, LidarPoints)
    front = a.cameras["front"]
    images = {
        "depth": depth_image(front.depth, max_m=150.0),
        "semantic": semantic_image(front.semantic),
        "instance": instance_image(front.instance),
        "bev": lidar_bev_image(a.lidar, extent_m=60.0, metres_per_pixel=0.5, color_by="class"),
        "bev_i": lidar_bev_image(a.lidar, extent_m=60.0, metres_per_pixel=0.5, boxes=[[45.0, 6.0, 32.0, 12.0, 0.0]]),
    }
    for name, img in images.items():
        assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3, name
        path = save_png(tmp_path / "ql" / f"{name}.png", img)
        assert path.is_file()
        back = np.asarray(Image.open(path).convert("RGB"))
        assert np.array_equal(back, img), name
    assert images["bev"].shape == (240, 240, 3)
    # The tug (45 m ahead, class vessel) shows up ahead of the sensor in the BEV.
    vessel = np.all(images["bev"] == np.array(PALETTE[SemanticClass.VESSEL], dtype=np.uint8), axis=2)
    rows, cols = np.nonzero(vessel)
    assert len(rows) > 10 and rows.mean() < 120 - 60 and abs(cols.mean() - 120) < 40
    with pytest.raises(InputError, match="uint8"):
        save_png(tmp_path / "x.png", np.zeros((2, 2, 3), dtype=np.float32))
