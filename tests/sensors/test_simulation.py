"""Capturing frames with :class:`mmusv.simulation.Simulation`: determinism, one shared state per frame,
sensor poses from the mounts, and configuration errors that name the field.

The bundled scenario (``scenarios/island_port_waves.yaml``) is used with a shrunk rig (one 160×120 camera, a
128×128 top view, no radar); the other tests use the small scenario of ``conftest.py``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mmusv._native import core
from mmusv.sensors import CameraImages, LidarPoints
from mmusv.sensors.camera import BODY_TO_OPTICAL
from mmusv.simulation import FrameCapture, Simulation, WorldState, sensor_seed
from mmusv.world.build import pose_matrices
from mmusv.world.vessels import get_asset

BUNDLED = Path(__file__).resolve().parents[2] / "scenarios" / "island_port_waves.yaml"
SMALL_RIG = {
    "cameras": [{"name": "front", "resolution": [160, 120], "mount": {"point": "camera_front"}}],
    "top_view": {"resolution": [128, 128]},
    "radar": None,
}
LIDAR_FIELDS = ("xyz", "range", "intensity", "ring", "azimuth", "semantic_class", "instance", "ray_index")


def bundled(**rig: Any) -> dict[str, Any]:
    """The bundled scenario as a dict with the small rig (plus ``rig`` overrides) for every USV."""
    d: dict[str, Any] = yaml.safe_load(BUNDLED.read_text(encoding="utf-8"))
    d["rigs"] = {"usv_standard": {**SMALL_RIG, **rig}}
    return d


def assert_same_capture(a: FrameCapture, b: FrameCapture) -> None:
    assert a.frame == b.frame and a.time_s == b.time_s
    for name in ("poses", "velocities", "box_centers", "matrices"):
        assert np.array_equal(getattr(a.world, name), getattr(b.world, name)), name
    assert a.agents.keys() == b.agents.keys()
    for aid, ca in a.agents.items():
        cb = b.agents[aid]
        assert isinstance(ca.lidar, LidarPoints) and isinstance(cb.lidar, LidarPoints)
        for f in LIDAR_FIELDS:
            assert np.array_equal(getattr(ca.lidar, f), getattr(cb.lidar, f)), f"{aid}.lidar.{f}"
        assert ca.lidar_pose is not None and cb.lidar_pose is not None
        assert np.array_equal(ca.lidar_pose, cb.lidar_pose)
        assert ca.cameras.keys() == cb.cameras.keys()
        pairs: list[tuple[str, CameraImages | None, CameraImages | None]] = [
            (f"camera/{n}", ca.cameras[n], cb.cameras[n]) for n in ca.cameras
        ]
        pairs.append(("top_view", ca.top_view, cb.top_view))
        for name, ia, ib in pairs:
            assert ia is not None and ib is not None
            for f in ("depth", "semantic", "instance"):
                assert np.array_equal(getattr(ia, f), getattr(ib, f)), f"{aid}.{name}.{f}"
            assert (ia.rgb is None) == (ib.rgb is None)
            if ia.rgb is not None:
                assert np.array_equal(ia.rgb, ib.rgb), f"{aid}.{name}.rgb"
        for n in ca.camera_poses:
            assert np.array_equal(ca.camera_poses[n], cb.camera_poses[n])


# ------------------------------------------------------------------------------------------ determinism


@pytest.fixture(scope="module")
def bundled_pair() -> tuple[Simulation, Simulation]:
    return Simulation(bundled()), Simulation(bundled())


def test_bundled_scenario_capture_is_deterministic(bundled_pair: tuple[Simulation, Simulation]) -> None:
    s1, s2 = bundled_pair
    a = s1.capture(3, radar=False)
    b = s2.capture(3, radar=False)
    assert set(a.agents) == {"usv_1", "usv_2", "usv_3", "usv_4"}
    assert_same_capture(a, b)
    for cap in a.agents.values():
        assert cap.lidar is not None and len(cap.lidar) > 100
        assert cap.cameras["front"].depth.shape == (120, 160)
        assert cap.top_view is not None and cap.top_view.depth.shape == (128, 128)
        assert cap.radar is None
    # Another frame is another state.
    c = s1.capture(4, radar=False)
    assert not np.array_equal(c.world.poses, a.world.poses)
    assert not np.array_equal(c.agents["usv_1"].cameras["front"].depth, a.agents["usv_1"].cameras["front"].depth)


def test_capture_does_not_depend_on_history(bundled_pair: tuple[Simulation, Simulation]) -> None:
    """The state of frame k is a pure function of (scenario, seed, k): visiting other frames first changes nothing."""
    s1, s2 = bundled_pair
    s1.capture(11, radar=False)
    s1.capture(0, radar=False)
    a = s1.capture(5, radar=False)
    b = Simulation(bundled()).capture(5, radar=False)
    assert_same_capture(a, b)
    s2.capture(5, agents=["usv_2"], radar=False)
    only = s2.capture(5, agents=["usv_2"], radar=False)
    assert set(only.agents) == {"usv_2"}
    lp_a, lp_o = a.agents["usv_2"].lidar, only.agents["usv_2"].lidar
    assert lp_a is not None and lp_o is not None
    for f in LIDAR_FIELDS:
        assert np.array_equal(getattr(lp_a, f), getattr(lp_o, f)), f


def test_threads_sharing_a_simulation_each_get_their_frame() -> None:
    """Two threads capturing different frames from one simulation: each capture is its own frame's (before, a
    thread could capture on the scene the other had just moved to its frame, silently)."""
    import threading

    d = bundled()
    ref = Simulation(d)
    want = {k: ref.capture(k) for k in range(1, 5)}
    shared = Simulation(d)
    got: dict[int, FrameCapture] = {}

    def work(frames: list[int]) -> None:
        for k in frames:
            got[k] = shared.capture(k)
            shared.prefetch_frame(min(k + 3, shared.frames - 1))

    threads = [threading.Thread(target=work, args=(list(range(start, 5, 2)),)) for start in (1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, cap in want.items():
        assert_same_capture(got[k], cap)


def test_scenario_seed_drives_the_noise() -> None:
    d = bundled()
    d["seed"] = 12
    other = Simulation(d).capture(3, agents=["usv_1"], radar=False)
    base = Simulation(bundled()).capture(3, agents=["usv_1"], radar=False)
    la, lb = base.agents["usv_1"].lidar, other.agents["usv_1"].lidar
    assert la is not None and lb is not None
    assert not (len(la) == len(lb) and np.array_equal(la.range, lb.range)), "another seed, other noise"
    assert sensor_seed(11, frame=3, agent=0, sensor="lidar") != sensor_seed(12, frame=3, agent=0, sensor="lidar")
    assert sensor_seed(11, frame=3, agent=0, sensor="lidar") != sensor_seed(11, frame=4, agent=0, sensor="lidar")
    assert sensor_seed(11, frame=3, agent=0, sensor="camera", index=0) != sensor_seed(
        11, frame=3, agent=0, sensor="camera", index=1
    )


_HASH_SCRIPT = """
import hashlib, json, sys
import numpy as np
from mmusv.simulation import Simulation

