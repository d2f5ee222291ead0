//! LiDAR returns from the displaced sea surface: quasi-specular glints from wave facets and whitecaps, detected
//! through speckle.
//!
//! Model (per beam that meets the water, `θ` the incidence angle against the *resolved* wave facet's normal,
//! so a beam meeting a wave face turned towards the sensor returns more than one grazing a back slope):
//!
//! * **Quasi-specular backscatter** of the unresolved capillary slopes, Gaussian and isotropic with total mean
//!   square slope `σ² = 0.003 + 5.12·10⁻³ U` (Cox, C. & Munk, W. (1954), "Measurement of the roughness of the sea
//!   surface from photographs of the sun's glitter", J. Opt. Soc. Am. 44(11)):
//!   `β_qs(θ) = ρ_F exp(−tan²θ / σ²) / (4π σ² cos⁴θ)` (sr⁻¹), `ρ_F` the Fresnel reflectance of water at normal
//!   incidence (Barrick, D. E. (1968), "Rough surface scattering based on the specular point theory", IEEE
//!   Trans. Antennas Propag. 16(4); in the lidar form of Bufton, J. L., Hoge, F. E. & Swift, R. N. (1983),
//!   Appl. Opt. 22(17), and Josset, D. et al. (2010), "Lidar equation for ocean surface and subsurface",
//!   Opt. Express 18(20), eq. 2).
//! * **Whitecaps**, Lambertian with reflectance `ρ_wc = 0.22` (Koepke, P. (1984), "Effective reflectance of
//!   oceanic whitecaps", Appl. Opt. 23(11)) over the fraction `W(U) = 3.84·10⁻⁶ U^3.41` (Monahan, E. C. &
//!   O'Muircheartaigh, I. (1980), J. Phys. Oceanogr. 10; the cameras' foam uses the same law):
//!   `β_wc(θ) = W ρ_wc cos θ / π`.
//!
//! * **Wake foam** where the beam meets it (the foam of [`super::shade::foam`], the cameras' own at the same
//!   point: the turbulent track and Kelvin arms behind every vessel under way, broken up by the same noise):
//!   foam of density `c` covers that fraction of the footprint with Lambertian foam of the fresh foam's albedo
//!   `ρ_f = 0.55` (Koepke 1984), so `β = (1 − c)(β_qs + β_wc) + c ρ_f cos θ / π`. Where a beam meets no wake
//!   foam (`c = 0`), `β` is the open sea's above, to the bit. Whitecaps stay the area mean `β_wc` of the
//!   calibration below; wakes are foam the sensor resolves (metres wide, tens to hundreds long), whitecaps at
//!   their coverage a fraction of every footprint's chance (`docs/sea/README.md`).
//!
//! The expected intensity of the return is the LiDAR's intensity law with the Lambertian-equivalent
//! reflectivity of `β` (a Lambertian target of reflectance ρ has `β = ρ cos θ / π`):
//! `⟨I⟩ = π β τ / (1 + (r / 100 m)²)`. The surface is rough on the scale of the wavelength, so the received
//! power is fully developed speckle, exponentially distributed about `⟨I⟩`; the return is detected when it
//! exceeds the threshold `I_d`, with probability `P_d = exp(−I_d / ⟨I⟩)` (Goodman, J. W. (1976), "Some
//! fundamental properties of speckle", J. Opt. Soc. Am. 66(11)), and its intensity is that draw: with `u` the
//! beam's uniform draw, `I = −⟨I⟩ ln u` is exponential about `⟨I⟩` and exceeds `I_d` exactly when `u < P_d`, so
//! a detected return's intensity is `I_d` plus an exponential of mean `⟨I⟩`, never below the threshold
//! ([`speckle_intensity`]). `I_d` ([`DETECTION_THRESHOLD`]) is set so
//! that a beam 20 m out over a W1 sea at 80° incidence (10° grazing) returns with the probability 0.2 of the
//! empirical rule this model replaces, with U = 8.4 m/s, the W1 sea's Pierson–Moskowitz wind at 19.5 m (at the
//! 8.2 m/s at 10 m the sensors take since 2026-11-30, `mmusv.sensors.env.wind_from_wave_height`, it is 0.17);
//! calm water (W0) then returns almost nothing, as at 905 nm it should.

