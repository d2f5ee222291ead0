"""An outside re-check (second pass) of mmusv's radar and atmosphere physics against the cited sources, through the
public Python API. Every reference value is computed here from the source's own formula and constants (never from
mmusv's code), and every tolerance is the numerics' (float32 intensities, range-bin centres, exponential draws),
far tighter than the error a wrong constant, a wrong table or a missing factor would make (argued per test).

Models and sources:

* Rain attenuation: ITU-R P.838-3 (2005), eqs. (2)–(3) with Tables 1–4: ``γ = k R^α`` dB/km, two-way on a radar
  echo. Reference check of the fit itself: at 10 GHz it gives the widely tabulated kH = 0.01217, αH = 1.2571,
  kV = 0.01129, αV = 1.2156.
* Rain clutter: Rayleigh scattering ``η = π⁵ |K|² Z / λ⁴`` with Marshall & Palmer's (1948) ``Z = 200 R^1.6``
  mm⁶/m³ (Skolnik, *Introduction to Radar Systems*, 3rd ed., §13.6), in the beam volume of a Gaussian fan:
  ``r² θ_az Δr ∫ G²(e) de`` with ``G²(e) = exp(−8 ln 2 e²/θ_el²)`` (half-power full width θ_el), so
  ``∫ G² de = θ_el √(π / (8 ln 2))``; the radar equation ``∝ σ / r⁴``.
* Sea clutter: the NRL model, Gregers-Hansen & Mital (2012), IEEE TAES 48(4) / NRL/MR/5310--12-9346, for VV as
  well as HH and at S band as well as X band (``tests/reference/test_independent_physics.py`` checks X-band HH
  only); the sea state of Hs by the WMO code 3700 (Douglas) bands, each state at its band's middle; the 4/3-earth
  grazing angle ``sin ψ = h/r − r/(2 k R_e)``.
* Atmosphere: Koschmieder (1924), ``C(t) = C₀ e^{−σ t}``; the meteorological optical range (WMO, the visibility
  ``visibility_m`` stands for) is where a black object's contrast falls to 5 %: ``σ = −ln 0.05 / V = 2.996 / V``;
  in the camera's aerial perspective (one way) and the LiDAR's echo (two way, Beer–Lambert).
* Ship response: the long-wave limits of Jensen, Mansour & Olsen's (2004) heave and pitch (the hull follows the
  surface) and of the roll oscillator, and the roll resonance of a 1-DOF oscillator with the stated k_xx = 0.39 B
  and ζ = 0.10.
* Sky: Preetham, Shirley & Smits (1999), the zenith luminance ``Y_z = (4.0453 T − 4.9710) tan χ − 0.2155 T +
  2.4192`` kcd/m², ``χ = (4/9 − T/120)(π − 2θs)``, and the zenith chromaticity polynomials (their Appendix A.2),
  which the Perez distribution leaves unchanged at the zenith (F(0, θs)/F(0, θs) = 1).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from clear_env import clear_env, clear_lidar
from mmusv._native import core
from mmusv.scene import Scene
from mmusv.sensors.camera import render
from mmusv.world.build import pose_matrices
from mmusv.world.environment import Weather
from nrl_clutter import fixed_and_physical_sweeps, nrl_sigma0

C_LIGHT = 299_792_458.0
"""Speed of light, m/s."""
G = 9.80665
"""Standard gravity, m/s²."""
ROLL_GYRADIUS_B, ROLL_ZETA = 0.39, 0.10
"""The roll model's stated k_xx / B and damping ratio (``ocean/response.rs``: IMO IS Code 2008 §2.3; ITTC)."""

# --- ITU-R P.838-3, Tables 1–4: (a_j, b_j, c_j) and (m, c) ---

