"""The radar and the LiDAR as a maritime sensor engineer meets them (a helper's round): each model against an
independent computation written out here (the cited model's own formula, the radar equation, a brute-force
cast of the same rays), not against the core's own functions.

Found by the round (each test below failed before its fix):

* radar, physical sea: a sea configured as WMO state ``s`` (the preset's Hs, the middle of the Douglas band) came
  out as the NRL model's sea state ``s - 0.5``, its σ⁰ 0.9–3.0 dB low between 18° and 0.6° grazing;
* radar: sea clutter was drawn at every range of every beam, over an island and in its shadow too;
* radar: a ray stood for ``Δφ · Δe`` of the beam without the ``cos e`` of the sphere, so a target 40° above the
  horizon came out 1/cos 40° = 1.31 times too bright;
* LiDAR, physical sea: a detected water return carried the model's mean intensity, below the detection
  threshold it had passed for one in seven returns at W1, instead of the speckle draw that passed it;
* LiDAR, physical sea in fog or rain: the water returns, whose detection already meets the attenuated mean,
  were lost a second time with the weather's probability ``1 − τ``;
* LiDAR: the range gates took the exact range before the noise, so points lay beyond ``range_m`` and before
  ``range_min_m``.

Checked and right, no change: the radar's R⁻⁴ for a point target and R⁻³ / R⁻⁷ for the tuned sea clutter, the
exponential (Rayleigh-amplitude) clutter intensity, a point target's azimuth spread (the beamwidth), range bins
(``floor(r / Δr)``, reported at the centre), the PPI pixel of a target north-up and head-up, dtypes; the LiDAR's
ring elevations, azimuths, noise and dropout statistics (``tests/sensors/test_lidar.py``).
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from mmusv._native import core
from mmusv.classes import SemanticClass
from mmusv.scene import Scene
from mmusv.sensors import RadarConfig, sensor_env
from mmusv.sensors.lidar import scan
from mmusv.sensors.radar import Orientation, ppi_image, radar_from_config, radar_sweep
from mmusv.world.sea_state import sea_spec_for_preset
from scipy import stats


def calm(wave_height_m: float, wind_speed_m_s: float | None = None) -> Any:
    """Clear air, no rain, waves of ``wave_height_m`` (and their wind, or ``wind_speed_m_s``)."""
    return sensor_env(
        fog_extinction_per_m=0.0, rain_mm_per_h=0.0, wave_height_m=wave_height_m, wind_speed_m_s=wind_speed_m_s
    )


EARTH_K_RE = 4.0 / 3.0 * 6_371_000.0


def quad(scene: Scene, corners: list[list[float]], cls: int) -> int:
    """An instance of the quadrilateral ``corners`` (counter-clockwise seen from its front) of class ``cls``."""
    m = scene.add_mesh(np.array(corners, dtype=np.float64), np.array([[0, 1, 2], [0, 2, 3]]), classes=cls)
    return scene.add_instance(m)


def sea_scene() -> tuple[Scene, int]:
    """A 40 km sea plane (class WATER) declared the sea, so a wave surface can replace it."""
    s = Scene()
    h = 20_000.0
    sea = quad(s, [[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], int(SemanticClass.WATER))
    s.set_sea(sea)
    return s, sea


def block(scene: Scene, lo: list[float], hi: list[float], cls: int) -> int:
    """An axis-aligned box ``[lo, hi]`` of class ``cls`` (outward faces)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], dtype=np.float64)
    f = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
         [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]],
        dtype=np.int64,
    )  # fmt: skip
    return scene.add_instance(scene.add_mesh(v, f, classes=cls))


def mast(height: float, yaw: float = 0.0) -> npt.NDArray[np.float64]:
    p = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    p[:2, :2] = [[c, -s], [s, c]]
    p[2, 3] = height
    return p


# ------------------------------------------------------------------------------------------------------- radar


