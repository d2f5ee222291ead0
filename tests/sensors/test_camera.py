"""Cameras (``mmusv.sensors.camera`` over ``mmusv_core::sensors::camera``).

* Pinhole geometry against closed forms: intrinsics ``fx = fy = W / (2 tan(hfov/2))``, ``c = (W/2, H/2)``;
  per-pixel rays rebuilt here from the intrinsics (pixel centres at +0.5, optical x right / y down / z forward);
  depth over a flat plane equals the analytic plane distance along the optical axis; sky = (inf, 0, −1).
* Orthographic top view: a box at a known world position lands where ``metres_per_pixel`` and the Simulation's
  top-view pose (heading-up and north-up) say.
* Depth–LiDAR agreement: LiDAR points moved into a camera through the sensor poses of one capture fall on
  pixels whose depth, class and instance match (tolerance derived from the pixel's angular size and the
  incidence angle).
* RGB only when asked; misconfigured cameras raise ``ConfigError`` naming the field.
"""

from __future__ import annotations

import math
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv._native import core
from mmusv.scene import Scene
from mmusv.sensors import (
    CameraConfig,
    TopViewConfig,
    camera_from_config,
    render,
    sensor_env,
    top_view_from_config,
)
from mmusv.sensors.camera import BODY_TO_OPTICAL
from mmusv.simulation import Simulation
from mmusv.world.build import pose_matrices


def plane_scene(half: float, *, z: float = 0.0, cls: int = 1) -> Scene:
    s = Scene()
    v = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    s.add_instance(s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), classes=cls, name="plane"))
    return s


def add_box(scene: Scene, lo: Any, hi: Any, *, cls: int) -> int:
    lo_, hi_ = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    v = np.array([[(hi_ if (i >> k) & 1 else lo_)[k] for k in range(3)] for i in range(8)])
    f = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ],
        dtype=np.int64,
    )
    return scene.add_instance(scene.add_mesh(v, f, classes=cls, name="box"))


def pixel_rays_world(intrinsics: Any, width: int, height: int, pose: np.ndarray) -> np.ndarray:
    """Unit world directions through every pixel centre, rebuilt from the intrinsics: ``(H·W, 3)`` float64."""
    fx, fy, cx, cy = intrinsics
    u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    opt = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=-1).reshape(-1, 3)
    body = opt @ BODY_TO_OPTICAL  # optical → body is BODY_TO_OPTICAL.T (row vectors)
    d = body @ pose[:3, :3].T
    out: np.ndarray = d / np.linalg.norm(d, axis=1, keepdims=True)
    return out


