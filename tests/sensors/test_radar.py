"""The marine radar (:mod:`mmusv.sensors.radar`): returns where the targets are, a PPI at a fixed scale,
determinism, sea clutter that grows with the waves, and configuration errors that name the field.

Scenes are a sea plane (class WATER) with 10 m box "vessels" at known ranges and bearings; settings are small
(512 beams, 1.5 km) so every sweep takes milliseconds, with the threshold 0.01 and σ⁰ 4e-6 these tests were
written for (plenty of clutter); one test checks the schema defaults (0.3, 4e-7) on their own.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import numpy.typing as npt
import pytest
from mmusv._native import core
from mmusv.classes import SemanticClass
from mmusv.config import load_scenario
from mmusv.sensors import RadarConfig, sensor_env
from mmusv.sensors.radar import RadarReturns, ppi_colormap, ppi_image, ppi_png, radar_from_config, radar_sweep
from pydantic import ValidationError

SMALL = RadarConfig(range_m=1500.0, azimuth_bins=512, rays_el=32, detection_threshold=0.01, sea_clutter_sigma0=4.0e-6)
RADAR = radar_from_config(SMALL)


def small(**change: Any) -> RadarConfig:
    """SMALL with some fields changed (validated)."""
    return RadarConfig(**{**SMALL.model_dump(), **change})


def env(*, waves: float = 0.0, rain: float = 0.0) -> Any:
    """Clear air with ``waves`` metres of waves and ``rain`` mm/h."""
    return sensor_env(fog_extinction_per_m=0.0, rain_mm_per_h=rain, wave_height_m=waves)


MAST_HEIGHT = 3.0
HALF = 5.0  # half side of the box targets, metres


def box_mesh(half: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """A cube of side ``2 half`` centred on the origin, outward winding."""
    a = half
    v = np.array(
        [[-a, -a, -a], [a, -a, -a], [a, a, -a], [-a, a, -a], [-a, -a, a], [a, -a, a], [a, a, a], [-a, a, a]],
        dtype=np.float64,
    )
    f = np.array(
        [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]],
        dtype=np.int64,
    )  # fmt: skip
    return v, f


def pose_at(x: float, y: float, z: float, yaw: float) -> npt.NDArray[np.float64]:
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.eye(4)
    p[:2, :2] = [[c, -s], [s, c]]
    p[:3, 3] = [x, y, z]
    return p


def box_pose(near_range: float, bearing: float) -> npt.NDArray[np.float64]:
    """Pose of a box whose near face is ``near_range`` m from the origin at world ``bearing`` (facing it)."""
    c = near_range + HALF
    return pose_at(c * math.cos(bearing), c * math.sin(bearing), 3.0, bearing)


class Sea:
    """A sea plane (instance 0), a target box and a second, movable box."""

    def __init__(self, near_range: float, bearing: float) -> None:
        self.scene = mmusv.Scene()
        h = 20_000.0
        water = self.scene.add_mesh(
            np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], dtype=np.float64),
            np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64),
            classes=int(SemanticClass.WATER),
        )
        self.water = self.scene.add_instance(water)
        v, f = box_mesh(HALF)
        cube = self.scene.add_mesh(v, f, classes=int(SemanticClass.VESSEL))
        self.target = self.scene.add_instance(cube, pose=box_pose(near_range, bearing))
        big_v, big_f = box_mesh(4 * HALF)
        big = self.scene.add_mesh(big_v, big_f, classes=int(SemanticClass.VESSEL))
        self.other = self.scene.add_instance(big, pose=box_pose(600.0, bearing + 2.0))

    def move_other(self, near_range: float, bearing: float) -> None:
        self.scene.set_poses([self.other], box_pose(near_range, bearing)[None])


def wrap(a: float | npt.NDArray[Any]) -> Any:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


@pytest.mark.parametrize(
    ("near_range", "bearing_deg", "yaw_deg"), [(250.0, 0.0, 0.0), (640.0, 75.0, 30.0), (1180.0, -140.0, 200.0)]
)
def test_box_return_at_its_range_bearing_and_id(near_range: float, bearing_deg: float, yaw_deg: float) -> None:
    sea = Sea(near_range, math.radians(bearing_deg))
    yaw = math.radians(yaw_deg)
    ret = radar_sweep(RADAR, sea.scene, pose=pose_at(0, 0, MAST_HEIGHT, yaw), env=env(), seed=0)
    mine = ret.instance_id == sea.target
    assert mine.any(), "the target box was not seen"
    assert set(np.unique(ret.instance_id)) <= {sea.target, sea.other}, "no clutter on a calm sea"
    assert abs(float(ret.range[mine].min()) - near_range) <= SMALL.range_resolution_m
    k = int(np.argmax(np.where(mine, ret.intensity, -np.inf)))
    expected = math.radians(bearing_deg) - yaw  # bearing in the sensor frame
    # Within half a beam (plus half a bin) of some point of the 10 m wide face.
    tol = math.radians(SMALL.beamwidth_deg) / 2 + math.pi / SMALL.azimuth_bins + math.atan(HALF / near_range)
    assert abs(float(wrap(ret.azimuth[k] - expected))) <= tol
    assert ret.semantic_class[k] == SemanticClass.VESSEL
    # World positions of the target's returns lie at its near face (within a range bin and the beam).
    centre = box_pose(near_range, math.radians(bearing_deg))[:2, 3]
    world = ret.points(frame="world")[mine]
    dist = np.linalg.norm(world[:, :2] - centre, axis=1)
    assert dist.min() < HALF + SMALL.range_resolution_m + near_range * math.radians(SMALL.beamwidth_deg)
    # Dtypes, shapes, sorted order, azimuth range.
    assert ret.range.dtype == np.float32 and ret.instance_id.dtype == np.int32 and ret.semantic_class.dtype == np.uint16
    assert all(a.shape == (len(ret),) for a in (ret.azimuth, ret.elevation, ret.intensity))
    beams = np.rint(ret.azimuth / (2 * np.pi) * SMALL.azimuth_bins).astype(np.int64)
    order = np.lexsort((ret.range, beams))
    assert np.array_equal(order, np.arange(len(ret)))
    assert ((ret.azimuth >= 0) & (ret.azimuth < 2 * np.pi)).all()
    assert (ret.intensity >= SMALL.detection_threshold).all()


def brightest_near(img: npt.NDArray[np.float32], row: float, col: float, radius: int = 6) -> tuple[int, int]:
    r0, c0 = round(row) - radius, round(col) - radius
    win = img[r0 : r0 + 2 * radius + 1, c0 : c0 + 2 * radius + 1]
    assert win.max() > 0, "nothing painted near the target"
    r, c = np.unravel_index(int(np.argmax(win)), win.shape)
    return r0 + int(r), c0 + int(c)


@pytest.mark.parametrize("orientation", ["north_up", "head_up"])
def test_ppi_scale_is_fixed_while_other_objects_move(orientation: str) -> None:
    size, mpp = 701, 5.0
    c = size // 2
    yaw = math.radians(35.0)
    bearing = math.radians(120.0)
    for near_range in (200.0, 455.0, 810.0, 1330.0):
        sea = Sea(near_range, bearing)
        dists = []
        for other_range, other_bearing in ((60.0, 0.5), (900.0, -2.0), (1450.0, 3.0)):
            sea.move_other(other_range, other_bearing)
            ret = radar_sweep(RADAR, sea.scene, pose=pose_at(0, 0, MAST_HEIGHT, yaw), env=env(), seed=1)
            img = ppi_image(ret, size_px=size, metres_per_pixel=mpp, orientation=orientation)  # type: ignore[arg-type]
            assert img.shape == (size, size) and img.dtype == np.float32
            theta = bearing if orientation == "north_up" else bearing - yaw + math.pi / 2
            rho = near_range / mpp
            row, col = brightest_near(img, c - rho * math.sin(theta), c + rho * math.cos(theta))
            d = math.hypot(row - c, col - c)
            assert abs(d - rho) <= 1.0, f"{orientation}: target at {near_range} m drawn {d:.2f} px out, want {rho:.2f}"
            dists.append(d)
        assert max(dists) - min(dists) <= 1.0, dists


def test_ppi_default_scale_and_yaw_come_from_the_sweep() -> None:
    sea = Sea(700.0, 0.0)
    ret = radar_sweep(RADAR, sea.scene, pose=pose_at(0, 0, MAST_HEIGHT, 0.4), env=env(), seed=0)
    assert math.isclose(ret.sensor_yaw, 0.4, abs_tol=1e-9)
    default = ppi_image(ret, size_px=300)
    explicit = ppi_image(ret, size_px=300, metres_per_pixel=SMALL.range_m / 150, sensor_yaw=0.4)
    assert np.array_equal(default, explicit)


def test_same_seed_same_arrays_other_seed_other_clutter() -> None:
    sea = Sea(500.0, 1.0)
    radar = radar_from_config(small(range_noise_std_m=0.4))
    pose = pose_at(0, 0, MAST_HEIGHT, 0.0)
    a = radar_sweep(radar, sea.scene, pose=pose, env=env(waves=2.0), seed=11)
    b = radar_sweep(radar, sea.scene, pose=pose, env=env(waves=2.0), seed=11)
    c = radar_sweep(radar, sea.scene, pose=pose, env=env(waves=2.0), seed=12)
    fields = ("range", "azimuth", "elevation", "intensity", "instance_id", "semantic_class")
    for name in fields:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.is_clutter.sum() > 100

    def cells(r: RadarReturns) -> set[tuple[float, float]]:
        return {
            (float(x), float(y)) for x, y in zip(r.azimuth[r.is_clutter], np.rint(r.range[r.is_clutter]), strict=False)
        }

    assert cells(a) != cells(c), "a different seed must give different clutter"
    assert (a.semantic_class[a.is_clutter] == SemanticClass.WATER).all()


def clutter_count(ret: RadarReturns) -> int:
    return int(ret.is_clutter.sum())


def test_sea_clutter_grows_from_w0_to_w3() -> None:
    sea = Sea(1200.0, 0.0)
    pose = pose_at(0, 0, MAST_HEIGHT, 0.0)
    heights = [core.wave_height(w) for w in ("W0", "W1", "W2", "W3")]
    assert heights[0] == 0.5 and heights[-1] == 3.5
    rets = [radar_sweep(RADAR, sea.scene, pose=pose, env=env(waves=h), seed=5) for h in heights]
    counts = [clutter_count(r) for r in rets]
    reach = [float(r.range[r.is_clutter].max()) for r in rets]
    assert counts[0] > 0 and all(x < y for x, y in itertools.pairwise(counts)), counts
    assert counts[-1] > 3 * counts[0], counts
    assert reach[-1] > 2 * reach[0], reach
    assert reach[-1] < SMALL.sea_clutter_max_range_m
    # The target is still there, and calm water has no clutter at all.
    assert (rets[-1].instance_id == sea.target).any()
    assert clutter_count(radar_sweep(RADAR, sea.scene, pose=pose, env=env(), seed=5)) == 0
    # Rain adds (a little) clutter of class NONE and attenuates the target.
    wet = radar_sweep(RADAR, sea.scene, pose=pose, env=env(rain=8.0), seed=5)
    assert 0 < clutter_count(wet) < counts[-1]
    assert (wet.semantic_class[wet.is_clutter] == SemanticClass.NONE).all()


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"azimuth_bins": 0}, "azimuth_bins"),
        ({"range_m": -100.0}, "range_m"),
        ({"min_range_m": -1.0}, "min_range_m"),
        ({"range_resolution_m": 0.0}, "range_resolution_m"),
        ({"beamwidth_deg": 0.0}, "beamwidth_deg"),
        ({"beamwidth_deg": -1.0}, "beamwidth_deg"),
        ({"elevation_fan_deg": (10.0, -10.0)}, "elevation_fan_deg"),
        ({"rays_az": 0}, "rays_az"),
        ({"rays_el": 0}, "rays_el"),
        ({"rays_el": 2.5}, "rays_el"),
        ({"detection_threshold": -0.1}, "detection_threshold"),
        ({"horizon_fraction": 2.0}, "horizon_fraction"),
        ({"horizon_band_deg": 90.0}, "horizon_band_deg"),
        ({"sea_clutter_sigma0": float("nan")}, "sea_clutter_sigma0"),
        # A range bin longer than the span it measures: every echo was reported beyond the range, none returned.
        ({"range_m": 100.0, "min_range_m": 1.0, "range_resolution_m": 1000.0}, "range_resolution_m"),
    ],
)
def test_bad_settings_raise_an_error_naming_the_field(change: dict[str, Any], field: str) -> None:
    with pytest.raises(ValidationError, match=field):
        small(**change)
    # In a scenario, the error is a ConfigError with the whole path.
    scenario = {
        "rigs": {"r": {"radar": {**SMALL.model_dump(exclude={"mount"}), **change}}},
        "vessels": [{"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[0, 0], [10, 0]]}],
    }
    with pytest.raises(mmusv.ConfigError, match=rf"rigs\.r\.radar\b.*{field}"):
        load_scenario(scenario)


def test_the_schema_limits_are_the_cores() -> None:
    """A config the schema accepts never trips the core's own checks, at the edges of what is allowed."""
    edges = [
        {"azimuth_bins": 65536, "rays_az": 8, "rays_el": 16},  # 2**23 rays (the core allows 2**24)
        {"range_m": 100_000.0, "range_resolution_m": 100_000.0 / 2**20},  # 2**20 range bins
        {"beamwidth_deg": 90.0, "horizon_band_deg": 45.0, "horizon_fraction": 1.0, "elevation_fan_deg": (-89.9, 89.9)},
        {"sea_clutter_sigma0": 1.0, "rain_clutter_eta": 1.0, "range_noise_std_m": 100_000.0, "min_range_m": 0.0},
    ]
    for change in edges:
        radar_from_config(RadarConfig(**change))  # no error from the core
    for change in [{"azimuth_bins": 65536, "rays_az": 8, "rays_el": 17}, {"range_resolution_m": 3000.0 / (2**20 + 1)}]:
        with pytest.raises(ValidationError, match="at most"):
            RadarConfig(**change)
    for bad in [{"detection_threshold": float("inf")}, {"range_noise_std_m": 2e5}, {"sea_clutter_sigma0": 2.0}]:
        with pytest.raises(ValidationError, match=next(iter(bad))):
            RadarConfig(**bad)