def nrl_sigma0_db(f_ghz: float, sea_state: float, psi_deg: float) -> float:
    """σ⁰ (dB) of the NRL model, HH, 0–60° fit: Gregers-Hansen & Mital (2012), NRL/MR/5310--12-9346, the
    coefficients of their own ``NRL_SigmaSea.m``."""
    c1, c2, c3, c4, c5 = -73.0, 20.781, 7.351, 25.65, 0.0054
    psi = psi_deg
    return (
        c1
        + c2 * math.log10(math.sin(math.radians(psi)))
        + (27.5 + c3 * psi) * math.log10(f_ghz) / (1 + 0.95 * psi)
        + c4 * math.pow(sea_state + 1, 1 / (2 + 0.085 * psi + 0.033 * sea_state))
        + c5 * psi * psi
    )


def test_physical_sea_clutter_is_the_nrl_model_at_the_configured_sea_state() -> None:
    """Over the physical sea of WMO state 3 and 5 (the bundled presets, ``sea: {state: s}``), every cell's clutter
    drawn (threshold 0), the mean clutter of 2048 beams × 3 range bins at 20, 60, 200 and 600 m (grazing 18° to
    0.6° from a 6 m mast, 4/3 earth) over the radar equation's ``A G² (R_ref/r)⁴`` (``A = r θ_az Δr sec ψ``,
    ``G²`` the fan's two-way gain where the water lies) is the NRL model's σ⁰ at X band (9.41 GHz), HH, at that
    sea state, within 0.4 dB (the sampling error is 0.06 dB). Before: 0.9 to 3.0 dB low, the model evaluated at
    sea state 2.5 and 4.5."""
    cfg = RadarConfig(
        range_m=700.0, min_range_m=10.0, rays_az=1, rays_el=1, detection_threshold=0.0, rain_clutter_eta=0.0
    )
    radar = radar_from_config(cfg)
    height = 6.0
    for state in ("3", "5"):
        sea = sea_spec_for_preset(state)
        scene, _ = sea_scene()
        scene.set_wave_surface(sea, scenario_seed=1, time_s=0.0, foci=np.zeros((1, 2)), detail=False, slopes=False)
        env = calm(sea.hs_m)
        ret = radar_sweep(radar, scene, pose=mast(height), env=env, seed=2)
        assert (ret.instance_id < 0).all() and (ret.semantic_class == SemanticClass.WATER).all()
        assert len(ret) == cfg.azimuth_bins * len(np.unique(ret.range)), "threshold 0: every cell is drawn"
        for r0 in (20.0, 60.0, 200.0, 600.0):
            k0 = math.floor(r0 / cfg.range_resolution_m)
            got = want = 0.0
            for k in (k0 - 1, k0, k0 + 1):
                r = (k + 0.5) * cfg.range_resolution_m
                psi = math.degrees(math.asin(height / r - r / (2 * EARTH_K_RE)))
                # The pulse-limited cell, r θ_az Δr sec ψ (Skolnik §13.2).
                sec_psi = 1.0 / math.cos(math.radians(psi))
                area = r * math.radians(cfg.beamwidth_deg) * cfg.range_resolution_m * sec_psi
                sigma0 = 10 ** (nrl_sigma0_db(9.41, int(state), psi) / 10)
                # The fan's Gaussian two-way gain where the water lies (θ_el = 20°, axis level): Probert-Jones 1962.
                g2 = math.exp(-8 * math.log(2) * (math.atan(height / r) / math.radians(20.0)) ** 2)
                want += sigma0 * area * g2 * (1000.0 / r) ** 4 * cfg.azimuth_bins
                got += float(ret.intensity[np.abs(ret.range - r) < 1e-3].astype(np.float64).sum())
            db = 10 * math.log10(got / want)
            assert abs(db) < 0.4, f"state {state}, {r0:.0f} m: clutter {db:+.2f} dB from the NRL model"


