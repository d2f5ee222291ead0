//! Surface reflection: a GGX microfacet specular with the separable Smith shadowing and Schlick's Fresnel over a
//! Lambert diffuse, the exact dielectric Fresnel for water, and the split-sum table for image-based lighting;
//! [`Lobes`]: a material's two lobes as the direct light (the sun, a lamp) reads them.
//!
//! * GGX (Trowbridge–Reitz) distribution: B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for
//!   Refraction through Rough Surfaces", EGSR 2007: `D(h) = α² / (π ((n·h)² (α² − 1) + 1)²)` and its Smith
//!   masking `G1(v) = 2 / (1 + √(1 + α² tan² θ_v))`; shadowing-masking `G = G1(l) G1(v)` (separable, as in
//!   Mitsuba 3's `MicrofacetDistribution`).
//! * Fresnel: C. Schlick, "An Inexpensive BRDF Model for Physically-based Rendering", CGF 13(3), 1994,
//!   `F = F0 + (1 − F0)(1 − cos θ)^5`; water uses the exact unpolarised dielectric Fresnel (IOR 1.33).
//! * Specular BRDF `f_s = D G F / (4 (n·l)(n·v))`; diffuse `f_d = (1 − metallic) · base / π`;
//!   `F0 = 0.04` for dielectrics, the base colour for metals (the metallic workflow of B. Burley, "Physically
//!   Based Shading at Disney", 2012; `α = roughness²`).
//! * Split sum: B. Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course: the specular reflection of
//!   an environment is the GGX-prefiltered environment times `F0 · A(n·v, α) + B(n·v, α)`, with `A`, `B` the
//!   hemispherical integrals of this BRDF (tabulated here once, by quadrature).
//!
//! Checked in the tests against closed forms: `D` integrates to 1 over projected microfacet normals, `G1` is 1
//! at normal incidence, the Fresnel values at normal incidence are `((n − 1)/(n + 1))²`, and the table's white
//! furnace value `A + B` matches a brute-force integral of `f_s · cos`.

use crate::material::Material;
use parry3d::math::Vec3;
use std::sync::OnceLock;

/// Smallest GGX `α` used (keeps the distribution finite for mirror-like materials).
pub const ALPHA_MIN: f32 = 1e-3;

/// A material's reflection as the direct light sees it: the Lambert lobe `f_d = (1 − metallic) base / π`, the
/// GGX lobe's Fresnel at normal incidence `f0` (0.04 for a dielectric, the base colour for a metal) and its
/// roughness `α = roughness²` (at least [`ALPHA_MIN`]).
#[derive(Debug, Clone, Copy)]
pub struct Lobes {
    /// `f_d`, linear RGB, 1/sr.
    pub diffuse: Vec3,
    /// Fresnel reflectance at normal incidence, linear RGB.
    pub f0: Vec3,
    /// GGX roughness `α`.
    pub alpha: f32,
}

impl Lobes {
    /// The lobes of material `m` (metallic workflow).
    #[inline(always)]
    pub fn of(m: &Material) -> Self {
        let base = Vec3::from_array(m.base_color);
        Self {
            diffuse: base * ((1.0 - m.metallic) / std::f32::consts::PI),
            f0: Vec3::splat(0.04) * (1.0 - m.metallic) + base * m.metallic,
            alpha: (m.roughness * m.roughness).max(ALPHA_MIN),
        }
    }

    /// Radiance towards unit `v` of light arriving from unit `l` with irradiance `e` normal to the beam, at a
    /// surface of unit normal `n`: `(f_d + f_s(v, l)) (n·l) E`, zero where `l` is below the surface.
    #[inline(always)]
    pub fn direct(&self, n: Vec3, v: Vec3, l: Vec3, e: Vec3) -> Vec3 {
        let nl = n.dot(l);
        if nl <= 0.0 {
            return Vec3::ZERO;
        }
        (self.diffuse * nl + specular_cos(n, v, l, self.alpha, self.f0)) * e
    }
}

/// GGX normal distribution `D` for `cos θ_h = n·h` and roughness `alpha`.
#[inline(always)]
pub fn ggx_d(n_dot_h: f32, alpha: f32) -> f32 {
    if n_dot_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    a2 / (std::f32::consts::PI * t * t)
}

