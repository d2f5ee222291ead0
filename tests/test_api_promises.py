"""An independent re-check of what the public Python API's docstrings promise (shape, dtype, unit, frame, order,
range), each against a computation of its own rather than the code re-run: a LiDAR point carried to the world by the
stated pose lies on the surface of the vessel it names (cast against that vessel's mesh alone); a depth pixel equals the
LiDAR's range of the same surface along the optical axis; a heading equals the direction the vessel moves along its
route; a top view's "bow up" is read off its rays and its pixels; a wave field's direction is the way its crests move.

One small scene built from the bundled ``open_sea_convoy`` scenario, its routes replaced so that nothing lines up with
the axes: ``usv_1`` heads 30° (north of east) with a fishing boat 45 m ahead crossing at 120°, ``usv_2`` sits to its
port side heading -135° with a north-up top view. Captured once (frame 1) and recorded once (one frame).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv import Scene, Simulation, run
from mmusv import frames as F
from mmusv._native import core
from mmusv.annotate import Annotations, SilhouetteCache, annotate_agent, box_corners, in_target_range
from mmusv.classes import SemanticClass
from mmusv.recording import decode_image, decode_point_cloud, frame_messages
from mmusv.recording.decode import WorldFrame
from mmusv.recording.stream import frame_ranges
from mmusv.recording.tables import read_table
from mmusv.sensors.config import LidarConfig
from mmusv.sensors.env import sensor_env, wind_from_wave_height
from mmusv.sensors.mounts import rpy_matrix
from mmusv.sensors.radar import ppi_colormap
from mmusv.simulation import FrameCapture, sensor_seed
from mmusv.world.sea_state import sea_spec_for_height, sea_spec_for_preset
from mmusv.world.vessels import get_asset
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]
G = 9.80665
FRAME = 1
HEADING_1 = math.radians(30.0)  # usv_1's route direction
CROSSING = 2.1  # the target's route direction, radians
HEADING_2 = math.radians(-135.0)  # usv_2's route direction
CHANNELS = 32
FOV = (-25.0, 15.0)  # the LiDAR's default vertical field of view, degrees
NOISE = 0.02  # the LiDAR's default range noise, metres (one sigma)
TOP_MPP = 0.25


def _scenario(frames: int = 3) -> dict[str, Any]:
    sc: dict[str, Any] = yaml.safe_load((ROOT / "scenarios/open_sea_convoy.yaml").read_text())
    sc["acquisition"]["frames"] = frames
    c, s = math.cos(HEADING_1), math.sin(HEADING_1)
    ahead = (45.0 * c, 45.0 * s)
    sc["vessels"] = [
        {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "heading", "speed_mps": 2.0,
         "route": [[0.0, 0.0], [400.0 * c, 400.0 * s]]},
        {"id": "target", "role": "target", "asset": "fishing_boat_12m", "speed_mps": 1.0,
         "route": [list(ahead), [ahead[0] + 200 * math.cos(CROSSING), ahead[1] + 200 * math.sin(CROSSING)]]},
        {"id": "usv_2", "role": "usv", "asset": "usv_patrol_12m", "rig": "north", "speed_mps": 1.5,
         "route": [[-40.0, 60.0], [-40.0 + 300 * math.cos(HEADING_2), 60.0 + 300 * math.sin(HEADING_2)]]},
    ]  # fmt: skip
    lidar = {"channels": CHANNELS, "points_per_second": CHANNELS * 720 * 5}
    radar = {"range_m": 1000, "azimuth_bins": 256, "rays_el": 8, "ppi_size_px": 64}
    top = {"resolution": [96, 96], "metres_per_pixel": TOP_MPP}
    cameras = [
        {"name": "front", "resolution": [160, 120], "mount": {"point": "camera_front"}},
        {"name": "left", "resolution": [80, 60], "mount": {"point": "camera_left"}, "outputs": ["depth", "instance"]},
    ]
    sc["rigs"] = {
        "heading": {"lidar": lidar, "radar": radar, "cameras": cameras, "top_view": top},
        "north": {"lidar": lidar, "radar": radar, "cameras": [], "top_view": {**top, "orientation": "north_up"}},
    }
    return sc


@pytest.fixture(scope="module")
def sim() -> Simulation:
    return Simulation(_scenario())


@pytest.fixture(scope="module")
def cap(sim: Simulation) -> FrameCapture:
    return sim.capture(FRAME)


@pytest.fixture(scope="module")
def ann(sim: Simulation, cap: FrameCapture) -> Annotations:
    agent = sim.agents[0]
    ac = cap.agents[agent.id]
    assert ac.lidar is not None and agent.rig.lidar is not None
    cams = {n: (agent.cameras[n][0], ac.camera_poses[n], img.instance) for n, img in ac.cameras.items()}
    return annotate_agent(
        agent_id=agent.id,
        agent_index=agent.index,
        frame=cap.frame,
        time_s=cap.time_s,
        vessels=sim.vessels,
        state=cap.world,
        lidar_pose=ac.lidar_pose,
        lidar_instances=ac.lidar.instance,
        cameras=cams,
        silhouettes=SilhouetteCache(),
        max_range_m=agent.rig.lidar.range_m,
        scene=sim.ws.scene,
        lidar_pattern=agent.lidar_pattern,
        lidar_beams=ac.lidar_beams,
    )


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    res = run(_scenario(frames=1), out_dir=tmp_path_factory.mktemp("promises"))
    assert res.status == "complete" and res.frames_written == 1
    return res.recording


def _index(sim: Simulation, vessel_id: str) -> int:
    return [v.id for v in sim.vessels].index(vessel_id)


def _angle(a: float, b: float) -> float:
    """|a - b| wrapped to [0, π]."""
    return abs(math.remainder(a - b, 2 * math.pi))


def _axis_angle(rows: np.ndarray, cols: np.ndarray) -> float:
    """The direction (radians, modulo π, counter-clockwise from image right with image up positive) of the long
    axis of a set of pixels."""
    pts = np.c_[cols - cols.mean(), -(rows - rows.mean())].astype(np.float64)
    w, v = np.linalg.eigh(pts.T @ pts)
    major = v[:, int(np.argmax(w))]
    return math.atan2(major[1], major[0]) % math.pi


# ---------------------------------------------------------------------------------------------- motion


def test_yaw_is_the_heading_along_the_route_in_radians(sim: Simulation) -> None:
    """``WorldState.poses`` yaw (radians, counter-clockwise from world +x = east) is the direction the route goes;
    ``velocities`` are world m/s at the configured speed; positions advance by speed · (t_k = k / f) metres."""
    want = {"usv_1": HEADING_1, "target": CROSSING, "usv_2": HEADING_2}
    speeds = {v.id: v.speed_mps for v in sim.scenario.vessels}
    first, last = sim.world_state(0), sim.world_state(2)
    assert last.time_s - first.time_s == pytest.approx(2 / sim.scenario.acquisition.frequency_hz)
    for vid, heading in want.items():
        i = _index(sim, vid)
        for state in (first, last):
            assert _angle(state.poses[i, 5], heading) < 1e-6, vid
            vx, vy = state.velocities[i, :2]
            assert math.hypot(vx, vy) == pytest.approx(speeds[vid], rel=1e-6)
            assert _angle(math.atan2(vy, vx), heading) < 1e-6, vid
        step = last.poses[i, :2] - first.poses[i, :2]
        np.testing.assert_allclose(
            step,
            speeds[vid] * (last.time_s - first.time_s) * np.array([math.cos(heading), math.sin(heading)]),
            atol=1e-6,
        )
    # the fleet: its vessels are the scenario's, it moves in the W2 sea; route lengths are metres along the routes
    assert len(sim.fleet) == 3 and sim.fleet.physical and sim.fleet.wave_height_m == core.wave_height("W2")
    routes = [np.asarray(v.route, dtype=np.float64) for v in sim.scenario.vessels]
    np.testing.assert_allclose(sim.fleet.route_lengths(), [np.hypot(*(r[1] - r[0])) for r in routes], rtol=1e-9)


# ---------------------------------------------------------------------------------------------- LiDAR


def test_lidar_points_lie_on_the_surface_of_what_they_hit(sim: Simulation, cap: FrameCapture) -> None:
    """``LidarPoints.xyz`` are metres in the LiDAR frame (``lidar_pose`` LiDAR → world): carried to the world, each
    vessel point lies on that vessel's own mesh along its ray (within the range noise) and inside its body box; its
    class is the vessel's; water points lie on the sea surface (``Scene.wave_heights``)."""
    ac = cap.agents["usv_1"]
    pts, pose = ac.lidar, ac.lidar_pose
    assert pts is not None and pose is not None
    world = F.transform_points(pose, pts.xyz)
    origin = pose[:3, 3]
    checked = 0
    for i, v in enumerate(sim.vessels):
        mine = pts.instance == v.instance_id
        if i == 0 or not mine.any():
            continue
        asset = get_asset(v.asset)
        alone = Scene()
        alone.add_instance(alone.add_mesh(asset.mesh.vertices, asset.mesh.faces), pose=cap.world.matrices[i])
        d = world[mine] - origin
        hits = alone.cast_rays(np.tile(origin, (len(d), 1)), d)
        assert hits.hit.all(), v.id
        np.testing.assert_allclose(hits.distance, np.linalg.norm(d, axis=1), atol=5 * NOISE)
        np.testing.assert_allclose(hits.distance, pts.range[mine], atol=5 * NOISE)
        body = F.transform_points(F.invert(cap.world.matrices[i]), world[mine])
        assert (body >= asset.bbox[0] - 5 * NOISE).all() and (body <= asset.bbox[1] + 5 * NOISE).all(), v.id
        assert set(pts.semantic_class[mine].tolist()) == {v.semantic_class}
        checked += 1
    assert checked == 2  # the target ahead and usv_2 to port
    assert sim.vessels[_index(sim, "usv_2")].semantic_class == SemanticClass.USV
    assert sim.vessels[_index(sim, "target")].semantic_class == SemanticClass.VESSEL
    water = pts.semantic_class == SemanticClass.WATER
    assert water.sum() > 100
    sea = sim.ws.scene.wave_heights(world[water, :2].astype(np.float32))
    assert np.abs(world[water, 2] - sea).max() < 5 * NOISE