def footprint_edges(
    scene: Scene, intrinsics: Any, pose: np.ndarray, u: np.ndarray, v: np.ndarray, *, rel: float = 1e-3
) -> tuple[np.ndarray, np.ndarray]:
    """``(K,)`` bool: whether the footprint of pixel ``(u[k], v[k])`` holds an edge, and ``(K, 3)`` the unit
    normal of the surface hit by the pixel-centre ray. Casts 3×3 sub-pixel rays
    (at 0.1, 0.5, 0.9 of the pixel) with the scene: an edge if they hit different instances (or some miss), or
    if their inverse depths are not one plane (on a plane, inverse depth is affine in the image coordinates,
    so the second differences through the centre vanish; a step or crease makes them large)."""
    fx, fy, cx, cy = intrinsics
    f = np.array([0.1, 0.5, 0.9])
    su = (u[:, None, None] + f[None, None, :]).repeat(3, axis=1)
    sv = (v[:, None, None] + f[None, :, None]).repeat(3, axis=2)
    opt = np.stack([(su - cx) / fx, (sv - cy) / fy, np.ones_like(su)], axis=-1).reshape(-1, 3)
    d = opt @ BODY_TO_OPTICAL @ pose[:3, :3].T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hits = scene.cast_rays(np.broadcast_to(pose[:3, 3], d.shape), d)
    inst = hits.instance_id.reshape(-1, 3, 3)
    depth = (hits.distance.astype(np.float64) * (d @ pose[:3, 0])).reshape(-1, 3, 3)
    edge = np.any(inst != inst[:, 1:2, 1:2], axis=(1, 2)) | np.any(inst < 0, axis=(1, 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(np.isfinite(depth), 1.0 / depth, 0.0)
        c = inv[:, 1, 1]
        for a, b in (((0, 1), (2, 1)), ((1, 0), (1, 2)), ((0, 0), (2, 2)), ((0, 2), (2, 0))):
            edge |= np.abs(inv[:, a[0], a[1]] + inv[:, b[0], b[1]] - 2 * c) > rel * c
    centre_normal = hits.normal.reshape(-1, 3, 3, 3)[:, 1, 1].astype(np.float64)
    return edge, centre_normal


# ------------------------------------------------------------------------------------------ pinhole, analytic


@pytest.mark.parametrize("width,height,hfov_deg", [(64, 48, 90.0), (33, 20, 60.0), (10, 40, 150.0)])
def test_intrinsics_closed_form(width: int, height: int, hfov_deg: float) -> None:
    cam = camera_from_config(CameraConfig(name="c", resolution=(width, height), hfov_deg=hfov_deg))
    fx, fy, cx, cy = cam.intrinsics
    f = width / (2 * math.tan(math.radians(hfov_deg) / 2))
    assert fx == pytest.approx(f, rel=1e-12) and fy == pytest.approx(f, rel=1e-12)
    assert (cx, cy) == (width / 2, height / 2)
    # The horizontal field of view spans the outer pixel edges.
    assert 2 * math.degrees(math.atan(cx / fx)) == pytest.approx(hfov_deg, rel=1e-12)
    assert tuple(cam.resolution) == (width, height)


@pytest.mark.parametrize("w,h", [(40, 30), (33, 21), (1, 1)])
def test_world_rays_match_intrinsics_and_conventions(w: int, h: int) -> None:
    cam = core.Camera(rgb=False, width=w, height=h, hfov=math.radians(80))
    pose = pose_matrices(np.array([1.0, 2.0, 3.0, 0.2, -0.3, 2.5]))
    origins, dirs = cam.world_rays(pose)
    assert origins.shape == (w * h, 3) and dirs.shape == (w * h, 3)
    np.testing.assert_allclose(origins, np.broadcast_to(pose[:3, 3], origins.shape), atol=1e-5)
    np.testing.assert_allclose(dirs, pixel_rays_world(cam.intrinsics, w, h, pose), atol=1e-6)
    # Conventions in the body frame: top-left pixel looks left (+y) and up (+z); row-major order.
    body = np.asarray(dirs, dtype=np.float64) @ pose[:3, :3]
    grid = body.reshape(h, w, 3)
    if w == h == 1:
        np.testing.assert_allclose(grid[0, 0], [1.0, 0.0, 0.0], atol=1e-6)  # the single pixel looks forward
        return
    assert grid[0, 0, 1] > 0 and grid[0, 0, 2] > 0
    assert np.all(np.diff(grid[:, :, 1], axis=1) < 0), "u grows to the right (−y)"
    assert np.all(np.diff(grid[:, :, 2], axis=0) < 0), "v grows downwards (−z)"


@pytest.mark.parametrize(
    "cam",
    [
        core.Camera(rgb=False, width=33, height=21, hfov=math.radians(80)),
        core.Camera(rgb=False, width=10, height=7, metres_per_pixel=0.25),
    ],
    ids=["pinhole", "orthographic"],
)
def test_pixel_rays_are_the_world_rays_of_those_pixels(cam: Any) -> None:
    """The annotation's silhouette rays: ``pixel_rays`` gives exactly the ``world_rays`` rows it is asked for."""
    w, h = cam.resolution
    pose = pose_matrices(np.array([1.0, 2.0, 3.0, 0.2, -0.3, 2.5]))
    origins, dirs = cam.world_rays(pose)
    pix = np.random.default_rng(3).permutation(w * h)[: w * h // 2].astype(np.int64)
    o, d = cam.pixel_rays(pose, pix)
    assert o.dtype == d.dtype == np.float32
    np.testing.assert_array_equal(o, origins[pix])
    np.testing.assert_array_equal(d, dirs[pix])
    with pytest.raises(mmusv.MmusvError, match=r"pixels\[1\].*outside"):
        cam.pixel_rays(pose, np.array([0, w * h], dtype=np.int64))
    with pytest.raises(TypeError, match="float64"):  # dtypes are checked by the binding, as for every array
        cam.pixel_rays(pose, np.array([0.5]))


@pytest.mark.parametrize("pitch_deg,roll_deg,yaw_deg", [(20.0, 6.0, 17.0), (60.0, -10.0, -120.0), (-5.0, 0.0, 90.0)])
def test_depth_over_a_plane_is_the_analytic_distance(pitch_deg: float, roll_deg: float, yaw_deg: float) -> None:
    w, h, hfov = 64, 48, math.radians(90)
    height_m, half = 10.0, 1e5
    scene = plane_scene(half, cls=1)
    cam = core.Camera(rgb=False, width=w, height=h, hfov=hfov)
    pose = pose_matrices(np.array([5.0, -3.0, height_m, *np.radians([roll_deg, pitch_deg, yaw_deg])]))
    img = render(cam, scene, pose=pose, env=sensor_env(), seed=1)
    assert img.depth.shape == (h, w) and img.depth.dtype == np.float32
    assert img.semantic.shape == (h, w) and img.semantic.dtype == np.uint16
    assert img.instance.shape == (h, w) and img.instance.dtype == np.int32
    assert img.rgb is None

    d = pixel_rays_world(cam.intrinsics, w, h, pose)
    with np.errstate(divide="ignore"):
        t = np.where(d[:, 2] < 0, height_m / -d[:, 2], np.inf)
    hit_xy = pose[:2, 3] + d[:, :2] * np.where(np.isfinite(t), t, 0)[:, None]
    t = np.where(np.all(np.abs(hit_xy) < half, axis=1), t, np.inf)
    depth = (t * (d @ pose[:3, 0])).reshape(h, w)
    ground = np.isfinite(depth)
    # Skip pixels whose ray grazes the horizon or the plane's edge (ambiguous in float32).
    clear = (np.abs(d[:, 2]) > 1e-3).reshape(h, w)
    assert clear.mean() > 0.9
    assert np.array_equal(np.isfinite(img.depth)[clear], ground[clear])
    rel = np.abs(img.depth[ground & clear] - depth[ground & clear]) / depth[ground & clear]
    assert rel.max() < 1e-4, f"depth off by up to {rel.max():.2e} (relative)"
    assert np.all(img.semantic[ground & clear] == 1) and np.all(img.instance[ground & clear] == 0)
    sky = ~ground & clear
    assert np.all(np.isposinf(img.depth[sky]))
    assert np.all(img.semantic[sky] == 0) and np.all(img.instance[sky] == -1)
    if pitch_deg > 50:
        assert not sky.any()
    else:
        assert sky.sum() > 10 and ground.sum() > 10


def test_pinhole_depth_is_along_the_axis_not_the_ray() -> None:
    """A wall facing the camera: every pixel has the same depth (the wall distance)."""
    s = Scene()
    add_box(s, (30.0, -500.0, -500.0), (31.0, 500.0, 500.0), cls=4)
    cam = core.Camera(rgb=False, width=32, height=24, hfov=math.radians(100))
    img = render(cam, s, pose=np.eye(4), env=sensor_env(), seed=1)
    np.testing.assert_allclose(img.depth, 30.0, rtol=1e-5)
    assert np.all(img.semantic == 4) and np.all(img.instance == 0)


def test_range_max_cuts_far_surfaces() -> None:
    s = Scene()
    add_box(s, (30.0, -500.0, -500.0), (31.0, 500.0, 500.0), cls=4)
    cam = core.Camera(rgb=False, width=8, height=6, hfov=math.radians(60), range_max=25.0)
    img = render(cam, s, pose=np.eye(4), env=sensor_env(), seed=1)
    assert np.all(np.isposinf(img.depth)) and np.all(img.instance == -1) and np.all(img.semantic == 0)


def test_the_sea_beyond_the_range_is_water_at_its_depth() -> None:
    """A declared sea plane smaller than the view, a camera 3 m up, pitched down and rolled, with a 60 m range:
    every pixel whose ray (rebuilt from the intrinsics) goes down is water, the sea's class and instance, at the
    depth where the ray meets z = 0 (the plane past the range and past the mesh's edge alike); every pixel whose
    ray rises is sky (+inf, class 0, instance -1). Before, the sea beyond the range was labelled sky."""
    s = plane_scene(200.0, cls=1)
    s.set_sea(0)
    cam = core.Camera(rgb=False, width=48, height=36, hfov=math.radians(90), range_max=60.0)
    pose = pose_matrices(np.array([0.0, 0.0, 3.0, 0.2, 0.05, 0.3]))
    img = render(cam, s, pose=pose, env=sensor_env(), seed=1)
    d = pixel_rays_world(cam.intrinsics, 48, 36, pose).reshape(36, 48, 3)
    down = d[..., 2] < 0
    assert 0 < down.sum() < down.size
    with np.errstate(divide="ignore"):
        t = np.where(down, 3.0 / -d[..., 2], np.inf)
    want = t * (d @ pose[:3, 0])
    assert (want[down] > 60.0).sum() > 48  # a band of pixels sees the sea past the range
    np.testing.assert_allclose(img.depth[down], want[down], rtol=1e-4)
    assert np.all(img.semantic[down] == 1) and np.all(img.instance[down] == 0)
    assert np.all(np.isposinf(img.depth[~down])) and np.all(img.semantic[~down] == 0)
    assert np.all(img.instance[~down] == -1)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"seed": 1.7}, r"seed = 1\.7: must be a whole number"),
        ({"seed": -1}, r"seed = -1: must be a whole number in 0\.\."),
        ({"seed": "3"}, r"seed = '3'.*not str"),
        ({"pose": np.eye(3)}, r"pose must be a \(4, 4\)"),
        ({"pose": np.eye(4).ravel()}, r"pose must be a \(4, 4\)"),
        ({"scene": "scene"}, r"scene must be an mmusv\.Scene, got str"),
    ],
)
def test_bad_render_arguments_are_named(kwargs: dict[str, Any], match: str) -> None:
    """A float seed used to be truncated (1.7 rendered as seed 1) and a flat 16-vector pose reshaped without a
    word; both are refused now, naming the argument, as the radar's sweep does."""
    cam = core.Camera(rgb=False, width=8, height=6, hfov=math.radians(60))
    args: dict[str, Any] = {"scene": plane_scene(10.0), "pose": np.eye(4), "seed": 1, **kwargs}
    scene = args.pop("scene")
    with pytest.raises(mmusv.InputError, match=match):
        render(cam, scene, env=sensor_env(), **args)