P838_LOG_K = {
    "H": (
        ((-5.33980, -0.10008, 1.13098), (-0.35351, 1.26970, 0.45400), (-0.23789, 0.86036, 0.15354)),
        ((-0.94158, 0.64552, 0.16817),),
        (-0.18961, 0.71147),
    ),
    "V": (
        ((-3.80595, 0.56934, 0.81061), (-3.44965, -0.22911, 0.51059), (-0.39902, 0.73042, 0.11899)),
        ((0.50167, 1.07319, 0.27195),),
        (-0.16398, 0.63297),
    ),
}
P838_ALPHA = {
    "H": (
        ((-0.14318, 1.82442, -0.55187), (0.29591, 0.77564, 0.19822), (0.32177, 0.63773, 0.13164)),
        ((-5.37610, -0.96230, 1.47828), (16.1721, -3.29980, 3.43990)),
        (0.67849, -1.95537),
    ),
    "V": (
        ((-0.07771, 2.33840, -0.76284), (0.56727, 0.95545, 0.54039), (-0.20238, 1.14520, 0.26809)),
        ((-48.2991, 0.791669, 0.116226), (48.5833, 0.791459, 0.116479)),
        (-0.053739, 0.83433),
    ),
}
P838_AT_10_GHZ = {"H": (0.01217, 1.2571), "V": (0.01129, 1.2156)}
"""(k, α) at 10 GHz as tabulated for P.838 (and quoted in radar texts)."""

# --- rain reflectivity ---

MARSHALL_PALMER = (200.0, 1.6)
"""Marshall & Palmer (1948): Z = 200 R^1.6 mm⁶/m³, R in mm/h."""
WATER_K2 = 0.93
"""|K|² = |(m² − 1)/(m² + 2)|² of liquid water at centimetre wavelengths."""

# --- NRL sea clutter ---

DOUGLAS_UPPER = (0.1, 0.5, 1.25, 2.5, 4.0, 6.0)
"""WMO code table 3700 (Douglas): the upper Hs bound (m) of sea states 1..6 (state 0: glassy, Hs 0)."""
EARTH_K, EARTH_RADIUS_M = 4.0 / 3.0, 6_371_000.0

# --- Koschmieder ---

CONTRAST_THRESHOLD = 0.05
"""WMO meteorological optical range: the distance at which contrast falls to 5 % (Koschmieder's 3.912/V is the 2 %
threshold of his 1924 paper)."""


# --- helpers ---


def _p838(f_ghz: float, pol: str) -> tuple[float, float]:
    """(k, α) of ITU-R P.838-3 eqs. (2)–(3) at ``f_ghz``, ``pol`` "H" or "V"."""
    x = math.log10(f_ghz)

    def fit(table: tuple) -> float:
        first, rest, (m, c) = table
        return sum(a * math.exp(-(((x - b) / w) ** 2)) for a, b, w in (*first, *rest)) + m * x + c

    return 10 ** fit(P838_LOG_K[pol]), fit(P838_ALPHA[pol])


def _radar(
    *,
    f_ghz: float,
    pol: str,
    range_min: float,
    range_max: float,
    dr: float,
    bins: int,
    sigma_1m: float = 0.0,
    eta: float = 0.0,
    rays_el: int = 1,
) -> core.Radar:
    return core.Radar(
        range_min_m=range_min,
        range_max_m=range_max,
        range_resolution_m=dr,
        azimuth_bins=bins,
        beamwidth_az_rad=math.radians(1.2),
        elevation_fan_rad=(math.radians(-10), math.radians(10)),
        rays_az=1,
        rays_el=rays_el,
        target_rays=0,
        horizon_fraction=0.0,
        horizon_band_rad=0.01,
        detection_threshold=0.0,
        range_noise_std_m=0.0,
        sea_sigma0_at_1m=sigma_1m,
        critical_range_per_m=100_000.0,
        sea_max_range_m=5000.0 if sigma_1m > 0 else 10.0,
        rain_eta_at_1mm_h=eta,
        frequency_ghz=f_ghz,
        polarisation=pol,
    )


def _quad(scene: Scene, corners: list[list[float]], cls: int) -> int:
    v = np.array(corners, dtype=float)
    return scene.add_instance(scene.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), classes=cls, name="quad"))


def _douglas_state(hs: float) -> float:
    """Continuous sea state: state s at the middle of its Douglas band, linear between the middles, 6 from the
    middle of band 6 on (the model's fit stops at 6)."""
    bounds = (0.0, *DOUGLAS_UPPER)
    middles = [0.0] + [(bounds[i] + bounds[i + 1]) / 2 for i in range(len(DOUGLAS_UPPER))]
    return float(np.interp(hs, middles, np.arange(len(middles))))


# --- 1. rain attenuation, ITU-R P.838-3 ---


