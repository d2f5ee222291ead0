"""The spinning LiDAR (``mmusv.sensors.lidar`` over ``mmusv_core::sensors::lidar``).

* Geometry: with noise, dropout and the water model switched off, every point is re-cast in Open3D's
  ``RaycastingScene`` built from ``Scene.world_mesh()`` (an independent ray caster): ranges agree to 1 cm, the
  face hit belongs to the point's instance, rays without a point are misses there.
* Pattern bookkeeping: ring / azimuth / ray_index / elevation of each point, explicit elevation tables.
* Noise model: seeding, Gaussian range noise, dropout, water returns versus wave height, fog losses (rain's
  through its visibility alone), the rain drops' own returns against a NumPy re-draw of LISA's model, and the
  intensity formula ``ρ(class) · |cos θ| · τ / (1 + (r / 100 m)²)``, checked analytically on simple scenes (a
  closed room whose every ray hits, a lone water plane).
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv._native import core
from mmusv.scene import Scene, demo_scene
from mmusv.sensors import LidarConfig, LidarPoints, lidar_from_config, scan, sensor_env
from mmusv.simulation import Simulation
from mmusv.world.build import pose_matrices
from mmusv.world.environment import Weather

# Room used by the noise tests: every ray of a ±25°..15° pattern from the origin hits one of its walls.
ROOM_LO = (-120.0, -25.0, -8.0)
ROOM_HI = (15.0, 40.0, 30.0)
ROOM_CLASS = 10  # painted hull, reflectivity 0.5
REFLECTIVITY = {1: 0.05, 2: 0.35, 3: 0.45, 4: 0.30, 5: 0.55, 6: 0.60, 7: 0.80, 8: 0.30, 10: 0.50, 11: 0.50}


def box_mesh(lo: Any, hi: Any) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(8, 3)`` and faces ``(12, 3)`` of the axis-aligned box ``[lo, hi]``."""
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
    return v, f


def plane_scene(half: float, *, z: float = 0.0, cls: int = 1) -> Scene:
    """A scene holding only the square ``[-half, half]²`` at height ``z`` (instance 0, class ``cls``)."""
    s = Scene()
    v = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    s.add_instance(s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), classes=cls, name="plane"))
    return s


def exact_lidar(channels: int = 32, steps: int = 720, *, range_m: float = 200.0, **kw: Any) -> Any:
    """A native LiDAR with every random effect off (exact geometry), uniform over [-25°, 15°]."""
    el = np.radians(np.linspace(-25.0, 15.0, channels)).tolist()
    args: dict[str, Any] = {
        "elevations": el,
        "azimuth_steps": steps,
        "range_min": 0.0,
        "range_max": range_m,
        "range_noise_std": 0.0,
        "dropout": 0.0,
        "water_probability": 1.0,
        "water_probability_per_wave_m": 0.0,
        "water_range_m": 1e6,
        "water_range_per_wave_m": 0.0,
        "beam_divergence": 0.0,
    }
    args.update(kw)
    return core.Lidar(**args)


def room_scene() -> Scene:
    s = Scene()
    v, f = box_mesh(ROOM_LO, ROOM_HI)
    s.add_instance(s.add_mesh(v, f, classes=ROOM_CLASS, name="room"))
    return s