def test_rgb_only_when_asked() -> None:
    s = plane_scene(1000.0)
    colour = core.Camera(width=16, height=12, rgb=True, hfov=math.radians(90))
    plain = core.Camera(width=16, height=12, rgb=False, hfov=math.radians(90))
    pose = pose_matrices(np.array([0.0, 0.0, 5.0, 0.0, 0.2, 0.0]))
    with_rgb = render(colour, s, pose=pose, env=sensor_env(), seed=1)
    without = render(plain, s, pose=pose, env=sensor_env(), seed=1)
    assert without.rgb is None
    assert with_rgb.rgb is not None and with_rgb.rgb.shape == (12, 16, 3) and with_rgb.rgb.dtype == np.uint8
    for name in ("depth", "semantic", "instance"):
        assert np.array_equal(getattr(with_rgb, name), getattr(without, name), equal_nan=False), name
    # Sky (upper rows) is brighter than the dark water body looking down.
    assert with_rgb.rgb[0].mean() > with_rgb.rgb[-1].mean()


def test_rgb_outputs_in_a_capture(sim: Simulation) -> None:
    cap = sim.capture(2, radar=False)
    a, b = cap.agents["usv_a"], cap.agents["usv_b"]
    assert a.cameras["front"].rgb is not None and a.cameras["front"].rgb.shape == (120, 160, 3)
    assert a.top_view is not None and a.top_view.rgb is not None and a.top_view.rgb.shape == (160, 160, 3)
    assert b.cameras["front"].rgb is not None
    assert b.cameras["aux"].rgb is None, "outputs without rgb"
    assert b.cameras["aux"].depth.shape == (32, 48)
    assert b.top_view is not None and b.top_view.rgb is None, "top view outputs without rgb"


