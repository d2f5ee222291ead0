"""The good-path contract of the public Python API: what comes back has the shape, dtype, unit, frame and order its
docstring states, checked against an independent computation where there is one (a pose said to be body → world
moves a known point there; a distance in metres is compared with the vessels' positions; "sorted" is checked).

Everything runs on one shrunk bundled scenario (two USVs, 64 × 48 cameras, a 16-channel LiDAR, a short radar),
captured once and recorded once for two frames, so the whole file stays fast.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import math
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mmusv import frames as F
from mmusv._native import core
from mmusv.acquire import annotations_for, run
from mmusv.annotate import SilhouetteCache, box_corners, in_target_range
from mmusv.classes import SemanticClass
from mmusv.motion import scenario_poses
from mmusv.recording import decode_image, decode_point_cloud, frame_messages, read_info, read_messages, summary
from mmusv.recording.decode import WorldFrame
from mmusv.recording.frames import OPTICAL_IN_BODY
from mmusv.recording.tables import SCHEMAS, read_table
from mmusv.scene import NO_HIT, Scene, demo_scene
from mmusv.sea_surface import SURFACE_TILE_M, surface_tiles
from mmusv.sensors import RigConfig, ppi_image, sensor_env
from mmusv.sensors.radar import RadarReturns
from mmusv.simulation import FrameCapture, Simulation
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]
W, H = 64, 48
CHANNELS = 16
FRAME = 1


def _scenario(frames: int = 2) -> dict[str, Any]:
    sc: dict[str, Any] = yaml.safe_load((ROOT / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = frames
    sc["vessels"] = [v for v in sc["vessels"] if v["id"] != "usv_3"]
    sc["rigs"] = {
        "usv_standard": {
            "lidar": {"channels": CHANNELS, "points_per_second": CHANNELS * 360 * 5},
            "radar": {"range_m": 1000, "azimuth_bins": 256, "rays_el": 8, "ppi_size_px": 64},
            "cameras": [
                {"name": "front", "resolution": [W, H], "mount": {"point": "camera_front"}},
                {
                    "name": "rear",
                    "resolution": [W, H],
                    "mount": {"point": "camera_rear"},
                    "outputs": ["rgb", "semantic"],
                },
            ],
            "top_view": {"resolution": [64, 64], "metres_per_pixel": 1.0},
        }
    }
    return sc


@pytest.fixture(scope="module")
def sim() -> Simulation:
    return Simulation(_scenario(frames=3))


@pytest.fixture(scope="module")
def cap(sim: Simulation) -> FrameCapture:
    return sim.capture(FRAME)


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    res = run(_scenario(), out_dir=tmp_path_factory.mktemp("contracts"))
    assert res.status == "complete" and res.frames_written == 2
    return res.recording


def _is(a: Any, dtype: Any, shape: tuple[int | None, ...]) -> None:
    """``a`` is a numpy array of exactly ``dtype`` and ``shape`` (``None``: any length on that axis)."""
    assert isinstance(a, np.ndarray), type(a)
    assert a.dtype == np.dtype(dtype), (a.dtype, dtype)
    assert a.ndim == len(shape) and all(s is None or s == n for s, n in zip(shape, a.shape, strict=True)), a.shape


def _index(sim: Simulation, vessel_id: str) -> int:
    return [v.id for v in sim.vessels].index(vessel_id)


# ---------------------------------------------------------------------------------------------- the API's names


PUBLIC = [
    "mmusv",
    "mmusv.sensors",
    "mmusv.recording",
    "mmusv.export",
    "mmusv.generate",
    "mmusv.scene",
    "mmusv.sea_surface",
    "mmusv.simulation",
    "mmusv.annotate",
    "mmusv.motion",
    "mmusv.frames",
    "mmusv.errors",
]


@pytest.mark.parametrize("name", PUBLIC)
def test_every_name_in_all_exists_and_all_is_sorted(name: str) -> None:
    mod = importlib.import_module(name)
    names = list(mod.__all__)
    assert len(set(names)) == len(names)
    for n in names:
        assert hasattr(mod, n), f"{name}.__all__ names {n!r}, which {name} does not have"


def test_options_are_keyword_only() -> None:
    """The project's standard: options (and every argument after the data) are keyword-only."""
    from mmusv.sensors import radar_sweep, render, scan

    expect: dict[Any, list[str]] = {
        surface_tiles: ["radius_m"],
        demo_scene: ["seed", "extent", "terrain_cells", "vessels"],
        Scene.cast_rays: ["max_range"],
        Scene.add_mesh: ["classes", "name", "materials"],
        Scene.add_instance: ["pose", "class_override"],
        Scene.set_wave_surface: ["scenario_seed", "time_s", "foci", "radius_m", "detail", "slopes", "fine_m"],
        Simulation.capture: ["agents", "sensors", "radar"],
        Simulation.set_frame: ["sea_radius_m", "shading_detail"],
        Simulation.renders: ["agents", "sensors"],
        scan: ["pose", "env", "seed", "wakes"],
        render: ["pose", "env", "seed", "wakes", "radiance"],
        radar_sweep: ["pose", "env", "seed"],
        ppi_image: ["size_px", "metres_per_pixel", "orientation", "sensor_yaw"],
        run: ["out_dir", "overwrite", "frames"],
        read_messages: ["damage"],
    }
    for fn, names in expect.items():
        params = inspect.signature(fn).parameters
        for n in names:
            assert params[n].kind is inspect.Parameter.KEYWORD_ONLY, f"{fn.__qualname__}({n}=...) is not keyword-only"


def test_documented_defaults_match_the_models() -> None:
    """The rig defaults ``mmusv.sensors.config`` states (the paper's suite) and the sea radius the scene and the
    core default to."""
    rig = RigConfig()
    assert rig.lidar is not None and rig.radar is not None and rig.top_view is not None
    assert (rig.lidar.channels, rig.lidar.points_per_second, rig.lidar.rotation_hz) == (64, 131_072.0, 5.0)
    assert len(rig.cameras) == 4
    assert all(c.resolution == (640, 480) and c.hfov_deg == 90.0 for c in rig.cameras)
    assert rig.top_view.altitude_m == 120.0
    assert inspect.signature(Scene.cast_rays).parameters["max_range"].default == math.inf
    radius = inspect.signature(Simulation.set_frame).parameters["sea_radius_m"].default
    assert radius == inspect.signature(Scene.set_wave_surface).parameters["radius_m"].default == 320.0


