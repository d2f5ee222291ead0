"""Unusual but valid recordings through every format, read back with the peers' own readers (pycocotools, rosbags,
Open3D, PIL/numpy for YOLO, MaSTr and SemanticKITTI, KITTI's devkit conventions written out here).

* ``mixed`` — two rigs that differ: ``usv_a`` LiDAR only (no camera at all), ``usv_b`` a LiDAR, a distorted front
  camera and a rear camera that records only RGB (64 × 48), no radar or top view; 2 frames;
* ``lonely`` — one USV, no other vessel, a LiDAR that drops every return (empty scans) and one front camera; 1 frame.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.errors import ConfigError
from mmusv.export import convert
from mmusv.export.conversion import load_report
from mmusv.recording import read_messages

LIDAR = {"channels": 16, "points_per_second": 20000, "rotation_hz": 5}
DIST = [-0.1, 0.02, 0.001, -0.001, 0.0]
FORMATS = ("opv2v", "kitti", "ros2", "coco", "yolo", "mastr", "semantickitti", "mot", "kitti_tracking")


def coop(name: str, frames: int, rigs: dict[str, Any]) -> dict[str, Any]:
    """conftest's ``coop`` scenario (usv_a, the tug ``tgt``, usv_b, the speedboat ``boat``), ``frames`` frames."""
    return {
        "name": name,
        "seed": 11,
        "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0}},
        "environment": {"time_of_day": "11:00", "weather": "clear", "wave": "W1", "motion": "paper"},
        "acquisition": {"frequency_hz": 5, "frames": frames},
        "rigs": rigs,
        "vessels": [
            {"id": "usv_a", "role": "usv", "asset": "usv_patrol_12m", "speed_mps": 3.0, "route": [[0, 0], [300, 200]]},
            {"id": "tgt", "role": "target", "asset": "tug_32m", "speed_mps": 3.0, "route": [[34.1, 30], [334.1, 230]]},
            {"id": "usv_b", "role": "usv", "asset": "usv_wamv", "speed_mps": 2.0, "route": [[90, -30], [60, 0]]},
            {"id": "boat", "role": "target", "asset": "speedboat_5m", "speed_mps": 4.0, "route": [[20, 60], [80, 20]]},
        ],
    }


def camera(name: str, **more: Any) -> dict[str, Any]:
    return {"name": name, "resolution": [64, 48], "quality": "draft", "mount": {"point": f"camera_{name}"}, **more}


@pytest.fixture(scope="module")
def mixed_rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    cams = [camera("front", distortion=DIST), camera("rear", outputs=["rgb"])]
    rigs = {
        "lidar_only": {"preset": "lidar_only", "lidar": LIDAR},
        "cams": {"lidar": LIDAR, "radar": None, "top_view": None, "cameras": cams},
    }
    cfg = coop("edge_mixed", 2, rigs)
    cfg["vessels"][0]["rig"] = "lidar_only"
    cfg["vessels"][2]["rig"] = "cams"
    return Path(run(cfg, out_dir=tmp_path_factory.mktemp("mixed")).recording)


@pytest.fixture(scope="module")
def lonely_rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    rig = {"lidar": {**LIDAR, "dropout": 1.0}, "radar": None, "top_view": None, "cameras": [camera("front")]}
    cfg = coop("edge_lonely", 1, {"r": rig})
    cfg["vessels"] = [{**cfg["vessels"][0], "rig": "r"}]
    return Path(run(cfg, out_dir=tmp_path_factory.mktemp("lonely")).recording)


def notes(out: Path) -> str:
    return "\n".join(n for r in load_report(out)["recordings"] for n in r["notes"])


# ---------------------------------------------------------------------------------------------- peers' readers


