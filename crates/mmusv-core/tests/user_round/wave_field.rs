//! The wave field: elevation is the documented sum of components, and bad parameters, grid sizes and depths
//! are refused.

use super::common::{close, guarded, ok, refuses, spec, Lcg};
use mmusv_core::ocean::{SeaSpec, WaveField};
use std::f64::consts::TAU;

#[test]
fn wave_field_is_the_documented_sum_of_components() {
    let field = ok("WaveField::new", || WaveField::new(&spec(), 42));
    let comps = field.components();
    assert_eq!(comps.len(), mmusv_core::ocean::DEFAULT_COMPONENTS);
    let g = mmusv_core::ocean::GRAVITY;
    for c in comps {
        assert!(close(c.k_rad_m, c.omega_rad_s * c.omega_rad_s / g, 1e-12), "deep water k = ω²/g");
        assert!(close(c.kx, c.k_rad_m * c.direction_rad.cos(), 1e-12));
        assert!(close(c.ky, c.k_rad_m * c.direction_rad.sin(), 1e-12));
        assert!((0.0..TAU).contains(&c.phase_rad));
        assert!(c.amplitude_m > 0.0);
    }
    assert!(comps.windows(2).all(|w| w[0].omega_rad_s < w[1].omega_rad_s), "increasing frequency");
    // Variance m0 = Hs²/16 exactly.
    let var: f64 = comps.iter().map(|c| c.amplitude_m * c.amplitude_m / 2.0).sum();
    assert!(close(var, 2.0 * 2.0 / 16.0, 1e-9), "{var}");
    assert!(close(field.max_elevation(), comps.iter().map(|c| c.amplitude_m).sum(), 1e-12));
    // η, ∇η, ∂η/∂t and the orbital velocity against the written-out formulas.
    let mut rng = Lcg(3);
    for _ in 0..50 {
        let (x, y, t) = (rng.range(-500.0, 500.0), rng.range(-500.0, 500.0), rng.range(0.0, 3600.0));
        let z = rng.range(-20.0, 0.0);
        let psi = |c: &mmusv_core::ocean::WaveComponent| {
            c.k_rad_m * (x * c.direction_rad.cos() + y * c.direction_rad.sin()) - c.omega_rad_s * t + c.phase_rad
        };
        let eta: f64 = comps.iter().map(|c| c.amplitude_m * psi(c).cos()).sum();
        let sx: f64 =
            -comps.iter().map(|c| c.amplitude_m * c.k_rad_m * c.direction_rad.cos() * psi(c).sin()).sum::<f64>();
        let sy: f64 =
            -comps.iter().map(|c| c.amplitude_m * c.k_rad_m * c.direction_rad.sin() * psi(c).sin()).sum::<f64>();
        let rate: f64 = comps.iter().map(|c| c.amplitude_m * c.omega_rad_s * psi(c).sin()).sum();
        let e = |c: &mmusv_core::ocean::WaveComponent| c.amplitude_m * c.omega_rad_s * (c.k_rad_m * z).exp();
        let u: f64 = comps.iter().map(|c| e(c) * psi(c).cos() * c.direction_rad.cos()).sum();
        let v: f64 = comps.iter().map(|c| e(c) * psi(c).cos() * c.direction_rad.sin()).sum();
        let wv: f64 = comps.iter().map(|c| e(c) * psi(c).sin()).sum();
        assert!((field.elevation(x, y, t) - eta).abs() < 1e-9);
        assert!(field.elevation(x, y, t).abs() <= field.max_elevation());
        let s = field.slope(x, y, t);
        assert!((s[0] - sx).abs() < 1e-9 && (s[1] - sy).abs() < 1e-9);
        assert!(s[0].hypot(s[1]) <= field.max_slope());
        assert!((field.elevation_rate(x, y, t) - rate).abs() < 1e-9);
        let vel = field.orbital_velocity(x, y, z, t);
        assert!((vel[0] - u).abs() < 1e-9 && (vel[1] - v).abs() < 1e-9 && (vel[2] - wv).abs() < 1e-9);
        // Above the mean level: the velocities at z = 0.
        assert_eq!(field.orbital_velocity(x, y, 3.0, t), field.orbital_velocity(x, y, 0.0, t));
        // Slope against a central difference of the elevation.
        let h = 1e-4;
        let fd = (field.elevation(x + h, y, t) - field.elevation(x - h, y, t)) / (2.0 * h);
        assert!((fd - s[0]).abs() < 1e-5);
    }
    // The grid: entry j·nx + i is η(x0 + i·dx, y0 + j·dx, t), f32.
    let (nx, ny, dx) = (7usize, 5usize, 3.5);
    let grid = ok("elevation_grid", || field.elevation_grid(-10.0, 20.0, dx, nx, ny, 12.5));
    assert_eq!(grid.len(), nx * ny);
    let (e, gx, gy) = ok("elevation_slope_grid", || field.elevation_slope_grid(-10.0, 20.0, dx, nx, ny, 12.5));
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (-10.0 + i as f64 * dx, 20.0 + j as f64 * dx);
            assert!((f64::from(grid[j * nx + i]) - field.elevation(x, y, 12.5)).abs() < 1e-4);
            assert_eq!(grid[j * nx + i], e[j * nx + i]);
            let s = field.slope(x, y, 12.5);
            assert!((f64::from(gx[j * nx + i]) - s[0]).abs() < 1e-5 && (f64::from(gy[j * nx + i]) - s[1]).abs() < 1e-5);
        }
    }
    // Deterministic in the seed; a flat sea has no components.
    let again = ok("again", || WaveField::new(&spec(), 42));
    assert_eq!(again.components(), comps);
    let flat = ok("flat", || WaveField::new(&SeaSpec { hs: 0.0, ..spec() }, 1));
    assert!(flat.components().is_empty() && flat.elevation(1.0, 2.0, 3.0) == 0.0);
}

