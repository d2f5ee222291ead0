"""``mmusv preview``: titled panels, one per recorded sensor image, 2D and 3D boxes drawn where the annotations say."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from mmusv.acquire import run
from mmusv.preview import _RING, _TITLE_H, BOX_COLOUR, _bev_half_extent, _font, _rings, compose_preview
from mmusv.recording import frame_messages, read_info, topics

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    sc = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = 1
    sc["vessels"] = [v for v in sc["vessels"] if v["id"] != "usv_3"]
    sc["rigs"] = {
        "usv_standard": {
            "lidar": {"channels": 16, "points_per_second": 16 * 360 * 5},
            "radar": {"range_m": 1000, "azimuth_bins": 256, "rays_el": 8, "ppi_size_px": 64},
            "cameras": [
                {"name": n, "resolution": [320, 240], "mount": {"point": f"camera_{n}"}}
                for n in ("front", "left", "rear", "right")
            ],
            "top_view": {"resolution": [64, 64], "metres_per_pixel": 2.0},
        }
    }
    return run(sc, out_dir=tmp_path_factory.mktemp("prev")).recording


def _is_box(px: np.ndarray) -> np.ndarray:
    return np.all(px == np.array(BOX_COLOUR, dtype=np.uint8), axis=-1)


def test_one_titled_non_blank_panel_per_recorded_image(recording: Path) -> None:
    sheet, panels = compose_preview(recording, frame=0)
    msgs = frame_messages(recording, 0)
    images = [
        t
        for t in msgs
        if topics.agent_of(t) == "usv_1"
        and (
            ("/camera/" in t and t.rsplit("/", 1)[1] in ("rgb", "depth", "semantic"))
            or (t.startswith(topics.top_view("usv_1")) and t.rsplit("/", 1)[1] in ("rgb", "semantic"))
            or t in (topics.radar_ppi("usv_1"), topics.lidar("usv_1"))
        )
    ]
    assert len(panels) == len(images) == 4 * 3 + 4
    arr = np.asarray(sheet)
    titles = [p.title for p in panels]
    assert len(set(titles)) == len(titles) and all(t.startswith("usv_1 · ") for t in titles)
    for cam in ("front", "left", "rear", "right"):
        for kind in ("RGB", "depth", "semantic"):
            assert sum(cam in t and kind in t for t in titles) == 1
    assert any("PPI" in t for t in titles) and any("BEV" in t for t in titles)
    assert sum("top view" in t for t in titles) == 2
    for p in panels:
        left, t, r, b = p.box
        body = arr[t:b, left:r].reshape(-1, 3)
        assert len(np.unique(body, axis=0)) > 1, f"blank panel {p.title}"
        strip = arr[t - _TITLE_H : t, left:r].reshape(-1, 3)
        assert len(np.unique(strip, axis=0)) > 2, f"no title text on {p.title}"
    # panels tile the sheet without overlapping
    for i, p in enumerate(panels):
        for q in panels[i + 1 :]:
            assert p.box[2] <= q.box[0] or q.box[2] <= p.box[0] or p.box[3] <= q.box[1] or q.box[3] <= p.box[1]


def test_2d_boxes_on_the_camera_edges(recording: Path) -> None:
    sheet, panels = compose_preview(recording, frame=0)
    arr = np.asarray(sheet)
    ann = frame_messages(recording, 0)[topics.agent_annotations("usv_1")]
    boxes = [b for b in ann.boxes_camera if b.x_max - b.x_min >= 6 and b.y_max - b.y_min >= 6]
    assert boxes, "the test scenario must put a box of a few pixels in a camera"
    for b in boxes:
        p = next(p for p in panels if p.title.startswith(f"usv_1 · {b.camera} camera · RGB"))
        left, t = p.box[0], p.box[1]
        x0, y0, x1, y1 = (
            round(left + b.x_min * p.scale),
            round(t + b.y_min * p.scale),
            round(left + b.x_max * p.scale),
            round(t + b.y_max * p.scale),
        )
        x1, y1 = min(x1, p.box[2] - 1), min(y1, p.box[3] - 1)
        # the left and right edges (skip the corners, where a label may sit above the top edge)
        for x in (x0, x1):
            col = arr[y0 + 2 : y1 - 1, max(x - 1, left) : x + 2]
            assert _is_box(col).any(axis=1).all(), f"edge x={x} of box {b.target_id} in {b.camera} not drawn"
        # and the box interior is not filled
        if x1 - x0 > 8 and y1 - y0 > 8:
            assert not _is_box(arr[y0 + 4 : y1 - 3, x0 + 4 : x1 - 3]).all()


def test_3d_box_footprints_in_the_bev(recording: Path) -> None:
    sheet, panels = compose_preview(recording, frame=0, agent="usv_2")  # usv_2 has the tug in LiDAR range
    arr = np.asarray(sheet)
    ann = frame_messages(recording, 0)[topics.agent_annotations("usv_2")]
    bev = next(p for p in panels if "BEV" in p.title)
    left, t, r, b = bev.box
    cu, cv = left + (r - left) / 2, t + (b - t) / 2
    assert list(ann.boxes_lidar)
    drawn = 0
    for box in ann.boxes_lidar:
        # a corner of the footprint, computed here from centre, size and yaw (x forward up, y left to the left)
        c, s = math.cos(box.yaw), math.sin(box.yaw)
        bx = box.center[0] + c * box.size[0] / 2 - s * box.size[1] / 2
        by = box.center[1] + s * box.size[0] / 2 + c * box.size[1] / 2
        u, v = round(cu - by * bev.scale), round(cv - bx * bev.scale)
        if left + 2 <= u < r - 2 and t + 2 <= v < b - 2:
            assert _is_box(arr[v - 2 : v + 3, u - 2 : u + 3]).any(), f"corner of {box.target_id} not drawn"
            drawn += 1
    assert drawn >= 1


def test_the_bev_holds_every_box_and_not_much_more() -> None:
    """The BEV square holds every box centre with a tenth to spare, and is at most a quarter wider than that (a
    target at 200 m in a ±500 m square left a 200 m LiDAR's points in its middle fifth), from 100 m to 1,000 m:
    box ranges 0-950 m every 0.5 m."""
    for reach_m in np.arange(0.0, 950.0, 0.5):
        boxes = [SimpleNamespace(center=(0.3 * reach_m, -reach_m, 1.0)), SimpleNamespace(center=(10.0, 5.0, 0.0))]
        half = _bev_half_extent(boxes)
        need = max(1.1 * reach_m, 100.0)
        assert min(need, 1000.0) <= half <= min(1.25 * need, 1000.0), (reach_m, half)


def test_ppi_ring_scale_from_the_recording(recording: Path) -> None:
    _sheet, panels = compose_preview(recording, frame=0)
    ppi = next(p for p in panels if "PPI" in p.title)
    a = read_info(recording).agents[0]
    assert a.ppi_metres_per_pixel == pytest.approx(1000 / 32)  # range_m / (ppi_size_px // 2)
    # the panel spans the PPI image: 64 px × m/px metres across
    assert ppi.scale * 64 * a.ppi_metres_per_pixel == pytest.approx(ppi.box[2] - ppi.box[0])


def test_ring_labels_stand_on_a_black_backing_over_returns() -> None:
    """Over a PPI full of returns, a ring label's box holds the label's colour, black and the anti-aliased shades
    between them, none of the returns' green (a return behind the "1" of "1000 m" made it read "4000 m")."""
    from PIL import Image, ImageDraw

    green = (40, 220, 40)
    pil = Image.new("RGB", (200, 200), green)
    draw = ImageDraw.Draw(pil)
    _rings(draw, centre=(100.0, 100.0), px_per_m=0.05, max_m=2000.0)
    at = (100 + 1000 * 0.05 * 0.7071 + 2, 100 - 1000 * 0.05 * 0.7071 - 12)
    x0, y0, x1, y1 = (round(v) for v in draw.textbbox(at, "1000 m", font=_font(11)))
    patch = np.asarray(pil)[y0:y1, x0:x1].reshape(-1, 3).astype(int)
    assert patch.size and not (patch == green).all(axis=1).any()
    assert (patch == _RING).all(axis=1).any()  # the label itself is drawn


def test_unknown_agent_is_a_clear_error(recording: Path) -> None:
    from mmusv.errors import ConfigError

    with pytest.raises(ConfigError, match=r"no agent 'nobody'.*usv_1"):
        compose_preview(recording, frame=0, agent="nobody")
    with pytest.raises(ConfigError, match=r"no agent ''"):  # an empty name is not "the first agent"
        compose_preview(recording, frame=0, agent="")


def test_the_output_is_a_picture_path_or_a_folder(recording: Path, tmp_path: Path) -> None:
    from mmusv.errors import ConfigError
    from mmusv.preview import write_preview

    # A folder takes the picture under its default name; a path without a picture suffix is refused before the
    # frame is read (it was a bare Pillow "unknown file extension" traceback).
    out = write_preview(recording, frame=0, output=tmp_path)
    assert out.parent == tmp_path and out.suffix == ".png" and out.stat().st_size > 0
    for bad in (tmp_path / "p.txt", tmp_path / "noext"):
        with pytest.raises(ConfigError, match=r"\.png, \.jpg, \.jpeg, or a folder"):
            write_preview(recording, frame=0, output=bad)
        assert not bad.exists()
    assert write_preview(recording, frame=0, output=tmp_path / "p.JPG").stat().st_size > 0


def test_a_frame_after_a_stopped_run_s_last_is_said_to_be_past_it(tmp_path: Path) -> None:
    """A review's: a run stopped after its first frames was said to hold every frame it set out to write ("holds
    frames 0..4999" of a run interrupted after 297), and a frame past its last was looked for as if damaged."""
    from mmusv.acquire import run
    from mmusv.errors import ConfigError
    from mmusv.recording import frame_messages
    from tiny_scenario import lidar_scenario

    def stop(done: int, _total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(lidar_scenario("stopped", frames=6), out_dir=tmp_path, progress=stop)
    rec = tmp_path / "stopped.mcap"
    assert frame_messages(rec, 1)
    with pytest.raises(ConfigError) as err:
        frame_messages(rec, 4)
    assert "which holds frames 0..1 (its run is interrupted: 2 of the 6 frames it set out to write)" in str(err.value)
    with pytest.raises(ConfigError, match=r"which holds frames 0\.\.1 \(its run is interrupted"):  # past the plan
        frame_messages(rec, 9)


def test_a_preview_that_cannot_be_written_leaves_the_picture_before_it(recording: Path, tmp_path: Path) -> None:
    """``-o`` of an existing picture and a write that fails (here the file size limit; a full disk alike): the
    picture was cut to the limit, a PNG that no longer reads, and the one before it lost."""
    import subprocess
    import sys

    out = tmp_path / "keep.png"
    before = b"\x89PNG\r\n\x1a\n" + b"an earlier preview" * 10
    out.write_bytes(before)

    code = (
        "import resource, sys\nfrom mmusv.errors import IoError\nfrom mmusv.preview import write_preview\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))\n"
        "try:\n    write_preview(sys.argv[1], frame=0, output=sys.argv[2])\n"
        "except IoError as exc:\n    print(exc)\n    sys.exit(3)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(recording), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 3 and "cannot write the preview" in done.stdout, (done.stdout, done.stderr)
    assert out.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["keep.png"]


def test_preview_names_the_flags_typed_and_python_the_arguments(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The command's messages named the API's keyword arguments (``frame = 5: not in ...``, ``output 'p.txt'``),
    not the flags typed, though the same command's ``--frame = -1`` named its flag."""
    from mmusv.cli import main
    from mmusv.errors import ConfigError
    from mmusv.preview import write_preview

    assert main(["preview", str(recording), "--frame", "5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: --frame 5: not in ") and "which holds frame 0" in err, err
    assert main(["preview", str(recording), "-o", str(tmp_path / "p.txt")]) == 2
    err = capsys.readouterr().err
    assert f"-o/--output {tmp_path / 'p.txt'}: give a picture path" in err, err
    # Python keeps its keyword arguments' names
    with pytest.raises(ConfigError, match=r"^frame = 5: not in "):
        write_preview(recording, frame=5)
    with pytest.raises(ConfigError, match=r"^output = '.*p\.txt': give a picture path"):
        write_preview(recording, frame=0, output=tmp_path / "p.txt")