/// Smith masking `G1` of GGX for a direction at `cos θ` from the normal.
#[inline(always)]
pub fn smith_g1(cos_theta: f32, alpha: f32) -> f32 {
    if cos_theta <= 0.0 {
        return 0.0;
    }
    let c2 = cos_theta * cos_theta;
    let tan2 = (1.0 - c2).max(0.0) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Schlick's Fresnel approximation.
#[inline(always)]
pub fn schlick(f0: Vec3, cos_theta: f32) -> Vec3 {
    let m = (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface (from the side of index 1 into index `eta`)
/// at incidence `cos θ_i` in `[0, 1]`.
#[inline(always)]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// GGX specular reflectance times `cos θ_l`, `f_s (n·l)`, for unit normal `n`, view `v` and light `l` (both
/// leaving the surface) and Fresnel at normal incidence `f0`.
#[inline(always)]
pub fn specular_cos(n: Vec3, v: Vec3, l: Vec3, alpha: f32, f0: Vec3) -> Vec3 {
    let (nl, nv) = (n.dot(l), n.dot(v));
    if nl <= 0.0 || nv <= 0.0 {
        return Vec3::ZERO;
    }
    let h = (v + l).normalize_or_zero();
    schlick(f0, v.dot(h)) * dg_over_4nv(n.dot(h), nl, nv, alpha)
}

/// The GGX/Smith part of [`specular_cos`] without the Fresnel factor, `D G / (4 n·l n·v) · n·l`, for a caller
/// that weights it by a Fresnel of its own: zero where `l` or `v` is below the surface.
#[inline(always)]
pub fn microfacet_cos(n: Vec3, v: Vec3, l: Vec3, alpha: f32) -> f32 {
    let (nl, nv) = (n.dot(l), n.dot(v));
    if nl <= 0.0 || nv <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize_or_zero();
    dg_over_4nv(n.dot(h), nl, nv, alpha)
}

/// `D(n·h) G(n·l, n·v) / (4 n·v)` of GGX with Smith masking.
#[inline(always)]
fn dg_over_4nv(nh: f32, nl: f32, nv: f32, alpha: f32) -> f32 {
    let d = ggx_d(nh, alpha);
    let g = smith_g1(nl, alpha) * smith_g1(nv, alpha);
    d * g / (4.0 * nv)
}

/// Resolution of the split-sum table in `n·v` and in roughness.
const LUT: usize = 32;

/// The split-sum table: `(A, B)` at `n·v = (i + 0.5) / LUT`, roughness `j / (LUT − 1)`.
fn dfg_table() -> &'static [[f32; 2]] {
    static TABLE: OnceLock<Vec<[f32; 2]>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = vec![[0f32; 2]; LUT * LUT];
        for j in 0..LUT {
            let rough = j as f32 / (LUT - 1) as f32;
            let alpha = (rough * rough).max(ALPHA_MIN);
            for i in 0..LUT {
                let nv = (i as f32 + 0.5) / LUT as f32;
                t[j * LUT + i] = dfg_integral(nv, alpha, 48);
            }
        }
        t
    })
}

