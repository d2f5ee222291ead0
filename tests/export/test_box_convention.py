"""``--box visible|projected`` of the COCO and YOLO exports (docs/exports.md).

``visible`` (the default) writes the tight box of the vessel's pixels in the instance image, COCO's own convention
for ``bbox`` (pycocotools' ``toBbox`` of the segmentation) and what detectors trained on COCO or YOLO sets expect;
``projected`` writes the recording's box (the vessel's projected 3D box clipped to the image, which reaches down to
the keel below the waterline). Every expectation is computed here from the recording (its instance images and 2D
annotations, by ``recorded_boxes.recorded``) and pycocotools, never from the exporters' code. Boxes are in
pixel-edge coordinates: pixel ``(i, j)`` over ``[i, i + 1) × [j, j + 1)``, so the tight box of columns ``c0..c1``
is ``[c0, c1 + 1)``.
"""

from __future__ import annotations

import argparse
import inspect
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.classes import SemanticClass
from mmusv.errors import ConfigError
from mmusv.export import cli as export_cli
from mmusv.export import convert
from mmusv.export.common import Options
from mmusv.recording import read_info
from pycocotools import mask as mask_util
from recorded_boxes import Boxes, recorded

FRAMES = 3
"""conftest's ``port`` recording: 3 frames, 3 USVs with 4 cameras of 160 × 120."""
CLASSES = [int(c) for c in SemanticClass if c != SemanticClass.NONE]
"""The YOLO class index of an mmusv class is its position here (docs/exports.md: every class but ``none``)."""


@pytest.fixture(scope="module")
def port_boxes(port_rec: Path) -> Boxes:
    return recorded(port_rec, FRAMES)


def coco_dir(port_rec: Path, root: Path, **kwargs: Any) -> Path:
    out = root / "o"
    convert(port_rec, to="coco", out_dir=out, splits=None, **kwargs)
    return out