# ---------------------------------------------------------------------------------------------- world state


def test_world_state_is_body_to_world_in_metres_and_seconds(sim: Simulation) -> None:
    ws = sim.world_state(FRAME)
    v = len(sim.vessels)
    _is(ws.poses, np.float64, (v, 6))
    _is(ws.velocities, np.float64, (v, 3))
    _is(ws.box_centers, np.float64, (v, 3))
    _is(ws.matrices, np.float64, (v, 4, 4))
    assert ws.frame == FRAME and ws.time_s == sim.time_of(FRAME) == FRAME / sim.scenario.acquisition.frequency_hz
    # matrices: R = Rz(yaw)·Ry(pitch)·Rx(roll), translation = position; body → world moves the body origin to the pose
    for i in range(v):
        x, y, z, roll, pitch, yaw = ws.poses[i]
        rot = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
        np.testing.assert_allclose(ws.matrices[i, :3, :3], rot, atol=1e-12)
        np.testing.assert_allclose(ws.matrices[i] @ [0, 0, 0, 1], [x, y, z, 1], atol=1e-12)
        # the box centre is the body-frame centre carried to the world
        c = ws.matrices[i] @ np.append(sim.vessels[i].box_center_body, 1.0)
        np.testing.assert_allclose(ws.box_centers[i], c[:3], atol=1e-9)
    # velocities are world m/s: the positions' central difference over the frames around
    a, b = sim.world_state(0), sim.world_state(2)
    fd = (b.poses[:, :3] - a.poses[:, :3]) / (b.time_s - a.time_s)
    assert np.abs(fd[:, :2] - ws.velocities[:, :2]).max() < 0.05
    # scenario vessels first in file order, then the moored ships (static)
    n = len(sim.scenario.vessels)
    assert [vi.id for vi in sim.vessels[:n]] == [vc.id for vc in sim.scenario.vessels]
    assert all(vi.role == "moored" and vi.static for vi in sim.vessels[n:])


def test_scenario_poses_are_the_world_states_poses(sim: Simulation) -> None:
    poses = scenario_poses(sim.scenario)
    n = len(sim.scenario.vessels)
    _is(poses, np.float64, (sim.frames, n, 6))
    for k in range(sim.frames):
        np.testing.assert_allclose(poses[k], sim.world_state(k).poses[:n], rtol=0, atol=1e-9)


def test_wakes_rows_start_with_each_vessel_itself(sim: Simulation) -> None:
    ws = sim.world_state(FRAME)
    wakes = sim.wakes(ws)
    _is(wakes, np.float32, (None, 9))
    assert len(wakes) > 0
    firsts = wakes[wakes[:, 7] == 0.0]  # age 0: the vessel's own piece
    assert (wakes[:, 7] >= 0).all() and (wakes[:, 6] >= 0).all()
    n = len(sim.scenario.vessels)
    for row in firsts:
        i = int(np.argmin(np.hypot(ws.poses[:n, 0] - row[0], ws.poses[:n, 1] - row[1])))
        assert np.hypot(*(ws.poses[i, :2] - row[:2])) < 1e-3
        assert row[2] == pytest.approx(ws.poses[i, 5], abs=1e-5)
        assert row[3] == pytest.approx(math.hypot(*ws.velocities[i, :2]), rel=1e-5)
        np.testing.assert_allclose(row[4:6], sim.vessels[i].box_size[:2], rtol=1e-6)


# ---------------------------------------------------------------------------------------------- sensors


def test_sensor_mounts_compose_to_the_poses(sim: Simulation, cap: FrameCapture) -> None:
    for agent in sim.agents:
        ac = cap.agents[agent.id]
        assert set(ac.sensors) == {"lidar", "radar", "camera/front", "camera/rear", "top_view"}
        _is(ac.body, np.float64, (4, 4))
        np.testing.assert_array_equal(ac.body, cap.world.matrices[agent.index])
        poses = sim.sensor_poses(agent, cap.world)
        for key, sm in ac.sensors.items():
            _is(sm.mount, np.float64, (4, 4))
            _is(sm.pose, np.float64, (4, 4))
            np.testing.assert_allclose(ac.body @ sm.mount, sm.pose, atol=1e-9)
            np.testing.assert_allclose(poses[key], sm.pose, atol=1e-12)
        for key, m in agent.mounts().items():
            np.testing.assert_array_equal(ac.sensors[key].mount, m)
        np.testing.assert_array_equal(ac.lidar_pose, ac.sensors["lidar"].pose)
        np.testing.assert_array_equal(ac.camera_poses["front"], ac.sensors["camera/front"].pose)
        # the level top view looks straight down (its body x axis is world -z), heading up: its body z axis (the
        # image's up) is the vessel's heading, at altitude_m above the vessel
        tv = ac.sensors["top_view"].pose
        yaw = cap.world.poses[agent.index, 5]
        np.testing.assert_allclose(tv[:3, 0], [0, 0, -1], atol=1e-12)
        np.testing.assert_allclose(tv[:3, 2], [math.cos(yaw), math.sin(yaw), 0], atol=1e-12)
        assert agent.rig.top_view is not None
        np.testing.assert_allclose(tv[:3, 3], [*cap.world.poses[agent.index, :2], agent.rig.top_view.altitude_m])


