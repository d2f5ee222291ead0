"""``--to kitti_tracking``: KITTI tracking sequences, read back by TrackEval's ``Kitti2DBox`` and checked against the
KITTI export of the same recording and options (the same label lines, scans, images and poses, by sequence) and the
recording's world state (every track id is one vessel's, in every frame and sequence).

The ``port`` recording (conftest: 3 frames, 3 USVs) converted with ``include_usvs`` and a 2 km range, so that the
front cameras see vessels (with the default 200 m every target in range is behind or beside them: occluded 3).
"""

from __future__ import annotations

import csv
import filecmp
import importlib.util
import itertools
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mmusv.errors import ConfigError, IoError
from mmusv.export import convert
from mmusv.recording import read_info
from trackeval_run import trackeval_scores

FRAMES = 3
OPTIONS: dict[str, Any] = {"splits": None, "include_usvs": True, "eval_range_m": 2000.0}
PER_FRAME = {  # the tracking layout's per-frame folder → the KITTI export's, and the files' extension
    "velodyne": ("velodyne", ".bin"),
    "image_02": ("image_2", ".png"),
    "depth_02": ("depth_2", ".png"),
    "semantic_02": ("semantic_2", ".png"),
    "radar_ppi": ("radar_ppi", ".png"),
    "top_view_rgb": ("top_view_rgb", ".png"),
    "top_view_semantic": ("top_view_semantic", ".png"),
}
"""The per-frame folders of the ``port`` recording with the default extras (depth, semantic, radar, top view)."""


