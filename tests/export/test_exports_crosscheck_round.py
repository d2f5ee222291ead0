"""One frame, every export, the same truth: a vessel must sit in the same place with the same size, heading, class and
track id in every format a recording converts to, read as each format's peer reads it, and agree with the recording's
ground-truth tables (``docs/recording.md``). Nothing here comes from the writers' code: the poses are built from the
``world_state`` table (``Rz(yaw)·Ry(pitch)·Rx(roll)``) and the recorded sensor mounts, each export is parsed from its
files (OPV2V's yaml poses through a CARLA ``x_to_world`` written here, KITTI's labels as the devkit and as OpenPCDet
read them, the ROS 2 bag through mcap-ros2-support and its TF tree, COCO/YOLO/MOT boxes from their text), and the
documented differences (KITTI's yaw-only boxes, the 2-decimal KITTI numbers, the range filters, MOT's 1-based
pixels, the bag's 1 s time offset) are the only ones allowed.

One recording (session scope, 2 frames of the bundled port map in the physical sea at W3, so hulls roll and pitch by
degrees): three USVs with the small rig of ``conftest.py`` and a front camera with Brown–Conrady distortion; ``usv_3``'s
front camera is mounted turned against its LiDAR (``rpy_deg``), the case where KITTI's LiDAR-frame readers and its
devkit part ways; the ferry is a 140 m container feeder; four ships are moored at the quays.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from mmusv.classes import class_name
from mmusv.export import convert
from mmusv.recording import decode_image, read_info, read_messages
from mmusv.recording.tables import read_table
from scipy.spatial.transform import Rotation

_spec = importlib.util.spec_from_file_location("_export_conftest_helpers", Path(__file__).with_name("conftest.py"))
assert _spec is not None and _spec.loader is not None
_helpers = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_helpers)
small_rig = _helpers.small_rig
REPO: Path = _helpers.REPO

DISTORTION = [-0.12, 0.03, 0.001, -0.002, 0.0]
TURNED = [3.0, 8.0, 10.0]
"""``rpy_deg`` of ``usv_3``'s front camera on its mount point."""
FORMATS = ("opv2v", "kitti", "ros2", "coco", "yolo", "mot", "kitti_tracking", "semantickitti")
OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
"""Body axes (x forward, y left, z up) → optical axes (x right, y down, z forward)."""