# ------------------------------------------------------------------------------------------ orthographic top view


def predicted_pixel(xy: np.ndarray, centre: np.ndarray, heading: float, mpp: float, w: int, h: int) -> np.ndarray:
    """Continuous image position (u, v) of world points ``xy`` in a top view centred on ``centre`` whose image
    top points along ``heading`` (radians from east, counter-clockwise)."""
    dx, dy = xy[:, 0] - centre[0], xy[:, 1] - centre[1]
    fwd = dx * math.cos(heading) + dy * math.sin(heading)
    left = -dx * math.sin(heading) + dy * math.cos(heading)
    return np.stack([w / 2 - left / mpp, h / 2 - fwd / mpp], axis=1)


@pytest.mark.parametrize("agent_id,orientation", [("usv_a", "heading_up"), ("usv_b", "north_up")])
def test_top_view_box_at_predicted_pixel(sim: Simulation, agent_id: str, orientation: str) -> None:
    frame = 4
    agent = sim.agent(agent_id)
    assert agent.rig.top_view is not None and agent.rig.top_view.orientation == orientation
    tv = agent.rig.top_view
    state = sim.world_state(frame)
    pose = sim.sensor_poses(agent, state)["top_view"]
    x, y, _, _, _, yaw = state.poses[agent.index]
    heading = yaw if orientation == "heading_up" else math.pi / 2
    assert abs(math.sin(yaw)) > 0.3 and abs(math.cos(yaw)) > 0.3, "a yaw that tells the orientations apart"
    # A 6 m × 6 m × 3 m box 20 m ahead-right-ish of the USV in world axes (not symmetric about the USV).
    cx, cy, side, tall = x + 17.0, y - 9.0, 6.0, 3.0
    scene = plane_scene(2000.0)
    box = add_box(scene, (cx - side / 2, cy - side / 2, 0.0), (cx + side / 2, cy + side / 2, tall), cls=5)
    cam = top_view_from_config(tv)
    assert cam.intrinsics is None
    w, h = tv.resolution
    mpp = tv.metres_per_pixel
    img = render(cam, scene, pose=pose, env=sensor_env(), seed=1)
    assert img.depth.shape == (h, w)
    mask = img.instance == box
    n = int(mask.sum())
    assert abs(n - (side / mpp) ** 2) <= 4 * side / mpp + 4, f"{n} box pixels for a {side} m box at {mpp} m/px"
    vv, uu = np.nonzero(mask)
    centroid = np.array([uu.mean() + 0.5, vv.mean() + 0.5])
    want = predicted_pixel(np.array([[cx, cy]]), np.array([x, y]), heading, mpp, w, h)[0]
    assert np.linalg.norm(centroid - want) < 0.75, f"box at pixel {centroid}, predicted {want}"
    np.testing.assert_allclose(img.depth[mask], tv.altitude_m - tall, atol=1e-3)
    water = img.instance == 0
    assert water.sum() + n == w * h
    np.testing.assert_allclose(img.depth[water], tv.altitude_m, atol=1e-3)
    # Every pixel centre maps back into the box footprint (within half a pixel diagonal).
    u_c, v_c = uu + 0.5, vv + 0.5
    left = (w / 2 - u_c) * mpp
    fwd = (h / 2 - v_c) * mpp
    wx = x + fwd * math.cos(heading) - left * math.sin(heading)
    wy = y + fwd * math.sin(heading) + left * math.cos(heading)
    slack = side / 2 + mpp * 0.71
    assert np.all(np.abs(wx - cx) <= slack) and np.all(np.abs(wy - cy) <= slack)