def test_defaults_come_from_the_schema_and_keep_clutter_near_the_ship() -> None:
    """The binding has no defaults of its own: a radar from ``RadarConfig()`` has the schema's threshold 0.3 and
    σ⁰ 4e-7. With them sea clutter still grows with every sea state but stays within a few hundred metres,
    while the target at 1.2 km is seen."""
    radar = radar_from_config(RadarConfig())
    assert (radar.detection_threshold, radar.sea_sigma0_at_1m) == (0.3, 4.0e-7)
    geometry = (radar.range_max_m, radar.range_resolution_m, radar.azimuth_bins, radar.num_rays)
    assert geometry == (3000.0, 3.0, 2048, 2048 * 3 * 16)
    sea = Sea(1200.0, 0.0)
    pose = pose_at(0, 0, MAST_HEIGHT, 0.0)
    schema = radar_from_config(RadarConfig(range_m=1500.0, azimuth_bins=512, rays_el=32))
    rets = [radar_sweep(schema, sea.scene, pose=pose, env=env(waves=core.wave_height(w)), seed=5) for w in ("W0", "W3")]
    counts = [clutter_count(r) for r in rets]
    assert 0 < counts[0] < counts[1], counts
    assert float(rets[1].range[rets[1].is_clutter].max()) < 400.0
    assert all((r.instance_id == sea.target).any() for r in rets)
    tuned = radar_sweep(RADAR, sea.scene, pose=pose, env=env(waves=3.5), seed=5)
    assert clutter_count(tuned) > 3 * counts[1]


