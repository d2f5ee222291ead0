"""The physically based camera image: exposure, sun disc, anti-aliasing, lens distortion, sensor noise, nav lights,
whitecaps and wakes, each against an independent computation (closed forms, a forward model in numpy, the
Monahan formula) rather than against pictures."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv._native import core
from mmusv.scene import Scene
from mmusv.sensors.camera import render
from mmusv.sensors.env import sensor_env
from mmusv.world.build import pose_matrices
from mmusv.world.environment import Environment
from mmusv.world.primitives import box


def _env(**kw: float) -> core.SensorEnv:
    base = {"fog_extinction_per_m": 0.0, "rain_mm_per_h": 0.0, "wave_height_m": 0.0, "wind_speed_m_s": 0.0}
    base.update(kw)
    return sensor_env(**base)  # type: ignore[arg-type]


def _box(s: Scene, lo: tuple[float, float, float], hi: tuple[float, float, float], *, cls: int, mat: int = 0) -> int:
    """An axis-aligned box from corner ``lo`` to ``hi`` (the library's box primitive), material ``mat``."""
    lo_, hi_ = np.asarray(lo), np.asarray(hi)
    m = box(center=(lo_ + hi_) / 2.0, size=hi_ - lo_, cls=cls)
    return s.add_instance(s.add_mesh(m.vertices, m.faces, classes=cls, name="box", materials=mat))


def _water(s: Scene, half: float = 5000.0) -> int:
    v = np.array([[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]])
    return s.add_instance(s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), classes=1, name="water"))


def test_metered_exposure_puts_a_grey_card_at_0_18() -> None:
    env = _env()
    lux, k = env.exposure
    assert lux > 50_000  # a clear noon: sun and sky together
    assert k == pytest.approx(math.pi / lux, rel=1e-6)
    # A fixed EV100 gives the saturation-based scale 1 / (1.2 · 2^EV).
    fixed = sensor_env(exposure_ev100=14.0)
    assert fixed.exposure[1] == pytest.approx(1.0 / (1.2 * 2.0**14), rel=1e-6)


def _metered_key(radiance: np.ndarray, width: int) -> float:
    """The highlight limit's reading: the log-average luminance of every 4th pixel of every 4th row (black as
    10⁻⁶ cd/m²), computed here independently of the core."""
    lum = (radiance.reshape(-1, width, 3)[::4, ::4] @ np.array([0.2126, 0.7152, 0.0722])).astype(np.float32)
    return float(np.exp(np.mean(np.log(np.maximum(lum, 1e-6).astype(np.float64)))))


@pytest.mark.parametrize(("time_of_day", "limited"), [("10:30", False), ("16:30", False), ("20:15", True)])
def test_exposure_holds_a_view_brighter_than_its_light_at_the_key(time_of_day: str, limited: bool) -> None:
    """The automatic exposure is the incident reading unless the view, so exposed, would average (log-average
    luminance, read on every 4th pixel of every 4th row) brighter than 0.5 before the tone curve; then it holds
    it at 0.5. By day, looking over the water towards the sun's side, the incident exposure stands; at 20:15
    (sun 4.5° below the horizon), looking into the afterglow, it is lowered and most of the picture is no longer
    white. Each image is compared with the same view at the fixed exposure the rule gives."""
    cfg = Environment.make(time_of_day=time_of_day)
    d = np.asarray(cfg.sun.direction)
    yaw = math.atan2(d[1], d[0])
    s = Scene()
    _water(s)

    w, h = 96, 54
    cam = core.Camera(width=w, height=h, rgb=True, hfov=math.radians(60.0), quality="draft")
    pose = pose_matrices(np.array([0, 0, 3.0, 0, math.radians(5.0), yaw]))
    env = sensor_env(cfg, wave_height_m=0.5)
    img = render(cam, s, pose=pose, env=env, seed=1, radiance=True)
    assert img.radiance is not None and img.rgb is not None
    k_incident = env.exposure[1]
    key = _metered_key(np.asarray(img.radiance), w)
    assert (key * k_incident > 0.5) == limited, key * k_incident
    k = min(k_incident, 0.5 / key)

    def at(k_fixed: float) -> np.ndarray:
        ev = math.log2(1.0 / (1.2 * k_fixed))  # the saturation-based scale 1 / (1.2 · 2^EV) = k_fixed
        fixed = render(cam, s, pose=pose, env=sensor_env(cfg, wave_height_m=0.5, exposure_ev100=ev), seed=1)
        assert fixed.rgb is not None
        return np.asarray(fixed.rgb).astype(np.int16)

    got = np.asarray(img.rgb).astype(np.int16)
    assert np.abs(got - at(k)).max() <= 1  # the same exposure, to the rounding of EV
    white = np.mean(got.max(axis=-1) >= 250)
    if limited:
        assert white < 0.3 and np.mean(at(k_incident).max(axis=-1) >= 250) > 0.5, white
    else:
        assert white < 0.05