def room_truth(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact range from the origin to the room's walls along unit ``dirs`` (float64) and |cos| of the incidence."""
    lo, hi = np.array(ROOM_LO), np.array(ROOM_HI)
    with np.errstate(divide="ignore"):
        t_axis = np.where(dirs > 0, hi / dirs, np.where(dirs < 0, lo / dirs, np.inf))
    axis = np.argmin(t_axis, axis=1)
    t = t_axis[np.arange(len(dirs)), axis]
    cos = np.abs(dirs[np.arange(len(dirs)), axis])
    return t, cos


def do_scan(lidar: Any, scene: Scene, pose: np.ndarray | None = None, *, seed: int = 1, **env: float) -> LidarPoints:
    """A scan in still, clear air unless ``env`` sets fog_extinction_per_m, rain_mm_per_h or wave_height_m."""
    still = {"fog_extinction_per_m": 0.0, "rain_mm_per_h": 0.0, "wave_height_m": 0.0}
    return scan(lidar, scene, pose=np.eye(4) if pose is None else pose, env=sensor_env(**{**still, **env}), seed=seed)


# ------------------------------------------------------------------------------------------ geometry vs Open3D


def _demo_case() -> tuple[Scene, np.ndarray]:
    scene, _ = demo_scene(seed=3, extent=400.0, terrain_cells=64, vessels=12)
    # 4 m above the water near the vessel cluster, slightly rolled / pitched / yawed.
    return scene, pose_matrices(np.array([0.0, 5.0, 4.0, 0.03, -0.05, 0.7]))


def _sim_case(sim: Simulation) -> tuple[Scene, np.ndarray]:
    """Frame 7 over the flat sea: Open3D sees the world mesh, the flat water plane included (the displaced
    surface is checked against a dense march in tests/test_wave_occlusion.py and the core's tests)."""
    sim.set_sea_surface(None)
    cap = sim.capture(7, agents=["usv_a"], radar=False)
    pose = cap.agents["usv_a"].lidar_pose
    assert pose is not None
    return sim.ws.scene, pose


@pytest.mark.parametrize("case", ["demo_scene", "simulation_frame"])
def test_geometry_matches_open3d(case: str, sim: Simulation) -> None:
    o3d = pytest.importorskip("open3d")
    sea = sim.sea
    try:
        _check_open3d(case, sim, o3d)
    finally:
        sim.set_sea_surface(sea)


def _check_open3d(case: str, sim: Simulation, o3d: Any) -> None:
    scene, pose = _demo_case() if case == "demo_scene" else _sim_case(sim)
    rmax = 200.0
    lidar = exact_lidar(32, 720, range_m=rmax)
    pts = do_scan(lidar, scene, pose, seed=9)
    n_rays = lidar.num_rays
    assert n_rays == 32 * 720 and len(pts) > 0.5 * n_rays

    wm = scene.world_mesh()
    rc = o3d.t.geometry.RaycastingScene()
    rc.add_triangles(o3d.core.Tensor(wm["vertices"].astype(np.float32)), o3d.core.Tensor(wm["faces"].astype(np.uint32)))
    pattern = np.asarray(lidar.pattern(), dtype=np.float64)
    assert pattern.shape == (n_rays, 3)
    dirs = pattern @ pose[:3, :3].T
    rays = np.hstack([np.broadcast_to(pose[:3, 3], dirs.shape), dirs]).astype(np.float32)
    ans = rc.cast_rays(o3d.core.Tensor(rays))
    t_o3d = ans["t_hit"].numpy().astype(np.float64)
    prim = ans["primitive_ids"].numpy().astype(np.int64)
    o3d_hit = np.isfinite(t_o3d) & (t_o3d <= rmax)

    ri = pts.ray_index.astype(np.int64)
    assert np.all(np.diff(ri) > 0), "points come in pattern order, each ray at most once"
    # Every point: its ray hits in Open3D at the same range (1 cm) and on a face of the same instance.
    assert o3d_hit[ri].all(), f"{int((~o3d_hit[ri]).sum())} points on rays that miss in Open3D"
    err = np.abs(t_o3d[ri] - pts.range.astype(np.float64))
    assert err.max() < 0.01, f"range differs from Open3D by up to {err.max():.4f} m"
    world = pts.xyz.astype(np.float64) @ pose[:3, :3].T + pose[:3, 3]
    o3d_pts = pose[:3, 3] + dirs[ri] * t_o3d[ri, None]
    assert np.abs(world - o3d_pts).max() < 0.01
    inst_o3d = wm["instance_ids"][prim[ri]].astype(np.int64)
    agree = np.mean(inst_o3d == pts.instance)
    assert agree >= 0.999, f"instance agrees with Open3D for {agree:.4%} of points"
    cls_o3d = wm["classes"][prim[ri]]
    assert np.mean(cls_o3d == pts.semantic_class) >= 0.999
    # Rays without a point are misses (or beyond range) in Open3D; count = rays - misses.
    no_point = np.ones(n_rays, dtype=bool)
    no_point[ri] = False
    assert not o3d_hit[no_point].any(), f"{int(o3d_hit[no_point].sum())} rays hit in Open3D but gave no point"
    assert len(pts) == n_rays - int((~o3d_hit).sum())
    # The scene has something to see beyond water.
    classes = set(np.unique(pts.semantic_class).tolist())
    assert 1 in classes and 10 in classes
    if case == "demo_scene":
        assert 2 in classes, "terrain in range"


def test_range_limits() -> None:
    """Returns closer than range_min or farther than range_max are dropped (room walls 8..130 m away)."""
    scene = room_scene()
    lidar = exact_lidar(16, 180, range_m=60.0, range_min=12.0)
    pts = do_scan(lidar, scene)
    truth, _ = room_truth(np.asarray(lidar.pattern(), dtype=np.float64))
    expect = (truth >= 12.0) & (truth <= 60.0)
    got = np.zeros(lidar.num_rays, dtype=bool)
    got[pts.ray_index] = True
    # Ignore rays within 1 mm of a limit (float32 ranges).
    clear = (np.abs(truth - 12.0) > 1e-3) & (np.abs(truth - 60.0) > 1e-3)
    assert np.array_equal(got[clear], expect[clear])
    assert pts.range.min() >= 12.0 and pts.range.max() <= 60.0


# ------------------------------------------------------------------------------------------ pattern bookkeeping


def test_ring_azimuth_ray_index_and_elevation() -> None:
    cfg = LidarConfig(
        channels=16, points_per_second=57_600, rotation_hz=10, range_noise_std_m=0.03, vertical_fov_deg=(-25, 15)
    )
    assert cfg.azimuth_steps == 360
    lidar = lidar_from_config(cfg)
    assert lidar.num_rays == 16 * 360
    pts = do_scan(lidar, room_scene(), pose_matrices(np.array([1.0, 2.0, 0.5, 0.0, 0.0, 0.4])), seed=4)
    assert len(pts) == lidar.num_rays, "every ray hits the room"
    ch, steps = 16, 360
    ri = pts.ray_index.astype(np.int64)
    assert np.array_equal(ri, np.arange(ch * steps))
    assert np.array_equal(pts.ring.astype(np.int64), ri % ch)
    np.testing.assert_allclose(pts.azimuth, 2 * np.pi * (ri // ch) / steps, rtol=0, atol=2e-6)
    assert pts.azimuth.min() >= 0 and pts.azimuth.max() < 2 * np.pi
    xyz = pts.xyz.astype(np.float64)
    r = np.linalg.norm(xyz, axis=1)
    np.testing.assert_allclose(r, pts.range, rtol=1e-5)
    elev_cfg = np.array(cfg.elevations_rad())
    np.testing.assert_allclose(np.arcsin(xyz[:, 2] / r), elev_cfg[pts.ring], rtol=0, atol=1e-5)
    np.testing.assert_allclose(np.mod(np.arctan2(xyz[:, 1], xyz[:, 0]), 2 * np.pi), pts.azimuth, rtol=0, atol=1e-5)
    # The pattern itself: azimuth-major unit vectors.
    pat = np.asarray(lidar.pattern(), dtype=np.float64)
    az = 2 * np.pi * (np.arange(ch * steps) // ch) / steps
    el = elev_cfg[np.arange(ch * steps) % ch]
    want = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)
    np.testing.assert_allclose(pat, want, atol=1e-6)
    # Uniform pattern: ring 0 is the lowest beam, the last ring the highest.
    assert math.isclose(elev_cfg[0], math.radians(-25)) and math.isclose(elev_cfg[-1], math.radians(15))


def test_explicit_elevation_table_is_honoured() -> None:
    table = [3.0, -15.0, 0.0, 7.5, -2.0, -30.0]
    cfg = LidarConfig(channels=6, elevations_deg=table, points_per_second=6 * 90 * 10, rotation_hz=10)
    assert cfg.azimuth_steps == 90
    lidar = lidar_from_config(cfg)
    pts = do_scan(lidar, room_scene())
    assert len(pts) == 6 * 90
    xyz = pts.xyz.astype(np.float64)
    elev = np.degrees(np.arcsin(xyz[:, 2] / np.linalg.norm(xyz, axis=1)))
    np.testing.assert_allclose(elev, np.array(table)[pts.ring], atol=1e-3)
    pat = np.asarray(lidar.pattern(), dtype=np.float64)
    np.testing.assert_allclose(np.degrees(np.arcsin(pat[:6, 2])), table, atol=1e-4)
    with pytest.raises(ValueError, match="elevations_deg"):
        LidarConfig(channels=5, elevations_deg=table)


def test_rings_that_would_fire_the_same_rays_are_refused() -> None:
    """16 channels over a vertical field of view of no angle ([0, 0]) fired one ring's rays 16 times, as did a table
    that repeats an elevation; one channel over [0, 0] is a single ring, as meant."""
    with pytest.raises(ValueError, match=r"vertical_fov_deg \[0\.0, 0\.0\] spans no angle: its 16 channels"):
        LidarConfig(channels=16, vertical_fov_deg=(0.0, 0.0))
    with pytest.raises(ValueError, match=r"elevations_deg repeats \[-2\.0\]"):
        LidarConfig(channels=3, elevations_deg=[-2.0, 0.0, -2.0])
    assert LidarConfig(channels=1, vertical_fov_deg=(0.0, 0.0)).elevations_rad() == [0.0]


# ------------------------------------------------------------------------------------------ noise, dropout, weather


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"seed": 2.9}, r"seed = 2\.9: must be a whole number"),
        ({"seed": 2**64}, r"seed = .*: must be a whole number in 0\.\."),
        ({"seed": True}, r"seed = True: must be a whole number"),
        ({"pose": np.eye(4)[:3]}, r"pose must be a \(4, 4\)"),
        ({"pose": np.eye(4).ravel()}, r"pose must be a \(4, 4\)"),
        ({"scene": None}, r"scene must be an mmusv\.Scene, got NoneType"),
    ],
)
def test_bad_scan_arguments_are_named(kwargs: dict[str, Any], match: str) -> None:
    """A float seed used to be truncated (2.9 scanned as seed 2) and a flat 16-vector pose reshaped without a
    word; both are refused now, naming the argument, as the radar's sweep does."""
    args: dict[str, Any] = {"scene": plane_scene(10.0, z=-2.0), "pose": np.eye(4), "seed": 1, **kwargs}
    scene = args.pop("scene")
    with pytest.raises(mmusv.InputError, match=match):
        scan(exact_lidar(channels=4, steps=8), scene, env=sensor_env(), **args)


