//! Unit tests of the radar sweep (`radar.rs`): binning, determinism, clutter, validation.

use super::*;
use crate::mesh::Mesh;
use crate::scene::tests::box_mesh;

/// A sea plane (instance 0) and a 10 m cube (instance 1) whose near face is at `range` and `bearing`
/// (world frame, from the origin), standing on the water.
fn sea_with_box(range: f64, bearing: f64) -> Scene {
    let mut s = Scene::new();
    let h = 20_000.0f32;
    let sea =
        Mesh::new("sea", &[[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]], &[[0, 1, 2], [0, 2, 3]], &[1]);
    let sea = s.add_mesh(sea.unwrap_or_else(|e| unreachable!("{e}")));
    let _ = s.add_instance(sea, RigidPose::IDENTITY, None);
    let cube = s.add_mesh(box_mesh([5.0, 5.0, 5.0], 10));
    let c = range + 5.0;
    let pose = RigidPose::from_xyz_rpy([c * bearing.cos(), c * bearing.sin(), 3.0], [0.0, 0.0, bearing]);
    let _ = s.add_instance(cube, pose, None);
    s
}

fn small_cfg() -> RadarConfig {
    RadarConfig { azimuth_bins: 512, range_max_m: 1500.0, rays_el: 32, ..RadarConfig::tuning() }
}

const MAST: RigidPose = RigidPose { rotation: parry3d::math::Mat3::IDENTITY, translation: Vec3::new(0.0, 0.0, 3.0) };

fn sweep(s: &Scene, cfg: &RadarConfig, waves: f32, seed: u64) -> RadarReturns {
    radar_sweep(s, &MAST, cfg, &RadarEnv { wave_height_m: waves, rain_mm_per_h: 0.0 }, seed)
        .unwrap_or_else(|e| unreachable!("{e}"))
}

#[test]
fn trace_order_is_a_permutation() {
    for (samples, rows) in [(24, 5), (13, 3), (1, 1), (8, 16)] {
        let mut seen = vec![false; samples * rows];
        for g in 0..samples {
            for k in 0..rows {
                let i = trace_index(g, k, samples, rows);
                assert!(!seen[i], "duplicate index {i}");
                seen[i] = true;
            }
        }
        assert!(seen.iter().all(|&x| x));
    }
}

#[test]
fn ray_pattern_spans_beam_and_fan() {
    let uniform = RadarConfig { horizon_fraction: 0.0, ..RadarConfig::tuning() };
    let [lo, hi] = uniform.elevation_fan_rad;
    let rows = uniform.rays_el as usize;
    let mut column = vec![(0.0, 0.0); rows];
    for cfg in [uniform, RadarConfig::tuning()] {
        let (mut min_el, mut max_el) = (f64::MAX, f64::MIN);
        for g in 0..cfg.rays_az * 64 {
            let b = g / cfg.rays_az;
            let az = cfg.sample_azimuth(g);
            assert!((az - cfg.beam_azimuth(b)).abs() < cfg.beamwidth_az_rad / 2.0);
            cfg.sample_elevations(g, Some(0.0), &mut column);
            let total: f64 = column.iter().map(|c| c.1).sum();
            assert!((total - (hi - lo)).abs() < 1e-9, "weights sum to the fan height");
            for &(el, _) in &column {
                assert!(el >= lo && el < hi);
                min_el = min_el.min(el);
                max_el = max_el.max(el);
            }
        }
        // Over a few beams the staggered rows cover the fan to within a small fraction of a row spacing.
        let row = (hi - lo) / rows as f64;
        assert!(min_el - lo < 0.05 * row && hi - max_el < 0.05 * row, "{min_el} {max_el}");
    }
    // Default: three quarters of the rays within ±1° of the horizon, which follows the sensor's roll.
    let cfg = RadarConfig::tuning();
    let rolled = RigidPose::from_xyz_rpy([0.0, 0.0, 3.0], [0.1, 0.0, 0.0]);
    let left = horizon_elevation(&rolled, std::f64::consts::FRAC_PI_2).unwrap_or(f64::NAN);
    assert!((left + 0.1).abs() < 1e-6, "rolled right-side-down by 0.1 rad: the horizon on the left is 0.1 rad low");
    cfg.sample_elevations(7, Some(left), &mut column);
    let near = column.iter().filter(|c| (c.0 - left).abs() <= cfg.horizon_band_rad).count();
    assert_eq!(near, rows * 3 / 4);
    assert_eq!(horizon_elevation(&RigidPose::from_xyz_rpy([0.0; 3], [0.0, 0.0, 2.0]), 1.0), Some(0.0));
    // A flat fan: every ray at the one elevation, weights still positive.
    let flat = RadarConfig { elevation_fan_rad: [0.0, 0.0], ..cfg };
    flat.sample_elevations(3, Some(0.0), &mut column);
    assert!(column.iter().all(|&(el, w)| el == 0.0 && w > 0.0));
}

