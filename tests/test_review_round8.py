"""Review of the exports' changes after ``ae31164`` (KITTI truncation, ROS 2 time offset, OPV2V depth for HEAL).

* ``<ts>_depth{i}.png`` (:func:`mmusv.export.opv2v.heal_depth_png`): its docs (the module's, ``HEAL_DEPTH_FAR``'s,
  ``docs/exports.md``, ``docs/opencood.md``) put a hit at 254.5 m and farther at 255; ``np.rint`` rounds half to
  even, so exactly 254.5 m was written 254.
* ``mmusv dataset`` takes an OPV2V conversion made before the change (``<ts>_depth{i}.png`` uint16 centimetres, no
  ``<ts>_depth_cm{i}.png``) for up to date when its recordings are unchanged, and keeps it: HEAL then reads the
  centimetres under the name the docs now give to 8-bit metres (``conversion.yaml``'s ``format_version``, now
  compared).
* KITTI ``truncated`` 1.00 ("wholly leaving image boundaries") is written for every target without a recorded
  front-camera box, also one whose projected box lies wholly inside the image (a small vessel far ahead that no pixel
  centre hits): before it was 0.00, right for that case (now its projected box's share outside the image).
* ``docs/opencood.md``'s *Depth for HEAL* left out that HEAL's camera hypes also need ``<ts>_bev_visibility.png``.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
import yaml
from kitti_files import label_corners, read_calib


def _read_png(data: bytes) -> np.ndarray:
    from PIL import Image

    with Image.open(io.BytesIO(data)) as img:
        assert img.mode == "L"
        return np.asarray(img)


def test_heal_depth_png_writes_254_5_m_and_farther_as_255() -> None:
    """``255 = no hit or 254.5 m and farther``: 254.5 m itself is 255, just below it 254 (float32 depths, as
    recorded)."""
    from mmusv.export.opv2v import HEAL_DEPTH_FAR, heal_depth_png

    d = np.array([[254.5, 254.75, 255.0, np.nextafter(np.float32(254.5), np.float32(0)), 253.6, 1.4]], np.float32)
    got = _read_png(heal_depth_png(d.astype(np.float64)))
    assert got.tolist() == [[HEAL_DEPTH_FAR, 255, 255, 254, 254, 1]]


def test_dataset_does_not_keep_an_opv2v_conversion_of_the_old_depth_format(tmp_path: Path) -> None:
    """An OPV2V folder converted before ``<ts>_depth{i}.png`` became 8-bit metres (its data_protocol's ``depth_png``
    uint16 centimetres, no ``_depth_cm`` files, the conversion report of that time) is not a finished conversion of
    today's format: ``mmusv dataset`` must convert again rather than report it up to date."""
    from mmusv.acquire import run
    from mmusv.batch.dataset import _conversion_complete
    from mmusv.export import convert

    cfg = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios" / "port_entry.yaml").read_text())
    cams = [
        {"name": n, "resolution": [64, 48], "hfov_deg": 90, "mount": {"point": f"camera_{n}"}}
        for n in ("front", "left", "rear", "right")
    ]
    cfg["rigs"] = {"usv_standard": {"lidar": {"channels": 16, "points_per_second": 14400}, "cameras": cams}}
    rec = Path(run(cfg, out_dir=tmp_path / "rec", frames=1).recording)
    out = tmp_path / "opv2v"
    convert(rec, to="opv2v", out_dir=out, splits=None, extras=("depth",))
    assert _conversion_complete(out)  # today's conversion is finished
    # The same folder as the converter before the change wrote it.
    depth_cm = sorted(out.rglob("*_depth_cm*.png"))
    assert depth_cm
    for p in depth_cm:
        p.replace(p.with_name(p.name.replace("_depth_cm", "_depth")))  # uint16 cm under the HEAL name
    for proto in out.rglob("data_protocol.yaml"):
        doc = yaml.safe_load(proto.read_text())
        m = doc["mmusv"]
        m.pop("depth_cm_png")
        m["depth_png"] = {"unit_m": 0.01, "no_hit": 0, "saturated": 65535, "along": "optical axis"}
        proto.write_text(yaml.safe_dump(doc, sort_keys=False))
    report = out / "conversion.yaml"
    old_keys = {"agent_frames", "format", "frames_converted", "options", "recordings", "status"}
    doc = yaml.safe_load(report.read_text())
    report.write_text(yaml.safe_dump({k: v for k, v in doc.items() if k in old_keys}, sort_keys=False))
    if _conversion_complete(out):
        pytest.fail(
            f"{out}: an OPV2V conversion of the old depth format (uint16 cm as <ts>_depth{{i}}.png) is taken for "
            "finished: `mmusv dataset` keeps it 'up to date', and HEAL reads centimetres as metres"
        )