def test_p838_reference_reproduces_the_tabulated_10_ghz_coefficients() -> None:
    """The reference fit written here gives the tabulated 10 GHz (k, α) to their printed digits: a guard that the
    transcribed Tables 1–4 are right before the radar is compared with them."""
    for pol, (k, alpha) in P838_AT_10_GHZ.items():
        got_k, got_alpha = _p838(10.0, pol)
        assert got_k == pytest.approx(k, abs=6e-6)
        assert got_alpha == pytest.approx(alpha, abs=6e-5)


@pytest.mark.parametrize(
    ("f_ghz", "pol", "rain"),
    [(9.41, "HH", 20.0), (9.41, "VV", 20.0), (10.0, "HH", 10.0), (5.6, "VV", 30.0), (3.05, "HH", 50.0)],
)
def test_rain_attenuates_a_target_echo_two_way_by_itu_p838(f_ghz: float, pol: str, rain: float) -> None:
    """A metal wall 5 km out, seen with and without rain (no rain clutter): the echo's ratio is the two-way loss
    10^(−2 γ r/10 km), γ = k R^α of P.838-3 at the radar's own frequency and polarisation. Within 0.5 % in γ (the
    range bin's centre stands for the ray's distance: ≤ 0.1 %). What a wrong model would give: H for V or V for H
    −18 %/+22 % at 9.41 GHz, the fixed 10 GHz HH table at 9.41 GHz +21 %, a one-way loss −50 %, the 5.6 GHz and
    3.05 GHz coefficients of another band off by factors."""
    scene = Scene()
    x = 5000.0
    _quad(scene, [[x, -300, -50], [x, 300, -50], [x, 300, 200], [x, -300, 200]], cls=5)
    radar = _radar(f_ghz=f_ghz, pol=pol, range_min=20.0, range_max=6000.0, dr=10.0, bins=360, rays_el=4)
    pose = pose_matrices(np.array([0.0, 0.0, 10.0, 0.0, 0.0, 0.0]))
    dry = radar.sweep(scene.native, pose=pose, env=clear_env(), seed=1)
    wet = radar.sweep(scene.native, pose=pose, env=clear_env(rain_mm_per_h=rain), seed=1)
    hit = dry["instance"] >= 0
    assert hit.sum() >= 3 and np.array_equal(dry["range"], wet["range"])
    r_km = dry["range"][hit].astype(float) / 1000.0
    gamma = -10 * np.log10(wet["intensity"][hit].astype(float) / dry["intensity"][hit]) / (2 * r_km)
    k, alpha = _p838(f_ghz, pol[0])
    np.testing.assert_allclose(gamma, k * rain**alpha, rtol=5e-3)


def test_radar_model_header_numbers_for_rain() -> None:
    """``sensors/radar_model.rs`` states: at 9.41 GHz HH k = 0.00930, α = 1.2895, 0.181 dB/km at 10 mm/h; the old
    10 GHz table gave 0.220 dB/km, 21 % too much; Marshall–Palmer at 9.41 GHz is η = 5.5·10⁻⁸ R^1.6 m²/m³, and the
    scenario default 5·10⁻⁹ lies 10.4 dB below it. Each computed here from the sources."""
    k, alpha = _p838(9.41, "H")
    assert round(k, 5) == 0.00930 and round(alpha, 4) == 1.2895
    assert round(k * 10**alpha, 3) == 0.181
    k10, a10 = _p838(10.0, "H")
    assert round(k10 * 10**a10, 3) == 0.220
    assert round(100 * (k10 * 10**a10 / (k * 10**alpha) - 1)) == 21
    lam = C_LIGHT / 9.41e9
    z = MARSHALL_PALMER[0] * 1e-18  # mm⁶/m³ → m⁶/m³ at 1 mm/h
    eta = math.pi**5 * WATER_K2 * z / lam**4
    assert round(eta, 9) == 5.5e-8
    assert round(10 * math.log10(eta / 5e-9), 1) == 10.4


# --- 2. rain clutter ---


