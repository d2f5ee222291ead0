//! The sky as the rough sea reflects it: the mean of the sky's radiance over the water's single-scattering
//! reflection lobe around a mirror direction, tabulated once per environment.
//!
//! **Model.** The microfacet reflection of `rough_water.rs` (K. E. Torrance & E. M. Sparrow, JOSA 57(9), 1967;
//! B. Walter, S. R. Marschner, H. Li & K. E. Torrance, "Microfacet Models for Refraction through Rough
//! Surfaces", EGSR 2007): Beckmann facets of Cox–Munk roughness `α` (C. Cox & W. Munk, JOSA 44(11), 1954), Smith's
//! separable masking by Walter et al.'s rational `G₁`, the exact Fresnel reflectance of water (n = 1.33). Level
//! water seen along `ω_o`, whose mirror direction is `r = (−ω_o.x, −ω_o.y, ω_o.z)`, reflects
//! `L̄(r, α) = ∫ w L dω_i / ∫ w dω_i` with `w = F(ω_o·h) D(h) G₁(ω_o) G₁(ω_i) / (4 μ_o)` over the upper hemisphere:
//! the lobe's mean, which the shader weighs by the directional reflectance `E(μ_o, α)` (`rough_water.rs`).
//! Evaluated by the stratified quadrature of `rough_water.rs` over facet normals drawn from `D(h) cos θ_h`
//! (`stratified_facets`), 20 × 20 facets per entry.
//!
//! **Why a table.** The cameras trace their reflections in directions drawn from the lobe and spread them over the
//! rest of it in screen space (`camera/glossy.rs`), which cannot look past the image's edge: a lens narrower than
//! the lobe, or a view steeply down, would read the sky of the mirror directions around the pixel instead of the
//! lobe's mean. The sky's part of the reflection comes from here instead, whatever the lens: each place reads the
//! spread reflections scaled, per channel, by this mean over the spread sky along the same rays
//! (`blur(value) · lobe_sky / blur(sky)`): where the lobe meets only sky that is this table's mean, and where it
//! meets a ship, a quay or an island it is the spread reflection of it, scaled by how far the sky's part is off.
//!
//! **Table.** Per roughness level `α = k/16`, `k = 1..8` (built on first use; `α` is read linearly between
//! levels, 0 at `k = 0`, and at 1/2 beyond it), a grid over the mirror direction: 48 columns uniform in the
//! "diamond" pseudo-angle of its azimuth (`envlight.rs`) and 24 rows uniform in `√r_z` (dense at the horizon,
//! where the lobe changes fastest). Each entry holds the lobe's mean minus the mirror direction's own radiance
//! (so that a calm sea reads the dense sky table exactly), for the sky (`Lighting::sky_radiance`) and the
//! horizon's air light (`Lighting::horizon_radiance`) separately: the shader blends the two by visibility as it
//! blends the mirror direction's.

use super::brdf::fresnel_dielectric;
use super::envlight::{columns, diamond, diamond_dir, Lighting, WATER_IOR};
use super::rough_water::{smith_g1, stratified_facets};
use parry3d::math::Vec3;
use std::sync::OnceLock;

/// Columns (azimuth) of each level's grid.
const COLS: usize = 48;
/// Rows (uniform in `√r_z` from the horizon to the zenith) of each level's grid.
const ROWS: usize = 24;
/// Roughness levels after `α = 0`: `α = k · ALPHA_STEP`, `k = 1..=LEVELS`.
const LEVELS: usize = 8;
/// Roughness between levels.
const ALPHA_STEP: f32 = 1.0 / 16.0;
/// Stratified facets per side of each entry's quadrature.
const STRATA: usize = 20;

/// One entry: the lobe's mean minus the mirror direction's radiance, for the sky and for the air light.
type Entry = [Vec3; 2];

/// The lobe means of one environment's sky, per roughness level, built on first use.
#[derive(Debug, Default)]
pub struct SkyLobe {
    levels: [OnceLock<Vec<Entry>>; LEVELS],
}

/// The mirror direction of node `(i, j)`.
fn node(i: usize, j: usize) -> Vec3 {
    let (x, y) = diamond_dir((i as f32 + 0.5) / COLS as f32 * 4.0);
    let u = j as f32 / (ROWS - 1) as f32;
    let z = (u * u).max(1e-4);
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * x, s * y, z)
}

