//! The fixed four-component swell: the water's shading normals where the scene has no displaced wave surface
//! (`sea::WaveSurface`).
//!
//! Four long-crested linear (Airy) waves, `η = Σ a_i sin(k_i (x cos θ_i + y sin θ_i) + φ_i)` (linear wave theory,
//! e.g. L. H. Holthuijsen, *Waves in Oceanic and Coastal Waters*, Cambridge University Press, 2007, ch. 5), of
//! wavelengths 41, 23, 11 and 3.7 m, directions `θ_i` and phases `φ_i` drawn from the render's seed; the normal is
//! `(−∂η/∂x, −∂η/∂y, 1)` normalised, each wave's slope amplitude `a_i k_i`. Their amplitudes share half the
//! significant wave height (weights 0.5, 0.3, 0.15, 0.05), each limited to `0.05 λ_i` (a steepness `H/λ` of 0.1,
//! below the breaking limit of about 1/7), so that the summed slopes stay below about 0.31.

use super::super::noise::{self, stream};
use super::tables::fast_cos;
use parry3d::math::Vec3;

/// Wavelengths of the four components (m).
const WAVELENGTHS_M: [f32; 4] = [41.0, 23.0, 11.0, 3.7];
/// Each component's share of half the significant wave height.
const WEIGHTS: [f32; 4] = [0.5, 0.3, 0.15, 0.05];

/// One swell component of the water surface: direction `(cos, sin)`, wave number, phase and slope amplitude.
#[derive(Debug, Clone, Copy)]
struct Wave {
    c: f32,
    s: f32,
    k: f32,
    phase: f32,
    amp_k: f32,
}

/// The four-component swell of one render.
#[derive(Debug, Clone, Copy)]
pub struct Swell {
    waves: [Wave; 4],
}

impl Swell {
    /// The swell of significant wave height `wave_height_m` (negative read as 0), its directions and phases
    /// drawn from `seed`.
    pub fn new(wave_height_m: f32, seed: u64) -> Self {
        let h = wave_height_m.max(0.0);
        let waves = std::array::from_fn(|i| {
            let i = i as u64;
            let dir = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i) as f32;
            let phase = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i + 1) as f32;
            let wavelength = WAVELENGTHS_M[i as usize];
            let k = std::f32::consts::TAU / wavelength;
            // Steepness limited so slopes stay below ~0.35.
            let amp = (0.5 * h).min(0.05 * wavelength) * WEIGHTS[i as usize];
            let (s, c) = dir.sin_cos();
            Wave { c, s, k, phase, amp_k: amp * k }
        });
        Self { waves }
    }

    /// Unit normal of the swell's surface at `p` (world x, y; `z` unused).
    #[inline(always)]
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let mut gx = 0.0;
        let mut gy = 0.0;
        for w in &self.waves {
            let arg = w.k * (w.c * p.x + w.s * p.y) + w.phase;
            let slope = w.amp_k * fast_cos(arg);
            gx += slope * w.c;
            gy += slope * w.s;
        }
        Vec3::new(-gx, -gy, 1.0).normalize_or_zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Result;

    #[test]
    fn calm_water_is_level() -> Result<()> {
        let swell = Swell::new(0.0, 7);
        for i in 0..100 {
            let p = Vec3::new(i as f32 * 3.1, i as f32 * -1.7, 0.0);
            assert_eq!(swell.normal(p), Vec3::Z, "{p}");
        }
        Ok(())
    }

    #[test]
    fn slopes_stay_within_the_steepness_limit() -> Result<()> {
        // Every component at its steepness cap: the summed slope amplitude is 0.05·2π·Σ weights ≈ 0.314.
        let swell = Swell::new(100.0, 3);
        let bound = 0.05 * std::f32::consts::TAU * WEIGHTS.iter().sum::<f32>() * (1.0 + 1e-5);
        let mut steepest = 0.0f32;
        for i in 0..4000 {
            let p = Vec3::new(i as f32 * 0.37, i as f32 * 0.53 - 300.0, 0.0);
            let n = swell.normal(p);
            assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
            let slope = (n.x * n.x + n.y * n.y).sqrt() / n.z;
            assert!(slope <= bound, "{slope} > {bound} at {p}");
            steepest = steepest.max(slope);
        }
        // The waves are there: somewhere the water tilts by a good share of the limit.
        assert!(steepest > 0.3 * bound, "{steepest}");
        Ok(())
    }

    #[test]
    fn the_seed_turns_the_swell() -> Result<()> {
        let (a, b) = (Swell::new(1.0, 1), Swell::new(1.0, 2));
        let p = Vec3::new(12.5, -4.0, 0.0);
        assert_eq!(a.normal(p), Swell::new(1.0, 1).normal(p));
        assert_ne!(a.normal(p), b.normal(p));
        Ok(())
    }
}
