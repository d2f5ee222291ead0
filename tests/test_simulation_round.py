"""The in-memory API as a machine-learning researcher meets it (a user round of ``mmusv.Simulation`` driven from a
training loop, never writing a recording): captures that pickle (a ``DataLoader`` worker returns them) and compare
by value (the determinism checks a user writes: ``a == b``), a capture's arrays that are its own (an augmentation
in place must not move the simulation's sensors), the sensors' Python wrappers refusing bad inputs with mmusv's
errors (never a bare ``TypeError``/``AttributeError``/``ValueError``, nor a string or ``True`` read as a number),
options keyword-only, and :mod:`mmusv.frames` refusing shapes it would misread."""

from __future__ import annotations

import copy
import dataclasses
import pickle
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from mmusv import frames
from mmusv.acquire import annotations_for
from mmusv.boxes3d import box_corners
from mmusv.errors import ConfigError, InputError
from mmusv.sensors.camera import camera_from_config, render, top_view_from_config
from mmusv.sensors.config import LidarConfig
from mmusv.sensors.env import sensor_env
from mmusv.sensors.lidar import lidar_from_config, scan
from mmusv.sensors.radar import RadarReturns, ppi_colormap, ppi_image, radar_from_config, radar_sweep
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Agent, FrameCapture, Simulation, sensor_seed
from refusals import unrefused
from tiny_scenario import lidar_scenario


def _scenario(*, frames: int = 4) -> dict[str, Any]:
    """The tests' tiny open sea, its USV carrying every kind of sensor, all small: an 8-channel LiDAR, a
    90-bin radar, one 48 x 32 camera and a 24 x 24 top view."""
    sc = lidar_scenario("sim_round", frames=frames)
    sc["rigs"]["r"].update(
        radar={"azimuth_bins": 90, "rays_el": 4, "range_m": 400, "ppi_size_px": 32},
        cameras=[{"name": "front", "resolution": [48, 32], "quality": "draft", "mount": {"point": "camera_front"}}],
        top_view={"resolution": [24, 24], "quality": "draft"},
    )
    return sc


@pytest.fixture(scope="module")
def sim() -> Simulation:
    return Simulation(_scenario())


@pytest.fixture(scope="module")
def cap(sim: Simulation) -> FrameCapture:
    return sim.capture(2)


# ------------------------------------------------------------------------------------- captures as values


def test_a_capture_pickles_with_its_radar(cap: FrameCapture) -> None:
    """A ``DataLoader`` worker pickles what it returns: a capture with a radar sweep failed (``TypeError: cannot
    pickle 'mmusv._core.Radar' object``). The sweep now pickles as its arrays and its ``RadarConfig``, its radar
    rebuilt from it, so the PPI of the unpickled sweep is the original's; copies share the native radar."""
    ac = cap.agents["u"]
    assert ac.radar is not None and len(ac.radar) > 0
    back = pickle.loads(pickle.dumps(cap))
    assert back == cap
    radar = back.agents["u"].radar
    assert radar is not None and radar.config == ac.radar.config
    np.testing.assert_array_equal(ppi_image(radar, size_px=32), ppi_image(ac.radar, size_px=32))
    deep = copy.deepcopy(ac.radar)
    assert deep == ac.radar and deep.radar is ac.radar.radar and deep.range is not ac.radar.range
    # A sweep made by hand does not know its config: refused with an mmusv error saying how to give it one.
    bare = dataclasses.replace(ac.radar, config=None)
    with pytest.raises(InputError, match="config"):
        pickle.dumps(bare)
    assert pickle.loads(pickle.dumps(dataclasses.replace(bare, config=ac.radar.config))) == ac.radar