def capture_digest(sim, frame):
    cap = sim.capture(frame, radar=False)
    h = hashlib.sha256()
    for aid, a in sorted(cap.agents.items()):
        for f in ("xyz", "range", "intensity", "ring", "azimuth", "semantic_class", "instance", "ray_index"):
            h.update(np.ascontiguousarray(getattr(a.lidar, f)).tobytes())
        images = [c for _, c in sorted(a.cameras.items())] + [a.top_view]
        for img in images:
            for f in ("depth", "semantic", "instance", "rgb"):
                v = getattr(img, f)
                h.update(b"-" if v is None else np.ascontiguousarray(v).tobytes())
    return h.hexdigest()

if __name__ == "__main__":
    print(capture_digest(Simulation(json.loads(sys.stdin.read())), int(sys.argv[1])))
"""


def test_capture_is_independent_of_the_thread_count(make_scenario: Any, sim: Simulation, tmp_path: Path) -> None:
    """Counter-based noise and per-ray results: one worker thread gives bit-identical frames."""
    import json
    import os
    import runpy
    import subprocess
    import sys

    script = tmp_path / "digest.py"
    script.write_text(_HASH_SCRIPT, encoding="utf-8")
    here = runpy.run_path(str(script))["capture_digest"](sim, 5)
    env = {**os.environ, "RAYON_NUM_THREADS": "1"}
    out = subprocess.run(
        [sys.executable, str(script), "5"],
        input=json.dumps(make_scenario()),
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    assert out.stdout.strip() == here


@pytest.mark.parametrize("agent_id", ["usv_a", "usv_b"])
def test_capture_applies_the_water_model_with_the_scenario_waves(sim: Simulation, agent_id: str) -> None:
    """Over the flat sea (no displaced surface), water returns in a capture follow the rig's empirical water model
    at the environment's wave height (W1: 1.5 m). (Over the physical sea they follow ``sensors/lidar_water.rs``,
    tested there and in tests/test_wave_occlusion.py.)"""
    sea = sim.sea
    sim.set_sea_surface(None)
    try:
        _check_flat_water_model(sim, agent_id)
    finally:
        sim.set_sea_surface(sea)


def _check_flat_water_model(sim: Simulation, agent_id: str) -> None:
    cap = sim.capture(2, agents=[agent_id], radar=False)
    ac = cap.agents[agent_id]
    agent = sim.agent(agent_id)
    cfg = agent.rig.lidar
    assert cfg is not None and ac.lidar is not None and ac.lidar_pose is not None
    wave = sim.environment.wave_height_m
    assert wave == pytest.approx(1.5)
    p = min(1.0, cfg.water_probability + cfg.water_probability_per_wave_m * wave)
    reach = cfg.water_range_m + cfg.water_range_per_wave_m * wave
    # Re-cast the pattern with the scene to know which rays reach open water, and how far.
    dirs = np.asarray(agent.lidar.pattern(), dtype=np.float64) @ ac.lidar_pose[:3, :3].T
    hits = sim.ws.scene.cast_rays(np.broadcast_to(ac.lidar_pose[:3, 3], dirs.shape), dirs, max_range=cfg.range_m)
    water_ray = (hits.semantic_class == 1) & (hits.distance >= cfg.range_min_m)
    eligible = water_ray & (hits.distance <= reach)
    got = ac.lidar.semantic_class == 1
    assert np.all(eligible[ac.lidar.ray_index[got]]), "water returns only within the water range"
    n, k = int(eligible.sum()), int(got.sum())
    assert n > 500 and abs(k - n * p) < 4.5 * math.sqrt(n * p * (1 - p)), f"{k} water returns of {n} rays, p = {p}"
    # Other surfaces return unless the (clear, 20 km visibility) air loses them: probability exp(−2σr).
    solid = (hits.semantic_class != 1) & np.isfinite(hits.distance) & (hits.distance >= cfg.range_min_m)
    sigma = sim.environment.weather.extinction_per_m  # rain's drops, when it rains, are in the visibility
    tau = np.exp(-2 * sigma * hits.distance[solid].astype(np.float64))
    kept = np.isin(np.flatnonzero(solid), ac.lidar.ray_index)
    assert abs(kept.sum() - tau.sum()) <= 4.5 * math.sqrt(np.sum(tau * (1 - tau))) + 1
    assert np.isin(ac.lidar.ray_index[~got], np.flatnonzero(solid)).all()


def test_fallback_mounts_on_assets_without_mount_points(make_scenario: Any) -> None:
    """A USV on an asset without mount points gets its sensors 0.5 m above the hull's top, pointing where the
    mount name says (camera_left: +90°)."""
    sc = make_scenario()
    sc["vessels"][2]["asset"] = "fishing_boat_12m"
    s = Simulation(sc)
    asset = get_asset("fishing_boat_12m")
    assert not asset.mounts
    agent = s.agent("usv_b")
    top = float(asset.bbox[1, 2]) + 0.5
    assert agent.lidar_mount is not None
    np.testing.assert_allclose(agent.lidar_mount, pose_matrices(np.array([0, 0, top, 0, 0, 0])), atol=1e-12)
    np.testing.assert_allclose(
        agent.cameras["aux"][2], pose_matrices(np.array([0, 0, top, 0, 0, math.pi / 2])), atol=1e-12
    )
    cap = s.capture(0, agents=["usv_b"], radar=False)
    lidar = cap.agents["usv_b"].lidar
    assert lidar is not None and not np.any(lidar.instance == s.vessels[2].instance_id), "no returns from its own hull"


# ------------------------------------------------------------------------------------------ one state per frame


def in_body_box(
    points_world: np.ndarray, state: WorldState, vessel: int, centre: np.ndarray, size: np.ndarray, margin: float
) -> np.ndarray:
    """``(N,)`` bool: world points inside vessel ``vessel``'s box (body frame, ±``margin`` metres) in ``state``."""
    m = state.matrices[vessel]
    body = (points_world - m[:3, 3]) @ m[:3, :3]
    inside: np.ndarray = np.all(np.abs(body - centre) <= size / 2 + margin, axis=1)
    return inside


