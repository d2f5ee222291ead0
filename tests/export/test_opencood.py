"""OpenCOOD hypes files: grid a multiple of the backbone's stride, anchors and constants from the data, and the
files an OPV2V export writes beside itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml
from mmusv.export import convert
from mmusv.export.opencood import BACKBONE_STRIDE, HypesStats, constants, hypes


def _grid(doc: dict) -> np.ndarray:
    """OpenCOOD's load_point_pillar_params: round((max - min) / voxel) per axis."""
    r = np.array(doc["preprocess"]["cav_lidar_range"], dtype=float)
    v = np.array(doc["preprocess"]["args"]["voxel_size"], dtype=float)
    return np.round((r[3:] - r[:3]) / v).astype(int)


def _stats() -> HypesStats:
    st = HypesStats(range_m=100.0)
    st.add(
        key=("a", 0),
        lidar_world=np.zeros(3),
        boxes_lidar=np.array([[50, 0, 4.0, 40, 8, 12, 0], [0, 30, -1, 4, 2, 2, 0]]),
    )
    st.add(key=("a", 0), lidar_world=np.array([300.0, 400.0, 0]), boxes_lidar=np.array([[10, 0, 1, 12, 4, 5, 0]]))
    return st


def test_grid_is_a_multiple_of_the_backbone_stride() -> None:
    # +-100 m at 0.8 m is OpenCOOD's "125 vs 126" size mismatch: the range is rounded up to 102.4 m (256 cells)
    docs = hypes(_stats(), root_dir="r", validate_dir="v", voxel_m=0.8)
    for doc in docs.values():
        g = _grid(doc)
        assert g[0] % BACKBONE_STRIDE == 0 and g[1] % BACKBONE_STRIDE == 0 and g[2] == 1
        assert doc["preprocess"]["cav_lidar_range"][3] == 102.4
    assert sorted(docs) == [f"point_pillar_{f}_fusion" for f in ("early", "intermediate", "late")]
    assert docs["point_pillar_intermediate_fusion"]["model"]["core_method"] == "point_pillar_intermediate"
    assert docs["point_pillar_late_fusion"]["fusion"]["core_method"] == "LateFusionDataset"


def test_anchors_heights_and_constants_come_from_the_data() -> None:
    st = _stats()
    doc = hypes(st, root_dir="r", validate_dir="v")["point_pillar_early_fusion"]
    a = doc["postprocess"]["anchor_args"]
    assert (a["l"], a["w"], a["h"]) == (12.0, 4.0, 5.0)  # the median vessel of the three
    r = doc["preprocess"]["cav_lidar_range"]
    assert (r[2], r[5]) == (-3.0, 11.0)  # lowest bottom -2 m, highest top 10 m, 1 m margin, whole metres
    c = constants(st)
    assert c["COM_RANGE"] == 510  # the USVs 500 m apart, rounded up to 10 m, plus 10 m
    assert c["GT_RANGE"] == r
    # OpenCOOD's remove_large_pred_bbx drops a box whose corners span more than the limit in x or y: no listed
    # vessel may be dropped at any yaw (the 40 x 8 m hull reaches 40.8 m; its length alone, 40 m, dropped it).
    limit = int(c["remove_large_pred_bbx"].split()[4])
    spans = []
    for length, width, _h in st.sizes:
        for yaw in np.linspace(0.0, np.pi, 721):
            rot = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
            xy = np.array([[sx * length / 2, sy * width / 2] for sx in (-1, 1) for sy in (-1, 1)]) @ rot.T
            spans.append(max(np.ptp(xy[:, 0]), np.ptp(xy[:, 1])))
    assert max(spans) <= limit < max(spans) + 1
    assert doc["optimizer"]["lr"] == 0.002 and doc["train_params"]["batch_size"] == 4


def test_opv2v_export_writes_the_hypes_beside_it(coop_rec: Path, tmp_path: Path) -> None:
    convert(coop_rec, to="opv2v", out_dir=tmp_path, splits=None)
    files = sorted(p.name for p in (tmp_path / "opencood").iterdir())
    assert files == [f"point_pillar_{f}_fusion.yaml" for f in ("early", "intermediate", "late")]
    text = (tmp_path / "opencood" / files[0]).read_text()
    assert "COM_RANGE" in text and "GT_RANGE" in text
    doc = yaml.safe_load(text)
    assert doc["root_dir"] == "."  # relative to the export folder: the bytes do not depend on where it is
    g = _grid(doc)
    assert g[0] % BACKBONE_STRIDE == 0 and doc["postprocess"]["anchor_args"]["l"] > 3.9


def test_hypes_name_split_folders_that_are_there(coop_rec: Path, tmp_path: Path) -> None:
    """One recording goes to train: validate_dir said ``validate``, a folder the export does not have (OpenCOOD lists
    it for its validation and inference); now another split's folder, said in the header. Only test held: both
    said ``.``, which lists ``test`` and ``opencood`` as scenarios."""
    for splits, root, val in (((0.7, 0.15, 0.15), "train", "train"), ((0, 0, 1), "test", "test")):
        out = tmp_path / f"o{root}"
        convert(coop_rec, to="opv2v", out_dir=out, splits=splits)
        for f in (out / "opencood").iterdir():
            text = f.read_text()
            doc = yaml.safe_load(text)
            assert (doc["root_dir"], doc["validate_dir"]) == (root, val), f
            assert (out / doc["root_dir"]).is_dir() and (out / doc["validate_dir"]).is_dir()
            assert f"# validate_dir is {val}: no recording went to validate" in text
            assert ("# root_dir is" in text) == (root != "train")