def test_opencood_doc_says_what_else_heals_camera_hypes_need() -> None:
    """``docs/opencood.md``'s *Depth for HEAL* presents the 8-bit depth as what HEAL's camera models need; their hypes
    (``m2``/``m4``: ``input_source: ['camera', 'depth']``) also read ``<ts>_bev_visibility.png``
    (``add_data_extension``, ``label_type: 'camera'``), which the export does not write: HEAL stops in
    ``cv2.cvtColor`` on the missing file. The section says so, and how to do without."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "opencood.md").read_text()
    section = doc.split("## Depth for HEAL", 1)[1].split("\n## ", 1)[0]
    assert "bev_visibility.png" in section and "label_type: 'lidar'" in section


def test_kitti_truncated_is_not_one_for_a_boxless_target_inside_the_image(tmp_path: Path) -> None:
    """The devkit's ``truncated`` is the share of the object "leaving image boundaries". A kayak 189 m dead ahead of
    the front camera (160×120, 90°: under a pixel tall) has no recorded 2D box (no pixel centre hits it), yet its
    projected 3D box lies wholly inside the image: it leaves no boundary, so 0.00 (what was written before), not the
    1.00 of a target behind or beside the camera."""
    import importlib.util

    from mmusv.acquire import run
    from mmusv.export import convert
    from PIL import Image

    spec = importlib.util.spec_from_file_location("review8_export_scenes", Path(__file__).parent / "export/conftest.py")
    assert spec is not None and spec.loader is not None
    scenes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scenes)
    cfg = scenes.coop(name="kayak_ahead")
    cfg["vessels"] = [v for v in cfg["vessels"] if v["id"] != "boat"] + [
        {"id": "kay", "role": "target", "asset": "kayak_4m", "speed_mps": 0.5, "route": [[158.0, 105.0], [258, 172]]}
    ]
    rec = Path(run(cfg, out_dir=tmp_path / "rec", frames=1).recording)
    convert(rec, to="kitti", out_dir=tmp_path / "k", splits=None, extras=())
    agent = tmp_path / "k" / "kayak_ahead" / "1000"  # usv_a
    p = read_calib(agent / "calib" / "000000.txt")["P2"].reshape(3, 4)
    with Image.open(agent / "image_2" / "000000.png") as img:
        width, height = img.size
    inside = []
    for line in (agent / "label_2" / "000000.txt").read_text().splitlines():
        f = line.split()
        corners = label_corners(f)
        if f[2] != "3" or not np.all(corners[:, 2] > 1.0):
            continue
        uvw = np.c_[corners, np.ones(8)] @ p.T
        uv = uvw[:, :2] / uvw[:, 2:]
        if np.all((uv >= 0) & (uv <= [width, height])):
            inside.append(line)
    assert inside, "the kayak ahead should be a box-less line (occluded 3) inside the front image"
    assert all(ln.split()[1] == "0.00" for ln in inside), inside


def test_convert_piped_prints_no_empty_line_before_an_error(tmp_path: Path) -> None:
    """``mmusv convert`` of a missing recording with its output piped (no ``--no-progress``): the transient progress
    bar, on no terminal, left an empty line on stdout before the error on stderr (a README walk's finding). The bar
    shows on a terminal only; stdout stays empty and stderr holds the one error line."""
    import subprocess
    import sys

    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "mmusv",
            "convert",
            str(tmp_path / "nope.mcap"),
            "--to",
            "kitti",
            "-o",
            str(tmp_path / "k"),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr.startswith("mmusv: error: recording ") and "does not exist" in r.stderr
