"""One native call per frame (``core.capture_frame``) gives exactly what the sensors give one by one."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from mmusv._native import core
from mmusv.sensors.camera import render
from mmusv.sensors.lidar import scan
from mmusv.sensors.radar import ppi_image, radar_sweep
from mmusv.simulation import Simulation, sensor_seed


@pytest.fixture()
def radar_sim(make_scenario: Callable[[], dict[str, Any]]) -> Simulation:
    """The small scenario with a short radar (and its PPI) on both USVs, rain and waves for the clutter."""
    sc = make_scenario()
    sc["environment"]["weather"] = "rain"
    for rig, orientation in (("r", "north_up"), ("rn", "head_up")):
        sc["rigs"][rig]["radar"] = {
            "range_m": 600,
            "azimuth_bins": 128,
            "rays_el": 4,
            "ppi_size_px": 96,
            "ppi_orientation": orientation,
            "range_noise_std_m": 0.5,
        }
    return Simulation(sc)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Same dtype, shape and bytes (so +inf depths and -0.0 compare as they are)."""
    return bool(a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes())


def test_batch_capture_is_bit_identical_to_the_sensors_one_by_one(radar_sim: Simulation) -> None:
    for frame in (0, 7):
        _check_frame(radar_sim, frame)


def _check_frame(sim: Simulation, frame: int) -> None:
    cap = sim.capture(frame)  # the batch
    seed = sim.scenario.seed
    env, scene = sim.sensor_env, sim.ws.scene  # the scene is at `frame` after the capture
    wakes = sim.wakes(sim.world_state(frame))  # the vessels under way, whose wakes the cameras and LiDARs see
    checked = 0
    for agent in sim.agents:
        ac = cap.agents[agent.id]
        assert agent.lidar is not None and ac.lidar is not None and ac.lidar_pose is not None
        lidar_seed = sensor_seed(seed, frame=frame, agent=agent.index, sensor="lidar")
        one = scan(agent.lidar, scene, pose=ac.lidar_pose, env=env, seed=lidar_seed, wakes=wakes)
        assert len(one) > 0
        for name in ("xyz", "range", "intensity", "ring", "azimuth", "semantic_class", "instance", "ray_index"):
            assert _same(getattr(ac.lidar, name), getattr(one, name)), name
        checked += 1
        for k, (name, (cam, _, _)) in enumerate(agent.cameras.items()):
            img = render(
                cam,
                scene,
                pose=ac.camera_poses[name],
                env=env,
                seed=sensor_seed(seed, frame=frame, agent=agent.index, sensor="camera", index=k),
                wakes=wakes,
            )
            got = ac.cameras[name]
            for part in ("depth", "semantic", "instance"):
                assert _same(getattr(got, part), getattr(img, part)), (name, part)
            assert (got.rgb is None) == (img.rgb is None)
            if img.rgb is not None and got.rgb is not None:
                assert _same(got.rgb, img.rgb)
            checked += 1
        assert agent.top_view is not None and ac.top_view is not None and ac.top_view_pose is not None
        tv = render(
            agent.top_view,
            scene,
            pose=ac.top_view_pose,
            env=env,
            seed=sensor_seed(seed, frame=frame, agent=agent.index, sensor="top_view"),
            wakes=wakes,
        )
        assert _same(ac.top_view.depth, tv.depth) and _same(ac.top_view.instance, tv.instance)
        assert (ac.top_view.rgb is None) == (tv.rgb is None)
        if ac.top_view.rgb is not None and tv.rgb is not None:
            assert _same(ac.top_view.rgb, tv.rgb)
        checked += 1
        assert agent.radar is not None and agent.rig.radar is not None and ac.radar is not None
        assert ac.radar_pose is not None and ac.radar_ppi is not None
        ret = radar_sweep(
            agent.radar,
            scene,
            pose=ac.radar_pose,
            env=env,
            seed=sensor_seed(seed, frame=frame, agent=agent.index, sensor="radar"),
        )
        assert len(ret) > 0
        for name in ("range", "azimuth", "elevation", "intensity", "instance_id", "semantic_class"):
            assert _same(getattr(ac.radar, name), getattr(ret, name)), name
        cfg = agent.rig.radar
        ppi = ppi_image(
            ret, size_px=cfg.ppi_size_px, metres_per_pixel=cfg.ppi_metres_per_pixel, orientation=cfg.ppi_orientation
        )
        assert ppi.shape == (96, 96) and ppi.max() > 0
        assert _same(ac.radar_ppi, ppi)
        checked += 1
    assert checked == 2 * 4 + 1  # usv_a: lidar, front, top view, radar; usv_b: the same and aux


def test_batch_capture_reports_every_sensor_time(radar_sim: Simulation) -> None:
    cap = radar_sim.capture(3)
    keys = set(cap.sensor_seconds)
    assert {"usv_a/lidar", "usv_a/camera/front", "usv_a/top_view", "usv_a/radar", "usv_a/ppi"} <= keys
    assert {"usv_b/camera/aux", "usv_b/ppi"} <= keys
    assert all(s >= 0 for s in cap.sensor_seconds.values())


def test_capture_frame_refuses_bad_tasks(radar_sim: Simulation) -> None:
    sim = radar_sim
    agent = sim.agents[0]
    pose = np.eye(4)
    native = sim.ws.scene.native
    with pytest.raises(TypeError, match=r"tasks\[0\]\[0\] must be a Lidar, Camera or Radar"):
        core.capture_frame(native, env=sim.sensor_env, tasks=[("lidar", pose, 1)])
    with pytest.raises(core.InputError, match=r"tasks\[1\]: only a radar task draws a PPI"):
        core.capture_frame(
            native, env=sim.sensor_env, tasks=[(agent.lidar, pose, 1), (agent.lidar, pose, 1, (64, 1.0, "north_up", 0))]
        )
    with pytest.raises(core.InputError, match=r"tasks\[0\]\.pose"):
        core.capture_frame(native, env=sim.sensor_env, tasks=[(agent.lidar, np.eye(3), 1)])
    with pytest.raises(core.ConfigError, match=r"ppi\.orientation"):
        core.capture_frame(native, env=sim.sensor_env, tasks=[(agent.radar, pose, 1, (64, 1.0, "south_up", 0.0))])
    with pytest.raises(core.ConfigError, match=r"ppi\.size_px"):
        core.capture_frame(native, env=sim.sensor_env, tasks=[(agent.radar, pose, 1, (0, 1.0, "north_up", 0.0))])
    assert core.capture_frame(native, env=sim.sensor_env, tasks=[]) == []