@pytest.mark.parametrize(
    ("time_of_day", "exposure"),
    [
        ("10:30", (None, 1.0, 6400.0)),
        ("10:30", (None, -1.5, 6400.0)),
        ("20:15", (None, 1.0, 6400.0)),  # held by the highlight limit: the compensation shifts the held value
        ("21:45", (None, 0.0, 6400.0)),  # below the floor: the camera's limit at ISO 6 400
        ("21:45", (None, 0.0, 25600.0)),  # two stops more gain: a quarter of the light
        ("21:45", (None, 0.5, 1600.0)),
    ],
)
def test_camera_exposure_settings_follow_the_metering_rule(
    time_of_day: str, exposure: tuple[float | None, float, float]
) -> None:
    """A camera's own exposure settings: the incident reading floored at the light its highest ISO reaches
    (3.46 lux at ISO 6 400, scaled by 6 400 / ISO), the highlight limit, then ``2^compensation``; each image is
    compared with the same view at the fixed exposure this rule, computed here, gives."""
    _, comp, max_iso = exposure
    cfg = Environment.make(time_of_day=time_of_day)
    d = np.asarray(cfg.sun.direction)
    yaw = math.atan2(d[1], d[0])
    s = Scene()
    _water(s)
    _box(s, (60.0, -10.0, 0.0), (80.0, 10.0, 12.0), cls=3)
    w, h = 96, 54
    cam = core.Camera(width=w, height=h, rgb=True, hfov=math.radians(60.0), quality="draft", exposure=exposure)
    pose = pose_matrices(np.array([0, 0, 3.0, 0, math.radians(5.0), yaw]))
    env = sensor_env(cfg, wave_height_m=0.5)
    img = render(cam, s, pose=pose, env=env, seed=1, radiance=True)
    assert img.radiance is not None and img.rgb is not None
    lux = env.exposure[0]
    k_incident = math.pi / max(lux, 3.46 * 6400.0 / max_iso)
    key = _metered_key(np.asarray(img.radiance), w)
    k = min(k_incident, 0.5 / key) * 2.0**comp
    ev = math.log2(1.0 / (1.2 * k))
    fixed = render(
        cam_fixed := core.Camera(width=w, height=h, rgb=True, hfov=math.radians(60.0), quality="draft"),
        s,
        pose=pose,
        env=sensor_env(cfg, wave_height_m=0.5, exposure_ev100=ev),
        seed=1,
    )
    assert cam_fixed.resolution == (w, h) and fixed.rgb is not None
    got = np.asarray(img.rgb).astype(np.int16)
    assert np.abs(got - np.asarray(fixed.rgb).astype(np.int16)).max() <= 1
    # And the same camera at its default settings shows another picture wherever the settings differ from them.
    default = render(
        core.Camera(width=w, height=h, rgb=True, hfov=math.radians(60.0), quality="draft"),
        s,
        pose=pose,
        env=env,
        seed=1,
    )
    assert default.rgb is not None
    changed = not (comp == 0.0 and (max_iso == 6400.0 or lux >= 3.46 * 6400.0 / max_iso))
    assert np.array_equal(np.asarray(default.rgb), np.asarray(img.rgb)) != changed