#[test]
fn target_lands_in_its_range_and_azimuth_bin() {
    let cfg = small_cfg();
    for (range, bearing_deg) in [(400.0, 0.0), (730.0, 37.0), (1210.0, 200.0), (95.0, 301.5)] {
        let bearing = f64::to_radians(bearing_deg);
        let s = sea_with_box(range, bearing);
        let ret = sweep(&s, &cfg, 0.0, 1);
        assert!(ret.instance.iter().all(|&i| i == 1), "only the cube, no clutter without waves");
        assert!(!ret.is_empty(), "cube at {range} m not seen");
        let nearest = ret.range.iter().fold(f32::MAX, |m, &r| m.min(r)) as f64;
        assert!((nearest - range).abs() <= cfg.range_resolution_m, "range {nearest} vs {range}");
        let k = (0..ret.len()).max_by(|&a, &b| ret.intensity[a].total_cmp(&ret.intensity[b])).unwrap_or(0);
        let mut diff = (ret.azimuth[k] as f64 - bearing).rem_euclid(std::f64::consts::TAU);
        if diff > std::f64::consts::PI {
            diff -= std::f64::consts::TAU;
        }
        // Within half a beam (plus half a bin) of some point of the 10 m wide face.
        let tol = cfg.beamwidth_az_rad / 2.0 + std::f64::consts::PI / cfg.azimuth_bins as f64 + (5.0 / range).atan();
        assert!(diff.abs() <= tol, "azimuth {} vs {bearing}", ret.azimuth[k]);
        // Sorted by (azimuth bin, range bin); azimuths are bin centres in [0, 2π).
        let bin_of = |a: f32| (a as f64 / std::f64::consts::TAU * cfg.azimuth_bins as f64).round() as u32;
        for w in 0..ret.len().saturating_sub(1) {
            let key = |i: usize| (bin_of(ret.azimuth[i]), ret.range[i].to_bits());
            assert!(key(w) < key(w + 1));
        }
        assert!(ret.azimuth.iter().all(|&a| (0.0..std::f32::consts::TAU).contains(&a)));
    }
}

#[test]
fn echoes_from_inside_the_blind_range_are_not_received() {
    // Bins of 30 m: the first, [0, 30), is reported at 15 m, beyond a blind range of 13 m. A 10 m cube from 2 to
    // 12 m lies wholly inside the blind range: nothing comes back (it was reported at 15 m). One from 40 m is seen.
    let cfg = RadarConfig { range_min_m: 13.0, range_resolution_m: 30.0, ..small_cfg() };
    assert!(sweep(&sea_with_box(2.0, 0.0), &cfg, 0.0, 1).is_empty());
    let far = sweep(&sea_with_box(40.0, 0.0), &cfg, 0.0, 1);
    assert!(!far.is_empty() && far.range.iter().all(|&r| r == 45.0), "{:?}", far.range);
}