def test_rain_clutter_is_rayleigh_marshall_palmer_in_the_gaussian_fan() -> None:
    """Rain alone (no water, nothing in range): every cell is clutter of mean
    μ = η₁ R^1.6 (f/9.41)⁴ · r² θ_az θ_el √(π/(8 ln 2)) Δr · (1 km/r)⁴ · 10^(−2γr/10 km), η₁ the knob at 1 mm/h
    (Rayleigh η ∝ λ⁻⁴ and Marshall–Palmer Z ∝ R^1.6 carry it in frequency and rate; P.838-3 loss, written here).
    (1) With one seed the cells' draws are the same whatever the rain and band, so the ratio of two sweeps is the
    ratio of their μ: to 1e-4 (float32), across rate and band: R^1.5 or R^2 for R^1.6 miss by 15–25 % at 4×, λ⁻²
    for λ⁻⁴ by ×10 at S band. (2) The mean of intensity/μ over the 297 000 cells is 1 within 1.5 % (exponential
    draws: a standard error of 0.2 %), and within 3 % in each 500 m band: the full θ_el instead of the Gaussian
    fan's θ_el √(π/(8 ln 2)) would read 1.33, a cell volume in r³ or r would grow or fall with range."""
    scene = Scene()
    scene.add_instance(
        scene.add_mesh(
            np.array([[9000.0, -1, 0], [9001, -1, 0], [9001, 1, 0]]), np.array([[0, 1, 2]]), classes=5, name="speck"
        )
    )
    pose = pose_matrices(np.array([0.0, 0.0, 15.0, 0.0, 0.0, 0.0]))
    eta1, dr = 5e-9, 20.0
    runs = {}
    for f_ghz, pol, rain in [(9.41, "HH", 4.0), (9.41, "HH", 16.0), (3.05, "VV", 16.0)]:
        radar = _radar(f_ghz=f_ghz, pol=pol, range_min=100.0, range_max=3000.0, dr=dr, bins=2048, eta=eta1)
        out = radar.sweep(scene.native, pose=pose, env=clear_env(rain_mm_per_h=rain), seed=5)
        r = out["range"].astype(float)
        assert np.all(out["instance"] == -1) and r.size > 250_000
        k, alpha = _p838(f_ghz, pol[0])
        loss = 10 ** (-2 * k * rain**alpha * (r / 1000.0) / 10)
        volume = r**2 * math.radians(1.2) * math.radians(20.0) * math.sqrt(math.pi / (8 * math.log(2))) * dr
        mu = eta1 * rain**1.6 * (f_ghz / 9.41) ** 4 * volume * (1000.0 / r) ** 4 * loss
        runs[(f_ghz, rain)] = (r, out["intensity"].astype(float), mu)
    r0, i0, mu0 = runs[(9.41, 4.0)]
    for key, (r, i, mu) in runs.items():
        assert np.array_equal(r, r0), key
        np.testing.assert_allclose(i / i0, mu / mu0, rtol=1e-4, err_msg=str(key))
    ratio = i0 / mu0
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.015)
    for lo in range(100, 3000, 500):
        band = (r0 >= lo) & (r0 < lo + 500)
        assert np.mean(ratio[band]) == pytest.approx(1.0, abs=0.03), lo


# --- 3. NRL sea clutter: VV and S band ---


@pytest.mark.parametrize(("f_ghz", "pol"), [(9.41, "VV"), (3.05, "HH"), (3.05, "VV")])
def test_nrl_sea_clutter_vv_and_s_band(f_ghz: float, pol: str) -> None:
    """A radar 15 m above a displaced sea: with one seed the cell's draw is the same over the same water without
    the wave surface (the fixed model, μ = σ⁰_1m H² A G² (1 km/r)⁴ with the fall-off pushed away), so the ratio of
    the two sweeps is σ⁰_NRL / (σ⁰_1m H²); compared with the NRL formula written here at the 4/3-earth grazing angle
    of each range bin's centre and the Douglas state of Hs (band middles; Hs 6.5 m is past the fit's state 6).
    And the physical sweep against the X-band HH one over the same water is σ⁰(f, pol)/σ⁰(9.41, HH). Within 1 %
    over 20–1200 m (0.7°–48.6° grazing): the rounded published coefficients differ by ≤ 0.7 %; the HH coefficients
    for VV would miss by 4–6 dB at low grazing, 9.41 GHz for 3.05 GHz by 3–5 dB, the band's upper Hs bound for its
    middle by 1–2.5 dB."""
    scene = Scene()
    sea = _quad(scene, [[-5000, -5000, 0], [5000, -5000, 0], [5000, 5000, 0], [-5000, 5000, 0]], cls=1)
    scene.set_sea(sea)
    height, sigma_1m = 15.0, 4e-7
    kw = {"range_min": 20.0, "range_max": 1200.0, "dr": 10.0, "bins": 256, "sigma_1m": sigma_1m}
    radar, x_hh = _radar(f_ghz=f_ghz, pol=pol, **kw), _radar(f_ghz=9.41, pol="HH", **kw)
    pose = pose_matrices(np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]))
    for hs in (0.5, 1.5, 3.5, 6.5):
        fixed, (phys, phys_x) = fixed_and_physical_sweeps(scene, [radar, x_hh], pose, clear_env(wave_height_m=hs))
        assert np.array_equal(fixed["range"], phys["range"]) and np.array_equal(phys["range"], phys_x["range"])
        r = phys["range"].astype(float)
        psi = np.degrees(np.arcsin(height / r - r / (2 * EARTH_K * EARTH_RADIUS_M)))
        assert psi.min() > 0.1 and psi.max() < 60.0  # inside the fit: no clamp involved
        ss = _douglas_state(hs)
        want = nrl_sigma0(pol, f_ghz, ss, psi)
        got = phys["intensity"].astype(float) / fixed["intensity"] * sigma_1m * hs**2
        np.testing.assert_allclose(got, want, rtol=0.01, err_msg=f"Hs {hs}")
        rel = phys["intensity"].astype(float) / phys_x["intensity"]
        np.testing.assert_allclose(rel, want / nrl_sigma0("HH", 9.41, ss, psi), rtol=0.01, err_msg=f"Hs {hs}")


