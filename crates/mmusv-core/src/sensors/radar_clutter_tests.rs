//! Unit tests of the radar's clutter: its frequency and polarisation (`RadarConfig::frequency_ghz`, `polarisation`:
//! the NRL sea clutter of the radar's band, rain clutter's `λ⁻⁴`, the checks of both fields) and the sea clutter's
//! cell (pulse-limited, `sec ψ`; independent of the rays cast).

use super::*;
use crate::mesh::Mesh;
use crate::sensors::radar::sea_clutter::Polarisation;

const MAST: RigidPose = RigidPose { rotation: parry3d::math::Mat3::IDENTITY, translation: Vec3::new(0.0, 0.0, 6.0) };
/// Speed of light, m/s.
const C: f64 = 299_792_458.0;

/// A flat sea plane (instance 0), displaced by a WMO state-4 sea (Hs 1.875 m) when `waves`.
fn sea(waves: bool) -> Scene {
    use crate::ocean::{sea_seed, SeaSpec, WaveField};
    use crate::sea::{SurfaceSpec, WaveSurface};
    let mut s = Scene::new();
    let h = 20_000.0f32;
    let sea =
        Mesh::new("sea", &[[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]], &[[0, 1, 2], [0, 2, 3]], &[1]);
    let m = s.add_mesh(sea.unwrap_or_else(|e| unreachable!("{e}")));
    let _ = s.add_instance(m, RigidPose::IDENTITY, None);
    if waves {
        s.set_sea(0, &[]).unwrap_or_else(|e| unreachable!("{e}"));
        let spec = SeaSpec { hs: 1.875, tp: 7.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 };
        let field = WaveField::new(&spec, sea_seed(5)).unwrap_or_else(|e| unreachable!("{e}"));
        let w = WaveSurface::new(field.components(), 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
            .unwrap_or_else(|e| unreachable!("{e}"));
        s.set_wave_surface(Some(w)).unwrap_or_else(|e| unreachable!("{e}"));
    }
    s
}

/// Every cell reported (threshold 0), few rays: the clutter of each cell is `μ · (−ln u)` with `u` its own draw,
/// the same for every frequency, so the ratio of two sweeps' intensities is the ratio of their means.
fn cfg(frequency_ghz: f64, polarisation: Polarisation) -> RadarConfig {
    RadarConfig {
        azimuth_bins: 256,
        range_min_m: 20.0,
        range_max_m: 1200.0,
        rays_az: 1,
        rays_el: 4,
        target_rays: 16,
        detection_threshold: 0.0,
        clutter: ClutterModel { critical_range_per_m: 100_000.0, ..ClutterModel::tuning() },
        frequency_ghz,
        polarisation,
        ..RadarConfig::tuning()
    }
}

/// `(azimuth bits, range bits) → intensity` of the clutter returns of one sweep.
fn clutter(s: &Scene, cfg: &RadarConfig, env: &RadarEnv) -> std::collections::BTreeMap<(u32, u32), f64> {
    let r = radar_sweep(s, &MAST, cfg, env, 7).unwrap_or_else(|e| unreachable!("{e}"));
    (0..r.len())
        .filter(|&i| r.instance[i] == NO_HIT)
        .map(|i| ((r.azimuth[i].to_bits(), r.range[i].to_bits()), f64::from(r.intensity[i])))
        .collect()
}

/// An S-band (3.05 GHz) VV radar sees the sea clutter of its own band: cell for cell, its clutter over a WMO
/// state-4 sea is the X-band HH radar's times `σ⁰_NRL(3.05 GHz, VV, 4, ψ) / σ⁰_NRL(9.41 GHz, HH, 4, ψ)`, the
/// published formula (Gregers-Hansen & Mital 2012) written out here with both coefficient sets at the 4/3-earth
/// grazing angle. Until 2026-12-01 the frequency and polarisation were fixed at 9.41 GHz HH (the ratio was 1).
#[test]
fn an_s_band_vv_radar_sees_the_sea_clutter_of_its_band() {
    let nrl_db = |c: [f64; 5], f: f64, ss: f64, psi: f64| {
        c[0] + c[1] * psi.to_radians().sin().log10()
            + (27.5 + c[2] * psi) * f.log10() / (1.0 + 0.95 * psi)
            + c[3] * (ss + 1.0).powf(1.0 / (2.0 + 0.085 * psi + 0.033 * ss))
            + c[4] * psi * psi
    };
    let hh = [-73.0, 20.781, 7.351, 25.65, 0.0054];
    let vv = [-50.796, 25.93, 0.7093, 21.588, 0.00211];
    let s = sea(true);
    let env = RadarEnv { wave_height_m: 1.875, rain_mm_per_h: 0.0 };
    let x = clutter(&s, &cfg(9.41, Polarisation::Horizontal), &env);
    let sband = clutter(&s, &cfg(3.05, Polarisation::Vertical), &env);
    let h = f64::from(MAST.translation.z);
    let mut checked = 0;
    for (key, &got) in &sband {
        let Some(&base) = x.get(key) else { continue };
        let r = f64::from(f32::from_bits(key.1));
        let sin_psi = h / r - r / (2.0 * (4.0 / 3.0) * 6_371_000.0);
        let psi = sin_psi.asin().to_degrees().clamp(0.1, 60.0);
        let want_db = nrl_db(vv, 3.05, 4.0, psi) - nrl_db(hh, 9.41, 4.0, psi);
        let got_db = 10.0 * (got / base).log10();
        assert!((got_db - want_db).abs() < 1e-3, "r {r} m, ψ {psi:.3}°: {got_db} dB vs NRL {want_db} dB");
        checked += 1;
    }
    assert!(checked > 50_000, "{checked} cells compared");
    // HH at S band and VV at X band differ from both too: the knobs are independent.
    let s_hh = clutter(&s, &cfg(3.05, Polarisation::Horizontal), &env);
    let x_vv = clutter(&s, &cfg(9.41, Polarisation::Vertical), &env);
    let key = x.keys().find(|k| f32::from_bits(k.1) > 500.0).copied().unwrap_or_default();
    let at = |m: &std::collections::BTreeMap<(u32, u32), f64>| m.get(&key).copied().unwrap_or(f64::NAN);
    assert!(at(&s_hh) < at(&x) && at(&x) < at(&x_vv), "{} {} {}", at(&s_hh), at(&x), at(&x_vv));
}

/// Rain clutter follows the radar's frequency as Rayleigh scattering does: with `rain_eta_at_1mm_h` set to
/// Marshall–Palmer rain at X band, `η = π⁵ |K|² Z / λ⁴` with `Z = 200 R^1.6` mm⁶/m³ (Skolnik §13.6), an S-band
/// radar's rain clutter is, cell for cell, the same formula at its own wavelength (over a calm sea: no sea
/// clutter), and both lose what ITU-R P.838-3 gives at their frequency. Until 2026-12-01 η did not depend on the
/// frequency (S band saw X band's rain, 19.6 dB too bright), nor did the rain's attenuation.
#[test]
fn rain_clutter_follows_the_radars_wavelength() {
    let eta_mp = |f_ghz: f64, rain: f64| {
        let lambda = C / (f_ghz * 1e9);
        std::f64::consts::PI.powi(5) * 0.93 * 200.0 * rain.powf(1.6) * 1e-18 / lambda.powi(4)
    };
    let knob = eta_mp(9.41, 1.0);
    assert!((knob / 5.52e-8 - 1.0).abs() < 0.01, "Marshall–Palmer at 9.41 GHz: {knob}");
    let with = |f: f64| RadarConfig {
        clutter: ClutterModel { sea_sigma0_at_1m: 0.0, rain_eta_at_1mm_h: knob, ..ClutterModel::tuning() },
        ..cfg(f, Polarisation::Horizontal)
    };
    let (s, rain) = (sea(false), 10.0);
    let env = RadarEnv { wave_height_m: 0.0, rain_mm_per_h: rain as f32 };
    let (x, sband) = (clutter(&s, &with(9.41), &env), clutter(&s, &with(3.05), &env));
    let mut checked = 0;
    for (key, &got) in &sband {
        let Some(&base) = x.get(key) else { continue };
        let r = f64::from(f32::from_bits(key.1));
        // And the two-way rain loss of each band (ITU-R P.838-3, HH, 10 mm/h: 0.18112 dB/km at 9.41 GHz,
        // 0.0024276 dB/km at 3.05 GHz, evaluated independently of the code).
        let loss = 10f64.powf(-2.0 * (0.0024276 - 0.18112) * r / 1000.0 / 10.0);
        let want = eta_mp(3.05, rain) / eta_mp(9.41, rain) * loss;
        assert!((got / base / want - 1.0).abs() < 1e-4, "r {r} m: {} vs {want}", got / base);
        checked += 1;
    }
    assert!(checked > 50_000, "{checked} cells compared");
}

/// A frequency outside the NRL model's 0.5–35 GHz, or not finite, is refused naming `radar.frequency_ghz`; a
/// polarisation other than HH or VV naming `radar.polarisation`.
#[test]
fn bad_frequency_or_polarisation_is_refused_by_name() {
    for f in [0.4, 35.1, f64::NAN, f64::INFINITY, -9.41] {
        let bad = RadarConfig { frequency_ghz: f, ..RadarConfig::tuning() };
        match bad.validate() {
            Err(MmusvError::Config { field, reason, .. }) => {
                assert_eq!(field, "radar.frequency_ghz");
                assert!(reason.contains("0.5") && reason.contains("35"), "{reason}");
            }
            other => unreachable!("{f} GHz: {other:?}"),
        }
    }
    for f in [0.5, 3.05, 9.41, 35.0] {
        assert!(RadarConfig { frequency_ghz: f, ..RadarConfig::tuning() }.validate().is_ok(), "{f} GHz");
    }
    assert_eq!(Polarisation::parse("VV").ok(), Some(Polarisation::Vertical));
    assert_eq!(Polarisation::parse("HH").ok(), Some(Polarisation::Horizontal));
    for name in ["hh", "HV", "circular", ""] {
        match Polarisation::parse(name) {
            Err(MmusvError::Config { field, reason, .. }) => {
                assert_eq!(field, "radar.polarisation");
                assert!(reason.contains("HH") && reason.contains("VV"), "{reason}");
            }
            other => unreachable!("{name:?}: {other:?}"),
        }
    }
}

/// The sea clutter's cell is pulse-limited, `A = r θ_az Δr sec ψ` (Skolnik §13.2): cell for cell (the same
/// draws), the clutter of an antenna 15 m up over the flat sea's fixed `σ⁰ H²` rule is that of one 3 m up times
/// `sec ψ₁₅(r) / sec ψ₃(r)`, with `sin ψ = h / r − r / (2 · 4/3 · R_e)` written out here (1.51 at 20 m), and
/// times the ratio of the fan's two-way gains where the water lies (the elevation pattern's test below); and no
/// sea clutter lies closer than the antenna's height, where there is no water at that slant range. Until
/// 2026-12-01 the area was `r θ_az Δr` whatever the grazing angle (the ratio was 1), and clutter was drawn there.
#[test]
fn the_sea_clutter_cell_is_pulse_limited() {
    let cfg = RadarConfig {
        range_min_m: 0.0,
        range_max_m: 600.0,
        clutter: ClutterModel { rain_eta_at_1mm_h: 0.0, ..cfg(9.41, Polarisation::Horizontal).clutter },
        ..cfg(9.41, Polarisation::Horizontal)
    };
    let s = sea(false);
    let env = RadarEnv { wave_height_m: 1.5, rain_mm_per_h: 0.0 };
    let at = |h: f32| {
        let pose = RigidPose { translation: Vec3::new(0.0, 0.0, h), ..MAST };
        let r = radar_sweep(&s, &pose, &cfg, &env, 7).unwrap_or_else(|e| unreachable!("{e}"));
        (0..r.len())
            .filter(|&i| r.instance[i] == NO_HIT)
            .map(|i| ((r.azimuth[i].to_bits(), r.range[i].to_bits()), f64::from(r.intensity[i])))
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    let (high, low) = (at(15.0), at(3.0));
    let sec = |h: f64, r: f64| {
        let s = (h / r - r / (2.0 * (4.0 / 3.0) * 6_371_000.0)).max(0.0);
        1.0 / (1.0 - s * s).sqrt()
    };
    let mut checked = 0;
    for (key, &base) in &low {
        let r = f64::from(f32::from_bits(key.1));
        match high.get(key) {
            Some(&got) => {
                assert!(r > 15.0, "sea clutter {r} m from an antenna 15 m up");
                // And the fan's two-way gain where the water lies (Gaussian, θ_el = 20°, axis level).
                let g2 = |h: f64| (-8.0 * std::f64::consts::LN_2 * ((h / r).atan() / 20f64.to_radians()).powi(2)).exp();
                let want = sec(15.0, r) / sec(3.0, r) * g2(15.0) / g2(3.0);
                assert!((got / base / want - 1.0).abs() < 1e-5, "r {r} m: {} vs sec ratio {want}", got / base);
                checked += 1;
            }
            None => assert!(r <= 15.0, "r {r} m: no clutter from 15 m up"),
        }
    }
    assert!(checked > 10_000 && low.keys().any(|k| f32::from_bits(k.1) < 15.0), "{checked} cells compared");
    assert!((sec(15.0, 19.5) - 1.5650).abs() < 1e-3);
}

/// Clutter intensities do not depend on how many rays the sweep casts: over the open physical sea the clutter
/// returns of 1 × 4, 3 × 16 and 2 × 9 rays a beam are the same, bit for bit (the clutter means come from the
/// beam's widths, not its rays; only shadows, which need something to cast them, are seen through the rays).
#[test]
fn clutter_does_not_depend_on_the_rays_cast() {
    let s = sea(true);
    let env = RadarEnv { wave_height_m: 1.875, rain_mm_per_h: 3.0 };
    let with = |rays_az: u32, rays_el: u32| {
        let c = RadarConfig { rays_az, rays_el, azimuth_bins: 128, ..cfg(9.41, Polarisation::Horizontal) };
        clutter(&s, &c, &env).into_iter().map(|(k, v)| (k, v.to_bits())).collect::<Vec<_>>()
    };
    let base = with(1, 4);
    assert!(base.len() > 10_000);
    assert_eq!(with(3, 16), base);
    assert_eq!(with(2, 9), base);
}

/// The fan's elevation pattern weights the sea clutter where the water lies: cell for cell (the same draws), the
/// clutter of a 20° fan (±10°) over that of a 60° fan from a 6 m mast is `G²₂₀(e) / G²₆₀(e)` at the water's
/// elevation `e = −atan(h / r)`, with the Gaussian two-way gain `exp(−8 ln 2 e² / θ_el²)` written out here (0.032
/// at 20 m, 0.98 at 300 m). And rain fills the beam: its mean is `η r² θ_az θ_el √(π / (8 ln 2)) Δr (R_ref/r)⁴`,
/// the pattern integrated. Until 2026-12-01 the fan was uniform: the sea 17° below the axis, outside a ±10° fan,
/// gave the same clutter as on it (the ratio was 1) and rain filled `θ_el` whole.
#[test]
fn the_fan_pattern_weights_sea_and_rain_clutter() {
    let base = RadarConfig {
        range_max_m: 600.0,
        clutter: ClutterModel { rain_eta_at_1mm_h: 0.0, ..cfg(9.41, Polarisation::Horizontal).clutter },
        ..cfg(9.41, Polarisation::Horizontal)
    };
    let fan = |deg: f64| RadarConfig { elevation_fan_rad: [(-deg).to_radians(), deg.to_radians()], ..base };
    let (s, env) = (sea(false), RadarEnv { wave_height_m: 1.5, rain_mm_per_h: 0.0 });
    let (narrow, wide) = (clutter(&s, &fan(10.0), &env), clutter(&s, &fan(30.0), &env));
    assert!(narrow.len() > 10_000);
    let g2 = |e: f64, width_deg: f64| (-8.0 * std::f64::consts::LN_2 * (e / width_deg.to_radians()).powi(2)).exp();
    let h = f64::from(MAST.translation.z);
    let mut checked = 0;
    for (key, &got) in &narrow {
        let Some(&w) = wide.get(key) else { continue };
        let r = f64::from(f32::from_bits(key.1));
        let e = -(h / r).atan();
        let want = g2(e, 20.0) / g2(e, 60.0);
        assert!((got / w / want - 1.0).abs() < 1e-5, "r {r} m: {} vs {want}", got / w);
        checked += 1;
    }
    assert!(checked > 10_000, "{checked} cells compared");
    assert!((g2(-(6f64 / 19.5).atan(), 20.0) / g2(-(6f64 / 19.5).atan(), 60.0) - 0.0272).abs() < 1e-3);
    // Rain: the mean of the model, against the integrated pattern written out.
    let c = RadarConfig { clutter: ClutterModel { rain_eta_at_1mm_h: 5e-9, ..base.clutter }, ..fan(10.0) };
    let cell = c.cell_shape(6.0);
    for r in [50.0, 400.0] {
        let (_, rain) = radar_model::clutter_mean(&c.clutter, &cell, &c.band(), 0.0, 4.0, r);
        let theta_el = 20f64.to_radians();
        let volume = r * r * c.beamwidth_az_rad * theta_el * (std::f64::consts::PI / (8.0 * 2f64.ln())).sqrt() * 3.0;
        // ITU-R P.838-3 at 9.41 GHz HH (radar_model's test): k = 0.009299, α = 1.28951.
        let loss = 10f64.powf(-2.0 * 0.009299 * 4f64.powf(1.28951) * r / 1000.0 / 10.0);
        let want = 5e-9 * 4f64.powf(1.6) * volume * (1000.0 / r).powi(4) * loss;
        assert!((rain / want - 1.0).abs() < 1e-5, "r {r} m: {rain} vs {want}");
    }
}