def test_lidar_points_are_in_the_lidar_frame_in_pattern_order(sim: Simulation, cap: FrameCapture) -> None:
    for agent in sim.agents:
        pts = cap.agents[agent.id].lidar
        assert pts is not None
        n = len(pts)
        assert n > 100
        _is(pts.xyz, np.float32, (n, 3))
        for name, dt in (("range", np.float32), ("intensity", np.float32), ("ring", np.uint16)):
            _is(getattr(pts, name), dt, (n,))
        for name, dt in (("azimuth", np.float32), ("semantic_class", np.uint16), ("instance", np.int32)):
            _is(getattr(pts, name), dt, (n,))
        _is(pts.ray_index, np.uint32, (n,))
        # pattern order, azimuth column then ring: ray_index = column · channels + ring, increasing
        assert (np.diff(pts.ray_index.astype(np.int64)) > 0).all()
        np.testing.assert_array_equal(pts.ring, pts.ray_index % CHANNELS)
        pattern = agent.lidar_pattern
        assert pattern is not None
        _is(pattern, np.float32, (agent.lidar.num_rays if agent.lidar else -1, 3))
        assert not pattern.flags.writeable
        np.testing.assert_allclose(np.linalg.norm(pattern, axis=1), 1.0, atol=1e-6)
        unit = pts.xyz / np.linalg.norm(pts.xyz, axis=1, keepdims=True)
        np.testing.assert_allclose(pattern[pts.ray_index], unit, atol=1e-5)
        # the pattern's rings rise with the ring index; its columns turn counter-clockwise from +x
        elevations = np.arcsin(pattern[:CHANNELS, 2])
        assert (np.diff(elevations) > 0).all()
        assert math.atan2(pattern[CHANNELS, 1], pattern[CHANNELS, 0]) > 0
        # range is |xyz| in metres; azimuth counter-clockwise from +x in [0, 2π); intensity in [0, 1]
        np.testing.assert_allclose(np.linalg.norm(pts.xyz, axis=1), pts.range, rtol=1e-5)
        assert (pts.azimuth >= 0).all() and (pts.azimuth < 2 * np.pi).all()
        az = np.mod(np.arctan2(pts.xyz[:, 1], pts.xyz[:, 0]), 2 * np.pi)
        assert np.abs(np.angle(np.exp(1j * (az - pts.azimuth)))).max() < 1e-4
        assert (pts.intensity >= 0).all() and (pts.intensity <= 1).all()
        # the beams: per ray of the full pattern, the instance its cast met first
        beams = cap.agents[agent.id].lidar_beams
        lidar_pose = cap.agents[agent.id].lidar_pose
        assert beams is not None and lidar_pose is not None
        _is(beams, np.int32, (len(pattern),))
        np.testing.assert_array_equal(beams[pts.ray_index], pts.instance)
        # LiDAR frame: carried to the world by the LiDAR pose, a vessel's points lie in its world box
        world = F.transform_points(lidar_pose, pts.xyz)
        for v in sim.vessels:
            mine = pts.instance == v.instance_id
            if mine.any():
                lo, hi = sim.ws.scene.instance_aabb(v.instance_id)
                assert ((world[mine] >= lo - 0.5) & (world[mine] <= hi + 0.5)).all(), v.id


def test_camera_images_depth_is_along_the_optical_axis(sim: Simulation, cap: FrameCapture) -> None:
    agent = sim.agents[0]
    cam = agent.cameras["front"][0]
    img = cap.agents[agent.id].cameras["front"]
    _is(img.depth, np.float32, (H, W))
    _is(img.semantic, np.uint16, (H, W))
    _is(img.instance, np.int32, (H, W))
    assert img.rgb is not None
    _is(img.rgb, np.uint8, (H, W, 3))
    assert img.radiance is None
    assert cam.intrinsics is not None
    np.testing.assert_allclose(cam.intrinsics, core.pinhole_intrinsics(width=W, height=H, hfov=math.pi / 2))
    assert cam.resolution == (W, H)
    pose = cap.agents[agent.id].camera_poses["front"]
    origins, dirs = cam.world_rays(np.ascontiguousarray(pose))
    _is(origins, np.float32, (W * H, 3))
    hits = sim.ws.scene.cast_rays(origins, dirs, max_range=5000.0)
    depth = img.depth.reshape(-1)
    sky = ~np.isfinite(depth)
    assert 0 < sky.sum() < depth.size
    # row-major from the top-left: the first pixel looks left and up of the optical axis (camera body y left, z up)
    first = F.invert(pose)[:3, :3] @ dirs[0]
    assert first[0] > 0 and first[1] > 0 and first[2] > 0
    # depth = distance · (direction · optical axis); instance ids are the hit instances; the sky is inf / 0 / -1
    along = hits.distance * (dirs @ pose[:3, 0])
    np.testing.assert_allclose(depth[~sky], along[~sky], rtol=2e-3, atol=1e-3)
    np.testing.assert_array_equal(img.instance.reshape(-1), hits.instance_id)
    assert (img.semantic.reshape(-1)[sky] == 0).all() and (img.instance.reshape(-1)[sky] == -1).all()
    # the rear camera records rgb and semantic: depth and instance still come (the core always makes them)
    rear = cap.agents[agent.id].cameras["rear"]
    _is(rear.depth, np.float32, (H, W))
    _is(rear.instance, np.int32, (H, W))