def test_top_view_config_scale() -> None:
    """The native orthographic camera samples at exactly metres_per_pixel around its centre."""
    cfg = TopViewConfig(resolution=(20, 10), metres_per_pixel=0.25, altitude_m=50.0)
    cam = top_view_from_config(cfg)
    pose = pose_matrices(np.array([100.0, 200.0, 50.0, 0.0, math.pi / 2, 0.0]))
    origins, dirs = cam.world_rays(pose)
    np.testing.assert_allclose(dirs, np.broadcast_to([0.0, 0.0, -1.0], dirs.shape), atol=1e-6)
    o = np.asarray(origins, dtype=np.float64).reshape(10, 20, 3)
    # Looking down with +x (east) at the top: u → −y (south), v → −x.
    np.testing.assert_allclose(np.diff(o[:, :, 1], axis=1), -0.25, atol=1e-4)
    np.testing.assert_allclose(np.diff(o[:, :, 0], axis=0), -0.25, atol=1e-4)
    np.testing.assert_allclose(o[:, :, :2].reshape(-1, 2).mean(axis=0), [100.0, 200.0], atol=1e-3)


# ------------------------------------------------------------------------------------------ depth vs LiDAR


@pytest.mark.parametrize("agent_id,frame", [("usv_a", 7), ("usv_b", 7), ("usv_a", 15)])
def test_depth_agrees_with_lidar(sim: Simulation, agent_id: str, frame: int) -> None:
    cap = sim.capture(frame, agents=[agent_id], radar=False)
    a = cap.agents[agent_id]
    assert a.lidar is not None and a.lidar_pose is not None
    pts = a.lidar
    cam, cfg, _ = sim.agent(agent_id).cameras["front"]
    w, h = cfg.resolution
    cp = a.camera_poses["front"]
    img = a.cameras["front"]
    # LiDAR frame → world → camera body → optical → pixel.
    pw = pts.xyz.astype(np.float64) @ a.lidar_pose[:3, :3].T + a.lidar_pose[:3, 3]
    body = (pw - cp[:3, 3]) @ cp[:3, :3]
    opt = body @ BODY_TO_OPTICAL.T
    fx, fy, cx, cy = cam.intrinsics
    z = opt[:, 2]
    ahead = z > 0.5
    u = np.where(ahead, fx * opt[:, 0] / np.where(ahead, z, 1) + cx, -1)
    v = np.where(ahead, fy * opt[:, 1] / np.where(ahead, z, 1) + cy, -1)
    inside = ahead & (u >= 0) & (u < w) & (v >= 0) & (v < h)
    idx = np.flatnonzero(inside)
    ui, vi = np.floor(u[idx]).astype(int), np.floor(v[idx]).astype(int)
    # Points the camera cannot see (parallax: LiDAR and camera sit at different places) are left out.
    to_pt = pw[idx] - cp[:3, 3]
    rng = np.linalg.norm(to_pt, axis=1)
    ray = to_pt / rng[:, None]
    vis = sim.ws.scene.cast_rays(np.broadcast_to(cp[:3, 3], ray.shape), ray)
    visible = vis.distance >= rng - np.maximum(0.05, 1e-3 * rng)
    assert visible.mean() > 0.8
    idx, ui, vi, ray, rng = idx[visible], ui[visible], vi[visible], ray[visible], rng[visible]
    normal = vis.normal[visible].astype(np.float64)
    assert len(idx) > 150, "enough points in view"
    # Pixels whose footprint holds an edge (silhouette, step, crease, a mast thinner than a pixel) are left out.
    edge, centre_normal = footprint_edges(sim.ws.scene, cam.intrinsics, cp, ui, vi)
    inner = ~edge
    # Most points are water returns over the W1 waves (the target's wake foam among them since the LiDAR sees it:
    # 857 points in view of usv_a's frame 7 before, 1,254 after), and half of those footprints hold a facet's
    # crease: at least 40 % of the points are left to judge.
    assert inner.mean() > 0.4

    # Tolerance: the pixel-centre ray is δ away from the point's ray. Along a surface at incidence θ the range
    # changes by about r·δ·tan θ over that angle, and the off-axis angle α by δ, so the depth r·cos α changes by
    # at most r·δ·(tan θ·cos α + sin α). θ is the larger of the incidences at the point and at the pixel centre;
    # ×2 covers curvature and second-order terms; 1 cm + 1e-4·r is float slack.
    centre = pixel_rays_world(cam.intrinsics, w, h, cp).reshape(h, w, 3)[vi, ui]
    delta = np.arccos(np.clip(np.sum(centre * ray, axis=1), -1.0, 1.0))
    assert delta.max() <= math.hypot(0.5, 0.5) / fx * 1.01 + 1e-9, "the point lies in the pixel's footprint"
    cos_i = np.minimum(np.abs(np.sum(normal * ray, axis=1)), np.abs(np.sum(centre_normal * centre, axis=1)))
    cos_i = np.clip(cos_i, 1e-3, 1.0)
    tan_i = np.sqrt(1 - cos_i**2) / cos_i
    cos_a = np.clip(ray @ cp[:3, 0], -1.0, 1.0)
    sin_a = np.sqrt(1 - cos_a**2)
    tol = 2.0 * rng * delta * (tan_i * cos_a + sin_a) + 1e-4 * rng + 0.01
    depth_pt = body[idx, 0]
    depth_px = img.depth[vi, ui].astype(np.float64)
    ok = np.abs(depth_px - depth_pt) <= tol
    assert ok[inner].mean() >= 0.98, f"depth agrees for {ok[inner].mean():.2%} of non-edge points"
    same_inst = img.instance[vi, ui] == pts.instance[idx]
    same_cls = img.semantic[vi, ui] == pts.semantic_class[idx]
    assert same_inst[inner].mean() >= 0.97, f"instance agrees for {same_inst[inner].mean():.2%}"
    assert same_cls[inner].mean() >= 0.97, f"class agrees for {same_cls[inner].mean():.2%}"
    # The check is about the target too, not only water.
    assert np.sum(pts.instance[idx] == sim.vessels[1].instance_id) > 20