def test_douglas_states_quoted_in_the_sea_doc() -> None:
    """``docs/sea/README.md``: W0's Hs 0.5 m was the model's state 2.0 and is now 2.35, W3's 3.5 m was 4.67 and is
    now 5.14; the fan's two-way gain is ¼ at its edges and 0.02 at 17° below its axis (20 m from a 6 m mast); sec ψ
    is 1.05 there."""
    assert round(_douglas_state(0.5), 2) == 2.35 and round(_douglas_state(3.5), 2) == 5.14
    upper = np.interp([0.5, 3.5], (0.0, *DOUGLAS_UPPER), np.arange(7))
    assert np.round(upper, 2).tolist() == [2.0, 4.67]
    theta = math.radians(20.0)

    def g2(e: float) -> float:
        return math.exp(-8 * math.log(2) * e**2 / theta**2)  # one-way half power at ±θ/2

    assert g2(theta / 2) == pytest.approx(0.25, rel=1e-12)
    e = math.atan(6.0 / 20.0)
    assert round(math.degrees(e)) == 17 and round(g2(e), 2) == 0.02
    assert round(1 / math.sqrt(1 - (6.0 / 20.0 - 20.0 / (2 * EARTH_K * EARTH_RADIUS_M)) ** 2), 2) == 1.05


# --- 4. Koschmieder ---