class SurfaceDistance:
    """Distance from world points to a vessel's mesh placed at its pose in a world state (Open3D)."""

    def __init__(self, asset_name: str) -> None:
        o3d = pytest.importorskip("open3d")
        mesh = get_asset(asset_name).mesh
        self._scene = o3d.t.geometry.RaycastingScene()
        self._scene.add_triangles(
            o3d.core.Tensor(np.asarray(mesh.vertices, dtype=np.float32)),
            o3d.core.Tensor(np.asarray(mesh.faces, dtype=np.uint32)),
        )
        self._o3d = o3d

    def __call__(self, points_world: np.ndarray, state: WorldState, vessel: int) -> np.ndarray:
        m = state.matrices[vessel]
        body = ((points_world - m[:3, 3]) @ m[:3, :3]).astype(np.float32)
        d: np.ndarray = self._scene.compute_distance(self._o3d.core.Tensor(body)).numpy().astype(np.float64)
        return d


@pytest.mark.parametrize("frame", [3, 12])
def test_all_sensors_see_the_frame_state(sim: Simulation, frame: int) -> None:
    """Every sensor of every USV sees the tug on its mesh at this frame's world-state pose (and not at the pose
    of three frames earlier, 1.8 m back): LiDAR points, camera pixels back-projected with their depth, top-view
    pixels at (pixel centre, altitude − depth)."""
    cap = sim.capture(frame, radar=False)
    state = cap.world
    assert state.frame == frame and state.time_s == pytest.approx(frame / 5.0)
    earlier = sim.world_state(frame - 3)
    tgt_index = 1
    tgt = sim.vessels[tgt_index]
    assert tgt.id == "tgt" and tgt.role == "target"
    box = (tgt.box_center_body, tgt.box_size)
    dist = SurfaceDistance(tgt.asset)
    # The scene holds exactly the world-state poses.
    for i, v in enumerate(sim.vessels[: len(sim.scenario.vessels)]):
        np.testing.assert_allclose(sim.ws.scene.instance_pose(v.instance_id), state.matrices[i], atol=1e-9)
    # The world-state box centre is the body box centre moved by the pose.
    m = state.matrices[tgt_index]
    np.testing.assert_allclose(state.box_centers[tgt_index], m[:3, :3] @ tgt.box_center_body + m[:3, 3], atol=1e-9)

    def check(world: np.ndarray, tol: float | np.ndarray, what: str) -> None:
        assert in_body_box(world, state, tgt_index, *box, margin=0.02).all(), what
        d_now = dist(world, state, tgt_index)
        assert np.all(d_now <= tol), f"{what}: up to {d_now.max():.3f} m off the tug's surface"
        assert np.quantile(dist(world, earlier, tgt_index), 0.9) > 0.2, f"{what}: the check tells frames apart"

    seen = []
    for aid, ac in cap.agents.items():
        # LiDAR (no range noise in this rig).
        assert ac.lidar is not None and ac.lidar_pose is not None
        on = ac.lidar.instance == tgt.instance_id
        assert np.all(ac.lidar.semantic_class[on] == tgt.semantic_class)
        if on.sum() >= 20:
            pw = ac.lidar.xyz[on].astype(np.float64) @ ac.lidar_pose[:3, :3].T + ac.lidar_pose[:3, 3]
            check(pw, 0.01, f"{aid}/lidar")
            seen.append(f"{aid}/lidar")
        # Cameras: pixel-centre ray scaled to the depth (optical z = depth).
        for name, img in ac.cameras.items():
            cam, _, _ = sim.agent(aid).cameras[name]
            mask = img.instance == tgt.instance_id
            assert np.all(img.semantic[mask] == tgt.semantic_class)
            if mask.sum() < 20:
                continue
            cp = ac.camera_poses[name]
            fx, fy, cx, cy = cam.intrinsics
            vv, uu = np.nonzero(mask)
            opt = np.stack([(uu + 0.5 - cx) / fx, (vv + 0.5 - cy) / fy, np.ones(len(uu))], axis=1)
            depth = img.depth[vv, uu].astype(np.float64)
            world = (opt * depth[:, None]) @ BODY_TO_OPTICAL @ cp[:3, :3].T + cp[:3, 3]
            check(world, 0.01 + 1e-4 * depth, f"{aid}/{name}")
            seen.append(f"{aid}/{name}")
        # Top view: camera body (depth, left, up) = (depth, (W/2 − u)·m, (H/2 − v)·m).
        tv, tvc = ac.top_view, sim.agent(aid).rig.top_view
        assert tv is not None and tvc is not None and ac.top_view_pose is not None
        mask = tv.instance == tgt.instance_id
        if mask.sum() >= 20:
            w, h = tvc.resolution
            mpp = tvc.metres_per_pixel
            vv, uu = np.nonzero(mask)
            local = np.stack(
                [tv.depth[vv, uu].astype(np.float64), (w / 2 - (uu + 0.5)) * mpp, (h / 2 - (vv + 0.5)) * mpp], axis=1
            )
            world = local @ ac.top_view_pose[:3, :3].T + ac.top_view_pose[:3, 3]
            check(world, 0.02, f"{aid}/top_view")
            seen.append(f"{aid}/top_view")
    assert len(seen) >= 5, f"the tug is seen by (nearly) every sensor: {seen}"