# ------------------------------------------------------------------------------------------ misconfiguration


@pytest.mark.parametrize(
    "camera,field",
    [
        ({"hfov_deg": 180}, "hfov_deg"),
        ({"hfov_deg": 200}, "hfov_deg"),
        ({"hfov_deg": 0}, "hfov_deg"),
        ({"range_m": -5}, "range_m"),
        ({"resolution": [0, 10]}, "resolution"),
        ({"outputs": ["rgb", "normals"]}, "outputs"),
        ({"lens": "fisheye"}, "lens"),
    ],
)
def test_camera_misconfig_names_the_field(make_scenario: Any, camera: dict[str, Any], field: str) -> None:
    sc = make_scenario()
    sc["rigs"]["r"]["cameras"][0].update(camera)
    with pytest.raises(mmusv.ConfigError, match=rf"rigs\.r\.cameras\[0\]\.{field}"):
        Simulation(sc)


def test_top_view_misconfig_names_the_field(make_scenario: Any) -> None:
    sc = make_scenario()
    sc["rigs"]["r"]["top_view"]["outputs"] = ["rgb", "bev"]
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.r\.top_view\.outputs"):
        Simulation(sc)
    sc = make_scenario()
    sc["rigs"]["r"]["top_view"]["metres_per_pixel"] = 0
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.r\.top_view\.metres_per_pixel"):
        Simulation(sc)


