//! Unit tests of the parent module (`field.rs`).

use super::*;

fn ok<T>(r: Result<T>) -> T {
    r.unwrap_or_else(|e| unreachable!("{e}"))
}

fn spec(hs: f64, tp: f64, gamma: f64, s: f64) -> SeaSpec {
    SeaSpec { hs, tp, gamma, direction_rad: 0.6, spread_s: s }
}

/// Periodogram of a real series at the Fourier frequencies `ω_j = 2πj/T` in `[omega_min, omega_max]`, by
/// direct DFT (Hann window, a rotating phasor per bin; scaled so that the bins sum to the variance):
/// `(ω_j, energy_j)`.
fn periodogram(x: &[f64], dt: f64, omega_min: f64, omega_max: f64) -> Vec<(f64, f64)> {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n as f64;
    let w: Vec<f64> = (0..n).map(|i| 0.5 - 0.5 * (TAU * i as f64 / n as f64).cos()).collect();
    let w2 = w.iter().map(|v| v * v).sum::<f64>();
    let xw: Vec<f64> = x.iter().zip(&w).map(|(v, wi)| (v - mean) * wi).collect();
    let t_total = n as f64 * dt;
    let j0 = (omega_min * t_total / TAU).ceil().max(1.0) as usize;
    let j1 = (omega_max * t_total / TAU) as usize;
    (j0..=j1)
        .into_par_iter()
        .map(|j| {
            let om = TAU * j as f64 / t_total;
            let (rs, rc) = (om * dt).sin_cos();
            let (mut pr, mut pi) = (1.0, 0.0);
            let (mut re, mut im) = (0.0, 0.0);
            for &v in &xw {
                re += v * pr;
                im += v * pi;
                let t = pr * rc - pi * rs;
                pi = pr * rs + pi * rc;
                pr = t;
            }
            (om, 2.0 * (re * re + im * im) / (w2 * n as f64))
        })
        .collect()
}

/// Peak of `Σ eᵢ K(ω − ωᵢ)`, `K` Gaussian of width `bw`, on a grid of `ω`.
fn smoothed_peak(bins: &[(f64, f64)], lo: f64, hi: f64, bw: f64) -> f64 {
    let mut best = (0.0, lo);
    for g in 0..2000 {
        let om = lo + (hi - lo) * g as f64 / 1999.0;
        let d: f64 = bins.iter().map(|&(w, e)| e * (-(om - w).powi(2) / (2.0 * bw * bw)).exp()).sum();
        if d > best.0 {
            best = (d, om);
        }
    }
    best.1
}

#[test]
fn derivatives_agree_with_finite_differences_and_continuity() {
    let f = ok(WaveField::new(&spec(2.0, 7.0, 3.3, 4.0), 5));
    let h = 1e-4;
    for k in 0..20 {
        let (x, y, t) = (13.0 * k as f64 - 40.0, 7.0 * k as f64, 3.1 * k as f64);
        let s = f.slope(x, y, t);
        let fx = (f.elevation(x + h, y, t) - f.elevation(x - h, y, t)) / (2.0 * h);
        let fy = (f.elevation(x, y + h, t) - f.elevation(x, y - h, t)) / (2.0 * h);
        let ft = (f.elevation(x, y, t + h) - f.elevation(x, y, t - h)) / (2.0 * h);
        assert!((s[0] - fx).abs() < 1e-6 && (s[1] - fy).abs() < 1e-6);
        // Kinematic surface condition (linear): w(z = 0) = ∂η/∂t.
        assert!((f.orbital_velocity(x, y, 0.0, t)[2] - ft).abs() < 1e-6);
        assert!((f.elevation_rate(x, y, t) - ft).abs() < 1e-6);
        // Incompressible: ∂u/∂x + ∂v/∂y + ∂w/∂z = 0 below the surface.
        let z = -1.5;
        let du = (f.orbital_velocity(x + h, y, z, t)[0] - f.orbital_velocity(x - h, y, z, t)[0]) / (2.0 * h);
        let dv = (f.orbital_velocity(x, y + h, z, t)[1] - f.orbital_velocity(x, y - h, z, t)[1]) / (2.0 * h);
        let dw = (f.orbital_velocity(x, y, z + h, t)[2] - f.orbital_velocity(x, y, z - h, t)[2]) / (2.0 * h);
        assert!((du + dv + dw).abs() < 1e-6, "divergence {}", du + dv + dw);
    }
}