def test_an_agent_pickles_as_its_rig_and_its_sensors_capture_the_same(sim: Simulation, cap: FrameCapture) -> None:
    """An agent did not pickle (``TypeError: cannot pickle 'mmusv._core.Lidar' object``), so a worker could not be
    handed one. It now pickles as its index, vessel, asset and rig; unpickled, its sensors are built again from the
    rig: it equals the original, and its LiDAR, camera and top view give the capture's arrays for the same pose,
    seed and scene."""
    agent = sim.agents[0]
    back = pickle.loads(pickle.dumps(agent))
    assert back == agent and back is not agent
    assert back.lidar is not None and back.lidar is not agent.lidar and back.top_view is not None
    ac = cap.agents[agent.id]
    sim.set_frame(cap.frame)
    scene, env, seed = sim.ws.scene, sim.sensor_env, sim.scenario.seed
    wakes = sim.wakes(cap.world)
    assert ac.lidar is not None and ac.lidar_pose is not None
    lidar_seed = sensor_seed(seed, frame=cap.frame, agent=agent.index, sensor="lidar")
    points = scan(back.lidar, scene, pose=ac.lidar_pose, env=env, seed=lidar_seed, wakes=wakes)
    assert np.array_equal(points.xyz, ac.lidar.xyz) and np.array_equal(points.instance, ac.lidar.instance)
    cam, _, _ = back.cameras["front"]
    cam_seed = sensor_seed(seed, frame=cap.frame, agent=0, sensor="camera", index=0)
    img = render(cam, scene, pose=ac.camera_poses["front"], env=env, seed=cam_seed, wakes=wakes)
    assert np.array_equal(img.rgb, ac.cameras["front"].rgb)
    assert ac.top_view_pose is not None
    top = render(
        back.top_view,
        scene,
        pose=ac.top_view_pose,
        env=env,
        seed=sensor_seed(seed, frame=cap.frame, agent=0, sensor="top_view"),
    )
    assert np.array_equal(top.semantic, ac.top_view.semantic)


def test_captures_compare_by_value_in_any_order(sim: Simulation, cap: FrameCapture) -> None:
    """``a == b`` on two captures raised numpy's ``ValueError`` (the dataclasses' generated ``__eq__`` asked an
    array for its truth value). Now equal captures compare equal: frame 2 of a second simulation, asked for after
    frame 3 (random access) and twice, is the first simulation's frame 2, and frame 1 is not."""
    other = Simulation(_scenario())
    other.capture(3)
    again = other.capture(2)
    assert again == cap and other.capture(np.int64(2)) == cap
    assert other.capture(1) != cap
    ac, bc = cap.agents["u"], again.agents["u"]
    assert ac.lidar == bc.lidar and ac.cameras["front"] == bc.cameras["front"] and ac.radar == bc.radar
    assert cap.world == again.world and ac.sensors["lidar"] == bc.sensors["lidar"]
    moved = dataclasses.replace(ac.lidar, xyz=ac.lidar.xyz + np.float32(0.01)) if ac.lidar is not None else None
    assert moved is not None and moved != ac.lidar
    with pytest.raises(TypeError, match="unhashable"):
        hash(cap)
    # The annotations of the two captures too (they held lists of arrays).
    mine, theirs = annotations_for(sim, cap, SilhouetteCache()), annotations_for(other, again, SilhouetteCache())
    assert mine == theirs and mine["u"].lidar_ids == ["t"]


def test_editing_a_capture_in_place_changes_no_later_capture(sim: Simulation) -> None:
    """A capture's ``sensors[...].mount`` was the agent's own mount matrix: an augmentation in place (jittering
    the extrinsics of a capture) silently moved that sensor in every later capture. Captures now get copies, and
    the simulation's mounts and vessel boxes are read-only."""
    before = sim.capture(1)
    cap = sim.capture(0)
    for mounted in cap.agents["u"].sensors.values():
        assert mounted.mount.flags.writeable
        mounted.mount[:3, 3] += 5.0
    cap.agents["u"].sensors["camera/front"].mount[:3, :3] = np.eye(3)[::-1]
    assert sim.capture(1) == before
    agent = sim.agent("u")
    for key, m in agent.mounts().items():
        with pytest.raises(ValueError, match="read-only"):
            m[0, 3] = 1.0
        assert key in cap.agents["u"].sensors
    for v in sim.vessels:
        assert not v.box_size.flags.writeable and not v.box_center_body.flags.writeable