def read_bag(bag: Path) -> int:
    """Every message of a rosbag2 folder deserialised by rosbags (Humble typestore + the bag's own schemas)."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    n = 0
    with Reader(bag) as r:
        for c in r.connections:
            if c.msgtype not in store.types:
                head, *rest = c.msgdef.data.split("\n" + "=" * 80 + "\nMSG: ")
                types = get_types_from_msg(head, c.msgtype)
                for part in rest:
                    name, _, text = part.partition("\n")
                    types.update(get_types_from_msg(text, name))
                store.register({k: v for k, v in types.items() if k not in store.types})
        for c, _, raw in r.messages():
            store.deserialize_cdr(raw, c.msgtype)
            n += 1
    return n


def check_coco(out: Path) -> int:
    """Loads every annotations file with pycocotools; evaluates the ground truth as results when it has boxes.
    Returns the annotation count."""
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    total = 0
    files = sorted((out / "annotations").glob("instances_*.json"))
    assert files
    for f in files:
        with contextlib.redirect_stdout(io.StringIO()):
            gt = COCO(str(f))
        split = f.stem.removeprefix("instances_")
        for img in gt.loadImgs(gt.getImgIds()):
            assert (out / "images" / split / img["file_name"]).is_file()
        anns = gt.loadAnns(gt.getAnnIds())
        total += len(anns)
        if anns:  # pycocotools' loadRes cannot take an empty result list
            with contextlib.redirect_stdout(io.StringIO()):
                ev = COCOeval(gt, gt.loadRes([{**a, "score": 1.0} for a in anns]), "bbox")
                ev.evaluate()
                ev.accumulate()
                ev.summarize()
            assert ev.stats[0] == pytest.approx(1.0)
    return total


def check_yolo(out: Path) -> int:
    """Label files beside every image, class ids in range, normalised boxes in [0, 1]; returns the box count."""
    from PIL import Image

    data = yaml.safe_load((out / "data.yaml").read_text())
    assert (out / data["train"]).is_dir() and (out / data["val"]).is_dir()
    images = sorted((out / "images").rglob("*.png"))
    assert images
    boxes = 0
    for img in images:
        with Image.open(img) as im:
            im.verify()
        label = out / "labels" / img.relative_to(out / "images").with_suffix(".txt")
        for line in label.read_text().splitlines():
            c, *b = line.split()
            assert 0 <= int(c) < len(data["names"]) and len(b) == 4
            assert all(0.0 <= float(v) <= 1.0 for v in b) and float(b[2]) > 0 and float(b[3]) > 0
            boxes += 1
    return boxes


def check_mot(out: Path) -> int:
    """Lines of every MOTChallenge ``gt/gt.txt``, each read back as nine comma-separated numbers with 1-based frames
    and ids (MOTChallenge's convention); every sequence has its ``seqinfo.ini`` and ``img1`` images."""
    lines = 0
    for gt in sorted(out.rglob("gt/gt.txt")):
        seq = gt.parent.parent
        assert (seq / "seqinfo.ini").is_file() and any((seq / "img1").iterdir()), seq
        for row in gt.read_text().splitlines():
            v = [float(x) for x in row.split(",")]
            assert len(v) == 9 and v[0] >= 1 and v[1] >= 1 and v[4] > 0 and v[5] > 0, row
            lines += 1
    return lines


def check_kitti_tracking(out: Path) -> int:
    """Every sequence of every split's seqmap as TrackEval's ``Kitti2DBox`` finds it (``<split>/label_02/<seq>.txt``,
    frames ``0 .. n - 1`` of the seqmap's ``n``, 17 fields a line, a track id >= 0), a scan per frame and a calibration
    with the tracking devkit's keys; returns the scan count."""
    scans = 0
    seqmaps = sorted(out.glob("*/evaluate_tracking.seqmap.*"))
    assert seqmaps
    for seqmap in seqmaps:
        split = seqmap.parent
        assert seqmap.name == f"evaluate_tracking.seqmap.{split.name}"
        for row in seqmap.read_text().splitlines():
            seq, empty, first, frames = row.split()
            n = int(frames)
            assert (len(seq), empty, first) == (4, "empty", "000000") and n > 0, row
            assert sorted(p.name for p in (split / "velodyne" / seq).iterdir()) == [f"{k:06d}.bin" for k in range(n)]
            for line in (split / "label_02" / f"{seq}.txt").read_text().splitlines():
                f = line.split()
                dont_care = f[1:3] == ["-1", "DontCare"]  # a region to ignore, track id -1 as in KITTI's own labels
                assert len(f) == 17 and 0 <= int(f[0]) < n and (int(f[1]) >= 0 or dont_care), line
            calib = [line.split()[0] for line in (split / "calib" / f"{seq}.txt").read_text().splitlines()]
            assert calib == ["P0:", "P1:", "P2:", "P3:", "R_rect", "Tr_velo_cam", "Tr_imu_velo"]
            assert len((split / "pose" / f"{seq}.txt").read_text().splitlines()) == n
            scans += n
    return scans


def check_mastr(out: Path) -> int:
    """Every mask beside an image of its size, uint8 values in MaSTr1325's {0, 1, 2, 4}; returns the mask count."""
    from PIL import Image

    masks = sorted(out.rglob("masks/**/*m.png"))
    for m in masks:
        with Image.open(m) as im:
            a = np.asarray(im)
        rgb = Path(str(m).replace("/masks/", "/images/").removesuffix("m.png") + ".png")
        assert a.dtype == np.uint8 and set(np.unique(a).tolist()) <= {0, 1, 2, 4}
        with Image.open(rgb) as im:
            assert im.size == (a.shape[1], a.shape[0])
    return len(masks)


def check_semantickitti(out: Path) -> int:
    """Every .bin/.label pair of equal point counts, uint32 labels, one pose per scan; returns the scan count."""
    scans = 0
    for seq in sorted((out / "sequences").iterdir()):
        bins = sorted((seq / "velodyne").glob("*.bin"))
        labels = sorted((seq / "labels").glob("*.label"))
        assert [b.stem for b in bins] == [p.stem for p in labels]
        assert len((seq / "poses.txt").read_text().splitlines()) == len(bins)
        for b, p in zip(bins, labels, strict=True):
            pts = np.fromfile(b, dtype=np.float32).reshape(-1, 4)
            lab = np.fromfile(p, dtype=np.uint32)
            assert len(pts) == len(lab)
        scans += len(bins)
    return scans


def check_opv2v(out: Path) -> int:
    """Every frame yaml with its PCD read by Open3D (point count = the header's); returns the point count."""
    import open3d as o3d

    points = 0
    for doc in sorted(out.rglob("[0-9][0-9][0-9][0-9][0-9][0-9].yaml")):
        d = yaml.safe_load(doc.read_text())
        assert {"lidar_pose", "true_ego_pos", "vehicles"} <= set(d)
        pcd = doc.with_suffix(".pcd")
        header = pcd.read_bytes().partition(b"DATA ascii\n")[0].decode().splitlines()
        n = int(next(h for h in header if h.startswith("POINTS ")).split()[1])
        if n:
            assert len(o3d.io.read_point_cloud(str(pcd)).points) == n
        points += n
        for i in range(4):
            if f"camera{i}" in d:
                assert (doc.parent / f"{doc.stem}_camera{i}.png").is_file()
    return points


# ---------------------------------------------------------------------------------------------- KITTI's devkit


def kitti_boxes_in_lidar(label: Path, calib: Path) -> list[tuple[np.ndarray, float, np.ndarray]]:
    """KITTI labels turned into LiDAR boxes the way KITTI's devkits do (OpenPCDet's
    ``boxes3d_kitti_camera_to_lidar``): location through ``(R0_rect · Tr_velo_to_cam)⁻¹``, raised by h / 2,
    heading ``-(π/2 + rotation_y)``. Returns ``(centre (3,), heading rad, (l, w, h))`` per line (15 fields)."""
    cal = {}
    for line in calib.read_text().splitlines():
        key, vals = line.split(":", 1)
        cal[key] = np.array([float(v) for v in vals.split()])
    assert cal["P2"].size == 12 and cal["Tr_velo_to_cam"].size == 12
    tr = np.vstack([cal["Tr_velo_to_cam"].reshape(3, 4), [0, 0, 0, 1]])
    r0 = np.eye(4)
    r0[:3, :3] = cal["R0_rect"].reshape(3, 3)
    to_velo = np.linalg.inv(r0 @ tr)
    out = []
    for line in label.read_text().splitlines():
        f = line.split()
        assert len(f) == 15
        if f[0] == "DontCare":  # a region to ignore, no box: OpenPCDet's loader drops these lines
            continue
        h, w, length = (float(v) for v in f[8:11])
        loc = to_velo @ np.array([*(float(v) for v in f[11:14]), 1.0])
        centre = loc[:3] + np.array([0.0, 0.0, h / 2])
        out.append((centre, -(math.pi / 2 + float(f[14])), np.array([length, w, h])))
    return out


def test_kitti_agent_without_front_camera_reads_back_with_the_right_heading(mixed_rec: Path, tmp_path: Path) -> None:
    # usv_a has no camera: its labels were written in the LiDAR frame itself (Tr_velo_to_cam = I), so a devkit
    # rotated every box by 90° and lost its heading.
    convert(mixed_rec, to="kitti", out_dir=tmp_path / "k", splits=None)
    d = tmp_path / "k" / "edge_mixed" / "1000"
    assert not (d / "image_2").exists()
    anns = {round(t * 5 / 1e9): m for _, t, m in read_messages(mixed_rec, topics=["/usv_a/annotations"])}
    checked = 0
    for k in range(2):
        boxes = kitti_boxes_in_lidar(d / "label_2" / f"{k:06d}.txt", d / "calib" / f"{k:06d}.txt")
        truth = {b.target_id: b for b in anns[k].boxes_lidar}
        assert len(boxes) == 2
        for centre, heading, size in boxes:
            match = [b for b in truth.values() if np.allclose(list(b.center), centre, atol=0.05)]
            assert len(match) == 1, (k, centre)
            b = match[0]
            np.testing.assert_allclose(size, list(b.size), atol=0.01)
            assert (heading - b.yaw + math.pi) % (2 * math.pi) - math.pi == pytest.approx(0.0, abs=0.02)
            checked += 1
    assert checked == 4
    assert "agent usv_a has no front camera" in notes(tmp_path / "k")


def test_kitti_records_the_front_camera_distortion(mixed_rec: Path, tmp_path: Path) -> None:
    convert(mixed_rec, to="kitti", out_dir=tmp_path / "k", splits=None)
    meta = yaml.safe_load((tmp_path / "k" / "edge_mixed" / "mmusv_kitti.yaml").read_text())
    assert meta["front_camera_distortion"] == {1000: None, 1002: pytest.approx(DIST)}
    assert "agent usv_b: front camera has lens distortion" in notes(tmp_path / "k")


def test_semantickitti_notes_the_front_camera_distortion(mixed_rec: Path, tmp_path: Path) -> None:
    """calib.txt's P0..P3 are the pinhole K; the notes said nothing of a distorting lens (KITTI's did)."""
    convert(mixed_rec, to="semantickitti", out_dir=tmp_path / "s", splits=None)
    said = notes(tmp_path / "s")
    assert "agent usv_b: front camera has lens distortion" in said
    assert "agent usv_a: front camera has lens distortion" not in said
    assert str(list(DIST)) in said


# ---------------------------------------------------------------------------------------------- refusals


@pytest.mark.parametrize("to", ["opv2v", "kitti", "kitti_tracking"])
def test_lidar_formats_refuse_a_recording_without_lidar_up_front(no_lidar_rec: Path, tmp_path: Path, to: str) -> None:
    # Before: a folder holding only conversion.yaml ("complete", 0 frames) and exit status 1.
    with pytest.raises(ConfigError, match=rf"export_no_lidar\.mcap: cannot convert to {to}: no agent with a LiDAR"):
        convert(no_lidar_rec, to=to, out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------------------------- every format


def test_two_different_rigs_read_back_in_every_format(mixed_rec: Path, tmp_path: Path) -> None:
    found = {}
    for to in FORMATS:
        out = tmp_path / to
        rep = convert(mixed_rec, to=to, out_dir=out, splits=None)
        assert rep.frames == 2, to
        found[to] = {
            "opv2v": check_opv2v,
            "kitti": lambda o: len(list(o.rglob("label_2/*.txt"))),
            "ros2": lambda o: read_bag(o / "edge_mixed"),
            "coco": check_coco,
            "yolo": check_yolo,
            "mastr": check_mastr,
            "semantickitti": check_semantickitti,
            "mot": check_mot,
            "kitti_tracking": check_kitti_tracking,
        }[to](out)
    assert found["kitti"] == 4 and found["semantickitti"] == 4 and found["opv2v"] > 0 and found["ros2"] > 20
    assert found["kitti_tracking"] == 4  # usv_a (no camera: no image_02) and usv_b, 2 frames each
    assert sorted(p.name for p in (tmp_path / "kitti_tracking" / "train" / "image_02").iterdir()) == ["0001"]
    assert "agent usv_a has no front camera: no image_02" in notes(tmp_path / "kitti_tracking")
    assert found["mastr"] == 2  # usv_b's front camera; the rear one records no semantic image
    assert found["mot"] == found["yolo"]  # the same visible boxes, one gt.txt line each (usv_b's front camera)
    assert "agent usv_a has no camera recording rgb and instance images and is left out" in notes(tmp_path / "mot")
    # The default --box visible takes YOLO's boxes from the instance images, so usv_b's rear camera (RGB only) is left
    # out, as in COCO; --box projected (the recorded boxes, the only ones before --box) converts it from RGB alone.
    assert len(list((tmp_path / "yolo" / "images").rglob("*.png"))) == 2  # usv_b's front, 2 frames
    yolo_notes = notes(tmp_path / "yolo")
    assert "agent usv_a has no camera recording rgb and instance images and is left out" in yolo_notes
    assert "agent usv_b: cameras ['rear'] do not record rgb and instance images and are left out (--box" in yolo_notes
    convert(mixed_rec, to="yolo", out_dir=tmp_path / "yolo_projected", splits=None, box="projected")
    assert check_yolo(tmp_path / "yolo_projected") >= found["yolo"]
    assert len(list((tmp_path / "yolo_projected" / "images").rglob("*.png"))) == 4  # usv_b's front and rear, 2 frames
    assert "agent usv_a has no camera recording rgb images and is left out" in notes(tmp_path / "yolo_projected")
    # data_protocol.yaml names the OPV2V cameras some agent writes (it said four whatever the rigs).
    protocol = yaml.safe_load((tmp_path / "opv2v" / "edge_mixed" / "data_protocol.yaml").read_text())
    assert protocol["vehicle_base"]["sensing"]["perception"]["camera"] == {"num": 2, "order": ["front", "rear"]}


def test_empty_scans_and_no_vessel_are_said_and_read_back(lonely_rec: Path, tmp_path: Path) -> None:
    for to in FORMATS:
        convert(lonely_rec, to=to, out_dir=tmp_path / to, splits=None)
    assert check_opv2v(tmp_path / "opv2v") == 0
    assert "the LiDAR has no point in frames 0" in notes(tmp_path / "opv2v")
    assert yaml.safe_load((tmp_path / "opv2v" / "edge_lonely" / "1000" / "000000.yaml").read_text())["vehicles"] == {}
    assert (tmp_path / "kitti" / "edge_lonely" / "1000" / "label_2" / "000000.txt").read_bytes() == b""
    assert check_semantickitti(tmp_path / "semantickitti") == 1
    assert read_bag(tmp_path / "ros2" / "edge_lonely") > 5
    assert check_coco(tmp_path / "coco") == 0 and check_yolo(tmp_path / "yolo") == 0
    assert check_mastr(tmp_path / "mastr") == 1
    assert check_mot(tmp_path / "mot") == 0
    assert check_kitti_tracking(tmp_path / "kitti_tracking") == 1
    assert (tmp_path / "kitti_tracking" / "train" / "label_02" / "0000.txt").read_bytes() == b""
    for to in ("coco", "yolo", "mot"):
        assert "no vessel is visible in any converted image" in notes(tmp_path / to), to


def test_box_filters_that_keep_nothing_are_said(mixed_rec: Path, tmp_path: Path) -> None:
    for to in ("coco", "yolo"):
        convert(mixed_rec, to=to, out_dir=tmp_path / to, splits=None, min_box_px=1e6)
        assert "visible 2D boxes were left out by min_box_px = 1e+06" in notes(tmp_path / to), to
    assert check_coco(tmp_path / "coco") == 0 and check_yolo(tmp_path / "yolo") == 0


# ---------------------------------------------------------------------------------------------- overwrite, recover


def test_overwrite_into_the_working_directory_and_a_link(
    lonely_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # ``-o .`` with --overwrite used to delete the working directory itself, then fail ("Invalid argument") with
    # the previous conversion gone; a link to a folder failed in shutil.rmtree.
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    convert(lonely_rec, to="opv2v", out_dir=".", splits=None)
    rep = convert(lonely_rec, to="kitti", out_dir=".", splits=None, overwrite=True)
    assert rep.frames == 1 and Path.cwd() == here and (here / "conversion.yaml").is_file()
    assert load_report(here)["format"] == "kitti" and not (here / "opencood").exists()
    (tmp_path / "real").mkdir()
    os.symlink(tmp_path / "real", tmp_path / "link")
    convert(lonely_rec, out_dir=tmp_path / "link", splits=None)
    convert(lonely_rec, to="coco", out_dir=tmp_path / "link", splits=None, overwrite=True)
    assert (tmp_path / "link").is_symlink() and load_report(tmp_path / "real")["format"] == "coco"


def test_recovered_recording_reads_back_with_rosbags_and_pycocotools(mixed_rec: Path, tmp_path: Path) -> None:
    from mcap_rechunk import rechunk
    from mmusv.recording.recover import recover

    small = tmp_path / "small.mcap"
    rechunk(mixed_rec, small, 16 * 1024)
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    data = small.read_bytes()
    (run_dir / "edge_mixed.mcap.partial").write_bytes(data[: int(len(data) * 0.55)])  # a killed writer
    assert recover(run_dir).frames == [0]
    rec = run_dir / "edge_mixed.mcap"
    for to in ("ros2", "coco"):
        rep = convert(rec, to=to, out_dir=tmp_path / to)
        assert rep.frames == 1 and rep.skipped == [
            {
                "recording": rec.name,
                "frames": [1, 1],
                "reason": "not in the recording (run interrupted: 1 of 2 frames written)",
            }
        ], to
    assert read_bag(tmp_path / "ros2" / "edge_mixed") > 10
    check_coco(tmp_path / "coco")


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(f.relative_to(folder)): f.read_bytes() for f in sorted(folder.rglob("*")) if f.is_file()}


def test_overwrite_keeps_the_previous_conversion_until_the_new_one_is_complete(
    lonely_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--overwrite`` deleted the previous conversion first: a new one failing halfway (here a full disk while a
    frame is written) left neither. The new one is now written beside it and swapped in when complete."""
    from mmusv.export.kitti import KittiWriter

    out = tmp_path / "ds"
    convert(lonely_rec, to="opv2v", out_dir=out, splits=None)
    before = _tree(out)

    def full_disk(self: Any, frame: Any) -> None:
        raise OSError(28, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(KittiWriter, "write_frame", full_disk)
        with pytest.raises(OSError, match="No space left"):
            convert(lonely_rec, to="kitti", out_dir=out, splits=None, overwrite=True)
    assert _tree(out) == before and load_report(out)["status"] == "complete"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]  # no staging folder left beside it
    # A staging folder of a killed conversion (its process gone) is cleared by the next one; a success swaps in.
    stale = tmp_path / ".ds.converting-999999999"
    stale.mkdir()
    rep = convert(lonely_rec, to="kitti", out_dir=out, splits=None, overwrite=True)
    assert rep.out_dir == out and load_report(out)["format"] == "kitti" and not (out / "opencood").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]


def test_a_killed_conversions_staging_folder_beside_a_name_with_brackets(tmp_path: Path) -> None:
    """An output folder ``a[1]``: its name went into a glob pattern (``[1]`` matches "1"), so a killed conversion's
    staging folder beside it stayed for ever, and ``a1``'s was taken for its."""
    from mmusv.export.convert_output import _remove_stale_stages

    own = tmp_path / ".a[1].converting-999999999"
    other = tmp_path / ".a1.converting-999999999"
    own.mkdir()
    other.mkdir()
    _remove_stale_stages(tmp_path / "a[1]")
    assert not own.exists() and other.exists()


def test_a_conversion_stopping_halfway_in_a_new_folder_says_so_in_its_report(
    lonely_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A conversion into a folder of its own that stops halfway (a bug's exception, a full disk, Ctrl-C) leaves the
    frames it wrote, and its ``conversion.yaml`` said ``in_progress`` for ever after: it now says ``failed`` (or
    ``interrupted``) and why. The next conversion replaces it with ``overwrite``."""
    from mmusv.export.kitti import KittiWriter

    calls: list[int] = []

    def broken(self: Any, frame: Any) -> None:
        calls.append(frame.index)
        raise ZeroDivisionError("division by zero")

    out = tmp_path / "ds"
    with monkeypatch.context() as m:
        m.setattr(KittiWriter, "write_frame", broken)
        with pytest.raises(ZeroDivisionError):
            convert(lonely_rec, to="kitti", out_dir=out, splits=None)
    report = load_report(out)
    assert calls and report["status"] == "failed" and report["error"] == "ZeroDivisionError: division by zero"
    assert report["format"] == "kitti" and "frames_converted" not in report

    with monkeypatch.context() as m:
        m.setattr(KittiWriter, "write_frame", lambda self, frame: (_ for _ in ()).throw(KeyboardInterrupt()))
        with pytest.raises(KeyboardInterrupt):
            convert(lonely_rec, to="kitti", out_dir=out, splits=None, overwrite=True)
    # --overwrite stages the new conversion beside the old: the failed one stays as it was, the staging goes
    assert load_report(out)["status"] == "failed" and sorted(p.name for p in tmp_path.iterdir()) == ["ds"]
    with monkeypatch.context() as m:
        m.setattr(KittiWriter, "write_frame", lambda self, frame: (_ for _ in ()).throw(KeyboardInterrupt()))
        with pytest.raises(KeyboardInterrupt):
            convert(lonely_rec, to="kitti", out_dir=tmp_path / "ds2", splits=None)
    assert load_report(tmp_path / "ds2") == {k: v for k, v in report.items() if k != "error"} | {
        "status": "interrupted"
    }

    done = convert(lonely_rec, to="kitti", out_dir=out, splits=None, overwrite=True)
    assert done.frames > 0 and load_report(out)["status"] == "complete" and "error" not in load_report(out)


def test_agents_and_frames_select_what_is_converted(mixed_rec: Path, tmp_path: Path) -> None:
    """``agents`` and ``frames`` (``--agents``, ``--frames``) convert a part of a recording: the other agents'
    folders are not written, the frames outside the range are neither converted nor reported missing, and the
    selection is in ``conversion.yaml``; a selection the recordings cannot honour is refused up front."""
    from mmusv.cli import main

    rep = convert(mixed_rec, to="kitti", out_dir=tmp_path / "b", splits=None, agents=["usv_b"], frames="1:")
    assert rep.frames == 1 and rep.agent_frames == 1
    scen = tmp_path / "b" / "edge_mixed"
    # usv_b (vessel index 2), not usv_a (1000)
    assert sorted(p.name for p in scen.iterdir()) == ["1002", "mmusv_kitti.yaml"]
    assert yaml.safe_load((scen / "mmusv_kitti.yaml").read_text())["agents"] == {1002: "usv_b"}
    assert sorted(p.name for p in (scen / "1002" / "label_2").iterdir()) == ["000001.txt"]
    doc = load_report(tmp_path / "b")
    assert doc["options"]["agents"] == ["usv_b"] and doc["options"]["frames"] == [1, None]
    assert doc["recordings"][0]["skipped"] == []
    rep = convert(mixed_rec, to="opv2v", out_dir=tmp_path / "o", splits=None, frames=(0, 1))
    assert rep.frames == 1 and rep.agent_frames == 2
    # Without an agent selection: both agents (of frame 0), and no agents in the options.
    assert "agents" not in load_report(tmp_path / "o")["options"]
    for agents, frames, said in (
        ("usv_9", None, "usv_9 is not an agent of the recordings (their agents: usv_a, usv_b)"),
        ("usv_a", None, "no selected agent (usv_a) to convert to coco: usv_a has no camera"),
        ("", None, "agents = '': must be one or more agent ids"),
        (None, "2:1", "frames = '2:1': STOP (1) must be greater than START (2)"),
        (None, "x", "frames = 'x': must be START:STOP"),
        (None, (-1, 2), "frames start = -1: must be a whole number >= 0"),
    ):
        with pytest.raises(ConfigError) as err:
            convert(mixed_rec, to="coco", out_dir=tmp_path / "bad", agents=agents, frames=frames)
        assert said in str(err.value), str(err.value)
    assert not (tmp_path / "bad").exists()
    out = tmp_path / "cli"
    argv = ["convert", str(mixed_rec), "--to", "semantickitti", "--agents", "usv_a", "--frames", "0:1", "-o", str(out)]
    assert main([*argv, "--no-progress"]) == 0
    assert load_report(out)["frames_converted"] == 1