#[test]
fn grids_match_pointwise_evaluation() {
    let f = ok(WaveField::new(&spec(3.5, 9.0, 3.3, 10.0), 11));
    let (x0, y0, dx, nx, ny, t) = (-300.0, 120.0, 0.75, 400, 5, 42.0);
    let g = ok(f.elevation_grid(x0, y0, dx, nx, ny, t));
    let (e, gx, gy) = ok(f.elevation_slope_grid(x0, y0, dx, nx, ny, t));
    assert_eq!(g, e);
    for j in 0..ny {
        for i in (0..nx).step_by(7) {
            let (x, y) = (x0 + i as f64 * dx, y0 + j as f64 * dx);
            let idx = j * nx + i;
            assert!((f64::from(g[idx]) - f.elevation(x, y, t)).abs() < 1e-5);
            let s = f.slope(x, y, t);
            assert!((f64::from(gx[idx]) - s[0]).abs() < 1e-5 && (f64::from(gy[idx]) - s[1]).abs() < 1e-5);
        }
    }
    assert!(matches!(f.elevation_grid(0.0, 0.0, 0.0, 2, 2, 0.0), Err(MmusvError::InvalidInput { .. })));
}

#[test]
fn same_seed_same_sea_and_bound_holds() {
    let sp = spec(2.5, 8.0, 3.3, 5.0);
    let (a, b, c) = (ok(WaveField::new(&sp, 9)), ok(WaveField::new(&sp, 9)), ok(WaveField::new(&sp, 10)));
    let bits = |f: &WaveField| (0..200).map(|k| f.elevation(k as f64, 0.5, 0.3).to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b));
    assert_ne!(bits(&a), bits(&c));
    let g = ok(a.elevation_grid(-500.0, -500.0, 2.0, 500, 500, 17.0));
    let peak = g.iter().fold(0f32, |m, v| m.max(v.abs()));
    assert!(f64::from(peak) <= a.max_elevation() && a.max_elevation() > 0.0);
    // Frequencies strictly increase: no two components share one.
    assert!(a.components().windows(2).all(|w| w[1].omega_rad_s > w[0].omega_rad_s));
    let flat = ok(WaveField::new(&spec(0.0, 8.0, 1.0, 5.0), 1));
    assert_eq!((flat.elevation(3.0, 4.0, 5.0), flat.max_elevation()), (0.0, 0.0));
}

#[test]
fn point_time_series_gives_hs_and_tp_within_five_percent() {
    for (gamma, seed) in [(3.3, 1), (3.3, 2), (3.3, 3), (2.0, 4), (5.0, 5)] {
        let sp = spec(2.5, 8.0, gamma, 6.0);
        let f = ok(WaveField::new(&sp, seed));
        // 20 000 s, 2 500 peak periods: long enough to resolve neighbouring components near the peak.
        let dt = 1.0;
        let series: Vec<f64> = (0..20_000).into_par_iter().map(|i| f.elevation(31.0, -12.0, i as f64 * dt)).collect();
        let mean = series.iter().sum::<f64>() / series.len() as f64;
        let var = series.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / series.len() as f64;
        let hs = 4.0 * var.sqrt();
        let wp = TAU / sp.tp;
        let bins = periodogram(&series, dt, 0.4 * wp, 2.5 * wp);
        let tp = TAU / smoothed_peak(&bins, 0.5 * wp, 2.0 * wp, 0.04 * wp);
        eprintln!(
            "time series γ={gamma} seed {seed}: Hs {hs:.3} m ({:+.2} %), Tp {tp:.3} s ({:+.2} %)",
            100.0 * (hs / sp.hs - 1.0),
            100.0 * (tp / sp.tp - 1.0)
        );
        assert!((hs / sp.hs - 1.0).abs() < 0.05 && (tp / sp.tp - 1.0).abs() < 0.05);
    }
}

/// Energy per Fourier wave vector of a Hann-windowed `n × n` snapshot (spacing `dx`), by a separable direct
/// DFT over the half plane `ky ≥ 0`, `|kx|, ky ≤ kmax`: `(kx, ky, energy)`.
fn wavenumber_periodogram(g: &[f32], n: usize, dx: f64, kmax: f64) -> Vec<(f64, f64, f64)> {
    let l = n as f64 * dx;
    let jm = (kmax * l / TAU) as i64;
    let w: Vec<f64> = (0..n).map(|i| 0.5 - 0.5 * (TAU * i as f64 / n as f64).cos()).collect();
    let mean = g.iter().map(|&v| f64::from(v)).sum::<f64>() / g.len() as f64;
    // Along x for every row.
    let kxs: Vec<i64> = (-jm..=jm).collect();
    let rows: Vec<Vec<(f64, f64)>> = (0..n)
        .into_par_iter()
        .map(|r| {
            kxs.iter()
                .map(|&jx| {
                    let kx = TAU * jx as f64 / l;
                    let (mut re, mut im) = (0.0, 0.0);
                    for i in 0..n {
                        let v = (f64::from(g[r * n + i]) - mean) * w[i] * w[r];
                        let (s, c) = (kx * i as f64 * dx).sin_cos();
                        re += v * c;
                        im -= v * s;
                    }
                    (re, im)
                })
                .collect()
        })
        .collect();
    let mut out = Vec::new();
    for (ix, &jx) in kxs.iter().enumerate() {
        for jy in 0..=jm {
            if jy == 0 && jx <= 0 {
                continue;
            }
            let ky = TAU * jy as f64 / l;
            let (mut re, mut im) = (0.0, 0.0);
            for (r, row) in rows.iter().enumerate() {
                let (s, c) = (ky * r as f64 * dx).sin_cos();
                let (a, b) = row[ix];
                re += a * c + b * s;
                im += b * c - a * s;
            }
            out.push((TAU * jx as f64 / l, ky, re * re + im * im));
        }
    }
    out
}