def test_no_sea_clutter_over_an_island_or_in_its_shadow() -> None:
    """A 30 m high island 60–160 m ahead of the radar (a terrain block 100 m wide) over the physical W3 sea, with
    the user defaults (threshold 0.3): no sea-clutter return lies over the island or behind it, while in front of
    it and in every other direction the clutter is the same, return for return, as without the island. Before,
    the sea clutter of the open sea was drawn over the island and in its shadow (thousands of returns)."""
    radar = radar_from_config(RadarConfig(range_m=900.0, azimuth_bins=1024))
    sea = sea_spec_for_preset("W3")
    env = calm(sea.hs_m)

    def sweep(island: bool) -> Any:
        scene, _ = sea_scene()
        if island:
            block(scene, [60.0, -50.0, -5.0], [160.0, 50.0, 25.0], int(SemanticClass.TERRAIN))
        scene.set_wave_surface(sea, scenario_seed=1, time_s=0.0, foci=np.zeros((1, 2)), detail=False, slopes=False)
        return radar_sweep(radar, scene, pose=mast(4.0), env=env, seed=3)

    def clutter(ret: Any, where: npt.NDArray[np.bool_]) -> set[tuple[float, float, float]]:
        keep = where & (ret.instance_id < 0)
        return set(zip(ret.azimuth[keep].tolist(), ret.range[keep].tolist(), ret.intensity[keep].tolist(), strict=True))

    def regions(ret: Any) -> tuple[npt.NDArray[np.bool_], ...]:
        bearing = (ret.azimuth + np.pi) % (2 * np.pi) - np.pi
        x = ret.range * np.cos(ret.azimuth)
        sector = np.abs(bearing) < 0.6  # well inside the island's ±39.8°
        return sector & (x > 62.0), sector & (x < 58.0), np.abs(bearing) > 1.0

    open_sea, island = sweep(False), sweep(True)
    (behind_o, front_o, away_o), (behind_i, front_i, away_i) = regions(open_sea), regions(island)
    assert len(clutter(open_sea, behind_o)) > 1000, "the open sea there has clutter"
    assert clutter(island, behind_i) == set(), "sea clutter over the island or in its shadow"
    assert len(clutter(open_sea, front_o)) > 100
    assert clutter(island, front_i) == clutter(open_sea, front_o)
    assert clutter(island, away_i) == clutter(open_sea, away_o)
    # The island itself is a target (class TERRAIN) at its near shore.
    land = island.semantic_class == SemanticClass.TERRAIN
    assert land.any() and abs(float(island.range[land].min()) - 60.0) <= 3.0


def test_target_echo_is_the_radar_equation_at_any_elevation_and_range() -> None:
    """A plate of 30 m × 30 m facing the radar: its echo summed over the beams that see it is the radar equation's
    ``ρ A (R_ref / r)⁴`` times the beams per point of it (beamwidth / bin width), on the horizon and 25° and 40°
    above it (within 6 %), times the fan's two-way gain there (Gaussian, 90° between half-power points here), and
    falls as r⁻⁴ from 300 to 600 m. Before, the plate 40° up was 1.31 times as bright (a ray's solid angle without
    ``cos e``), and until the elevation pattern (2026-12-01) as bright as on the horizon."""
    cfg = RadarConfig(
        range_m=1000.0,
        azimuth_bins=1024,
        rays_az=8,
        rays_el=256,
        elevation_fan_deg=(-45.0, 45.0),
        horizon_fraction=0.0,
        detection_threshold=1e-12,
        sea_clutter_sigma0=0.0,
        rain_clutter_eta=0.0,
    )
    radar = radar_from_config(cfg)
    half, rho = 15.0, 1.0  # class VESSEL: radar reflectivity 1
    beams = math.radians(cfg.beamwidth_deg) / (2 * math.pi / cfg.azimuth_bins)

    def total(r: float, e_deg: float) -> float:
        s = Scene()
        e = math.radians(e_deg)
        # The plate's corners: centre r·(cos e, 0, sin e), spanned by y and by the up vector tilted back by e.
        c = np.array([r * math.cos(e), 0.0, r * math.sin(e)])
        up = np.array([-math.sin(e), 0.0, math.cos(e)]) * half
        side = np.array([0.0, half, 0.0])
        corners = [c - side - up, c - side + up, c + side + up, c + side - up]
        inst = quad(s, [p.tolist() for p in corners], int(SemanticClass.VESSEL))
        ret = radar_sweep(radar, s, pose=np.eye(4), env=calm(0.0), seed=1)
        assert (ret.instance_id == inst).all() and len(ret) > 0
        return float(ret.intensity.astype(np.float64).sum())

    def gain(r: float, e_deg: float) -> float:
        """The fan's Gaussian two-way gain exp(−8 ln 2 e² / θ_el²), θ_el = 90°, averaged over the plate."""
        e = np.radians(e_deg) + np.linspace(-1.0, 1.0, 101) * math.atan(half / r)
        return float(np.mean(np.exp(-8 * math.log(2) * (e / math.radians(90.0)) ** 2)))

    for e_deg in (0.0, 25.0, 40.0):
        want = rho * (2 * half) ** 2 * (1000.0 / 300.0) ** 4 * beams * gain(300.0, e_deg)
        got = total(300.0, e_deg)
        assert abs(got / want - 1) < 0.06, f"plate {e_deg}° up: {got / want:.3f} of the radar equation"
    assert abs(total(300.0, 0.0) / total(600.0, 0.0) / 16.0 - 1) < 0.06, "r⁻⁴"


