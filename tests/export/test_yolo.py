"""``--to yolo``: the Ultralytics layout, boxes that round-trip to the tight boxes of the vessels' pixels in the
recorded instance images (the default ``--box visible``), and ``data.yaml``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from mmusv.classes import SemanticClass, class_name
from mmusv.export import convert
from mmusv.recording import decode_image, frame_messages, read_info, topics
from PIL import Image


@pytest.fixture(scope="module")
def yolo_dir(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("yolo") / "o"
    convert(port_rec, to="yolo", out_dir=out, splits=None)
    return out


def test_data_yaml(yolo_dir: Path) -> None:
    doc = yaml.safe_load((yolo_dir / "data.yaml").read_text())
    assert doc["train"] == doc["val"] == "images/all" and "path" not in doc
    assert doc["names"] == {i: class_name(c) for i, c in enumerate(c for c in SemanticClass if c != 0)}


def test_boxes_round_trip_to_pixels(yolo_dir: Path, port_rec: Path) -> None:
    doc = yaml.safe_load((yolo_dir / "data.yaml").read_text())
    index = {name: i for i, name in doc["names"].items()}
    info = read_info(port_rec)
    n_images = n_boxes = 0
    for k in range(3):
        msgs = frame_messages(port_rec, k)
        world = {v.id: v for v in msgs[topics.WORLD_STATE].vessels}
        for a in info.agents:
            for name, cam in a.cameras.items():
                rel = f"{port_rec.stem}/{a.id}/{name}/{k:06d}"
                img = np.asarray(Image.open(yolo_dir / "images" / "all" / f"{rel}.png"))
                np.testing.assert_array_equal(img, decode_image(msgs[topics.camera(a.id, name, kind="rgb")]))
                lines = (yolo_dir / "labels" / "all" / f"{rel}.txt").read_text().splitlines()
                want = [
                    b
                    for b in msgs[topics.agent_annotations(a.id)].boxes_camera
                    if b.camera == name and b.visible_pixels > 0
                ]
                inst = np.asarray(decode_image(msgs[topics.camera(a.id, name, kind="instance")]))
                assert len(lines) == len(want)
                n_images += 1
                for line, b in zip(lines, want, strict=True):
                    c, cx, cy, w, h = line.split()
                    assert int(c) == index[class_name(world[b.target_id].semantic_class)]
                    W, H = cam.width, cam.height
                    x0, x1 = (float(cx) - float(w) / 2) * W, (float(cx) + float(w) / 2) * W
                    y0, y1 = (float(cy) - float(h) / 2) * H, (float(cy) + float(h) / 2) * H
                    # The default box is ``visible``: the tight box (pixel edges) of the vessel's pixels, to the
                    # labels' 6 decimals; it was the recorded projected box, within 1 px, before ``--box`` existed.
                    ys, xs = np.nonzero(inst == world[b.target_id].instance_id)
                    tight = [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]
                    assert np.max(np.abs(np.array([x0, y0, x1, y1]) - tight)) < 1e-4
                    assert all(0.0 <= float(v) <= 1.0 for v in (cx, cy, w, h))
                    n_boxes += 1
    assert n_images == 36 and n_boxes >= 10


def test_splits_by_sequence(many_recs: list[Path], tmp_path: Path) -> None:
    from mmusv.export.splits import assign_splits, parse_ratios

    out = tmp_path / "y"
    convert(many_recs, to="yolo", out_dir=out, max_occlusion=0.3)
    doc = yaml.safe_load((out / "data.yaml").read_text())
    assert (doc["train"], doc["val"], doc["test"]) == ("images/train", "images/validate", "images/test")
    want = assign_splits([p.stem for p in many_recs], ratios=parse_ratios((0.7, 0.15, 0.15)), seed=0)
    for split in ("train", "validate", "test"):
        got = {p.name for p in (out / "images" / split).iterdir()}
        assert got == {k for k, s in want.items() if s == split}
    conv = yaml.safe_load((out / "conversion.yaml").read_text())
    assert conv["options"]["max_occlusion"] == 0.3