def test_bad_environment_pose_and_ppi_arguments() -> None:
    sea = Sea(300.0, 0.0)
    with pytest.raises(mmusv.ConfigError, match="wave_height_m"):
        env(waves=-1.0)
    with pytest.raises(mmusv.ConfigError, match="wave_height_m"):
        radar_sweep(RADAR, sea.scene, pose=np.eye(4), env=env(waves=31.0), seed=0)
    with pytest.raises(mmusv.ConfigError, match="rain_mm_per_h"):
        env(rain=float("inf"))
    with pytest.raises(mmusv.ConfigError, match="rain_mm_per_h"):
        radar_sweep(RADAR, sea.scene, pose=np.eye(4), env=env(rain=501.0), seed=0)
    with pytest.raises(mmusv.InputError, match="pose"):
        radar_sweep(RADAR, sea.scene, pose=np.eye(3), env=env(), seed=0)
    with pytest.raises(mmusv.InputError, match="seed"):
        radar_sweep(RADAR, sea.scene, pose=np.eye(4), env=env(), seed=-1)
    ret = radar_sweep(RADAR, sea.scene, pose=np.eye(4), env=env(), seed=0)
    with pytest.raises(mmusv.ConfigError, match="orientation"):
        ppi_image(ret, orientation="sideways")  # type: ignore[arg-type]
    with pytest.raises(mmusv.ConfigError, match="metres_per_pixel"):
        ppi_image(ret, metres_per_pixel=0.0)
    with pytest.raises(mmusv.ConfigError, match="size_px"):
        ppi_image(ret, size_px=0)