def test_a_fixed_camera_exposure_is_the_environments_fixed_exposure() -> None:
    """``exposure=(ev100, 0, iso)`` on the camera gives the bytes of the same EV100 fixed for the whole
    environment, at noon and at dusk alike (no metering, no highlight limit)."""
    s = Scene()
    _water(s)
    _box(s, (60.0, -10.0, 0.0), (80.0, 10.0, 12.0), cls=3)
    pose = pose_matrices(np.array([0, 0, 3.0, 0, math.radians(3.0), 0.3]))
    for tod in ("12:00", "20:30"):
        cfg = Environment.make(time_of_day=tod)
        mine = core.Camera(width=64, height=48, rgb=True, hfov=1.2, exposure=(11.0, 0.0, 6400.0))
        plain = core.Camera(width=64, height=48, rgb=True, hfov=1.2)
        a = render(mine, s, pose=pose, env=sensor_env(cfg), seed=4)
        b = render(plain, s, pose=pose, env=sensor_env(cfg, exposure_ev100=11.0), seed=4)
        assert a.rgb is not None and b.rgb is not None
        assert np.array_equal(np.asarray(a.rgb), np.asarray(b.rgb)), tod


@pytest.mark.parametrize(
    ("exposure", "field"),
    [
        ({"ev100": 30}, "exposure.ev100"),
        ({"compensation_ev": -9}, "exposure.compensation_ev"),
        ({"max_iso": 50}, "exposure.max_iso"),
        ({"ev100": 12, "compensation_ev": 1}, "exposure"),
        ({"iso": 800}, "exposure.iso"),
    ],
)
def test_camera_exposure_misconfig_names_the_field(exposure: dict[str, float], field: str) -> None:
    from mmusv.sensors.config import CameraConfig, TopViewConfig

    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        CameraConfig(name="front", exposure=exposure)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        TopViewConfig(exposure=exposure)  # type: ignore[arg-type]
    for bad, name in [
        ((40.0, 0.0, 6400.0), "ev100"),
        ((None, 7.0, 6400.0), "compensation_ev"),
        ((None, 0.0, 1e7), "max_iso"),
        ((12.0, 1.0, 6400.0), "compensation_ev"),
    ]:
        with pytest.raises(mmusv.ConfigError, match=rf"camera\.exposure\.{name}"):
            core.Camera(width=8, height=8, rgb=True, hfov=1.0, exposure=bad)


def test_sun_disc_has_its_true_angular_size() -> None:
    """Looking at the sun with a narrow camera: the pixels inside the disc cover a 0.533° circle."""
    env = sensor_env(Environment.make(time_of_day="15:00"))
    sun = np.asarray(env.sky_radiance(np.array([[0, 0, 1]], dtype=np.float32)))  # just to touch the API
    assert sun.shape == (1, 3)
    # Point the camera at the sun: direction from the environment.
    d = np.asarray(Environment.make(time_of_day="15:00").sun.direction)
    yaw, pitch = math.atan2(d[1], d[0]), -math.asin(d[2])
    w = h = 101
    hfov = math.radians(2.0)
    cam = core.Camera(width=w, height=h, rgb=True, hfov=hfov, quality="draft")
    img = render(cam, Scene(), pose=pose_matrices(np.array([0, 0, 0, 0, pitch, yaw])), env=env, seed=1, radiance=True)
    assert img.radiance is not None
    lum = img.radiance @ np.array([0.2126, 0.7152, 0.0722])
    disc = lum > 0.5 * lum.max()
    pixel_deg = 2.0 / w
    want = math.pi * (0.5333 / 2 / pixel_deg) ** 2
    assert disc.sum() == pytest.approx(want, rel=0.1), (disc.sum(), want)
    # The disc is ~10^5 times brighter than the sky beside it.
    assert lum.max() / np.median(lum) > 1e4