def test_sensor_poses_follow_mounts(sim: Simulation) -> None:
    cap = sim.capture(6, radar=False)
    state = cap.world
    for agent in sim.agents:
        ac = cap.agents[agent.id]
        asset = get_asset(agent.vessel.asset)
        body = state.matrices[agent.index]
        mp = asset.mounts["lidar"]
        assert ac.lidar_pose is not None
        np.testing.assert_allclose(ac.lidar_pose[:3, 3], body[:3, :3] @ np.array(mp.xyz) + body[:3, 3], atol=1e-9)
        np.testing.assert_allclose(ac.lidar_pose[:3, :3], body[:3, :3], atol=1e-12)  # LiDAR mount not rotated
        fp = asset.mounts["camera_front"]
        np.testing.assert_allclose(
            ac.camera_poses["front"][:3, 3], body[:3, :3] @ np.array(fp.xyz) + body[:3, 3], atol=1e-9
        )
        if "aux" in ac.camera_poses:  # on the camera_left point: looks 90° to port
            np.testing.assert_allclose(ac.camera_poses["aux"][:3, 0], body[:3, 1], atol=1e-9)
        # Top view: level, altitude above the USV's (x, y), looking straight down.
        tv = agent.rig.top_view
        assert tv is not None and ac.top_view_pose is not None
        x, y, _, _, _, yaw = state.poses[agent.index]
        np.testing.assert_allclose(ac.top_view_pose[:3, 3], [x, y, tv.altitude_m], atol=1e-9)
        np.testing.assert_allclose(ac.top_view_pose[:3, 0], [0.0, 0.0, -1.0], atol=1e-12)
        up_in_image = ac.top_view_pose[:3, 2]  # camera body +z = image up (−v)
        heading = yaw if tv.orientation == "heading_up" else math.pi / 2
        np.testing.assert_allclose(up_in_image, [math.cos(heading), math.sin(heading), 0.0], atol=1e-12)


def test_capture_carries_the_sensor_mounts(sim: Simulation) -> None:
    """Every sensor of every USV is in ``AgentCapture.sensors`` with its mount (sensor → body) and pose (sensor →
    world) = body · mount; the mounts are the asset's mount points; the top view's mount is body⁻¹ · its pose."""
    cap = sim.capture(4, sensors=("lidar",))
    for agent in sim.agents:
        ac = cap.agents[agent.id]
        body = cap.world.matrices[agent.index]
        assert ac.body is not None and np.array_equal(ac.body, body)
        assert set(ac.sensors) == {"lidar", "top_view", *(f"camera/{c.name}" for c in agent.rig.cameras)}
        asset = get_asset(agent.vessel.asset)
        lidar = ac.sensors["lidar"]
        np.testing.assert_allclose(lidar.mount[:3, 3], asset.mounts["lidar"].xyz, atol=1e-12)
        for key, sm in ac.sensors.items():
            np.testing.assert_allclose(sm.pose, body @ sm.mount, atol=1e-9, err_msg=key)
        assert ac.lidar_pose is not None and np.array_equal(ac.sensors["lidar"].pose, ac.lidar_pose)
        # Cameras not captured this time still have their pose; the top view hangs level above the USV.
        assert not ac.cameras and "camera/front" in ac.sensors
        tv = ac.sensors["top_view"]
        np.testing.assert_allclose(tv.pose[:3, 0], [0.0, 0.0, -1.0], atol=1e-12)


# ------------------------------------------------------------------------------------------ misconfiguration