#[test]
fn bigger_and_nearer_targets_are_brighter_rain_attenuates() {
    let cfg = small_cfg();
    let total = |r: &RadarReturns| r.intensity.iter().map(|&x| x as f64).sum::<f64>();
    let near = sweep(&sea_with_box(300.0, 0.5), &cfg, 0.0, 1);
    let far = sweep(&sea_with_box(900.0, 0.5), &cfg, 0.0, 1);
    assert!(total(&near) > 3.0 * total(&far), "{} vs {}", total(&near), total(&far));
    let s = sea_with_box(900.0, 0.5);
    let wet_cfg = RadarConfig { clutter: ClutterModel { rain_eta_at_1mm_h: 0.0, ..ClutterModel::tuning() }, ..cfg };
    let wet = radar_sweep(&s, &MAST, &wet_cfg, &RadarEnv { wave_height_m: 0.0, rain_mm_per_h: 30.0 }, 1);
    let wet = wet.unwrap_or_default();
    assert!(!wet.is_empty() && total(&wet) < 0.97 * total(&far));
}

#[test]
fn same_seed_same_bytes_other_seed_other_clutter() {
    let cfg = RadarConfig { range_noise_std_m: 0.5, ..small_cfg() };
    let s = sea_with_box(500.0, 1.0);
    let a = sweep(&s, &cfg, 2.0, 7);
    let b = sweep(&s, &cfg, 2.0, 7);
    assert_eq!(a, b);
    let c = sweep(&s, &cfg, 2.0, 8);
    assert_ne!(a.range, c.range);
    // Thread count does not matter.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build();
    let one = pool.map(|p| p.install(|| sweep(&s, &cfg, 2.0, 7))).unwrap_or_default();
    assert_eq!(a, one);
}

#[test]
fn clutter_grows_with_waves_and_stops_at_range() {
    let cfg = small_cfg();
    let s = sea_with_box(1400.0, 0.0);
    let clutter = |h: f32| {
        let r = sweep(&s, &cfg, h, 3);
        let keep: Vec<(u32, u32)> = (0..r.len())
            .filter(|&i| r.instance[i] == NO_HIT)
            .map(|i| (r.azimuth[i].to_bits(), r.range[i].to_bits()))
            .collect();
        assert!((0..r.len()).filter(|&i| r.instance[i] == NO_HIT).all(|i| r.class[i] == CLASS_WATER));
        let far = (0..r.len()).filter(|&i| r.instance[i] == NO_HIT).map(|i| r.range[i]).fold(0.0f32, f32::max);
        (keep, far)
    };
    let (w0, far0) = clutter(0.5);
    let (w3, far3) = clutter(3.5);
    assert!(w0.len() > 50, "{}", w0.len());
    assert!(w3.len() > 3 * w0.len(), "{} vs {}", w3.len(), w0.len());
    eprintln!("clutter cells W0 {} (to {far0} m), W3 {} (to {far3} m)", w0.len(), w3.len());
    assert!(far3 > 2.0 * far0 && far0 > 0.0, "{far0} {far3}");
    // Same seed: the calm-sea clutter cells are a subset of the rough-sea ones.
    let rough: std::collections::HashSet<(u32, u32)> = w3.into_iter().collect();
    assert!(w0.iter().all(|c| rough.contains(c)));
    assert!(clutter(0.0).0.is_empty());
    // Nothing beyond the sea clutter limit.
    let limited = RadarConfig { clutter: ClutterModel { sea_max_range_m: 150.0, ..ClutterModel::tuning() }, ..cfg };
    let r = sweep(&s, &limited, 3.5, 3);
    assert!((0..r.len()).filter(|&i| r.instance[i] == NO_HIT).all(|i| r.range[i] <= 150.0));
}

