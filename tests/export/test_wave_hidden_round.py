"""Targets the waves hide, through the exports: a W3 sea (the physical sea, the default motion) with 5 m craft at
120, 180 and 250 m ahead of two USVs with a narrow front camera and a long-range LiDAR, 2 frames.

In that recording (measured 2026-12-06) the crests hide the craft at 180 m wholly from ``usv_b`` in both frames
(camera: 0 of its pixels, occlusion and wave share 1; LiDAR: 0 of 10 beams, share 1) and the craft at 250 m by 44 %
and 34 % from its camera (37 and 48 pixels left of 66 and 73 over a flat sea); the craft at 120 m keeps 4 LiDAR points
of 45 beams (share 0.91) in frame 1.
"""

from __future__ import annotations

import glob
import json
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.recording.tables import read_table


def _scenario() -> dict[str, Any]:
    camera = {
        "name": "front",
        "resolution": [320, 180],
        "hfov_deg": 24.0,
        "outputs": ["rgb", "instance", "semantic"],
        "quality": "draft",
        "mount": {"xyz": [2.0, 0.0, 3.5], "rpy_deg": [0.0, 0.8, 0.0]},
    }
    lidar = {"channels": 64, "vertical_fov_deg": [-6.0, 4.0], "points_per_second": 64 * 1500 * 5.0, "range_m": 300.0}
    craft = [("c120", 120.0, -5.0), ("c180", 180.0, 12.0), ("c250", 250.0, -15.0)]
    return {
        "name": "wavehide",
        "seed": 29,
        "map": {"type": "open_sea", "seed": 1, "params": {"n_buoys": 0, "islet_probability": 0.0}},
        "environment": {"time_of_day": "15:00", "weather": "clear", "wave": "W3"},
        "acquisition": {"frequency_hz": 5, "frames": 2},
        "rigs": {"r": {"cameras": [camera], "top_view": None, "lidar": lidar, "radar": None}},
        "vessels": [
            *(
                {"id": i, "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0.5, "route": [[0, y], [200, y]]}
                for i, y in (("usv_a", 0.0), ("usv_b", 30.0))
            ),
            *(
                {"id": i, "role": "target", "asset": "speedboat_5m", "speed_mps": 0.5, "route": [[x, y], [x, 200.0]]}
                for i, x, y in craft
            ),
        ],
    }


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    out = tmp_path_factory.mktemp("wavehide")
    return Path(run(_scenario(), out_dir=out).recording)


def _convert(rec: Path, tmp: Path, to: str, **kw: Any) -> Path:
    from mmusv.export import convert

    out = tmp / to
    convert(rec, to=to, out_dir=out, splits=None, **kw)
    return out


def _boxes(rec: Path, table: str) -> pl.DataFrame:
    return read_table(rec.parent / "tables", table).rows


def test_the_recording_holds_wholly_and_partly_hidden_craft(rec: Path) -> None:
    """The premise of the tests below (a change of the sea or the renderer moves it, and this says so first)."""
    b2 = _boxes(rec, "boxes_2d").filter(pl.col("agent") == "usv_b")
    hidden = b2.filter(pl.col("target_id") == "c180")
    assert hidden.height == 2 and (hidden["visible_pixels"] == 0).all() and (hidden["wave_occlusion"] == 1.0).all()
    part = b2.filter(pl.col("target_id") == "c250")
    assert ((part["wave_occlusion"] > 0.2) & (part["wave_occlusion"] < 0.6) & (part["visible_pixels"] > 0)).all()
    b3 = _boxes(rec, "boxes_3d").filter((pl.col("agent") == "usv_b") & (pl.col("target_id") == "c180"))
    assert (b3["wave_occlusion"] == 1.0).all() and (b3["lidar_points"] == 0).all()


def test_coco_annotations_carry_the_camera_wave_share(rec: Path, tmp_path: Path) -> None:
    """COCO's extras had ``occlusion``, which counts the crests and the other hulls alike, but not the share the
    waves hide (the recording's ``wave_occlusion``): a user of the COCO set could not tell a craft behind a crest
    from one behind a ship. Each annotation now carries the camera box's ``wave_occlusion`` as recorded."""
    out = _convert(rec, tmp_path, "coco")
    doc = json.loads(Path(glob.glob(str(out / "annotations" / "*.json"))[0]).read_text())
    images = {im["id"]: im for im in doc["images"]}
    want = {
        (r["frame"], r["agent"], r["camera"], r["target_id"]): r["wave_occlusion"]
        for r in _boxes(rec, "boxes_2d").iter_rows(named=True)
    }
    got = {}
    for a in doc["annotations"]:
        im = images[a["image_id"]]
        got[(im["frame"], im["agent"], im["camera"], a["mmusv_id"])] = a.get("wave_occlusion")
    assert got and all(k in want for k in got)
    for k, v in got.items():
        assert v == round(want[k], 6), (k, v, want[k])
    assert any(0.0 < v < 1.0 for v in got.values())  # the craft at 250 m, partly hidden


def test_opv2v_vehicles_carry_the_ego_lidar_wave_share(rec: Path, tmp_path: Path) -> None:
    """OPV2V's ``_additional.yaml`` gave each target's ``lidar_points`` but not why a target has none: a craft the
    crests hide wholly from the ego (share 1) and one no beam reaches looked alike. Each vehicle now carries the
    ego LiDAR box's ``wave_occlusion`` as recorded."""
    out = _convert(rec, tmp_path, "opv2v", extras="")
    want = {
        (r["frame"], r["agent"], r["target_id"]): (r["wave_occlusion"], r["lidar_points"])
        for r in _boxes(rec, "boxes_3d").iter_rows(named=True)
    }
    seen = []
    for f in sorted(glob.glob(str(out / "*" / "*" / "*_additional.yaml"))):
        m = yaml.safe_load(Path(f).read_text())["mmusv"]
        for v in m["vehicles"].values():
            share, points = want[(m["frame"], m["agent"], v["name"])]
            assert v.get("wave_occlusion") == round(share, 6), (f, v)
            assert v["lidar_points"] == points
            seen.append((m["agent"], v["name"], v["wave_occlusion"], v["lidar_points"]))
    assert ("usv_b", "c180", 1.0, 0) in seen  # wholly hidden: share 1, no point


def test_a_craft_the_waves_hide_wholly_is_left_out_of_coco_yolo_mot_and_kitti_scores(rec: Path, tmp_path: Path) -> None:
    """docs/exports.md: a vessel without a visible pixel gets no box in COCO, YOLO and MOT, whatever hides it (here
    the crests alone); KITTI keeps a target in range with ``occluded`` 3 (its "unknown", a distractor for its
    evaluations) and box ``0 0 0 0``, as one outside the image: it wrote the recorded (projected) box and ``occluded``
    2, a ground truth KITTI's evaluation scored. Counted against the recording: every COCO, YOLO and MOT box is one
    with a visible pixel."""
    b2 = _boxes(rec, "boxes_2d")
    n_visible = b2.filter(pl.col("visible_pixels") > 0).height
    coco = json.loads(Path(glob.glob(str(_convert(rec, tmp_path, "coco") / "annotations" / "*.json"))[0]).read_text())
    assert len(coco["annotations"]) == n_visible
    assert all(a["area"] > 0 and a["iscrowd"] == 0 for a in coco["annotations"])
    yolo = _convert(rec, tmp_path, "yolo")
    lines = [ln for f in sorted(yolo.rglob("labels/**/*.txt")) for ln in f.read_text().splitlines()]
    assert len(lines) == n_visible
    mot = _convert(rec, tmp_path, "mot")
    gt = [ln for f in sorted(mot.rglob("gt.txt")) for ln in f.read_text().splitlines()]
    assert len(gt) == n_visible
    kitti = _convert(rec, tmp_path, "kitti", extras="")
    # usv_b is cav 1001; its front box of c180 (occlusion 1, 0 pixels) in frame 0
    row = b2.filter((pl.col("frame") == 0) & (pl.col("agent") == "usv_b") & (pl.col("target_id") == "c180")).row(
        0, named=True
    )
    labels = [ln.split() for ln in (kitti / "wavehide" / "1001" / "label_2" / "000000.txt").read_text().splitlines()]
    projected = np.round([row["x_min"], row["y_min"], row["x_max"], row["y_max"]], 2)
    assert not any(np.array_equal(np.array(f[4:8], dtype=float), projected) for f in labels), labels
    unknown = [f for f in labels if f[0] != "DontCare" and f[2] == "3"]
    assert unknown and all(f[4:8] == ["0.00"] * 4 for f in unknown), labels
    assert f"{row['truncation']:.2f}" in {f[1] for f in unknown}, (labels, row["truncation"])


def test_the_detection_study_reads_the_wave_shares_from_an_opv2v_export_as_from_the_recording(
    rec: Path, tmp_path: Path
) -> None:
    """The detection study scores the recall of the targets the waves hide from the ego (``wave_shares``); read from
    an OPV2V export it had no share at all (every one NaN), so the W3 tables could only come from recordings. With
    the shares in ``_additional.yaml`` it reads, for each CAV and target, the recording's share."""
    from mmusv.studies.detection.data import gt_with_ids, read_opv2v, read_recording, wave_shares

    out = _convert(rec, tmp_path, "opv2v", extras="")
    from_rec = read_recording(rec)
    from_opv2v = read_opv2v(out / "wavehide")
    names: dict[str, str] = {}  # cav id -> vessel id, from the export's own _additional.yaml
    for f in glob.glob(str(out / "wavehide" / "*" / "*_additional.yaml")):
        for cav, v in yaml.safe_load(Path(f).read_text())["mmusv"]["vehicles"].items():
            names[str(cav)] = v["name"]
    compared = 0
    for fr_rec, fr_opv in zip(from_rec.frames, from_opv2v.frames, strict=True):
        for a_rec, a_opv in zip(fr_rec.agents, fr_opv.agents, strict=True):
            _, ids = gt_with_ids(fr_opv, a_opv)
            got = wave_shares(a_opv, ids)
            want = wave_shares(a_rec, [names[i] for i in ids])
            assert np.isfinite(want).all()
            np.testing.assert_allclose(got, want, atol=5e-7)
            compared += len(ids)
    assert compared >= 4


def test_a_rig_without_a_lidar_gives_its_3d_boxes_share_0_and_its_cameras_the_waves_share() -> None:
    """docs/recording.md: a share is of the rays that meet the vessel, so a rig without a LiDAR has every 3D box at
    ``wave_occlusion`` 0 (and ``lidar_points`` 0), while its camera gives the craft the crests hide wholly share 1:
    read the camera boxes for what the waves hide from such a USV."""
    from mmusv.acquire import annotations_for
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    cfg = _scenario()
    cfg["rigs"]["r"]["lidar"] = None
    sim = Simulation(cfg)
    cols = annotations_for(sim, sim.capture(0, radar=False), SilhouetteCache())["usv_b"].columns()
    lid, cam = cols["lidar"], cols["camera"]
    assert "c180" in list(lid["target_id"])
    assert (lid["wave_occlusion"] == 0.0).all() and (lid["lidar_points"] == 0).all()
    j = list(cam["target_id"]).index("c180")
    assert cam["wave_occlusion"][j] == 1.0 and cam["visible_pixels"][j] == 0


def _lidar_case() -> tuple[Any, Any, Any]:
    """A frame where ``usv_a``, 30 m abeam of ``usv_b``, lies above ``usv_b``'s LiDAR's lowest reach: rolled and
    pitched by the sea (Hs 3.5 m, Tp 9 s), its beams towards ``usv_a`` all run below -4.16° and meet the still level
    20.8 m out, short of ``usv_a`` (29.6 m), whose box reaches from -0.93 to 1.89 m. Over a flat sea no beam meets
    ``usv_a``; over the waves a trough bares 5 points of its hull below the still level, and the water stops 26 more
    beams there."""
    from mmusv.acquire import annotations_for
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    cfg = _scenario()
    cfg["acquisition"]["frames"] = 20
    cfg["environment"].pop("wave")
    cfg["environment"]["sea"] = {"hs_m": 3.5, "tp_s": 9.0}
    cfg["rigs"]["r"]["cameras"] = []
    sim = Simulation(cfg)
    sea, sil = sim.sea, SilhouetteCache()
    waves = sim.capture(17, radar=False, sensors=["lidar"])
    ann = annotations_for(sim, waves, sil)["usv_b"].columns()["lidar"]
    sim.set_sea_surface(None)
    flat = sim.capture(17, radar=False, sensors=["lidar"])
    sim.set_sea_surface(sea)
    return sim, (waves, flat), ann


def test_a_lidar_box_whose_part_above_the_still_level_no_beam_reaches_is_not_called_hidden_by_waves() -> None:
    """The camera's rule (docs/recording.md): where the image border cuts off all of a box's part above the still
    level, its rays meet only the lower hull and nothing of it counts as exposed (``wave_occlusion`` 0), rather than
    calling the lower hull, which a calm sea hides too, hidden by waves. The LiDAR's vertical field of view is its
    border: ``usv_b``'s LiDAR met ``usv_a`` only below the still level (its part above lies above the beams) and
    read ``wave_occlusion`` 0.839 (26 of 31 beams), with 5 points on ``usv_a`` that the waves bared, none hidden."""
    sim, (waves, flat), ann = _lidar_case()
    a = next(v for v in sim.vessels if v.id == "usv_a").instance_id
    on_flat = int((np.asarray(flat.agents["usv_b"].lidar_beams) == a).sum())
    on_waves = int((np.asarray(waves.agents["usv_b"].lidar_beams) == a).sum())
    assert on_flat == 0 and on_waves > 0  # the premise: the calm sea shows nothing of it, the waves show some
    j = list(ann["target_id"]).index("usv_a")
    assert ann["lidar_points"][j] > 0
    assert ann["wave_occlusion"][j] == 0.0
