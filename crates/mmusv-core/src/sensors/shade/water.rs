//! The sea surface's optics for cameras: capillary roughness, whitecap coverage, shallow water and the water body
//! (the foam itself, whitecaps and wakes, in [`super::foam`]).
//!
//! * **Capillary roughness** (waves too small to be geometry): C. Cox & W. Munk, "Measurement of the Roughness of
//!   the Sea Surface from Photographs of the Sun's Glitter", JOSA 44(11), 1954: mean square slope
//!   `σ² = 0.003 + 5.12·10⁻³ U` (U the wind speed at 12.5 m, m/s); their slopes are Gaussian, so the roughness is
//!   a Beckmann one of `α = σ` (`rough_water.rs`), for the sun's glitter (the Cox–Munk glitter pattern rather than
//!   a disc) and for the glossy reflections alike.
//! * **Whitecap coverage**: E. C. Monahan & I. O'Muircheartaigh, "Optimal Power-Law Description of Oceanic
//!   Whitecap Coverage Dependence on Wind Speed", J. Phys. Oceanogr. 10, 1980: `W = 3.84·10⁻⁶ U^3.41`
//!   (fraction of the surface; [`super::foam`] places it).
//! * **Wind**: the environment's (m/s at 10 m); when the scenario gives none, the Python layer derives it from the
//!   sea state (`mmusv.sensors.env.wind_from_wave_height`: a fully developed Pierson–Moskowitz sea, whose 19.5 m
//!   wind `√(H_s g / 0.21)` (W. J. Pierson & L. Moskowitz, JGR 69(24), 1964) is brought to 10 m).
//! * **Shallow water**: over a seabed `d` metres down, the water body's diffuse reflectance is
//!   `ρ(d) = ρ∞ + (A_b − ρ∞) exp(−2 K_d d)` (S. Maritorena, A. Morel & B. Gentili, "Diffuse reflectance of
//!   oceanic shallow waters: influence of water depth and bottom albedo", Limnol. Oceanogr. 39(7), 1994), with a
//!   sand bottom of albedo `A_b` and the diffuse attenuation `K_d` of clear coastal water: pure water's
//!   absorption at the channels' wavelengths (R. M. Pope & E. S. Fry, Appl. Opt. 36(33), 1997: 0.264, 0.057 and
//!   0.010 m⁻¹ at 610, 550 and 465 nm, the last between the table's 0.00979 at 460 and 0.0106 at 470 nm; it was
//!   0.012, the table's value near 477 nm, until 2026-12-05) plus 0.06 m⁻¹ for scattering and dissolved matter
//!   (an approximation).
//! * **Water body**: the light scattered back out of the water is the smooth-plastic model of Mitsuba 3 — a
//!   dielectric interface (IOR 1.33) over a Lambertian body of diffuse reflectance `ρ`: radiance
//!   `ρ / (1 − F_dr) · (1 − F(θ_o)) / η² · ∫ (1 − F(θ_i)) L cos θ_i dω / π`, with `F_dr` the interface's internal
//!   diffuse reflectance (here integrated exactly, with total internal reflection).

use parry3d::math::Vec3;

/// Albedo of a sand bottom, linear RGB.
pub const BOTTOM_ALBEDO: [f32; 3] = [0.36, 0.31, 0.22];
/// Diffuse attenuation of clear coastal water, 1/m, per channel (see the module docs).
pub const K_D: [f32; 3] = [0.324, 0.117, 0.070];

/// Diffuse reflectance of the water body `rho_deep` over a sand bottom `depth` metres down (Maritorena et al.).
#[inline(always)]
pub fn shallow_albedo(rho_deep: Vec3, depth: f32) -> Vec3 {
    let d = depth.max(0.0);
    let k = Vec3::from_array(K_D) * (-2.0 * d);
    let f = Vec3::new(k.x.exp(), k.y.exp(), k.z.exp());
    rho_deep + (Vec3::from_array(BOTTOM_ALBEDO) - rho_deep) * f
}

/// Depth steps per metre of [`ShallowWater`]'s table.
const SHALLOW_STEPS_PER_M: f32 = 32.0;
/// Depth past which [`ShallowWater`] takes the water as deep: the bottom's share `e^(−2 K_D d)` is below
/// `e^(−2 · 0.070 · 64) ≈ 10⁻⁴` in every channel.
const SHALLOW_MAX_M: f32 = 64.0;

/// [`shallow_albedo`] of one water body tabulated over depth (every 1/32 m to 64 m, read linearly: within
/// `10⁻⁴` of the formula relative to the bottom's contrast), so a pixel costs no exponentials.
#[derive(Debug)]
pub struct ShallowWater {
    rho_deep: Vec3,
    table: Vec<Vec3>,
}

impl ShallowWater {
    /// The table for a water body of deep albedo `rho_deep`.
    pub fn new(rho_deep: Vec3) -> Self {
        let n = (SHALLOW_MAX_M * SHALLOW_STEPS_PER_M) as usize;
        let table = (0..=n).map(|i| shallow_albedo(rho_deep, i as f32 / SHALLOW_STEPS_PER_M)).collect();
        Self { rho_deep, table }
    }

    /// The table of `rho_deep`, built once per process and shared (a cache of the last few).
    pub fn shared(rho_deep: Vec3) -> std::sync::Arc<Self> {
        use std::sync::{Arc, Mutex};
        static CACHE: Mutex<Vec<Arc<ShallowWater>>> = Mutex::new(Vec::new());
        if let Ok(c) = CACHE.lock() {
            if let Some(t) = c.iter().find(|t| t.rho_deep == rho_deep) {
                return Arc::clone(t);
            }
        }
        let t = Arc::new(Self::new(rho_deep));
        if let Ok(mut c) = CACHE.lock() {
            if c.len() >= 8 {
                c.remove(0);
            }
            c.push(Arc::clone(&t));
        }
        t
    }