use super::shade::foam::FOAM_ALBEDO;

/// Fresnel reflectance of water at normal incidence at 905 nm (n ≈ 1.328): `((n − 1)/(n + 1))²`.
pub const FRESNEL_NORMAL: f32 = 0.0199;
/// Whitecap reflectance (Koepke 1984).
pub const WHITECAP_REFLECTANCE: f32 = 0.22;
/// Detection threshold `I_d` of a water return, in the LiDAR's intensity units (see the module docs).
pub const DETECTION_THRESHOLD: f32 = 3.2e-4;

/// Cox–Munk total mean square slope of the capillary waves under wind `u` (m/s) (the cameras' roughness,
/// [`super::shade::water::cox_munk_mss`]).
#[inline]
pub fn mean_square_slope(u: f32) -> f32 {
    super::shade::water::cox_munk_mss(u)
}

/// Monahan & O'Muircheartaigh whitecap fraction under wind `u` (m/s), in `[0, 1]` (the cameras' coverage,
/// [`super::shade::water::monahan_coverage`]).
#[inline]
pub fn whitecap_fraction(u: f32) -> f32 {
    super::shade::water::monahan_coverage(u)
}

/// Backscatter coefficient `β = β_qs + β_wc` (sr⁻¹) of the sea surface at incidence `cos θ` (against the facet
/// normal) under wind `u` (m/s).
#[inline]
pub fn backscatter(cos_theta: f32, u: f32) -> f32 {
    let c = cos_theta.clamp(1e-6, 1.0);
    let s2 = mean_square_slope(u);
    let tan2 = (1.0 - c * c) / (c * c);
    let qs = FRESNEL_NORMAL * exp_or_zero(-tan2 / s2) / (4.0 * std::f32::consts::PI * s2 * c.powi(4));
    let wc = whitecap_fraction(u) * WHITECAP_REFLECTANCE * c / std::f32::consts::PI;
    qs + wc
}

/// Backscatter coefficient (sr⁻¹) where the beam meets foam of density `foam` in `[0, 1]` (a wake's; see the
/// module docs): `(1 − c) β + c ρ_f cos θ / π`, with `β` the open sea's [`backscatter`]; `foam ≤ 0` gives
/// [`backscatter`] itself, to the bit.
#[inline]
pub fn backscatter_with_foam(cos_theta: f32, u: f32, foam: f32) -> f32 {
    let b = backscatter(cos_theta, u);
    if foam <= 0.0 {
        return b;
    }
    let (c, f) = (cos_theta.clamp(1e-6, 1.0), foam.min(1.0));
    (1.0 - f) * b + f * FOAM_ALBEDO * c / std::f32::consts::PI
}

/// Expected intensity `⟨I⟩ = π β τ / (1 + (r/100)²)` of a water return at range `r` (m), two-way transmission
/// `tau`.
#[inline]
pub fn mean_intensity(cos_theta: f32, u: f32, r: f32, tau: f32) -> f32 {
    mean_intensity_with_foam(cos_theta, u, r, tau, 0.0)
}

/// [`mean_intensity`] where the beam meets foam of density `foam` ([`backscatter_with_foam`]).
#[inline]
pub fn mean_intensity_with_foam(cos_theta: f32, u: f32, r: f32, tau: f32, foam: f32) -> f32 {
    std::f32::consts::PI * backscatter_with_foam(cos_theta, u, foam) * tau / (1.0 + (r / 100.0) * (r / 100.0))
}