def test_agents_of_two_simulations_of_one_scenario_compare_equal(sim: Simulation) -> None:
    """``Agent`` used the dataclass's generated ``__eq__``: the agents of two simulations of one scenario were
    unequal (their native sensors compared by identity), and for a rig without a LiDAR ``==`` raised numpy's
    ``ValueError`` (the radar mounts' truth value). Agents now compare by value, as captures do: the same USV with
    the same rig is equal, another index, rig or mount is not; like captures they are not hashable."""
    other = Simulation(_scenario())
    a, b = sim.agent("u"), other.agent("u")
    assert a == b and a is not b and a.lidar is not b.lidar
    assert a != "u" and a != dataclasses.replace(b, index=1)
    moved = b.mounts()["camera/front"].copy()
    moved[0, 3] += 0.5
    cams = dict(b.cameras)
    cams["front"] = (cams["front"][0], cams["front"][1], moved)
    assert a != dataclasses.replace(b, cameras=cams)
    assert a != dataclasses.replace(b, lidar=None, lidar_mount=None)
    with pytest.raises(TypeError, match="unhashable"):
        hash(a)
    # Another LiDAR in the rig: another agent.
    sc = _scenario()
    sc["rigs"]["r"]["lidar"] = {"channels": 16, "points_per_second": 40960}
    assert Simulation(sc).agent("u") != a
    # A rig with a radar but no LiDAR (the radar's mount array was compared for its truth value).
    sc = _scenario()
    sc["rigs"]["r"] = {"lidar": None, "cameras": [], "top_view": None, "radar": {"azimuth_bins": 90, "rays_el": 4}}
    one, two = Simulation(sc).agents[0], Simulation(sc).agents[0]
    assert isinstance(one, Agent) and one.lidar is None and one.radar_mount is not None
    assert one == two and one != a


def test_sensor_poses_refuse_an_agent_or_state_of_another_scenario(sim: Simulation) -> None:
    """``sensor_poses`` took any ``Agent`` and any ``WorldState``: another scenario's agent got the pose of
    whichever vessel of this one had its index, with its own mounts, and a state of another scenario gave the
    poses of its vessels. Both are now refused with a ``ConfigError``; an agent of a simulation of the same
    scenario (equal to this one's) gives this one's poses."""
    state = sim.world_state(1)
    sc = _scenario()
    sc["rigs"]["r"]["cameras"][0]["mount"] = {"xyz": [1.0, 0.0, 2.0]}
    sc["vessels"].append({"id": "t2", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[0, -60], [60, -60]]})
    other = Simulation(sc)
    with pytest.raises(ConfigError, match="'u' \\(vessel index 0\\) is not an agent of this simulation"):
        sim.sensor_poses(other.agent("u"), state)
    with pytest.raises(ConfigError, match="state holds 3 vessels, this simulation 2"):
        sim.sensor_poses(sim.agent("u"), other.world_state(1))
    same = Simulation(_scenario()).agent("u")
    mine = sim.sensor_poses(sim.agent("u"), state)
    theirs = sim.sensor_poses(same, state)
    assert mine.keys() == theirs.keys() and all(np.array_equal(mine[k], theirs[k]) for k in mine)
    # The poses are the vessel's pose times each mount (worked out here from the state and the mounts).
    body = state.matrices[0]
    for key, m in sim.agent("u").mounts().items():
        np.testing.assert_allclose(mine[key], body @ m, rtol=0, atol=1e-12)