def test_radar_returns_sorted_by_cell_in_metres_and_radians(sim: Simulation, cap: FrameCapture) -> None:
    agent = sim.agents[0]
    ret = cap.agents[agent.id].radar
    cfg = agent.rig.radar
    assert ret is not None and cfg is not None
    n = len(ret)
    assert n > 0
    for name, dt in (("range", np.float32), ("azimuth", np.float32), ("elevation", np.float32)):
        _is(getattr(ret, name), dt, (n,))
    _is(ret.intensity, np.float32, (n,))
    _is(ret.instance_id, np.int32, (n,))
    _is(ret.semantic_class, np.uint16, (n,))
    _is(ret.pose, np.float64, (4, 4))
    np.testing.assert_array_equal(ret.pose, cap.agents[agent.id].sensors["radar"].pose)
    # sorted by (azimuth bin, range bin), at most one per cell; range = the bin's centre (no range noise by default)
    az_bin = np.rint(ret.azimuth / (2 * np.pi / cfg.azimuth_bins)).astype(np.int64)
    r_bin = np.floor(ret.range / cfg.range_resolution_m).astype(np.int64)
    np.testing.assert_allclose(ret.range, (r_bin + 0.5) * cfg.range_resolution_m, atol=1e-3)
    key = az_bin * 1_000_000 + r_bin
    assert (np.diff(key) > 0).all()
    assert (ret.azimuth >= 0).all() and (ret.azimuth < 2 * np.pi).all()
    assert (ret.intensity >= cfg.detection_threshold).all()
    assert set(ret.semantic_class[ret.is_clutter].tolist()) <= {int(SemanticClass.WATER), 0}
    assert ret.sensor_yaw == pytest.approx(math.atan2(ret.pose[1, 0], ret.pose[0, 0]))
    # world points of a vessel's returns lie around that vessel (its box, grown by a range bin and a beamwidth)
    world = ret.points(frame="world")
    _is(world, np.float32, (n, 3))
    sensor = ret.points()
    np.testing.assert_allclose(F.transform_points(ret.pose, sensor), world, atol=1e-2)
    checked = 0
    for i, v in enumerate(sim.vessels):
        mine = ret.instance_id == v.instance_id
        if mine.any():
            centre = cap.world.box_centers[i, :2]
            reach = 0.5 * math.hypot(*v.box_size[:2]) + cfg.range_resolution_m
            spread = np.radians(cfg.beamwidth_deg) * ret.range[mine].max()
            assert np.hypot(*(world[mine, :2] - centre).T).max() <= reach + spread, v.id
            checked += 1
    assert checked > 0


def test_ppi_geometry_north_up_and_head_up(sim: Simulation, cap: FrameCapture) -> None:
    agent = sim.agents[0]
    ret = cap.agents[agent.id].radar
    ppi = cap.agents[agent.id].radar_ppi
    assert ret is not None and ppi is not None
    _is(ppi, np.float32, (64, 64))
    np.testing.assert_array_equal(ppi_image(ret, size_px=64), ppi)  # default scale: range over size_px // 2
    assert ppi_image(ret, size_px=64, metres_per_pixel=1000.0 / 32).tolist() == ppi.tolist()
    # one return, turned so that north-up and head-up differ: north-up puts it at its world offset (x right, y up)
    i = int(np.argmax(np.where(ret.instance_id >= 0, ret.intensity, 0)))
    turned = ret.pose @ F.pose_matrices(np.array([0, 0, 0, 0, 0, 0.7]))
    one = dataclasses.replace(
        ret,
        **{k: getattr(ret, k)[i : i + 1] for k in ("range", "azimuth", "elevation", "intensity")},
        instance_id=ret.instance_id[i : i + 1],
        semantic_class=ret.semantic_class[i : i + 1],
        pose=turned,
    )
    assert isinstance(one, RadarReturns)
    size, mpp, c = 256, 4.0, 128
    world = one.points(frame="world")[0] - turned[:3, 3]
    sensor = one.points()[0]
    for orientation, (right, up) in (("north_up", world[:2]), ("head_up", (-sensor[1], sensor[0]))):
        img = ppi_image(one, size_px=size, metres_per_pixel=mpp, orientation=orientation)  # type: ignore[arg-type]
        rows, cols = np.nonzero(img)
        assert abs(rows.mean() - (c - up / mpp)) < 1.5, orientation
        assert abs(cols.mean() - (c + right / mpp)) < 1.5, orientation


def test_sensor_env_values_and_units() -> None:
    env = sensor_env(fog_extinction_per_m=0.001, rain_mm_per_h=2.0, wave_height_m=1.5)
    assert env.fog_extinction_per_m == pytest.approx(0.001)
    assert env.rain_mm_per_h == pytest.approx(2.0)
    assert env.wave_height_m == pytest.approx(1.5)
    sky = env.sky_radiance(np.array([[0, 0, 1]], dtype=np.float32))
    _is(sky, np.float32, (1, 3))
    lux, scale = env.exposure
    assert lux > 0 and scale > 0


# ---------------------------------------------------------------------------------------------- annotations


