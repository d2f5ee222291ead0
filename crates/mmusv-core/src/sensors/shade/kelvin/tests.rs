//! Checks of the Kelvin waves against the model's own wave integral (summed numerically), its closed forms
//! (Kelvin's angle, the transverse wavelength `2π U²/g`, the decay laws) and finite differences.

use super::*;

/// A 20 m craft at 8 m/s (Froude number 0.57), 100 m³, heading +x from the origin, its path straight.
fn craft() -> Wake {
    Wake {
        x: 0.0,
        y: 0.0,
        heading: 0.0,
        speed: 8.0,
        length: 20.0,
        beam: 6.0,
        reach_m: f32::INFINITY,
        age_s: 0.0,
        displacement_m3: 100.0,
        goes_on: false,
    }
}

/// The wave integral the stationary phase approximates, summed numerically over `θ`:
/// `Re[i (V k₀²/π) ∫ sec⁴θ G(θ) exp(i ψ(θ)) dθ]` over the directions with `cos(θ − α) > 0`.
fn integral(w: &Wake, behind: f64, port: f64) -> f64 {
    let u = f64::from(w.speed);
    let k0 = G / (u * u);
    let (sx2, sy2) = ((f64::from(w.length) / 4.0).powi(2), (f64::from(w.beam) / 4.0).powi(2));
    let r = behind.hypot(port);
    let alpha = port.atan2(behind);
    let n = 400_000;
    let (lo, hi) = (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
    let h = (hi - lo) / f64::from(n);
    let mut im = 0.0;
    for i in 0..n {
        let th = lo + (f64::from(i) + 0.5) * h;
        let cd = (th - alpha).cos();
        if cd <= 0.0 {
            continue;
        }
        let sec2 = 1.0 / th.cos().powi(2);
        let k = k0 * sec2;
        let e = k * k * (sx2 * th.cos().powi(2) + sy2 * th.sin().powi(2)) / 2.0;
        if e > 60.0 {
            continue;
        }
        let amp = sec2 * sec2 * (-e).exp();
        im += amp * (k0 * r * cd * sec2).sin() * h;
    }
    // Re[i e^{iψ}] = −sin ψ.
    -f64::from(w.displacement_m3) * k0 * k0 / std::f64::consts::PI * im
}

fn field(w: Wake) -> KelvinWaves {
    KelvinWaves::new(&[w])
}

#[test]
fn phase_derivatives_match_finite_differences() {
    let f = |th: f64, a: f64| (th - a).cos() / th.cos().powi(2);
    for (th, a) in [(0.3f64, 0.1f64), (-0.9, 0.25), (1.2, -0.3), (0.0, 0.0)] {
        let [f0, f1, f2, f3] = phase_derivatives(f64::tan(th), a.cos(), a.sin());
        let h = 1e-5;
        let d1 = (f(th + h, a) - f(th - h, a)) / (2.0 * h);
        let h = 1e-4;
        let d2 = (f(th + h, a) - 2.0 * f(th, a) + f(th - h, a)) / (h * h);
        let h = 1e-3;
        let d3 =
            (f(th + 2.0 * h, a) - 2.0 * f(th + h, a) + 2.0 * f(th - h, a) - f(th - 2.0 * h, a)) / (2.0 * h * h * h);
        assert!((f0 - f(th, a)).abs() < 1e-12);
        assert!((f1 - d1).abs() < 1e-6 * (1.0 + d1.abs()), "f' {f1} {d1}");
        assert!((f2 - d2).abs() < 1e-5 * (1.0 + d2.abs()), "f'' {f2} {d2}");
        assert!((f3 - d3).abs() < 1e-3 * (1.0 + d3.abs()), "f''' {f3} {d3}");
    }
}

#[test]
fn two_stationary_waves_inside_kelvins_angle_and_none_beyond() {
    let k = field(craft());
    let deg = |d: f64| d.to_radians();
    for a in [1.0, 5.0, 10.0, 15.0, 19.0] {
        let (b, p) = (300.0 * deg(a).cos(), 300.0 * deg(a).sin());
        let waves = k.waves_at(b, p);
        // Near the track the divergent wave is so short (k₀ sec²θ) that the hull does not make it.
        assert_eq!(waves.len(), if a < 6.0 { 1 } else { 2 }, "{a}°");
        // Each is stationary: ψ'(θ) = 0, so its wavefronts are the pattern's (∇Φ = k (cos θ, sin θ)).
        for w in &waves {
            let t = w.dir[1] / w.dir[0];
            let [_, f1, _, _] = phase_derivatives(t, deg(a).cos(), deg(a).sin());
            assert!(f1.abs() < 1e-9, "{a}° f' = {f1}");
            // k = k₀ sec²θ: the waves move with the vessel.
            let k0 = G / 64.0;
            assert!((w.k - k0 * (1.0 + t * t)).abs() < 1e-12);
        }
        // The transverse wave turns less than 35.26° (where the two meet on the cusp), the divergent one more.
        let cusp = (1.0f64 / 2.0f64.sqrt()).atan();
        assert!(waves[0].dir[1].atan2(waves[0].dir[0]).abs() < cusp);
        if waves.len() > 1 {
            assert!(waves[1].dir[1].atan2(waves[1].dir[0]).abs() > cusp);
        }
    }
    // Beyond Kelvin's angle only the Airy tail: one wave, decaying fast.
    let on = k.waves_at(300.0 * deg(19.4).cos(), 300.0 * deg(19.4).sin());
    let beyond = k.waves_at(300.0 * deg(21.0).cos(), 300.0 * deg(21.0).sin());
    let far = k.waves_at(300.0 * deg(26.0).cos(), 300.0 * deg(26.0).sin());
    assert_eq!(beyond.len(), 1);
    let sum = |w: &[KelvinWave]| w.iter().map(|w| w.amplitude).sum::<f64>();
    assert!(sum(&beyond) < 0.5 * sum(&on), "{} {}", sum(&beyond), sum(&on));
    assert!(sum(&far) < 0.05 * sum(&on), "{} {}", sum(&far), sum(&on));
    // Ahead of the centre, nothing.
    assert!(k.waves_at(-10.0, 1.0).is_empty());
}

#[test]
fn the_pattern_matches_the_wave_integral_inside_on_and_beyond_the_cusps() {
    let w = craft();
    let k = field(w);
    // Inside (stationary phase's ground), near the cusps (the caustic) and beyond Kelvin's angle (the Airy tail),
    // 300–450 m behind (k₀ r = 46–69): every point within 8 % of the largest elevation along that ray.
    let mut cusp_scale = 0.0f64;
    for a in [2.0f64, 6.0, 11.0, 15.0, 18.0, 19.47, 20.5, 22.0] {
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for i in 0..24 {
            let r = 300.0 + f64::from(i) * 6.3;
            let (b, p) = (r * a.to_radians().cos(), r * a.to_radians().sin());
            let ours = k.local_elevation(b, p);
            let exact = integral(&w, b, p);
            worst = worst.max((ours - exact).abs());
            scale = scale.max(exact.abs());
        }
        assert!(scale > 0.01, "{a}°: the pattern is there: {scale} m");
        if a > 19.0 && a < 19.5 {
            cusp_scale = scale;
        }
        // Beyond the cusp line the tail is the cubic expansion at the cusp angle alone, rougher: within 15 % of the
        // cusp line's largest elevation there (the tail's own is 30–70 % of it).
        let limit = if a > 19.5 { 0.15 * cusp_scale } else { 0.08 * scale };
        assert!(worst < limit, "{a}°: worst {worst} m of {scale} m");
    }
}

#[test]
fn transverse_waves_along_the_track_are_2_pi_u2_over_g_long() {
    let w = craft();
    let k = field(w);
    // Zero crossings of the elevation along the track between 300 and 600 m behind: half a wavelength apart.
    let (mut last, mut crossings) = (k.elevation(-300.0, 0.0), Vec::new());
    let mut x = 300.0;
    while x < 600.0 {
        x += 0.01;
        let z = k.elevation(-x, 0.0);
        if (z > 0.0) != (last > 0.0) {
            crossings.push(x);
        }
        last = z;
    }
    let lambda = 2.0 * std::f64::consts::PI * 64.0 / G;
    let mean = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    assert!((2.0 * mean - lambda).abs() < 0.005 * lambda, "{} vs {lambda}", 2.0 * mean);
}

#[test]
fn amplitudes_decay_as_r_to_the_minus_half_inside_and_minus_third_on_the_cusp() {
    let k = field(craft());
    let amp = |r: f64, a: f64| -> f64 {
        let w = k.waves_at(r * a.cos(), r * a.sin());
        w.iter().map(|w| w.amplitude).sum()
    };
    // Near the track (3°, where only the transverse wave is made) and on the cusp line.
    let a = 3f64.to_radians();
    let ratio = amp(4000.0, a) / amp(1000.0, a);
    assert!((ratio - 0.5).abs() < 0.02, "inside: {ratio} (4^-1/2 = 0.5)");
    let cusp = TAN_KELVIN.atan();
    let ratio = amp(4000.0, cusp) / amp(1000.0, cusp);
    let want = 4f64.powf(-1.0 / 3.0);
    assert!((ratio - want).abs() < 0.02, "cusp: {ratio} ({want})");
}

#[test]
fn slopes_are_the_gradient_of_the_elevation() {
    let k = field(craft());
    // Points behind the vessel (it heads +x, k₀ r = 40–80): inside the wedge, near and on the cusp lines (the
    // caustic) and in the tail beyond. Within the cusps the slope leaves out the amplitudes' variation, small
    // against the phases' over a wavelength.
    let mut worst = 0.0f64;
    let mut largest = 0.0f64;
    for i in 0..120 {
        let a = (-23.0 + 46.0 * f64::from(i) / 119.0).to_radians();
        for r in [260.0, 390.0, 520.0] {
            let (x, y) = (-r * a.cos(), r * a.sin());
            let s = k.slope(x as f32, y as f32, 0.0);
            let h = 0.005;
            let gx = (k.elevation(x + h, y) - k.elevation(x - h, y)) / (2.0 * h);
            let gy = (k.elevation(x, y + h) - k.elevation(x, y - h)) / (2.0 * h);
            let e = (f64::from(s.slope[0]) - gx).hypot(f64::from(s.slope[1]) - gy);
            worst = worst.max(e);
            largest = largest.max(gx.hypot(gy));
            assert_eq!(s.unresolved_mss, 0.0);
        }
    }
    assert!(largest > 0.02, "slopes to compare: {largest}");
    assert!(worst < 0.1 * largest, "worst {worst} of {largest}");
}

#[test]
fn waves_a_pixel_cannot_resolve_become_roughness() {
    let k = field(craft());
    let (x, y) = (-300.0f32, 40.0f32);
    let sharp = k.slope(x, y, 0.0);
    let blurred = k.slope(x, y, 30.0); // a footprint of 30 m: every wave here is shorter than four of them
    assert_eq!(blurred.slope, [0.0, 0.0]);
    assert!(blurred.unresolved_mss > 0.0);
    // The roughness is the slopes' mean square: (A k)²/2 per wave.
    let waves = k.waves_at(300.0, 40.0);
    let fade = 1.0 - (-(300.0f64 / 20.0).powi(2)).exp();
    let want: f64 = waves.iter().map(|w| 0.5 * (w.amplitude * fade * w.k).powi(2)).sum();
    assert!((f64::from(blurred.unresolved_mss) - want).abs() < 1e-4 * want);
    assert!(sharp.slope != [0.0, 0.0]);
}

#[test]
fn no_waves_ahead_past_the_reach_or_without_a_displacement() {
    let w = craft();
    let k = field(w);
    assert_eq!(k.slope(50.0, 0.0, 0.0).slope, [0.0, 0.0]); // ahead
    let short = field(Wake { reach_m: 100.0, ..w });
    assert_eq!(short.slope(-150.0, 10.0, 0.0).slope, [0.0, 0.0]); // past where the path ran straight
    assert!(short.slope(-60.0, 5.0, 0.0).slope != [0.0, 0.0]);
    assert!(field(Wake { displacement_m3: 0.0, ..w }).is_empty());
    assert!(field(Wake { age_s: 3.0, ..w }).is_empty()); // an older piece of a bent path: its foam only
    assert!(field(Wake { speed: 0.2, ..w }).is_empty());
    // Turned: the same pattern about the new heading.
    let turned = field(Wake { heading: std::f32::consts::FRAC_PI_2, ..w });
    let a = k.slope(-300.0, 40.0, 0.0).slope;
    let b = turned.slope(-40.0, -300.0, 0.0).slope;
    assert!((a[0] - b[1]).abs() < 1e-4 && (a[1] + b[0]).abs() < 1e-4, "{a:?} {b:?}");
}

#[test]
fn steepness_never_passes_michells_limit() {
    let k = field(Wake { speed: 12.0, length: 12.0, beam: 4.0, displacement_m3: 40.0, ..craft() });
    for i in 0..200 {
        let x = -2.0 - f64::from(i) * 0.5;
        for y in [-3.0, -1.0, 0.0, 1.5, 4.0] {
            let s = k.slope(x as f32, y as f32, 0.0).slope;
            // At most two waves, each no steeper than a k = 0.446.
            assert!(f64::from(s[0].hypot(s[1])) <= 2.0 * MAX_STEEPNESS + 1e-6);
        }
    }
}

/// A facet of slopes `(sx, sy)` has the normal `∝ (−sx, −sy, 1)`; tilted by waves of slopes `(kx, ky)` laid over
/// it, the normal of the summed slopes. A facet that does not face up, or no slope, is kept as it is.
#[test]
fn tilting_a_facet_adds_the_slopes() {
    use parry3d::math::Vec3;
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    for _ in 0..1000 {
        let (sx, sy, kx, ky) = (next(), next(), 0.6 * next(), 0.6 * next());
        let n = Vec3::new(-sx, -sy, 1.0).normalize();
        let want = Vec3::new(-(sx + kx), -(sy + ky), 1.0).normalize();
        let got = tilted(n, [kx, ky]);
        assert!((got - want).length() < 1e-5, "{got:?} vs {want:?}");
        assert_eq!(tilted(n, [0.0, 0.0]), n);
    }
    let down = Vec3::new(0.1, 0.0, -1.0).normalize();
    assert_eq!(tilted(down, [0.2, 0.1]), down);
}