def test_tuned_clutter_ranges_and_statistics_and_a_point_target() -> None:
    """Checked and right (no change): the tuned sea clutter's mean follows ``σ⁰ H² A (R_ref/r)⁴``, times
    ``(R_c / r)⁴`` past the critical range (r⁻³ then r⁻⁷), and each cell's intensity is exponential (Rayleigh
    amplitude); a 2 m target at 600 m shows in the beams whose 1.2° holds some of it (bins of 0.176°, centred),
    in the range bin ``floor(r / Δr)`` reported at its centre, at its pixel of the PPI north-up and head-up."""
    h_wave = 2.0
    cfg = RadarConfig(
        range_m=1500.0, azimuth_bins=2048, rays_az=1, rays_el=1, detection_threshold=0.0, sea_clutter_sigma0=4e-6
    )
    env = calm(h_wave)
    ret = radar_sweep(radar_from_config(cfg), Scene(), pose=mast(0.0), env=env, seed=3)
    rc = cfg.clutter_critical_range_per_m * h_wave
    for r0 in (30.0, 300.0, 900.0, 1400.0):
        r = (math.floor(r0 / 3.0) + 0.5) * 3.0
        x = ret.intensity[np.abs(ret.range - r) < 1e-3].astype(np.float64)
        mu = 4e-6 * h_wave**2 * r * math.radians(1.2) * 3.0 * (1000.0 / r) ** 4 * min(1.0, (rc / r) ** 4)
        assert len(x) == 2048 and abs(x.mean() / mu - 1) < 5 / math.sqrt(2048), f"{r0} m"
        assert stats.kstest(x / mu, "expon").pvalue > 1e-3, f"{r0} m: not exponential"
    # A point target: a 2 m cube whose near face is 601 m off at world bearing 0, the radar yawed 100°.
    fine = RadarConfig(
        range_m=1500.0, azimuth_bins=2048, rays_az=32, rays_el=128, elevation_fan_deg=(-2.0, 2.0),
        horizon_fraction=0.0, detection_threshold=1e-9, sea_clutter_sigma0=0.0, rain_clutter_eta=0.0,
    )  # fmt: skip
    s = Scene()
    bearing, r = 0.0, 601.0
    cube = block(s, [r, -1.0, -1.0], [r + 2.0, 1.0, 1.0], int(SemanticClass.VESSEL))
    yaw = math.radians(100.0)
    pose = mast(0.0, yaw)
    ret = radar_sweep(radar_from_config(fine), s, pose=pose, env=calm(0.0), seed=0)
    assert (ret.instance_id == cube).all()
    off = np.degrees((ret.azimuth - (bearing - yaw) + np.pi) % (2 * np.pi) - np.pi)
    # The beams whose 1.2° holds some of its 0.19°: every beam centre within 0.6° + 0.095°, one per 0.176° bin.
    half_deg, bin_deg = 0.6 + math.degrees(1.0 / r), 360.0 / 2048
    assert np.abs(off).max() <= half_deg and len(ret) - math.floor(2 * half_deg / bin_deg) in (0, 1), off
    assert abs(off.mean()) < bin_deg, "centred on the target"
    assert np.allclose(ret.range, (math.floor(r / 3.0) + 0.5) * 3.0)
    views: tuple[tuple[Orientation, float], ...] = (("north_up", bearing), ("head_up", bearing - yaw + math.pi / 2))
    for orientation, theta in views:
        img = ppi_image(ret, size_px=512, metres_per_pixel=3.0, orientation=orientation)
        row, col = np.unravel_index(int(np.argmax(img)), img.shape)
        want = (256 - r / 3.0 * math.sin(theta), 256 + r / 3.0 * math.cos(theta))
        assert math.hypot(row - want[0], col - want[1]) < 2.5, (orientation, (row, col), want)


