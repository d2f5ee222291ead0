"""``--to semantickitti``: scans and labels with equal counts, labels equal to the recording's per-point class and
instance, poses that chain to the recording's LiDAR poses, the label map, and clean errors on bad input."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.errors import ConfigError, IoError
from mmusv.export import convert
from mmusv.recording import decode_point_cloud, read_info, read_messages, topics
from scipy.spatial.transform import Rotation


@pytest.fixture(scope="module")
def sk_dir(coop_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sk") / "o"
    convert(coop_rec, to="semantickitti", out_dir=out, splits=None)
    return out


def kitti_matrix(line: str) -> np.ndarray:
    """A 3×4 row-major line as a 4×4 matrix (semantic-kitti-api's parse_calibration / parse_poses)."""
    m = np.eye(4)
    m[:3, :4] = np.array([float(v) for v in line.split()]).reshape(3, 4)
    return m


def recording(rec: Path) -> dict[str, list[Any]]:
    out: dict[str, list[Any]] = defaultdict(list)
    for topic, _t, msg in read_messages(rec):
        out[topic].append(msg)
    return out


def tf_matrix(x: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([x.rotation.x, x.rotation.y, x.rotation.z, x.rotation.w]).as_matrix()
    m[:3, 3] = [x.translation.x, x.translation.y, x.translation.z]
    return m


def test_scans_labels_and_poses(sk_dir: Path, coop_rec: Path) -> None:
    info = read_info(coop_rec)
    src = recording(coop_rec)
    for number, a in enumerate(info.agents):  # one sequence per agent, in agent order
        seq = sk_dir / "sequences" / f"{number:02d}"
        scans = sorted((seq / "velodyne").glob("*.bin"))
        labels = sorted((seq / "labels").glob("*.label"))
        poses = (seq / "poses.txt").read_text().splitlines()
        assert [p.stem for p in scans] == [p.stem for p in labels] == [f"{i:06d}" for i in range(3)]
        assert len(poses) == 3 and (seq / "frames.txt").read_text().split() == ["0", "1", "2"]
        calib = {
            k: kitti_matrix(v) for k, v in (line.split(":", 1) for line in (seq / "calib.txt").read_text().splitlines())
        }
        assert sorted(calib) == ["P0", "P1", "P2", "P3", "Tr"]
        tr = calib["Tr"]
        lidar_world = []
        for tf in src[topics.TF]:
            edges = {(x.parent_frame_id, x.child_frame_id): tf_matrix(x) for x in tf.transforms}
            lidar_world.append(edges[(topics.WORLD_FRAME, a.id)] @ edges[(a.id, topics.lidar_frame(a.id))])
        for i, (scan, label, msg) in enumerate(zip(scans, labels, src[topics.lidar(a.id)], strict=True)):
            ref = decode_point_cloud(msg)
            pts = np.fromfile(scan, dtype="<f4").reshape(-1, 4)
            lab = np.fromfile(label, dtype="<u4")
            assert len(pts) == len(lab) == len(ref["x"]) > 0
            for j, name in enumerate(("x", "y", "z", "intensity")):
                np.testing.assert_array_equal(pts[:, j], ref[name])
            np.testing.assert_array_equal(lab & 0xFFFF, ref["class"])
            # a vessel's points carry its world-state instance id, every other point (sea, land, buoys) 0 ("stuff")
            vessels = [v.instance_id for v in src[topics.WORLD_STATE][i].vessels]
            vessel = np.isin(ref["instance"], vessels)
            np.testing.assert_array_equal(lab >> 16, np.where(vessel, ref["instance"], 0))
            assert np.any(~vessel & (ref["instance"] != 0)), "no non-vessel point with a scene instance: no check"
            # semantic-kitti-api: the LiDAR pose of scan i in scan 0's LiDAR frame = Tr⁻¹ · pose_i · Tr
            velo = np.linalg.inv(tr) @ kitti_matrix(poses[i]) @ tr
            np.testing.assert_allclose(velo, np.linalg.inv(lidar_world[0]) @ lidar_world[i], atol=2e-5)
        assert np.any(lab >> 16)  # some points carry an instance


def test_label_map(sk_dir: Path) -> None:
    doc = yaml.safe_load((sk_dir / "semantic-kitti.yaml").read_text())
    assert set(doc) >= {
        "labels",
        "color_map",
        "content",
        "learning_map",
        "learning_map_inv",
        "learning_ignore",
        "split",
    }
    assert doc["labels"][10] == "vessel" and doc["learning_map"][0] == 0 and doc["learning_ignore"][0] is True
    assert sum(doc["content"].values()) == pytest.approx(1.0, abs=1e-6)
    assert doc["split"] == {"train": [0, 1], "valid": [], "test": []}
    assert all(doc["learning_map_inv"][v] == k for k, v in doc["learning_map"].items() if v)


def test_split_lists_sequences(many_recs: list[Path], tmp_path: Path) -> None:
    convert(many_recs, to="semantickitti", out_dir=tmp_path / "s")
    doc = yaml.safe_load((tmp_path / "s" / "semantic-kitti.yaml").read_text())
    conv = yaml.safe_load((tmp_path / "s" / "conversion.yaml").read_text())
    counts = {s: sum(1 for r in conv["recordings"] if r["split"] == s) for s in ("train", "validate", "test")}
    assert {k: len(v) for k, v in doc["split"].items()} == {
        "train": 2 * counts["train"],
        "valid": 2 * counts["validate"],
        "test": 2 * counts["test"],
    }
    assert sorted(n for v in doc["split"].values() for n in v) == list(range(10))


def test_bad_input(no_lidar_rec: Path, coop_rec: Path, sk_dir: Path, tmp_path: Path) -> None:
    with pytest.raises(
        ConfigError, match=r"export_no_lidar\.mcap: cannot convert to semantickitti: no agent with a LiDAR"
    ):
        convert(no_lidar_rec, to="semantickitti", out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()
    with pytest.raises(IoError, match="already exists"):
        convert(coop_rec, to="semantickitti", out_dir=sk_dir)