/// The lobe's mean of `(sky, air)` around mirror direction `r` for facets `facets` of roughness `alpha`, minus
/// `r`'s own: [`SkyLobe`]'s entries, by quadrature.
fn entry(light: &Lighting, r: Vec3, alpha: f64, facets: &[Vec3]) -> Entry {
    let o = Vec3::new(-r.x, -r.y, r.z);
    let (mut sky, mut air, mut wsum) = (Vec3::ZERO, Vec3::ZERO, 0.0f64);
    for &m in facets {
        let c = o.dot(m);
        if c <= 0.0 {
            continue;
        }
        let i = m * (2.0 * c) - o;
        if i.z <= 0.0 {
            continue;
        }
        // (G₁(ω_o) / μ_o is the same for every facet: it cancels in the mean.)
        let w = f64::from(fresnel_dielectric(c, WATER_IOR)) * smith_g1(f64::from(i.z), alpha) * f64::from(c / m.z);
        let (s, a) = light.sky_and_horizon(i.normalize());
        sky += s * w as f32;
        air += a * w as f32;
        wsum += w;
    }
    if wsum <= 0.0 {
        return [Vec3::ZERO; 2];
    }
    let (s0, a0) = light.sky_and_horizon(r);
    [sky / wsum as f32 - s0, air / wsum as f32 - a0]
}

impl SkyLobe {
    /// The grid of level `k` (`α = (k + 1) · ALPHA_STEP`), built on first use (tens of milliseconds, on the
    /// calling thread: no parallel work inside a lock that other workers may wait on).
    fn level(&self, light: &Lighting, k: usize) -> &[Entry] {
        self.levels[k].get_or_init(|| {
            let alpha = f64::from((k + 1) as f32 * ALPHA_STEP);
            let facets: Vec<Vec3> =
                stratified_facets(alpha, STRATA).map(|h| Vec3::new(h[0] as f32, h[1] as f32, h[2] as f32)).collect();
            (0..ROWS)
                .flat_map(|j| (0..COLS).map(move |i| (i, j)))
                .map(|(i, j)| entry(light, node(i, j), alpha, &facets))
                .collect()
        })
    }

    /// `(sky, air)`: the lobe's mean minus the mirror direction's own radiance, around unit mirror direction `r`
    /// (above the horizon) on water of roughness `alpha`, read linearly in the grid and between levels.
    pub fn correction(&self, light: &Lighting, r: Vec3, alpha: f32) -> (Vec3, Vec3) {
        // (NaN reads as calm water: `max` takes the other operand.)
        let a = (alpha.max(0.0) / ALPHA_STEP).min(LEVELS as f32);
        if a <= 0.0 {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        // Between levels `l` and `l + 1` of the sequence 0, 1/16, ..., 1/2 (level 0 is all zeros, not stored;
        // level `l` is stored at `l - 1`).
        let l = (a as usize).min(LEVELS);
        let f = a - l as f32;
        let (i0, i1, fx) = columns(COLS, diamond(r.x, r.y) / 4.0 * COLS as f32 - 0.5);
        let y = r.z.clamp(0.0, 1.0).sqrt() * (ROWS - 1) as f32;
        let j0 = (y as usize).min(ROWS - 2);
        let fy = y - j0 as f32;
        let read = |grid: &[Entry], c: usize| -> Vec3 {
            let at = |i: usize, j: usize| grid[j * COLS + i][c];
            let lo = at(i0, j0) * (1.0 - fx) + at(i1, j0) * fx;
            let hi = at(i0, j0 + 1) * (1.0 - fx) + at(i1, j0 + 1) * fx;
            lo * (1.0 - fy) + hi * fy
        };
        let (mut sky, mut air) = (Vec3::ZERO, Vec3::ZERO);
        if l >= 1 {
            let lower = self.level(light, l - 1);
            sky += read(lower, 0) * (1.0 - f);
            air += read(lower, 1) * (1.0 - f);
        }
        if l < LEVELS && f > 0.0 {
            let upper = self.level(light, l);
            sky += read(upper, 0) * f;
            air += read(upper, 1) * f;
        }
        (sky, air)
    }
}

#[cfg(test)]
mod tests {
    use super::super::envlight::LightingKey;
    use super::*;

