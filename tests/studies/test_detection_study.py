"""The detection and robustness studies end to end on a tiny LiDAR-only recording (2 USVs, 4 frames), the
predictions-file round trip, the OPV2V input, and the errors on bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.studies.detection.data import read_recording
from mmusv.studies.detection.sources import lidar_only

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "island_occlusion.yaml"


def record(out: Path, usvs: tuple[str, ...], frames: int = 4) -> Path:
    from mmusv.acquire import run

    data = lidar_only(yaml.safe_load(SCENARIO.read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in usvs]
    data["name"] = f"tiny_{len(usvs)}usv"
    data["acquisition"]["frames"] = frames
    return run(data, out_dir=out).recording


@pytest.fixture(scope="module")
def two_usv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record(tmp_path_factory.mktemp("rec2"), ("usv_1", "usv_3"))


def test_recording_loads_with_gt_and_usvs(two_usv: Path) -> None:
    seq = read_recording(two_usv)
    assert seq.agent_ids == ("usv_1", "usv_3") and len(seq.frames) == 4
    f = seq.frames[0]
    assert f.target_ids == ("target_1", "tanker", "speedboat", "workboat", "trawler", "sailboat")  # no USVs
    assert len(f.usv_boxes) == 2
    assert all(a.points.dtype == np.float32 and a.points.shape[1] == 4 for a in f.agents)


def test_detection_study_end_to_end(two_usv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "det"
    assert main(["study", "detection", str(two_usv), "-o", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "Table III" in text and "NOT the paper's learned model" in text
    table = pl.read_csv(out / "detection_table.csv")
    assert table["mode"].to_list() == ["none", "late", "early"]
    assert table["det"].sum() > 0 and table["gt"][0] > 0
    boxes = pl.read_parquet(out / "detection_boxes.parquet")
    assert boxes.columns == [
        "sequence",
        "frame",
        "ego",
        "mode",
        "kind",
        "x",
        "y",
        "z",
        "l",
        "w",
        "h",
        "yaw",
        "score",
        "range_bin",
        "matched",
        "ego_points",
        "neighbour_points",
        "wave_occlusion",
    ]
    assert table["gt_visible"][0] + table["gt_hidden"][0] + table["gt_unseen"][0] == table["gt"][0]
    gt = boxes.filter(pl.col("kind") == "gt")
    assert len(gt) == 3 * int(table["gt"][0])  # the same ground truth under each mode
    assert set(gt["range_bin"].to_list()) <= {"0-50", "50-100", "100-150", "150-200"}
    # The boxes file re-scores to the same table (the predictions interface round trip).
    out2 = tmp_path / "rescored"
    assert (
        main(
            [
                "study",
                "detection",
                str(two_usv),
                "--predictions",
                str(out / "detection_boxes.parquet"),
                "-o",
                str(out2),
                "--no-progress",
            ]
        )
        == 0
    )
    again = pl.read_csv(out2 / "detection_table.csv")
    for col in ("ap30", "ap50", "ap70", "recall50", "gt", "det"):
        a, b = table[col].to_list(), again[col].to_list()
        assert all((math.isnan(x) and math.isnan(y)) or x == pytest.approx(y) for x, y in zip(a, b, strict=True)), col
    assert (out / "detection_ap.png").stat().st_size > 0


def test_wave_occlusion_of_every_ground_truth_is_the_recordings_own(two_usv: Path, tmp_path: Path) -> None:
    """Each ground truth's wave-occlusion share is the one the recording's table gives that vessel from that ego
    (boxes_3d, written by the run; matched by position in the LiDAR frame, so a share given to the wrong box fails),
    and the wave-hidden count and recall are those of the boxes at or over WAVE_HIDDEN_SHARE."""
    from mmusv.studies.detection.study import WAVE_HIDDEN_SHARE

    out = tmp_path / "det"
    assert main(["study", "detection", str(two_usv), "--modes", "none", "-o", str(out), "--no-progress"]) == 0
    gt = pl.read_parquet(out / "detection_boxes.parquet").filter(pl.col("kind") == "gt")
    table = pl.read_parquet(sorted((two_usv.parent / "tables" / "boxes_3d").glob("*.parquet")))
    assert (table["wave_occlusion"] > 0).any()  # a W2 sea: some targets are partly behind waves
    checked = 0
    for r in gt.iter_rows(named=True):
        rows = table.filter((pl.col("frame") == r["frame"]) & (pl.col("agent") == r["ego"]))
        d = np.hypot(rows["x"].to_numpy() - r["x"], rows["y"].to_numpy() - r["y"])
        k = int(np.argmin(d))
        if d[k] < 1e-3:
            assert r["wave_occlusion"] == pytest.approx(rows["wave_occlusion"][k], abs=1e-12)
            checked += 1
        else:
            assert math.isnan(r["wave_occlusion"])  # not among the ego's annotated boxes
    assert checked >= 0.9 * len(gt) and checked > 0
    t = pl.read_csv(out / "detection_table.csv")
    hidden = gt.filter(pl.col("wave_occlusion") >= WAVE_HIDDEN_SHARE)
    assert int(t["gt_wave_hidden"][0]) == len(hidden)
    if len(hidden):
        assert t["recall50_wave_hidden"][0] == pytest.approx(hidden["matched"].mean())


def test_robustness_study_end_to_end(two_usv: Path, tmp_path: Path) -> None:
    out = tmp_path / "rob"
    assert (
        main(["study", "robustness", str(two_usv), "--settings", "delay:1,noise:1/1", "-o", str(out), "--no-progress"])
        == 0
    )
    wide = pl.read_csv(out / "robustness_table.csv")
    assert wide["setting"].to_list() == ["clean", "delay:1", "noise:1/1"]
    assert {"none", "late", "early"} <= set(wide.columns)
    boxes = pl.read_parquet(out / "robustness_boxes.parquet")
    assert "setting" in boxes.columns
    assert boxes["frame"].min() == 1  # frames before the largest delay are skipped for every setting
    # Same inputs and seed, same bytes (the pose noise is seeded).
    again = tmp_path / "rob2"
    assert (
        main(
            ["study", "robustness", str(two_usv), "--settings", "delay:1,noise:1/1", "-o", str(again), "--no-progress"]
        )
        == 0
    )
    for name in ("robustness_table.csv", "robustness_boxes.parquet"):
        assert (out / name).read_bytes() == (again / name).read_bytes()


def test_opv2v_input_gives_the_same_ground_truth(
    two_usv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.export.conversion import convert

    convert([two_usv], to="opv2v", out_dir=tmp_path / "opv2v", splits=None, extras="")
    rec_out, opv_out = tmp_path / "a", tmp_path / "b"
    assert main(["study", "detection", str(two_usv), "--modes", "none,early", "-o", str(rec_out), "--no-progress"]) == 0
    assert (
        main(
            [
                "study",
                "detection",
                "--opv2v",
                str(tmp_path / "opv2v"),
                "--modes",
                "none,early",
                "-o",
                str(opv_out),
                "--no-progress",
            ]
        )
        == 0
    )
    out = " ".join(capsys.readouterr().out.split())  # rich wraps its lines
    assert "at least half hidden from the ego by the waves" in out  # the recording has the shares
    # and so has the OPV2V export since 2026-12-06 (each CAV's _additional.yaml; before, none, and the study said so)
    assert "the source gives no wave-occlusion shares" not in out
    a, b = pl.read_csv(rec_out / "detection_table.csv"), pl.read_csv(opv_out / "detection_table.csv")
    assert a["gt"].to_list() == b["gt"].to_list()
    assert a["gt_wave_hidden"].to_list() == b["gt_wave_hidden"].to_list()
    ga = pl.read_parquet(rec_out / "detection_boxes.parquet").filter(pl.col("kind") == "gt").sort(["frame", "x"])
    gb = pl.read_parquet(opv_out / "detection_boxes.parquet").filter(pl.col("kind") == "gt").sort(["frame", "x"])
    assert np.allclose(
        ga.select(["x", "y", "l", "w"]).to_numpy(), gb.select(["x", "y", "l", "w"]).to_numpy(), atol=1e-3
    )
    assert np.allclose(ga["wave_occlusion"].to_numpy(), gb["wave_occlusion"].to_numpy(), atol=1e-6, equal_nan=True)
    # Same clouds (to 0.1 mm): the baseline finds the same boxes, up to a few of the clusters it forms in the
    # physical sea's water returns, which the 0.1 mm rounding of the export can split or merge.
    assert np.allclose(a["det"].to_numpy(), b["det"].to_numpy(), rtol=0.03, atol=0)
    # An OPV2V tree on two processes: the same bytes as on one.
    jobs = tmp_path / "j"
    argv = ["study", "detection", "--opv2v", str(tmp_path / "opv2v"), "--modes", "none,early", "--no-progress"]
    assert main([*argv, "--jobs", "2", "-o", str(jobs)]) == 0
    for name in ("detection_table.csv", "detection_boxes.parquet"):
        assert (opv_out / name).read_bytes() == (jobs / name).read_bytes(), name
    # the OPV2V folder given where recordings go: it said only "folder holds no .mcap recording"
    capsys.readouterr()
    assert main(["study", "detection", str(tmp_path / "opv2v"), "-o", str(tmp_path / "c"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f"it is an OPV2V folder: give it as --opv2v {tmp_path / 'opv2v'}" in err, err


def test_bad_input_errors(two_usv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    one = record(tmp_path / "one", ("usv_1",), frames=2)

    def err(args: list[str]) -> str:
        assert main([*args, "-o", str(tmp_path / "o"), "--no-progress"]) == 2
        return capsys.readouterr().err

    # one USV: nothing to fuse, scored in mode none only (tests/studies/test_detection_leftovers.py); no mode none:
    # nothing to score, said
    assert "add none to --modes" in err(["study", "detection", str(one), "--modes", "late"])
    assert "only with --model" in err(["study", "detection", str(two_usv), "--refine", "off"])
    assert "--rescore on: only with --model" in err(["study", "detection", str(two_usv), "--rescore", "on"])
    assert "--threads 1: only with --model" in err(["study", "detection", str(two_usv), "--threads", "1"])
    assert main(["study", "detection", str(one), "--modes", "none", "-o", str(tmp_path / "o1"), "--no-progress"]) == 0
    capsys.readouterr()
    assert "unknown mode" in err(["study", "detection", str(two_usv), "--modes", "none,mid"])
    assert "--settings" in err(["study", "robustness", str(two_usv), "--settings", "delay:x"])
    (tmp_path / "empty").mkdir()
    assert "no .mcap" in err(["study", "detection", str(tmp_path / "empty")])
    assert "empty dataset" in err(["study", "detection"])
    assert "not an OPV2V folder" in err(["study", "detection", "--opv2v", str(tmp_path / "empty")])
    assert "empty dataset" in err(["study", "detection", str(two_usv), "--split", "test"])
    assert "--split" in err(["study", "detection", str(two_usv), "--split", "bogus"])
    notmcap = tmp_path / "x.mcap"
    notmcap.write_text("hello")
    assert "not an MCAP file" in err(["study", "detection", str(notmcap)])
    assert "--detector" in err(["study", "detection", str(two_usv), "--detector", "nowhere:fn"])
    assert "--predictions" in err(["study", "detection", str(two_usv), "--predictions", str(notmcap)])


def test_rescore_of_the_boxes_parquet_gives_the_table(two_usv: Path, tmp_path: Path) -> None:
    from mmusv.studies.detection.report import rescore

    out = tmp_path / "det"
    assert main(["study", "detection", str(two_usv), "-o", str(out), "--no-progress"]) == 0
    table = pl.read_csv(out / "detection_table.csv")
    boxes = pl.read_parquet(out / "detection_boxes.parquet")
    for row in table.iter_rows(named=True):
        got = rescore(boxes.filter(pl.col("mode") == row["mode"]))
        for k in ("ap30", "ap50", "ap70", "gt", "det"):
            assert (math.isnan(got[k]) and math.isnan(row[k])) or got[k] == pytest.approx(row[k]), k


def test_late_merge_option_is_recorded(two_usv: Path, tmp_path: Path) -> None:
    out = {}
    for merge in ("nms", "wbf"):
        out[merge] = tmp_path / merge
        args = ["study", "detection", str(two_usv), "--modes", "none,late", "--late-merge", merge]
        assert main([*args, "-o", str(out[merge]), "--no-progress"]) == 0
        assert f"late fusion merge: {merge}" in (out[merge] / "detection_note.txt").read_text()
    tables = {m: pl.read_csv(p / "detection_table.csv") for m, p in out.items()}
    assert tables["nms"].filter(pl.col("mode") == "none").equals(tables["wbf"].filter(pl.col("mode") == "none"))
