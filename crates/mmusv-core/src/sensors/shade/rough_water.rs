//! The rough sea surface's reflection: the sun's glitter from it, and how much of the light arriving over its
//! reflection lobe the camera receives, for glossy reflections (`sensors/camera/glossy.rs` draws the traced
//! reflections' directions from the lobe and spreads them over the rest of it; this weighs them).
//!
//! **Model.** Microfacet reflection (K. E. Torrance & E. M. Sparrow, JOSA 57(9), 1967; B. Walter, S. R. Marschner,
//! H. Li & K. E. Torrance, "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007) with
//! * the Beckmann facet distribution `D(h) = exp(−tan²θ_h / α²) / (π α² cos⁴θ_h)`, whose slopes are Gaussian
//!   with mean square `α²` (both axes): Cox & Munk's sea slopes (C. Cox & W. Munk, JOSA 44(11), 1954; their
//!   slope distribution is Gaussian to first order);
//! * Smith's separable shadowing–masking `G = G₁(ω_o) G₁(ω_i)`, `G₁` by Walter et al.'s rational approximation
//!   (their eq. 27, within 0.35 % of the exact Beckmann `G₁`, the form Mitsuba 3 uses too);
//! * the exact Fresnel reflectance of water (IOR 1.33).
//!
//! The directional reflectance `E(μ_o, α) = ∫ F(ω_o·h) D(h) G / (4 μ_o) dω_i` over the upper hemisphere (light
//! whose mirror direction would leave below the horizon is lost, as masking also loses it) and the moments of the
//! reflected directions under that same weight — the mean elevation above the mirror direction's, the standard
//! deviations of elevation and azimuth, the lobe the glossy blur spreads the radiance over — are tabulated once
//! over `√μ_o ∈ [0, 1]` (dense at grazing views, where they change fastest) and `α ∈ [0, 1]` by a stratified
//! quadrature over the facet normals drawn from `D`, and read bilinearly. At `α → 0`, `E` is the Fresnel
//! reflectance. Away from grazing the lobe is the first-order one (elevation spread `2σ₁`, azimuth `2σ₁ tan γ`
//! at the mirror direction, `σ₁ = α/√2`); near it, the facets the camera sees lean towards it, so the lobe rises
//! (at `γ = 1°`, `α = 0.055`: mean elevation 5.8°, spread 3.0°) and `E` falls below the Fresnel reflectance.

use super::brdf::fresnel_dielectric;
use parry3d::math::Vec3;

/// Refractive index of sea water (the same as the shader's).
const IOR: f32 = 1.33;
/// Table nodes along `μ_o` and along `α` (each from 0 to 1).
const NODES: usize = 65;
/// Stratified samples per side of each table entry's quadrature.
const STRATA: usize = 32;

