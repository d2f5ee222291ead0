"""KITTI-style output read back with KITTI's conventions (written out here: camera-frame boxes with the location
at the bottom centre, ``rotation_y`` about the camera's y axis, ``Tr_velo_to_cam``, ``P2``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from kitti_files import read_calib
from mmusv.export import convert
from mmusv.recording import decode_point_cloud, read_messages


def parse_labels(path: Path) -> list[dict[str, Any]]:
    rows = []
    for line in path.read_text().splitlines():
        f = line.split()
        assert len(f) == 15
        if f[0] == "DontCare":  # a region to ignore, not an object
            continue
        rows.append(
            {
                "type": f[0],
                "truncated": float(f[1]),
                "occluded": int(f[2]),
                "alpha": float(f[3]),
                "bbox": [float(v) for v in f[4:8]],
                "hwl": [float(v) for v in f[8:11]],
                "xyz": np.array([float(v) for v in f[11:14]]),
                "ry": float(f[14]),
            }
        )
    return rows


def in_kitti_box(p_cam: np.ndarray, label: dict[str, Any], tol: float) -> np.ndarray:
    """Points (camera frame) inside the KITTI box: translate to the bottom centre, rotate by -ry about y."""
    h, w, length = label["hwl"]
    c, s = math.cos(label["ry"]), math.sin(label["ry"])
    rot_y = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    local = (p_cam - label["xyz"]) @ rot_y  # rows: R^T (p - t)
    inside: np.ndarray = (
        (np.abs(local[:, 0]) <= length / 2 + tol)
        & (np.abs(local[:, 2]) <= w / 2 + tol)
        & (local[:, 1] <= tol)
        & (local[:, 1] >= -h - tol)
    )
    return inside


@pytest.fixture(scope="module")
def kitti_out(coop_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("kitti")
    convert(coop_rec, to="kitti", out_dir=out, splits=None)
    return out / "export_coop"


def test_kitti_layout_and_boxes(kitti_out: Path, coop_rec: Path) -> None:
    clouds: dict[tuple[str, int], dict[str, np.ndarray]] = {}
    worlds: dict[int, Any] = {}
    anns: dict[tuple[str, int], Any] = {}
    for topic, t, msg in read_messages(
        coop_rec, topics=["/usv_a/lidar", "/usv_b/lidar", "/world/state", "/usv_a/annotations", "/usv_b/annotations"]
    ):
        k = round(t * 5 / 1e9)
        if topic == "/world/state":
            worlds[k] = msg
        elif topic.endswith("/lidar"):
            clouds[(topic.split("/")[1], k)] = decode_point_cloud(msg)
        else:
            anns[(topic.split("/")[1], k)] = msg
    checked = 0
    for cav, agent in (("1000", "usv_a"), ("1002", "usv_b")):
        d = kitti_out / cav
        assert sorted(p.name for p in d.iterdir()) == sorted(
            [
                "calib",
                "image_2",
                "label_2",
                "pose",
                "velodyne",
                "depth_2",
                "semantic_2",
                "radar_ppi",
                "top_view_rgb",
                "top_view_semantic",
            ]
        )
        for k in range(3):
            ts = f"{k:06d}"
            pts = np.fromfile(d / "velodyne" / f"{ts}.bin", dtype="<f4").reshape(-1, 4)
            rec = clouds[(agent, k)]
            np.testing.assert_allclose(pts[:, :3], np.column_stack([rec["x"], rec["y"], rec["z"]]), atol=1e-6)
            calib = read_calib(d / "calib" / f"{ts}.txt")
            assert set(calib) == {"P0", "P1", "P2", "P3", "R0_rect", "Tr_velo_to_cam", "Tr_imu_to_velo"}
            p2 = calib["P2"].reshape(3, 4)
            assert (
                p2[0, 0] == pytest.approx(80.0) and p2[0, 2] == pytest.approx(80.0) and p2[1, 2] == pytest.approx(60.0)
            )
            tr = np.vstack([calib["Tr_velo_to_cam"].reshape(3, 4), [0, 0, 0, 1]])
            p_cam = pts[:, :3].astype(np.float64) @ tr[:3, :3].T + tr[:3, 3]
            labels = parse_labels(d / "label_2" / f"{ts}.txt")
            ws = worlds[k]
            by_name = {v.id: v for v in ws.vessels}
            assert len(labels) == 2  # the tug and the speedboat; no USV
            boxes2d = {b.target_id: b for b in anns[(agent, k)].boxes_camera if b.camera == "front"}
            for lab, name in zip(labels, ("tgt", "boat"), strict=True):
                v = by_name[name]
                assert lab["type"] == "Vessel"
                np.testing.assert_allclose(lab["hwl"], [v.box_size[2], v.box_size[1], v.box_size[0]], atol=0.01)
                assert -math.pi <= lab["alpha"] <= math.pi and -math.pi <= lab["ry"] <= math.pi
                if name in boxes2d and boxes2d[name].visible_pixels > 0:
                    b = boxes2d[name]
                    np.testing.assert_allclose(lab["bbox"], [b.x_min, b.y_min, b.x_max, b.y_max], atol=0.006)
                else:  # out of the image, or in it with no pixel seen (hidden wholly: KITTI's "unknown")
                    assert lab["occluded"] == 3 and lab["bbox"] == [0.0, 0.0, 0.0, 0.0]
                own = p_cam[rec["instance"] == v.instance_id]
                if len(own):
                    # KITTI boxes are yaw-only: allow for the hull's roll and pitch in waves
                    frac = in_kitti_box(own, lab, 0.15).mean()
                    assert frac > 0.97, (cav, k, name, frac)
                    checked += len(own)
                # the label's heading is the vessel's: the box x axis in the LiDAR frame has the annotation yaw
                ann = {b.target_id: b for b in anns[(agent, k)].boxes_lidar}
                if name in ann:
                    x_cam = np.array([math.cos(lab["ry"]), 0.0, -math.sin(lab["ry"])])
                    x_velo = tr[:3, :3].T @ x_cam
                    yaw = math.atan2(x_velo[1], x_velo[0])
                    assert (yaw - ann[name].yaw + math.pi) % (2 * math.pi) - math.pi == pytest.approx(0.0, abs=0.03)
    assert checked > 200