    fn lighting(sun_elevation_deg: f32, sun_azimuth_deg: f32) -> Lighting {
        let (e, a) = (sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians());
        Lighting::new(&LightingKey {
            sun: [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()],
            turbidity: 3.0,
            cloud: 0.0,
            ground_albedo: 0.06,
        })
    }

    /// The lobe's mean of the sky by a fine quadrature in spherical coordinates of the half vector (the
    /// definition, independent of the facet sampling): `Σ F D G₁(ω_i) (ω_o·h) / μ_o · sin θ_h` over a polar grid.
    fn reference(light: &Lighting, r: Vec3, alpha: f64) -> Vec3 {
        let o = Vec3::new(-r.x, -r.y, r.z);
        let (nt, np) = (600, 720);
        let t_max = (8.0 * alpha).atan().min(1.5);
        let (mut acc, mut wsum) = (Vec3::ZERO, 0.0f64);
        for a in 0..nt {
            let t = (a as f64 + 0.5) / nt as f64 * t_max;
            let d =
                (-(t.tan().powi(2)) / (alpha * alpha)).exp() / (std::f64::consts::PI * alpha * alpha * t.cos().powi(4));
            for b in 0..np {
                let p = (b as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                let h = Vec3::new((t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32);
                let c = o.dot(h);
                let i = h * (2.0 * c) - o;
                if c <= 0.0 || i.z <= 0.0 {
                    continue;
                }
                let w = f64::from(fresnel_dielectric(c, WATER_IOR))
                    * d
                    * smith_g1(f64::from(i.z), alpha)
                    * f64::from(c)
                    * t.sin();
                acc += light.sky_radiance(i.normalize()) * w as f32;
                wsum += w;
            }
        }
        acc / wsum as f32
    }

    #[test]
    fn the_table_is_the_lobe_mean_of_the_sky() {
        // Nodes of a level (the quadrature alone) and points between nodes and levels (with the table's
        // interpolation), against the definition: within 2 % per channel (measured in the test's message).
        let light = lighting(40.0, 160.0);
        let lobe = SkyLobe::default();
        let mut worst = 0.0f32;
        for (az, el, alpha) in [
            (0.0f32, 3.0f32, 0.125f32),
            (200.0, 10.0, 0.25),
            (90.0, 45.0, 0.1875),
            (300.0, 80.0, 0.3125),
            (17.0, 23.0, 0.21),
            (123.0, 1.5, 0.15),
            (250.0, 60.0, 0.4),
            (10.0, 89.0, 0.09),
        ] {
            let (a, e) = (az.to_radians(), el.to_radians());
            let r = Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
            let (sky, _) = lobe.correction(&light, r, alpha);
            let got = light.sky_radiance(r) + sky;
            let want = reference(&light, r, f64::from(alpha));
            let err = ((got - want) / want).abs().max_element();
            worst = worst.max(err);
            assert!(err < 0.02, "az {az} el {el} α {alpha}: {got:?} against {want:?}");
        }
        eprintln!("worst relative error {worst}");
        assert!(worst > 0.0);
    }

    #[test]
    fn calm_water_reads_the_mirror_and_rougher_water_spreads_more() {
        let light = lighting(30.0, 0.0);
        let lobe = SkyLobe::default();
        let r = Vec3::new(-0.9, 0.1, 0.2).normalize();
        assert_eq!(lobe.correction(&light, r, 0.0), (Vec3::ZERO, Vec3::ZERO));
        assert!(lobe.levels.iter().all(|l| l.get().is_none()), "α = 0 builds nothing");
        // Looking down at the water, away from the sun (mirror 11.5° up the sky): the lobe leans up the sky (the
        // facets the camera sees tilt towards it), where the sky is darker, more so the rougher the sea.
        let small = lobe.correction(&light, r, 0.1).0.y;
        let large = lobe.correction(&light, r, 0.3).0.y;
        assert!(small < 0.0 && large < small, "{small} {large}");
        // Between levels, linear in α.
        let mid = lobe.correction(&light, r, 0.15625).0;
        let (lo, hi) = (lobe.correction(&light, r, 0.125).0, lobe.correction(&light, r, 0.1875).0);
        assert!(((lo + hi) * 0.5 - mid).abs().max_element() < 1e-3 * mid.abs().max_element().max(1.0));
    }
}