# ------------------------------------------------------------------------------------------------------- LiDAR

FRESNEL_NORMAL, WHITECAP_REFLECTANCE, DETECTION_THRESHOLD = 0.0199, 0.22, 3.2e-4


def water_mean_intensity(cos: npt.NDArray[np.float64], wind: float, r: npt.NDArray[np.float64]) -> Any:
    """``⟨I⟩ = π β / (1 + (r/100)²)`` of ``docs/sea/README.md`` / ``lidar_water.rs``, from the cited formulas:
    Cox & Munk's ``σ² = 0.003 + 5.12e-3 U``, the quasi-specular ``ρ_F exp(−tan²θ/σ²) / (4π σ² cos⁴θ)`` and
    Monahan's whitecaps ``3.84e-6 U^3.41`` of Koepke's reflectance 0.22, Lambertian."""
    s2 = 0.003 + 5.12e-3 * wind
    tan2 = (1 - cos**2) / cos**2
    qs = FRESNEL_NORMAL * np.exp(-tan2 / s2) / (4 * np.pi * s2 * cos**4)
    wc = 3.84e-6 * wind**3.41 * WHITECAP_REFLECTANCE * cos / np.pi
    return np.pi * (qs + wc) / (1 + (r / 100.0) ** 2)


@pytest.mark.parametrize("fog", [0.0, 3.0 / 600.0])
def test_lidar_water_returns_follow_incidence_and_are_speckle_above_the_threshold(fog: float) -> None:
    """Over the W1 sea (wind 8 m/s), a 64-ring LiDAR 3 m up, in clear air and in fog of 600 m visibility: the beams
    re-cast here give each water hit its facet normal and range, hence ``⟨I⟩`` (times the two-way transmission
    ``τ = exp(−2σr)``) and the detection probability ``exp(−I_d/⟨I⟩)`` by the cited formulas; the returns per band
    of incidence occur at that rate, and each return's intensity is the speckle draw that passed the threshold:
    never below ``I_d``, ``(I − I_d)/⟨I⟩`` exponential of mean 1. Before, a return carried ``⟨I⟩`` itself (44 % of
    them here below the threshold they had passed), and in fog the water returns were lost a second time with
    probability ``1 − τ`` (a tenth to a third fewer than the model's)."""
    scene, _ = sea_scene()
    sea = sea_spec_for_preset("W1")
    scene.set_wave_surface(sea, scenario_seed=4, time_s=3.0, foci=np.zeros((1, 2)), detail=False, slopes=False)
    el = np.radians(np.linspace(-25.0, 2.0, 64)).tolist()
    # The flat sea's knobs, ignored over the waves, but for both probabilities 0, which switch the water off.
    lidar = core.Lidar(
        elevations=el, azimuth_steps=2048, range_min=0.5, range_max=120.0, range_noise_std=0.0, dropout=0.0,
        water_probability=0.05, water_probability_per_wave_m=0.1, water_range_m=0.0, water_range_per_wave_m=0.0,
        beam_divergence=3e-3,
    )  # fmt: skip
    pose = mast(3.0)
    wind = 8.0
    env = sensor_env(fog_extinction_per_m=fog, rain_mm_per_h=0.0, wave_height_m=sea.hs_m, wind_speed_m_s=wind)
    pts = scan(lidar, scene, pose=pose, env=env, seed=6)
    dirs = np.asarray(lidar.pattern(), dtype=np.float32)
    hits = scene.cast_rays(np.tile(pose[:3, 3], (len(dirs), 1)), dirs, max_range=120.0)
    water = (np.asarray(hits.semantic_class) == SemanticClass.WATER) & np.isfinite(hits.distance)
    cos = np.abs(np.einsum("ij,ij->i", np.asarray(hits.normal, np.float64), dirs.astype(np.float64)))
    cos = np.clip(cos, 1e-6, 1.0)
    r = np.where(water, np.asarray(hits.distance, np.float64), 0.0)
    mean = water_mean_intensity(cos, wind, r) * np.exp(-2 * fog * r)
    p_detect = np.where(water, np.exp(-DETECTION_THRESHOLD / np.where(water, mean, 1.0)), 0.0)
    returned = np.zeros(len(dirs), dtype=bool)
    returned[pts.ray_index] = True
    assert np.array_equal(pts.semantic_class == SemanticClass.WATER, water[pts.ray_index])
    assert returned[water].sum() > 3000
    # Detection rate per band of incidence against the model's probability.
    edges = np.quantile(cos[water], np.linspace(0, 1, 9))
    for lo, hi in itertools.pairwise(edges):
        band = water & (cos >= lo) & (cos <= hi)
        n, expect = int(returned[band].sum()), float(p_detect[band].sum())
        sd = math.sqrt(float((p_detect[band] * (1 - p_detect[band])).sum()))
        assert abs(n - expect) <= 4.5 * sd + 2, f"cos θ {lo:.3f}–{hi:.3f}: {n} returns, model {expect:.1f}"
    # Intensities: the speckle draw above the threshold.
    w = pts.semantic_class == SemanticClass.WATER
    intensity = pts.intensity[w].astype(np.float64)
    assert intensity.min() >= DETECTION_THRESHOLD * (1 - 1e-6), f"{(intensity < DETECTION_THRESHOLD).mean():.1%} below"
    mu = mean[pts.ray_index[w]]
    free = intensity < 0.999  # the intensity is clamped to 1
    excess = (intensity[free] - DETECTION_THRESHOLD) / mu[free]
    assert abs(excess.mean() - 1.0) < 5 / math.sqrt(len(excess)), excess.mean()
    assert stats.kstest(excess, "expon").pvalue > 1e-3