def test_sensor_seed_refuses_what_it_would_seed_silently() -> None:
    """``sensor_seed`` hashed whatever it was given: a sensor name that is no sensor (``'cameras'``, capture's kind,
    or ``'Lidar'``) all got one seed, ``True`` a seed other than 1's, a negative frame or a float index a seed of
    their own. They are now refused with a ``ConfigError`` naming the argument and what is allowed; the seeds of valid
    arguments are those of before (numpy integers as their values)."""
    bad: list[tuple[tuple[Any, ...], str]] = [
        ((7, 0, 0, "cameras"), "sensor = 'cameras': must be one of 'lidar', 'radar', 'camera', 'top_view' (one camera"),
        ((7, 0, 0, "Lidar"), "sensor = 'Lidar': must be one of"),
        ((7, 0, 0, 3), "sensor = 3: must be one of"),
        ((7, 0, 0, None), "sensor = None: must be one of"),
        ((7, 0, 0, np.array(["lidar"])), "sensor = array"),
        ((-1, 0, 0, "lidar"), "scenario_seed = -1: must be a whole number in 0..9223372036854775807"),
        ((2**63, 0, 0, "lidar"), "scenario_seed = 9223372036854775808"),
        ((True, 0, 0, "lidar"), "scenario_seed = True"),
        ((7.0, 0, 0, "lidar"), "scenario_seed = 7.0"),
        ((7, -3, 0, "lidar"), "frame = -3: must be a whole number >= 0"),
        ((7, "1", 0, "lidar"), "frame = '1'"),
        ((7, 0, -1, "lidar"), "agent = -1: must be a whole number >= 0"),
        ((7, 0, 1.0, "lidar"), "agent = 1.0"),
        ((7, 0, 0, "camera", -1), "index = -1: must be a whole number >= 0"),
        ((7, 0, 0, "camera", 1.5), "index = 1.5"),
        ((7, 0, 0, "camera", False), "index = False"),
    ]
    for args, words in bad:
        with pytest.raises(ConfigError) as e:
            sensor_seed(args[0], **dict(zip(("frame", "agent", "sensor", "index"), args[1:], strict=False)))
        assert words in str(e.value), (args, str(e.value))
    # The seeds of before (worked out by the function as it was: recordings made with them stay reproducible).
    assert sensor_seed(7, frame=0, agent=0, sensor="lidar") == 4555428456120885206
    assert (
        sensor_seed(np.int64(7), frame=np.int32(0), agent=np.uint8(0), sensor="lidar", index=np.int16(0))
        == 4555428456120885206
    )
    assert sensor_seed(7, frame=0, agent=0, sensor="camera", index=np.uint8(2)) == 1693360538744150905
    assert len({sensor_seed(7, frame=0, agent=0, sensor=s) for s in ("lidar", "radar", "camera", "top_view")}) == 4


# ---------------------------------------------------------------------------- the sensors' Python wrappers


