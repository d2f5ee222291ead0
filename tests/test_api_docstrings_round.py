"""A sweep of the public API's docstrings against what the code returns (shape, dtype, unit, frame, range), on a tiny
scenario: one USV with a LiDAR, a small camera and a top view, one fishing boat ahead; one frame captured and one
recorded. Each test pins a docstring that said something the code does not do."""

from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path
from typing import Any

import mmusv.annotate
import mmusv.classes
import mmusv.sensors.config
import numpy as np
import pytest
from mmusv import Simulation, run
from mmusv.acquire import annotations_for
from mmusv.recording import decode_image
from mmusv.recording.info import read_info
from mmusv.recording.stream import FrameStream
from mmusv.sensors.config import Mount
from mmusv.sensors.mounts import mount_matrix
from mmusv.sensors.radar import ppi_image
from mmusv.silhouettes import SilhouetteCache
from mmusv.world.vessels import get_asset

PPI_SIZE = 33  # odd: its default scale is the range over 16 pixels, not 16.5


def _scenario() -> dict[str, Any]:
    rig = {
        "preset": "lidar_only",
        "lidar": {"channels": 8, "points_per_second": 8 * 360 * 5},
        "cameras": [{"name": "front", "resolution": [48, 32], "mount": {"point": "camera_front"}}],
        "top_view": {"resolution": [32, 32], "metres_per_pixel": 0.5},
        "radar": {"range_m": 300, "azimuth_bins": 64, "rays_el": 2, "ppi_size_px": PPI_SIZE},
    }
    return {
        "name": "docstrings",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": 1},
        "environment": {"motion": "paper"},
        "rigs": {"r": rig},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 1, "route": [[30, -10], [30, 50]]},
        ],
    }


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return run(_scenario(), out_dir=tmp_path_factory.mktemp("rec")).recording


def _frame0(path: Path) -> Any:
    return next(iter(FrameStream(read_info(path), lambda topic: True)))


def test_recorded_semantic_images_are_class_ids_not_the_palette(recorded: Path) -> None:
    """``mmusv.classes`` said the palette is the one "semantic camera PNGs use"; the recorded semantic PNGs hold
    the class ids themselves, 16-bit gray (docs/recording.md), and the palette colours only the quick-look images."""
    sim = Simulation(_scenario())
    cap = sim.capture(0, sensors=["cameras", "top_view"])
    fr = _frame0(recorded)
    for topic, images in (
        ("/u/camera/front/semantic", cap.agents["u"].cameras["front"]),
        ("/u/top_view/semantic", cap.agents["u"].top_view),
    ):
        assert images is not None
        img = decode_image(fr.messages[topic])
        assert img.dtype == np.uint16 and img.ndim == 2, topic
        np.testing.assert_array_equal(img, images.semantic)
    doc = inspect.getdoc(mmusv.classes) or ""
    assert "semantic camera PNGs use" not in doc
    assert "class ids themselves" in doc


def test_box_pixels_are_the_pixels_the_2d_box_touches() -> None:
    """``box_pixels`` was "the recorded box's area, whole pixels" (docs/recording.md: "pixels of the clipped box"):
    it is the count of the pixels the box touches, ``(ceil x_max - floor x_min) * (ceil y_max - floor y_min)``,
    the window ``visible_pixels`` is counted in, well above the box's area for a small box."""
    sim = Simulation(_scenario())
    cap = sim.capture(0, sensors=["lidar", "cameras"])
    ann = annotations_for(sim, cap, SilhouetteCache())["u"]  # as a recording annotates the frame
    cam = ann.columns()["camera"]
    assert len(cam["target_id"]) >= 1
    x0, y0, x1, y1 = (cam[k] for k in ("x_min", "y_min", "x_max", "y_max"))
    touched = (np.ceil(x1) - np.floor(x0)) * (np.ceil(y1) - np.floor(y0))
    np.testing.assert_array_equal(cam["box_pixels"], touched.astype(np.uint32))
    assert (cam["box_pixels"] > np.round((x1 - x0) * (y1 - y0))).all()  # not the area
    doc = inspect.getdoc(mmusv.annotate) or ""
    assert "the recorded box's area, whole pixels" not in doc
    assert "ceil(x_max) − floor(x_min)" in doc
    docs = (Path(__file__).resolve().parents[1] / "docs/recording.md").read_text()
    assert "// pixels of the clipped box" not in docs