def winding_number(vertices: np.ndarray, faces: np.ndarray, p: np.ndarray) -> float:
    """Generalised winding number of a closed mesh around ``p`` (1 inside, 0 outside; Van Oosterom–Strackee)."""
    a, b, c = (vertices[faces[:, k]].astype(np.float64) - p for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (
        la * lb * lc
        + np.einsum("ij,ij->i", a, b) * lc
        + np.einsum("ij,ij->i", b, c) * la
        + np.einsum("ij,ij->i", c, a) * lb
    )
    return float(2 * np.arctan2(num, den).sum() / (4 * np.pi))


def test_mount_inside_hull_is_refused(make_scenario: Any) -> None:
    """A camera at 1 m above the WAM-V origin is inside its hull (winding number 1): refused, naming the mount."""
    asset = get_asset("usv_wamv")
    assert winding_number(asset.mesh.vertices, asset.mesh.faces, np.array([0.0, 0.0, 1.0])) == pytest.approx(
        1.0, abs=1e-6
    )
    sc = make_scenario()
    sc["rigs"]["rn"]["cameras"][0]["mount"] = {"xyz": [0.0, 0.0, 1.0]}
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.rn\.cameras\[0\]\.mount"):
        Simulation(sc)
    sc = make_scenario()
    sc["rigs"]["rn"]["lidar"]["mount"] = {"xyz": [0.0, 0.0, 1.0]}
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.rn\.lidar\.mount"):
        Simulation(sc)


@pytest.mark.parametrize("z", [0.0, 1.0, 2.0])
def test_mount_inside_monohull_is_refused(make_scenario: Any, z: float) -> None:
    """``{xyz: [0, 0, z]}`` without a point is relative to the vessel origin (midship, waterline): inside the
    patrol boat's hull for these z (winding number 1), so the Simulation must refuse it, naming the mount."""
    asset = get_asset("usv_patrol_12m")
    assert winding_number(asset.mesh.vertices, asset.mesh.faces, np.array([0.0, 0.0, z])) == pytest.approx(
        1.0, abs=1e-6
    )
    sc = make_scenario()
    assert sc["vessels"][0]["asset"] == "usv_patrol_12m" and sc["vessels"][0]["rig"] == "r"
    sc["rigs"]["r"]["cameras"][0]["mount"] = {"xyz": [0.0, 0.0, z]}
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.r\.cameras\[0\]\.mount"):
        Simulation(sc)


def test_mount_outside_hull_is_accepted(make_scenario: Any) -> None:
    """Between the WAM-V's pontoons at the waterline is outside the hull (winding number 0)."""
    asset = get_asset("usv_wamv")
    assert winding_number(asset.mesh.vertices, asset.mesh.faces, np.array([0.0, 0.0, 0.0])) == pytest.approx(
        0.0, abs=1e-6
    )
    sc = make_scenario()
    sc["rigs"]["rn"]["cameras"][0]["mount"] = {"xyz": [0.0, 0.0, 3.0]}
    Simulation(sc)


@pytest.mark.parametrize(
    "lidar,pattern",
    [
        ({"channels": 0}, r"rigs\.r\.lidar\.channels"),
        ({"range_m": -10}, r"rigs\.r\.lidar\.range_m"),
        ({"range_m": 0}, r"rigs\.r\.lidar\.range_m"),
        ({"range_min_m": 250}, r"rigs\.r\.lidar\b.*range_min_m"),
        ({"range_min_m": 200}, r"rigs\.r\.lidar\b.*range_min_m"),
        ({"range_min_m": -1}, r"rigs\.r\.lidar\.range_min_m"),
        ({"dropout": 1.5}, r"rigs\.r\.lidar\.dropout"),
        ({"vertical_fov_deg": [-95, 10]}, r"rigs\.r\.lidar\.vertical_fov_deg"),
        ({"elevations_deg": [1.0, 2.0]}, r"rigs\.r\.lidar\b.*elevations_deg"),
        ({"points_per_second": 0}, r"rigs\.r\.lidar\.points_per_second"),
        ({"channel": 16}, r"rigs\.r\.lidar\.channel\b"),
        ({"mount": {"point": "lidar", "xyz": [0, 0, float("nan")]}}, r"rigs\.r\.lidar\.mount\.xyz"),
    ],
)
def test_lidar_misconfig_names_the_field(make_scenario: Any, lidar: dict[str, Any], pattern: str) -> None:
    sc = make_scenario()
    sc["rigs"]["r"]["lidar"].update(lidar)
    with pytest.raises(mmusv.ConfigError, match=pattern):
        Simulation(sc)


@pytest.mark.parametrize(
    "rig,pattern",
    [
        ({"lidars": {}}, r"rigs\.r\.lidars"),
        ({"sonar": None}, r"rigs\.r\.sonar"),
        ({"cameras": [{"name": "a"}, {"name": "a"}]}, r"rigs\.r\b.*repeated: a"),
        # front and FRONT: one export folder on a file system that ignores case (they were both accepted)
        ({"cameras": [{"name": "front"}, {"name": "FRONT"}]}, r"rigs\.r\b.*than case: 'front' and 'FRONT'"),
        ({"cameras": [{"name": "bad name!"}]}, r"rigs\.r\.cameras\[0\]\.name"),
        # 0 in the native sensors' 32-bit floats: refused as "range_m = 0", though the file said 1e-300
        ({"cameras": [{"name": "a", "range_m": 1e-300}]}, r"rigs\.r\.cameras\[0\]\.range_m = 1e-300: .*0\.01"),
        ({"top_view": {"orientation": "south_up"}}, r"rigs\.r\.top_view\.orientation"),
    ],
)
def test_rig_misconfig_names_the_field(make_scenario: Any, rig: dict[str, Any], pattern: str) -> None:
    sc = make_scenario()
    sc["rigs"]["r"].update(rig)
    with pytest.raises(mmusv.ConfigError, match=pattern):
        Simulation(sc)


def test_unknown_rig_name_is_an_error(make_scenario: Any) -> None:
    sc = make_scenario()
    sc["vessels"][0]["rig"] = "nope"
    with pytest.raises(mmusv.ConfigError, match="nope"):
        Simulation(sc)


def test_native_lidar_misconfig_names_the_field() -> None:
    ok: dict[str, Any] = {
        "elevations": [0.0, 0.1],
        "azimuth_steps": 16,
        "range_min": 0.5,
        "range_max": 100.0,
        "range_noise_std": 0.0,
        "dropout": 0.0,
        "water_probability": 0.1,
        "water_probability_per_wave_m": 0.1,
        "water_range_m": 20.0,
        "water_range_per_wave_m": 10.0,
        "beam_divergence": 3e-3,
    }
    core.Lidar(**ok)
    for change, field in [
        ({"elevations": []}, "lidar.channels"),
        ({"range_max": -1.0}, "lidar.range_m"),
        ({"range_min": 200.0}, "lidar.range_m"),
        ({"range_min": -1.0}, "lidar.range_min_m"),
        ({"dropout": 2.0}, "lidar.dropout"),
        ({"water_probability": -0.1}, "lidar.water_probability"),
        ({"range_noise_std": float("nan")}, "lidar.range_noise_std_m"),
        ({"azimuth_steps": 0}, "lidar.azimuth_steps"),
        ({"beam_divergence": -1e-3}, "lidar.beam_divergence"),
        ({"beam_divergence": float("inf")}, "lidar.beam_divergence"),
        ({"elevations": [0.0, math.pi / 2]}, "elevations"),
    ]:
        with pytest.raises(mmusv.errors.ConfigError, match=field.replace(".", r"\.")):
            core.Lidar(**{**ok, **change})


def test_frame_outside_acquisition(sim: Simulation) -> None:
    with pytest.raises(mmusv.ConfigError, match="frame"):
        sim.capture(sim.frames)
    with pytest.raises(mmusv.ConfigError, match="frame"):
        sim.capture(-1)
    with pytest.raises(mmusv.ConfigError, match="no USV named"):
        sim.agent("tgt")


# ------------------------------------------------------------------------------------------ sampling ahead


def _surface_bits(sim: Simulation) -> tuple[bytes, float | None]:
    """The heights of the scene's wave surface on a 2 m grid over its USVs' water, and its crest bound."""
    g = np.arange(-300.0, 300.0, 2.0)
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2).astype(np.float32)
    return sim.ws.scene.wave_heights(xy).tobytes(), sim.ws.scene.wave_top