def test_colormap_matches_its_formula_pixel_by_pixel() -> None:
    """dB mapped linearly from -20 to 30 dB, then (255 t³, 50 + 205 t^0.6, 30 t + 200 t⁴) rounded; black where the
    intensity is not > 0 (NaN included). Checked one pixel at a time in plain Python."""
    rng = np.random.default_rng(3)
    img = np.where(rng.random((40, 50)) < 0.2, 10 ** rng.uniform(-4, 5, (40, 50)), 0.0).astype(np.float32)
    img[0, :6] = [np.inf, np.nan, -1.0, 1e-30, 0.01, 1000.0]
    rgb = ppi_colormap(img)
    for (i, j), v in np.ndenumerate(img):
        if not v > 0:
            want = (0, 0, 0)
        else:
            t = min(max((10.0 * math.log10(float(v)) + 20.0) / 50.0, 0.0), 1.0)
            want = (round(255.0 * t**3), round(50.0 + 205.0 * t**0.6), round(30.0 * t + 200.0 * t**4))
        got = tuple(int(c) for c in rgb[i, j])
        assert all(abs(g - w) <= 1 for g, w in zip(got, want, strict=True)), ((i, j), v, got, want)
    assert tuple(rgb[0, 4]) == (0, 50, 0) and tuple(rgb[0, 5]) == (255, 255, 230)  # -20 dB, +30 dB


def test_colormap_and_png(tmp_path: Path) -> None:
    from PIL import Image

    sea = Sea(400.0, 0.3)
    ret = radar_sweep(RADAR, sea.scene, pose=pose_at(0, 0, MAST_HEIGHT, 0.0), env=env(waves=1.0), seed=0)
    img = ppi_image(ret, size_px=256)
    rgb = ppi_colormap(img)
    assert rgb.shape == (256, 256, 3) and rgb.dtype == np.uint8
    assert (rgb[img <= 0] == 0).all() and (rgb[img > 0].max(axis=1) > 0).all()
    path = tmp_path / "ppi.png"
    ppi_png(path, img)
    back = np.asarray(Image.open(path))
    assert back.shape == (256, 256, 3) and np.array_equal(back, rgb)
