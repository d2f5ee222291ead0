//! Lookup tables of the shader's two hottest functions, built once: `cos` of the swell's phases
//! ([`fast_cos`]) and the exact Fresnel reflectance of water ([`water_fresnel`], the dielectric formula of
//! [`super::brdf::fresnel_dielectric`] at IOR 1.33), each read by linear interpolation. Their errors against the
//! functions they stand for are bounded in their docs and tested below over the whole domain.

use super::brdf::fresnel_dielectric;
use super::envlight::WATER_IOR;

/// Intervals per turn of [`fast_cos`]'s table.
const COS_STEPS: usize = 4096;

/// `cos` at `COS_STEPS + 1` evenly spaced points of one turn (built once).
fn cos_table() -> &'static [f32] {
    static TABLE: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        (0..=COS_STEPS).map(|i| (i as f64 / COS_STEPS as f64 * std::f64::consts::TAU).cos() as f32).collect()
    })
}

/// `cos x` to within 10⁻⁶ without a library call (for `|x| < 10⁹`): the argument reduced to turns in `f64`,
/// then a table of [`COS_STEPS`] intervals per turn read linearly (error below `(2π/4096)² / 8 ≈ 3·10⁻⁷`).
#[inline(always)]
pub(super) fn fast_cos(x: f32) -> f32 {
    let t = x as f64 * (COS_STEPS as f64 / std::f64::consts::TAU);
    let f = t.floor();
    let i = (f as i64).rem_euclid(COS_STEPS as i64) as usize;
    let w = (t - f) as f32;
    let table = cos_table();
    table[i] + (table[i + 1] - table[i]) * w
}

/// Intervals of the water's Fresnel table over `cos θ` in `[0, 1]`.
const FRESNEL_STEPS: usize = 1024;

/// The exact Fresnel reflectance of water at `FRESNEL_STEPS + 1` evenly spaced `cos θ` (built once).
fn water_fresnel_table() -> &'static [f32] {
    static TABLE: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        (0..=FRESNEL_STEPS).map(|i| fresnel_dielectric(i as f32 / FRESNEL_STEPS as f32, WATER_IOR)).collect()
    })
}

/// [`fresnel_dielectric`] of water at `cos θ`, linearly interpolated in its table (within 2·10⁻⁴ of it, tested).
#[inline]
pub(super) fn water_fresnel(cos: f32) -> f32 {
    let t = water_fresnel_table();
    let x = cos.clamp(0.0, 1.0) * FRESNEL_STEPS as f32;
    let i = (x as usize).min(FRESNEL_STEPS - 1);
    let f = x - i as f32;
    t[i] + (t[i + 1] - t[i]) * f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn water_fresnel_table_is_the_formula() {
        for i in 0..=100_000 {
            let c = i as f32 / 100_000.0;
            let (a, b) = (water_fresnel(c), fresnel_dielectric(c, WATER_IOR));
            assert!((a - b).abs() < 2e-4, "{c}: {a} vs {b}");
        }
    }

    #[test]
    fn fast_cos_is_cos() {
        for i in -200_000..200_000 {
            let x = i as f32 * 0.001_37;
            assert!((fast_cos(x) - (x as f64).cos() as f32).abs() < 2e-6, "{x}");
        }
    }
}