def _rot(axis: int, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def _T(r: np.ndarray, t: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = t
    return m


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def _carla(pose: list[float]) -> np.ndarray:
    """OpenCOOD's ``x_to_world`` of a CARLA pose ``[x, y, z, roll, yaw, pitch]`` (metres, degrees), left-handed:
    ``Rz(yaw)·Ry(−pitch)·Rx(−roll)`` in the left-handed axes."""
    x, y, z, roll, yaw, pitch = pose
    r = _rot(2, math.radians(yaw)) @ _rot(1, -math.radians(pitch)) @ _rot(0, -math.radians(roll))
    return _T(r, [x, y, z])


MIRROR = np.diag([1.0, -1.0, 1.0, 1.0])
"""CARLA (y right) ↔ mmusv (y left): ``S·m·S`` turns a transform of one into the other's."""


# ------------------------------------------------------------------------------------------------ the recording


@pytest.fixture(scope="session")
def xc(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The recording, its ground truth and its conversion to every format (no split)."""
    from mmusv.acquire import run

    d: dict[str, Any] = yaml.safe_load((REPO / "scenarios" / "port_entry.yaml").read_text())
    d["name"] = "xc_port"
    d["acquisition"]["frames"] = 2
    d["environment"] = {"time_of_day": "16:30", "weather": "clear", "wave": "W3"}  # motion: physical (default)
    level, turned = small_rig(), small_rig()
    level["cameras"][0] = {**level["cameras"][0], "distortion": DISTORTION}
    turned["cameras"][0] = {
        **turned["cameras"][0],
        "distortion": DISTORTION,
        "mount": {"point": "camera_front", "rpy_deg": TURNED},
    }
    d["rigs"] = {"usv_standard": level, "turned": turned}
    for v in d["vessels"]:
        if v["id"] == "usv_3":
            v["rig"] = "turned"
        if v["id"] == "ferry":
            v["asset"] = "feeder_container_140m"
    root = tmp_path_factory.mktemp("xc")
    rec = Path(run(d, out_dir=root / "rec").recording)
    out = {f: root / f for f in FORMATS}
    notes = {}
    for f in FORMATS:
        report = convert(rec, to=f, out_dir=out[f], splits=None, extras="")
        notes[f] = [n for r in report.recordings for n in r.notes]
    tables = rec.parent / "tables"
    return {
        "rec": rec,
        "info": read_info(rec),
        "ws": read_table(tables, "world_state").rows,
        "b3": read_table(tables, "boxes_3d").rows,
        "b2": read_table(tables, "boxes_2d").rows,
        "out": out,
        "notes": notes,
    }


def _world(xc: dict[str, Any], frame: int) -> dict[str, dict[str, Any]]:
    """Per vessel id at ``frame``: its world-state ``row`` (index), table ``r``, ``body`` and ``box`` → world."""
    out = {}
    for i, r in enumerate(xc["ws"].filter(pl.col("frame") == frame).iter_rows(named=True)):
        rot = _rot(2, r["yaw"]) @ _rot(1, r["pitch"]) @ _rot(0, r["roll"])
        out[r["vessel_id"]] = {
            "row": i,
            "r": r,
            "body": _T(rot, [r["x"], r["y"], r["z"]]),
            "box": _T(rot, [r["box_cx"], r["box_cy"], r["box_cz"]]),
            "size": np.array([r["length"], r["beam"], r["height"]]),
        }
    return out


def _lidar(xc: dict[str, Any], frame: int, agent: Any) -> np.ndarray:
    return _world(xc, frame)[agent.id]["body"] @ agent.lidar_mount


def _targets(xc: dict[str, Any], frame: int, agent: Any, range_m: float = 200.0) -> dict[str, dict[str, Any]]:
    """The agent's targets (docs: box centre within the range of its LiDAR in bird's-eye view, other USVs left out),
    each with ``m``, its box → LiDAR, in world-state order."""
    w = _world(xc, frame)
    inv = np.linalg.inv(_lidar(xc, frame, agent))
    out = {}
    for vid, v in w.items():
        m = inv @ v["box"]
        if vid != agent.id and v["r"]["role"] != "usv" and math.hypot(m[0, 3], m[1, 3]) <= range_m:
            out[vid] = {**v, "m": m}
    return out


def _calib(path: Path) -> dict[str, np.ndarray]:
    out = {}
    for line in path.read_text().splitlines():
        key, _, vals = line.partition(":") if ":" in line else line.partition(" ")
        out[key] = np.array(vals.split(), dtype=np.float64)
    return out


def _velo_to_cam(cal: dict[str, np.ndarray], key: str = "Tr_velo_to_cam") -> np.ndarray:
    v = np.eye(4)
    v[:3] = cal[key].reshape(3, 4)
    return v


FRAMES = (0, 1)


# ------------------------------------------------------------------------------------------------ 3D boxes


def test_opv2v_boxes_read_with_x_to_world_are_the_world_state_boxes(xc: dict[str, Any]) -> None:
    """OPV2V's vehicles (``location + center`` with ``angle`` [roll, yaw, pitch], ``extent``), taken into the agent's
    LiDAR with its ``lidar_pose`` as OpenCOOD does, are the world state's rolled and pitched boxes (the full rotation,
    not only the yaw), and the listed vessels are exactly the targets in range, keyed 1000 + their world-state row."""
    listed: list[dict[str, Any]] = []
    for f in FRAMES:
        for a in xc["info"].agents:
            d = xc["out"]["opv2v"] / "xc_port" / str(1000 + a.index)
            doc = yaml.safe_load((d / f"{f:06d}.yaml").read_text())
            add = yaml.safe_load((d / f"{f:06d}_additional.yaml").read_text())["mmusv"]["vehicles"]
            lidar = _carla(doc["lidar_pose"])
            np.testing.assert_allclose(MIRROR @ lidar @ MIRROR, _lidar(xc, f, a), atol=1e-5)
            gt = _targets(xc, f, a)
            assert {add[k]["name"] for k in doc["vehicles"]} == set(gt), (f, a.id)
            for k, v in doc["vehicles"].items():
                g = gt[add[k]["name"]]
                listed.append(g)
                assert int(k) == 1000 + g["row"]
                assert add[k]["semantic_class"] == g["r"]["semantic_class"] and add[k]["role"] == g["r"]["role"]
                assert add[k]["static"] == g["r"]["static"]
                obj = _carla([v["location"][i] + v["center"][i] for i in range(3)] + list(v["angle"]))
                m = MIRROR @ np.linalg.inv(lidar) @ obj @ MIRROR
                np.testing.assert_allclose(m[:3, 3], g["m"][:3, 3], atol=1e-4)
                np.testing.assert_allclose(m[:3, :3], g["m"][:3, :3], atol=1e-6)
                np.testing.assert_allclose(2.0 * np.array(v["extent"]), g["size"], atol=1e-6)
    # the cases this file is about are in it: a moored ship, a 100 m+ ship, hulls rolling and pitching by degrees
    assert any(g["r"]["role"] == "moored" for g in listed) and max(g["size"][0] for g in listed) >= 100.0
    assert max(abs(g["r"]["roll"]) for g in listed) > math.radians(1.0)


def _kitti_lines(xc: dict[str, Any], f: int, a: Any) -> tuple[list[list[str]], np.ndarray]:
    d = xc["out"]["kitti"] / "xc_port" / str(1000 + a.index)
    text = (d / "label_2" / f"{f:06d}.txt").read_text()
    lines = [line.split() for line in text.splitlines() if not line.startswith("DontCare ")]  # regions to ignore
    return lines, _velo_to_cam(_calib(d / "calib" / f"{f:06d}.txt"))


def test_kitti_labels_read_as_the_devkit_are_the_world_state_boxes(xc: dict[str, Any]) -> None:
    """KITTI's ``label_2``, read as the devkit reads it (camera frame, box upright about the camera's y, location at
    the bottom centre: the centre is ``h/2`` up the camera's y), taken into the LiDAR with ``Tr_velo_to_cam``: the
    same vessels in world-state order, sizes exact, centres to the labels' 2 decimals, and ``rotation_y`` the heading
    of the box's x axis projected onto the camera's x-z plane (KITTI's yaw-only box), for a level camera and for a
    turned one. ``pose`` is the LiDAR → world, ``Tr_imu_to_velo`` the inverse of the LiDAR's mount."""
    for f in FRAMES:
        for a in xc["info"].agents:
            lines, v = _kitti_lines(xc, f, a)
            np.testing.assert_allclose(
                v, _T(OPTICAL, [0, 0, 0]) @ np.linalg.inv(a.cameras["front"].mount) @ a.lidar_mount, atol=1e-6
            )
            d = xc["out"]["kitti"] / "xc_port" / str(1000 + a.index)
            pose = np.loadtxt(d / "pose" / f"{f:06d}.txt").reshape(3, 4)
            np.testing.assert_allclose(pose, _lidar(xc, f, a)[:3], atol=1e-3, rtol=1e-5)
            gt = _targets(xc, f, a)
            assert len(lines) == len(gt), (f, a.id)
            for g, line in zip(sorted(gt.values(), key=lambda g: g["row"]), lines, strict=True):
                assert line[0] == {10: "Vessel", 11: "Usv"}[g["r"]["semantic_class"]]
                h, w, length = map(float, line[8:11])
                np.testing.assert_allclose([length, w, h], g["size"], atol=0.005)
                centre_cam = np.array(line[11:14], dtype=np.float64) - [0.0, h / 2.0, 0.0]
                centre = (np.linalg.inv(v) @ np.r_[centre_cam, 1.0])[:3]
                np.testing.assert_allclose(centre, g["m"][:3, 3], atol=0.01)
                heading_cam = (v @ g["m"])[:3, 0]  # the box's x axis in the camera frame
                ry = math.atan2(-heading_cam[2], heading_cam[0])
                assert abs(_wrap(float(line[14]) - ry)) <= 0.0051, (f, a.id, line, ry)


def test_kitti_labels_read_as_openpcdet_on_a_level_camera(xc: dict[str, Any]) -> None:
    """OpenPCDet's ``boxes3d_kitti_camera_to_lidar`` (``rect_to_lidar`` of the location, then ``h/2`` along the LiDAR's
    z, heading ``−(rotation_y + π/2)``) gets the world state's box centre and yaw back for the agents whose front camera
    sits level and forward (the default mounts), the hulls rolling and pitching in waves."""
    for f in FRAMES:
        for a in xc["info"].agents:
            if a.id == "usv_3":
                continue
            lines, v = _kitti_lines(xc, f, a)
            gt = _targets(xc, f, a)
            for g, line in zip(sorted(gt.values(), key=lambda g: g["row"]), lines, strict=True):
                h = float(line[8])
                p = (np.linalg.inv(v) @ np.r_[np.array(line[11:14], dtype=np.float64), 1.0])[:3]
                p[2] += h / 2.0
                np.testing.assert_allclose(p, g["m"][:3, 3], atol=0.01)
                yaw = math.atan2(g["m"][1, 0], g["m"][0, 0])
                assert abs(_wrap(-(float(line[14]) + math.pi / 2.0) - yaw)) <= 0.0051


def test_kitti_notes_a_front_camera_turned_against_the_lidar(xc: dict[str, Any]) -> None:
    """``usv_3``'s front camera is mounted turned (``rpy_deg`` 3°, 8°, 10°): its labels are in its frame, as the
    devkit reads them (above), but OpenPCDet's conversion leaves out the calibration's rotation and misplaces and
    turns every box (metres for the 140 m feeder). The KITTI and KITTI tracking conversions must say so for that
    agent, with the angles, and not for the level ones (docs/exports.md, *OPV2V and KITTI*)."""
    a = next(x for x in xc["info"].agents if x.id == "usv_3")
    for f in FRAMES:  # the defect the note is about, measured
        lines, v = _kitti_lines(xc, f, a)
        for g, line in zip(sorted(_targets(xc, f, a).values(), key=lambda g: g["row"]), lines, strict=True):
            h = float(line[8])
            p = (np.linalg.inv(v) @ np.r_[np.array(line[11:14], dtype=np.float64), 1.0])[:3]
            p[2] += h / 2.0
            tilt = math.acos(-float(v[1, 2]))
            assert np.linalg.norm(p - g["m"][:3, 3]) == pytest.approx(h * math.sin(tilt / 2.0), abs=0.02)
            yaw = math.atan2(g["m"][1, 0], g["m"][0, 0])
            assert abs(_wrap(-(float(line[14]) + math.pi / 2.0) - yaw)) > math.radians(5.0)
    for fmt in ("kitti", "kitti_tracking"):
        turned = [n for n in xc["notes"][fmt] if "turned" in n and "against the LiDAR" in n]
        assert len(turned) == 1 and turned[0].startswith("agent usv_3:"), (fmt, xc["notes"][fmt])
        assert "+10.00 deg off the LiDAR's x" in turned[0] and "OpenPCDet" in turned[0], turned[0]


def _bag(path: Path) -> dict[str, list[tuple[int, Any]]]:
    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with next(path.glob("*.mcap")).open("rb") as fh:
        for _s, ch, m, msg in make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            out[ch.topic].append((m.log_time, msg))
    return out


def _tf(tr: Any) -> np.ndarray:
    q = tr.rotation
    return _T(
        Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), [tr.translation.x, tr.translation.y, tr.translation.z]
    )


def _pose(p: Any) -> np.ndarray:
    q = p.orientation
    return _T(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), [p.position.x, p.position.y, p.position.z])