#[test]
fn misconfiguration_names_the_field() {
    let s = Scene::new();
    let field_of = |cfg: RadarConfig, env: RadarEnv| match radar_sweep(&s, &MAST, &cfg, &env, 0) {
        Err(MmusvError::Config { field, .. }) => field,
        other => format!("no config error: {other:?}"),
    };
    let d = RadarConfig::tuning();
    let e = RadarEnv::default();
    let cases = [
        (RadarConfig { azimuth_bins: 0, ..d }, "radar.azimuth_bins"),
        (RadarConfig { range_max_m: -5.0, ..d }, "radar.range_max_m"),
        (RadarConfig { range_min_m: -1.0, ..d }, "radar.range_min_m"),
        (RadarConfig { range_min_m: 4000.0, ..d }, "radar.range_min_m"),
        (RadarConfig { range_resolution_m: 0.0, ..d }, "radar.range_resolution_m"),
        (RadarConfig { range_resolution_m: 1e-4, ..d }, "radar.range_resolution_m"),
        (RadarConfig { beamwidth_az_rad: 0.0, ..d }, "radar.beamwidth_az_rad"),
        (RadarConfig { beamwidth_az_rad: -0.1, ..d }, "radar.beamwidth_az_rad"),
        (RadarConfig { elevation_fan_rad: [0.2, -0.2], ..d }, "radar.elevation_fan_rad"),
        (RadarConfig { rays_az: 0, ..d }, "radar.rays_az"),
        (RadarConfig { rays_el: 0, ..d }, "radar.rays_el"),
        (RadarConfig { rays_el: 100_000, ..d }, "radar.rays_el"),
        (RadarConfig { detection_threshold: f64::NAN, ..d }, "radar.detection_threshold"),
        (RadarConfig { horizon_fraction: 1.5, ..d }, "radar.horizon_fraction"),
        (RadarConfig { horizon_band_rad: -0.1, ..d }, "radar.horizon_band_rad"),
        (RadarConfig { range_noise_std_m: -1.0, ..d }, "radar.range_noise_std_m"),
        (
            RadarConfig { clutter: ClutterModel { sea_sigma0_at_1m: -1.0, ..ClutterModel::tuning() }, ..d },
            "radar.clutter.sea_sigma0_at_1m",
        ),
    ];
    for (cfg, field) in cases {
        assert_eq!(field_of(cfg, e), field);
    }
    assert_eq!(field_of(d, RadarEnv { wave_height_m: -1.0, ..e }), "radar.wave_height_m");
    assert_eq!(field_of(d, RadarEnv { rain_mm_per_h: f32::INFINITY, ..e }), "radar.rain_mm_per_h");
    // An empty scene is not an error: no targets, no clutter without waves.
    assert!(radar_sweep(&s, &MAST, &d, &e, 0).is_ok_and(|r| r.is_empty()));
}

