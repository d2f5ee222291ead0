"""Tables I and II as a researcher reproduces them (a helper's round): ``mmusv study waves`` and ``study agreement``
refuse scenarios they cannot measure before making their output folder, measure what the paper defines, and never
leave a new table beside an old plot; their numbers against independent computations from a recording."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.acquire import run
from mmusv.cli import main
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.scenario_checks import MmusvWarning
from mmusv.studies.agreement import run_agreement_study, sample_agreement
from mmusv.studies.waves import run_wave_study

ROOT = Path(__file__).resolve().parents[2]


def _scenario(bundled: str, **changes: Any) -> dict[str, Any]:
    data = yaml.safe_load((ROOT / "scenarios" / f"{bundled}.yaml").read_text(encoding="utf-8"))
    data.update(changes)
    return data


def _write(tmp_path: Path, data: dict[str, Any], name: str) -> str:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return str(path)


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and "Traceback" not in err and err.count("\n") == 1, err
    return err


# --- Table I: mmusv study waves ---------------------------------------------------------------------------------


def test_waves_without_usvs_is_refused_before_the_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = _scenario("island_port_waves", name="no_usvs")
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv"]
    scenario = _write(tmp_path, data, "no_usvs")
    for motion in ("paper", "physical"):
        out = tmp_path / f"waves_{motion}"
        err = _refused(
            ["study", "waves", "--scenario", scenario, "--frames", "5", "--motion", motion, "-o", str(out)], capsys
        )
        assert not out.exists()  # was an empty folder left behind
        assert "'no_usvs'" in err and "role: usv" in err, err
        assert err.startswith(f"mmusv: error: {scenario}: "), err  # the file given: its name: inside did not say it


def test_waves_of_a_one_frame_scenario_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # One frame: heave about each USV's mean is 0 at every wave setting; was a table of zeros, R² = 1, exit 0.
    data = _scenario("island_port_waves", name="one_frame", acquisition={"frequency_hz": 5, "frames": 1})
    scenario = _write(tmp_path, data, "one_frame")
    out = tmp_path / "waves"
    err = _refused(["study", "waves", "--scenario", scenario, "-o", str(out)], capsys)
    assert "acquisition.frames = 1" in err and "at least 2 frames" in err and "--frames" in err, err
    assert not out.exists()
    with pytest.raises(ConfigError, match="at least 2 frames"):
        run_wave_study(load_scenario(data))
    assert main(["study", "waves", "--scenario", scenario, "--frames", "3", "-o", str(out)]) == 0  # the way out


def test_waves_table_is_the_rms_of_the_recorded_world_state(tmp_path: Path) -> None:
    # Independent: the heave (mean per USV removed), roll and pitch RMS of a recording of the same scenario at W2
    # with the paper's motion, from its world_state table, pooled over USVs and frames.
    data = _scenario("island_port_waves", name="w2_paper", acquisition={"frequency_hz": 5, "frames": 12})
    data["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": None}}
    data["environment"] = {**data["environment"], "wave": "W2", "motion": "paper"}
    with pytest.warns(MmusvWarning, match="switches every sensor off"):  # world state only, on purpose
        rec = run(data, out_dir=tmp_path / "rec").recording
    ws = pl.read_parquet(rec.parent / "tables" / "world_state").filter(pl.col("role") == "usv")
    ids = sorted(set(ws["vessel_id"].to_list()))

    def series(col: str) -> np.ndarray:
        return np.stack([ws.filter(pl.col("vessel_id") == i).sort("frame")[col].to_numpy() for i in ids], axis=1)

    z = series("z")
    rms = [
        np.sqrt(np.mean(a**2)) for a in (z - z.mean(axis=0), np.degrees(series("roll")), np.degrees(series("pitch")))
    ]
    # One setting: no line to fit, R² NaN (was numpy's RankWarning from polyfit).
    study = run_wave_study(load_scenario(data), waves=("W2",))
    assert all(np.isnan(v) for v in study.r2.values()), study.r2
    row = study.table.row(0, named=True)
    assert row["H_m"] == 2.5 and row["usvs"] == 4 and row["frames"] == 12
    np.testing.assert_allclose([row["heave_rms_m"], row["roll_rms_deg"], row["pitch_rms_deg"]], rms, rtol=1e-12)


def test_waves_never_writes_a_new_table_beside_an_old_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A folder named wave_study.png in -o: the CSV was written, then the plot failed (exit 2, a new CSV beside
    # whatever the folder held). Now nothing is written and the file is named.
    out = tmp_path / "waves"
    (out / "wave_study.png").mkdir(parents=True)
    assert main(["study", "waves", "--frames", "3", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "wave_study.png" in err and "Traceback" not in err, err
    assert sorted(p.name for p in out.iterdir()) == ["wave_study.png"]
    # Into an existing folder: the study's files are replaced, others kept, the same bytes as into a new one.
    (out / "wave_study.png").rmdir()
    (out / "notes.txt").write_text("mine\n", encoding="utf-8")
    assert main(["study", "waves", "--frames", "3", "-o", str(out)]) == 0
    assert main(["study", "waves", "--frames", "3", "-o", str(tmp_path / "fresh")]) == 0
    for name in ("wave_study.csv", "wave_study.png"):
        assert (out / name).read_bytes() == (tmp_path / "fresh" / name).read_bytes(), name
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "wave_study.csv", "wave_study.png"]


# --- Table II: mmusv study agreement ----------------------------------------------------------------------------


def test_agreement_without_a_top_view_is_refused_before_the_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Was an empty table, a two-column CSV and exit status 0.
    no_tv = _write(
        tmp_path, _scenario("open_sea_convoy", name="no_tv", rigs={"usv_standard": {"top_view": None}}), "no_tv"
    )
    no_usv = _scenario("open_sea_convoy", name="no_usv")
    no_usv["vessels"] = [v for v in no_usv["vessels"] if v["role"] != "usv"]
    no_usv_path = _write(tmp_path, no_usv, "no_usv")
    for scenario, said in ((no_tv, "no USV whose rig has a top_view"), (no_usv_path, "no vessel with role: usv")):
        out = tmp_path / "agree"
        err = _refused(["study", "agreement", scenario, "--frames", "1", "-o", str(out)], capsys)
        assert scenario in err and "top-view camera" in err and said in err, err
        assert not out.exists()
        with pytest.raises(ConfigError, match="top-view camera"):
            run_agreement_study([scenario], frames=1)


def test_agreement_checks_every_scenario_before_the_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A missing (or unreadable, or a folder) second scenario was named after the first had run, and left an
    # empty output folder behind.
    good = str(ROOT / "scenarios/open_sea_convoy.yaml")
    (tmp_path / "a_folder").mkdir()
    (tmp_path / "bad.yaml").write_text("vessels: [\n", encoding="utf-8")
    for other, said in (
        (str(tmp_path / "missing.yaml"), "does not exist"),
        (str(tmp_path / "a_folder"), "is a directory"),
        (str(tmp_path / "bad.yaml"), "not valid YAML"),
    ):
        out = tmp_path / "agree"
        err = _refused(["study", "agreement", good, other, "--frames", "1", "-o", str(out)], capsys)
        assert said in err, err
        assert not out.exists(), other


def test_agreement_without_valid_samples_keeps_its_columns(tmp_path: Path) -> None:
    # A target far outside the only top view: no valid sample. The tables had two columns (their CSV header too).
    data = {
        "name": "far",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 1},
        "acquisition": {"frequency_hz": 5, "frames": 1},
        "rigs": {"r": {"preset": "lidar_only", "lidar": None, "top_view": {"resolution": [64, 64]}}},
        "vessels": [
            {
                "id": "usv_1",
                "role": "usv",
                "asset": "usv_wamv",
                "rig": "r",
                "speed_mps": 2.0,
                "route": [[0, 0], [100, 0]],
            },
            {"id": "t", "asset": "tug_32m", "speed_mps": 2.0, "route": [[1000, 1000], [1100, 1000]]},
        ],
    }
    study = run_agreement_study([_write(tmp_path, data, "far")])
    assert study.samples.height == 0 and study.summary.height == 0
    assert study.summary.columns == [
        "map",
        "valid_samples",
        "median_centre_error_px",
        "median_centroid_error_px",
        "mean_containment",
        "mean_hull_occupancy",
    ]
    assert study.samples.columns[:5] == ["map", "scenario", "frame", "agent", "target"]
    assert "centroid_error_px" in study.samples.columns and "hull_occupancy" in study.samples.columns
    paths = study.write(tmp_path / "out")
    assert pl.read_csv(paths["summary"]).columns == study.summary.columns


def test_agreement_centroid_and_occupancy_are_the_papers_over_the_overlap() -> None:
    # The paper: the centroid of M_local ∩ H_proj, and O_hull = |M_local ∩ H_proj| / |H_proj|. A rendered vessel
    # sticking out of its box's hull by 30 of its 90 pixels: the overlap's centroid is the box centre (error 0),
    # and the hull is full (1.0); the whole component's centroid was 2.5 px off and its occupancy 1.5 (over 1).
    semantic = np.zeros((40, 40), dtype=np.uint8)
    semantic[17:23, 15:30] = 10
    instance = np.where(semantic > 0, 7, 0).astype(np.uint16)
    # Camera frame = world (x viewing direction): u = 20 − y, v = 20 − z; the box spans u 15..25, v 17..23.
    r = sample_agreement(
        semantic=semantic,
        instance=instance,
        camera_pose=np.eye(4),
        metres_per_pixel=1.0,
        box_matrix=np.eye(4),
        box_size=np.array([2.0, 10.0, 6.0]),
        instance_id=7,
    )
    assert r is not None
    assert r["containment"] == pytest.approx(60 / 90)
    assert r["centroid_error_px"] == pytest.approx(0.0, abs=1e-9)
    assert r["hull_occupancy"] == pytest.approx(1.0)
    assert r["pixels"] == 90


def test_agreement_matches_an_independent_projection_of_a_recording(tmp_path: Path) -> None:
    # Independent: the recorded top-view semantic/instance PNGs, the /tf top-view poses (optical frame: x right,
    # y down, z forward) and the world-state boxes; own corner rotation, projection, hull and labelling.
    from matplotlib.path import Path as MplPath
    from mmusv.recording import read_messages, summary
    from PIL import Image
    from scipy import ndimage
    from scipy.spatial import ConvexHull

    data = _scenario("open_sea_convoy", name="tv_only", acquisition={"frequency_hz": 5, "frames": 1})
    data["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": None, "top_view": {}}}
    rec = run(data, out_dir=tmp_path / "rec").recording
    rigs = json.loads(summary(rec)["metadata"]["sensors"]["json"])
    msgs = {t: m for t, _, m in read_messages(rec)}

    def quat(q: Any) -> np.ndarray:
        x, y, z, w = q.x, q.y, q.z, q.w
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )

    def rpy(r: float, p: float, y: float) -> np.ndarray:
        rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
        ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
        rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
        return rz @ ry @ rx

    mine = []
    for agent, info in rigs.items():
        tv = info["rig"]["top_view"]
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        tf = next(t for t in msgs["/tf"].transforms if t.child_frame_id == f"{agent}/top_view")
        rot, origin = quat(tf.rotation), np.array([tf.translation.x, tf.translation.y, tf.translation.z])
        sem = np.array(Image.open(io.BytesIO(msgs[f"/{agent}/top_view/semantic"].data)))
        ins = np.array(Image.open(io.BytesIO(msgs[f"/{agent}/top_view/instance"].data)))
        labels, _ = ndimage.label(np.isin(sem, (10, 11)))
        vv, uu = np.mgrid[0:h, 0:w]
        for v in msgs["/world/state"].vessels:
            if v.id == agent:
                continue
            signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) / 2.0
            corners = np.array(v.box_center) + (signs * np.array(v.box_size)) @ rpy(*v.pose[3:6]).T
            cam = (corners - origin) @ rot
            uv = np.stack([w / 2 + cam[:, 0] / m, h / 2 + cam[:, 1] / m], axis=1)
            if uv.min() < 0 or uv[:, 0].max() > w or uv[:, 1].max() > h:
                continue
            hull = ConvexHull(uv)
            inside = MplPath(uv[hull.vertices]).contains_points(np.stack([uu.ravel() + 0.5, vv.ravel() + 0.5], 1))
            inside = inside.reshape(h, w)
            cand = labels[inside & (labels > 0)]
            if cand.size == 0:
                continue
            mask = labels == np.bincount(cand).argmax()
            if not np.all(ins[mask] == v.instance_id):
                continue
            both = mask & inside
            rows, cols = np.nonzero(both)
            centre = (np.array(v.box_center) - origin) @ rot
            err = np.hypot(cols.mean() + 0.5 - (w / 2 + centre[0] / m), rows.mean() + 0.5 - (h / 2 + centre[1] / m))
            mine.append((agent, v.id, err, both.sum() / mask.sum(), both.sum() / hull.volume))
    assert len(mine) >= 5
    got = run_agreement_study([_write(tmp_path, data, "tv_only")]).samples.sort(["agent", "target"])
    assert list(zip(got["agent"], got["target"], strict=True)) == sorted((a, t) for a, t, *_ in mine)
    ref = np.array([r[2:] for r in sorted(mine)])
    np.testing.assert_allclose(
        got.select("centroid_error_px", "containment", "hull_occupancy").to_numpy(), ref, atol=1e-6
    )
    assert float(np.median(ref[:, 0])) <= 2.0  # within the paper's 2.08 px median