def test_annotations_are_in_the_lidar_frame(sim: Simulation, cap: FrameCapture) -> None:
    anns = annotations_for(sim, cap, SilhouetteCache())
    for agent in sim.agents:
        ac = cap.agents[agent.id]
        cols = anns[agent.id].columns()
        lid, bev, camera = cols["lidar"], cols["bev"], cols["camera"]
        n = len(lid["target_id"])
        for key, dt, shape in (
            ("instance_id", np.uint32, (n,)),
            ("semantic_class", np.uint32, (n,)),
            ("center", np.float64, (n, 3)),
            ("size", np.float64, (n, 3)),
            ("rotation", np.float64, (n, 4)),
            ("yaw", np.float64, (n,)),
            ("lidar_points", np.uint32, (n,)),
            ("range_m", np.float64, (n,)),
            ("static", np.bool_, (n,)),
            ("wave_occlusion", np.float64, (n,)),
        ):
            _is(lid[key], dt, shape)
        idx = [_index(sim, t) for t in lid["target_id"]]
        assert agent.index not in idx and idx == sorted(idx)  # never the ego; vessels in world-state order
        assert ac.lidar_pose is not None and ac.lidar is not None
        inv = F.invert(ac.lidar_pose)
        centres = F.transform_points(inv, cap.world.box_centers[idx])
        np.testing.assert_allclose(lid["center"], centres, atol=1e-9)
        np.testing.assert_allclose(lid["range_m"], np.linalg.norm(centres, axis=1), atol=1e-9)
        rel = np.einsum("ij,vjk->vik", inv[:3, :3], cap.world.matrices[idx][:, :3, :3])
        np.testing.assert_allclose(Rotation.from_quat(lid["rotation"]).as_matrix().reshape(-1, 3, 3), rel, atol=1e-9)
        np.testing.assert_allclose(lid["yaw"], np.arctan2(rel[:, 1, 0], rel[:, 0, 0]), atol=1e-12)
        np.testing.assert_array_equal(lid["size"], np.array([sim.vessels[i].box_size for i in idx]).reshape(n, 3))
        counts = [int(np.count_nonzero(ac.lidar.instance == sim.vessels[i].instance_id)) for i in idx]
        assert lid["lidar_points"].tolist() == counts
        # every other vessel within the LiDAR's range in bird's-eye view gets a box, and no other
        others = [i for i in range(len(sim.vessels)) if i != agent.index]
        near = in_target_range(F.transform_points(inv, cap.world.box_centers[others]), agent.rig.lidar.range_m)  # type: ignore[union-attr]
        assert idx == [i for i, ok in zip(others, near, strict=True) if ok]
        # BEV: the 3D box's footprint
        np.testing.assert_array_equal(bev["x"], lid["center"][:, 0])
        np.testing.assert_array_equal(bev["y"], lid["center"][:, 1])
        np.testing.assert_array_equal(bev["length"], lid["size"][:, 0])
        np.testing.assert_array_equal(bev["width"], lid["size"][:, 1])
        # 2D boxes: the projected 3D box corners clipped to the image (pixels, origin top-left)
        m = len(camera["target_id"])
        for key in ("x_min", "y_min", "x_max", "y_max", "truncation", "occlusion", "wave_occlusion"):
            _is(camera[key], np.float64, (m,))
        _is(camera["visible_pixels"], np.uint32, (m,))
        _is(camera["box_pixels"], np.uint32, (m,))
        rows = [
            (_index(sim, t), list(agent.cameras).index(c))
            for t, c in zip(camera["target_id"], camera["camera"], strict=True)
        ]
        assert rows == sorted(rows)  # vessel by vessel (world-state order), camera by camera (rig order)
        for j, (target, name) in enumerate(zip(camera["target_id"], camera["camera"], strict=True)):
            vi = _index(sim, target)
            cam = agent.cameras[name][0]
            corners = box_corners(
                cap.world.matrices[vi] @ F.translation(sim.vessels[vi].box_center_body), sim.vessels[vi].box_size
            )
            _is(corners, np.float64, (8, 3))
            opt = F.transform_points(F.invert(ac.camera_poses[name]), corners) @ F.BODY_TO_OPTICAL.T
            box = [camera[k][j] for k in ("x_min", "y_min", "x_max", "y_max")]
            assert 0 <= box[0] < box[2] <= W and 0 <= box[1] < box[3] <= H
            if (opt[:, 2] > 0.05).all():
                assert cam.intrinsics is not None
                fx, fy, cx, cy = cam.intrinsics
                u, v = fx * opt[:, 0] / opt[:, 2] + cx, fy * opt[:, 1] / opt[:, 2] + cy
                want = [max(u.min(), 0), max(v.min(), 0), min(u.max(), W), min(v.max(), H)]
                np.testing.assert_allclose(box, want, atol=1e-6)
            inst = ac.cameras[name].instance
            x0, y0, x1, y1 = int(box[0]), int(box[1]), math.ceil(box[2]), math.ceil(box[3])
            assert camera["visible_pixels"][j] == np.count_nonzero(inst[y0:y1, x0:x1] == sim.vessels[vi].instance_id)
            assert camera["box_pixels"][j] == (x1 - x0) * (y1 - y0)


# ---------------------------------------------------------------------------------------------- scene


def test_scene_rays_hit_where_the_geometry_is() -> None:
    scene = Scene()
    tri = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], dtype=np.float64)
    mesh = scene.add_mesh(tri, np.array([[0, 1, 2]]), classes=10)
    pose = F.pose_matrices(np.array([10.0, 20.0, 1.0, 0.0, 0.0, math.pi / 2]))
    inst = scene.add_instance(mesh, pose=pose)
    np.testing.assert_allclose(scene.instance_pose(inst), pose)
    assert scene.instance_pose(inst).dtype == np.float64
    aabb = scene.instance_aabb(inst)
    _is(aabb, np.float32, (2, 3))
    world = F.transform_points(pose, tri)  # body → world: the instance's vertices
    np.testing.assert_allclose(aabb, [world.min(axis=0), world.max(axis=0)], atol=1e-5)
    # a ray down onto the triangle's world position (front face: winding normal +z), one that misses
    origins = np.array([[9.0, 21.0, 11.0], [0.0, 0.0, 11.0]])
    dirs = np.array([[0.0, 0.0, -3.0], [0.0, 0.0, -1.0]])  # any length: distances along the unit direction
    hits = scene.cast_rays(origins, dirs)
    _is(hits.distance, np.float32, (2,))
    _is(hits.instance_id, np.int32, (2,))
    _is(hits.triangle_id, np.int32, (2,))
    _is(hits.normal, np.float32, (2, 3))
    _is(hits.semantic_class, np.uint16, (2,))
    _is(hits.backface, np.bool_, (2,))
    assert hits.distance[0] == pytest.approx(10.0) and hits.distance[1] == np.inf
    assert hits.instance_id.tolist() == [inst, NO_HIT] and hits.triangle_id.tolist() == [0, NO_HIT]
    assert hits.semantic_class.tolist() == [10, 0] and hits.hit.tolist() == [True, False]
    np.testing.assert_allclose(hits.normal, [[0, 0, 1], [0, 0, 0]], atol=1e-6)
    assert hits.backface.tolist() == [False, False]
    up = scene.cast_rays(np.array([[9.0, 21.0, -4.0]]), np.array([[0.0, 0.0, 1.0]]))
    assert up.backface.tolist() == [True]
    pts = hits.points(origins, dirs)
    _is(pts, np.float32, (2, 3))
    np.testing.assert_allclose(pts[0], [9.0, 21.0, 1.0], atol=1e-5)
    assert np.isnan(pts[1]).all()
    assert not scene.cast_rays(origins[:1], dirs[:1], max_range=5.0).hit[0]
    wm = scene.world_mesh()
    _is(wm["vertices"], np.float32, (3, 3))
    _is(wm["faces"], np.uint32, (1, 3))
    _is(wm["classes"], np.uint16, (1,))
    _is(wm["instance_ids"], np.uint32, (1,))
    _is(wm["triangle_ids"], np.uint32, (1,))
    np.testing.assert_allclose(wm["vertices"][wm["faces"][0]], world, atol=1e-5)
    heights = scene.wave_heights(np.zeros((3, 2)))
    _is(heights, np.float32, (3,))
    assert scene.wave_top is None and scene.sea_instance is None