    /// Diffuse reflectance over a sand bottom `depth` metres down.
    #[inline(always)]
    pub fn albedo(&self, depth: f32) -> Vec3 {
        let x = depth.max(0.0) * SHALLOW_STEPS_PER_M;
        let last = self.table.len() - 1;
        if x >= last as f32 {
            return self.rho_deep;
        }
        let i = x as usize;
        let f = x - i as f32;
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }
}

/// Cox–Munk total mean square slope `σ² = 0.003 + 5.12·10⁻³ U` of the capillary waves under wind `u` (m/s, at
/// 12.5 m in their paper, 10 m here).
pub fn cox_munk_mss(u: f32) -> f32 {
    0.003 + 5.12e-3 * u.max(0.0)
}

/// Cox–Munk (Beckmann) roughness `α` of the capillary waves under wind `u` (m/s): `√σ²`.
pub fn cox_munk_alpha(u: f32) -> f32 {
    cox_munk_mss(u).sqrt()
}

/// Monahan's whitecap coverage (fraction in `[0, 1]`) under wind `u` (m/s).
pub fn monahan_coverage(u: f32) -> f32 {
    (3.84e-6 * u.max(0.0).powf(3.41)).min(1.0)
}

/// Internal diffuse reflectance of a dielectric interface of relative index `eta` seen from inside
/// (`∫ F(θ) 2 cos θ sin θ dθ` with the inside-to-outside Fresnel, total internal reflection included).
pub fn internal_diffuse_reflectance(eta: f32) -> f32 {
    let n = 2000;
    let mut s = 0.0f64;
    for i in 0..n {
        let th = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
        let c = th.cos();
        // From inside: incidence in a medium of index eta towards index 1, relative index 1/eta.
        let sin_t2 = (eta as f64 * th.sin()).powi(2);
        let f = if sin_t2 >= 1.0 {
            1.0
        } else {
            let ct = (1.0 - sin_t2).sqrt();
            let e = 1.0 / eta as f64;
            let rs = (c - e * ct) / (c + e * ct);
            let rp = (e * c - ct) / (e * c + ct);
            0.5 * (rs * rs + rp * rp)
        };
        s += f * 2.0 * c * th.sin() * std::f64::consts::FRAC_PI_2 / n as f64;
    }
    s as f32
}

/// Radiance scattered out of the water body per unit entering irradiance, `ρ / (1 − F_dr) (1 − F_o) / (η² π)`,
/// for a view whose Fresnel reflectance is `f_o`.
#[inline(always)]
pub fn body_factor(rho: Vec3, fdr: f32, f_o: f32, eta: f32) -> Vec3 {
    rho * ((1.0 - f_o) / ((1.0 - fdr) * eta * eta * std::f32::consts::PI))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms() {
        assert!((cox_munk_alpha(10.0) - (0.003f32 + 0.0512).sqrt()).abs() < 1e-6);
        // Monahan at 10 m/s: 3.84e-6 · 10^3.41 = 0.00987.
        assert!((monahan_coverage(10.0) - 0.009_87).abs() < 1e-4);
        // Internal diffuse reflectance of water: total internal reflection beyond the critical angle alone
        // gives 1 − (1/1.33)² = 0.435; the Fresnel inside the cone adds a little.
        let f = internal_diffuse_reflectance(1.33);
        assert!(f > 0.435 && f < 0.48, "{f}");
    }

    #[test]
    fn shallow_table_is_the_formula() {
        let rho = Vec3::new(0.02, 0.03, 0.025);
        let t = ShallowWater::new(rho);
        let contrast = (Vec3::from_array(BOTTOM_ALBEDO) - rho).max_element();
        for i in 0..20_000 {
            let d = i as f32 * 0.0049;
            let err = (t.albedo(d) - shallow_albedo(rho, d)).abs().max_element();
            assert!(err < 1e-4 * contrast, "{d} m: {err}");
        }
        assert_eq!(t.albedo(1e9), rho);
        assert_eq!(t.albedo(-1.0), shallow_albedo(rho, 0.0));
    }

    #[test]
    fn shallow_water_tends_to_the_bottom_and_the_deep() {
        let deep = Vec3::new(0.004, 0.018, 0.03);
        assert!((shallow_albedo(deep, 0.0) - Vec3::from_array(BOTTOM_ALBEDO)).length() < 1e-6);
        assert!((shallow_albedo(deep, 1000.0) - deep).length() < 1e-6);
        // At 5 m the blue channel keeps exp(-2·0.070·5) = 0.497 of the bottom's contrast.
        let b = shallow_albedo(deep, 5.0).z;
        assert!((b - (0.03 + (0.22 - 0.03) * (-0.70f32).exp())).abs() < 1e-5);
    }

    #[test]
    fn diffuse_attenuation_is_pope_and_fry_plus_the_scattering_term() {
        // Pope & Fry (1997), Table 3, pure water's absorption, 1/m: 0.2644 at 610 nm, 0.0565 at 550 nm, and 0.00979
        // and 0.0106 at 460 and 470 nm, read linearly at 465 nm; plus the module's 0.06 for the rest.
        let blue = 0.5 * (0.00979 + 0.0106);
        for (k, a) in K_D.iter().zip([0.2644f32, 0.0565, blue]) {
            assert!((k - (a + 0.06)).abs() < 0.001, "{k} against {}", a + 0.06);
        }
    }
}
