"""``--to mot``: MOTChallenge sequences read back by py-motmetrics (``motmetrics.io.loadtxt``, ``fmt="mot15-2D"``) and
TrackEval's ``MotChallenge2DBox`` loader, every box and track id checked against the recording (docs/exports.md).

The expectations are computed here from the recording: the world state read with the ``mcap`` reader and its
protobuf decoder (the vessels' rows, as ``tests/test_tracking_round.py`` reads them), the boxes brute force from the
instance images (the pixels equal to the vessel's instance id), the occlusion from the recorded 2D annotations.
MOTChallenge's boxes are 1-based (the image's top-left pixel is ``(1, 1)``): ``bb_left`` is the 1-based column of
the vessel's leftmost pixel, ``bb_width`` its number of columns; py-motmetrics' loader subtracts the 1 again.
"""

from __future__ import annotations

import configparser
import csv
import filecmp
import importlib.util
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mmusv.errors import ConfigError
from mmusv.export import convert
from mmusv.recording import decode_image, frame_messages, read_info, topics
from PIL import Image
from recorded_boxes import Boxes, recorded
from trackeval_run import trackeval_scores

FRAMES = 3
"""conftest's ``port`` recording: 3 frames, 3 USVs with 4 cameras of 160 × 120 (12 sequences)."""
CAMERAS = ("front", "left", "rear", "right")