def test_a_frame_sampled_ahead_sets_the_same_surface(make_scenario: Any) -> None:
    """``prefetch_frame`` samples the next frame's surface on a thread of its own: the frame then set has the
    surface it would have had without (every height bit for bit), a prefetch of another frame or with other
    arguments is left unused, and the captures are the same."""
    plain, ahead = Simulation(make_scenario()), Simulation(make_scenario())
    assert plain.sea is not None and plain.sea.hs_m > 0
    for frame, detail in ((3, True), (4, False)):
        plain.set_frame(frame, shading_detail=detail)
        ahead.prefetch_frame(frame, shading_detail=detail)
        ahead.set_frame(frame, shading_detail=detail)
        assert _surface_bits(ahead) == _surface_bits(plain), frame
        assert plain.ws.scene.wave_top is not None
    # Sampled ahead for frame 6 (or frame 5 without the slopes): frame 5 is sampled afresh, the same.
    plain.set_frame(5)
    for other in ({"frame": 6}, {"frame": 5, "shading_detail": False}):
        ahead.prefetch_frame(**other)
        state = ahead.set_frame(5)
        assert _surface_bits(ahead) == _surface_bits(plain)
        assert state.frame == 5 and np.array_equal(state.matrices, plain.world_state(5).matrices)
    # What a recording does: capture, sample the next frame ahead, capture it.
    ahead.capture(1)
    ahead.prefetch_frame(2, shading_detail=ahead.renders())
    assert_same_capture(ahead.capture(2), plain.capture(2))


def test_sampling_ahead_checks_its_arguments_and_skips_what_needs_none(make_scenario: Any) -> None:
    sim = Simulation(make_scenario())
    assert sim.sea is not None
    with pytest.raises(mmusv.InputError, match="radius_m"):
        sim.ws.scene.prefetch_wave_surface(sim.sea, scenario_seed=1, time_s=0.0, foci=[[0.0, 0.0]], radius_m=-1.0)
    with pytest.raises(mmusv.InputError, match="foci"):
        sim.ws.scene.prefetch_wave_surface(sim.sea, scenario_seed=1, time_s=0.0, foci=[[0.0, np.nan]])
    for fine_m in (-1.0, np.inf, np.nan):
        with pytest.raises(mmusv.InputError, match="fine_m"):
            sim.ws.scene.set_wave_surface(sim.sea, scenario_seed=1, time_s=0.0, foci=[[0.0, 0.0]], fine_m=fine_m)
    sim.prefetch_frame(sim.frames)  # past the acquisition: nothing to sample
    sim.prefetch_frame(-1)
    sim.set_sea_surface(None)
    sim.prefetch_frame(1)  # a flat sea: nothing to sample
    sim.set_frame(1)
    assert sim.ws.scene.wave_top is None


