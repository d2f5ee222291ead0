"""OPV2V frames the detection study reads (``mmusv study detection --opv2v``, :func:`read_opv2v`) with values that
are not finite: a NaN or infinite point in a ``.pcd`` reached the baseline detector's water-plane fit and ended the
study with numpy's LinAlgError traceback; a NaN ``lidar_pose`` or ``true_ego_pos`` dropped the frame's ground truth
without a word (0.67 boxes per ego-frame instead of 1.00), and a pose of another length was refused without naming
the file. Each is now an IoError naming the frame's file and the field."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from mmusv.errors import IoError
from mmusv.export.pcd import read_pcd, write_pcd
from mmusv.studies.detection.data import read_opv2v

POSE = [0.8, 0.0, 2.3, 0.0, 0.0, 0.0]
VEHICLE = {"angle": [0.0, 0.0, 0.0], "center": [0.0, 0.0, 1.0], "extent": [6.0, 2.0, 1.5], "location": [40.0, 5.0, 0]}


def _scenario(tmp_path: Path, *, doc: dict[str, object] | None = None, pcd: str | None = None) -> Path:
    cav = tmp_path / "seq" / "1000"
    cav.mkdir(parents=True)
    xyz = np.array([[10.0, 1.0, -2.0], [20.0, -3.0, -2.1], [30.0, 2.0, -1.9], [40.0, 5.0, 1.0]])
    write_pcd(cav / "000000.pcd", xyz=xyz, intensity=np.full(4, 0.5))
    if pcd is not None:
        text = (cav / "000000.pcd").read_text(encoding="ascii").splitlines(keepends=True)
        text[-1] = pcd
        (cav / "000000.pcd").write_text("".join(text), encoding="ascii")
    base = {"lidar_pose": POSE, "true_ego_pos": [0.0] * 6, "vehicles": {1001: VEHICLE}}
    (cav / "000000.yaml").write_text(yaml.safe_dump({**base, **(doc or {})}), encoding="utf-8")
    return tmp_path / "seq"


def test_a_whole_frame_reads(tmp_path: Path) -> None:
    seq = read_opv2v(_scenario(tmp_path))
    assert len(seq.frames) == 1 and seq.frames[0].target_ids == ("1001",)


@pytest.mark.parametrize(
    ("row", "said"),
    [
        ("nan 5.0 1.0 8323072\n", "not finite"),
        ("40.0 inf 1.0 8323072\n", "not finite"),
        ("40.0 5.0 1.0 1e30\n", "rgb is an unsigned 32-bit integer"),
        ("40.0 5.0 1.0 -1\n", "rgb is an unsigned 32-bit integer"),
    ],
)
def test_a_cloud_of_a_point_not_finite_is_refused_naming_the_file(tmp_path: Path, row: str, said: str) -> None:
    folder = _scenario(tmp_path, pcd=row)
    with pytest.raises(IoError) as info:
        read_opv2v(folder)
    msg = str(info.value)
    assert "000000.yaml" in msg and "000000.pcd: point 3" in msg and said in msg, msg
    with pytest.raises(ValueError, match="point 3"):
        read_pcd(folder / "1000" / "000000.pcd")


@pytest.mark.parametrize(
    ("key", "value", "said"),
    [
        (
            "lidar_pose",
            [float("nan"), 0, 2.3, 0, 0, 0],
            "lidar_pose = [nan, 0.0, 2.3, 0.0, 0.0, 0.0]: must be 6 finite",
        ),
        (
            "true_ego_pos",
            [0, 0, 0, 0, float("inf"), 0],
            "true_ego_pos = [0.0, 0.0, 0.0, 0.0, inf, 0.0]: must be 6 finite",
        ),
        ("lidar_pose", [1, 2], "lidar_pose = [1, 2]: must be 6 numbers"),
        ("true_ego_pos", 5, "true_ego_pos = 5: must be 6 numbers"),
    ],
)
def test_a_pose_not_of_6_finite_numbers_is_refused_naming_the_file(
    tmp_path: Path, key: str, value: object, said: str
) -> None:
    with pytest.raises(IoError) as info:
        read_opv2v(_scenario(tmp_path, doc={key: value}))
    msg = str(info.value)
    assert "000000.yaml: not a readable OPV2V frame" in msg and said in msg, msg
