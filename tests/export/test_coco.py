"""``--to coco``: pycocotools loads the files, COCOeval of the ground truth against itself gives AP = 1, the RLE
masks decode to the instance images' pixels, the split follows the OPV2V export's, and bad input is refused."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.errors import ConfigError, IoError, MmusvError
from mmusv.export import cli as export_cli
from mmusv.export import convert
from mmusv.recording import decode_image, frame_messages, read_info, topics
from PIL import Image
from pycocotools import mask as mask_util
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval


@pytest.fixture(scope="module")
def coco_dir(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("coco") / "o"
    convert(port_rec, to="coco", out_dir=out, splits=None)
    return out


def decode(rle: dict[str, Any]) -> np.ndarray:
    """pycocotools' RLE decoder; its Cython ``__array__`` predates numpy 2's ``copy`` keyword, which numpy reports
    as a DeprecationWarning (pycocotools 2.0.11), not ours to fix."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, message=".*copy keyword")
        out: np.ndarray = mask_util.decode(rle)
    return out


def load(path: Path) -> COCO:
    with contextlib.redirect_stdout(io.StringIO()):
        return COCO(str(path))


def test_pycocotools_loads_and_evaluates_ground_truth_as_perfect(coco_dir: Path) -> None:
    gt = load(coco_dir / "annotations" / "instances_all.json")
    anns = gt.loadAnns(gt.getAnnIds())
    assert len(anns) >= 10 and len(gt.getImgIds()) == 3 * 3 * 4  # 3 frames x 3 USVs x 4 cameras
    assert {a["iscrowd"] for a in anns} == {0} and {a["category_id"] for a in anns} <= {10, 11}
    assert {c["name"] for c in gt.loadCats(gt.getCatIds())} >= {"vessel", "usv", "water"}
    for iou in ("bbox", "segm"):
        dets = [{**a, "score": 1.0} for a in anns]
        with contextlib.redirect_stdout(io.StringIO()):
            dt = gt.loadRes(dets)
            ev = COCOeval(gt, dt, iou)
            ev.evaluate()
            ev.accumulate()
            ev.summarize()
        assert ev.stats[0] == pytest.approx(1.0), iou  # AP @ IoU 0.50:0.95


def test_masks_decode_to_the_instance_images(coco_dir: Path, port_rec: Path) -> None:
    gt = load(coco_dir / "annotations" / "instances_all.json")
    info = read_info(port_rec)
    cams = {a.id: a.cameras for a in info.agents}
    frames = {k: frame_messages(port_rec, k) for k in range(3)}
    for img in gt.loadImgs(gt.getImgIds()):
        msgs = frames[img["frame"]]
        inst = decode_image(msgs[topics.camera(img["agent"], img["camera"], kind="instance")])
        rgb = np.asarray(Image.open(coco_dir / "images" / "all" / img["file_name"]))
        cam = cams[img["agent"]][img["camera"]]
        assert rgb.shape == (cam.height, cam.width, 3) == (img["height"], img["width"], 3)
        np.testing.assert_array_equal(rgb, decode_image(msgs[topics.camera(img["agent"], img["camera"], kind="rgb")]))
        world = {v.id: v for v in msgs[topics.WORLD_STATE].vessels}
        boxes = {
            b.target_id: b
            for b in msgs[topics.agent_annotations(img["agent"])].boxes_camera
            if b.camera == img["camera"] and b.visible_pixels > 0
        }
        anns = gt.loadAnns(gt.getAnnIds(imgIds=[img["id"]]))
        assert sorted(a["mmusv_id"] for a in anns) == sorted(boxes)  # the default keeps every visible box
        for a in anns:
            m = decode(a["segmentation"])
            v = world[a["mmusv_id"]]
            np.testing.assert_array_equal(m.astype(bool), inst == v.instance_id)
            assert a["area"] == int(np.count_nonzero(inst == v.instance_id)) == boxes[a["mmusv_id"]].visible_pixels
            assert a["category_id"] == v.semantic_class and a["role"] == v.role
            b = boxes[a["mmusv_id"]]
            # The default box is ``visible`` (COCO's convention): the tight box of the mask in pixel edges, no longer
            # the recorded projected box (tests/export/test_box_convention.py checks both).
            ys, xs = np.nonzero(m)
            np.testing.assert_allclose(
                a["bbox"], [xs.min(), ys.min(), xs.max() + 1 - xs.min(), ys.max() + 1 - ys.min()], atol=1e-6
            )
            assert a["occlusion"] == pytest.approx(b.occlusion, abs=1e-6)
            assert a["truncation"] == pytest.approx(b.truncation, abs=1e-6)


def test_box_filters(coco_dir: Path, port_rec: Path, tmp_path: Path) -> None:
    every = json.loads((coco_dir / "annotations" / "instances_all.json").read_text())["annotations"]
    out = tmp_path / "f"
    convert(port_rec, to="coco", out_dir=out, splits=None, min_box_px=8, max_occlusion=0.5)
    kept = json.loads((out / "annotations" / "instances_all.json").read_text())["annotations"]
    expect = [a for a in every if min(a["bbox"][2], a["bbox"][3]) >= 8 and a["occlusion"] <= 0.5]
    assert 0 < len(kept) < len(every)
    assert [(a["image_id"], a["mmusv_id"]) for a in kept] == [(a["image_id"], a["mmusv_id"]) for a in expect]
    with pytest.raises(ConfigError, match="max_occlusion"):
        convert(port_rec, to="coco", out_dir=tmp_path / "g", max_occlusion=1.5)


def test_split_by_sequence_as_opv2v(many_recs: list[Path], tmp_path: Path) -> None:
    convert(many_recs, to="coco", out_dir=tmp_path / "c", seed=3)
    convert(many_recs, to="opv2v", out_dir=tmp_path / "o", seed=3, extras="")
    ref = yaml.safe_load((tmp_path / "o" / "conversion.yaml").read_text())
    want: dict[str, set[str]] = {}
    for r in ref["recordings"]:
        want.setdefault(r["split"], set()).add(r["scenario"])
    assert sorted(want) == ["test", "train", "validate"]
    for split, names in want.items():
        doc = json.loads((tmp_path / "c" / "annotations" / f"instances_{split}.json").read_text())
        assert {i["scenario"] for i in doc["images"]} == names
        assert all((tmp_path / "c" / "images" / split / i["file_name"]).is_file() for i in doc["images"])


def _parse(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="mmusv")
    export_cli.add_parser(p.add_subparsers(dest="command"))
    return p.parse_args(["convert", *argv, "--no-progress"])


def test_bad_input_is_a_clean_error(no_camera_rec: Path, coop_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    with pytest.raises(ConfigError, match=r"export_no_camera\.mcap: cannot convert to coco: no camera") as exc:
        export_cli.run(_parse([str(no_camera_rec), "--to", "coco", "-o", str(out)]))
    assert "\n" not in str(exc.value) and not out.exists()
    out.mkdir()
    (out / "mine.txt").write_text("keep")
    err: Any
    for argv in (
        [str(coop_rec), "--to", "coco", "-o", str(out)],
        [str(coop_rec), "--to", "coco", "-o", str(out), "--overwrite"],
    ):
        with pytest.raises(IoError) as err:
            export_cli.run(_parse(argv))
        assert isinstance(err.value, MmusvError) and "\n" not in str(err.value)
    assert (out / "mine.txt").read_text() == "keep"


def test_cli_prints_one_line_errors(no_camera_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from mmusv.cli import main

    assert main(["convert", str(no_camera_rec), "--to", "coco", "-o", str(tmp_path / "o"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and "Traceback" not in err
