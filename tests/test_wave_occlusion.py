"""The wave-occlusion share of a target and the displaced sea surface every ray meets, against independent
computations: a dense march of each ray against the surface's heights, and the LiDAR's water returns against the
sea state."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.errors import InputError
from mmusv.scene import Scene
from mmusv.sensors.config import LidarConfig
from mmusv.sensors.env import sensor_env
from mmusv.sensors.lidar import lidar_from_config, scan
from mmusv.wave_occlusion import (
    exposed_hidden,
    exposed_hidden_boxes,
    exposed_rays,
    lidar_beam_rays,
    lidar_box_beams,
    lidar_box_rays,
    lidar_boxes_beams,
    pattern_angles,
    share,
)
from refusals import unrefused


@dataclass(frozen=True)
class Sea:
    """A directional JONSWAP sea (the fields :class:`mmusv.sea_surface.SeaState` asks for)."""

    hs_m: float
    tp_s: float
    gamma: float = 3.3
    direction_rad: float = 0.0
    spread_s: float = 20.0


def _box(half: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    hx, hy, hz = half
    v = np.array([[sx * hx, sy * hy, sz * hz] for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)], float)
    f = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6],
         [1, 3, 5], [3, 7, 5]]
    )  # fmt: skip
    return v, f


def _pose(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _world(sea: Sea | None, *, target_x: float = 150.0) -> tuple[Scene, int, Scene, int]:
    """A 4 km water plane, a 5 m craft-sized box (freeboard 1.2 m) at ``target_x``; the same box alone."""
    s = Scene()
    e = 2000.0
    water = s.add_mesh(
        np.array([[-e, -e, 0], [e, -e, 0], [e, e, 0], [-e, e, 0]], float), np.array([[0, 1, 2], [0, 2, 3]]), classes=1
    )
    w = s.add_instance(water)
    v, f = _box((2.5, 1.0, 1.0))
    boat = s.add_instance(s.add_mesh(v, f, classes=10), pose=_pose(target_x, 0.0, 0.2))
    s.set_sea(w, moving=[boat])
    if sea is not None:
        s.set_wave_surface(sea, scenario_seed=3, time_s=12.0, foci=np.array([[0.0, 0.0]]))
    alone = Scene()
    alone_id = alone.add_instance(alone.add_mesh(v, f, classes=10), pose=_pose(target_x, 0.0, 0.2))
    return s, w, alone, alone_id


def _hidden_by_march(scene: Scene, o: np.ndarray, p: np.ndarray, step_m: float = 0.25) -> np.ndarray:
    """Independent: whether the segment from ``o`` to each ``p`` dips below the sea surface anywhere (sampled every
    ``step_m`` metres against the surface's heights), endpoints' last 5 cm left out."""
    out = np.zeros(len(p), dtype=bool)
    for k, q in enumerate(p):
        length = float(np.linalg.norm(q - o))
        n = max(int(length / step_m), 2)
        t = np.linspace(0.0, 1.0 - 0.05 / length, n)
        pts = o + (q - o) * t[:, None]
        h = scene.wave_heights(pts[:, :2].astype(np.float32))
        out[k] = bool(np.any(pts[:, 2] < h))
    return out


def _fan(o: np.ndarray, target: np.ndarray, n: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """``n × n`` rays from ``o`` spanning a little more than the box at ``target``."""
    d0 = target - o
    r = float(np.linalg.norm(d0))
    az0, el0 = np.arctan2(d0[1], d0[0]), np.arcsin(d0[2] / r)
    az, el = np.meshgrid(az0 + np.linspace(-3.0, 3.0, n) / r, el0 + np.linspace(-1.6, 1.6, n) / r)
    d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
    return np.tile(o, (len(d), 1)).astype(np.float32), d.astype(np.float32)


def test_crests_hide_a_craft_at_150_m_as_a_dense_march_says() -> None:
    scene, water, alone, _ = _world(Sea(3.5, 9.0))
    o = np.array([0.0, 0.0, 2.0])
    origins, dirs = _fan(o, np.array([150.0, 0.0, 0.8]))
    t = alone.cast_rays(origins, dirs).distance
    exposed, hidden = exposed_hidden(scene, origins=origins, directions=dirs, vessel_t=t)
    # Independent: march every exposed ray's segment to the hull against the surface heights.
    hit = np.isfinite(t)
    pts = origins[hit].astype(np.float64) + dirs[hit].astype(np.float64) * t[hit, None]
    above = pts[:, 2] > 0.0
    marched = _hidden_by_march(scene, o, pts[above])
    assert exposed == int(above.sum()) > 100
    assert 0 < hidden < exposed, "at W3 the crests hide part of the craft, not all of it"
    assert abs(share(exposed, hidden) - marched.mean()) < 0.03, (share(exposed, hidden), marched.mean())
    # The full scene agrees ray by ray with the march where the two are far from grazing a crest.
    first = scene.cast_rays(origins[hit][above], dirs[hit][above]).instance_id
    assert np.mean((first == water) == marched) > 0.97


def test_flat_sea_hides_nothing_and_lidar_box_rays_cover_the_box() -> None:
    scene, _, alone, _ = _world(None)
    o = np.array([0.0, 0.0, 2.0])
    origins, dirs = _fan(o, np.array([150.0, 0.0, 0.8]), n=20)
    t = alone.cast_rays(origins, dirs).distance
    exposed, hidden = exposed_hidden(scene, origins=origins, directions=dirs, vessel_t=t)
    assert exposed > 0 and hidden == 0
    # LiDAR beams within the box's extent: every beam of the full pattern that meets the box alone is among them.
    pattern = lidar_from_config(
        LidarConfig(channels=128, points_per_second=128 * 4000 * 5.0, vertical_fov_deg=(-5.0, 5.0))
    ).pattern()
    pose = _pose(0.0, 0.0, 2.0)
    corners = np.array(
        [[150 + sx * 2.5, sy * 1.0, 0.2 + sz * 1.0] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    )
    bo, bd = lidar_box_rays(pattern, pattern_angles(pattern), lidar_pose=pose, corners_world=corners)
    full = np.isfinite(alone.cast_rays(np.tile(pose[:3, 3], (len(pattern), 1)), pattern).distance).sum()
    assert full > 0 and np.isfinite(alone.cast_rays(bo, bd).distance).sum() == full


def test_wave_surface_needs_a_sea() -> None:
    s = Scene()
    with pytest.raises(InputError):
        s.set_wave_surface(Sea(1.0, 6.0), scenario_seed=1, time_s=0.0, foci=np.zeros((1, 2)))


@pytest.mark.parametrize(("sea", "lo", "hi"), [(Sea(0.5, 3.5), 0.5, 1.5), (Sea(3.5, 9.0), 0.4, 1.5)])
def test_lidar_water_returns_follow_the_waves(sea: Sea, lo: float, hi: float) -> None:
    """World-z spread of the LiDAR's water returns within 60 m, in units of Hs/4 (the surface's own standard
    deviation): flat water gives millimetres; the waves give the order of Hs/4 (less at W3, where the crests near a
    LiDAR 2.5 m up hide the troughs behind them)."""
    lidar = lidar_from_config(LidarConfig())
    pose = _pose(0.0, 0.0, 2.5)
    z = []
    for k, t in enumerate((0.0, 7.0, 14.0)):
        scene, _, _, _ = _world(None, target_x=900.0)
        scene.set_wave_surface(sea, scenario_seed=3, time_s=t, foci=np.array([[0.0, 0.0]]))
        env = sensor_env(wave_height_m=sea.hs_m)
        pts = scan(lidar, scene, pose=pose, env=env, seed=k)
        w = (pts.semantic_class == 1) & (np.hypot(pts.xyz[:, 0], pts.xyz[:, 1]) < 60.0)
        z.append(pts.xyz[w, 2] + 2.5)
    zz = np.concatenate(z)
    assert zz.size > 100
    ratio = float(zz.std()) / (sea.hs_m / 4.0)
    print(f"Hs {sea.hs_m} m: {zz.size} water returns within 60 m, world-z std {zz.std():.3f} m = {ratio:.2f} Hs/4")
    assert lo < ratio < hi, ratio


def test_lidar_returns_from_wake_foam_along_the_track_and_the_kelvin_arms() -> None:
    """A boat at 14 m/s passes 10 m beside a LiDAR 2.5 m up over a W1-like sea. With its wake, the beams that meet
    the wake's foam return from it (the model's Lambertian foam, detected through speckle) and every other beam
    is as it was: the returns the wake adds lie behind the boat, on its track or on two arms at the Kelvin angle
    asin(1/3) = 19.47° from the bow, measured here from the points themselves."""
    lidar = lidar_from_config(LidarConfig())
    sea = Sea(1.25, 5.5)
    length, beam = 20.0, 5.0
    bow = np.array([40.0 + length / 2, 10.0])
    wake = np.array([[40.0, 10.0, 0.0, 14.0, length, beam]], np.float32)
    from_bow, lateral = [], []
    for seed, t in ((1, 5.0), (2, 9.0)):
        scene, _, _, _ = _world(None, target_x=900.0)
        scene.set_wave_surface(sea, scenario_seed=3, time_s=t, foci=np.array([[0.0, 0.0]]))
        env = sensor_env(wave_height_m=sea.hs_m)
        open_sea = scan(lidar, scene, pose=_pose(0.0, 0.0, 2.5), env=env, seed=seed)
        waked = scan(lidar, scene, pose=_pose(0.0, 0.0, 2.5), env=env, seed=seed, wakes=wake)
        kept = np.isin(waked.ray_index, open_sea.ray_index)
        # Every return of the open sea is still there at the same point; the wake adds water returns, and those of
        # the open sea's that fall on its foam return brighter (foam against the glints' nothing at grazing).
        assert np.isin(open_sea.ray_index, waked.ray_index).all()
        np.testing.assert_array_equal(waked.xyz[kept], open_sea.xyz)
        brighter = waked.intensity[kept] != open_sea.intensity
        assert (waked.intensity[kept][brighter] > open_sea.intensity[brighter]).all()
        changed = ~kept
        changed[np.nonzero(kept)[0][brighter]] = True
        assert (waked.semantic_class[changed] == 1).all()
        assert (~kept).sum() > 1500, (~kept).sum()
        added = waked.xyz[changed]
        from_bow.append(bow[0] - added[:, 0])
        lateral.append(np.abs(added[:, 1] - bow[1]))
    fb, lat = np.concatenate(from_bow), np.concatenate(lateral)
    # Behind the stern (from the bow's 0.9 boat lengths back) and within the arms' wedge.
    assert fb.min() > 0.85 * length, fb.min()
    assert (lat <= fb * np.tan(np.radians(19.47)) + 0.6 * beam + 0.08 * fb + 0.5).all()
    track = lat < 0.5 * beam
    arms = (fb > 40.0) & (lat > 0.6 * beam + 0.1 * fb)
    assert track.sum() > 300 and arms.sum() > 300, (track.sum(), arms.sum())
    angle = float(np.median(np.degrees(np.arctan2(lat[arms], fb[arms]))))
    print(f"{len(fb)} returns from the wake: {track.sum()} on the track, {arms.sum()} on the arms at {angle:.2f} deg")
    assert abs(angle - 19.47) < 1.0, angle


def test_recordings_carry_the_shares_as_annotated(tmp_path: Path) -> None:
    """A W3 run writes each box's wave-occlusion share to the Parquet tables and to the MCAP annotation messages,
    equal to the annotations of the same frames computed afresh."""
    import sys

    from mmusv.acquire import annotations_for, run
    from mmusv.recording.messages import read_messages
    from mmusv.recording.tables import read_table
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    sys.path.insert(0, str(Path(__file__).parent))
    from test_acquire import small_scenario

    sc = small_scenario(frames=2)
    sc["environment"]["wave"] = "W3"
    res = run(sc, out_dir=tmp_path)
    assert res.status == "complete"
    sim, sil = Simulation(sc), SilhouetteCache()
    want3: dict[tuple[int, str, str], float] = {}
    want2: dict[tuple[int, str, str, str], float] = {}
    for k in range(2):
        for agent, ann in annotations_for(sim, sim.capture(k), sil).items():
            cols = ann.columns()
            for t, w in zip(cols["lidar"]["target_id"], cols["lidar"]["wave_occlusion"], strict=True):
                want3[(k, agent, t)] = float(w)
            cam = cols["camera"]
            for t, c, w in zip(cam["target_id"], cam["camera"], cam["wave_occlusion"], strict=True):
                want2[(k, agent, c, t)] = float(w)
    assert any(v > 0 for v in [*want3.values(), *want2.values()])  # W3 crests hide part of some box
    b3 = read_table(tmp_path / "tables", "boxes_3d").rows
    b2 = read_table(tmp_path / "tables", "boxes_2d").rows
    got3 = {(r["frame"], r["agent"], r["target_id"]): r["wave_occlusion"] for r in b3.iter_rows(named=True)}
    got2 = {
        (r["frame"], r["agent"], r["camera"], r["target_id"]): r["wave_occlusion"] for r in b2.iter_rows(named=True)
    }
    assert got3 == want3 and got2 == want2
    msg3: dict[tuple[int, str, str], float] = {}
    msg2: dict[tuple[int, str, str, str], float] = {}
    for topic, _, msg in read_messages(res.recording):
        if topic.endswith("/annotations"):
            for b in msg.boxes_lidar:
                msg3[(msg.frame, msg.agent_id, b.target_id)] = b.wave_occlusion
            for b in msg.boxes_camera:
                msg2[(msg.frame, msg.agent_id, b.camera, b.target_id)] = b.wave_occlusion
    assert msg3 == want3 and msg2 == want2


def test_shares_read_from_the_capture_equal_the_beams_cast_again() -> None:
    """A capture keeps the instance each LiDAR beam met first (``AgentCapture.lidar_beams``): every returned point
    is its beam's hit, the beams agree with casting the pattern again from the LiDAR pose, and the boxes'
    wave-occlusion shares read from them are those of casting each box's beams again (both within the LiDAR's
    range)."""
    import sys

    from mmusv.acquire import annotations_for
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    sys.path.insert(0, str(Path(__file__).parent))
    from test_acquire import small_scenario

    sc = small_scenario(frames=3)
    sc["environment"]["wave"] = "W3"
    sim, sil = Simulation(sc), SilhouetteCache()
    shares = 0
    for k in range(3):
        cap = sim.capture(k)
        for agent in sim.agents:
            ac = cap.agents[agent.id]
            assert ac.lidar is not None and ac.lidar_beams is not None and ac.lidar_pose is not None
            beams = ac.lidar_beams
            assert beams.dtype == np.int32 and beams.shape == (agent.lidar_pattern.shape[0],)
            assert np.array_equal(beams[ac.lidar.ray_index], ac.lidar.instance)
            dirs = agent.lidar_pattern.astype(np.float64) @ ac.lidar_pose[:3, :3].T
            origins = np.broadcast_to(ac.lidar_pose[:3, 3], dirs.shape)
            again = sim.ws.scene.cast_rays(origins, dirs, max_range=agent.rig.lidar.range_m).instance_id
            assert np.mean(again == beams) > 0.999
        read = annotations_for(sim, cap, sil)
        for ac in cap.agents.values():
            ac.lidar_beams = None  # the annotations cast the beams again
        cast = annotations_for(sim, cap, sil)
        for agent_id, ann in read.items():
            assert ann.lidar_wave_occlusion == cast[agent_id].lidar_wave_occlusion
            shares += sum(w > 0 for w in ann.lidar_wave_occlusion)
    assert shares > 0  # W3 crests hide part of some box


def _box_beams_by_testing_every_beam(pattern: np.ndarray, pose: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Indices of the beams within the box's azimuth and elevation extent, every beam tested (the definition): the
    azimuths of its corners, the elevations of every point of its edges (a box seen broadside reaches higher and
    lower between its corners; each edge's extremes found by a bounded search, as the elevation along a segment has
    one stationary point), every beam where the LiDAR's vertical axis passes through the box (the tests' LiDARs turn
    about z only and their boxes are upright: where the LiDAR's x, y lie within the box's)."""
    from scipy.optimize import minimize_scalar

    p = np.asarray(pattern, dtype=np.float64)
    paz, pel = np.arctan2(p[:, 1], p[:, 0]), np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))
    lo_xy, hi_xy = corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)
    if np.all((lo_xy <= pose[:2, 3]) & (pose[:2, 3] <= hi_xy)):
        return np.arange(len(p))
    inv = np.linalg.inv(pose)
    c = corners @ inv[:3, :3].T + inv[:3, 3]
    az, el = np.arctan2(c[:, 1], c[:, 0]), np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1]))
    lo, hi = el.min(), el.max()
    edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
    for a, b in edges:

        def elevation(t: float, a: int = a, b: int = b) -> float:
            q = c[a] + t * (c[b] - c[a])
            return float(np.arctan2(q[2], np.hypot(q[0], q[1])))

        fine = {"xatol": 1e-12}
        lo = min(lo, minimize_scalar(elevation, bounds=(0.0, 1.0), method="bounded", options=fine).fun)
        hi = max(hi, -minimize_scalar(lambda t: -elevation(t), bounds=(0.0, 1.0), method="bounded", options=fine).fun)
    mid = np.arctan2(np.sin(az).mean(), np.cos(az).mean())
    rel = np.angle(np.exp(1j * (az - mid)))
    inside = (pel >= lo) & (pel <= hi)
    prel = np.angle(np.exp(1j * (paz - mid)))
    return np.flatnonzero(inside & (prel >= rel.min()) & (prel <= rel.max()))