def test_pose_matrices_convention() -> None:
    """R = Rz(yaw)·Ry(pitch)·Rx(roll): positive pitch points the nose (x) down, positive yaw turns x to +y."""
    m = pose_matrices(np.array([0, 0, 0, 0.0, math.radians(30), 0.0]))
    np.testing.assert_allclose(m[:3, 0], [math.cos(math.radians(30)), 0, -0.5], atol=1e-12)
    m = pose_matrices(np.array([1, 2, 3, 0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(m[:3, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(m[:3, 3], [1, 2, 3])


def test_the_sensors_sea_state_is_the_physical_seas() -> None:
    """A scenario that sets the physical sea alone (``environment.sea``) is that sea to every sensor — wind,
    whitecaps, water returns, clutter — not the default ``wave: W0`` (0.5 m); ``motion: paper`` keeps the ``wave``
    setting's height, and :meth:`Simulation.set_sea_surface` moves the sensors' sea with the water."""
    from mmusv.bundled import resolve_scenario
    from mmusv.config import load_scenario
    from mmusv.world.sea_state import sea_spec_for_preset

    sc = load_scenario(resolve_scenario("open_sea_convoy")).model_dump()
    sc["environment"] = {"sea": {"state": 6}}
    sim = Simulation(sc)
    assert sim.sea is not None and sim.sensor_env.wave_height_m == pytest.approx(sim.sea.hs_m) and sim.sea.hs_m > 4
    sim.set_sea_surface(sea_spec_for_preset("W2"))
    assert sim.sensor_env.wave_height_m == pytest.approx(2.5)
    sim.set_sea_surface(None)
    assert sim.sensor_env.wave_height_m == pytest.approx(0.5)  # the `wave` setting's (W0)
    sc["environment"] = {"wave": "W3", "motion": "paper"}
    assert Simulation(sc).sensor_env.wave_height_m == pytest.approx(3.5)


def _rows_of(w: np.ndarray, st: Any, index: int) -> np.ndarray:
    """The rows of ``Simulation.wakes`` that are vessel ``index``'s: its own (at its pose), then its older pieces."""
    x, y = (float(st.poses[index, k]) for k in (0, 1))
    start = [k for k in range(len(w)) if w[k, 7] == 0.0 and abs(w[k, 0] - x) < 1e-3 and abs(w[k, 1] - y) < 1e-3]
    assert len(start) == 1
    k = start[0] + 1
    while k < len(w) and w[k, 7] > 0.0:
        k += 1
    return w[start[0] : k]


def test_wakes_reach_only_as_far_as_the_path_ran_straight(make_scenario: Any) -> None:
    """A wake is drawn as straight pieces of the path behind its vessel: ``Simulation.wakes`` gives the vessel's own
    piece (from its stern as far back as its path ran straight, within half a beam of the line back along its
    heading) and the older ones from where each left the line. On a straight route, one piece as far as the foam
    lasts; on a 100 m ping-pong leg at 5 m/s, 24 s in, back to where it turned 20 m ago (4 m behind the 32 m tug's
    stern), then the outbound leg from there, which its stern passed 0.8 s ago (the route's ends are worked out
    independently here: the leg runs from x = 100 to x = 200)."""
    sc = make_scenario()
    sc["acquisition"] = {"frequency_hz": 5, "frames": 130}
    sc["vessels"].append(
        {"id": "shuttle", "role": "target", "asset": "tug_32m", "speed_mps": 5.0, "end": "ping_pong",
         "route": [[100.0, 300.0], [200.0, 300.0]]}
    )  # fmt: skip
    sim = Simulation(sc)
    names = [v.id for v in sim.scenario.vessels]
    for frame in (60, 120):
        st = sim.world_state(frame)
        w = sim.wakes(st)
        assert w.shape[1] == 9 and w.dtype == np.float32
        # The ninth column is each vessel's displaced volume, Cb·L·B·T of its hull (its Kelvin waves' strength).
        from mmusv.world.hydrostatics import hull_particulars
        from mmusv.world.vessels import get_asset

        length, beam, draft, cb, _ = hull_particulars(get_asset("tug_32m"))
        assert np.allclose(_rows_of(w, st, names.index("shuttle"))[:, 8], cb * length * beam * draft, rtol=1e-6)
        shuttle = _rows_of(w, st, names.index("shuttle"))
        x = float(st.poses[names.index("shuttle"), 0])
        if frame == 60:  # 60 m out from x = 100, heading +x: straight all the way back (and before the start)
            assert abs(x - 160.0) < 0.5 and len(shuttle) == 1 and shuttle[0, 6] == np.inf
        else:  # 120 m travelled: turned at x = 200 20 m ago, heading -x at x = 180, its stern (16 m aft) at x = 196
            assert abs(x - 180.0) < 0.5 and abs(shuttle[0, 6] - 4.0) <= 2.0, (x, shuttle)
            # Then the outbound leg, heading +x from the turn, the stern there 0.8 s ago (the row's "vessel" at x = 216)
            assert len(shuttle) == 2 and shuttle[1, 6] == np.inf, shuttle
            assert abs(shuttle[1, 0] - 216.0) <= 2.0 and abs(shuttle[1, 2]) < 1e-3, shuttle
            assert abs(shuttle[1, 7] - 0.8) <= 0.4, shuttle
        usv_a = _rows_of(w, st, names.index("usv_a"))
        assert len(usv_a) == 1 and usv_a[0, 6] == np.inf  # a straight route


def test_a_wake_follows_its_vessel_round_the_bend(make_scenario: Any) -> None:
    """A boat at 8 m/s went east 300 m, then turned north; 400 m on, its top-view foam (flat water, the wakes of
    ``Simulation.wakes``) lies along the path it took round the bend (the path from its own poses, frame by frame):
    most of the path behind its own first piece has foam within 1.5 m, where the first piece alone (the wake drawn
    straight back from the vessel, as before) has none. Its Kelvin arms bend round the turn: they follow the
    envelope of the waves' energy circles along the path (``sensors/shade/wake.rs``), worked out here from the
    poses alone (each frame's bow position, heading and turn rate); most of that envelope beyond the first piece's
    arms has foam, where the first piece alone has none; and every foam pixel lies within the wake's width of the
    path, on the first piece's arms, or within an arm's width of that envelope."""
    from mmusv._native import core
    from mmusv.scene import Scene
    from mmusv.sensors.camera import render
    from mmusv.sensors.env import sensor_env
    from mmusv.world.build import pose_matrices

    sc = make_scenario()
    sc["acquisition"] = {"frequency_hz": 5, "frames": 300}
    sc["vessels"].append(
        {"id": "runner", "role": "target", "asset": "pilot_boat_16m", "speed_mps": 8.0,
         "route": [[0.0, 500.0], [300.0, 500.0], [300.0, 900.0]]}
    )  # fmt: skip
    sim = Simulation(sc)
    i = [v.id for v in sim.scenario.vessels].index("runner")
    frame = 250
    st = sim.world_state(frame)
    mine = _rows_of(sim.wakes(st), st, i)
    assert len(mine) > 4 and np.all(np.diff(mine[:, 7]) > 0), mine
    path = np.array([sim.world_state(k).poses[i, :2] for k in range(frame + 1)])
    s = Scene()
    v = np.array([[-5000.0, -5000.0, 0.0], [5000.0, -5000.0, 0.0], [5000.0, 5000.0, 0.0], [-5000.0, 5000.0, 0.0]])
    s.add_instance(s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), classes=1, name="water"))
    env = sensor_env(fog_extinction_per_m=0.0, rain_mm_per_h=0.0, wave_height_m=0.0, wind_speed_m_s=0.0)
    top = core.Camera(width=300, height=300, rgb=True, metres_per_pixel=1.0, quality="draft", range_max=500.0)
    pose = pose_matrices(np.array([250.0, 550.0, 300.0, 0.0, math.pi / 2, 0.0]))  # +x at the image top
    lum = np.array([0.2126, 0.7152, 0.0722])

    def foam(wakes: np.ndarray | None) -> np.ndarray:
        img = render(top, s, pose=pose, env=env, seed=1, wakes=wakes, radiance=True).radiance
        assert img is not None
        return img @ lum

    water = foam(None)
    chain = foam(mine) - water > 0.05 * np.median(water)
    first = foam(mine[:1]) - water > 0.05 * np.median(water)
    # Pixel (v, u) is world x = 399.5 - v, y = 699.5 - u.
    vv, uu = np.nonzero(chain)
    pts = np.stack([399.5 - vv, 699.5 - uu], axis=1)
    # The path behind the boat's own piece (and inside the picture): foam along it with the chain, none without.
    back = float(mine[0, 6]) + 20.0
    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    old = path[(travelled[-1] - travelled > back) & (path[:, 0] > 255.0) & (path[:, 1] < 695.0)]
    assert len(old) > 50

    def near(mask: np.ndarray, q: np.ndarray) -> bool:
        v, u = int(np.rint(399.5 - q[0])), int(np.rint(699.5 - q[1]))
        return bool(mask[max(v - 1, 0) : v + 2, max(u - 1, 0) : u + 2].any())

    with_chain = np.mean([near(chain, q) for q in old])
    alone = np.mean([near(first, q) for q in old])
    assert with_chain > 0.8 and alone < 0.05, (with_chain, alone)
    # The envelope of the energy circles (Lighthill 1978, as wake.rs): waves sent out from the bow's position E
    # metres of travel ago, heading h, path curvature kappa there: k = E kappa, normal at psi = atan2(k, 3) +/-
    # acos(1 / sqrt(9 + k^2)) from the heading, the arm point at P + (E/4)(h + n).
    # Before the scenario's start the boat is taken to have come straight (as the core's wake pieces do).
    length, beam = float(mine[0, 4]), float(mine[0, 5])
    yaw = np.unwrap([float(sim.world_state(k).poses[i, 5]) for k in range(frame + 1)])
    pre = np.arange(1000.0, 0.0, -2.0)
    centre = np.concatenate([path[0] - pre[:, None] * [math.cos(yaw[0]), math.sin(yaw[0])], path])
    yaw = np.concatenate([np.full(len(pre), yaw[0]), yaw])
    along = np.concatenate([-pre, travelled])
    bow = centre + 0.5 * length * np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
    kappa = np.gradient(yaw) / np.maximum(np.gradient(along), 1e-6)
    e = along[-1] - along
    k = e * kappa
    arms = []
    for sign in (1.0, -1.0):
        psi = np.arctan2(k, 3.0) + sign * np.arccos(1.0 / np.sqrt(9.0 + k**2))
        n = np.stack([np.cos(yaw + psi), np.sin(yaw + psi)], axis=1)
        arms.append(bow + 0.25 * e[:, None] * (np.stack([np.cos(yaw), np.sin(yaw)], axis=1) + n))
    env_pts, env_e = np.concatenate(arms), np.concatenate([e, e])
    in_view = (np.abs(env_pts[:, 0] - 250.0) < 145.0) & (np.abs(env_pts[:, 1] - 550.0) < 145.0)
    # Beyond the first piece's arms (sent out before its straight stretch) and fresh enough to show.
    bent = in_view & (env_e > length + float(mine[0, 6]) + 30.0) & (env_e < 500.0)
    assert bent.sum() > 50, bent.sum()
    on_chain = np.mean([near(chain, q) for q in env_pts[bent]])
    on_first = np.mean([near(first, q) for q in env_pts[bent]])
    assert on_chain > 0.6 and on_first < 0.05, (on_chain, on_first)
    # Every foam pixel: within the widest track (half-width 9 m here, plus the noise and the pixel) of the path,
    # foam the first piece alone lays too (its straight arms), or within an arm's width of the envelope, plus 10 m:
    # the core works the arms out along the wake's pieces (chords within half a beam of the path, the heading
    # turning between them), and on the inside of the turn the envelope moves with the curvature times the
    # distance gone (k = E kappa): the farthest foam pixel here lies 8.4 m beyond an arm's width.
    d = np.min(np.hypot(pts[:, None, 0] - path[None, ::2, 0], pts[:, None, 1] - path[None, ::2, 1]), axis=1)
    own = first[vv, uu]
    to_env = np.hypot(pts[:, None, 0] - env_pts[None, :, 0], pts[:, None, 1] - env_pts[None, :, 1])
    width = 0.3 + 0.02 * (2.0 / 3.0) * env_e + 0.1 * beam + 10.0
    on_arm = np.any(to_env < width[None, :], axis=1)
    stray = ~((d < 12.0) | own | on_arm)
    assert not np.any(stray), pts[stray][:10]


def test_a_wake_reach_cuts_the_foam_every_sensor_sees() -> None:
    """The core draws no wake foam farther behind the stern than the row's ``reach_m``: a LiDAR beside a 14 m/s
    boat whose path turned 30 m behind its stern returns from its foam only that far back; with the same row and
    no reach (six columns), far beyond. Bad rows are refused, naming the row."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from mmusv.errors import InputError
    from mmusv.sensors.config import LidarConfig
    from mmusv.sensors.env import sensor_env
    from mmusv.sensors.lidar import lidar_from_config, scan
    from test_wave_occlusion import Sea, _pose, _world

    lidar = lidar_from_config(LidarConfig())
    scene, _, _, _ = _world(None, target_x=900.0)
    sea = Sea(0.5, 3.5)
    scene.set_wave_surface(sea, scenario_seed=3, time_s=5.0, foci=np.array([[0.0, 0.0]]))
    env = sensor_env(wave_height_m=sea.hs_m)
    row = [40.0, 8.0, 0.0, 14.0, 20.0, 5.0]  # stern at x = 30, track along y = 8 back past the LiDAR
    behind = {}
    for name, wakes in (("open", None), ("full", [row]), ("cut", [[*row, 30.0]])):
        pts = scan(lidar, scene, pose=_pose(0.0, 0.0, 2.5), env=env, seed=4, wakes=wakes)
        track = (pts.semantic_class == 1) & (np.abs(pts.xyz[:, 1] - 8.0) < 2.5)
        behind[name] = 30.0 - pts.xyz[track, 0]
    assert (behind["cut"] > 30.0).sum() <= (behind["open"] > 30.0).sum()  # no more than the open sea gives
    assert (behind["full"] > 30.0).sum() > 200, (behind["full"] > 30.0).sum()
    near = {k: int(((v > 5.0) & (v < 20.0)).sum()) for k, v in behind.items()}
    print(near, {k: int((v > 30.0).sum()) for k, v in behind.items()})
    assert near["cut"] == near["full"] and near["cut"] > near["open"] + 20, near  # the foam before the cut stays
    with pytest.raises(InputError, match=r"wakes\[0\]"):
        scan(lidar, scene, pose=_pose(0.0, 0.0, 2.5), env=env, seed=4, wakes=[[*row, -1.0]])
    with pytest.raises(InputError, match=r"\(K, 6\) to \(K, 9\)"):
        scan(lidar, scene, pose=_pose(0.0, 0.0, 2.5), env=env, seed=4, wakes=[row[:5]])


@pytest.mark.parametrize("hs_m", [1e-6, 1e-3])
def test_a_calm_physical_sea_still_holds_the_water(make_scenario: Any, hs_m: float) -> None:
    """A sea of micrometre waves (``environment.sea.hs_m: 1e-6``, allowed) is water to every ray, as flat water
    is: its band of heights was thinner than a ray's height rounds to, and rays went through to the seabed, or
    out of the world."""
    sc = make_scenario()
    sc["environment"] = {"sea": {"hs_m": hs_m}}
    sc["vessels"] = sc["vessels"][:1]
    sim = Simulation(sc)
    assert sim.sea is not None and sim.sea.hs_m == hs_m
    sim.set_frame(0)
    g = np.arange(-200.0, 200.0, 7.3)
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    o = np.column_stack([xy, np.full(len(xy), 30.0)]).astype(np.float32)
    d = np.tile(np.array([0.0, 0.0, -1.0], np.float32), (len(xy), 1))
    dist, inst = sim.ws.scene._native.cast_rays(o, d, 1000.0)[:2]
    water = inst == sim.ws.static_instances["water"]
    assert water.sum() > 0.95 * len(xy)
    np.testing.assert_allclose(30.0 - dist[water], 0.0, atol=1e-2)
    assert (inst[~water] == sim.ws.vessel_instances[0]).all()  # the USV's hull, nothing under the water