@pytest.mark.parametrize("time_of_day", ["20:15", "21:00"])
def test_twilight_sky_is_blue_over_an_orange_afterglow(time_of_day: str) -> None:
    """Sun 4.5° and 10° below the horizon (21 June, 45° N): towards it, the band just over the horizon is orange
    and outshines the sky above, which is blue; at 4.5° the sky opposite is blue too (at 10° it is near the night
    floor, where single scattering leaves it a dim reddish grey). The twilight model's colours reach the cameras'
    sky through the bindings; its physics is tested in the core."""
    env_cfg = Environment.make(time_of_day=time_of_day)
    assert env_cfg.sun.elevation_deg < -4.0
    d = np.asarray(env_cfg.sun.direction)
    az = math.atan2(d[1], d[0])

    def towards(elev_deg: float, azimuth: float) -> list[float]:
        e = math.radians(elev_deg)
        return [math.cos(e) * math.cos(azimuth), math.cos(e) * math.sin(azimuth), math.sin(e)]

    dirs = np.array([towards(1.5, az), towards(35.0, az), towards(35.0, az + math.pi)], dtype=np.float32)
    band, above, opposite = np.asarray(sensor_env(env_cfg).sky_radiance(dirs))
    assert band[0] > 1.3 * band[1] > 2.0 * band[2], band
    assert above[2] > above[0], above
    if env_cfg.sun.elevation_deg > -6.0:
        assert opposite[2] > opposite[0], opposite
    lum = np.array([0.2126, 0.7152, 0.0722])
    assert band @ lum > 2.0 * (above @ lum)