/// Walter et al.'s rational approximation of the Beckmann Smith `G₁` of a direction at `cos_theta` to the
/// macro normal, for roughness `alpha` (1 when the direction is grazing-free: `a ≥ 1.6`).
#[inline]
pub fn smith_g1(cos_theta: f64, alpha: f64) -> f64 {
    if cos_theta <= 0.0 {
        return 0.0;
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    if sin_theta <= 0.0 || alpha <= 0.0 {
        return 1.0;
    }
    let a = cos_theta / (alpha * sin_theta);
    if a >= 1.6 {
        1.0
    } else {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    }
}

/// Beyond this `tan²θ_h / α²` the Beckmann `D` is taken as 0: `e^−60 ≈ 10⁻²⁶`, so even the sun's glint there is
/// below 10⁻¹⁸ cd/m² (and the exponential, most pixels' case, is skipped).
const D_CUTOFF: f32 = 60.0;

/// The Beckmann distribution `D` at `cos θ_h = n_dot_h` for roughness `alpha` (0 where `tan²θ_h / α² > 60`).
#[inline(always)]
pub fn beckmann_d(n_dot_h: f32, alpha: f32) -> f32 {
    if n_dot_h <= 0.0 || alpha <= 0.0 {
        return 0.0;
    }
    let c2 = n_dot_h * n_dot_h;
    let tan2 = (1.0 - c2).max(0.0) / c2;
    let a2 = alpha * alpha;
    let x = tan2 / a2;
    if x > D_CUTOFF {
        return 0.0;
    }
    (-x).exp() / (std::f32::consts::PI * a2 * c2 * c2)
}

/// The specular reflection of light from unit direction `l` seen from `v` on water of normal `n` and roughness
/// `alpha`, times `n·l` and without the Fresnel factor: `D G / (4 n·v)` (the sun's glitter is this times its
/// irradiance and the Fresnel reflectance at the half vector).
#[inline(always)]
pub fn specular_cos(n: Vec3, v: Vec3, l: Vec3, alpha: f32) -> f32 {
    let (nl, nv) = (n.dot(l), n.dot(v));
    if nl <= 0.0 || nv <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize_or_zero();
    let d = beckmann_d(n.dot(h), alpha);
    if d == 0.0 {
        return 0.0;
    }
    let a = f64::from(alpha);
    let g = (smith_g1(f64::from(nl), a) * smith_g1(f64::from(nv), a)) as f32;
    d * g / (4.0 * nv)
}

/// A facet normal of the Beckmann distribution of roughness `alpha`, drawn from `D(m) cos θ_m` by the uniform
/// numbers `u1` (the slope's size) and `u2` (its azimuth): `tan²θ_m = −α² ln(1 − u1)`, `φ = 2π u2`.
#[inline]
pub fn beckmann_facet(alpha: f64, u1: f64, u2: f64) -> [f64; 3] {
    let tan2 = -alpha * alpha * (1.0 - u1).ln();
    let cos_m = 1.0 / (1.0 + tan2).sqrt();
    let sin_m = (1.0 - cos_m * cos_m).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * u2;
    [sin_m * phi.cos(), sin_m * phi.sin(), cos_m]
}

/// The facet normals ([`beckmann_facet`]) at the midpoints of a `strata × strata` stratified grid of `(u1, u2)`:
/// the quadratures' sample of the facets, each standing for `1 / strata²` of `D(m) cos θ_m`.
pub fn stratified_facets(alpha: f64, strata: usize) -> impl Iterator<Item = [f64; 3]> {
    let n = strata as f64;
    (0..strata)
        .flat_map(move |a| (0..strata).map(move |b| beckmann_facet(alpha, (a as f64 + 0.5) / n, (b as f64 + 0.5) / n)))
}

/// `E(μ_o, α)` by quadrature (see the module docs): facet normals drawn from the Beckmann distribution on a
/// `strata × strata` stratified grid, each weighted by `F G₁(ω_o) G₁(ω_i) (ω_o·h) / (μ_o cos θ_h)`.
pub fn reflectance_quadrature(mu_o: f64, alpha: f64, strata: usize) -> f64 {
    lobe_quadrature(mu_o, alpha, strata)[0]
}

/// `[E, Δe, σ_e, σ_a]` by quadrature: the reflectance, and under its weight the mean elevation of the reflected
/// directions above the mirror direction's (radians), their elevation's and their azimuth's standard deviations
/// (radians; azimuth about the mirror direction's).
pub fn lobe_quadrature(mu_o: f64, alpha: f64, strata: usize) -> [f64; 4] {
    let mu = mu_o.clamp(1e-4, 1.0);
    let mirror_el = mu.asin();
    if alpha <= 0.0 {
        return [f64::from(fresnel_dielectric(mu as f32, IOR)), 0.0, 0.0, 0.0];
    }
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let g_o = smith_g1(mu, alpha);
    let (mut sum, mut s_el, mut s_el2, mut s_az2) = (0.0, 0.0, 0.0, 0.0);
    for h in stratified_facets(alpha, strata) {
        let c = wo[0] * h[0] + wo[2] * h[2];
        if c <= 0.0 {
            continue;
        }
        let wi = [2.0 * c * h[0] - wo[0], 2.0 * c * h[1], 2.0 * c * h[2] - wo[2]];
        if wi[2] <= 0.0 {
            continue;
        }
        let f = f64::from(fresnel_dielectric(c as f32, IOR));
        let w = f * g_o * smith_g1(wi[2], alpha) * c / (mu * h[2]);
        // The reflected direction's elevation, and its azimuth about the mirror direction's (which is 0: the
        // mirror of ω_o lies in the x–z plane, leaving along −x).
        let el = wi[2].clamp(-1.0, 1.0).asin() - mirror_el;
        let az = wi[1].atan2(-wi[0]);
        sum += w;
        s_el += w * el;
        s_el2 += w * el * el;
        s_az2 += w * az * az;
    }
    if sum <= 0.0 {
        return [0.0; 4];
    }
    let mean = s_el / sum;
    let n = (strata * strata) as f64;
    [sum / n, mean, (s_el2 / sum - mean * mean).max(0.0).sqrt(), (s_az2 / sum).sqrt()]
}

/// The table of [`lobe_quadrature`] over `NODES × NODES` nodes (`√μ_o` fastest, then `α`), built on first use.
fn table() -> &'static [[f32; 4]] {
    static TABLE: std::sync::OnceLock<Vec<[f32; 4]>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let step = 1.0 / (NODES - 1) as f64;
        (0..NODES * NODES)
            .map(|i| {
                let u = (i % NODES) as f64 * step;
                lobe_quadrature(u * u, (i / NODES) as f64 * step, STRATA).map(|v| v as f32)
            })
            .collect()
    })
}