def test_fog_contrast_at_the_visibility_is_five_percent() -> None:
    """A sunlit metal wall at the scenario's visibility V = 800 m, seen level from 20 m: the rendered radiance
    is L = L₀ T + L_air (1 − T). Three renders (no fog, the weather's fog, an opaque fog that leaves L_air alone)
    give T = (L − L_air)/(L₀ − L_air) per pixel and channel, which must be Koschmieder's e^{−σ t} with t the ray's
    length to the wall and σ = −ln 0.05 / V (the 5 % contrast of the meteorological optical range): within 1 %
    (mmusv's σ = 3.0/V is 0.14 % above 2.996/V; float32). Koschmieder's 2 % threshold, σ = 3.912/V, would give
    T = 0.020 for 0.050 at the centre (−60 %); a fog applied one-way twice (e^{−2σt}) 0.0025."""
    vis = 800.0
    sigma = Weather.make("fog", visibility_m=vis).extinction_per_m
    assert sigma * vis == pytest.approx(-math.log(CONTRAST_THRESHOLD), rel=2e-3)
    scene = Scene()
    _quad(scene, [[vis, -2000, -500], [vis, 2000, -500], [vis, 2000, 1500], [vis, -2000, 1500]], cls=5)
    w, h = 64, 48
    cam = core.Camera(width=w, height=h, rgb=True, hfov=math.radians(40), quality="draft", range_max=50_000.0)
    pose = pose_matrices(np.array([0.0, 0.0, 20.0, 0.0, 0.0, 0.0]))
    sun = np.array([-math.cos(math.radians(30)), 0.2, math.sin(math.radians(30))])
    sun /= np.linalg.norm(sun)
    shots = {}
    for fog in (0.0, sigma, 0.5):
        img = render(cam, scene, pose=pose, env=clear_env(sun, fog_extinction_per_m=fog), seed=1, radiance=True)
        assert img.radiance is not None and np.all(img.semantic == 5)
        shots[fog] = img.radiance.astype(float)
    clear, foggy, opaque = shots[0.0], shots[sigma], shots[0.5]
    t = vis / cam.world_rays(pose)[1][:, 0].astype(float).reshape(h, w)
    want = np.broadcast_to(np.exp(-t * -math.log(CONTRAST_THRESHOLD) / vis)[..., None], clear.shape)
    contrast = clear - opaque
    ok = np.abs(contrast) > 0.05 * opaque  # pixels and channels where the wall stands out of the air light
    assert ok.mean() > 0.9
    transmission = (foggy - opaque)[ok] / contrast[ok]
    np.testing.assert_allclose(transmission, want[ok], rtol=0.01)
    assert want[h // 2, w // 2, 0] == pytest.approx(0.05, rel=0.01)


def test_lidar_fog_is_koschmieder_two_way() -> None:
    """A metal wall 150 m out, LiDAR 32 × 2048, in the fog of a 600 m visibility (the scenario's ``Weather``): every
    return's intensity is its clear-air intensity times the two-way transmission e^{−2σr} (the same ray, the same
    seed), σ = −ln 0.05 / V: the σ read back from each surviving return within 0.5 % (3.0/V against 2.996/V is
    0.14 %); and the returns kept number Σ e^{−2σr} over the clear-air returns within 5 binomial standard
    deviations (the loss is drawn per ray). A one-way loss reads σ/2, Koschmieder's 2 % threshold 1.3 σ."""
    vis = 600.0
    sigma = Weather.make("fog", visibility_m=vis).extinction_per_m
    scene = Scene()
    x = 150.0
    _quad(scene, [[x, -400, -100], [x, 400, -100], [x, 400, 100], [x, -400, 100]], cls=5)
    lidar = clear_lidar(channels=32, azimuth_steps=2048)
    pose = pose_matrices(np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0]))
    clear = lidar.scan(scene.native, pose=pose, env=clear_env(), seed=3)
    foggy = lidar.scan(scene.native, pose=pose, env=clear_env(fog_extinction_per_m=sigma), seed=3)
    assert clear["range"].size > 20_000
    kept, in_clear, in_fog = np.intersect1d(clear["ray_index"], foggy["ray_index"], return_indices=True)
    assert kept.size == foggy["ray_index"].size  # fog only removes returns
    r = clear["range"][in_clear].astype(float)
    read = -np.log(foggy["intensity"][in_fog].astype(float) / clear["intensity"][in_clear]) / (2 * r)
    np.testing.assert_allclose(read, -math.log(CONTRAST_THRESHOLD) / vis, rtol=5e-3)
    tau = np.exp(2 * math.log(CONTRAST_THRESHOLD) / vis * clear["range"].astype(float))
    assert abs(kept.size - tau.sum()) < 5 * math.sqrt(np.sum(tau * (1 - tau)))


# --- 5. ship response: the closed forms' limits ---