/// The speckle intensity of a water return of mean `mean` (`⟨I⟩`) for the beam's uniform draw `u` in `[0, 1)`:
/// `−⟨I⟩ ln u`, exponentially distributed about `⟨I⟩`, at least [`DETECTION_THRESHOLD`] whenever the draw detects
/// the return (`u < `[`detection_probability`]`(mean)`; the bound held against the rounding of the two sides).
#[inline]
pub fn speckle_intensity(mean: f32, u: f64) -> f32 {
    ((-f64::from(mean) * u.ln()) as f32).max(DETECTION_THRESHOLD)
}

/// Probability `exp(−I_d / ⟨I⟩)` that a water return is detected (0 for `⟨I⟩ = 0`).
#[inline]
pub fn detection_probability(mean: f32) -> f32 {
    if mean > 0.0 {
        exp_or_zero(-DETECTION_THRESHOLD / mean)
    } else {
        0.0
    }
}

/// `x.exp()`, with the 0 it rounds to below −104 given at once: `expf` reaches that 0 through its underflow
/// path (the error and the floating-point exception it raises), which grazing beams and far returns take every
/// time. The same bits either way (the smallest subnormal `f32` is `e^−103.28`; `e^−104` rounds to 0).
#[inline(always)]
fn exp_or_zero(x: f32) -> f32 {
    if x < -104.0 {
        0.0
    } else {
        x.exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quasi-specular term against its definition: the density of facet slopes that turn the beam back
    /// (Gaussian, isotropic, variance σ²/2 per axis) times `ρ_F / (4 cos⁴θ)`, the density estimated by counting
    /// sampled slopes in a small box around `tan θ`.
    #[test]
    fn quasi_specular_term_matches_sampled_facet_slopes() {
        let u = 9.0f32;
        let s2 = mean_square_slope(u) as f64;
        let mut state = 3u64;
        let mut gauss = || {
            // Box–Muller from a 64-bit LCG.
            let mut uni = || {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (uni(), uni());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        let n = 4_000_000;
        let sd = (s2 / 2.0).sqrt();
        let slopes: Vec<(f64, f64)> = (0..n).map(|_| (gauss() * sd, gauss() * sd)).collect();
        for theta_deg in [5.0f64, 12.0, 18.0] {
            let t = theta_deg.to_radians().tan();
            let h = 0.02;
            let inside = slopes.iter().filter(|(x, y)| (x - t).abs() < h / 2.0 && y.abs() < h / 2.0).count();
            let density = inside as f64 / n as f64 / (h * h);
            let c = theta_deg.to_radians().cos();
            let want = f64::from(FRESNEL_NORMAL) * density / (4.0 * c.powi(4));
            let got = f64::from(backscatter(c as f32, u))
                - f64::from(whitecap_fraction(u) * WHITECAP_REFLECTANCE) * c / std::f64::consts::PI;
            assert!((got / want - 1.0).abs() < 0.08, "θ = {theta_deg}°: {got} vs sampled {want}");
        }
    }

    #[test]
    fn returns_follow_incidence_and_whitecaps() {
        // Faces turned towards the beam return more; more wind (whitecaps) returns more; calm water almost none.
        let p = |cos: f32, u: f32| detection_probability(mean_intensity(cos, u, 20.0, 1.0));
        assert!(p(0.5, 8.4) > p(0.17, 8.4) && p(0.17, 8.4) > p(0.05, 8.4));
        assert!(p(0.17, 12.8) > p(0.17, 8.4));
        assert!(p(0.17, 4.8) < 1e-3, "calm water at 905 nm is a mirror: {}", p(0.17, 4.8));
        // The calibration point of the module docs.
        assert!((p((80f32).to_radians().cos(), 8.4) - 0.2).abs() < 0.03, "{}", p((80f32).to_radians().cos(), 8.4));
        // Near normal incidence the glint dominates.
        assert!(p(0.999, 8.4) > 0.99);
    }

    /// Wake foam: none is the open sea's backscatter to the bit; full foam is a Lambertian target of the fresh
    /// foam's albedo; between, the footprint's mix. At grazing, where the open sea returns almost nothing, a beam
    /// on a wake's foam returns almost always (the foam is what a LiDAR sees of a wake).
    #[test]
    fn wake_foam_is_a_lambertian_share_of_the_footprint() {
        for (cos, u) in [(0.999f32, 8.4f32), (0.5, 12.8), (0.17, 8.4), (0.02, 4.8)] {
            assert_eq!(backscatter_with_foam(cos, u, 0.0).to_bits(), backscatter(cos, u).to_bits());
            assert_eq!(
                mean_intensity_with_foam(cos, u, 37.0, 0.9, 0.0).to_bits(),
                mean_intensity(cos, u, 37.0, 0.9).to_bits()
            );
            let lambert = FOAM_ALBEDO * cos / std::f32::consts::PI;
            assert!((backscatter_with_foam(cos, u, 1.0) / lambert - 1.0).abs() < 1e-5);
            let half = 0.5 * backscatter(cos, u) + 0.5 * lambert;
            assert!((backscatter_with_foam(cos, u, 0.5) / half - 1.0).abs() < 1e-5);
            assert_eq!(
                backscatter_with_foam(cos, u, 3.0),
                backscatter_with_foam(cos, u, 1.0),
                "density is capped at 1"
            );
        }
        let p = |foam: f32| detection_probability(mean_intensity_with_foam(0.17, 4.8, 20.0, 1.0, foam));
        assert!(p(0.0) < 1e-3 && p(0.5) > 0.95, "open water {} against foam {}", p(0.0), p(0.5));
    }

    /// A detected water return's intensity is the speckle draw that passed the threshold: never below `I_d`, and
    /// `I − I_d` exponential of mean `⟨I⟩` (memoryless), its mean and its tail checked against the closed form over
    /// a million draws at three means around the threshold. Until 2026-12-01 the return carried `⟨I⟩` itself,
    /// below the threshold it had passed whenever `⟨I⟩ < I_d`.
    #[test]
    fn detected_water_returns_are_speckle_draws_above_the_threshold() {
        for mean in [0.3 * DETECTION_THRESHOLD, DETECTION_THRESHOLD, 5.0 * DETECTION_THRESHOLD] {
            let p = f64::from(detection_probability(mean));
            let (mut n, mut excess, mut tail) = (0u64, 0.0f64, 0u64);
            for i in 0..1_000_000u64 {
                let u = crate::sensors::noise::uniform(9, 3, i);
                if u >= p {
                    continue;
                }
                let x = speckle_intensity(mean, u);
                assert!(x >= DETECTION_THRESHOLD, "mean {mean}: {x} below the threshold");
                n += 1;
                let e = f64::from(x - DETECTION_THRESHOLD) / f64::from(mean);
                excess += e;
                tail += u64::from(e > 1.0);
            }
            let nf = n as f64;
            assert!((nf / 1e6 - p).abs() < 5.0 * (p * (1.0 - p) / 1e6).sqrt(), "mean {mean}: rate {}", nf / 1e6);
            assert!((excess / nf - 1.0).abs() < 5.0 / nf.sqrt(), "mean {mean}: mean excess {}", excess / nf);
            let e1 = (-1.0f64).exp();
            assert!((tail as f64 / nf - e1).abs() < 5.0 * (e1 * (1.0 - e1) / nf).sqrt(), "mean {mean}: tail");
        }
    }

    /// The shortcut to 0 gives `exp`'s own bits everywhere: across the underflow and far below it.
    #[test]
    fn exp_or_zero_is_exp() {
        let mut x = -200.0f32;
        while x < 5.0 {
            assert_eq!(exp_or_zero(x).to_bits(), x.exp().to_bits(), "x = {x}");
            x += 0.013;
        }
        for x in [-104.0f32, -103.98, -103.97, -103.28, f32::MIN, -1e30] {
            assert_eq!(exp_or_zero(x).to_bits(), x.exp().to_bits(), "x = {x}");
        }
    }
}