def test_demo_scene_and_surface_tiles() -> None:
    scene, vessels = demo_scene(seed=3, extent=200.0, terrain_cells=8, vessels=3)
    assert isinstance(scene, Scene) and isinstance(vessels, list) and all(type(i) is int for i in vessels)
    assert len(vessels) == 3 and scene.num_instances == 5 and vessels == [2, 3, 4]
    # instance 0 the terrain (2·cells² triangles), instance 1 the water plane at z = 0
    wm = scene.world_mesh()
    assert np.count_nonzero(wm["instance_ids"] == 0) == 2 * 8 * 8
    water = wm["vertices"][wm["faces"][wm["instance_ids"] == 1].reshape(-1)]
    np.testing.assert_allclose(water[:, 2], 0.0, atol=1e-6)
    # the tiles of the 32 m grid (aligned on multiples of SURFACE_TILE_M) that cover the foci's rectangle grown by
    # radius_m
    for foci, radius in ((np.zeros((1, 2)), 320.0), (np.array([[0.0, 0.0], [320.0, 0.0]]), 100.0)):
        lo, hi = foci.min(axis=0) - radius, foci.max(axis=0) + radius
        want = int(np.prod(np.ceil(hi / SURFACE_TILE_M) - np.floor(lo / SURFACE_TILE_M)))
        tiles = surface_tiles(foci, radius_m=radius)
        assert type(tiles) is int and tiles == want
    assert surface_tiles(np.zeros((0, 2)), radius_m=320.0) == 0


# ---------------------------------------------------------------------------------------------- frames


def test_frames_conventions() -> None:
    rng = np.random.default_rng(0)
    eta = rng.uniform(-1, 1, (5, 6)) * [100, 100, 2, 0.4, 0.4, 3]
    m = F.pose_matrices(eta)
    _is(m, np.float64, (5, 4, 4))
    rot = Rotation.from_euler("ZYX", eta[:, [5, 4, 3]]).as_matrix()
    np.testing.assert_allclose(m[:, :3, :3], rot, atol=1e-12)
    np.testing.assert_allclose(F.matrix_to_pose(m), eta, atol=1e-12)
    np.testing.assert_allclose(F.invert(m) @ m, np.broadcast_to(np.eye(4), (5, 4, 4)), atol=1e-12)
    p = rng.normal(size=(7, 3))
    np.testing.assert_allclose(F.transform_points(m[0], p), (m[0] @ np.c_[p, np.ones(7)].T).T[:, :3])
    np.testing.assert_array_equal(F.translation([1, 2, 3])[:3, 3], [1, 2, 3])
    # camera body (x forward, y left, z up) → optical (x right, y down, z forward)
    np.testing.assert_array_equal(F.BODY_TO_OPTICAL @ [1, 0, 0], [0, 0, 1])
    np.testing.assert_array_equal(F.BODY_TO_OPTICAL @ [0, 1, 0], [-1, 0, 0])
    np.testing.assert_array_equal(F.BODY_TO_OPTICAL @ [0, 0, 1], [0, -1, 0])
    # CARLA: [x, -y, z, deg(roll), -deg(yaw), -deg(pitch)], carla_matrix(carla_pose(m)) = S·m·S
    carla = F.carla_pose(m)
    _is(carla, np.float64, (5, 6))
    np.testing.assert_allclose(carla, F.carla_pose_from_eta(eta), atol=1e-9)
    np.testing.assert_allclose(carla[:, :3], eta[:, :3] * [1, -1, 1])
    np.testing.assert_allclose(F.carla_matrix(carla), F.mirror_transform(m), atol=1e-12)
    np.testing.assert_allclose(F.mirror_points(p), p * [1, -1, 1])
    np.testing.assert_allclose(
        F.x1_to_x2(carla[0], carla[1]), F.invert(F.carla_matrix(carla[1])) @ F.carla_matrix(carla[0])
    )
    # wrapping to (-180, 180] and (-π, π]
    deg = F.wrap_deg(np.array([-540.0, -180.0, 180.0, 190.0, 720.0]))
    np.testing.assert_allclose(deg, [180.0, 180.0, 180.0, -170.0, 0.0])
    rad = F.wrap_rad(np.array([-math.pi, math.pi, 3 * math.pi / 2]))
    np.testing.assert_allclose(rad, [math.pi, math.pi, -math.pi / 2])


# ---------------------------------------------------------------------------------------------- the core's stub


def _stub_returns() -> dict[str, dict[str, str]]:
    """Per class of ``_core.pyi`` (``""``: module functions), the return annotation of each property and function."""
    tree = ast.parse((Path(mmusv.__file__).parent / "_core.pyi").read_text())
    out: dict[str, dict[str, str]] = {"": {}}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.returns is not None:
            out[""][node.name] = ast.unparse(node.returns)
        elif isinstance(node, ast.ClassDef):
            out[node.name] = {
                f.name: ast.unparse(f.returns)
                for f in node.body
                if isinstance(f, ast.FunctionDef) and f.returns is not None
            }
    return out


def _matches(value: Any, annotation: str) -> bool:
    """Whether ``value``'s container type is the one ``annotation`` names (``tuple[...]``, ``list[...]``, ``dict``,
    ``float``, ``int``, ``bool``, ``str``, numpy arrays), allowing ``| None``."""
    options = [a.strip() for a in annotation.split(" | ")] if "[" not in annotation.split(" | ")[-1] else [annotation]
    if value is None:
        return "None" in options
    for a in options:
        head = a.split("[", 1)[0]
        kind = {"tuple": tuple, "list": list, "dict": dict, "float": float, "int": int, "bool": bool, "str": str}.get(
            head
        )
        if kind is not None and type(value) is kind:
            return True
        if head == "npt.NDArray" and isinstance(value, np.ndarray):
            return True
    return False