@pytest.fixture(scope="module")
def mot_dir(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("mot") / "o"
    convert(port_rec, to="mot", out_dir=out, splits=None)
    return out


def world_rows(rec: Path) -> dict[int, list[Any]]:
    """Per frame, the world state's vessels in row order (the ``mcap`` reader, not mmusv's)."""
    out: dict[int, list[Any]] = {}
    with rec.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, _, _, msg in reader.iter_decoded_messages(topics=["/world/state"]):
            out[int(msg.frame)] = list(msg.vessels)
    return out


@pytest.fixture(scope="module")
def port_truth(port_rec: Path) -> Boxes:
    """Per image, per vessel with a visible pixel in its recorded 2D box: ``recorded_boxes.recorded``'s entry, whose
    ``visible`` is the tight box of its pixels in the instance image, brute force (0-based ``[x_min, y_min, x_max,
    y_max]``, pixel edges), with its class and recorded occlusion."""
    return recorded(port_rec, FRAMES)


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def gt_lines(seq: Path) -> list[list[str]]:
    return [line.split(",") for line in (seq / "gt" / "gt.txt").read_text().splitlines()]


def box_problems(
    lines: list[list[str]], frames: list[int], want: dict[int, dict[str, dict[str, Any]]], names: dict[int, str]
) -> list[str]:
    """What a sequence's gt lines get wrong against the recording: one line per kept vessel and frame, ``bb_left``
    = its leftmost pixel column + 1 (1-based), ``bb_width`` = its column count (the same for rows), exactly; the
    class; visibility = (1 − occlusion) · (1 − truncation), MOT16's share in view counting the image border's crop.
    ``frames``: the acquisition index of MOT frame k at ``k - 1``; ``want``: per
    acquisition index, per vessel id, :func:`port_truth`'s entry; ``names``: track id → vessel id."""
    got: dict[tuple[int, str], list[str]] = {}
    problems = []
    for f in lines:
        key = (frames[int(f[0]) - 1], names[int(f[1])])
        if key in got:
            problems.append(f"{key} twice")
        got[key] = f
    expected = {(k, vid) for k, per in want.items() for vid in per}
    if set(got) != expected:
        problems.append(f"rows {sorted(set(got) ^ expected)} differ")
    for (k, vid), f in got.items():
        if (k, vid) not in expected:
            continue
        e = want[k][vid]
        x0, y0, x1, y1 = e["visible"]
        if [float(v) for v in f[2:6]] != [x0 + 1, y0 + 1, x1 - x0, y1 - y0]:
            problems.append(f"frame {k} {vid}: box {f[2:6]}, pixels {e['visible']}")
        if (f[6], int(f[7])) != ("1", e["class"]):
            problems.append(f"frame {k} {vid}: conf, class {f[6:8]}")
        if abs(float(f[8]) - (1.0 - e["occlusion"]) * (1.0 - e["truncation"])) > 5e-7:
            problems.append(f"frame {k} {vid}: visibility {f[8]}, occlusion {e['occlusion']}, {e['truncation']}")
    return problems


@pytest.fixture()
def pandas3_tuple() -> Iterator[None]:
    """py-motmetrics 1.4.0's MOTChallenge loader shifts the boxes with ``df[['X', 'Y']] -= (1, 1)``, which pandas 3
    reports as a Pandas4Warning (arithmetic with a tuple); not ours to fix."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Operation with tuple is deprecated")
        yield


def load_mot(path: Path) -> Any:
    import motmetrics as mm

    return mm.io.loadtxt(str(path), fmt="mot15-2D")


def accumulate(gt: Any, hyp: Any) -> Any:
    """py-motmetrics' accumulator over the frames of ``gt`` and ``hyp`` (DataFrames of ``loadtxt``), IoU distance
    with its threshold 0.5. ``mm.utils.compare_to_groundtruth`` does the same but calls ``np.asfarray``, gone from
    numpy 2 (py-motmetrics 1.4.0), so its ``boxiou`` is called here."""
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=False)
    frames = sorted(set(gt.index.get_level_values(0)) | set(hyp.index.get_level_values(0)))
    for fid in frames:
        g = gt.loc[[fid]] if fid in gt.index.get_level_values(0) else gt.iloc[:0]
        h = hyp.loc[[fid]] if fid in hyp.index.get_level_values(0) else hyp.iloc[:0]
        a = g[["X", "Y", "Width", "Height"]].to_numpy(float)
        b = h[["X", "Y", "Width", "Height"]].to_numpy(float)
        dist = 1.0 - mm.distances.boxiou(a[:, None], b[None, :]) if len(a) and len(b) else np.empty((len(a), len(b)))
        dist = np.where(dist > 0.5, np.nan, dist)
        acc.update(g.index.get_level_values(1).tolist(), h.index.get_level_values(1).tolist(), dist, frameid=int(fid))
    return acc


# ------------------------------------------------------------------------------------------------- layout


def test_layout_seqinfo_and_images(mot_dir: Path, port_rec: Path) -> None:
    info = read_info(port_rec)
    seqs = sorted(p.name for p in (mot_dir / "train").iterdir())
    want = sorted(f"port_entry.{a.id}.{c}" for a in info.agents for c in a.cameras)
    assert seqs == want and len(seqs) == 12
    assert (mot_dir / "seqmaps" / "train.txt").read_text().splitlines() == ["name", *want]
    assert sorted(p.name for p in mot_dir.iterdir()) == [
        "classes.csv",
        "conversion.yaml",
        "seqmaps",
        "tracks.csv",
        "train",
    ]
    msgs = {k: frame_messages(port_rec, k) for k in range(FRAMES)}
    for a in info.agents:
        for name, cam in a.cameras.items():
            seq = mot_dir / "train" / f"port_entry.{a.id}.{name}"
            ini = configparser.ConfigParser()
            ini.optionxform = str
            ini.read(seq / "seqinfo.ini")
            assert dict(ini["Sequence"]) == {
                "name": seq.name,
                "imDir": "img1",
                "frameRate": "5",
                "seqLength": str(FRAMES),
                "imWidth": str(cam.width),
                "imHeight": str(cam.height),
                "imExt": ".png",
            }
            assert sorted(p.name for p in (seq / "img1").iterdir()) == [f"{k:06d}.png" for k in range(1, FRAMES + 1)]
            assert (seq / "frames.txt").read_text().split() == [str(k) for k in range(FRAMES)]
            for k in range(FRAMES):
                img = np.asarray(Image.open(seq / "img1" / f"{k + 1:06d}.png"))
                np.testing.assert_array_equal(img, decode_image(msgs[k][topics.camera(a.id, name, kind="rgb")]))


def test_classes_and_tracks_files(mot_dir: Path, port_rec: Path) -> None:
    from mmusv.classes import SemanticClass, class_name

    classes = read_csv(mot_dir / "classes.csv")
    assert [(int(r["class"]), r["name"]) for r in classes] == [(int(c), class_name(c)) for c in SemanticClass if c]
    rows = world_rows(port_rec)
    tracks = read_csv(mot_dir / "tracks.csv")
    assert [r["vessel_id"] for r in tracks] == [v.id for v in rows[0]]
    for k, vessels in rows.items():  # the row of every vessel, hence its track id, is the same in every frame
        for r in tracks:
            i = int(r["track_id"]) - 1
            assert vessels[i].id == r["vessel_id"], k
            assert (vessels[i].role, vessels[i].semantic_class, vessels[i].asset) == (
                r["role"],
                int(r["class"]),
                r["asset"],
            )
    assert {(r["split"], r["scenario"]) for r in tracks} == {("train", "port_entry")}


# ------------------------------------------------------------------------------------------------- boxes and ids


def test_every_box_and_id_is_the_recordings(mot_dir: Path, port_rec: Path, port_truth: Any) -> None:
    names = {int(r["track_id"]): r["vessel_id"] for r in read_csv(mot_dir / "tracks.csv")}
    info = read_info(port_rec)
    total = 0
    seen: dict[str, set[tuple[str, int]]] = {}  # vessel → (sequence, MOT frame) where its id appears
    for a in info.agents:
        for name in a.cameras:
            seq = mot_dir / "train" / f"port_entry.{a.id}.{name}"
            lines = gt_lines(seq)
            frames = [int(x) for x in (seq / "frames.txt").read_text().split()]
            want = {k: port_truth[(a.id, name, k)] for k in range(FRAMES)}
            assert box_problems(lines, frames, want, names) == [], seq.name
            keys = [(int(f[0]), int(f[1])) for f in lines]
            assert keys == sorted(keys)  # by frame, then id
            for f in lines:
                seen.setdefault(names[int(f[1])], set()).add((seq.name, int(f[0])))
            total += len(lines)
    assert total >= 30
    # one id per vessel across frames and sequences: some vessels are seen in several of both
    assert max(len({s for s, _ in v}) for v in seen.values()) >= 2
    assert max(len({f for _, f in v}) for v in seen.values()) == FRAMES


def test_a_box_one_pixel_off_is_caught(mot_dir: Path, port_truth: Any) -> None:
    """The comparison is exact: a writer that forgot MOTChallenge's 1-based offset (or added it twice), moved by one
    pixel, or mixed two ids up, fails it, although IoU-based metrics would still call it a perfect track."""
    names = {int(r["track_id"]): r["vessel_id"] for r in read_csv(mot_dir / "tracks.csv")}
    seq = mot_dir / "train" / "port_entry.usv_3.left"
    lines = gt_lines(seq)
    frames = [int(x) for x in (seq / "frames.txt").read_text().split()]
    want = {k: port_truth[("usv_3", "left", k)] for k in range(FRAMES)}
    assert len(lines) >= 5 and box_problems(lines, frames, want, names) == []
    for col, dv in ((2, -1), (2, 1), (3, -1), (4, 1), (5, -1)):
        shifted = [[*f[:col], str(int(float(f[col])) + dv), *f[col + 1 :]] for f in lines]
        assert len(box_problems(shifted, frames, want, names)) == len(lines), (col, dv)
    a, b = lines[0][1], next(f[1] for f in lines if f[0] == lines[0][0] and f[1] != lines[0][1])
    swapped = [[f[0], {a: b, b: a}.get(f[1], f[1]), *f[2:]] if f[0] == lines[0][0] else f for f in lines]
    assert box_problems(swapped, frames, want, names)


# ------------------------------------------------------------------------------------------------- peers


@pytest.mark.usefixtures("pandas3_tuple")
def test_motmetrics_reads_gt_and_scores_it_perfect(mot_dir: Path, port_truth: Any) -> None:
    import motmetrics as mm
    import pandas as pd

    names = {int(r["track_id"]): r["vessel_id"] for r in read_csv(mot_dir / "tracks.csv")}
    accs, seq_names = [], []
    for seq in sorted((mot_dir / "train").iterdir()):
        gt = load_mot(seq / "gt" / "gt.txt")
        assert len(gt) == len(gt_lines(seq))
        _, agent, camera = seq.name.split(".")
        frames = [int(x) for x in (seq / "frames.txt").read_text().split()]
        for (fid, tid), row in gt.iterrows():
            e = port_truth[(agent, camera, frames[fid - 1])][names[tid]]
            x0, y0, x1, y1 = e["visible"]  # motmetrics takes the 1 off: 0-based pixel edges again
            assert [row["X"], row["Y"], row["Width"], row["Height"]] == [x0, y0, x1 - x0, y1 - y0]
            assert (row["Confidence"], row["ClassId"]) == (1, e["class"])
            # MOT16's visibility: the share in view, cut by the image border too (box_problems' rule)
            assert row["Visibility"] == pytest.approx((1.0 - e["occlusion"]) * (1.0 - e["truncation"]), abs=5e-7)
        accs.append(accumulate(gt, gt))
        seq_names.append(seq.name)
    mh = mm.metrics.create()
    summary = mh.compute_many(
        accs, names=seq_names, metrics=["mota", "idf1", "num_switches", "num_objects"], generate_overall=True
    )
    overall = summary.loc["OVERALL"]
    assert overall["mota"] == 1.0 and overall["idf1"] == 1.0 and overall["num_switches"] == 0
    assert overall["num_objects"] == sum(len(gt_lines(s)) for s in (mot_dir / "train").iterdir())
    # and the evaluation does see identities: swapping two ids from frame 2 on breaks IDF1 and counts switches
    seq = mot_dir / "train" / "port_entry.usv_3.left"
    gt = load_mot(seq / "gt" / "gt.txt")
    ids = sorted({int(i) for i in gt.index.get_level_values(1)})
    hyp = gt.rename(index={ids[0]: ids[1], ids[1]: ids[0]}, level=1)
    hyp = hyp[hyp.index.get_level_values(0) >= 2]
    hyp = pd.concat([gt[gt.index.get_level_values(0) < 2], hyp])
    bad = mh.compute(accumulate(gt, hyp), metrics=["idf1", "num_switches"])
    assert bad["idf1"].iloc[0] < 1.0 and bad["num_switches"].iloc[0] > 0


def test_trackeval_loads_and_scores_gt_perfect(mot_dir: Path, tmp_path: Path) -> None:
    """TrackEval's MOTChallenge loader (``MotChallenge2DBox``) with the layout as documented: the split folder as
    ``GT_FOLDER`` with ``SKIP_SPLIT_FOL``, the seqmap, and ``DO_PREPROC`` off (its preprocessing keeps MOT class 1,
    pedestrian, alone); the ground truth written as a tracker's results (class -1) scores HOTA = MOTA = IDF1 = 1."""
    if importlib.util.find_spec("trackeval") is None:
        pytest.skip("trackeval is not installed (scripts/test.sh installs it without its dependencies)")

    trk = tmp_path / "trackers" / "gt_copy" / "data"
    trk.mkdir(parents=True)
    seqs = sorted((mot_dir / "train").iterdir())
    for seq in seqs:
        text = "".join(",".join([*f[:6], "1", "-1", "-1", "-1"]) + "\n" for f in gt_lines(seq))
        (trk / f"{seq.name}.txt").write_text(text)
    dataset, res, msg = trackeval_scores(
        "MotChallenge2DBox",
        {
            "GT_FOLDER": str(mot_dir / "train"),
            "SKIP_SPLIT_FOL": True,
            "SEQMAP_FILE": str(mot_dir / "seqmaps" / "train.txt"),
            "TRACKERS_FOLDER": str(tmp_path / "trackers"),
            "DO_PREPROC": False,
        },
    )
    assert dataset.seq_lengths == {s.name: FRAMES for s in seqs}
    assert msg == {"gt_copy": "Success"}
    r = res["gt_copy"]["COMBINED_SEQ"]["pedestrian"]
    assert r["CLEAR"]["MOTA"] == 1.0 and r["Identity"]["IDF1"] == 1.0 and float(np.mean(r["HOTA"]["HOTA"])) == 1.0
    assert r["Count"]["GT_Dets"] == sum(len(gt_lines(s)) for s in seqs)
    assert r["Count"]["GT_IDs"] == sum(len({f[1] for f in gt_lines(s)}) for s in seqs)


# ------------------------------------------------------------------------------------------------- options


def test_same_recording_same_bytes(mot_dir: Path, port_rec: Path, tmp_path: Path) -> None:
    again = tmp_path / "again"
    convert(port_rec, to="mot", out_dir=again, splits=None)
    files = sorted(p.relative_to(mot_dir) for p in mot_dir.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(again) for p in again.rglob("*") if p.is_file())
    match, mismatch, errors = filecmp.cmpfiles(mot_dir, again, [str(f) for f in files], shallow=False)
    assert not mismatch and not errors and len(match) == len(files)


def test_frames_are_renumbered_from_one(port_rec: Path, port_truth: Any, tmp_path: Path) -> None:
    out = tmp_path / "f"
    convert(port_rec, to="mot", out_dir=out, splits=None, frames="1:", agents="usv_3")
    seqs = sorted((out / "train").iterdir())
    assert [s.name for s in seqs] == [f"port_entry.usv_3.{c}" for c in CAMERAS]
    names = {int(r["track_id"]): r["vessel_id"] for r in read_csv(out / "tracks.csv")}
    msgs = {k: frame_messages(port_rec, k) for k in (1, 2)}
    for seq in seqs:
        assert "seqLength=2\n" in (seq / "seqinfo.ini").read_text()
        assert (seq / "frames.txt").read_text() == "1\n2\n"
        assert sorted(p.name for p in (seq / "img1").iterdir()) == ["000001.png", "000002.png"]
        camera = seq.name.split(".")[-1]
        for k in (1, 2):  # MOT frame k - 0 is acquisition index k
            img = np.asarray(Image.open(seq / "img1" / f"{k:06d}.png"))
            np.testing.assert_array_equal(img, decode_image(msgs[k][topics.camera("usv_3", camera, kind="rgb")]))
        want = {k: port_truth[("usv_3", camera, k)] for k in (1, 2)}
        assert box_problems(gt_lines(seq), [1, 2], want, names) == []


def test_projected_boxes_and_filters(port_rec: Path, tmp_path: Path) -> None:
    """``--box projected``: the recorded box + 1 (3 decimals); ``--max-occlusion`` and ``--min-box-px`` leave lines
    out as they do COCO's boxes, and are recorded in ``conversion.yaml``."""
    out = tmp_path / "p"
    convert(port_rec, to="mot", out_dir=out, splits=None, box="projected", min_box_px=3, max_occlusion=0.5)
    names = {int(r["track_id"]): r["vessel_id"] for r in read_csv(out / "tracks.csv")}
    info = read_info(port_rec)
    n = 0
    for k in range(FRAMES):
        msgs = frame_messages(port_rec, k)
        for a in info.agents:
            boxes = msgs[topics.agent_annotations(a.id)].boxes_camera
            for name in a.cameras:
                seq = out / "train" / f"port_entry.{a.id}.{name}"
                got = {names[int(f[1])]: f for f in gt_lines(seq) if int(f[0]) == k + 1}
                kept = {
                    b.target_id: b
                    for b in boxes
                    if b.camera == name
                    and b.visible_pixels > 0
                    and b.occlusion <= 0.5
                    and min(b.x_max - b.x_min, b.y_max - b.y_min) >= 3
                }
                assert set(got) == set(kept)
                for vid, b in kept.items():
                    want = [b.x_min + 1, b.y_min + 1, b.x_max - b.x_min, b.y_max - b.y_min]
                    np.testing.assert_allclose([float(v) for v in got[vid][2:6]], want, atol=5e-4 + 1e-9)
                    n += 1
    assert n >= 10
    options = yaml.safe_load((out / "conversion.yaml").read_text())["options"]
    assert (options["box"], options["min_box_px"], options["max_occlusion"]) == ("projected", 3, 0.5)


def test_splits_follow_the_recordings(many_recs: list[Path], tmp_path: Path) -> None:
    from mmusv.export.splits import assign_splits, parse_ratios

    out = tmp_path / "s"
    convert(many_recs, to="mot", out_dir=out, seed=3)
    want = assign_splits([p.stem for p in many_recs], ratios=parse_ratios((0.7, 0.15, 0.15)), seed=3)
    tracks = read_csv(out / "tracks.csv")
    for split in ("train", "validate", "test"):
        seqs = (out / "seqmaps" / f"{split}.txt").read_text().splitlines()[1:]
        assert seqs == sorted(p.name for p in (out / split).iterdir())
        assert {s.split(".")[0] for s in seqs} == {k for k, v in want.items() if v == split}
        assert {r["scenario"] for r in tracks if r["split"] == split} == {k for k, v in want.items() if v == split}
    # ids are per recording: the same vessel of another recording has the same number in its own sequences
    assert sorted({(r["track_id"], r["vessel_id"]) for r in tracks}) == sorted(
        {("1", "usv_a"), ("2", "tgt"), ("3", "usv_b"), ("4", "boat")}
    )


# ------------------------------------------------------------------------------------------------- bad input


def test_a_recording_without_cameras_is_refused(no_camera_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    with pytest.raises(ConfigError, match=r"export_no_camera\.mcap: cannot convert to mot: no camera") as exc:
        convert(no_camera_rec, to="mot", out_dir=out)
    assert "\n" not in str(exc.value) and not out.exists()


def test_visible_boxes_need_instance_images(tmp_path: Path, make_coop: Any) -> None:
    """A camera recording RGB alone: refused with ``--box visible`` (the default), naming the file and the images it
    lacks, nothing written; converted with ``--box projected``."""
    from mmusv.acquire import run

    cam = {"name": "front", "resolution": [64, 48], "quality": "draft", "outputs": ["rgb"]}
    cfg = make_coop(name="mot_rgb_only", acquisition={"frequency_hz": 5, "frames": 1})
    cfg["rigs"] = {"r": {"preset": "lidar_only", "cameras": [{**cam, "mount": {"point": "camera_front"}}]}}
    rec = Path(run(cfg, out_dir=tmp_path / "rec").recording)
    out = tmp_path / "o"
    with pytest.raises(ConfigError, match=r"mot_rgb_only\.mcap: cannot convert to mot: no camera recording rgb and "):
        convert(rec, to="mot", out_dir=out)
    assert not out.exists()
    convert(rec, to="mot", out_dir=out, box="projected", splits=None)
    assert sorted(p.name for p in (out / "train").iterdir()) == ["mot_rgb_only.usv_a.front", "mot_rgb_only.usv_b.front"]


@pytest.mark.parametrize(("hz", "rate"), [(2.5, "3"), (0.4, "1"), (12.0, "12")])
def test_frame_rate_is_a_whole_number(tmp_path: Path, make_coop: Any, hz: float, rate: str) -> None:
    """MOTChallenge's ``frameRate`` is a whole number, and trackers read it with ``int()`` (FairMOT, JDE): a 2.5 Hz
    recording wrote ``frameRate=2.5``, which they refuse. It is the nearest whole number now (at least 1), and the
    notes give the exact rate."""
    from mmusv.acquire import run
    from mmusv.export.convert_report import load_report

    cam = {"name": "front", "resolution": [64, 48], "quality": "draft", "outputs": ["rgb"]}
    cfg = make_coop(name="mot_rate", acquisition={"frequency_hz": hz, "frames": 1})
    cfg["rigs"] = {"r": {"preset": "lidar_only", "cameras": [{**cam, "mount": {"point": "camera_front"}}]}}
    rec = Path(run(cfg, out_dir=tmp_path / "rec").recording)
    convert(rec, to="mot", out_dir=tmp_path / "o", box="projected", splits=None)
    ini = configparser.ConfigParser()
    ini.read(tmp_path / "o" / "train" / "mot_rate.usv_a.front" / "seqinfo.ini")
    assert ini["Sequence"]["frameRate"] == rate
    assert int(ini["Sequence"]["frameRate"]) >= 1
    notes = [n for r in load_report(tmp_path / "o")["recordings"] for n in r["notes"]]
    said = [n for n in notes if "frameRate" in n]
    assert said == ([] if hz.is_integer() else [said[0]])
    if said:
        assert f"recorded at {hz:g} Hz: seqinfo.ini's frameRate is {rate}" in said[0]


def test_the_command_writes_mot_and_its_help_lists_it(
    port_rec: Path, no_camera_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.cli import main

    out = tmp_path / "c"
    argv = ["convert", str(port_rec), "--to", "mot", "-o", str(out), "--no-split", "--agents", "usv_1"]
    assert main([*argv, "--frames", "2:", "--no-progress"]) == 0
    assert sorted(p.name for p in (out / "train").iterdir()) == [f"port_entry.usv_1.{c}" for c in CAMERAS]
    assert (out / "train" / "port_entry.usv_1.front" / "frames.txt").read_text() == "2\n"
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["convert", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "semantickitti or mot (MOTChallenge" in text and "coco, yolo, mot: the 2D box written" in text
    assert main(["convert", str(no_camera_rec), "--to", "mot", "-o", str(tmp_path / "n"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and "cannot convert to mot" in err


def test_visibility_counts_the_part_cropped_by_the_image_border(tmp_path: Path, make_coop: Any) -> None:
    """MOT16/MOT17's visibility counts occlusion *and* cropping by the image border. A tug straddling the front
    camera's left edge (45° off the bow, 60 m out) is cut by it: its line's visibility is the recorded
    ``(1 − occlusion) · (1 − truncation)``, below 1 − occlusion (which is all the export wrote before)."""
    from mmusv.acquire import run

    cam = {"name": "front", "resolution": [160, 120], "hfov_deg": 90, "outputs": ["rgb", "instance"]}
    cfg = make_coop(
        name="mot_cropped",
        acquisition={"frequency_hz": 5, "frames": 1},
        rigs={
            "r": {
                "lidar": None,
                "radar": None,
                "top_view": None,
                "cameras": [{**cam, "mount": {"point": "camera_front"}}],
            }
        },
        vessels=[
            {
                "id": "usv_a",
                "role": "usv",
                "asset": "usv_wamv",
                "rig": "r",
                "speed_mps": 2.0,
                "route": [[0, 0], [300, 0]],
            },
            {"id": "tug", "role": "target", "asset": "tug_32m", "speed_mps": 2.0, "route": [[60, 60], [360, 60]]},
        ],
    )
    rec = Path(run(cfg, out_dir=tmp_path / "rec").recording)
    truth = recorded(rec, 1)[("usv_a", "front", 0)]["tug"]
    assert 0.1 < truth["truncation"] < 0.9  # the border cuts it
    convert(rec, to="mot", out_dir=tmp_path / "mot", splits=None)
    (line,) = gt_lines(tmp_path / "mot" / "train" / "mot_cropped.usv_a.front")
    want = (1.0 - truth["occlusion"]) * (1.0 - truth["truncation"])
    assert abs(float(line[8]) - want) <= 5e-7 and float(line[8]) < 1.0 - truth["occlusion"] - 0.05