@pytest.mark.parametrize(
    "hull", [(4.88, 2.44, 0.35, 0.45, 1.464), (32.0, 12.0, 5.0, 0.52, 1.2), (190.0, 32.3, 12.8, 0.83, 2.584)]
)
def test_hull_raos_long_wave_limits_and_roll_resonance(hull: tuple[float, ...]) -> None:
    """``hull_rao`` of the catalogue's USV, tug and bulk carrier particulars. (1) Long waves (ω = 1e-3 rad/s): the
    hull follows the surface, heave → 1 m/m, pitch → k|cos β| (the wave slope along the hull) in head seas,
    roll → k in beam seas: within 1e-4 (JMO's F, G → κ f and k_e as k_e L → 0). (2) Beam seas, no speed: roll over
    its Froude–Krylov forcing k e^{−kT} R(kB/2), R(σ) = 3(sin σ − σ cos σ)/σ³ (the slope averaged over a flat
    bottom of beam B, derived here), is a 1-DOF oscillator whose amplitude peaks at ω_n √(1 − 2ζ²) at
    1/(2ζ √(1 − ζ²)) = 5.025, ω_n = √(g GM)/(0.39 B): within 1e-3 in place and height. ζ = 0.05 would peak at 10,
    k_xx = 0.35 B 11 % higher in frequency."""
    _, beam, draft, _, gm = hull
    w0 = np.array([1e-3, 1e-3])
    low = core.hull_rao(hull=list(hull), omega=w0, beta=np.array([math.pi, math.pi / 2]), omega_e=w0)
    k0 = 1e-6 / G
    assert abs(low[0, 0]) == pytest.approx(1.0, abs=1e-4)
    assert abs(low[0, 2]) / k0 == pytest.approx(1.0, abs=1e-4)
    assert abs(low[1, 1]) / k0 == pytest.approx(1.0, abs=1e-4)
    wn = math.sqrt(G * gm) / (ROLL_GYRADIUS_B * beam)
    w = np.linspace(0.5 * wn, 1.5 * wn, 20001)
    k = w**2 / G
    roll = core.hull_rao(hull=list(hull), omega=w, beta=np.full_like(w, math.pi / 2), omega_e=w)[:, 1]
    s = k * beam / 2
    forcing = k * np.exp(-k * draft) * 3 * (np.sin(s) - s * np.cos(s)) / s**3
    gain = np.abs(roll) / forcing
    peak = int(np.argmax(gain))
    assert w[peak] == pytest.approx(wn * math.sqrt(1 - 2 * ROLL_ZETA**2), rel=1e-3)
    assert gain[peak] == pytest.approx(1 / (2 * ROLL_ZETA * math.sqrt(1 - ROLL_ZETA**2)), rel=1e-3)


# --- 6. Preetham zenith ---

PREETHAM_XZ = (
    (0.00166, -0.00375, 0.00209, 0.0),
    (-0.02903, 0.06377, -0.03202, 0.00394),
    (0.11693, -0.21196, 0.06052, 0.25886),
)
PREETHAM_YZ = (
    (0.00275, -0.00610, 0.00317, 0.0),
    (-0.04214, 0.08970, -0.04153, 0.00516),
    (0.15346, -0.26756, 0.06670, 0.26688),
)
"""Preetham et al. (1999), Appendix A.2: x_z, y_z = [T², T, 1] · M · [θs³, θs², θs, 1]."""
SRGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
"""IEC 61966-2-1: linear sRGB (D65) to CIE XYZ."""


def test_preetham_zenith_luminance_and_chromaticity() -> None:
    """``sky_radiance`` straight up, for turbidity 2–8 and the sun 20°–70° from the zenith (cloud 0), converted to
    CIE XYZ: Y is Preetham's Y_z (kcd/m² → cd/m²) within 0.1 % (measured 4e-5: float32 and the sky table), x and y
    his x_z, y_z within 5e-4 (measured < 1e-4). A wrong χ (e.g. 4/9 − T/12) or a missing ×1000 misses Y by tens of
    per cent to ×1000; the T² row of the chromaticity matrices alone moves x_z by ~0.01 at T = 8."""
    for turbidity in (2.0, 3.0, 5.0, 8.0):
        for zenith_deg in (20.0, 45.0, 70.0):
            th = math.radians(zenith_deg)
            env = clear_env(np.array([math.sin(th), 0.0, math.cos(th)]), turbidity=turbidity)
            rgb = env.sky_radiance(np.array([[0.0, 0.0, 1.0]], np.float32))[0].astype(float)
            x_, y_, z_ = SRGB_TO_XYZ @ rgb
            chi = (4 / 9 - turbidity / 120) * (math.pi - 2 * th)
            lum = ((4.0453 * turbidity - 4.9710) * math.tan(chi) - 0.2155 * turbidity + 2.4192) * 1000.0
            tt, ths = np.array([turbidity**2, turbidity, 1.0]), np.array([th**3, th**2, th, 1.0])
            label = f"T {turbidity}, θs {zenith_deg}°"
            assert y_ == pytest.approx(lum, rel=1e-3), label
            assert x_ / (x_ + y_ + z_) == pytest.approx(tt @ np.array(PREETHAM_XZ) @ ths, abs=5e-4), label
            assert y_ / (x_ + y_ + z_) == pytest.approx(tt @ np.array(PREETHAM_YZ) @ ths, abs=5e-4), label