def test_edge_pixels_are_averaged_and_labels_stay_exact() -> None:
    """A dark box on a bright sky: at standard quality its silhouette pixels take intermediate values equal to
    the covered fraction (checked against an analytic edge), while depth, class and instance stay the centre's."""
    s = Scene()
    black = np.zeros((2, 9), dtype=np.float32)
    black[1, :3] = 0.0  # material 1: black, rough
    black[1, 3] = 1.0
    s.set_materials(black)
    # A wall whose left edge is at y = 0.3 m, 10 m ahead: it crosses pixel columns at a fraction.
    _box(s, (10.0, -50.0, -50.0), (10.5, 0.3, 50.0), cls=4, mat=1)
    env = _env()
    pose = np.eye(4)
    hard = core.Camera(width=40, height=20, rgb=True, hfov=math.radians(40), quality="draft")
    soft = core.Camera(width=40, height=20, rgb=True, hfov=math.radians(40), quality="high")
    a = render(hard, s, pose=pose, env=env, seed=3, radiance=True)
    b = render(soft, s, pose=pose, env=env, seed=3, radiance=True)
    for name in ("depth", "semantic", "instance"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.radiance is not None and b.radiance is not None
    lum_a = a.radiance @ np.array([0.2126, 0.7152, 0.0722])
    lum_b = b.radiance @ np.array([0.2126, 0.7152, 0.0722])
    row = 10
    # Column of the edge: u = cx - fy·y/x with y = 0.3, x = 10 (body y left = image u decreasing).
    fx = 40 / (2 * math.tan(math.radians(20)))
    u_edge = 20 - fx * 0.3 / 10.0
    col = int(u_edge)
    covered = (col + 1) - u_edge  # the wall covers the right part [u_edge, col + 1) of that pixel
    sky, wall = lum_a[row, col - 1], lum_a[row, col + 1]  # the neighbours, one on each side of the edge
    assert wall < 0.05 * sky
    # Draft: one sample at the centre, all sky or all wall. High: the covered fraction of each.
    assert lum_a[row, col] == pytest.approx(wall if covered > 0.5 else sky, rel=0.15)
    expect = (1 - covered) * sky + covered * wall
    assert lum_b[row, col] == pytest.approx(expect, rel=0.15), (lum_b[row, col], expect, covered)


def test_brown_conrady_rays_land_where_the_forward_model_projects() -> None:
    """A distorted camera: a small marker's pixel equals the projection of its centre through the Brown–Conrady
    forward model (written here in numpy, OpenCV's convention)."""
    k = (-0.25, 0.06, 0.001, -0.002, 0.0)
    w, h, hfov = 160, 120, math.radians(80)
    cam = core.Camera(width=w, height=h, rgb=False, hfov=hfov, distortion=list(k))
    assert cam.distortion == pytest.approx(k)
    f = w / (2 * math.tan(hfov / 2))
    for y, z in ((3.0, 2.0), (-4.0, -2.5), (0.0, 0.0), (5.5, 3.5)):
        s = Scene()
        _box(s, (10.0, y - 0.1, z - 0.1), (10.1, y + 0.1, z + 0.1), cls=7)
        img = render(cam, s, pose=np.eye(4), env=_env(), seed=1)
        vs, us = np.nonzero(img.instance == 0)
        assert len(us) > 0, (y, z)
        # Optical coordinates of the marker: x right = -y, y down = -z, over the depth 10.
        xn, yn = -y / 10.0, -z / 10.0
        r2 = xn * xn + yn * yn
        k1, k2, p1, p2, k3 = k
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2**3
        xd = xn * radial + 2 * p1 * xn * yn + p2 * (r2 + 2 * xn * xn)
        yd = yn * radial + p1 * (r2 + 2 * yn * yn) + 2 * p2 * xn * yn
        u, v = w / 2 + f * xd, h / 2 + f * yd
        assert abs((us.mean() + 0.5) - u) < 1.0 and abs((vs.mean() + 0.5) - v) < 1.0, (us.mean(), vs.mean(), u, v)
    # A barrel strong enough to fold over inside the image leaves pixels without a ray: refused, naming the field.
    with pytest.raises(mmusv.ConfigError, match=r"camera\.distortion"):
        core.Camera(width=w, height=h, rgb=False, hfov=hfov, distortion=[-2.0, 0, 0, 0, 0])


def test_sensor_noise_has_shot_and_read_variance() -> None:
    """A uniform grey wall: with noise on, the sRGB spread is positive and reproducible from the seed; off, the
    wall is flat."""
    s = Scene()
    _box(s, (5.0, -50.0, -50.0), (5.5, 50.0, 50.0), cls=4)
    env = _env()
    clean = core.Camera(width=64, height=48, rgb=True, hfov=math.radians(40), quality="draft")
    noisy = core.Camera(width=64, height=48, rgb=True, hfov=math.radians(40), quality="draft", noise=(400.0, 5.0))
    a = render(clean, s, pose=np.eye(4), env=env, seed=2).rgb
    b = render(noisy, s, pose=np.eye(4), env=env, seed=2).rgb
    c = render(noisy, s, pose=np.eye(4), env=env, seed=2).rgb
    d = render(noisy, s, pose=np.eye(4), env=env, seed=9).rgb
    assert a is not None and b is not None and c is not None and d is not None
    assert a[..., 1].std() < 0.6
    assert b[..., 1].astype(float).std() > 2.0
    assert np.array_equal(b, c) and not np.array_equal(b, d)


def test_nav_lights_glow_at_night_only_under_way() -> None:
    s = Scene()
    table = np.zeros((2, 9), dtype=np.float32)
    table[1] = [0.8, 0.05, 0.05, 0.3, 0.0, 2e4, 0.0, 0.0, 1.0]  # a red sidelight
    s.set_materials(table)
    lamp = _box(s, (20.0, -0.2, 1.8), (20.3, 0.2, 2.2), cls=10, mat=1)
    night = sensor_env(Environment.make(time_of_day="23:30"))
    cam = core.Camera(width=64, height=48, rgb=True, hfov=math.radians(30), quality="draft")
    pose = pose_matrices(np.array([0.0, 0.0, 2.0, 0.0, 0.0, 0.0]))
    off = render(cam, s, pose=pose, env=night, seed=1).rgb
    s.set_lights([lamp], on=True)
    on = render(cam, s, pose=pose, env=night, seed=1).rgb
    assert off is not None and on is not None
    centre = (24, 32)
    assert on[centre][0] > 200 and on[centre][0] > 3 * on[centre][1]
    assert off[centre][0] < 60


def test_whitecap_cover_follows_monahan() -> None:
    """The top view of open water at 14 m/s: the share of pixels with foam is Monahan's W = 3.84e-6 U^3.41, and
    over them the foam brightens the water by Koepke's effective whitecap reflectance, 0.4 of fresh foam's.

    Rendered at ``high``: below it, pixels between anchors that both see clear water take their mean, which loses
    foam features narrower than two pixels (at 2 m a pixel, about a third of the area here)."""
    u = 14.0
    want = 3.84e-6 * u**3.41
    s = Scene()
    _water(s)
    env = _env(wind_speed_m_s=u)
    top = core.Camera(width=256, height=256, rgb=True, metres_per_pixel=2.0, quality="high", range_max=500.0)
    pose = pose_matrices(np.array([137.0, -59.0, 300.0, 0.0, math.pi / 2, 0.0]))
    windy = render(top, s, pose=pose, env=env, seed=4, radiance=True).radiance
    assert windy is not None
    lum = windy @ np.array([0.2126, 0.7152, 0.0722])
    # Open water seen straight down is uniform here (a flat plane, no swell): any foam lifts a pixel above it.
    water = np.median(lum)
    foam = lum > 1.01 * water
    assert foam.mean() == pytest.approx(want, rel=0.2), (foam.mean(), want)
    # Full foam: Lambertian albedo 0.55 under the pixel's irradiance; the covered pixels' mean lift over the water is
    # 0.4 of what full foam would give (the ratio of the lifts, so the irradiance cancels).
    full = lum[foam].max() - water
    assert (lum[foam] - water).mean() / full == pytest.approx(0.4, abs=0.06)


def test_wake_lies_behind_a_vessel_under_way() -> None:
    s = Scene()
    _water(s)
    env = _env()
    top = core.Camera(width=200, height=200, rgb=True, metres_per_pixel=1.0, quality="draft", range_max=500.0)
    pose = pose_matrices(np.array([0.0, 0.0, 300.0, 0.0, math.pi / 2, 0.0]))  # bow (+x) at the image top
    wakes = np.array([[20.0, 0.0, 0.0, 10.0, 12.0, 4.0]], dtype=np.float32)  # at x = 20 m heading +x, 10 m/s
    a = render(top, s, pose=pose, env=env, seed=1, wakes=wakes, radiance=True).radiance
    b = render(top, s, pose=pose, env=env, seed=1, radiance=True).radiance
    assert a is not None and b is not None
    diff = (a - b) @ np.array([0.2126, 0.7152, 0.0722])
    foam = diff > 0.05 * np.median(b @ np.array([0.2126, 0.7152, 0.0722]))
    rows, _ = np.nonzero(foam)
    assert foam.sum() > 100
    # Image row v is world x = (100 - v - 0.5) m: foam lies behind the stern (x < 14 m), none ahead of the bow.
    x = 100 - rows - 0.5
    assert (x < 14.5).mean() > 0.99


def test_camera_image_options_reach_the_recording(tmp_path: Path) -> None:
    """quality, distortion and noise from the scenario schema reach the native camera, and the distortion is
    written beside the intrinsics (recording metadata, read back by the one reader). Noise and quality are seen in
    the images: a capture with the scenario's noise differs from one without it and is the same again from the
    same seed, and one at ``high`` differs from the ``draft`` one (before this check a camera built without the
    scenario's noise passed this file, and no other test renders a scenario's noise)."""
    import yaml
    from mmusv.acquire import run
    from mmusv.recording.info import read_info

    root = Path(__file__).resolve().parents[2]
    sc = yaml.safe_load((root / "scenarios/port_entry.yaml").read_text())
    sc["acquisition"]["frames"] = 1
    sc["vessels"] = [v for v in sc["vessels"] if v["id"] != "usv_3" and v["id"] != "usv_2"]
    k = [-0.1, 0.01, 0.0, 0.0, 0.0]
    sc["rigs"] = {
        "usv_standard": {
            "lidar": None,
            "radar": None,
            "top_view": None,
            "cameras": [
                {
                    "name": "front",
                    "resolution": [48, 32],
                    "mount": {"point": "camera_front"},
                    "quality": "draft",
                    "distortion": k,
                    "noise": {"full_well_e": 5000, "read_noise_e": 2},
                }
            ],
        }
    }
    res = run(sc, out_dir=tmp_path)
    info = read_info(res.recording)
    cam = info.agents[0].cameras["front"]
    assert cam.distortion == pytest.approx(tuple(k))
    from mmusv.simulation import Simulation

    def front(noise: dict[str, float] | None, quality: str = "draft") -> np.ndarray:
        one = {**sc["rigs"]["usv_standard"]["cameras"][0], "noise": noise, "quality": quality}
        rigs = {"usv_standard": {**sc["rigs"]["usv_standard"], "cameras": [one]}}
        rgb = Simulation({**sc, "rigs": rigs}).capture(0).agents["usv_1"].cameras["front"].rgb
        assert rgb is not None
        return rgb

    noisy, clean = front({"full_well_e": 5000, "read_noise_e": 2}), front(None)
    assert not np.array_equal(noisy, clean), "the scenario's noise did not reach the camera"
    assert np.array_equal(noisy, front({"full_well_e": 5000, "read_noise_e": 2})), "noise is seeded"
    assert not np.array_equal(front(None, "high"), clean), "the scenario's quality did not reach the camera"
    bad = dict(sc)
    bad["rigs"] = {"usv_standard": {"cameras": [{"name": "front", "quality": "ultra"}]}}
    with pytest.raises(mmusv.ConfigError, match="quality"):
        run(bad, out_dir=tmp_path / "bad")


def test_shallow_water_shows_the_bottom() -> None:
    """Over a seabed 3 m down the water body is brighter than over 30 m, and 300 m is the deep water's colour:
    Maritorena's exp(−2 K_d d) towards the sand bottom, blue reaching deepest."""
    top = core.Camera(width=32, height=32, rgb=True, metres_per_pixel=1.0, quality="draft", range_max=500.0)
    pose = pose_matrices(np.array([0.0, 0.0, 100.0, 0.0, math.pi / 2, 0.0]))
    env = _env()

    def lum(depth: float | None) -> np.ndarray:
        s = Scene()
        _water(s)
        if depth is not None:
            s.set_seabed(np.full((3, 3), -depth), x0=-500.0, y0=-500.0, spacing=500.0)
        out = render(top, s, pose=pose, env=env, seed=1, radiance=True).radiance
        assert out is not None
        return np.asarray(out.reshape(-1, 3).mean(axis=0))

    deep, d3, d30, d300 = lum(None), lum(3.0), lum(30.0), lum(300.0)
    assert np.all(d3 > d30) and np.all(d30 >= deep)
    np.testing.assert_allclose(d300, deep, rtol=1e-4)
    gain3, gain30 = d3 - deep, d30 - deep
    # At 30 m little red survives the round trip (exp(-2·0.324·30) ~ 4e-9), blue still does (exp(-4.3) ~ 1 %).
    assert gain30[0] < 1e-3 * gain3[0] and gain30[2] > 1e-3 * gain3[2]


def test_light_scattered_between_wave_facets_brightens_grazing_water_only() -> None:
    """Rough water (12 m/s) seen from 3 m towards the horizon, with and without the light reflected more than
    once between the wave facets (``sensors/shade/sea_ms.rs``): near the horizon, where single scattering loses
    most, the water is a few per cent brighter; looking down steeply it is the same to 1 %; the sky is
    untouched. (The walk itself and its table are checked in Rust: energy conserved with mirror facets, its
    first order against a quadrature.)"""
    s = Scene()
    _water(s)
    cam = core.Camera(width=64, height=96, rgb=True, hfov=math.radians(60.0), quality="draft", range_max=6000.0)
    # Looking along +x, pitched 30° down: the horizon near the top, 60° below it at the bottom.
    pose = pose_matrices(np.array([0.0, 0.0, 3.0, 0.0, math.radians(30.0), 0.0]))
    out = {}
    for ms in (True, False):
        env = _env(wind_speed_m_s=12.0, exposure_ev100=12.0, water_multiple_scattering=ms)
        frame = render(cam, s, pose=pose, env=env, seed=3, radiance=True)
        assert frame.radiance is not None
        out[ms] = (frame.radiance @ np.array([0.2126, 0.7152, 0.0722])).reshape(96, 64)
        sem = np.asarray(frame.semantic).reshape(96, 64)
    water = sem == 1
    assert water.any() and (~water).any()
    assert np.array_equal(out[True][~water], out[False][~water])
    ratio = out[True][water] / out[False][water]
    assert ratio.min() >= 1.0 - 1e-6 and ratio.max() < 1.15
    full = np.flatnonzero(water.all(axis=1))  # rows of water only, from just below the horizon down
    near = np.median(out[True][full[0]] / out[False][full[0]])
    steep = np.median(out[True][full[-1]] / out[False][full[-1]])
    assert 1.02 < near < 1.12, near
    assert abs(steep - 1.0) < 0.01, steep


def test_rig_quality_is_every_camera_s_unless_it_sets_its_own(make_scenario: Any) -> None:
    """``quality`` on a rig reaches every camera and the top view that do not set their own: the captures equal
    those of the same rig with the quality written on each sensor, and differ from the default's (so the test can
    tell the rig's quality was not ignored). A camera's own quality wins; a LiDAR-only rig has nothing to set; a
    bad value names the rig's field."""
    from mmusv.config import Scenario
    from mmusv.editor.document import to_document
    from mmusv.simulation import Simulation

    def capture(rig: dict[str, Any]) -> dict[str, np.ndarray]:
        sc = make_scenario()
        sc["rigs"] = {"r": rig, "rn": {"preset": "lidar_only", "quality": "draft"}}
        sim = Simulation(sc)
        agent = sim.capture(2, agents=["usv_a"]).agents["usv_a"]
        return {"front": agent.cameras["front"].rgb, "top": agent.top_view.rgb}

    cams = [{"name": "front", "resolution": [64, 48], "mount": {"point": "camera_front"}}]
    top = {"resolution": [48, 48], "metres_per_pixel": 1.0}
    by_rig = capture({"quality": "draft", "cameras": cams, "top_view": top, "radar": None})
    each = capture(
        {"cameras": [{**cams[0], "quality": "draft"}], "top_view": {**top, "quality": "draft"}, "radar": None}
    )
    default = capture({"cameras": cams, "top_view": top, "radar": None})
    for name in ("front", "top"):
        assert np.array_equal(by_rig[name], each[name]), name
    assert not np.array_equal(by_rig["front"], default["front"])
    sc = make_scenario()
    sc["rigs"]["r"] = {"quality": "high", "cameras": [{**cams[0], "quality": "draft"}, {"name": "b"}]}
    rig = Scenario.model_validate(sc).rigs["r"]
    assert [c.quality for c in rig.cameras] == ["draft", "high"] and rig.top_view is not None
    assert rig.top_view.quality == "high"
    assert Scenario.model_validate(sc).rigs["rn"].cameras[0].quality == "standard"
    # The editor's document keeps the rig's quality, not a copy on every camera, and loads back equal.
    sc["rigs"]["r"] = {"quality": "draft"}
    scenario = Scenario.model_validate(sc)
    doc = to_document(scenario)
    assert doc["rigs"]["r"] == {"quality": "draft"}
    assert Scenario.model_validate(doc) == scenario
    sc["rigs"]["r"] = {"quality": "best"}
    with pytest.raises(mmusv.ConfigError, match=r"rigs\.r\.quality"):
        Simulation(sc)