def test_native_camera_misconfig_names_the_field() -> None:
    with pytest.raises(mmusv.errors.ConfigError, match=r"camera\.hfov_deg"):
        core.Camera(rgb=False, width=8, height=8, hfov=math.pi)
    with pytest.raises(mmusv.errors.ConfigError, match=r"camera\.resolution"):
        core.Camera(rgb=False, width=0, height=8, hfov=1.0)
    with pytest.raises(mmusv.errors.ConfigError, match=r"camera\.range_m"):
        core.Camera(rgb=False, width=8, height=8, hfov=1.0, range_max=-1.0)
    with pytest.raises(mmusv.errors.ConfigError, match="metres_per_pixel"):
        core.Camera(rgb=False, width=8, height=8, metres_per_pixel=0.0)
    with pytest.raises(mmusv.errors.ConfigError, match="hfov"):
        core.Camera(rgb=False, width=8, height=8, hfov=1.0, metres_per_pixel=1.0)


def test_sea_detail_bands_change_only_the_water_colours_near_the_camera() -> None:
    """The sea surface's detail bands (``set_wave_surface(detail=...)``) are shading only: depth and labels are the
    same with and without, and the far water's colours within a level; the near water's colours change (its short
    waves drawn as normals rather than roughness)."""
    from mmusv.world.sea_state import sea_spec_for_preset

    s = plane_scene(2000.0)
    s.set_sea(0)
    cam = core.Camera(width=160, height=96, rgb=True, hfov=math.radians(90))
    pose = pose_matrices(np.array([0.0, 0.0, 2.5, 0.0, 0.12, 0.0]))
    images = []
    for detail in (False, True):
        s.set_wave_surface(sea_spec_for_preset("W1"), scenario_seed=3, time_s=5.0, foci=np.zeros((1, 2)), detail=detail)
        images.append(render(cam, s, pose=pose, env=sensor_env(), seed=1))
    plain, fine = images
    for name in ("depth", "semantic", "instance"):
        assert np.array_equal(getattr(plain, name), getattr(fine, name)), name
    assert plain.rgb is not None and fine.rgb is not None
    near = np.isfinite(plain.depth) & (plain.depth < 15.0)
    far = np.isfinite(plain.depth) & (plain.depth > 70.0)  # the finest tiles end within 40 + 16√2 m
    assert near.sum() > 1000 and far.sum() > 400
    diff = np.abs(plain.rgb.astype(int) - fine.rgb.astype(int)).max(axis=2)
    assert (diff[near] > 0).mean() > 0.5, "the near water shows its short waves"
    # Beyond the finest tiles the water itself is the same; its colours move by a level at most, through the
    # glossy reflections, whose lobe there reaches down the image into the near water (glossy.rs). That level can
    # flip whether a pixel between two anchors takes their mean or is shaded on its own (radiance.rs: anchors
    # within 2 levels are alike), so a rare pixel shows its own shade in one image and the mean in the other.
    assert (diff[far] > 1).mean() < 0.01, "beyond the finest tiles the colours stay"