_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
"""The corners of a box as signs of its half sizes."""


def _grid_pattern(az: np.ndarray, el: np.ndarray) -> np.ndarray:
    """``(len(az) * len(el), 3)`` float32 unit beams on the azimuth × elevation grid (radians), azimuth-major."""
    a, e = np.meshgrid(az, el, indexing="ij")
    pattern = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)
    return pattern.astype(np.float32)


def _random_pose(rng: np.random.Generator) -> np.ndarray:
    """A LiDAR pose turned by a random yaw about z and moved a few metres (draws: the yaw, then the offset)."""
    th = rng.uniform(-np.pi, np.pi)
    pose = np.eye(4)
    pose[:2, :2] = [[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]
    pose[:3, 3] = rng.normal(size=3) * 5.0
    return pose


def test_lidar_box_rays_find_the_beams_that_testing_every_beam_finds() -> None:
    """The binary search over sorted azimuths selects exactly the beams a test of every beam selects, boxes
    behind the LiDAR (straddling ±π) and boxes wider than half a turn included."""
    el = np.deg2rad(np.linspace(-25.0, 15.0, 64))
    az = np.linspace(-np.pi, np.pi, 512, endpoint=False)
    pattern = _grid_pattern(az, el)
    angles = pattern_angles(pattern)
    rng = np.random.default_rng(3)
    for k in range(200):
        pose = _random_pose(rng)
        centre = np.array([rng.uniform(-200, 200), rng.uniform(-200, 200), rng.uniform(0, 10)])
        if k % 4 == 0:  # straight behind the sensor: the box straddles azimuth ±π
            centre[:2] = pose[:2, 3] - 80.0 * pose[:2, 0]
        half = rng.uniform([1.0, 0.5, 0.5], [150.0, 20.0, 15.0])
        corners = centre + half * _SIGNS
        _, dirs = lidar_box_rays(pattern, angles, lidar_pose=pose, corners_world=corners)
        want = _box_beams_by_testing_every_beam(pattern, pose, corners)
        expected = (pattern.astype(np.float64)[want] @ pose[:3, :3].T).astype(np.float32)
        assert dirs.shape == expected.shape and np.array_equal(dirs, expected), k


def test_many_boxes_beams_are_each_box_s_own() -> None:
    """:func:`lidar_boxes_beams` gives each of a stack of boxes the beams a test of every beam selects for it alone
    (boxes behind the LiDAR, overlapping boxes and an empty stack included), in ``starts``' slices."""
    el = np.deg2rad(np.linspace(-25.0, 15.0, 32))
    az = np.linspace(-np.pi, np.pi, 256, endpoint=False)
    pattern = _grid_pattern(az, el)
    angles = pattern_angles(pattern)
    rng = np.random.default_rng(11)
    for k in range(60):
        pose = _random_pose(rng)
        boxes = []
        for _ in range(k % 7):
            centre = np.array([rng.uniform(-200, 200), rng.uniform(-200, 200), rng.uniform(0, 10)])
            if rng.uniform() < 0.3:  # straight behind the sensor: the box straddles azimuth ±π
                centre[:2] = pose[:2, 3] - 80.0 * pose[:2, 0]
            boxes.append(centre + rng.uniform([1.0, 0.5, 0.5], [150.0, 20.0, 15.0]) * _SIGNS)
        stack = np.array(boxes, dtype=np.float64).reshape(-1, 8, 3)
        beams, starts = lidar_boxes_beams(angles, lidar_pose=pose, corners_world=stack)
        assert beams.dtype == starts.dtype == np.int64 and starts.shape == (len(boxes) + 1,) and starts[0] == 0
        assert starts[-1] == len(beams)
        for b, corners in enumerate(boxes):
            want = _box_beams_by_testing_every_beam(pattern, pose, corners)
            np.testing.assert_array_equal(beams[starts[b] : starts[b + 1]], want, err_msg=f"stack {k}, box {b}")
            np.testing.assert_array_equal(lidar_box_beams(angles, lidar_pose=pose, corners_world=corners), want)


def test_many_targets_counted_at_once_are_each_counted_alone() -> None:
    """:func:`exposed_hidden_boxes` over several targets' rows gives each the counts :func:`exposed_hidden` gives
    it alone: rays cast here or read from the full scene's answers, within a range, with an empty target and rows
    shared by two targets; over W3 crests, where some rays are hidden."""
    scene, _, alone, _ = _world(Sea(hs_m=3.5, tp_s=8.0))
    origins, dirs = _fan(np.array([0.0, 0.0, 2.0]), np.array([150.0, 0.0, 0.8]), n=40)
    t = alone.cast_rays(origins, dirs).distance
    first = scene.cast_rays(origins, dirs).instance_id
    n = len(t)
    # Targets: the first half, nothing, the second half, a middle slice again (rows listed twice).
    rows = [np.arange(0, n // 2), np.arange(0, 0), np.arange(n // 2, n), np.arange(n // 4, 3 * n // 4)]
    idx = np.concatenate(rows)
    starts = np.concatenate([[0], np.cumsum([len(r) for r in rows])])
    for inst in (None, first):
        for reach in (float("inf"), 151.0):
            got = exposed_hidden_boxes(
                scene,
                origins=origins[idx],
                directions=dirs[idx],
                vessel_t=t[idx],
                starts=starts,
                scene_instance=None if inst is None else inst[idx],
                max_range_m=reach,
            )
            want = [
                exposed_hidden(
                    scene,
                    origins=origins[r],
                    directions=dirs[r],
                    vessel_t=t[r],
                    scene_instance=None if inst is None else inst[r],
                    max_range_m=reach,
                )
                for r in rows
            ]
            assert got[0].dtype == got[1].dtype == np.int64
            assert list(zip(got[0].tolist(), got[1].tolist(), strict=True)) == want
    assert want[1] == (0, 0) and want[0][1] + want[2][1] > 0  # some rays hidden by the crests


def test_the_whole_silhouette_stands_in_only_where_allowed() -> None:
    """:func:`exposed_rays`: the rays above the still level; for a target met only below it, all its rays, unless
    its flag says no (a camera box cut by the border whose ship rises above the level); a target met above keeps
    only those, and one met by no ray has none. The counts of :func:`exposed_hidden_boxes` follow the flags."""
    hit = np.array([True, True, False, True, True, True, False])
    z = np.array([0.5, -0.2, 9.0, -1.0, -0.5, -0.3, 1.0])
    box = np.array([0, 0, 0, 1, 1, 2, 3])  # 0: met above and below, 1 and 2: only below, 3: no ray meets it
    np.testing.assert_array_equal(exposed_rays(hit, z, box=box, n_boxes=4), [1, 0, 0, 1, 1, 1, 0])
    flags = np.array([False, True, False, True])
    np.testing.assert_array_equal(exposed_rays(hit, z, box=box, n_boxes=4, whole_when_low=flags), [1, 0, 0, 1, 1, 0, 0])
    np.testing.assert_array_equal(exposed_rays(hit[3:5], z[3:5]), [1, 1])  # one target: all rays its
    # through the counts: a craft sunk in a trough 150 m off, the crests hiding some of it; flagged off, nothing
    scene, _, alone, _ = _world(Sea(hs_m=3.5, tp_s=8.0))
    origins, dirs = _fan(np.array([0.0, 0.0, 2.0]), np.array([150.0, 0.0, 0.8]), n=30)
    t = alone.cast_rays(origins, dirs).distance
    low = np.isfinite(t) & (origins[:, 2] + dirs[:, 2] * np.where(np.isfinite(t), t, 0.0) <= 0.0)
    t = np.where(low, t, np.inf).astype(np.float32)  # only the rays meeting it below the still level
    assert low.sum() > 50
    starts = np.array([0, len(t)])
    e, h = exposed_hidden_boxes(scene, origins=origins, directions=dirs, vessel_t=t, starts=starts)
    assert e[0] == low.sum() and h[0] > 0
    e, h = exposed_hidden_boxes(
        scene, origins=origins, directions=dirs, vessel_t=t, starts=starts, whole_when_low=np.array([False])
    )
    assert e[0] == h[0] == 0


def test_unsigned_offsets_are_offsets() -> None:
    """``starts`` of any integer dtype (``lidar_boxes_beams`` gives int64; a user's may be unsigned) counts each
    target's rows as int64 offsets do: uint64 offsets were a ``TypeError`` (numpy will not repeat by them)."""
    scene, _, alone, _ = _world(Sea(hs_m=3.5, tp_s=8.0))
    # 144 rays: offsets that fit uint8
    origins, dirs = _fan(np.array([0.0, 0.0, 2.0]), np.array([150.0, 0.0, 0.8]), n=12)
    t = alone.cast_rays(origins, dirs).distance
    n = len(t)
    want = exposed_hidden_boxes(
        scene, origins=origins, directions=dirs, vessel_t=t, starts=np.array([0, n // 2, n // 2, n], np.int64)
    )
    assert want[0].sum() > 0
    for dtype in (np.uint8, np.uint16, np.uint32, np.uint64, np.int32):
        offsets = np.array([0, n // 2, n // 2, n]).astype(dtype)
        got = exposed_hidden_boxes(scene, origins=origins, directions=dirs, vessel_t=t, starts=offsets)
        assert got[0].tolist() == want[0].tolist() and got[1].tolist() == want[1].tolist(), dtype


def test_pattern_angles_are_remembered_by_content() -> None:
    """The same pattern twice gives the remembered angles; another pattern its own (not a stale entry)."""
    rng = np.random.default_rng(5)
    for _ in range(3):
        p = rng.normal(size=(257, 3)).astype(np.float32)
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        first, again = pattern_angles(p), pattern_angles(p.copy())
        assert again is first
        q = p.astype(np.float64)
        np.testing.assert_array_equal(first.az, np.arctan2(q[:, 1], q[:, 0]))
        np.testing.assert_array_equal(first.el, np.arctan2(q[:, 2], np.hypot(q[:, 0], q[:, 1])))
        np.testing.assert_array_equal(first.az_sorted, np.sort(first.az))


def test_pattern_angles_trust_identity_only_for_frozen_arrays() -> None:
    """A read-only array that owns its data (a rig's pattern, as ``Agent.lidar_pattern`` keeps it) is recognised
    by identity; a writeable one changed in place, or a read-only view of a changing base, gets fresh angles."""
    rng = np.random.default_rng(9)
    p = rng.normal(size=(64, 3)).astype(np.float32)
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    frozen = p.copy()
    frozen.flags.writeable = False
    assert pattern_angles(frozen) is pattern_angles(frozen)
    w = p.copy()
    before = pattern_angles(w).az.copy()
    w[:, :2] *= -1.0  # every azimuth turns by π
    after = pattern_angles(w).az
    assert not np.allclose(before, after)
    np.testing.assert_array_equal(after, np.arctan2(w[:, 1].astype(np.float64), w[:, 0].astype(np.float64)))
    base = p.copy()
    view = base[:]
    view.flags.writeable = False
    first = pattern_angles(view).az.copy()
    base[:, :2] *= -1.0
    assert not np.allclose(first, pattern_angles(view).az)


def test_a_surface_sampled_without_its_shading_slopes_is_the_same_geometry() -> None:
    """``slopes=False`` (what a frame nothing renders samples) gives every ray the same hit, bit for bit, and the
    same heights: the slopes only ever reach the cameras' shading."""
    sea = Sea(3.5, 9.3)
    s, _, _, _ = _world(None)
    rng = np.random.default_rng(4)
    n = 4000
    o = np.column_stack([rng.uniform(-80, 80, n), rng.uniform(-80, 80, n), rng.uniform(1.5, 4.0, n)]).astype(np.float32)
    el, az = rng.uniform(-0.5, 0.1, n), rng.uniform(0, 2 * np.pi, n)
    d = np.column_stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]).astype(np.float32)
    out = {}
    for slopes in (True, False):
        s.set_wave_surface(sea, scenario_seed=3, time_s=12.0, foci=np.array([[0.0, 0.0]]), slopes=slopes)
        hits = s.cast_rays(o, d, max_range=300.0)
        out[slopes] = (hits.distance, hits.instance_id, hits.triangle_id, hits.normal, s.wave_heights(o[:, :2]))
    water_hits = int(np.count_nonzero(np.isfinite(out[True][0])))
    assert water_hits > n // 2
    for a, b in zip(out[True], out[False], strict=True):
        np.testing.assert_array_equal(a, b)


def _bad_calls() -> list[tuple[str, Any, str]]:
    """(label, call, words the ``InputError`` must hold) of calls that gave a bare ``IndexError``/``ValueError``/
    ``AttributeError``/``LinAlgError`` or, worse, an answer: the functions typed ``Any`` (wrong on purpose)."""
    scene, _, _, _ = _world(None)
    o = np.zeros((4, 3), np.float32)
    d = np.tile(np.array([1.0, 0.0, 0.0], np.float32), (4, 1))
    t = np.full(4, 5.0, np.float32)
    p = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]], np.float32)
    angles = pattern_angles(p)
    pose = np.eye(4)
    corners = np.array([[10.0 + sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    scaled = np.diag([2.0, 2.0, 2.0, 1.0])
    eh: Any = exposed_hidden
    sh: Any = share
    pa: Any = pattern_angles
    lbb: Any = lidar_box_beams
    lbr: Any = lidar_beam_rays
    lbx: Any = lidar_box_rays
    lbs: Any = lidar_boxes_beams
    ehb: Any = exposed_hidden_boxes
    er: Any = exposed_rays
    stack = np.stack([corners, corners + 1.0])
    return [
        # answers for counts that are not counts
        ("share(3, 5)", lambda: sh(3, 5), "hidden = 5: must be <= exposed = 3"),
        ("share(0, 5)", lambda: sh(0, 5), "hidden = 5: must be <= exposed = 0"),
        ("share(-2, 1)", lambda: sh(-2, 1), "exposed = -2: must be a whole number >= 0"),
        ("share(True, True)", lambda: sh(True, True), "exposed = True"),
        ("share(2.5, 1)", lambda: sh(2.5, 1), "exposed = 2.5"),
        # exposed_hidden: broadcast, NaN read as a miss, a range that is no range, bare errors
        (
            "one origin for 4 rays",
            lambda: eh(scene, origins=o[:1], directions=d, vessel_t=t),
            "directions must be (N, 3)",
        ),
        ("origins (4, 2)", lambda: eh(scene, origins=o[:, :2], directions=d, vessel_t=t), "origins must be (N, 3)"),
        ("3 distances for 4 rays", lambda: eh(scene, origins=o, directions=d, vessel_t=t[:3]), "vessel_t must be (N,)"),
        (
            "a NaN distance",
            lambda: eh(scene, origins=o, directions=d, vessel_t=np.full(4, np.nan)),
            "vessel_t must be distances >= 0",
        ),
        ("a negative distance", lambda: eh(scene, origins=o, directions=d, vessel_t=-t), "row 0 is -5.0"),
        ("NaN origins", lambda: eh(scene, origins=o + np.nan, directions=d, vessel_t=t), "origins must be finite"),
        (
            "a zero direction",
            lambda: eh(scene, origins=o, directions=d * 0, vessel_t=t),
            "directions must be directions of any non-zero",
        ),
        ("origins 'abc'", lambda: eh(scene, origins="abc", directions=d, vessel_t=t), "origins must be (N, 3)"),
        ("bool directions", lambda: eh(scene, origins=o, directions=d > 0, vessel_t=t), "got dtype bool"),
        (
            "scene None",
            lambda: eh(None, origins=o, directions=d, vessel_t=t),
            "scene = None: must be a mmusv.scene.Scene",
        ),
        (
            "max_range_m NaN",
            lambda: eh(scene, origins=o, directions=d, vessel_t=t, max_range_m=float("nan")),
            "max_range_m = nan",
        ),
        (
            "max_range_m -1",
            lambda: eh(scene, origins=o, directions=d, vessel_t=t, max_range_m=-1.0),
            "max_range_m = -1.0",
        ),
        (
            "float instances",
            lambda: eh(scene, origins=o, directions=d, vessel_t=t, scene_instance=t),
            "scene_instance must be (N,)",
        ),
        (
            "2 instances",
            lambda: eh(scene, origins=o, directions=d, vessel_t=t, scene_instance=np.zeros(2, np.int32)),
            "scene_instance",
        ),
        # pattern_angles: NaN and (0, 0, 0) beams got angles
        ("pattern (4, 2)", lambda: pa(p[:, :2]), "pattern must be (M, 3)"),
        ("NaN pattern", lambda: pa(np.full((3, 3), np.nan, np.float32)), "pattern must be finite"),
        ("zero beam", lambda: pa(np.zeros((3, 3), np.float32)), "row 0 is (0, 0, 0)"),
        ("pattern 'x'", lambda: pa("x"), "pattern must be (M, 3)"),
        # lidar_box_beams: a NaN pose gave no beams, a singular one LinAlgError, a scaled one wrong angles
        (
            "angles a tuple",
            lambda: lbb((1, 2), lidar_pose=pose, corners_world=corners),
            "angles = (1, 2): must be the BeamAngles",
        ),
        (
            "pose (3, 3)",
            lambda: lbb(angles, lidar_pose=np.eye(3), corners_world=corners),
            "lidar_pose must be a (4, 4) rigid",
        ),
        (
            "pose singular",
            lambda: lbb(angles, lidar_pose=np.zeros((4, 4)), corners_world=corners),
            "lidar_pose must be a (4, 4) rigid",
        ),
        ("pose NaN", lambda: lbb(angles, lidar_pose=pose + np.nan, corners_world=corners), "not finite"),
        (
            "pose scaled",
            lambda: lbb(angles, lidar_pose=scaled, corners_world=corners),
            "lidar_pose must be a (4, 4) rigid",
        ),
        (
            "corners (8, 2)",
            lambda: lbb(angles, lidar_pose=pose, corners_world=corners[:, :2]),
            "corners_world must be the (8, 3)",
        ),
        ("corners NaN", lambda: lbb(angles, lidar_pose=pose, corners_world=corners + np.nan), "corners_world must be"),
        # lidar_boxes_beams: many boxes at once, checked as one
        (
            "boxes (2, 8, 2)",
            lambda: lbs(angles, lidar_pose=pose, corners_world=stack[..., :2]),
            "corners_world must be the (B, 8, 3)",
        ),
        (
            "one box (8, 3)",
            lambda: lbs(angles, lidar_pose=pose, corners_world=corners),
            "corners_world must be the (B, 8, 3)",
        ),
        (
            "box 1 NaN",
            lambda: lbs(angles, lidar_pose=pose, corners_world=stack * [[[1.0]], [[np.nan]]]),
            "box 1 corner 0",
        ),
        (
            "boxes pose scaled",
            lambda: lbs(angles, lidar_pose=scaled, corners_world=stack),
            "lidar_pose must be a (4, 4) rigid",
        ),
        # exposed_hidden_boxes: offsets that are not the rows' slices
        (
            "starts past N",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[0, 5]),
            "starts must be (B + 1,) row offsets rising from 0",
        ),
        ("starts not from 0", lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[1, 4]), "got [1, 4]"),
        (
            "starts falling",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[0, 3, 2, 4]),
            "got [0, 3, 2, 4]",
        ),
        ("starts empty", lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[]), "got []"),
        (
            "starts float",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[0.0, 4.0]),
            "starts must be (B + 1,) row offsets",
        ),
        (
            "starts bool",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[False, True]),
            "got dtype bool",
        ),
        (
            "starts (1, 2)",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[[0, 4]]),
            "starts must be (B + 1,)",
        ),
        (
            "whole_when_low of 1 for 2 targets",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[0, 2, 4], whole_when_low=np.array([True])),
            "whole_when_low must be a (2,) bool array",
        ),
        (
            "whole_when_low as numbers",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=[0, 4], whole_when_low=np.array([1])),
            "whole_when_low must be a (1,) bool array",
        ),
        # the exposed-silhouette rule, called on its own
        ("exposed_rays hit as numbers", lambda: er(np.ones(3), np.zeros(3)), "hit must be an (N,) bool array"),
        ("exposed_rays z short", lambda: er(np.ones(3, bool), np.zeros(2)), "z must be (N,) world heights"),
        (
            "exposed_rays box past n_boxes",
            lambda: er(np.ones(3, bool), np.zeros(3), box=np.array([0, 1, 2]), n_boxes=2),
            "box must be (N,) targets in 0..1: it holds 0..2",
        ),
        (
            "exposed_rays box negative",
            lambda: er(np.ones(2, bool), np.zeros(2), box=np.array([-1, 0]), n_boxes=2),
            "it holds -1..0",
        ),
        ("exposed_rays no box for 2", lambda: er(np.ones(2, bool), np.zeros(2), n_boxes=2), "box is needed"),
        ("exposed_rays n_boxes 0", lambda: er(np.ones(2, bool), np.zeros(2), n_boxes=0), "n_boxes = 0"),
        (
            "exposed_rays flags short",
            lambda: er(np.ones(2, bool), np.zeros(2), box=np.array([0, 1]), n_boxes=2, whole_when_low=np.ones(1, bool)),
            "whole_when_low must be a (2,) bool array",
        ),
        # unsigned offsets that fall: np.diff wrapped round to a rise (uint32: a 32 GiB array), a bare IndexError
        (
            "starts uint8 falling",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=np.array([0, 3, 2, 4], np.uint8)),
            "got [0, 3, 2, 4]",
        ),
        (
            "starts uint16 falling",
            lambda: ehb(scene, origins=o, directions=d, vessel_t=t, starts=np.array([0, 3, 2, 4], np.uint16)),
            "got [0, 3, 2, 4]",
        ),
        # lidar_beam_rays: -1 gave the last beam's ray, a boolean mask was read as one
        (
            "beam -1",
            lambda: lbr(p, lidar_pose=pose, beams=np.array([-1])),
            "beams must be indices of the pattern's beams, in 0..3",
        ),
        ("beam 9", lambda: lbr(p, lidar_pose=pose, beams=np.array([9])), "got 9"),
        ("float beams", lambda: lbr(p, lidar_pose=pose, beams=np.array([0.0, 1.0])), "beams must be (K,) beam indices"),
        ("a mask", lambda: lbr(p, lidar_pose=pose, beams=np.array([True, False, True, False])), "got dtype bool"),
        ("NaN beam", lambda: lbr(p + np.nan, lidar_pose=pose, beams=np.array([2])), "row 2"),
        # lidar_box_rays: the angles of another pattern gave another pattern's beams
        (
            "angles of 4, pattern of 2",
            lambda: lbx(p[:2], angles, lidar_pose=pose, corners_world=corners),
            "angles are of a pattern of 4",
        ),
    ]