def test_lidar_rings_are_the_configured_elevations(sim: Simulation, cap: FrameCapture) -> None:
    """Ring ``i`` is the ``i``-th elevation, lowest first, spread uniformly over ``vertical_fov_deg`` (degrees in
    the config, radians out of ``elevations_rad``); columns = ``points_per_second / (rotation_hz · channels)``."""
    agent = sim.agents[0]
    cfg = agent.rig.lidar
    assert cfg is not None and agent.lidar is not None
    want = np.radians(np.linspace(*FOV, CHANNELS))
    np.testing.assert_allclose(cfg.elevations_rad(), want, atol=1e-12)
    np.testing.assert_allclose(core.uniform_elevations(channels=CHANNELS, lower=want[0], upper=want[-1]), want)
    assert agent.lidar.num_rays == CHANNELS * 720
    pts = cap.agents[agent.id].lidar
    assert pts is not None
    elevation = np.arcsin(pts.xyz[:, 2] / np.linalg.norm(pts.xyz, axis=1))
    np.testing.assert_allclose(elevation, want[pts.ring], atol=1e-5)
    assert LidarConfig(channels=1).elevations_rad() == pytest.approx([math.radians(sum(FOV) / 2)])


# ---------------------------------------------------------------------------------------------- cameras


def test_depth_is_metres_along_the_optical_axis_like_the_lidar(sim: Simulation, cap: FrameCapture) -> None:
    """The target's LiDAR points, projected into the front camera with its intrinsics (pixel centres at +0.5), land
    on pixels of the target whose depth is the points' z in the optical frame: metres along the optical axis."""
    agent = sim.agents[0]
    ac = cap.agents[agent.id]
    cam = agent.cameras["front"][0]
    img = ac.cameras["front"]
    pts = ac.lidar
    assert pts is not None and ac.lidar_pose is not None and cam.intrinsics is not None
    target = sim.vessels[_index(sim, "target")].instance_id
    world = F.transform_points(ac.lidar_pose, pts.xyz[pts.instance == target])
    opt = F.transform_points(F.invert(ac.camera_poses["front"]), world) @ F.BODY_TO_OPTICAL.T
    fx, fy, cx, cy = cam.intrinsics
    u, v = fx * opt[:, 0] / opt[:, 2] + cx, fy * opt[:, 1] / opt[:, 2] + cy
    h, w = img.depth.shape
    inside = (opt[:, 2] > 0) & (u >= 0) & (u < w) & (v >= 0) & (v < h)
    ui, vi = np.floor(u[inside]).astype(int), np.floor(v[inside]).astype(int)
    same = img.instance[vi, ui] == target
    assert same.sum() >= 20
    diff = img.depth[vi, ui][same] - opt[inside, 2][same]
    assert np.median(np.abs(diff)) < 0.05 and np.mean(np.abs(diff) < 0.2) > 0.8
    assert 30.0 < np.median(opt[inside, 2]) < 60.0  # the target is some 45 m ahead