/// Channels `C` of the table bilinearly at `cos θ_o = mu_o`, roughness `alpha` (each clamped to `[0, 1]`).
#[inline(always)]
fn lookup<const N: usize>(mu_o: f32, alpha: f32, channels: [usize; N]) -> [f32; N] {
    let t = table();
    let last = (NODES - 1) as f32;
    let x = mu_o.clamp(0.0, 1.0).sqrt() * last;
    let y = alpha.clamp(0.0, 1.0) * last;
    let (i, j) = ((x as usize).min(NODES - 2), (y as usize).min(NODES - 2));
    let (fx, fy) = (x - i as f32, y - j as f32);
    let (a, b, c, d) = (&t[j * NODES + i], &t[j * NODES + i + 1], &t[(j + 1) * NODES + i], &t[(j + 1) * NODES + i + 1]);
    channels.map(|k| {
        let lo = a[k] + (b[k] - a[k]) * fx;
        let hi = c[k] + (d[k] - c[k]) * fx;
        lo + (hi - lo) * fy
    })
}

/// `E(μ_o, α)`: the directional reflectance of water of Beckmann roughness `alpha` seen at `cos θ_o = mu_o` from
/// its (shading) normal.
#[inline]
pub fn reflectance(mu_o: f32, alpha: f32) -> f32 {
    lookup(mu_o, alpha, [0])[0]
}