@pytest.fixture(scope="module")
def exports(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The KITTI tracking export (``track``: its ``train`` folder; ``root``), the same with ``kitti_class="Car"`` and
    no extras (``car``) and the KITTI export (``kitti``: its scenario folder)."""
    root = tmp_path_factory.mktemp("kitti_tracking")
    convert(port_rec, to="kitti_tracking", out_dir=root / "t", **OPTIONS)
    convert(port_rec, to="kitti_tracking", out_dir=root / "c", kitti_class="Car", extras=None, **OPTIONS)
    convert(port_rec, to="kitti", out_dir=root / "k", **OPTIONS)
    return {
        "root": root / "t",
        "track": root / "t" / "train",
        "car": root / "c" / "train",
        "kitti": root / "k" / "port_entry",
    }


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def sequences(root: Path) -> dict[str, dict[str, str]]:
    """``sequences.csv`` by sequence."""
    return {r["sequence"]: r for r in read_csv(root / "sequences.csv")}


def labels(split: Path, seq: str) -> list[list[str]]:
    return [line.split() for line in (split / "label_02" / f"{seq}.txt").read_text().splitlines()]


def read_tracking_calib(path: Path) -> dict[str, np.ndarray]:
    """A KITTI tracking ``calib/<seq>.txt``: ``P0:`` … with a colon, ``R_rect`` … without, by key (colon dropped)."""
    out = {}
    for line in path.read_text().splitlines():
        key, *vals = line.split()
        out[key.removesuffix(":")] = np.array([float(v) for v in vals])
    return out


def homogeneous(rows: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :] = np.asarray(rows).reshape(3, 4)
    return m


def world_states(rec: Path) -> dict[int, Any]:
    """The world state per frame, read with the ``mcap`` reader (not mmusv's)."""
    out: dict[int, Any] = {}
    with rec.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, _, _, msg in reader.iter_decoded_messages(topics=["/world/state"]):
            out[int(msg.frame)] = msg
    return out


# ------------------------------------------------------------------------------------------------- layout


def test_layout_sequences_and_seqmap(exports: dict[str, Path], port_rec: Path) -> None:
    root, train = exports["root"], exports["track"]
    info = read_info(port_rec)
    root_files = ["conversion.yaml", "sequences.csv", "top_views.yaml", "tracks.csv", "train"]  # top view: an extra
    assert sorted(p.name for p in root.iterdir()) == root_files
    seqs = sequences(root)
    assert [(s, r["agent"], r["cav_id"], r["scenario"], r["split"], r["frames"]) for s, r in seqs.items()] == [
        (f"{i:04d}", a.id, str(1000 + a.index), "port_entry", "train", str(FRAMES)) for i, a in enumerate(info.agents)
    ]
    assert {r["frequency_hz"] for r in seqs.values()} == {"5.0"}
    want = sorted([*PER_FRAME, "calib", "evaluate_tracking.seqmap.train", "frames", "label_02", "oxts", "pose"])
    assert sorted(p.name for p in train.iterdir()) == want
    assert (train / "evaluate_tracking.seqmap.train").read_text() == "".join(
        f"{s} empty 000000 {FRAMES:06d}\n" for s in seqs
    )
    for folder, (_, ext) in PER_FRAME.items():
        assert sorted(p.name for p in (train / folder).iterdir()) == list(seqs), folder
        for s in seqs:
            assert sorted(p.name for p in (train / folder / s).iterdir()) == [f"{k:06d}{ext}" for k in range(FRAMES)]
    for s in seqs:
        assert (train / "frames" / f"{s}.txt").read_text() == "0\n1\n2\n"
        assert len((train / "pose" / f"{s}.txt").read_text().splitlines()) == FRAMES
        assert len((train / "oxts" / f"{s}.txt").read_text().splitlines()) == FRAMES  # test_kitti_oxts.py reads them
        keys = [line.split()[0] for line in (train / "calib" / f"{s}.txt").read_text().splitlines()]
        assert keys == ["P0:", "P1:", "P2:", "P3:", "R_rect", "Tr_velo_cam", "Tr_imu_velo"]  # the devkit's names


def test_files_are_the_kitti_exports_by_sequence(exports: dict[str, Path]) -> None:
    """Scans, images, extras and poses are the KITTI export's files of the same agent and frame; the calibration is
    its calibration, one per sequence: LiDAR → front camera is the same in every frame (within 1e-6) although the
    hulls roll and pitch in the port's waves."""
    train, kitti = exports["track"], exports["kitti"]
    for s, row in sequences(exports["root"]).items():
        agent = kitti / row["cav_id"]
        for folder, (theirs, ext) in PER_FRAME.items():
            for k in range(FRAMES):
                ours = (train / folder / s / f"{k:06d}{ext}").read_bytes()
                assert ours == (agent / theirs / f"{k:06d}{ext}").read_bytes(), (s, folder, k)
        poses = (train / "pose" / f"{s}.txt").read_text().splitlines()
        assert poses == [(agent / "pose" / f"{k:06d}.txt").read_text().strip() for k in range(FRAMES)]
        calib = read_tracking_calib(train / "calib" / f"{s}.txt")
        first = (agent / "calib" / "000000.txt").read_text()
        names = {"R_rect": "R0_rect:", "Tr_velo_cam": "Tr_velo_to_cam:", "Tr_imu_velo": "Tr_imu_to_velo:"}
        ours_text = (train / "calib" / f"{s}.txt").read_text()
        for key, theirs in names.items():
            ours_text = ours_text.replace(f"\n{key} ", f"\n{theirs} ")
        assert ours_text == first  # frame 0's file, the object benchmark's names put back
        for k in range(FRAMES):
            per_frame = {}
            for line in (agent / "calib" / f"{k:06d}.txt").read_text().splitlines():
                key, vals = line.split(":", 1)
                per_frame[key] = np.array([float(v) for v in vals.split()])
            np.testing.assert_allclose(calib["Tr_velo_cam"], per_frame["Tr_velo_to_cam"], rtol=0, atol=1e-6)


def as_tracking(line: str) -> str:
    """A KITTI object ``label_2`` line with its truncation fraction turned into the tracking benchmark's level (the
    KITTI raw data's tracklets: 0 in the image, 1 cut by the border, 2 out of the image: a line without a box,
    occluded 3, and truncated 1.00; one without a box but in view, too small for a pixel, is 0 or 1 by its share)."""
    f = line.split()
    frac = float(f[1])
    out = f[2] == "3" and frac >= 1.0  # with a box (occluded < 3) it is in the image, however much is cut
    f[1] = "2" if out else "0" if frac <= 0.0 else "1"
    return " ".join(f)


def test_label_lines_are_the_kitti_lines_with_frame_and_track_id(exports: dict[str, Path]) -> None:
    train, kitti = exports["track"], exports["kitti"]
    total = 0
    levels: set[str] = set()
    for s, row in sequences(exports["root"]).items():
        lines = labels(train, s)
        keys = [(int(f[0]), int(f[1])) for f in lines]
        assert keys == sorted(keys) and len(set(keys)) == len(keys)  # by frame, then id; one line per track and frame
        for k in range(FRAMES):
            theirs = (kitti / row["cav_id"] / "label_2" / f"{k:06d}.txt").read_text().splitlines()
            assert [" ".join(f[2:]) for f in lines if int(f[0]) == k] == [as_tracking(x) for x in theirs], (s, k)
        total += len(lines)
        levels |= {f[3] for f in lines}
    assert total >= 20
    assert {"0", "2"} <= levels <= {"0", "1", "2"}  # whole numbers, as the tracking devkit's readme defines them
    # kitti_class: the type alone differs
    types: set[str] = set()
    for s in sequences(exports["root"]):
        car = labels(exports["car"], s)
        assert [f[:2] + f[3:] for f in car] == [f[:2] + f[3:] for f in labels(train, s)]
        assert {f[2] for f in car} <= {"Car"}
        types |= {f[2] for f in labels(train, s)}
    assert types == {"Vessel", "Usv"}


def test_every_track_id_is_one_vessel_in_every_frame_and_sequence(exports: dict[str, Path], port_rec: Path) -> None:
    """A KITTI reader's box centre (location through ``(R_rect · Tr_velo_cam)⁻¹``, raised by h/2) taken to the world
    with ``pose/<seq>.txt`` is, in every line, the world-state box centre of the vessel ``tracks.csv`` names for the
    line's track id (0.03 m: the labels' 2 decimals), so an id is one vessel in every frame and sequence."""
    train = exports["track"]
    world = world_states(port_rec)
    tracks = read_csv(exports["root"] / "tracks.csv")
    assert [r["vessel_id"] for r in tracks] == [v.id for v in world[0].vessels]
    assert [int(r["track_id"]) for r in tracks] == list(range(1, len(tracks) + 1))
    for r, v in zip(tracks, world[0].vessels, strict=True):
        assert (r["split"], r["scenario"], r["role"], int(r["class"]), r["asset"]) == (
            "train",
            "port_entry",
            v.role,
            v.semantic_class,
            v.asset,
        )
    vessel = {int(r["track_id"]): r["vessel_id"] for r in tracks}
    where: dict[str, set[tuple[str, int]]] = defaultdict(set)
    for s in sequences(exports["root"]):
        calib = read_tracking_calib(train / "calib" / f"{s}.txt")
        r0 = np.eye(4)
        r0[:3, :3] = calib["R_rect"].reshape(3, 3)
        cam_to_lidar = np.linalg.inv(r0 @ homogeneous(calib["Tr_velo_cam"]))
        poses = [homogeneous(np.loadtxt(train / "pose" / f"{s}.txt")[k]) for k in range(FRAMES)]
        for f in labels(train, s):
            k, vid = int(f[0]), vessel[int(f[1])]
            centre = cam_to_lidar @ [float(f[13]), float(f[14]), float(f[15]), 1.0]
            centre[2] += float(f[10]) / 2.0  # h
            box = next(v.box_center for v in world[k].vessels if v.id == vid)
            assert float(np.linalg.norm(np.subtract((poses[k] @ centre)[:3], list(box)))) < 0.03, (s, k, vid)
            where[vid].add((s, k))
    assert max(len({s for s, _ in v}) for v in where.values()) >= 2  # a vessel in several sequences
    assert max(len({k for _, k in v}) for v in where.values()) == FRAMES


# ------------------------------------------------------------------------------------------------- the peer


def _trackeval(gt: Path, trackers: Path) -> Any:
    folders = {"GT_FOLDER": str(gt), "TRACKERS_FOLDER": str(trackers)}
    return trackeval_scores("Kitti2DBox", {**folders, "SPLIT_TO_EVAL": "train", "CLASSES_TO_EVAL": ["car"]})


def test_trackeval_kitti2dbox_scores_gt_perfect_and_a_swap_lower(exports: dict[str, Path], tmp_path: Path) -> None:
    """Stock TrackEval (``Kitti2DBox``, class ``car``: ``kitti_class="Car"``) loads every sequence of the split through
    its seqmap and scores the ground truth as a tracker's output HOTA = MOTA = IDF1 = 1, counting the lines it
    evaluates (occluded <= 2, not truncated: the others, the vessels outside the front image among them, are
    KITTI's distractors); two tracks swapping ids from frame 1 on score lower, with identity switches."""
    if importlib.util.find_spec("trackeval") is None:
        pytest.skip("trackeval is not installed (scripts/test.sh installs it without its dependencies)")
    car = exports["car"]
    seqs = list(sequences(exports["root"]))
    per_frame: dict[tuple[str, int], list[int]] = defaultdict(list)
    counted = 0
    for s in seqs:
        for f in labels(car, s):
            if int(f[4]) <= 2 and f[3] == "0":
                per_frame[(s, int(f[0]))].append(int(f[1]))
                counted += 1
    assert counted >= 5
    # the swap: two ids evaluated together in every frame of one sequence (a target hidden wholly in a frame is
    # occluded 3 there, a distractor)
    s, a, b = next(
        (s, a, b)
        for (s, k), ids in sorted(per_frame.items())
        if k == 0
        for a, b in itertools.combinations(sorted(ids), 2)
        if all({a, b} <= set(per_frame[(s, j)]) for j in range(FRAMES))
    )
    for name in ("gt_copy", "swapped"):
        (tmp_path / name / "data").mkdir(parents=True)
        for q in seqs:
            text = (car / "label_02" / f"{q}.txt").read_text()
            if name == "swapped" and q == s:
                rows = [line.split() for line in text.splitlines()]
                for f in rows:
                    if int(f[0]) >= 1 and int(f[1]) in (a, b):
                        f[1] = str(a + b - int(f[1]))
                text = "".join(" ".join(f) + "\n" for f in rows)
            (tmp_path / name / "data" / f"{q}.txt").write_text(text)
    dataset, res, msg = _trackeval(car, tmp_path)
    assert dataset.seq_lengths == dict.fromkeys(seqs, FRAMES)
    assert msg == {"gt_copy": "Success", "swapped": "Success"}
    r = res["gt_copy"]["COMBINED_SEQ"]["car"]
    assert r["CLEAR"]["MOTA"] == 1.0 and r["Identity"]["IDF1"] == 1.0 and float(np.mean(r["HOTA"]["HOTA"])) == 1.0
    assert r["Count"]["GT_Dets"] == counted
    bad = res["swapped"]["COMBINED_SEQ"]["car"]
    assert float(np.mean(bad["HOTA"]["HOTA"])) < 1.0 and bad["Identity"]["IDF1"] < 1.0 and bad["CLEAR"]["IDSW"] > 0


# ------------------------------------------------------------------------------------------------- options


def test_same_recording_same_bytes(exports: dict[str, Path], port_rec: Path, tmp_path: Path) -> None:
    root = exports["root"]
    again = tmp_path / "again"
    convert(port_rec, to="kitti_tracking", out_dir=again, **OPTIONS)
    files = sorted(p.relative_to(root) for p in root.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(again) for p in again.rglob("*") if p.is_file())
    match, mismatch, errors = filecmp.cmpfiles(root, again, [str(f) for f in files], shallow=False)
    assert not mismatch and not errors and len(match) == len(files) > 50


def test_the_command_renumbers_frames_from_zero_and_writes_the_class(
    exports: dict[str, Path], port_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--frames 1:`` gives frames 0 and 1 (the files and label lines of acquisition indices 1 and 2, mapped back
    in ``frames/``), ``--kitti-class Car`` every type; the help lists both."""
    from mmusv.cli import main

    out = tmp_path / "c"
    argv = ["convert", str(port_rec), "--to", "kitti_tracking", "-o", str(out), "--no-split", "--agents", "usv_2"]
    argv += ["--include-usvs", "--range", "2000", "--kitti-class", "Car", "--frames", "1:", "--no-progress"]
    assert main(argv) == 0
    train, kitti = out / "train", exports["kitti"] / "1001"
    assert [(r["sequence"], r["agent"], r["frames"]) for r in read_csv(out / "sequences.csv")] == [
        ("0000", "usv_2", "2")
    ]
    assert (train / "evaluate_tracking.seqmap.train").read_text() == "0000 empty 000000 000002\n"
    assert (train / "frames" / "0000.txt").read_text() == "1\n2\n"
    for k in (0, 1):
        assert (train / "velodyne" / "0000" / f"{k:06d}.bin").read_bytes() == (
            kitti / "velodyne" / f"{k + 1:06d}.bin"
        ).read_bytes()
        theirs = (kitti / "label_2" / f"{k + 1:06d}.txt").read_text().splitlines()
        ours = [f for f in labels(train, "0000") if f[0] == str(k)]
        assert [" ".join(f[3:]) for f in ours] == [as_tracking(line).split(" ", 1)[1] for line in theirs]
        assert {f[2] for f in ours} <= {"Car"} and len(ours) == len(theirs) > 0
    assert sorted(p.name for p in (train / "velodyne" / "0000").iterdir()) == ["000000.bin", "000001.bin"]
    doc = yaml.safe_load((out / "conversion.yaml").read_text())
    assert doc["format"] == "kitti_tracking" and doc["options"]["kitti_class"] == "Car"
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["convert", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "or kitti_tracking (the KITTI tracking benchmark's layout" in text and "--kitti-class NAME" in text
    bad = ["convert", str(port_rec), "-o", str(tmp_path / "bad"), "--no-progress", "--kitti-class"]
    for more, said in (
        (["two words", "--to", "kitti_tracking"], "--kitti-class two words: must be one KITTI type word"),
        (["Car", "--to", "coco"], "--kitti-class Car: only --to kitti_tracking writes it, not --to coco"),
    ):
        assert main([*bad, *more]) == 2
        err = capsys.readouterr().err
        assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and said in err, err
    assert not (tmp_path / "bad").exists()


def test_splits_number_sequences_over_the_conversion(many_recs: list[Path], tmp_path: Path) -> None:
    from mmusv.export.splits import assign_splits, parse_ratios

    out = tmp_path / "s"
    convert(many_recs, to="kitti_tracking", out_dir=out, seed=3)
    want = assign_splits([p.stem for p in many_recs], ratios=parse_ratios((0.7, 0.15, 0.15)), seed=3)
    rows = read_csv(out / "sequences.csv")
    # every (recording, agent) once, numbered 0000 … in the conversion's order: split, scenario, agent
    assert [r["sequence"] for r in rows] == [f"{i:04d}" for i in range(2 * len(many_recs))]
    order = ("train", "validate", "test")
    assert [(r["split"], r["scenario"], r["agent"]) for r in rows] == sorted(
        ((want[p.stem], p.stem, a) for p in many_recs for a in ("usv_a", "usv_b")),
        key=lambda t: (order.index(t[0]), t[1], t[2]),
    )
    for split in order:
        mine = [r["sequence"] for r in rows if r["split"] == split]
        seqmap = (out / split / f"evaluate_tracking.seqmap.{split}").read_text().splitlines()
        assert [line.split()[0] for line in seqmap] == mine and mine
        assert sorted(p.stem for p in (out / split / "label_02").iterdir()) == mine
        assert {r["scenario"] for r in rows if r["split"] == split} == {k for k, v in want.items() if v == split}
    assert sorted({(r["track_id"], r["vessel_id"]) for r in read_csv(out / "tracks.csv")}) == sorted(
        {("1", "usv_a"), ("2", "tgt"), ("3", "usv_b"), ("4", "boat")}
    )


# ------------------------------------------------------------------------------------------------- bad input


def test_bad_input_is_refused_in_one_line_before_writing(port_rec: Path, no_lidar_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    for rec, kwargs, said in (
        (no_lidar_rec, {}, r"export_no_lidar\.mcap: cannot convert to kitti_tracking: no agent with a LiDAR"),
        (
            port_rec,
            {"kitti_class": "Car", "to": "mot"},
            r"kitti_class = 'Car': only to = 'kitti_tracking' writes it, not to",
        ),
        (port_rec, {"kitti_class": 5}, r"kitti_class = 5: must be one KITTI type word"),
        (port_rec, {"kitti_class": "Car "}, r"kitti_class = 'Car ': must be one KITTI type word"),
        (port_rec, {"kitti_class": "DontCare"}, r"kitti_class = 'DontCare': DontCare marks regions to ignore"),
    ):
        with pytest.raises(ConfigError, match=said) as exc:
            convert(rec, **{"to": "kitti_tracking", "out_dir": out, **kwargs})
        assert "\n" not in str(exc.value) and not out.exists()


def test_a_front_camera_moving_against_the_lidar_is_refused(
    port_rec: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One calibration per sequence holds because the camera is rigid on the hull (the recorded mounts); were LiDAR →
    camera to change between frames, the conversion stops naming the agent and frame instead of writing labels in a
    camera frame the calibration file does not describe."""
    from mmusv.export import kitti_tracking

    real = kitti_tracking.camera0
    frames: list[int] = []

    def drifting(agent: Any, view: Any) -> tuple[np.ndarray, np.ndarray]:
        k, velo_to_cam = real(agent, view)
        frames.append(0)
        moved = velo_to_cam.copy()
        moved[0, 3] += 1e-3 * (len(frames) > 2)  # usv_1, first frame: the sequence's calibration, then its labels
        return k, moved

    monkeypatch.setattr(kitti_tracking, "camera0", drifting)
    with pytest.raises(IoError, match=r"port_entry\.mcap: agent usv_1's front camera moves against its LiDAR") as exc:
        convert(port_rec, to="kitti_tracking", out_dir=tmp_path / "o", splits=None, extras=None)
    assert "(by 0.001 at frame 1)" in str(exc.value)  # usv_2's calibration already drifted: usv_1 at frame 1
    report = yaml.safe_load((tmp_path / "o" / "conversion.yaml").read_text())
    assert report["status"] == "failed" and report["error"] == str(exc.value)
