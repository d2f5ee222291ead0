"""Fields of the KITTI, KITTI tracking, COCO, YOLO, SemanticKITTI and MaSTr exports checked against what the peers'
own definitions say they mean, with the values expected from the recording (its annotations), not from the writers.

* KITTI object ``truncated``: the devkit's readme (``devkit_object/readme.txt``) defines it as a "Float from 0
  (non-truncated) to 1 (truncated), where truncated refers to the object leaving image boundaries"; a target with no
  box in the front image (occluded 3, box ``0 0 0 0``) behind or beside the camera has wholly left the image, so 1,
  as the tracking export's level 2 ("out of the image") of the same line says, not 0 (a target wholly in the image);
  one in view that no pixel centre meets, the share of its projected box outside the image.
* KITTI tracking ``truncated``: the devkit's readme (``devkit_tracking/readme.txt``) makes it an "Integer (0,1,2)
  indicating the level of truncation", the levels of KITTI's raw-data tracklets (``TRUNC_IN_IMAGE`` 0,
  ``TRUNC_TRUNCATED`` 1, ``TRUNC_OUT_IMAGE`` 2): a target with a box in the image is never 2, however much of it the
  border cuts (a sliver of a long ship whose object-label fraction rounds to 1.00).
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from kitti_files import label_corners, read_calib
from mmusv.export import convert
from mmusv.export.geometry import Target
from mmusv.export.kitti import LIDAR_OPTICAL, kitti_label
from mmusv.recording import frame_messages, read_info, topics


@pytest.fixture(params=["port_rec", "no_camera_rec"])
def kitti_case(request: pytest.FixtureRequest, tmp_path: Path) -> tuple[Path, Path]:
    """A recording (``port``: targets in range behind and beside the front cameras; ``no_camera``: agents without a
    front camera) and its KITTI export's scenario folder."""
    rec: Path = request.getfixturevalue(request.param)
    convert(rec, to="kitti", out_dir=tmp_path / "o", splits=None)
    return rec, tmp_path / "o" / rec.stem


def _share_out_of_image(fields: list[str], boxes: list[Any], calib: Path, image: Path) -> float | None:
    """The share of a label line's target whose pinhole image (``P2`` of ``calib``) lies outside ``image``: its
    recorded 3D box (of ``boxes``, the frame's LiDAR boxes, the one whose centre carried by ``Tr_velo_to_cam`` lies
    nearest the label's box centre), with its whole rotation (a camera rolling on the waves sees the box rolled,
    which the label's ``rotation_y`` alone cannot say), corners projected by ``P2``; 1.0 without a camera (zero
    ``P2``) or with the box wholly behind it; ``None`` for a box across the camera's plane (not worked out here)."""
    cal = read_calib(calib)
    p = cal["P2"]
    if not p.any() or not image.is_file():
        return 1.0
    from PIL import Image

    with Image.open(image) as img:
        width, height = img.size
    tr = cal["Tr_velo_to_cam"].reshape(3, 4)
    label_centre = label_corners(fields).mean(axis=0)
    box = min(boxes, key=lambda b: float(np.linalg.norm(tr[:, :3] @ np.asarray(b.center) + tr[:, 3] - label_centre)))
    x, y, z, w = box.rotation
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
    corners = (signs * np.asarray(box.size) / 2.0) @ rot.T + np.asarray(box.center)
    corners = corners @ tr[:, :3].T + tr[:, 3]
    if np.all(corners[:, 2] <= 0.0):
        return 1.0
    if np.any(corners[:, 2] <= 0.1):
        return None
    uvw = np.c_[corners, np.ones(8)] @ p.reshape(3, 4).T
    u, v = uvw[:, 0] / uvw[:, 2], uvw[:, 1] / uvw[:, 2]
    area = (u.max() - u.min()) * (v.max() - v.min())
    cw = min(u.max(), width) - max(u.min(), 0.0)
    ch = min(v.max(), height) - max(v.min(), 0.0)
    return 1.0 if cw <= 0 or ch <= 0 else float(1.0 - cw * ch / area)