def test_ros2_boxes_through_the_tf_tree_are_the_world_state_boxes(xc: dict[str, Any]) -> None:
    """The bag's ``Detection3DArray`` (in ``<usv>/lidar``) and ``MarkerArray`` cubes, put in ``map`` through the bag's
    own TF tree (``/tf_static`` + the frame's ``/tf``), are the world state's boxes in the world, one per recorded
    ``boxes_3d`` row; the frame's stamp is its sim time + 1 s; ``Detection2DArray`` boxes are the recorded boxes less
    half a pixel; ``CameraInfo`` holds the OPV2V/KITTI intrinsics less half a pixel and the lens distortion."""
    bag = _bag(xc["out"]["ros2"] / "xc_port")
    static: dict[str, tuple[str, np.ndarray]] = {}
    for _t, msg in bag["/tf_static"]:
        static.update({x.child_frame_id: (x.header.frame_id, _tf(x.transform)) for x in msg.transforms})
    freq = xc["info"].frequency_hz
    for f in FRAMES:
        stamp = round(f / freq * 1e9) + 1_000_000_000
        tree = dict(static)
        (tf,) = [m for t, m in bag["/tf"] if t == stamp]
        tree.update({x.child_frame_id: (x.header.frame_id, _tf(x.transform)) for x in tf.transforms})

        def to_map(frame: str, tree: dict[str, tuple[str, np.ndarray]] = tree) -> np.ndarray:
            m = np.eye(4)
            while frame != "map":
                frame, step = tree[frame][0], tree[frame][1]
                m = step @ m
            return m

        w = _world(xc, f)
        for a in xc["info"].agents:
            (det,) = [m for t, m in bag[f"/{a.id}/detections"] if t == stamp]
            (mk,) = [m for t, m in bag[f"/{a.id}/boxes"] if t == stamp]
            assert det.header.frame_id == f"{a.id}/lidar"
            assert det.header.stamp.sec * 1_000_000_000 + det.header.stamp.nanosec == stamp
            rows = xc["b3"].filter((pl.col("frame") == f) & (pl.col("agent") == a.id))
            assert sorted(d.id for d in det.detections) == sorted(rows["target_id"].to_list())
            lidar = to_map(f"{a.id}/lidar")
            np.testing.assert_allclose(lidar, _lidar(xc, f, a), atol=1e-9)
            for d, cube in zip(det.detections, mk.markers[1:], strict=True):
                for box in (_pose(d.bbox.center), _pose(cube.pose)):
                    np.testing.assert_allclose(lidar @ box, w[d.id]["box"], atol=1e-6)
                size = [d.bbox.size.x, d.bbox.size.y, d.bbox.size.z]
                np.testing.assert_allclose(size, w[d.id]["size"], atol=1e-9)
                assert d.results[0].hypothesis.class_id == {10: "vessel", 11: "usv"}[w[d.id]["r"]["semantic_class"]]
            for name, cam in a.cameras.items():
                (ci,) = [m for t, m in bag[f"/{a.id}/camera/{name}/camera_info"] if t == stamp]
                fx, fy, cx, cy = cam.intrinsics
                np.testing.assert_allclose(ci.k, [fx, 0, cx - 0.5, 0, fy, cy - 0.5, 0, 0, 1])
                np.testing.assert_allclose(ci.d, cam.distortion or [0.0] * 5)
                (d2,) = [m for t, m in bag[f"/{a.id}/camera/{name}/detections"] if t == stamp]
                rec = {
                    r["target_id"]: r
                    for r in xc["b2"]
                    .filter((pl.col("frame") == f) & (pl.col("agent") == a.id) & (pl.col("camera") == name))
                    .iter_rows(named=True)
                }
                assert sorted(x.id for x in d2.detections) == sorted(rec)
                for x in d2.detections:
                    r = rec[x.id]
                    c = x.bbox.center.position
                    assert (c.x + 0.5, c.y + 0.5) == pytest.approx(
                        ((r["x_min"] + r["x_max"]) / 2, (r["y_min"] + r["y_max"]) / 2)
                    )
                    assert (x.bbox.size_x, x.bbox.size_y) == pytest.approx(
                        (r["x_max"] - r["x_min"], r["y_max"] - r["y_min"])
                    )