#[test]
fn wave_field_refuses_bad_parameters() {
    let s = spec();
    let cases: Vec<(&str, SeaSpec, &str)> = vec![
        ("hs NaN", SeaSpec { hs: f64::NAN, ..s }, "hs_m"),
        ("hs < 0", SeaSpec { hs: -1.0, ..s }, "hs_m"),
        ("hs 26", SeaSpec { hs: 26.0, tp: 30.0, ..s }, "hs_m"),
        ("hs inf", SeaSpec { hs: f64::INFINITY, ..s }, "hs_m"),
        ("too steep", SeaSpec { hs: 10.0, tp: 3.0, ..s }, "hs_m"),
        ("tp 0", SeaSpec { tp: 0.0, ..s }, "tp_s"),
        ("tp NaN", SeaSpec { tp: f64::NAN, ..s }, "tp_s"),
        ("tp 100", SeaSpec { tp: 100.0, ..s }, "tp_s"),
        ("gamma 0.5", SeaSpec { gamma: 0.5, ..s }, "gamma"),
        ("gamma NaN", SeaSpec { gamma: f64::NAN, ..s }, "gamma"),
        ("gamma 8", SeaSpec { gamma: 8.0, ..s }, "gamma"),
        ("direction inf", SeaSpec { direction_rad: f64::INFINITY, ..s }, "direction_rad"),
        ("spread 0", SeaSpec { spread_s: 0.0, ..s }, "spread_s"),
        ("spread NaN", SeaSpec { spread_s: f64::NAN, ..s }, "spread_s"),
        ("spread 1000", SeaSpec { spread_s: 1000.0, ..s }, "spread_s"),
    ];
    for (what, spec, field) in cases {
        refuses(what, field, || WaveField::new(&spec, 1));
        refuses(what, field, || spec.validate());
    }
    for n in [0usize, 7, 12, 4104, usize::MAX] {
        refuses(&format!("{n} components"), "components", || WaveField::with_components(&s, 1, n));
    }
    let field = ok("field", || WaveField::with_components(&s, 1, 16));
    refuses("grid dx 0", "dx", || field.elevation_grid(0.0, 0.0, 0.0, 4, 4, 0.0));
    refuses("grid dx < 0", "dx", || field.elevation_grid(0.0, 0.0, -1.0, 4, 4, 0.0));
    refuses("grid dx NaN", "dx", || field.elevation_grid(0.0, 0.0, f64::NAN, 4, 4, 0.0));
    refuses("grid x0 inf", "x0", || field.elevation_grid(f64::INFINITY, 0.0, 1.0, 4, 4, 0.0));
    refuses("grid y0 NaN", "y0", || field.elevation_grid(0.0, f64::NAN, 1.0, 4, 4, 0.0));
    refuses("grid t NaN", "t", || field.elevation_slope_grid(0.0, 0.0, 1.0, 4, 4, f64::NAN));
    // An empty grid is empty.
    assert!(ok("0 × 4 grid", || field.elevation_grid(0.0, 0.0, 1.0, 0, 4, 0.0)).is_empty());
    assert!(ok("4 × 0 grid", || field.elevation_grid(0.0, 0.0, 1.0, 4, 0, 0.0)).is_empty());
}

#[test]
fn wave_grid_refuses_sizes_whose_product_overflows() {
    // nx · ny overflows usize (here it wraps to 1): an error naming the size, not a panic or a huge allocation.
    let field = ok("field", || WaveField::with_components(&spec(), 1, 16));
    refuses("grid usize::MAX × usize::MAX", "nx", || field.elevation_grid(0.0, 0.0, 1.0, usize::MAX, usize::MAX, 0.0));
    refuses("grid 2^33 × 2^33", "nx", || field.elevation_grid(0.0, 0.0, 1.0, 1 << 33, 1 << 33, 0.0));
}

#[test]
fn orbital_velocity_refuses_to_read_a_nan_depth_as_the_surface() {
    // `z.min(0.0)` turns a NaN depth into 0: the surface velocity comes back for a point that is not one.
    let field = ok("field", || WaveField::with_components(&spec(), 1, 16));
    let v = guarded("orbital_velocity NaN z", || field.orbital_velocity(1.0, 2.0, f64::NAN, 3.0));
    assert!(v.iter().all(|c| c.is_nan()), "a NaN depth must not give a velocity: {v:?}");
}