@pytest.mark.parametrize("preset", ["W1", "W3"])
def test_a_top_view_shades_every_level_of_the_sea_alike(preset: str) -> None:
    """An orthographic top view sees the water with one footprint (0.5 m) across its whole image, while the sea
    is sampled at 1 m within about 40 m of its USV and coarser beyond. With ``fine_m`` (what the simulation sets
    to its top views' reach) the texture the image shows — the pixel-scale contrast left after a 5-pixel box blur
    — is the same near the USV and 50–64 m out (0.89 and 1.13 times); without, the finest tiles stand out as a
    square of other texture (2.4 and 4.2 times the contrast at W1 and W3)."""
    from mmusv.world.sea_state import sea_spec_for_preset
    from scipy.ndimage import uniform_filter

    s = plane_scene(2000.0)
    s.set_sea(0)
    top = core.Camera(width=256, height=256, rgb=True, metres_per_pixel=0.5, range_max=500.0)
    pose = pose_matrices(np.array([0.0, 0.0, 120.0, 0.0, math.pi / 2, 0.0]))
    ratios = []
    for fine_m in (0.0, 91.0):
        sea = sea_spec_for_preset(preset)
        s.set_wave_surface(sea, scenario_seed=3, time_s=5.0, foci=np.zeros((1, 2)), fine_m=fine_m)
        rgb = render(top, s, pose=pose, env=sensor_env(), seed=1).rgb
        assert rgb is not None
        lum = rgb.astype(float).mean(axis=2)
        texture = lum - uniform_filter(lum, 5)
        v, u = np.mgrid[0:256, 0:256]
        r = np.hypot(v - 127.5, u - 127.5) * 0.5  # metres from the USV
        calm = np.abs(texture) < 20  # whitecaps' edges left out
        near = np.sqrt((texture[(r > 4) & (r < 28) & calm] ** 2).mean())
        ring = np.sqrt((texture[(r > 50) & (r < 64) & calm] ** 2).mean())
        ratios.append(near / ring)
    without, with_fine = ratios
    assert 0.75 < with_fine < 1.33, ratios
    assert without > 1.6, ratios