def test_same_seed_same_sweep_other_seed_other_noise() -> None:
    cfg = LidarConfig(channels=16, points_per_second=57_600, rotation_hz=10, range_noise_std_m=0.05, dropout=0.1)
    lidar = lidar_from_config(cfg)
    scene = room_scene()
    a = do_scan(lidar, scene, seed=123, fog_extinction_per_m=0.002)
    b = do_scan(lidar, scene, seed=123, fog_extinction_per_m=0.002)
    c = do_scan(lidar, scene, seed=124, fog_extinction_per_m=0.002)
    for name in ("xyz", "range", "intensity", "ring", "azimuth", "semantic_class", "instance", "ray_index"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name
    assert not np.array_equal(a.ray_index, c.ray_index), "another seed drops other rays"
    common = np.intersect1d(a.ray_index, c.ray_index)
    ra = a.range[np.searchsorted(a.ray_index, common)]
    rc = c.range[np.searchsorted(c.ray_index, common)]
    assert np.mean(ra != rc) > 0.99, "another seed draws other noise"
    assert a.xyz.dtype == np.float32 and a.range.dtype == np.float32 and a.intensity.dtype == np.float32
    assert a.ring.dtype == np.uint16 and a.semantic_class.dtype == np.uint16
    assert a.instance.dtype == np.int32 and a.ray_index.dtype == np.uint32


def test_range_noise_std_and_direction() -> None:
    std = 0.05
    lidar = exact_lidar(32, 720, range_noise_std=std)
    pts = do_scan(lidar, room_scene(), seed=77)
    pat = np.asarray(lidar.pattern(), dtype=np.float64)
    truth, _ = room_truth(pat)
    assert len(pts) == lidar.num_rays
    res = pts.range.astype(np.float64) - truth[pts.ray_index]
    n = len(res)
    assert abs(res.mean()) < 4 * std / math.sqrt(n)
    # Standard error of a sample std: std / sqrt(2n); allow 5 of them.
    assert abs(res.std() - std) < 5 * std / math.sqrt(2 * n), f"measured std {res.std():.4f} m, configured {std}"
    # Gaussian: ~68.3 % within one sigma, ~95.4 % within two.
    assert abs(np.mean(np.abs(res) < std) - 0.6827) < 0.02
    assert abs(np.mean(np.abs(res) < 2 * std) - 0.9545) < 0.01
    # Noise moves the point along its ray.
    np.testing.assert_allclose(pts.xyz, pat[pts.ray_index] * pts.range[:, None], atol=1e-4)


def test_dropout_fraction() -> None:
    p = 0.25
    lidar = exact_lidar(32, 720, dropout=p)
    n = lidar.num_rays
    fracs = []
    for seed in (1, 2):
        pts = do_scan(lidar, room_scene(), seed=seed)
        frac = 1 - len(pts) / n
        assert abs(frac - p) < 4.5 * math.sqrt(p * (1 - p) / n), f"dropped {frac:.4f}, configured {p}"
        fracs.append(frac)
    none = do_scan(exact_lidar(32, 720, dropout=0.0), room_scene())
    assert len(none) == n
    everything = do_scan(exact_lidar(32, 720, dropout=1.0), room_scene())
    assert len(everything) == 0


@pytest.mark.parametrize("wave_h", [0.0, 1.0, 3.0, 20.0])
def test_water_returns_follow_the_wave_model(wave_h: float) -> None:
    """Open water returns with probability p0 + k·H (clamped to 1) and only within r0 + c·H metres."""
    z0, p0, kp, r0, kr = 2.5, 0.05, 0.1, 20.0, 10.0
    lidar = exact_lidar(
        32,
        720,
        range_m=200.0,
        water_probability=p0,
        water_probability_per_wave_m=kp,
        water_range_m=r0,
        water_range_per_wave_m=kr,
    )
    pose = pose_matrices(np.array([3.0, -4.0, z0, 0.0, 0.0, 1.0]))
    pts = do_scan(lidar, plane_scene(2000.0), pose, seed=31, wave_height_m=wave_h)
    dirs = np.asarray(lidar.pattern(), dtype=np.float64) @ pose[:3, :3].T
    with np.errstate(divide="ignore"):
        truth = np.where(dirs[:, 2] < 0, z0 / -dirs[:, 2], np.inf)
    water_range = r0 + kr * wave_h
    p = min(1.0, p0 + kp * wave_h)
    limit = min(water_range, 200.0)
    eligible = truth <= limit
    assert set(np.unique(pts.semantic_class).tolist()) <= {1}
    assert np.all(truth[pts.ray_index] <= limit + 1e-3), "no water return beyond the water range"
    n = int(eligible.sum())
    if p >= 1.0:
        assert len(pts) == n, "p clamps to 1: every water ray within range returns"
    else:
        sigma = math.sqrt(n * p * (1 - p))
        assert abs(len(pts) - n * p) < 4.5 * sigma, f"{len(pts)} water returns of {n} rays, expected {n * p:.0f}"


def test_water_returns_grow_with_wave_height() -> None:
    lidar = lidar_from_config(LidarConfig(channels=32, points_per_second=32 * 720 * 5, rotation_hz=5))
    scene = plane_scene(2000.0)
    pose = pose_matrices(np.array([0.0, 0.0, 2.5, 0.0, 0.0, 0.0]))
    counts, far = [], []
    for h in (0.0, 0.5, 1.5, 2.5, 3.5):
        pts = do_scan(lidar, scene, pose, seed=8, wave_height_m=h)
        counts.append(len(pts))
        far.append(float(pts.range.max()) if len(pts) else 0.0)
    assert all(b > a for a, b in itertools.pairwise(counts)), counts
    assert all(b > a for a, b in itertools.pairwise(far)), far


def test_fog_drops_far_returns_by_two_way_transmission() -> None:
    sigma = 3.0 / 500.0  # fog, 500 m visibility
    lidar = exact_lidar(32, 720)
    clear = do_scan(lidar, room_scene(), seed=5)
    foggy = do_scan(lidar, room_scene(), seed=5, fog_extinction_per_m=sigma)
    assert len(clear) == lidar.num_rays
    truth = clear.range.astype(np.float64)
    kept = np.zeros(lidar.num_rays, dtype=bool)
    kept[foggy.ray_index] = True
    tau = np.exp(-2 * sigma * truth)
    bins = [(0, 20), (20, 40), (40, 80), (80, 200)]
    rates = []
    for lo, hi in bins:
        sel = (truth >= lo) & (truth < hi)
        n = int(sel.sum())
        assert n > 300
        expect = tau[sel].mean()
        got = kept[sel].mean()
        sd = math.sqrt(np.sum(tau[sel] * (1 - tau[sel]))) / n
        assert abs(got - expect) < 4.5 * sd + 1e-9, f"{lo}-{hi} m: kept {got:.3f}, expected {expect:.3f}"
        rates.append(got)
    assert rates == sorted(rates, reverse=True) and rates[-1] < 0.5 * rates[0]


def test_rain_dims_the_lidar_through_the_visibility_alone() -> None:
    """The drops extinguish 905 nm as they do visible light, and the visibility in rain holds them
    (:mod:`mmusv.world.rain`): a LiDAR in 50 mm/h loses the returns that the rain's visibility loses, and the rain
    rate adds no second loss (until 2026-12-07 an unsourced ``1e-5·R^0.6`` per metre was added to the visibility's
    extinction, the drops counted twice: the scans differed). A line for a beam (divergence 0) meets no drop; the
    drops' own returns are the test below."""
    weather = Weather.make("rain", rain_mm_per_h=50.0)
    sigma = weather.extinction_per_m
    assert 2.5e-3 < sigma < 6e-3  # the drops alone: 0.365·50^0.63 per km, 4.1e-3 per metre; and the air's
    lidar = exact_lidar(32, 720)
    clear = do_scan(lidar, room_scene(), seed=5)
    in_rain = do_scan(lidar, room_scene(), seed=5, fog_extinction_per_m=sigma, rain_mm_per_h=50.0)
    same_air = do_scan(lidar, room_scene(), seed=5, fog_extinction_per_m=sigma)
    np.testing.assert_array_equal(in_rain.ray_index, same_air.ray_index)
    np.testing.assert_array_equal(in_rain.intensity, same_air.intensity)
    assert np.isin(in_rain.ray_index, clear.ray_index).all() and len(in_rain) < 0.8 * len(clear)
    # The rain rate without its visibility (clear air) dims nothing.
    rate_alone = do_scan(lidar, room_scene(), seed=5, rain_mm_per_h=100.0)
    np.testing.assert_array_equal(rate_alone.intensity, clear.intensity)


def _lisa_brute_share(
    p0: np.ndarray,
    reach: np.ndarray,
    *,
    rain: float,
    sigma: float,
    divergence: float,
    range_min: float,
    range_max: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Per beam, whether LISA's hybrid Monte Carlo (Kilic et al. 2021, ``lisa_mc``, *strongest* mode) puts a drop
    in place of its return: every drop of the beam's cone (Marshall–Palmer sizes from 0.05 mm, ranges from the
    cone's ``s²`` law, a Poisson count), the strongest replacing a return of power ``p0`` when it beats it and
    ``0.9 / range_max²``. Drawn out to ``min(reach, √(ρ_w / P_min))``: no drop beyond can beat ``P_min``."""
    rho_w = ((1.328 - 1) / (1.328 + 1)) ** 2
    p_min = 0.9 / range_max**2
    lam = 4.1 * rain**-0.21
    per_m3 = 8000.0 * math.exp(-lam * 0.05) / lam
    top = np.minimum(reach, math.sqrt(rho_w / p_min))
    counts = rng.poisson(per_m3 * math.pi / 3 * top * (divergence * top / 2) ** 2)
    beam = np.repeat(np.arange(len(p0)), counts)
    s = top[beam] * rng.random(len(beam)) ** (1 / 3)
    d_mm = 0.05 + rng.exponential(1 / lam, len(beam))
    power = rho_w * np.minimum((d_mm / (1e3 * divergence * s)) ** 2, 1) * np.exp(-2 * sigma * s) / s**2
    power = np.where(s > range_min, power, 0.0)
    best = np.zeros(len(p0))
    np.maximum.at(best, beam, power)
    return best > np.maximum(p0, p_min)


@pytest.mark.parametrize("rain", [10.0, 50.0])
def test_rain_drops_return_as_lisa_draws_them(rain: float) -> None:
    """In rain a diverging beam's drops return (LISA's model, ``lidar_rain.rs``): the share of beams whose return is
    a drop (class 0, instance -1) matches a NumPy re-implementation of LISA's brute-force draw of every drop in
    every beam within 4.5 standard errors, beam by beam from the dry scan's own returns; those points lie between
    the minimum range and 0.149 of the range; more rain, more of them; without rain none."""
    sigma = Weather.make("rain", rain_mm_per_h=rain).extinction_per_m
    lidar = exact_lidar(32, 720, range_min=0.5, beam_divergence=3e-3)
    dry = do_scan(lidar, room_scene(), seed=4, fog_extinction_per_m=sigma)
    wet = do_scan(lidar, room_scene(), seed=4, fog_extinction_per_m=sigma, rain_mm_per_h=rain)
    drop = wet.semantic_class == 0
    assert (wet.instance[drop] == -1).all() and (wet.instance[~drop] >= 0).all()
    assert (wet.range[drop] >= 0.5).all() and (wet.range[drop] <= 0.149 * 200.0).all()
    # The dry scan's power per beam, LISA's units: the intensity without its near-range factor, over r².
    r = dry.range.astype(np.float64)
    p0 = np.zeros(lidar.num_rays)
    p0[dry.ray_index] = dry.intensity * (1 + (r / 100) ** 2) / r**2
    reach, _ = room_truth(np.asarray(lidar.pattern(), dtype=np.float64))
    assert np.isfinite(reach).all()  # every beam meets the room (its return lost to the air's extinction or not)
    brute = _lisa_brute_share(
        p0, reach, rain=rain, sigma=sigma, divergence=3e-3, range_min=0.5, range_max=200.0,
        rng=np.random.default_rng(11),
    )  # fmt: skip
    n = lidar.num_rays
    got, want = drop.sum() / n, brute.mean()
    se = math.sqrt(got * (1 - got) / n + want * (1 - want) / n)
    assert drop.sum() > 100 and abs(got - want) < 4.5 * se, f"{rain} mm/h: {got:.4f} of beams vs LISA {want:.4f}"
    # Where no drop won, the return is the dry one to the bit.
    kept = np.isin(dry.ray_index, wet.ray_index[~drop])
    np.testing.assert_array_equal(dry.intensity[kept], wet.intensity[~drop])
    # The default LiDAR config has a diverging beam, and passes it on; negative is refused naming the field.
    assert LidarConfig().beam_divergence_mrad == 3.0
    with pytest.raises(ValueError, match="beam_divergence_mrad"):
        LidarConfig(beam_divergence_mrad=-1.0)
    for mrad, any_drop in ((3.0, True), (0.0, False)):
        made = lidar_from_config(LidarConfig(points_per_second=32 * 720 * 5.0, beam_divergence_mrad=mrad))
        assert (do_scan(made, room_scene(), seed=4, rain_mm_per_h=50.0).semantic_class == 0).any() == any_drop


def test_more_rain_more_drop_returns() -> None:
    lidar = exact_lidar(32, 720, range_min=0.5, beam_divergence=3e-3)
    counts = [
        int((do_scan(lidar, room_scene(), seed=4, rain_mm_per_h=rate).semantic_class == 0).sum())
        for rate in (0.0, 2.0, 10.0, 50.0)
    ]
    assert counts[0] == 0 and counts == sorted(counts) and counts[-1] > 2 * counts[1], counts


@pytest.mark.parametrize(("fog", "rain"), [(0.0, 0.0), (0.004, 0.0), (0.004, 50.0)])
def test_intensity_formula(fog: float, rain: float) -> None:
    """``τ = exp(−2σr)`` with σ the visibility's extinction alone, in rain too (its drops are in the visibility)."""
    lidar = exact_lidar(32, 360)
    pose = pose_matrices(np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    pts = do_scan(lidar, room_scene(), pose, seed=2, fog_extinction_per_m=fog, rain_mm_per_h=rain)
    pat = np.asarray(lidar.pattern(), dtype=np.float64)
    truth, cos = room_truth(pat)
    r = truth[pts.ray_index]
    tau = np.exp(-2 * fog * r)
    want = REFLECTIVITY[ROOM_CLASS] * cos[pts.ray_index] * tau / (1 + (r / 100.0) ** 2)
    np.testing.assert_allclose(pts.intensity, want, rtol=1e-4, atol=1e-6)
    assert pts.intensity.min() >= 0 and pts.intensity.max() <= 1


def test_intensity_in_unit_interval_and_by_class() -> None:
    scene, pose = _demo_case()
    lidar = exact_lidar(32, 720)
    pts = do_scan(lidar, scene, pose, seed=3)
    assert np.all((pts.intensity >= 0) & (pts.intensity <= 1))
    # Per class, intensity never exceeds the class reflectivity (|cos| ≤ 1, τ ≤ 1, range factor ≤ 1).
    for c in np.unique(pts.semantic_class):
        sel = pts.semantic_class == c
        assert pts.intensity[sel].max() <= REFLECTIVITY[int(c)] + 1e-6, f"class {c}"