#[test]
fn spatial_snapshot_gives_hs_tp_and_spread() {
    for (s, seed) in [(2.0, 21), (10.0, 22)] {
        let sp = spec(3.0, 8.0, 3.3, s);
        let f = ok(WaveField::new(&sp, seed));
        let lp = sp.peak_wavelength();
        let (n, dx) = (384, lp / 16.0);
        let g = ok(f.elevation_grid(-1000.0, 500.0, dx, n, n, 123.0));
        let mean = g.iter().map(|&v| f64::from(v)).sum::<f64>() / g.len() as f64;
        let var = g.iter().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / g.len() as f64;
        let hs = 4.0 * var.sqrt();
        let kp = TAU / lp;
        let spec2 = wavenumber_periodogram(&g, n, dx, 3.0 * kp);
        // Omnidirectional frequency spectrum: energy of each wave vector at ω = √(g|k|).
        let bins: Vec<(f64, f64)> = spec2.iter().map(|&(kx, ky, e)| ((GRAVITY * kx.hypot(ky)).sqrt(), e)).collect();
        let wp = TAU / sp.tp;
        let tp = TAU / smoothed_peak(&bins, 0.5 * wp, 2.0 * wp, 0.04 * wp);
        // Second circular moment of the energy about the mean direction (the snapshot cannot tell θ from θ+π).
        let (mut c2, mut tot) = (0.0, 0.0);
        for &(kx, ky, e) in &spec2 {
            let k = kx.hypot(ky);
            if k > 0.4 * kp && k < 2.5 * kp {
                c2 += e * (2.0 * (ky.atan2(kx) - sp.direction_rad)).cos();
                tot += e;
            }
        }
        let s_est = CosTwoS::s_from_mean_cos2(c2 / tot);
        eprintln!(
            "snapshot s={s}: Hs {hs:.3} ({:+.2} %), Tp {tp:.3} ({:+.2} %), s {s_est:.2} ({:+.1} %)",
            100.0 * (hs / sp.hs - 1.0),
            100.0 * (tp / sp.tp - 1.0),
            100.0 * (s_est / s - 1.0)
        );
        assert!((hs / sp.hs - 1.0).abs() < 0.05);
        assert!((tp / sp.tp - 1.0).abs() < 0.05);
        assert!((s_est / s - 1.0).abs() < 0.10);
    }
}

#[test]
fn component_directions_follow_the_spreading() {
    for (s, seed) in [(1.0, 31), (4.0, 32), (10.0, 33), (40.0, 34)] {
        let sp = spec(2.0, 7.0, 3.3, s);
        let f = ok(WaveField::new(&sp, seed));
        let (mut c, mut sn, mut tot) = (0.0, 0.0, 0.0);
        for comp in f.components() {
            let e = comp.amplitude_m.powi(2);
            c += e * (comp.direction_rad - sp.direction_rad).cos();
            sn += e * (comp.direction_rad - sp.direction_rad).sin();
            tot += e;
        }
        let r = c.hypot(sn) / tot;
        let s_est = CosTwoS::s_from_mean_cos(r);
        eprintln!("components s={s}: estimate {s_est:.2} ({:+.1} %)", 100.0 * (s_est / s - 1.0));
        assert!((s_est / s - 1.0).abs() < 0.10, "s={s}: {s_est}");
        assert!((sn / tot).abs() < 0.05 * r.max(0.1) + 0.02, "mean direction off: {}", sn / tot);
        let var: f64 = f.components().iter().map(|c| c.amplitude_m.powi(2) / 2.0).sum();
        assert!((4.0 * var.sqrt() / sp.hs - 1.0).abs() < 1e-12);
    }
}

#[test]
fn bad_specs_name_their_field() {
    let good = spec(2.0, 8.0, 3.3, 5.0);
    for (bad, field) in [
        (SeaSpec { hs: -1.0, ..good }, "hs_m"),
        (SeaSpec { hs: 30.0, ..good }, "hs_m"),
        (SeaSpec { tp: 0.1, ..good }, "tp_s"),
        (SeaSpec { gamma: 9.0, ..good }, "gamma"),
        (SeaSpec { direction_rad: f64::NAN, ..good }, "direction_rad"),
        (SeaSpec { spread_s: 0.0, ..good }, "spread_s"),
        (SeaSpec { hs: 5.0, tp: 3.0, ..good }, "hs_m"),
    ] {
        match WaveField::new(&bad, 1) {
            Err(MmusvError::Config { field: f, reason, .. }) => assert_eq!(f, field, "{reason}"),
            other => unreachable!("{bad:?}: {other:?}"),
        }
    }
    assert!(matches!(WaveField::with_components(&good, 1, 2), Err(MmusvError::Config { .. })));
}