def test_core_stub_return_types_match_the_extension() -> None:
    """The containers the stub promises (a tuple is not a list) for every argument-free property and function."""
    stub = _stub_returns()
    pinhole = core.Camera(width=8, height=6, rgb=True, hfov=1.0, distortion=[0.1, 0.0, 0.0, 0.0, 0.0])
    ortho = core.Camera(width=8, height=6, rgb=False, metres_per_pixel=1.0)
    env = sensor_env()
    wave = core.WaveField(hs_m=2.0, tp_s=8.0, gamma=3.3, direction_rad=0.3, spread_s=10.0, seed=1)
    objects: dict[str, list[Any]] = {"Camera": [pinhole, ortho], "SensorEnv": [env], "WaveField": [wave]}
    checked = 0
    for cls, objs in objects.items():
        for obj in objs:
            for name, annotation in stub[cls].items():
                if name.startswith("_"):
                    continue
                value = getattr(obj, name)
                if callable(value):  # a method: only those without arguments
                    try:
                        value = value()
                    except TypeError:
                        continue
                assert _matches(value, annotation), (
                    f"{cls}.{name} returns {type(value).__name__}, stub says {annotation}"
                )
                checked += 1
    for name in ("default_amplitudes", "wave_presets", "sea_presets", "sea_limits", "exposure_limits"):
        value = getattr(core, name)()
        assert _matches(value, stub[""][name]), f"{name} returns {type(value).__name__}, stub says {stub[''][name]}"
        checked += 1
    assert _matches(core.fully_developed(2.0), stub[""]["fully_developed"])
    assert _matches(core.pinhole_intrinsics(width=8, height=6, hfov=1.0), stub[""]["pinhole_intrinsics"])
    assert checked > 15


def test_core_arrays_have_the_stub_dtypes_and_shapes(sim: Simulation) -> None:
    fleet = sim.fleet
    v = len(fleet)
    _is(fleet.poses_at(0.3), np.float64, (v, 6))
    _is(fleet.velocities_at(0.3), np.float64, (v, 3))
    _is(fleet.poses_at_times(np.array([0.0, 0.2, 0.4])), np.float64, (3, v, 6))
    _is(fleet.route_lengths(), np.float64, (v,))
    _is(fleet.alphas(), np.float64, (v,))
    _is(fleet.wake_pieces(5.0, np.ones(v)), np.float64, (None, 6))
    wave = core.WaveField(hs_m=2.0, tp_s=8.0, gamma=3.3, direction_rad=0.3, spread_s=10.0, seed=1)
    x = np.array([0.0, 1.0, 2.0])
    _is(wave.components(), np.float64, (None, 5))
    _is(wave.elevation(x, x, 1.0), np.float64, (3,))
    _is(wave.slope(x, x, 1.0), np.float64, (3, 2))
    _is(wave.orbital_velocity(np.zeros((3, 3)), 1.0), np.float64, (3, 3))
    grid = wave.elevation_grid(x0=10.0, y0=-5.0, dx=2.0, nx=4, ny=3, t=1.0)
    _is(grid, np.float32, (3, 4))  # [j, i] at (x0 + i·dx, y0 + j·dx)
    assert grid[2, 1] == pytest.approx(float(wave.elevation(np.array([12.0]), np.array([-1.0]), 1.0)[0]), abs=1e-5)
    hull = [5.0, 2.0, 0.5, 0.5, 1.0]
    _is(
        wave.hull_response(
            hull=hull, positions=np.zeros((4, 2)), yaw=np.zeros(4), velocities=np.zeros((4, 2)), times=np.arange(4.0)
        ),
        np.float64,
        (4, 3),
    )
    rao = core.hull_rao(hull=hull, omega=np.array([0.5, 1.0]), beta=np.zeros(2), omega_e=np.array([0.5, 1.0]))
    _is(rao, np.complex128, (2, 3))
    _is(core.uniform_elevations(channels=4, lower=-0.2, upper=0.2), np.float64, (4,))
    assert (np.diff(core.uniform_elevations(channels=4, lower=-0.2, upper=0.2)) > 0).all()  # lowest first
    order = core.lidar_trace_order(channels=4, azimuth_steps=8)
    _is(order, np.uint32, (32,))
    assert sorted(order.tolist()) == list(range(32))
    _is(sim.ws.scene.native.instance_meshes(), np.uint32, (sim.ws.scene.num_instances,))


# ---------------------------------------------------------------------------------------------- recordings