def _calls(sim: Simulation) -> list[tuple[str, Callable[[], Any], type[Exception], str]]:
    """(label, call, error class, words the message must hold) of bad calls that gave a bare error or were
    quietly read as something else (the functions typed ``Any``: the calls are wrong on purpose)."""
    state = sim.set_frame(0)
    agent = sim.agent("u")
    pose = sim.sensor_poses(agent, state)["lidar"]
    scene, env = sim.ws.scene, sim.sensor_env
    assert agent.lidar is not None and agent.radar is not None
    lidar, radar, camera = agent.lidar, agent.radar, agent.cameras["front"][0]
    ret = radar_sweep(radar, scene, pose=pose, env=env, seed=0)
    sc: Any = scan
    rd: Any = render
    sw: Any = radar_sweep
    ppi: Any = ppi_image
    cmap: Any = ppi_colormap
    senv: Any = sensor_env
    lcfg: Any = lidar_from_config
    ccfg: Any = camera_from_config
    tcfg: Any = top_view_from_config
    rcfg: Any = radar_from_config
    at = {"pose": pose, "seed": 0}
    return [
        # bare TypeError / AttributeError
        ("scan env=None", lambda: sc(lidar, scene, env=None, **at), InputError, "env = None"),
        ("scan env=Environment", lambda: sc(lidar, scene, env=sim.environment, **at), InputError, "sensor_env"),
        ("scan a config", lambda: sc(LidarConfig(), scene, env=env, **at), InputError, "lidar_from_config"),
        ("scan wakes='x'", lambda: sc(lidar, scene, env=env, wakes="x", **at), InputError, "wakes"),
        ("render a lidar", lambda: rd(lidar, scene, env=env, **at), InputError, "camera = "),
        ("render radiance=1", lambda: rd(camera, scene, env=env, radiance=1, **at), InputError, "radiance = 1"),
        ("sweep radar=None", lambda: sw(None, scene, env=env, **at), InputError, "radar = None"),
        ("sweep env=None", lambda: sw(radar, scene, env=None, **at), InputError, "env = None"),
        ("ppi of a dict", lambda: ppi({}, size_px=16), InputError, "RadarReturns"),
        ("colormap vmin_db='a'", lambda: cmap(np.ones((2, 2)), vmin_db="a"), InputError, "vmin_db = 'a'"),
        ("colormap of a str", lambda: cmap("abc"), InputError, "img = 'abc'"),
        ("sensor_env fog='a'", lambda: senv(fog_extinction_per_m="a"), ConfigError, "env.fog_extinction_per_m"),
        ("sensor_env of a dict", lambda: senv({}), ConfigError, "Environment"),
        ("sensor_env shadows='no'", lambda: senv(shadows="no"), ConfigError, "env.shadows = 'no'"),
        ("sensor_env ev100='12'", lambda: senv(exposure_ev100="12"), ConfigError, "env.exposure_ev100"),
        ("lidar_from_config(dict)", lambda: lcfg({"channels": 4}), ConfigError, "LidarConfig"),
        ("camera_from_config(dict)", lambda: ccfg({"name": "a"}), ConfigError, "CameraConfig"),
        ("top_view_from_config(None)", lambda: tcfg(None), ConfigError, "TopViewConfig"),
        ("radar_from_config(None)", lambda: rcfg(None), ConfigError, "RadarConfig"),
        # quietly read as numbers
        ("ppi metres_per_pixel='8'", lambda: ppi(ret, size_px=16, metres_per_pixel="8"), ConfigError, "'8'"),
        ("ppi metres_per_pixel=True", lambda: ppi(ret, size_px=16, metres_per_pixel=True), ConfigError, "True"),
        ("ppi sensor_yaw='1'", lambda: ppi(ret, size_px=16, sensor_yaw="1"), InputError, "sensor_yaw = '1'"),
        ("sensor_env wave_height_m=True", lambda: senv(wave_height_m=True), ConfigError, "env.wave_height_m"),
        # the allowed range named wrongly (0..4294967295; the core allows 1..8192)
        ("ppi size_px=-1", lambda: ppi(ret, size_px=-1), ConfigError, "1..8192"),
    ]


def test_sensor_wrappers_refuse_bad_inputs_with_mmusv_errors(sim: Simulation) -> None:
    wrong = unrefused(_calls(sim))
    assert not wrong, "\n".join(wrong)


def test_radar_points_frame_is_keyword_only(cap: FrameCapture) -> None:
    """The project's style: options are keyword-only (``points("world")`` read as the frame)."""
    ret = cap.agents["u"].radar
    assert isinstance(ret, RadarReturns)
    with pytest.raises(TypeError):
        ret.points("world")  # type: ignore[call-arg]
    world = ret.points(frame="world")
    expect = ret.points().astype(np.float64) @ ret.pose[:3, :3].T + ret.pose[:3, 3]
    np.testing.assert_allclose(world, expect, atol=1e-3)


# ---------------------------------------------------------------------------------------------- mmusv.frames