def test_kitti_truncated_is_the_share_out_of_the_front_image(kitti_case: tuple[Path, Path]) -> None:
    """A label line without a recorded front-camera box (occluded 3, box ``0 0 0 0``) says how much of the target
    leaves the image: 1.00 behind or beside the camera or without one (these recordings' cases; before, 0.00, "wholly
    in the image"), the share of its projected box outside the image for one in view that no pixel centre meets
    (``tests/test_review_round8.py``'s kayak); a target with a box keeps the recorded fraction (two decimals)."""
    rec, kitti = kitti_case
    info = read_info(rec)
    out_of_image = 0
    for a in info.agents:
        agent = kitti / str(1000 + a.index)
        for path in sorted((agent / "label_2").glob("*.txt")):
            k = int(path.stem)
            ann = frame_messages(rec, k)[topics.agent_annotations(a.id)]
            boxes = [b for b in ann.boxes_camera if b.camera == "front"]
            calib = agent / "calib" / path.name
            for line in path.read_text().splitlines():
                f = line.split()
                if f[0] == "DontCare":  # a region to ignore: no truncation of its own (-1)
                    continue
                truncated, occluded, bbox = float(f[1]), int(f[2]), [float(v) for v in f[4:8]]
                assert 0.0 <= truncated <= 1.0 and f[1] == f"{truncated:.2f}"
                if occluded == 3:
                    assert bbox == [0.0, 0.0, 0.0, 0.0]
                    want = _share_out_of_image(f, ann.boxes_lidar, calib, agent / "image_2" / f"{path.stem}.png")
                    if want is not None:
                        assert truncated == pytest.approx(want, abs=0.0051), (a.id, k, line)
                    out_of_image += truncated == 1.0
                else:
                    b = min(
                        boxes,
                        key=lambda b: float(np.abs(np.subtract([b.x_min, b.y_min, b.x_max, b.y_max], bbox)).max()),
                    )
                    assert truncated == pytest.approx(float(b.truncation), abs=0.005)
    assert out_of_image >= 2  # targets in range the front cameras do not see (or no front camera)


def _target_ahead() -> Target:
    """A 30 m ship 40 m ahead of the LiDAR (x forward), heading across the view (its x axis to the left)."""
    box = np.eye(4)
    box[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    box[:3, 3] = [40.0, 0.0, 2.0]
    size = np.array([30.0, 8.0, 10.0])
    return Target(0, "ship", "ship", "target", 10, 5, box, box, box, size, 0.0)


@pytest.mark.parametrize(
    ("fraction", "level"), [(0.0, "0"), (0.004, "0"), (0.3, "1"), (0.996, "1"), (1.0 - 1e-9, "1"), (None, "2")]
)
def test_kitti_tracking_truncation_level_is_2_only_out_of_the_image(fraction: float | None, level: str) -> None:
    """The tracking line's level: 0 when the object label writes 0.00, 1 for any box the border cuts (also one whose
    fraction the object label writes as 1.00), 2 only without a box in the image (occluded 3)."""
    box2d = (
        None
        if fraction is None
        else SimpleNamespace(truncation=fraction, occlusion=0.1, x_min=150.0, y_min=50.0, x_max=160.0, y_max=70.0)
    )
    line = kitti_label(_target_ahead(), LIDAR_OPTICAL, box2d=box2d, levels=True).split()
    obj = kitti_label(_target_ahead(), LIDAR_OPTICAL, box2d=box2d).split()
    assert line[1] == level and (line[2] == "3") == (fraction is None)
    assert line[:1] + line[2:] == obj[:1] + obj[2:]  # the object label's line but for truncated
    assert obj[1] == ("1.00" if fraction is None else f"{round(fraction, 2) + 0.0:.2f}")