def test_recorded_ppi_scale_is_the_drawn_one_for_an_odd_size(recorded: Path) -> None:
    """``AgentInfo.ppi_metres_per_pixel`` (and ``RadarConfig``'s docstring) took the default scale as ``range_m /
    (ppi_size_px / 2)``; the PPI is drawn at ``range_m / (ppi_size_px // 2)`` (``ppi_request``), so for an odd
    size the scale read back from a recording (and the preview's range rings) was off by one part in ``size``."""
    sim = Simulation(_scenario())
    ret = sim.capture(0, sensors=["radar"]).agents["u"].radar
    assert ret is not None
    scale = read_info(recorded).agents[0].ppi_metres_per_pixel
    assert scale is not None
    # One return dead ahead at 290 m, drawn head-up at the default scale: the ego is pixel (16, 16), centre 16.5,
    # and the return lies 290 m / scale above it.
    one = dataclasses.replace(
        ret,
        range=np.array([290.0], np.float32),
        azimuth=np.zeros(1, np.float32),
        elevation=np.zeros(1, np.float32),
        intensity=np.ones(1, np.float32),
        instance_id=np.full(1, -1, np.int32),
        semantic_class=np.ones(1, np.uint16),
    )
    rows, cols = np.nonzero(ppi_image(one, size_px=PPI_SIZE, orientation="head_up") > 0)
    assert set(cols.tolist()) == {PPI_SIZE // 2}
    assert set(rows.tolist()) == {int(np.floor(PPI_SIZE // 2 + 0.5 - 290.0 / scale))}
    assert scale == pytest.approx(300.0 / (PPI_SIZE // 2))


def test_a_mount_point_missing_from_an_asset_without_points_is_half_a_metre_over_the_hull() -> None:
    """``mmusv.sensors.config`` said a sensor on an asset without mount points falls back to "the top of the hull's
    bounding box"; it sits 0.5 m above it, over the vessel origin, turned the way the point's name looks."""
    asset = get_asset("fishing_boat_12m")
    assert not asset.mounts
    top = float(asset.bbox[1, 2])
    for point, yaw in (("lidar", 0.0), ("camera_left", 90.0), ("camera_rear", 180.0), ("camera_right", -90.0)):
        m = mount_matrix(asset, Mount(point=point), where="test")
        np.testing.assert_allclose(m[:3, 3], [0.0, 0.0, top + 0.5], atol=1e-12)
        forward = m[:3, 0]
        assert np.degrees(np.arctan2(forward[1], forward[0])) == pytest.approx(yaw, abs=1e-9)
    doc = inspect.getdoc(mmusv.sensors.config) or ""
    assert "0.5 m above the top of the hull's bounding box" in doc


def test_lidar_box_beams_hold_every_beam_that_meets_a_box_seen_broadside() -> None:
    """``lidar_box_beams`` promises the beams within the box's angular extent, and the LiDAR's wave-occlusion share
    counts "the rays that meet the vessel alone above the still level" (docs/recording.md); the elevation window was
    the corners' elevations only, and a hull seen broadside reaches lower (and higher) between its corners: beams
    meeting a 90 m hull 10 m abeam at its waterline were left out of the share."""
    from mmusv import Scene
    from mmusv.boxes3d import box_corners
    from mmusv.wave_occlusion import lidar_box_beams, pattern_angles

    el = np.deg2rad(np.linspace(-25.0, 15.0, 32))
    az = np.linspace(-np.pi, np.pi, 720, endpoint=False)
    a, e = np.meshgrid(az, el, indexing="ij")
    pattern = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3).astype(np.float32)
    pose = np.eye(4)
    pose[2, 3] = 2.2  # a USV's LiDAR, 2.2 m over the still water
    box = np.eye(4)
    box[:3, 3] = [0.0, 10.0, 4.0]  # 90 m long, 15 m beam, 4 m draft and 12 m above the water, 10 m abeam
    size = np.array([90.0, 15.0, 16.0])
    corners = box_corners(box, size)
    scene = Scene()
    faces = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4), (2, 6, 3), (3, 6, 7)]
    faces += [(0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]
    scene.add_instance(scene.add_mesh(corners, np.array(faces), classes=10), pose=np.eye(4))
    origins = np.tile(pose[:3, 3], (len(pattern), 1))
    meets = np.flatnonzero(scene.cast_rays(origins, pattern).hit)
    beams = lidar_box_beams(pattern_angles(pattern), lidar_pose=pose, corners_world=corners)
    assert len(meets) > 0
    assert np.setdiff1d(meets, beams).size == 0, "beams that meet the box are outside its window"


@pytest.mark.parametrize("camera_range", [20.0, 5000.0])
def test_a_vessel_beyond_the_camera_range_is_not_hidden_by_the_waves(camera_range: float) -> None:
    """``CameraConfig.range_m``: a vessel beyond it is not seen, and the sea beyond it is still drawn; a 2D box's
    ``wave_occlusion`` is the share of the vessel the water hides (docs/recording.md: of the rays that meet it
    alone, the share the full scene stops at the water first). A fishing boat 35 m ahead of a camera of 20 m range
    got a 2D box with ``wave_occlusion`` 0.6 over a physical sea: the water the camera drew in front of it
    (beyond its range) counted as waves hiding it. Beyond the range it is neither seen nor hidden: no 2D box."""
    from mmusv.acquire import annotations_for

    cam = {"name": "f", "resolution": [64, 48], "range_m": camera_range, "mount": {"point": "camera_front"}}
    sc = {
        "name": "beyond",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": 1},
        "environment": {"motion": "physical"},
        "rigs": {"r": {"preset": "lidar_only", "cameras": [cam]}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 0, "route": [[35, 0], [35, 60]]},
        ],
    }
    sim = Simulation(sc)
    ann = annotations_for(sim, sim.capture(0), SilhouetteCache())["u"].columns()
    assert ann["lidar"]["target_id"] == ["t"]  # within the LiDAR's range: a 3D box either way
    cam_rows = ann["camera"]
    if camera_range < 35.0:
        assert cam_rows["target_id"] == []
    else:
        assert cam_rows["target_id"] == ["t"] and int(cam_rows["visible_pixels"][0]) > 0


def test_opv2v_protocol_fov_is_the_rings_when_elevations_are_given(tmp_path: Path) -> None:
    """``LidarConfig.elevations_deg`` replaces the uniform ``vertical_fov_deg`` pattern; the OPV2V export's
    ``data_protocol.yaml`` gave ``upper_fov``/``lower_fov`` from ``vertical_fov_deg`` (its default -25..15) even
    then, not the rings the LiDAR fired."""
    import yaml
    from mmusv.export import convert

    sc = _scenario()
    sc["name"] = "rings"
    rig = sc["rigs"]["r"]
    rig["lidar"] = {"channels": 4, "elevations_deg": [-10.0, 6.0, -3.0, 0.0], "points_per_second": 4 * 360 * 5}
    for key in ("cameras", "top_view", "radar"):
        rig.pop(key)
    rec = run(sc, out_dir=tmp_path / "rec").recording
    convert([rec], out_dir=tmp_path / "opv2v", to="opv2v")
    (protocol_file,) = (tmp_path / "opv2v").rglob("data_protocol.yaml")
    lidar = yaml.safe_load(protocol_file.read_text())["vehicle_base"]["sensing"]["perception"]["lidar"]
    assert (lidar["lower_fov"], lidar["upper_fov"]) == (-10.0, 6.0)