def test_recording_readers(sim: Simulation, cap: FrameCapture, recording: Path) -> None:
    info = read_info(recording)
    assert info.scenario_name == "port_entry" and info.frames_configured == 2 and info.frequency_hz == 5.0
    assert [a.id for a in info.agents] == [a.id for a in sim.agents]
    for rec_agent, agent in zip(info.agents, sim.agents, strict=True):
        assert rec_agent.index == agent.index
        np.testing.assert_allclose(rec_agent.lidar_mount, agent.lidar_mount, atol=1e-9)  # type: ignore[arg-type]
        for name, c in rec_agent.cameras.items():
            _is(c.mount, np.float64, (4, 4))
            np.testing.assert_allclose(c.mount, agent.cameras[name][2], atol=1e-9)
            assert isinstance(c.intrinsics, tuple) and c.intrinsics == pytest.approx(agent.cameras[name][0].intrinsics)
        assert rec_agent.ppi_metres_per_pixel == pytest.approx(1000.0 / 32)
    s = summary(recording)
    assert set(s) == {"path", "complete", "messages", "start_ns", "end_ns", "duration_s", "topics", "metadata"} | {
        "attachments",
        "damage",
        "frames",
    }
    # "first": the acquisition index the expected frames start from (a part of a split run), since 8f9453e
    assert set(s["frames"]) == {"read", "expected", "first", "missing", "incomplete", "report"}
    assert s["complete"] and s["frames"]["read"] == 2 and s["frames"]["first"] == 0
    assert s["start_ns"] == 0 and s["end_ns"] == 200_000_000
    assert list(s["topics"]) == sorted(s["topics"])
    msgs = list(read_messages(recording))
    assert len(msgs) == s["messages"]
    times = [t for _, t, _ in msgs]
    assert times == sorted(times)  # file order is log-time order
    only = list(read_messages(recording, topics=["/world/state"]))
    assert [t for t, _, _ in only] == ["/world/state"] * 2
    by_topic = frame_messages(recording, FRAME)
    assert set(by_topic) == set(s["topics"])
    # the recorded frame is the capture: world state, LiDAR cloud (LiDAR frame), images
    world = WorldFrame.from_message(by_topic["/world/state"])
    assert world.frame == FRAME and world.ids == [v.id for v in sim.vessels]
    np.testing.assert_allclose(world.poses, cap.world.poses)
    body, lidar_pose, cam_poses = info.agents[0].sensor_poses(world)
    agent = sim.agents[0]
    ac = cap.agents[agent.id]
    assert ac.body is not None
    np.testing.assert_allclose(body, ac.body, atol=1e-9)
    np.testing.assert_allclose(lidar_pose, ac.lidar_pose, atol=1e-7)  # type: ignore[arg-type]
    np.testing.assert_allclose(cam_poses["front"], ac.camera_poses["front"], atol=1e-7)
    cloud = decode_point_cloud(by_topic[f"/{agent.id}/lidar"])
    assert {k: v.dtype.name for k, v in cloud.items()} == {
        "x": "float32",
        "y": "float32",
        "z": "float32",
        "intensity": "float32",
        "ring": "uint16",
        "azimuth": "float32",
        "class": "uint16",
        "instance": "int32",
    }
    assert ac.lidar is not None
    np.testing.assert_array_equal(np.c_[cloud["x"], cloud["y"], cloud["z"]], ac.lidar.xyz)
    depth = decode_image(by_topic[f"/{agent.id}/camera/front/depth"])
    _is(depth, np.float32, (H, W))
    np.testing.assert_array_equal(depth, ac.cameras["front"].depth)
    inst = decode_image(by_topic[f"/{agent.id}/camera/front/instance"])
    _is(inst, np.uint16, (H, W))
    np.testing.assert_array_equal(inst, np.where(ac.cameras["front"].instance < 0, 65535, ac.cameras["front"].instance))
    _is(decode_image(by_topic[f"/{agent.id}/camera/front/rgb"]), np.uint8, (H, W, 3))
    _is(decode_image(by_topic[f"/{agent.id}/camera/rear/semantic"]), np.uint16, (H, W))
    # /tf: agent → camera is the camera's optical frame (its z axis is the camera body's x, forward)
    tf = {(t.parent_frame_id, t.child_frame_id): t for t in by_topic["/tf"].transforms}
    t = tf[(agent.id, f"{agent.id}/camera/front")]
    q = [t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
    mount = agent.cameras["front"][2]
    np.testing.assert_allclose(Rotation.from_quat(q).as_matrix(), mount[:3, :3] @ OPTICAL_IN_BODY[:3, :3], atol=1e-9)
    np.testing.assert_allclose(Rotation.from_quat(q).apply([0, 0, 1]), mount[:3, 0], atol=1e-9)
    np.testing.assert_allclose([t.translation.x, t.translation.y, t.translation.z], mount[:3, 3], atol=1e-9)


def test_tables_have_the_schemas_columns(sim: Simulation, recording: Path) -> None:
    tables = recording.parent / "tables"
    for name, schema in SCHEMAS.items():
        read = read_table(tables, name, expected=range(2))
        assert read.damaged == [] and read.missing == []
        assert list(read.rows.columns) == list(schema)
        assert dict(read.rows.schema) == schema
        assert read.rows["frame"].to_list() == sorted(read.rows["frame"].to_list())
    ws = read_table(tables, "world_state").rows.filter(frame=FRAME)
    state = sim.world_state(FRAME)
    np.testing.assert_allclose(ws.select("x", "y", "z", "roll", "pitch", "yaw").to_numpy(), state.poses)
    np.testing.assert_allclose(ws.select("vx", "vy", "vz").to_numpy(), state.velocities)
    np.testing.assert_allclose(ws.select("box_cx", "box_cy", "box_cz").to_numpy(), state.box_centers)


# ---------------------------------------------------------------------------------------------- selection, world


def test_capture_selection_runs_only_what_was_asked(sim: Simulation) -> None:
    first = sim.agents[0].id
    cap = sim.capture(0, agents=[first], sensors=["lidar", "radar"], radar=False)
    assert list(cap.agents) == [first]
    ac = cap.agents[first]
    assert ac.lidar is not None and ac.radar is None and ac.cameras == {} and ac.top_view is None
    assert cap.frame == 0 and cap.time_s == 0.0
    assert set(ac.sensors) == {"lidar", "radar", "camera/front", "camera/rear", "top_view"}  # poses of every sensor
    assert sim.renders(sensors=["lidar"]) is False and sim.renders(agents=[first], sensors=["top_view"]) is True


def test_world_helpers_units_and_frames() -> None:
    from mmusv.world.environment import sun_at
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.sea_state import sea_spec_for_height, sea_spec_for_preset
    from mmusv.world.vessels import asset_names, get_asset

    # the sun's direction points towards it (world x east, y north); azimuth clockwise from north
    for time, east in (("08:00", True), ("16:00", False)):
        sun = sun_at(time)
        assert (sun.direction[0] > 0) is east and sun.direction[2] > 0
        assert math.hypot(*sun.direction) == pytest.approx(1.0)
        az = math.radians(sun.azimuth_deg)
        el = math.radians(sun.elevation_deg)
        assert sun.direction == pytest.approx((math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)))
    assert sun_at("12:00").direction[1] < 0  # due south at noon in the northern hemisphere
    # a preset's sea is the core's; directions in degrees counter-clockwise from east become radians
    spec = sea_spec_for_preset("W2", direction_deg=90.0)
    hs = {p[0]: p[2] for p in core.sea_presets()}["W2"]
    assert spec.hs_m == hs and spec.direction_rad == pytest.approx(math.pi / 2)
    assert sea_spec_for_height(2.0).tp_s == pytest.approx(core.fully_developed(2.0)[0])
    asset = get_asset("usv_wamv")
    length, beam, draft, cb, gm = hull_particulars(asset)
    assert (length, beam) == (asset.length, asset.beam) and 0 < draft < asset.height and 0 < cb <= 1 and gm > 0
    assert asset_names() == sorted(asset_names())