def test_pinhole_pixels_intrinsics_and_rays() -> None:
    """``pinhole_intrinsics``: fx = fy = (W / 2) / tan(hfov / 2), (cx, cy) the image centre; ``world_rays`` are
    row-major from the top-left through the pixel centres (+0.5), unit, from the camera origin; ``pixel_rays`` are
    their rows."""
    w, h, hfov = 40, 30, math.radians(70.0)
    fx = (w / 2) / math.tan(hfov / 2)
    np.testing.assert_allclose(core.pinhole_intrinsics(width=w, height=h, hfov=hfov), [fx, fx, w / 2, h / 2])
    cam = core.Camera(width=w, height=h, rgb=False, hfov=hfov)
    pose = F.pose_matrices(np.array([5.0, -3.0, 2.0, 0.1, -0.2, 0.7]))
    origins, dirs = cam.world_rays(pose)
    assert origins.shape == dirs.shape == (w * h, 3) and origins.dtype == dirs.dtype == np.float32
    np.testing.assert_allclose(origins, np.tile(pose[:3, 3], (w * h, 1)), atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-6)
    opt = dirs.astype(np.float64) @ pose[:3, :3] @ F.BODY_TO_OPTICAL.T
    rows, cols = np.divmod(np.arange(w * h), w)
    np.testing.assert_allclose(fx * opt[:, 0] / opt[:, 2] + w / 2, cols + 0.5, atol=1e-3)
    np.testing.assert_allclose(fx * opt[:, 1] / opt[:, 2] + h / 2, rows + 0.5, atol=1e-3)
    some = np.array([0, 7, w * h - 1, w * 3 + 11], dtype=np.int64)
    o, d = cam.pixel_rays(pose, some)
    np.testing.assert_array_equal(d, dirs[some])
    np.testing.assert_array_equal(o, origins[some])


def test_distortion_is_opencv_brown_conrady() -> None:
    """``Camera.distort``: Brown–Conrady ``[k1, k2, p1, p2, k3]`` in OpenCV's order, on normalised coordinates."""
    k1, k2, p1, p2, k3 = 0.12, -0.03, 0.004, -0.002, 0.01
    cam = core.Camera(width=8, height=6, rgb=False, hfov=1.2, distortion=[k1, k2, p1, p2, k3])
    assert cam.distortion == pytest.approx([k1, k2, p1, p2, k3])
    xy = np.random.default_rng(1).uniform(-0.6, 0.6, (50, 2))
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    want = np.c_[
        x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
        y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y,
    ]
    np.testing.assert_allclose(cam.distort(xy), want, atol=1e-9)
    plain = core.Camera(width=8, height=6, rgb=False, hfov=1.2)
    assert plain.distortion is None
    np.testing.assert_allclose(plain.distort(xy), xy)