/// Over the physical sea, the clutter-only detections of each range band occur at the rate the NRL model's mean
/// gives (`exp(−threshold / μ)` per cell, `μ = σ⁰_NRL(SS, ψ) · A · (R_ref/r)⁴ · G²`, `G²` the fan's two-way gain
/// where the water lies), and grow with the sea state.
#[test]
fn physical_sea_clutter_follows_the_nrl_model() {
    use crate::ocean::{sea_seed, SeaSpec, WaveField};
    use crate::sea::{SurfaceSpec, WaveSurface};
    use crate::sensors::radar::sea_clutter::PhysicalSea;
    let cfg = RadarConfig {
        azimuth_bins: 1024,
        range_max_m: 1200.0,
        rays_el: 8,
        target_rays: 16,
        detection_threshold: 0.3,
        ..RadarConfig::tuning()
    };
    let detections = |hs: f64, tp: f64| {
        let mut s = sea_with_box(5000.0, 0.0);
        s.set_sea(0, &[]).unwrap_or_else(|e| unreachable!("{e}"));
        let spec = SeaSpec { hs, tp, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 };
        let field = WaveField::new(&spec, sea_seed(5)).unwrap_or_else(|e| unreachable!("{e}"));
        let w = WaveSurface::new(field.components(), 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
            .unwrap_or_else(|e| unreachable!("{e}"));
        s.set_wave_surface(Some(w)).unwrap_or_else(|e| unreachable!("{e}"));
        let r = sweep(&s, &cfg, hs as f32, 11);
        (0..r.len()).filter(|&i| r.instance[i] == NO_HIT).map(|i| r.range[i] as f64).collect::<Vec<f64>>()
    };
    let expected = |hs: f64, lo: f64, hi: f64| {
        let sea = PhysicalSea::new(hs, f64::from(MAST.translation.z));
        let (first, _) = cfg.range_bins();
        let mut n = 0.0;
        for bin in first.. {
            let r = cfg.bin_centre(bin);
            if r >= hi {
                break;
            }
            if r >= lo {
                // Weighted by the fan's two-way gain where the water lies (Gaussian, θ_el = 20°, axis level).
                let e = f64::from(MAST.translation.z).atan2(r) / 20f64.to_radians();
                let g2 = (-8.0 * std::f64::consts::LN_2 * e * e).exp();
                let (mu, _) = radar_model::clutter_mean_sigma0(
                    &cfg.clutter,
                    &cfg.cell_shape(sea.antenna_height_m),
                    &cfg.band(),
                    sea.sigma0(r),
                    0.0,
                    r,
                );
                n += (-cfg.detection_threshold / (mu * g2)).exp() * cfg.azimuth_bins as f64;
            }
        }
        n
    };
    let (w1, w3) = (detections(1.5, 6.0), detections(3.5, 9.0));
    assert!(w3.len() > w1.len() && !w1.is_empty(), "{} vs {}", w3.len(), w1.len());
    for (hs, got) in [(1.5, &w1), (3.5, &w3)] {
        for (lo, hi) in [(10.0, 100.0), (100.0, 300.0), (300.0, 1200.0)] {
            let n = got.iter().filter(|&&r| r >= lo && r < hi).count() as f64;
            let want = expected(hs, lo, hi);
            // Binomial counts: within 4 standard deviations (and 2 cells) of the model's expectation.
            let sd = want.sqrt();
            eprintln!("clutter Hs {hs} m, {lo}-{hi} m: {n} detections, NRL model {want:.1}");
            assert!((n - want).abs() <= 4.0 * sd + 2.0, "Hs {hs}, {lo}-{hi} m: {n} detections, model {want:.1}");
        }
    }
}

/// A ray stands for the solid angle `Δφ · Δe · cos e` of the beam: a 30 m plate facing the radar 300 m away
/// gives (summed over the beams that see it) the radar equation's `ρ A (R_ref/r)⁴` times the beams per point of
/// it (beamwidth / bin width) times the fan's two-way gain there (Gaussian, 90° between half-power points here:
/// 0.335 at 40°), on the horizon and 40° above it. Without the `cos e` the plate 40° up came out 1/cos 40° = 1.31
/// times as bright; without the elevation pattern (until 2026-12-01) as bright as on the horizon.
#[test]
fn a_target_above_the_horizon_follows_the_fan_pattern() {
    let cfg = RadarConfig {
        azimuth_bins: 1024,
        rays_az: 4,
        rays_el: 512,
        target_rays: 16,
        elevation_fan_rad: [(-45f64).to_radians(), 45f64.to_radians()],
        horizon_fraction: 0.0,
        detection_threshold: 1e-12,
        clutter: ClutterModel { sea_sigma0_at_1m: 0.0, rain_eta_at_1mm_h: 0.0, ..ClutterModel::tuning() },
        ..RadarConfig::tuning()
    };
    let (r, half) = (300.0f64, 15.0f32);
    let total = |e_deg: f64| {
        let mut s = Scene::new();
        let plate = Mesh::new(
            "plate",
            &[[0.0, -half, -half], [0.0, half, -half], [0.0, half, half], [0.0, -half, half]],
            &[[0, 2, 1], [0, 3, 2]],
            &[10],
        )
        .unwrap_or_else(|e| unreachable!("{e}"));
        let m = s.add_mesh(plate);
        let e = e_deg.to_radians();
        let _ = s.add_instance(m, RigidPose::from_xyz_rpy([r * e.cos(), 0.0, r * e.sin()], [0.0, -e, 0.0]), None);
        let ret = radar_sweep(&s, &RigidPose::IDENTITY, &cfg, &RadarEnv::default(), 1)
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert!(ret.instance.iter().all(|&i| i == 0) && !ret.is_empty());
        ret.intensity.iter().map(|&x| f64::from(x)).sum::<f64>()
    };
    let (level, raised) = (total(0.0), total(40.0));
    // The fan's Gaussian two-way gain exp(−8 ln 2 e² / θ_el²), θ_el = 90°, averaged over the plate's ±atan(15/300).
    let gain = |e_deg: f64| {
        let a = (f64::from(half) / r).atan();
        (0..=100)
            .map(|i| {
                let e = e_deg.to_radians() - a + 2.0 * a * f64::from(i) / 100.0;
                (-8.0 * std::f64::consts::LN_2 * (e / std::f64::consts::FRAC_PI_2).powi(2)).exp()
            })
            .sum::<f64>()
            / 101.0
    };
    let want =
        900.0 * (radar_model::REFERENCE_RANGE_M / r).powi(4) * cfg.beamwidth_az_rad / (std::f64::consts::TAU / 1024.0);
    eprintln!("plate on the horizon {:.3}, 40° up {:.3} of the radar equation", level / want, raised / want);
    assert!((level / (want * gain(0.0)) - 1.0).abs() < 0.08, "{}", level / want);
    let ratio = raised / level / (gain(40.0) / gain(0.0));
    assert!((ratio - 1.0).abs() < 0.05, "40° up {raised} vs level {level}: {ratio} of the pattern's");
}

/// Sea clutter comes from the water in view: an island 60–160 m off (a 30 m high block, 100 m wide) leaves no sea
/// clutter over itself nor in its shadow behind it, while the sea in front of it and in the other directions
/// keeps the clutter it had without the island, return for return (the same draws). Until 2026-12-01 sea
/// clutter was drawn at every range of every beam, over the island and behind it too.
#[test]
fn no_sea_clutter_over_land_or_in_its_shadow() {
    let cfg = RadarConfig { range_max_m: 900.0, ..small_cfg() };
    let with_island = |island: bool| {
        let mut s = sea_with_box(5000.0, 0.0);
        if island {
            let block = s.add_mesh(box_mesh([50.0, 50.0, 15.0], 2));
            let _ = s.add_instance(block, RigidPose::from_xyz_rpy([110.0, 0.0, 10.0], [0.0; 3]), None);
        }
        sweep(&s, &cfg, 3.5, 4)
    };
    let (open, island) = (with_island(false), with_island(true));
    let clutter = |r: &RadarReturns, keep: &dyn Fn(f64, f64) -> bool| -> Vec<(u32, u32, u32)> {
        (0..r.len())
            .filter(|&i| r.instance[i] == NO_HIT && keep(r.azimuth[i] as f64, r.range[i] as f64))
            .map(|i| (r.azimuth[i].to_bits(), r.range[i].to_bits(), r.intensity[i].to_bits()))
            .collect()
    };
    let bearing = |a: f64| if a > std::f64::consts::PI { a - std::f64::consts::TAU } else { a };
    // The island spans bearings ±atan(50 / 60) = ±39.8°; beams well inside it, beyond its near shore (x = 60 m).
    let behind = |a: f64, r: f64| bearing(a).abs() < 0.6 && r * a.cos() > 62.0;
    assert!(clutter(&open, &behind).len() > 1000, "the open sea there has clutter");
    assert_eq!(clutter(&island, &behind).len(), 0, "no sea clutter over the island or behind it");
    // In front of the island and away from it, the same clutter as without the island.
    let in_front = |a: f64, r: f64| bearing(a).abs() < 0.6 && r * a.cos() < 58.0;
    let away = |a: f64, _r: f64| bearing(a).abs() > 1.0;
    assert!(clutter(&open, &in_front).len() > 100);
    assert_eq!(clutter(&island, &in_front), clutter(&open, &in_front));
    assert_eq!(clutter(&island, &away), clutter(&open, &away));
}