# ------------------------------------------------------------------------------------------------ 2D, ids, time


def test_2d_boxes_classes_and_track_ids_agree_across_coco_yolo_mot_kitti(xc: dict[str, Any]) -> None:
    """Per image: COCO's boxes are the tight boxes of the recorded instance image (one per recorded box with a visible
    pixel, the vessel's class, instance, truncation and occlusion), YOLO's lines the same boxes normalised with the
    class's position, MOT's lines the same boxes + 1 with track id 1 + the world-state row and visibility
    ``(1 − occlusion)(1 − truncation)``; KITTI's front 2D boxes are the recorded (projected) boxes and its occluded
    flags the recorded occlusion's levels; KITTI tracking's lines are KITTI's with the same track ids as MOT."""
    coco = json.loads((xc["out"]["coco"] / "annotations" / "instances_all.json").read_text())
    images = {i["id"]: i for i in coco["images"]}
    per: dict[tuple[int, str, str], list[dict[str, Any]]] = defaultdict(list)
    for an in coco["annotations"]:
        im = images[an["image_id"]]
        assert im["time_s"] == pytest.approx(im["frame"] / xc["info"].frequency_hz)
        per[(im["frame"], im["agent"], im["camera"])].append(an)
    inst = {}
    for topic, t, msg in read_messages(xc["rec"]):
        parts = topic.strip("/").split("/")
        if len(parts) == 4 and parts[1] == "camera" and parts[3] == "instance":
            inst[(round(t * xc["info"].frequency_hz / 1e9), parts[0], parts[2])] = np.asarray(decode_image(msg))
    visible = xc["b2"].filter(pl.col("visible_pixels") > 0)
    assert len(coco["annotations"]) == visible.height
    names = list(yaml.safe_load((xc["out"]["yolo"] / "data.yaml").read_text())["names"].values())
    tracks = {
        r["vessel_id"]: int(r["track_id"])
        for r in csv.DictReader((xc["out"]["mot"] / "tracks.csv").read_text().splitlines())
    }
    mot: dict[tuple[int, str, str], list[list[float]]] = defaultdict(list)
    for a in xc["info"].agents:
        for name in a.cameras:
            seq = xc["out"]["mot"] / "train" / f"xc_port.{a.id}.{name}"
            acq = [int(x) for x in (seq / "frames.txt").read_text().split()]
            for line in (seq / "gt" / "gt.txt").read_text().split():
                v = [float(x) for x in line.split(",")]
                mot[(acq[int(v[0]) - 1], a.id, name)].append(v)
    for key, anns in per.items():
        f, agent, cam = key
        w = _world(xc, f)
        yolo = sorted(
            tuple(map(float, x.split()))
            for x in (xc["out"]["yolo"] / "labels" / "all" / "xc_port" / agent / cam / f"{f:06d}.txt")
            .read_text()
            .splitlines()
        )
        exp_yolo, exp_mot = [], []
        for an in anns:
            g = w[an["mmusv_id"]]
            assert tracks[an["mmusv_id"]] == g["row"] + 1
            assert (an["category_id"], an["instance_id"], an["role"]) == (
                g["r"]["semantic_class"],
                g["r"]["instance_id"],
                g["r"]["role"],
            )
            ys, xs = np.nonzero(inst[key] == an["instance_id"])
            tight = [xs.min(), ys.min(), xs.max() + 1 - xs.min(), ys.max() + 1 - ys.min()]
            assert an["bbox"] == [float(x) for x in tight] and an["area"] == xs.size
            r = visible.filter(
                (pl.col("frame") == f)
                & (pl.col("agent") == agent)
                & (pl.col("camera") == cam)
                & (pl.col("target_id") == an["mmusv_id"])
            ).row(0, named=True)
            assert (an["truncation"], an["occlusion"]) == pytest.approx((r["truncation"], r["occlusion"]), abs=1e-6)
            x, y, bw, bh = an["bbox"]
            cls = names.index(class_name(an["category_id"]))
            exp_yolo.append((cls, (x + bw / 2) / 160, (y + bh / 2) / 120, bw / 160, bh / 120))
            vis = (1 - r["occlusion"]) * (1 - r["truncation"])
            exp_mot.append([g["row"] + 1, x + 1, y + 1, bw, bh, 1, an["category_id"], vis])
        np.testing.assert_allclose(np.array(yolo), np.array(sorted(exp_yolo)), atol=1e-6)
        got_mot = sorted(v[1:] for v in mot[key])
        np.testing.assert_allclose(np.array(got_mot), np.array(sorted(exp_mot)), atol=1e-6)
    assert sum(len(v) for v in mot.values()) == visible.height
    # KITTI (front) and KITTI tracking
    seqs = {
        r["agent"]: r for r in csv.DictReader((xc["out"]["kitti_tracking"] / "sequences.csv").read_text().splitlines())
    }
    for a in xc["info"].agents:
        kt = (
            (xc["out"]["kitti_tracking"] / "train" / "label_02" / f"{seqs[a.id]['sequence']}.txt")
            .read_text()
            .splitlines()
        )
        for k, f in enumerate(FRAMES):
            lines, _v = _kitti_lines(xc, f, a)
            gt = sorted(_targets(xc, f, a).items(), key=lambda x: x[1]["row"])
            rec = {
                r["target_id"]: r
                for r in xc["b2"]
                .filter((pl.col("frame") == f) & (pl.col("agent") == a.id) & (pl.col("camera") == "front"))
                .iter_rows(named=True)
            }
            tl = [x.split() for x in kt if int(x.split()[0]) == k and x.split()[2] != "DontCare"]
            assert len(tl) == len(lines) == len(gt)
            for (vid, _g), line, t in zip(gt, lines, tl, strict=True):
                assert int(t[1]) == tracks[vid] and t[2] == line[0] and t[4:] == line[2:]
                r = rec.get(vid)
                if r is None:
                    assert line[2] == "3" and line[4:8] == ["0.00"] * 4
                    continue
                np.testing.assert_allclose(
                    [float(x) for x in line[4:8]], [r["x_min"], r["y_min"], r["x_max"], r["y_max"]], atol=0.005
                )
                occ = r["occlusion"]
                assert int(line[2]) == (0 if occ < 0.25 else 1 if occ < 0.6 else 2)
                assert float(line[1]) == pytest.approx(r["truncation"], abs=0.005)