def test_lidar_points_stay_within_the_range_gates() -> None:
    """With 5 cm of range noise, a wall 29.5 m ahead and gates at 30 m: no point's range lies beyond
    ``range_m`` = 30 or below ``range_min_m`` = 30, and the beams that meet the wall just beyond 30 m come in
    about as often as those just inside go out. Before, the gates took the exact range: points up to 3σ
    beyond ``range_m`` and before ``range_min_m``."""
    s = Scene()
    quad(s, [[29.5, -40, -40], [29.5, -40, 40], [29.5, 40, 40], [29.5, 40, -40]], int(SemanticClass.VESSEL))
    el = np.radians(np.linspace(-10.0, 10.0, 32)).tolist()

    def lidar(range_min: float, range_max: float) -> Any:
        return core.Lidar(
            elevations=el, azimuth_steps=3600, range_min=range_min, range_max=range_max, range_noise_std=0.05,
            dropout=0.0, water_probability=0.0, water_probability_per_wave_m=0.0, water_range_m=0.0,
            water_range_per_wave_m=0.0, beam_divergence=3e-3,
        )  # fmt: skip

    env = calm(0.0)
    far = scan(lidar(0.5, 30.0), s, pose=np.eye(4), env=env, seed=2)
    near = scan(lidar(30.0, 200.0), s, pose=np.eye(4), env=env, seed=2)
    assert len(far) > 100 and far.range.max() <= 30.0
    assert len(near) > 1000 and near.range.min() >= 30.0
    dirs = np.asarray(lidar(0.5, 30.0).pattern(), dtype=np.float64)
    truth = np.where(dirs[:, 0] > 0, 29.5 / np.where(dirs[:, 0] > 0, dirs[:, 0], 1.0), np.inf)
    t = truth[far.ray_index]
    came_in = int((t > 30.0).sum())
    went_out = int(((truth > 29.9) & (truth <= 30.0)).sum() - ((t > 29.9) & (t <= 30.0)).sum())
    assert came_in > 20 and abs(came_in - went_out) < 4 * math.sqrt(came_in + went_out), (came_in, went_out)
    # The points lie on their rays at the measured range (the LiDAR frame).
    np.testing.assert_allclose(far.xyz, dirs[far.ray_index] * far.range[:, None], atol=1e-4)