def test_the_helpers_refuse_bad_input_with_input_errors() -> None:
    """Wrong shapes, NaN, wrong dtypes and counts gave bare numpy errors or quietly wrong answers (a share above 1,
    a NaN ray counted as a miss, ``-1`` read as the last beam); each is now an ``InputError`` naming the argument
    and what it must be."""
    wrong = unrefused((label, call, InputError, words) for label, call, words in _bad_calls())
    assert not wrong, "\n".join(wrong)


def test_the_helpers_still_take_what_they_document() -> None:
    """The checks refuse nothing valid: counts as numpy integers, patterns as lists, a float32 pose, empty beams,
    and the right answers for them (worked out here)."""
    assert share(np.int64(4), np.int32(3)) == 0.75 and share(0, 0) == 0.0 and share(4, 1) == 0.25
    p = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0]]
    angles = pattern_angles(p)
    np.testing.assert_array_equal(angles.az, [0.0, np.pi / 2, 0.0, np.pi])
    np.testing.assert_array_equal(angles.el, [0.0, 0.0, np.pi / 2, 0.0])
    th = 0.3
    pose = np.array([[np.cos(th), -np.sin(th), 0, 5], [np.sin(th), np.cos(th), 0, 6], [0, 0, 1, 2], [0, 0, 0, 1]])
    o, d = lidar_beam_rays(
        np.asarray(p, np.float32), lidar_pose=pose.astype(np.float32), beams=np.array([3, 0], np.uint8)
    )
    np.testing.assert_allclose(o, [[5, 6, 2], [5, 6, 2]])
    np.testing.assert_allclose(d, [[-np.cos(th), -np.sin(th), 0], [np.cos(th), np.sin(th), 0]], atol=1e-7)
    o, d = lidar_beam_rays(np.asarray(p, np.float32), lidar_pose=pose, beams=[])
    assert o.shape == d.shape == (0, 3)
    # A box 10 m straight ahead of the LiDAR (in its frame): the forward beam only.
    ahead = np.array([[10.0 + sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    corners = ahead @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_array_equal(lidar_box_beams(angles, lidar_pose=pose, corners_world=corners), [0])
    scene, _, alone, _ = _world(None)
    origins, dirs = _fan(np.array([0.0, 0.0, 2.0]), np.array([150.0, 0.0, 0.8]), n=8)
    t = alone.cast_rays(origins, dirs).distance
    n = int(np.count_nonzero(np.isfinite(t) & (origins[:, 2] + dirs[:, 2] * t > 0)))
    assert (
        exposed_hidden(scene, origins=origins, directions=dirs, vessel_t=t, max_range_m=np.float32(1e4)) == (n, 0)
        and n > 0
    )


def test_a_user_round_on_a_real_capture_is_unchanged() -> None:
    """The LiDAR helpers on an ``open_sea_convoy.yaml`` capture (W2 waves), as a user would call them: the rig's
    pattern, the capture's LiDAR pose and each vessel's box pass the checks, the beams are those a test of every
    beam selects, and each share is that of the beams the capture's own cast found."""
    from mmusv.boxes3d import box_corners
    from mmusv.frames import translation
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    root = Path(__file__).resolve().parents[1]
    sim, sil = Simulation(root / "scenarios" / "open_sea_convoy.yaml"), SilhouetteCache()
    cap = sim.capture(0, sensors=["lidar"])
    agent = sim.agents[0]
    ac = cap.agents[agent.id]
    pattern, pose, beams_hit = agent.lidar_pattern, ac.lidar_pose, ac.lidar_beams
    assert pattern is not None and pose is not None and beams_hit is not None and agent.rig.lidar is not None
    angles = pattern_angles(pattern)
    shares = []
    for vi, info in enumerate(sim.vessels):
        if vi == agent.index:
            continue
        corners = box_corners(cap.world.matrices[vi] @ translation(info.box_center_body), info.box_size)
        beams = lidar_box_beams(angles, lidar_pose=pose, corners_world=corners)
        np.testing.assert_array_equal(beams, _box_beams_by_testing_every_beam(pattern, pose, corners))
        o, d = lidar_box_rays(pattern, angles, lidar_pose=pose, corners_world=corners)
        assert o.dtype == d.dtype == np.float32 and o.shape == d.shape == (len(beams), 3)
        t = sil.distances(info.asset, pose=cap.world.matrices[vi], origins=o, directions=d)
        exposed, hidden = exposed_hidden(
            sim.ws.scene,
            origins=o,
            directions=d,
            vessel_t=t,
            scene_instance=beams_hit[beams],
            max_range_m=agent.rig.lidar.range_m,
        )
        water = sim.ws.scene.sea_instance
        reach = np.isfinite(t) & (t <= agent.rig.lidar.range_m)
        above = reach & (o[:, 2].astype(np.float64) + d[:, 2].astype(np.float64) * np.where(reach, t, 0.0) > 0.0)
        assert exposed == int(above.sum()) and hidden == int(np.count_nonzero(beams_hit[beams][above] == water))
        shares.append(share(exposed, hidden))
    assert any(s > 0 for s in shares)
