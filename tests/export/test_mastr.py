"""``--to mastr``: MaSTr1325-style masks (0 obstacle, 1 water, 2 sky) agree with the recording's semantic images
pixel for pixel, beside the copied RGB images."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from mmusv.export import convert
from mmusv.recording import decode_image, frame_messages, read_info, topics
from PIL import Image


@pytest.fixture(scope="module")
def mastr_dir(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("mastr") / "o"
    convert(port_rec, to="mastr", out_dir=out, splits=None)
    return out


def test_masks_agree_with_the_semantic_images(mastr_dir: Path, port_rec: Path) -> None:
    info = read_info(port_rec)
    seen: set[int] = set()
    n = 0
    for k in range(3):
        msgs = frame_messages(port_rec, k)
        for a in info.agents:
            for name, cam in a.cameras.items():
                rel = f"{port_rec.stem}/{a.id}/{name}/{k:06d}"
                mask = np.asarray(Image.open(mastr_dir / "masks" / f"{rel}m.png"))
                sem = decode_image(msgs[topics.camera(a.id, name, kind="semantic")])
                assert mask.dtype == np.uint8 and mask.shape == sem.shape == (cam.height, cam.width)
                want = np.where(sem == 0, 2, np.where(sem == 1, 1, 0))  # sky (nothing hit), water, obstacle
                np.testing.assert_array_equal(mask, want)
                rgb = np.asarray(Image.open(mastr_dir / "images" / f"{rel}.png"))
                np.testing.assert_array_equal(rgb, decode_image(msgs[topics.camera(a.id, name, kind="rgb")]))
                seen |= set(np.unique(mask).tolist())
                n += 1
    assert n == 36 and seen == {0, 1, 2}  # the port scene shows all three
    doc = yaml.safe_load((mastr_dir / "mastr.yaml").read_text())
    assert doc["labels"] == {0: "obstacle", 1: "water", 2: "sky", 4: "ignore"}
    assert doc["from_mmusv_class"]["water"] == 1 and doc["from_mmusv_class"]["vessel"] == 0


def test_split_folders(many_recs: list[Path], tmp_path: Path) -> None:
    convert(many_recs[:3], to="mastr", out_dir=tmp_path / "m", splits=(1, 1, 1))
    for split in ("train", "validate", "test"):
        imgs = sorted(
            p.relative_to(tmp_path / "m" / split / "images") for p in (tmp_path / "m" / split / "images").rglob("*.png")
        )
        masks = sorted(
            p.relative_to(tmp_path / "m" / split / "masks") for p in (tmp_path / "m" / split / "masks").rglob("*.png")
        )
        assert len(imgs) == 2 * 2 * 4  # 2 frames x 2 USVs x 4 cameras
        assert [m.with_name(m.name.replace("m.png", ".png")) for m in masks] == imgs