@pytest.fixture(scope="module")
def coco_visible(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return coco_dir(port_rec, tmp_path_factory.mktemp("coco_visible"))  # the default


@pytest.fixture(scope="module")
def coco_projected(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return coco_dir(port_rec, tmp_path_factory.mktemp("coco_projected"), box="projected")


def coco_doc(out: Path) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads((out / "annotations" / "instances_all.json").read_text())
    return doc


def coco_anns(out: Path) -> dict[tuple[str, str, int, str], dict[str, Any]]:
    """Annotations by ``(agent, camera, frame, vessel id)``."""
    doc = coco_doc(out)
    images = {i["id"]: i for i in doc["images"]}
    out_: dict[tuple[str, str, int, str], dict[str, Any]] = {}
    for a in doc["annotations"]:
        img = images[a["image_id"]]
        out_[(img["agent"], img["camera"], img["frame"], a["mmusv_id"])] = a
    return out_


def to_bbox(segmentation: dict[str, Any]) -> np.ndarray:
    """pycocotools' ``toBbox`` of an RLE with ``counts`` as a string (its ``__array__`` predates numpy 2's ``copy``
    keyword, a DeprecationWarning of pycocotools 2.0.11)."""
    rle = {"size": segmentation["size"], "counts": segmentation["counts"].encode("ascii")}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, message=".*copy keyword")
        return np.asarray(mask_util.toBbox(rle), dtype=np.float64)


def xywh(xyxy: list[float]) -> list[float]:
    return [xyxy[0], xyxy[1], xyxy[2] - xyxy[0], xyxy[3] - xyxy[1]]


def yolo_labels(out: Path, rec: Path) -> dict[tuple[str, str, int], list[list[float]]]:
    """Per image ``(agent, camera, frame)``: its label rows ``[class, cx, cy, w, h]``."""
    info = read_info(rec)
    got = {}
    for k in range(FRAMES):
        for a in info.agents:
            for name in a.cameras:
                path = out / "labels" / "all" / rec.stem / a.id / name / f"{k:06d}.txt"
                got[(a.id, name, k)] = [[float(v) for v in line.split()] for line in path.read_text().splitlines()]
    return got


def yolo_rows(per: dict[str, dict[str, Any]], kind: str) -> np.ndarray:
    """The label rows an image's boxes of ``kind`` (``visible`` or ``projected``) give, sorted: class index and the
    box normalised."""
    rows = []
    for b in per.values():
        x0, y0, x1, y1 = b[kind]
        w, h = b["size"]
        rows.append([CLASSES.index(b["class"]), (x0 + x1) / 2 / w, (y0 + y1) / 2 / h, (x1 - x0) / w, (y1 - y0) / h])
    return np.array(sorted(rows), dtype=np.float64).reshape(-1, 5)


# ---------------------------------------------------------------------------------------------- the default


def test_the_default_is_visible_and_is_recorded(coco_visible: Path, port_rec: Path, tmp_path: Path) -> None:
    assert Options().box == "visible"
    assert inspect.signature(convert).parameters["box"].default == "visible"
    p = argparse.ArgumentParser(prog="mmusv")
    export_cli.add_parser(p.add_subparsers(dest="command"))
    assert p.parse_args(["convert", "r.mcap", "--to", "coco", "-o", "o"]).box == "visible"
    info = coco_doc(coco_visible)["info"]
    assert info["mmusv_box"] == "visible" and "tight box" in info["mmusv_box_definition"]
    assert yaml.safe_load((coco_visible / "conversion.yaml").read_text())["options"]["box"] == "visible"
    convert(port_rec, to="yolo", out_dir=tmp_path / "y", splits=None, frames=(0, 1))
    data = yaml.safe_load((tmp_path / "y" / "data.yaml").read_text())
    assert data["mmusv_box"] == "visible" and "tight box" in data["mmusv_box_definition"]
    assert yaml.safe_load((tmp_path / "y" / "conversion.yaml").read_text())["options"]["box"] == "visible"


# ---------------------------------------------------------------------------------------------- COCO


def test_coco_visible_bbox_is_the_segmentations_tight_box(
    coco_visible: Path, port_boxes: dict[tuple[str, str, int], dict[str, dict[str, Any]]]
) -> None:
    """``bbox`` = pycocotools' ``toBbox`` of ``segmentation`` for every annotation (COCO's convention), = the tight
    box of the vessel's pixels in the recorded instance image; one annotation per vessel with a visible pixel."""
    anns = coco_anns(coco_visible)
    want = {(*img, vid): b for img, per in port_boxes.items() for vid, b in per.items()}
    assert len(anns) >= 10 and sorted(anns) == sorted(want)
    for key, a in anns.items():
        np.testing.assert_allclose(a["bbox"], to_bbox(a["segmentation"]), rtol=0, atol=1e-6, err_msg=str(key))
        np.testing.assert_allclose(a["bbox"], xywh(want[key]["visible"]), rtol=0, atol=1e-6, err_msg=str(key))
        assert a["area"] == a["visible_pixels"] > 0
        assert a["occlusion"] == pytest.approx(want[key]["occlusion"], abs=1e-6)
        assert a["truncation"] == pytest.approx(want[key]["truncation"], abs=1e-6)


def test_coco_projected_bbox_is_the_recorded_box(
    coco_projected: Path, coco_visible: Path, port_boxes: dict[tuple[str, str, int], dict[str, dict[str, Any]]]
) -> None:
    """With ``box="projected"``, ``bbox`` is the recording's box (to the file's 3 decimals) and holds the mask's
    tight box; every other field is the ``visible`` export's."""
    proj, vis = coco_anns(coco_projected), coco_anns(coco_visible)
    assert sorted(proj) == sorted(vis)
    info = coco_doc(coco_projected)["info"]
    assert info["mmusv_box"] == "projected" and "projected 3D box" in info["mmusv_box_definition"]
    for key, a in proj.items():
        b = port_boxes[key[:3]][key[3]]
        np.testing.assert_allclose(a["bbox"], xywh(b["projected"]), rtol=0, atol=5e-4 + 1e-9, err_msg=str(key))
        x, y, w, h = to_bbox(a["segmentation"])
        px0, py0, px1, py1 = b["projected"]
        assert np.floor(px0) <= x and np.floor(py0) <= y and x + w <= np.ceil(px1) and y + h <= np.ceil(py1), key
        assert {k: v for k, v in a.items() if k != "bbox"} == {k: v for k, v in vis[key].items() if k != "bbox"}


def test_a_vessel_in_the_water_gets_a_visible_box_above_its_keel(coco_visible: Path, coco_projected: Path) -> None:
    """The projected box reaches down to the keel below the waterline, which the water hides: a vessel in view whose
    box is not cut by the image's bottom edge and spans a few pixel rows gets a visible box whose bottom is above the
    projected box's bottom (never below the last row the projected box touches)."""
    proj, vis = coco_anns(coco_projected), coco_anns(coco_visible)
    checked = lower = 0
    for key, a in vis.items():
        p = proj[key]["bbox"]
        bottom_p, bottom_v = p[1] + p[3], a["bbox"][1] + a["bbox"][3]
        assert bottom_v <= np.ceil(bottom_p), key
        if bottom_p < a["segmentation"]["size"][0] - 1 and a["occlusion"] < 0.5 and p[3] >= 4.0:
            assert bottom_v < bottom_p, key
            checked += 1
            lower += bottom_p - bottom_v >= 1.0
    assert checked >= 10 and lower >= 3


def test_filters_apply_to_the_box_written(
    port_rec: Path, coco_visible: Path, coco_projected: Path, tmp_path: Path
) -> None:
    """``min_box_px`` tests the shorter side of the box written (the visible one by default), ``max_occlusion`` the
    recorded occlusion."""
    vis, proj = coco_anns(coco_visible), coco_anns(coco_projected)
    sides = sorted({min(a["bbox"][2], a["bbox"][3]) for a in vis.values()})
    px = sides[len(sides) // 2]
    differs = [k for k in vis if (min(vis[k]["bbox"][2:]) >= px) != (min(proj[k]["bbox"][2:]) >= px)]
    assert differs  # the two boxes give different sets: the test tells which box the filter read
    kept = coco_anns(coco_dir(port_rec, tmp_path / "v", min_box_px=px, max_occlusion=0.5))
    assert sorted(kept) == sorted(k for k, a in vis.items() if min(a["bbox"][2:]) >= px and a["occlusion"] <= 0.5)
    kept = coco_anns(coco_dir(port_rec, tmp_path / "p", min_box_px=px, max_occlusion=0.5, box="projected"))
    assert sorted(kept) == sorted(k for k, a in proj.items() if min(a["bbox"][2:]) >= px and a["occlusion"] <= 0.5)


# ---------------------------------------------------------------------------------------------- YOLO


@pytest.mark.parametrize("box", ["visible", "projected"])
def test_yolo_labels_are_the_boxes_normalised(
    port_rec: Path, port_boxes: dict[tuple[str, str, int], dict[str, dict[str, Any]]], tmp_path: Path, box: str
) -> None:
    """``visible`` (the default): every label is the tight box of the vessel's pixels in the instance image,
    normalised (6 decimals); ``projected``: the recorded box, normalised."""
    given: dict[str, Any] = {} if box == "visible" else {"box": box}  # visible: the default, not given
    convert(port_rec, to="yolo", out_dir=tmp_path / "y", splits=None, **given)
    assert yaml.safe_load((tmp_path / "y" / "data.yaml").read_text())["mmusv_box"] == box
    got = yolo_labels(tmp_path / "y", port_rec)
    assert sorted(got) == sorted(port_boxes) and len(got) == FRAMES * 3 * 4
    n = 0
    for img, rows in got.items():
        exp = yolo_rows(port_boxes[img], box)
        have = np.array(sorted(rows), dtype=np.float64).reshape(-1, 5)
        assert have.shape == exp.shape, img
        np.testing.assert_array_equal(have[:, 0], exp[:, 0])
        np.testing.assert_allclose(have[:, 1:], exp[:, 1:], rtol=0, atol=5e-7 + 1e-9, err_msg=str(img))
        n += len(rows)
    assert n >= 10


# ---------------------------------------------------------------------------------------------- bad values


@pytest.mark.parametrize("bad", ["tight", "Visible", "", None, 1])
def test_a_bad_box_is_refused_before_anything_is_written(port_rec: Path, tmp_path: Path, bad: Any) -> None:
    out = tmp_path / "o"
    with pytest.raises(ConfigError, match=r"^box = .*: must be 'visible' .* or 'projected'") as exc:
        convert(port_rec, to="coco", out_dir=out, box=bad)
    assert "\n" not in str(exc.value) and not out.exists()


def test_the_cli_refuses_a_bad_box_in_one_line(
    port_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.cli import main

    out = tmp_path / "o"
    for to in ("coco", "yolo"):
        assert main(["convert", str(port_rec), "--to", to, "-o", str(out), "--box", "tight", "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.startswith("mmusv: error: unknown --box 'tight'; allowed: visible") and err.count("\n") == 1
        assert "projected" in err and "Traceback" not in err and not out.exists()