def test_lidar_points_and_frames_agree_across_semantickitti_opv2v_and_the_tables(xc: dict[str, Any]) -> None:
    """Per agent and frame: SemanticKITTI's points of each vessel instance number the recorded ``lidar_points`` of
    its ``boxes_3d`` row and OPV2V's ``_additional.yaml``; its scans are KITTI's ``velodyne`` files, its ``times`` the
    frames' sim times, its poses the LiDAR's motion (``Tr⁻¹·pose·Tr``); KITTI tracking's ``frames`` and the OPV2V
    ``time_s`` name the same acquisition indices."""
    freq = xc["info"].frequency_hz
    for i, a in enumerate(sorted(xc["info"].agents, key=lambda x: x.index)):
        sq = xc["out"]["semantickitti"] / "sequences" / f"{i:02d}"
        assert [int(x) for x in (sq / "frames.txt").read_text().split()] == list(FRAMES)
        np.testing.assert_allclose(np.loadtxt(sq / "times.txt").reshape(-1), [f / freq for f in FRAMES])
        tr = _velo_to_cam(_calib(sq / "calib.txt"), "Tr")
        poses = np.loadtxt(sq / "poses.txt").reshape(-1, 3, 4)
        for k, f in enumerate(FRAMES):
            lab = np.fromfile(sq / "labels" / f"{k:06d}.label", dtype="<u4")
            scan = (sq / "velodyne" / f"{k:06d}.bin").read_bytes()
            assert (
                scan
                == (xc["out"]["kitti"] / "xc_port" / str(1000 + a.index) / "velodyne" / f"{f:06d}.bin").read_bytes()
            )
            assert lab.size * 16 == len(scan)
            for r in xc["b3"].filter((pl.col("frame") == f) & (pl.col("agent") == a.id)).iter_rows(named=True):
                assert int(((lab >> 16) == r["instance_id"]).sum()) == r["lidar_points"], (a.id, f, r["target_id"])
            add = yaml.safe_load(
                (xc["out"]["opv2v"] / "xc_port" / str(1000 + a.index) / f"{f:06d}_additional.yaml").read_text()
            )["mmusv"]
            assert add["frame"] == f and add["time_s"] == pytest.approx(f / freq)
            for v in add["vehicles"].values():
                assert int(((lab >> 16) == v["instance_id"]).sum()) == v["lidar_points"]
            p = np.eye(4)
            p[:3] = poses[k]
            motion = np.linalg.inv(_lidar(xc, FRAMES[0], a)) @ _lidar(xc, f, a)
            np.testing.assert_allclose(np.linalg.inv(tr) @ p @ tr, motion, atol=1e-5)