def test_left_camera_looks_to_port(sim: Simulation, cap: FrameCapture) -> None:
    """Body frames are x forward, y left: ``camera_left`` looks along +y, and usv_2, on usv_1's port side in the
    world state, is seen by it and not by the front camera. ``MountPoint``: yaw 90 looks to port, pitch 90 down."""
    agent = sim.agents[0]
    mounts = agent.mounts()
    np.testing.assert_allclose(mounts["camera/left"][:3, 0], [0, 1, 0], atol=1e-9)
    np.testing.assert_allclose(mounts["camera/front"][:3, 0], [1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(rpy_matrix((0, 0, 0), (0, 0, 90))[:3, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rpy_matrix((0, 0, 0), (0, 90, 0))[:3, 0], [0, 0, -1], atol=1e-12)
    i2 = _index(sim, "usv_2")
    rel = F.transform_points(F.invert(cap.world.matrices[agent.index]), cap.world.poses[i2, :3])[0]
    assert rel[1] > abs(rel[0])  # to port
    inst = sim.vessels[i2].instance_id
    ac = cap.agents[agent.id]
    assert (ac.cameras["left"].instance == inst).any()
    assert not (ac.cameras["front"].instance == inst).any()
    assert ac.cameras["left"].rgb is None  # outputs without rgb: no rgb image


def test_top_view_heading_up_and_north_up(sim: Simulation, cap: FrameCapture) -> None:
    """``TopViewConfig``: a level orthographic camera looking straight down, ``metres_per_pixel`` apart;
    ``heading_up`` puts the bow at the top of the image (image right = starboard), ``north_up`` north (right =
    east); depth is metres down to the water from ``altitude_m``."""
    for agent, up in ((sim.agents[0], HEADING_1), (sim.agents[1], math.pi / 2)):
        ac = cap.agents[agent.id]
        assert agent.top_view is not None and ac.top_view_pose is not None and ac.top_view is not None
        w, h = agent.top_view.resolution
        origins, dirs = agent.top_view.world_rays(np.ascontiguousarray(ac.top_view_pose))
        np.testing.assert_allclose(dirs, np.tile([0, 0, -1], (w * h, 1)), atol=1e-6)
        grid = origins.reshape(h, w, 3).astype(np.float64)
        top_minus_bottom = grid[0, w // 2] - grid[-1, w // 2]
        right_minus_left = grid[h // 2, -1] - grid[h // 2, 0]
        np.testing.assert_allclose(
            top_minus_bottom[:2], (h - 1) * TOP_MPP * np.array([math.cos(up), math.sin(up)]), atol=1e-3
        )
        right = up - math.pi / 2
        np.testing.assert_allclose(
            right_minus_left[:2], (w - 1) * TOP_MPP * np.array([math.cos(right), math.sin(right)]), atol=1e-3
        )
        # the rendered image: the USV's own hull lies along its heading (rows for heading-up; at the world yaw,
        # counter-clockwise from image right, for north-up)
        own = sim.vessels[agent.index]
        rows, cols = np.nonzero(ac.top_view.instance == own.instance_id)
        assert len(rows) > 50
        axis = math.pi / 2 if agent.rig.top_view and agent.rig.top_view.orientation == "heading_up" else HEADING_2
        assert abs(math.remainder(_axis_angle(rows, cols) - axis, math.pi)) < math.radians(10)
        if axis == math.pi / 2:  # heading-up: the hull's length, in metres, down the rows
            assert (rows.max() - rows.min() + 1) * TOP_MPP == pytest.approx(own.box_size[0], abs=2 * TOP_MPP)
        water = ac.top_view.instance == sim.ws.scene.sea_instance
        assert agent.rig.top_view is not None
        assert abs(float(np.median(ac.top_view.depth[water])) - agent.rig.top_view.altitude_m) < 2.0


# ---------------------------------------------------------------------------------------------- annotations


def test_2d_boxes_hold_every_pixel_of_their_vessel(sim: Simulation, cap: FrameCapture, ann: Annotations) -> None:
    """``camera`` boxes are pixels, origin top-left, pixel centres at +0.5: every pixel of the vessel's instance lies
    in its box, ``visible_pixels`` counts them, ``truncation`` and ``occlusion`` are shares in [0, 1]."""
    cols = ann.columns()["camera"]
    assert sorted(zip(cols["target_id"], cols["camera"], strict=True)) == [("target", "front"), ("usv_2", "left")]
    for j, (vid, name) in enumerate(zip(cols["target_id"], cols["camera"], strict=True)):
        inst = cap.agents["usv_1"].cameras[name].instance
        rows, cc = np.nonzero(inst == sim.vessels[_index(sim, vid)].instance_id)
        x0, y0, x1, y1 = (cols[k][j] for k in ("x_min", "y_min", "x_max", "y_max"))
        assert 0 <= x0 < x1 <= inst.shape[1] and 0 <= y0 < y1 <= inst.shape[0]
        assert ((cc + 0.5 >= x0) & (cc + 0.5 <= x1) & (rows + 0.5 >= y0) & (rows + 0.5 <= y1)).all(), vid
        assert cols["visible_pixels"][j] == len(rows) > 0
        assert cols["box_pixels"][j] >= (x1 - x0) * (y1 - y0) >= len(rows)
        for k in ("truncation", "occlusion", "wave_occlusion"):
            assert 0.0 <= cols[k][j] <= 1.0, k


def test_3d_boxes_hold_the_lidar_points_of_their_vessel(sim: Simulation, cap: FrameCapture, ann: Annotations) -> None:
    """``lidar`` boxes: centre, size (length, beam, height) and quaternion ``x, y, z, w`` in the LiDAR frame hold
    the vessel's LiDAR points (as many as ``lidar_points``); ``yaw`` (radians) is the vessel's heading less the
    LiDAR's; ``range_m`` the metres from the LiDAR to the box centre; BEV is the box's footprint."""
    ac = cap.agents["usv_1"]
    pts, pose = ac.lidar, ac.lidar_pose
    assert pts is not None and pose is not None
    lid, bev = ann.columns()["lidar"], ann.columns()["bev"]
    assert lid["target_id"] == ["target", "usv_2"]
    lidar_yaw = math.atan2(pose[1, 0], pose[0, 0])
    assert _angle(lidar_yaw, HEADING_1) < 1e-9  # mounted level, facing forward
    for j, vid in enumerate(lid["target_id"]):
        i = _index(sim, vid)
        mine = pts.instance == sim.vessels[i].instance_id
        rot = Rotation.from_quat(lid["rotation"][j])  # scalar-last
        local = rot.inv().apply(pts.xyz[mine].astype(np.float64) - lid["center"][j])
        assert (np.abs(local) <= lid["size"][j] / 2 + 5 * NOISE).all(), vid
        assert lid["lidar_points"][j] == mine.sum() > 0
        assert _angle(lid["yaw"][j], cap.world.poses[i, 5] - lidar_yaw) < 0.15  # roll and pitch aside
        assert _angle(lid["yaw"][j], rot.as_euler("ZYX")[0]) < 1e-9
        centre_world = cap.world.box_centers[i]
        assert lid["range_m"][j] == pytest.approx(np.linalg.norm(centre_world - pose[:3, 3]), abs=1e-6)
        np.testing.assert_allclose(lid["size"][j], sim.vessels[i].box_size)
        assert (bev["x"][j], bev["y"][j], bev["length"][j], bev["width"][j]) == (
            lid["center"][j][0],
            lid["center"][j][1],
            lid["size"][j][0],
            lid["size"][j][1],
        )


def test_box_corners_order_and_target_range() -> None:
    """``box_corners``: ``(8, 3)``, corner ``i`` at ``±size/2`` with bit 0 → +x, bit 1 → +y, bit 2 → +z (box frame),
    carried by ``matrix``. ``in_target_range``: bird's-eye distance, height ignored, shape ``centres.shape[:-1]``."""
    size = np.array([4.0, 2.0, 1.0])
    m = F.pose_matrices(np.array([10.0, -5.0, 1.0, 0.0, 0.0, math.pi / 2]))
    corners = box_corners(m, size)
    assert corners.shape == (8, 3)
    for i in range(8):
        local = [(1 if i >> b & 1 else -1) * size[b] / 2 for b in range(3)]
        np.testing.assert_allclose(corners[i], F.transform_points(m, local)[0], atol=1e-12)
    # yaw 90°: the box's +x (length) runs along world +y
    np.testing.assert_allclose(corners[1] - corners[0], [0.0, 4.0, 0.0], atol=1e-12)
    c = np.array([[[3.0, 4.0, 100.0], [3.0, 4.1, 0.0]], [[0.0, 0.0, -50.0], [6.0, 0.0, 0.0]]])
    near = in_target_range(c, 5.0)
    assert near.shape == (2, 2) and near.dtype == np.bool_
    assert near.tolist() == [[True, False], [True, False]]


# ---------------------------------------------------------------------------------------------- radar


def test_radar_units_frames_and_clutter(sim: Simulation, cap: FrameCapture) -> None:
    """Radar ranges are metres (a vessel's returns lie between the nearest and farthest of its box corners, give or
    take a range bin); ``sensor_yaw`` is radians counter-clockwise from east (the heading, for a forward mount); sea
    clutter is class WATER at the still sea level (world z = 0) seen from the sensor, tilted as it is."""
    agent = sim.agents[0]
    ret = cap.agents[agent.id].radar
    cfg = agent.rig.radar
    assert ret is not None and cfg is not None
    assert _angle(ret.sensor_yaw, HEADING_1) < 1e-9
    origin = ret.pose[:3, 3]
    for vid in ("target", "usv_2"):
        i = _index(sim, vid)
        mine = ret.instance_id == sim.vessels[i].instance_id
        assert mine.any(), vid
        corners = box_corners(
            cap.world.matrices[i] @ F.translation(sim.vessels[i].box_center_body), sim.vessels[i].box_size
        )
        dist = np.linalg.norm(corners - origin, axis=1)
        res = cfg.range_resolution_m
        assert (ret.range[mine] >= dist.min() - res).all() and (ret.range[mine] <= dist.max() + res).all(), vid
    clutter = ret.is_clutter
    assert clutter.sum() > 10
    assert set(ret.semantic_class[clutter].tolist()) == {int(SemanticClass.WATER)}
    assert abs(cap.world.poses[agent.index, 4]) > 0.02  # the hull pitches: the sensor is not level
    z = ret.points(frame="world")[clutter, 2]
    assert np.abs(z).max() < 0.05


def test_ppi_colormap_promises() -> None:
    """``ppi_colormap``: ``(H, W, 3)`` uint8; ``<= 0`` black; dB mapped from ``vmin_db`` (dark green) to ``vmax_db``
    (near white), brighter with intensity."""
    img = np.array([[0.0, -1.0, 0.01, 1.0], [10.0, 100.0, 1000.0, 1e6]], dtype=np.float32)
    rgb = ppi_colormap(img)
    assert rgb.shape == (2, 4, 3) and rgb.dtype == np.uint8
    assert rgb[0, 0].tolist() == [0, 0, 0] and rgb[0, 1].tolist() == [0, 0, 0]
    low, high = rgb[0, 2], rgb[1, 2]  # -20 dB and +30 dB
    assert low[1] > low[0] and low[1] > low[2] and low.sum() < 150  # dark green
    assert (high >= 200).all()  # near white
    brightness = rgb.reshape(-1, 3).astype(int).sum(axis=1)[2:]
    assert (np.diff(brightness) >= 0).all()


# ---------------------------------------------------------------------------------------------- the sea


def test_wave_field_units_and_direction() -> None:
    """``WaveField``: deep-water components (k = ω²/g), Hs = 4·√m0 metres, ``max_elevation`` the sum of the
    amplitudes, ``slope`` = [dη/dx, dη/dy], and ``direction_rad`` (counter-clockwise from +x) the way the crests
    travel: where the surface rises with time, it falls along the travel direction."""
    hs, direction = 2.0, 0.7
    wave = core.WaveField(hs_m=hs, tp_s=8.0, gamma=3.3, direction_rad=direction, spread_s=10.0, seed=5)
    comp = wave.components()
    a, omega, k, theta = comp[:, 0], comp[:, 1], comp[:, 2], comp[:, 3]
    np.testing.assert_allclose(k, omega**2 / G, rtol=1e-6)
    assert 4 * math.sqrt(np.sum(a**2) / 2) == pytest.approx(hs, rel=0.05)
    assert wave.max_elevation == pytest.approx(np.abs(a).sum(), rel=1e-9)
    mean = math.atan2(np.sum(a**2 * np.sin(theta)), np.sum(a**2 * np.cos(theta)))
    assert _angle(mean, direction) < 0.05
    rng = np.random.default_rng(2)
    x, y = rng.uniform(-200, 200, 400), rng.uniform(-200, 200, 400)
    t, dt, dx = 3.0, 1e-3, 1e-3
    slope = wave.slope(x, y, t)
    fd = np.c_[
        (wave.elevation(x + dx, y, t) - wave.elevation(x - dx, y, t)) / (2 * dx),
        (wave.elevation(x, y + dx, t) - wave.elevation(x, y - dx, t)) / (2 * dx),
    ]
    np.testing.assert_allclose(slope, fd, atol=1e-4)
    rate = (wave.elevation(x, y, t + dt) - wave.elevation(x, y, t - dt)) / (2 * dt)
    along = slope @ [math.cos(direction), math.sin(direction)]
    corr = np.corrcoef(rate, along)[0, 1]
    assert corr < -0.8  # η_t = -c·∂η/∂s for crests moving towards +s
    # orbital velocities (m/s, world frame, z up): at the still surface the vertical one is η_t, the water moves
    # towards the travel direction under the crests, and the motion dies out with depth
    surface = wave.orbital_velocity(np.c_[x, y, np.zeros_like(x)], t)
    assert surface.shape == (400, 3)
    np.testing.assert_allclose(surface[:, 2], rate, atol=1e-3)
    forward = surface[:, :2] @ [math.cos(direction), math.sin(direction)]
    assert np.corrcoef(wave.elevation(x, y, t), forward)[0, 1] > 0.8
    deep = wave.orbital_velocity(np.c_[x, y, np.full_like(x, -10.0)], t)
    assert np.abs(deep).mean() < 0.7 * np.abs(surface).mean()


def test_the_simulated_sea_is_the_scenarios_wave_field(sim: Simulation, cap: FrameCapture) -> None:
    """``Simulation.set_sea_surface`` / ``SeaSpec.field``: the water every sensor sees is the wave field drawn from
    the scenario's sea seed, at the frame time (world z, metres)."""
    spec = sim.scenario.environment.sea_spec()
    assert sim.sea == spec and spec.hs_m == core.wave_height("W2")
    here = cap.world.poses[0, :2] + np.random.default_rng(3).uniform(-15, 15, (30, 2))
    heights = sim.ws.scene.wave_heights(here.astype(np.float32))
    assert heights.dtype == np.float32 and heights.shape == (30,)
    field = spec.field(scenario_seed=sim.scenario.seed).elevation(here[:, 0].copy(), here[:, 1].copy(), cap.time_s)
    assert np.abs(heights - field).max() < 0.1
    other = spec.field(scenario_seed=sim.scenario.seed + 1).elevation(here[:, 0].copy(), here[:, 1].copy(), cap.time_s)
    assert np.abs(heights - other).max() > 0.3


def test_sea_presets_and_spectra() -> None:
    """Preset heights as documented (W0 = 0.5 m, W3 = 3.5 m), presets in order; ``fully_developed``: the
    Pierson–Moskowitz wind (at 19.5 m, ``U = √(Hs g / 0.21)``) and peak period ``2πU / (0.877 g)``; the sensors'
    wind is that over 1.026 (at 10 m); ``dnv_gamma``: DNV-RP-C205; degrees counter-clockwise from east in, radians
    out."""
    assert [n for n, _ in core.wave_presets()] == ["W0", "W1", "W2", "W3"]
    assert core.wave_height("W0") == 0.5 and core.wave_height("W3") == 3.5
    assert [p[0] for p in core.sea_presets()] == [str(i) for i in range(10)] + ["W0", "W1", "W2", "W3"]
    for hs in (0.5, 2.0, 4.0):
        u = math.sqrt(hs * G / 0.21)
        tp, wind = core.fully_developed(hs)
        assert wind == pytest.approx(u, rel=1e-6)
        assert tp == pytest.approx(2 * math.pi * u / (0.877 * G), rel=1e-3)
        assert wind_from_wave_height(hs) == pytest.approx(u / 1.026, rel=1e-9)
    for hs, tp in ((2.0, 4.0), (2.0, 6.0), (2.0, 6.5), (2.0, 9.0)):
        ratio = tp / math.sqrt(hs)
        want = 5.0 if ratio <= 3.6 else 1.0 if ratio >= 5.0 else math.exp(5.75 - 1.15 * ratio)
        assert core.dnv_gamma(hs, tp) == pytest.approx(want, rel=1e-6)
        assert sea_spec_for_height(hs, tp_s=tp).gamma == pytest.approx(want, rel=1e-6)
    assert sea_spec_for_preset("W1", direction_deg=-90.0).direction_rad == pytest.approx(-math.pi / 2)


def test_sensor_env_light_units() -> None:
    """``SensorEnv``: the sun's direct-normal irradiance in lux (a list of 3, zero at night), the horizontal
    illuminance of sun and sky in lux (a clear noon: about 10⁵), the sky's radiance in cd/m² (a clear zenith: blue,
    thousands), the ground below the horizon."""
    from mmusv.world.environment import Environment

    noon = sensor_env(Environment.make(time_of_day="12:00"))
    night = sensor_env(Environment.make(time_of_day="00:30"))
    assert isinstance(noon.sun_irradiance, list) and len(noon.sun_irradiance) == 3
    assert night.sun_irradiance == [0.0, 0.0, 0.0]
    assert 3e4 < min(noon.sun_irradiance) <= max(noon.sun_irradiance) < 1.5e5
    lux, _ = noon.exposure
    assert 5e4 < lux < 1.5e5 and night.exposure[0] < 1.0
    sky = noon.sky_radiance(np.array([[0, 0, 1], [0, 0, -1]], dtype=np.float32))
    assert sky.shape == (2, 3) and sky.dtype == np.float32
    assert 1e3 < sky[0, 0] < sky[0, 2] < 1e5  # a blue sky overhead
    assert sky[1].sum() < sky[0].sum()  # the ground below


def test_hull_rao_long_wave_limits() -> None:
    """``hull_rao`` units (heave m/m, roll and pitch rad/m): in waves much longer than the hull it rides the surface,
    heave → 1 and the tilt → the wave slope per metre of amplitude, k = ω²/g (pitch in head seas, β = 0; roll in
    beam seas, β = π/2)."""
    hull = [5.0, 2.0, 0.5, 0.5, 1.0]
    omega = np.array([0.05, 0.1])
    k = omega**2 / G
    head = np.abs(core.hull_rao(hull=hull, omega=omega, beta=np.zeros(2), omega_e=omega))
    beam = np.abs(core.hull_rao(hull=hull, omega=omega, beta=np.full(2, math.pi / 2), omega_e=omega))
    assert head.shape == (2, 3)
    np.testing.assert_allclose(head[:, 0], 1.0, atol=1e-3)
    np.testing.assert_allclose(head[:, 2], k, rtol=0.01)
    np.testing.assert_allclose(head[:, 1], 0.0, atol=1e-9)
    np.testing.assert_allclose(beam[:, 0], 1.0, atol=1e-2)
    np.testing.assert_allclose(beam[:, 1], k, rtol=0.01)
    np.testing.assert_allclose(beam[:, 2], 0.0, atol=1e-9)


# ---------------------------------------------------------------------------------------------- world


def test_heightfield_rows_grow_north_and_match_the_terrain_mesh() -> None:
    """``Heightfield.sample`` is the terrain mesh's height (world x, y metres; row ``i`` northwards, column ``j``
    eastwards); ``MapPriors`` call land what stands above the water and map cells back to their centres."""
    from mmusv.world.maps import generate_map

    world = generate_map("island", seed=4)
    assert list(world.static_meshes) == sorted(world.static_meshes)
    hf = world.heightfield
    terrain = world.static_meshes["terrain"]
    scene = Scene()
    scene.add_instance(scene.add_mesh(terrain.vertices, terrain.faces))
    x0, y0, x1, y1 = hf.bounds()
    xs, ys = hf.axes()
    assert (xs[0], ys[0], xs[-1], ys[-1]) == (x0, y0, x1, y1)
    rng = np.random.default_rng(0)
    xy = np.c_[rng.uniform(x0, x1, 3000), rng.uniform(y0, y1, 3000)]
    hits = scene.cast_rays(np.c_[xy, np.full(len(xy), 1000.0)], np.tile([0.0, 0.0, -1.0], (len(xy), 1)))
    assert hits.hit.sum() > 100
    np.testing.assert_allclose(1000.0 - hits.distance[hits.hit], hf.sample(xy[hits.hit]), atol=2e-3)
    # a vertex: row i at y0 + i·spacing (north), column j at x0 + j·spacing (east)
    i, j = np.unravel_index(int(np.argmax(hf.z)), hf.z.shape)
    assert hf.sample([[x0 + j * hf.spacing, y0 + i * hf.spacing]])[0] == pytest.approx(hf.z[i, j])
    assert math.isnan(hf.sample([[x1 + 1.0, y0]])[0])
    priors = world.priors
    h = hf.sample(xy)
    assert not priors.is_water(xy[h > 3.0]).any() and priors.is_water(xy[h < -20.0]).all()
    centres = priors.cell_to_world(priors.world_to_cell(xy))
    assert np.abs(centres - xy).max() <= priors.resolution / 2 + 1e-9


def test_asset_dimensions_are_the_mesh_extents(sim: Simulation) -> None:
    """``VesselAsset``: length, beam, height (metres) the mesh's x, y, z extents, ``draft`` below z = 0, ``bbox``
    ``(2, 3)`` float64 min/max; ``VesselInfo.box_size`` those, ``box_center_body`` the box's centre."""
    for v in sim.vessels:
        asset = get_asset(v.asset)
        verts = np.asarray(asset.mesh.vertices, dtype=np.float64)
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        assert asset.bbox.shape == (2, 3) and asset.bbox.dtype == np.float64
        np.testing.assert_allclose(asset.bbox, [lo, hi])
        assert (asset.length, asset.beam, asset.height) == pytest.approx(tuple(hi - lo))
        assert asset.draft == pytest.approx(-lo[2]) and asset.air_draft == pytest.approx(hi[2])
        np.testing.assert_allclose(v.box_size, hi - lo)
        np.testing.assert_allclose(v.box_center_body, (lo + hi) / 2)


# ---------------------------------------------------------------------------------------------- frames, small


def test_matrix_to_pose_ranges_and_gimbal_lock() -> None:
    """``matrix_to_pose``: pitch in [-π/2, π/2], roll = 0 at gimbal lock, and ``pose_matrices`` of its answer is the
    matrix; ``sensor_seed`` is a 64-bit whole number; ``frame_ranges`` sorts and counts each index once."""
    for pitch in (math.pi / 2, -math.pi / 2):
        m = F.pose_matrices(np.array([1.0, 2.0, 3.0, 0.4, pitch, -0.9]))
        eta = F.matrix_to_pose(m)
        assert eta[3] == 0.0 and eta[4] == pytest.approx(pitch)
        np.testing.assert_allclose(F.pose_matrices(eta), m, atol=1e-9)
    rng = np.random.default_rng(4)
    m = F.pose_matrices(rng.uniform(-4, 4, (50, 6)))
    eta = F.matrix_to_pose(m)
    assert (np.abs(eta[:, 4]) <= math.pi / 2).all() and (np.abs(eta[:, 3:]) <= math.pi).all()
    np.testing.assert_allclose(F.pose_matrices(eta), m, atol=1e-9)
    seeds = {
        sensor_seed(7, frame=k, agent=a, sensor=s)
        for k in range(3)
        for a in range(2)
        for s in ("lidar", "radar", "camera")
    }
    assert len(seeds) == 18 and all(0 <= s < 2**64 for s in seeds) and max(seeds) >= 2**32
    assert frame_ranges([9, 3, 1, 2, 2, 7, 10, 12]) == "1..3, 7, 9..10, 12"


# ---------------------------------------------------------------------------------------------- the recording


def test_recording_frames_units_and_sentinels(sim: Simulation, recording: Path) -> None:
    """The recorded frame, from the file alone: ``/tf`` world → vessel is the world state's body → world; a
    ``/<agent>/boxes`` cube in the LiDAR frame, carried through ``/tf``, is the vessel's world box centre; the top
    view's frame is optical (z down, image down = astern); depth ``+inf`` (sky) exactly where the instance PNG says
    65535; the radar cloud's x, y, z are its range, azimuth, elevation; the tables' yaw is the heading."""
    msgs = frame_messages(recording, 0)
    state = sim.world_state(0)
    world = WorldFrame.from_message(msgs["/world/state"])
    np.testing.assert_allclose(world.poses, state.poses, atol=1e-9)
    tf = {}
    for t in msgs["/tf"].transforms:
        m = np.eye(4)
        m[:3, :3] = Rotation.from_quat([t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]).as_matrix()
        m[:3, 3] = [t.translation.x, t.translation.y, t.translation.z]
        tf[(t.parent_frame_id, t.child_frame_id)] = m
    for i, v in enumerate(sim.vessels):
        np.testing.assert_allclose(tf[("world", v.id)], state.matrices[i], atol=1e-9)
    lidar_to_world = tf[("world", "usv_1")] @ tf[("usv_1", "usv_1/lidar")]
    entity = msgs["/usv_1/boxes"].entities[0]
    assert entity.frame_id == "usv_1/lidar"
    cubes = dict(zip([m.key for m in entity.metadata], entity.cubes, strict=True))
    for vid, cube in cubes.items():
        i = _index(sim, vid)
        p = cube.pose.position
        np.testing.assert_allclose(
            F.transform_points(lidar_to_world, [p.x, p.y, p.z])[0], state.box_centers[i], atol=1e-6
        )
        np.testing.assert_allclose([cube.size.x, cube.size.y, cube.size.z], sim.vessels[i].box_size)
    top = tf[("world", "usv_1/top_view")]
    yaw = state.poses[0, 5]
    np.testing.assert_allclose(top[:3, 2], [0, 0, -1], atol=1e-9)
    np.testing.assert_allclose(top[:3, 1], [-math.cos(yaw), -math.sin(yaw), 0], atol=1e-9)
    depth = decode_image(msgs["/usv_1/camera/front/depth"])
    inst = decode_image(msgs["/usv_1/camera/front/instance"])
    assert depth.dtype == np.float32 and inst.dtype == np.uint16 and depth.shape == inst.shape == (120, 160)
    sky = inst == 65535
    assert 0 < sky.sum() < sky.size
    np.testing.assert_array_equal(np.isposinf(depth), sky)
    cloud = decode_point_cloud(msgs["/usv_1/radar/returns"])
    r, az, el = (cloud[k].astype(np.float64) for k in ("range", "azimuth", "elevation"))
    xyz = np.c_[r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)]
    np.testing.assert_allclose(np.c_[cloud["x"], cloud["y"], cloud["z"]], xyz, atol=1e-3)
    tables = recording.parent / "tables"
    ws = read_table(tables, "world_state").rows
    moving = ws.filter(ws["vx"] ** 2 + ws["vy"] ** 2 > 0.01)
    heading = np.arctan2(moving["vy"].to_numpy(), moving["vx"].to_numpy())
    assert np.abs(np.angle(np.exp(1j * (moving["yaw"].to_numpy() - heading)))).max() < 1e-6
    boxes = read_table(tables, "boxes_3d").rows
    quat = boxes.select("qx", "qy", "qz", "qw").to_numpy()
    np.testing.assert_allclose(boxes["yaw"].to_numpy(), Rotation.from_quat(quat).as_euler("ZYX")[:, 0], atol=1e-9)