/// `(A, B)` with `∫ f_s cos θ_l dω_l = F0 · A + B` for Schlick's Fresnel (the `(1 − v·h)^5` split), by GGX
/// importance sampling of the half vector on an `m × m` stratified grid.
pub fn dfg_integral(nv: f32, alpha: f32, m: usize) -> [f32; 2] {
    let v = Vec3::new((1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for p in 0..m {
        for q in 0..m {
            let u1 = (p as f32 + 0.5) / m as f32;
            let u2 = (q as f32 + 0.5) / m as f32;
            // GGX half-vector sample: pdf(h) = D(h) (n·h).
            let cos_h = ((1.0 - u1) / (1.0 + (alpha * alpha - 1.0) * u1)).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u2;
            let h = Vec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let vh = v.dot(h);
            let l = h * (2.0 * vh) - v;
            if l.z <= 0.0 || vh <= 0.0 {
                continue;
            }
            // f_s cos / pdf(l) with pdf(l) = D (n·h) / (4 v·h): G v·h / (n·v n·h) times Fresnel.
            let g = smith_g1(l.z, alpha) * smith_g1(nv, alpha);
            let w = (g * vh / (nv * cos_h)) as f64;
            let fc = (1.0 - vh).powi(5) as f64;
            a += w * (1.0 - fc);
            b += w * fc;
        }
    }
    let n = (m * m) as f64;
    [(a / n) as f32, (b / n) as f32]
}

/// `(A, B)` of the split sum at `n·v` and roughness (bilinear in the table).
#[inline(always)]
pub fn dfg(nv: f32, roughness: f32) -> [f32; 2] {
    let t = dfg_table();
    let x = (nv.clamp(0.0, 1.0) * LUT as f32 - 0.5).clamp(0.0, (LUT - 1) as f32);
    let y = (roughness.clamp(0.0, 1.0) * (LUT - 1) as f32).clamp(0.0, (LUT - 1) as f32);
    let (i0, j0) = (x as usize, y as usize);
    let (i1, j1) = ((i0 + 1).min(LUT - 1), (j0 + 1).min(LUT - 1));
    let (fx, fy) = (x - i0 as f32, y - j0 as f32);
    let at = |i: usize, j: usize, c: usize| t[j * LUT + i][c];
    let lerp = |c: usize| {
        let a = at(i0, j0, c) * (1.0 - fx) + at(i1, j0, c) * fx;
        let b = at(i0, j1, c) * (1.0 - fx) + at(i1, j1, c) * fx;
        a * (1.0 - fy) + b * fy
    };
    [lerp(0), lerp(1)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ggx_normalises_and_g1_is_one_head_on() {
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            // ∫ D(h) cos θ_h dω_h = 1.
            let n = 4000;
            let mut s = 0.0f64;
            for i in 0..n {
                let th = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                let d = ggx_d(th.cos() as f32, alpha) as f64;
                s += d * th.cos() * th.sin() * std::f64::consts::TAU * (std::f64::consts::FRAC_PI_2 / n as f64);
            }
            assert!((s - 1.0).abs() < 0.01, "alpha {alpha}: {s}");
            assert!((smith_g1(1.0, alpha) - 1.0).abs() < 1e-6);
            assert!(smith_g1(0.1, alpha) < 1.0);
        }
    }

    #[test]
    fn fresnel_at_normal_incidence_and_grazing() {
        let want = ((1.33f32 - 1.0) / (1.33 + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, 1.33) - want).abs() < 1e-6);
        assert!((fresnel_dielectric(0.0, 1.33) - 1.0).abs() < 1e-6);
        assert_eq!(schlick(Vec3::splat(0.04), 1.0), Vec3::splat(0.04));
        assert!((schlick(Vec3::splat(0.04), 0.0).x - 1.0).abs() < 1e-6);
    }

    #[test]
    fn split_sum_table_matches_brute_force() {
        // ∫ f_s cos dω over the hemisphere by a dense direction grid, for F0 = 1 (A + B) and F0 = 0 (B).
        for (nv, rough) in [(0.9f32, 0.5f32), (0.5, 0.3), (0.2, 0.8), (0.7, 1.0)] {
            let alpha = rough * rough;
            let v = Vec3::new((1.0 - nv * nv).sqrt(), 0.0, nv);
            let (n_t, n_p) = (600, 600);
            let (mut one, mut zero) = (0.0f64, 0.0f64);
            for i in 0..n_t {
                let th = (i as f32 + 0.5) / n_t as f32 * std::f32::consts::FRAC_PI_2;
                for j in 0..n_p {
                    let ph = (j as f32 + 0.5) / n_p as f32 * std::f32::consts::TAU;
                    let l = Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                    let dw = (th.sin() * std::f32::consts::FRAC_PI_2 / n_t as f32 * std::f32::consts::TAU / n_p as f32)
                        as f64;
                    one += specular_cos(Vec3::Z, v, l, alpha, Vec3::ONE).x as f64 * dw;
                    zero += specular_cos(Vec3::Z, v, l, alpha, Vec3::ZERO).x as f64 * dw;
                }
            }
            let [a, b] = dfg(nv, rough);
            assert!(((a + b) as f64 - one).abs() < 0.02 * one.max(0.05), "nv {nv} r {rough}: {} vs {one}", a + b);
            assert!((b as f64 - zero).abs() < 0.02 * one.max(0.05), "nv {nv} r {rough}: {b} vs {zero}");
        }
    }
}