def test_frames_refuse_shapes_they_would_misread() -> None:
    """``transform_points`` and ``mirror_points`` reshaped anything to ``(-1, 3)``: ``(N, 4)`` homogeneous points
    (or ``(N, 6)`` poses) came back as ``4N / 3`` (``2N``) garbage points; ``pose_matrices`` read a 7-vector's
    first six values; the others raised bare ``IndexError``/``ValueError``."""
    homogeneous = np.array([[1.0, 2.0, 3.0, 1.0], [4.0, 5.0, 6.0, 1.0], [7.0, 8.0, 9.0, 1.0]])
    bad: list[tuple[Callable[[], Any], str]] = [
        (lambda: frames.transform_points(np.eye(4), homogeneous), "points"),
        (lambda: frames.transform_points(np.eye(4), np.zeros((1, 6))), "points"),
        (lambda: frames.mirror_points(homogeneous), "points"),
        (lambda: frames.transform_points(np.eye(3), np.zeros((1, 3))), "m must be a (4, 4)"),
        (lambda: frames.pose_matrices(np.zeros(7)), "eta"),
        (lambda: frames.pose_matrices([1.0, 2.0, 3.0]), "eta"),
        (lambda: frames.pose_matrices("abc"), "eta"),
        (lambda: frames.matrix_to_pose(np.eye(3)), "m must be"),
        (lambda: frames.invert(np.eye(3)), "m must be"),
        (lambda: frames.translation([1.0, 2.0]), "v must be 3 numbers"),
        (lambda: frames.carla_matrix(np.zeros(5)), "pose"),
        (lambda: frames.carla_pose_from_eta(np.zeros(7)), "eta"),
        (lambda: box_corners(np.eye(4), np.array([1.0, 2.0])), "size"),
    ]
    for call, words in bad:
        with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)")):
            call()
    # What they document still works: (N, 3) points, one (3,) point, a list for the transform, stacks of poses.
    m = frames.pose_matrices(np.array([[1.0, 2.0, 3.0, 0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    assert m.shape == (2, 4, 4)
    np.testing.assert_allclose(frames.transform_points(m[0].tolist(), [0.0, 0.0, 0.0]), [[1.0, 2.0, 3.0]])
    np.testing.assert_allclose(frames.mirror_points([1.0, 2.0, 3.0]), [[1.0, -2.0, 3.0]])
    assert frames.transform_points(m[0], np.zeros((0, 3))).shape == (0, 3)
    np.testing.assert_allclose(frames.pose_matrices(frames.matrix_to_pose(m)), m, atol=1e-12)


# ------------------------------------------------------------------------------------------- annotations


def test_a_vessel_in_plain_view_on_flat_water_is_not_occluded() -> None:
    """``occlusion`` is the share of the vessel's part above the still water level that the camera does not see
    (``docs/recording.md``: hidden by other objects). The hull below the waterline, which a flat sea always hides,
    counted as occluded: a fishing boat in plain view 60 m ahead read 0.34. Here it reads 0 (every pixel whose
    ray meets the boat above the water level, cast against the boat alone, shows the boat), while the 2D box still
    reaches below the waterline (the projected 3D box), so fewer pixels show the boat than the box's silhouette."""
    sc = _scenario(frames=1)
    sc["rigs"]["r"]["cameras"][0].update(resolution=[320, 240])
    sc["vessels"] = [
        {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0.0, "route": [[0, 0], [10, 0]]},
        {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 0.0, "route": [[60, -8], [60, 8]]},
    ]
    s = Simulation(sc)
    cap = s.capture(0)
    ann = annotations_for(s, cap, SilhouetteCache())["u"].columns()["camera"]
    (row,) = [i for i, v in enumerate(ann["target_id"]) if v == "t"]
    assert ann["camera"][row] == "front" and ann["visible_pixels"][row] > 100
    assert ann["occlusion"][row] == pytest.approx(0.0, abs=0.01)


def test_a_missing_field_is_named_and_not_shown_as_the_mapping_it_is_missing_from() -> None:
    """``Simulation({"name": "x"})`` said ``invalid config vessels = {'name': 'x'}: Field required``, the whole
    document shown as if it were the value of ``vessels``."""
    with pytest.raises(ConfigError) as e:
        Simulation({"name": "x"})
    assert "vessels = <missing>: required" in str(e.value) and "'name'" not in str(e.value)
    with pytest.raises(ConfigError) as e:
        Simulation({"name": "x", "vessels": [{"id": "a"}]})
    assert "vessels[0].asset = <missing>: required" in str(e.value)