/// The reflection lobe seen at `cos θ_o = mu_o` (for a flat surface, the sine of the view's angle below the
/// horizontal) on water of roughness `alpha`: `[Δe, σ_e, σ_a]`, radians (see [`lobe_quadrature`]).
#[inline]
pub fn lobe(mu_o: f32, alpha: f32) -> [f32; 3] {
    lookup(mu_o, alpha, [1, 2, 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `[E, Δe, σ_e, σ_a]` by plain Monte Carlo over the hemisphere of incoming directions (uniform in solid
    /// angle, a seeded generator), evaluating the BRDF directly: independent of the quadrature's facet sampling.
    fn monte_carlo(mu_o: f64, alpha: f64, n: usize) -> [f64; 4] {
        let wo = [(1.0 - mu_o * mu_o).sqrt(), 0.0, mu_o];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut rand = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut sum, mut s_el, mut s_el2, mut s_az2) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let z = rand();
            let phi = std::f64::consts::TAU * rand();
            let r = (1.0 - z * z).sqrt();
            let wi = [r * phi.cos(), r * phi.sin(), z];
            let hs = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
            let len = (hs[0] * hs[0] + hs[1] * hs[1] + hs[2] * hs[2]).sqrt();
            let h = hs.map(|v| v / len);
            let c = wo[0] * h[0] + wo[2] * h[2];
            let cos_h = h[2];
            let tan2 = (1.0 - cos_h * cos_h) / (cos_h * cos_h);
            let d = (-tan2 / (alpha * alpha)).exp() / (std::f64::consts::PI * alpha * alpha * cos_h.powi(4));
            let g = smith_g1(mu_o, alpha) * smith_g1(z, alpha);
            let f = f64::from(fresnel_dielectric(c as f32, IOR));
            // BRDF · cos θ_i over the uniform pdf 1 / 2π.
            let w = f * d * g / (4.0 * mu_o * z) * z * std::f64::consts::TAU;
            let el = z.asin() - mu_o.asin();
            let az = wi[1].atan2(-wi[0]);
            sum += w;
            s_el += w * el;
            s_el2 += w * el * el;
            s_az2 += w * az * az;
        }
        let mean = s_el / sum;
        [sum / n as f64, mean, (s_el2 / sum - mean * mean).sqrt(), (s_az2 / sum).sqrt()]
    }

    #[test]
    fn quadrature_agrees_with_monte_carlo_over_the_hemisphere() {
        for (mu, alpha) in [(0.9, 0.3), (0.5, 0.2), (0.2, 0.25), (0.1, 0.4), (0.05, 0.15)] {
            let q = lobe_quadrature(mu, alpha, 128);
            let mc = monte_carlo(mu, alpha, 2_000_000);
            assert!((q[0] - mc[0]).abs() < 0.01 * mc[0] + 2e-4, "μ {mu}, α {alpha}: E {q:?}, Monte Carlo {mc:?}");
            for c in 1..4 {
                assert!((q[c] - mc[c]).abs() < 0.004 + 0.03 * mc[c].abs(), "μ {mu}, α {alpha}: {q:?} vs {mc:?}");
            }
        }
    }

    #[test]
    fn the_lobe_is_the_first_order_one_away_from_grazing_and_rises_near_it() {
        // γ = 60°, α = 0.05: σ₁ = 0.0354; elevation spread 2σ₁, azimuth 2σ₁ tan γ at the mirror direction.
        let (g, alpha) = (60f64.to_radians(), 0.05);
        let [_, de, se, sa] = lobe_quadrature(g.sin(), alpha, 128);
        let s1 = alpha / 2f64.sqrt();
        assert!(de.abs() < 0.1 * 2.0 * s1, "shift {de}");
        assert!((se - 2.0 * s1).abs() < 0.05 * 2.0 * s1, "elevation spread {se}, want {}", 2.0 * s1);
        // (The azimuth about the mirror direction, which stands g above the horizontal: 2σ₁ sin γ / cos γ.)
        assert!((sa - 2.0 * s1 * g.tan()).abs() < 0.05 * 2.0 * s1 * g.tan(), "azimuth spread {sa}");
        // Grazing: the visible facets lean towards the camera and the lobe rises by several degrees.
        let [de, se, _] = lobe(1f32.to_radians().sin(), 0.055);
        assert!(de.to_degrees() > 3.5 && de.to_degrees() < 6.0, "shift {}°", de.to_degrees());
        assert!(se.to_degrees() > 2.0 && se.to_degrees() < 4.0, "spread {}°", se.to_degrees());
    }

    #[test]
    fn beckmann_d_integrates_to_one_over_projected_normals() {
        for alpha in [0.05f32, 0.2, 0.5] {
            // ∫ D(h) cos θ_h dω over the hemisphere, midpoint rule in θ (fine near the peak) and exact in φ.
            let n = 20_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                    let d = f64::from(beckmann_d(t.cos() as f32, alpha));
                    d * t.cos() * t.sin() * std::f64::consts::TAU * std::f64::consts::FRAC_PI_2 / n as f64
                })
                .sum();
            assert!((sum - 1.0).abs() < 2e-3, "α {alpha}: {sum}");
        }
        // The glitter's reflection at the mirror configuration: D(1) G / (4 n·v) with G = 1 at normal incidence.
        let n = Vec3::Z;
        let s = specular_cos(n, n, n, 0.1);
        assert!((s - 1.0 / (std::f32::consts::PI * 0.01 * 4.0)).abs() < 1e-3 * s, "{s}");
    }

    #[test]
    fn smooth_water_reflects_the_fresnel_share_and_roughness_darkens_grazing_views() {
        // At the table's nodes (√μ = k/64), exactly the Fresnel reflectance when smooth.
        for mu in [(8.0f32 / 64.0).powi(2), 0.25, (40.0f32 / 64.0).powi(2), 1.0] {
            let f = fresnel_dielectric(mu, IOR);
            assert!((reflectance(mu, 0.0) - f).abs() < 1e-6, "μ {mu}");
            // Slightly rough: close to Fresnel away from grazing.
            if mu >= 0.3 {
                assert!((reflectance(mu, 0.05) - f).abs() < 0.002, "μ {mu}");
            }
        }
        // At grazing views roughness hides the mirror (masking, and lobe directions under the horizon).
        assert!(reflectance(0.05, 0.2) < 0.7 * reflectance(0.05, 0.0));
        assert!(reflectance(0.05, 0.3) < reflectance(0.05, 0.1));
        // The table reads the quadrature between nodes to within its interpolation error.
        let (mu, alpha) = (0.337f32, 0.171f32);
        let q = reflectance_quadrature(f64::from(mu), f64::from(alpha), STRATA) as f32;
        assert!((reflectance(mu, alpha) - q).abs() < 0.003, "{} vs {q}", reflectance(mu, alpha));
    }
}
