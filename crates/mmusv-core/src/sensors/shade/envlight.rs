//! Image-based lighting from the sky: the environment's radiance (the [`Sky`] above the horizon, a uniform
//! ground/sea below it) integrated once per environment into an irradiance map for Lambert surfaces and
//! GGX-prefiltered maps for glossy ones (the split sum of [`super::brdf`]).
//!
//! The source grids are cylindrical equal-area (columns uniform in azimuth, rows uniform in `z`), so every
//! texel has the same solid angle `4π / (W H)` and the integrals are plain sums. The output maps, and a dense
//! table of the sky's own radiance that the cameras read instead of evaluating the sky model per pixel, are
//! read bilinearly without trigonometry: columns uniform in the "diamond" pseudo-angle of the azimuth, rows
//! uniform in `(√(1 + z) − √(1 − z)) / √2` (nearly uniform in angle) with the poles as first and last rows (the
//! up and down normals, the commonest, are exact;
//! the sky table's rows follow `(√z + 1 − √(1 − z)) / 2`, dense in angle at the horizon and the zenith):
//! * irradiance `E(n) = Σ L(ω) max(0, n·ω) Δω`;
//! * prefiltered radiance `P(r, α) = Σ L(ω) w(ω) / Σ w(ω)` with the GGX lobe weight `w = D(h) (h·r) / (4 h·ω)
//!   · max(0, r·ω)` around the mirror direction `r` (Karis 2013's `n = v = r` assumption).
//!
//! The lower hemisphere's radiance is `a_g E_h / π`: the light a Lambert ground of albedo `a_g` under the
//! horizontal illuminance `E_h` reflects; for the sea `a_g` = 0.06, the sea-surface albedo under a high sun
//! (G. R. Payne, "Albedo of the Sea Surface", J. Atmos. Sci. 29, 1972).
//!
//! Built once per environment and kept in a small process-wide cache (every camera of a run shares it).

use super::brdf::{fresnel_dielectric, ggx_d};
use super::sky::{luminance, Sky};
use super::sky_lobe::SkyLobe;
use super::twilight;
use parry3d::math::Vec3;
use std::sync::{Arc, Mutex};

/// Source grid of the irradiance integral (azimuth × z).
const SRC_IRR: (usize, usize) = (128, 64);
/// Source grid of the prefiltered maps.
const SRC_PRE: (usize, usize) = (64, 32);
/// Output grid of every map.
const OUT: (usize, usize) = (32, 17);
/// Roughness of the prefiltered levels; below the first, the sky is read along the mirror direction.
pub const LEVELS: [f32; 5] = [0.2, 0.35, 0.5, 0.7, 1.0];
/// Roughness up to which a surface reads the sky directly along its mirror direction.
const MIRROR_UP_TO: f32 = 0.1;

/// Index of refraction of sea water.
pub const WATER_IOR: f32 = 1.33;

/// What the lighting depends on (the cache key).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightingKey {
    /// Unit vector towards the sun.
    pub sun: [f32; 3],
    /// Preetham turbidity.
    pub turbidity: f32,
    /// Cloud cover in `[0, 1]`.
    pub cloud: f32,
    /// Albedo of the lower hemisphere (the sea).
    pub ground_albedo: f32,
}

/// The sky and its precomputed environment lighting.
#[derive(Debug)]
pub struct Lighting {
    /// The sky and the sun.
    pub sky: Sky,
    /// Radiance of the lower hemisphere (linear RGB, cd/m²).
    pub ground: Vec3,
    /// Horizontal illuminance from the sky and the sun (lux, luminance of the RGB).
    pub horizontal_lux: f32,
    /// `∫ (1 − F_water(θ)) L(ω) cos θ dω` over the upper hemisphere for the normal `+z`: the sky light that enters
    /// a level water surface (linear RGB, lux).
    pub water_entering: Vec3,
    irradiance: Vec<Vec3>,
    prefiltered: Vec<Vec<Vec3>>,
    /// The sky's radiance (no sun disc) on the `SKY` grid.
    sky_table: Vec<Vec3>,
    /// What distant things fade into, per column of the `SKY` grid: the sky's radiance just above the horizon
    /// (elevation ~1.1°), in twilight blended into the haze in the Earth's shadow (`twilight::shadowed_haze`).
    horizon: Vec<Vec3>,
    /// The sky's means over the rough water's reflection lobes (`sky_lobe.rs`), built as they are first read.
    sky_lobe: SkyLobe,
}

/// Unit direction of the centre of texel `(i, j)` of a `w × h` equal-area grid.
fn texel_dir(i: usize, j: usize, w: usize, h: usize) -> Vec3 {
    let phi = (i as f32 + 0.5) / w as f32 * std::f32::consts::TAU - std::f32::consts::PI;
    let z = (j as f32 + 0.5) / h as f32 * 2.0 - 1.0;
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// The "diamond angle" of `(x, y)` in `[0, 4)`: a monotone stand-in for the azimuth (1 per quarter turn)
/// without trigonometry.
#[inline(always)]
pub(super) fn diamond(x: f32, y: f32) -> f32 {
    let s = x.abs() + y.abs();
    if s == 0.0 {
        return 0.0;
    }
    let p = if y >= 0.0 {
        if x >= 0.0 {
            y / s
        } else {
            1.0 - x / s
        }
    } else if x < 0.0 {
        2.0 - y / s
    } else {
        3.0 + x / s
    };
    if p >= 4.0 {
        0.0
    } else {
        p
    }
}

/// Unit horizontal `(x, y)` of diamond angle `p` in `[0, 4)`.
pub(super) fn diamond_dir(p: f32) -> (f32, f32) {
    let q = p.floor();
    let f = p - q;
    let (x, y) = match q as i32 {
        0 => (1.0 - f, f),
        1 => (-f, 1.0 - f),
        2 => (f - 1.0, -f),
        _ => (f, f - 1.0),
    };
    let n = (x * x + y * y).sqrt();
    (x / n, y / n)
}

/// Row parameter `t` in `[−1, 1]` of height `z` in the output grids: `(√(1 + z) − √(1 − z)) / √2`, whose rows
/// are at most √2 apart in angle anywhere (rows uniform in `z` would be 29° apart at the poles).
#[inline(always)]
fn row_of(z: f32) -> f32 {
    let z = z.clamp(-1.0, 1.0);
    ((1.0 + z).sqrt() - (1.0 - z).sqrt()) * std::f32::consts::FRAC_1_SQRT_2
}

/// Unit direction of node `(i, j)` of a `w × h` output grid (row 0 straight down, row `h − 1` straight up).
fn node_dir(i: usize, j: usize, w: usize, h: usize) -> Vec3 {
    let (x, y) = diamond_dir((i as f32 + 0.5) / w as f32 * 4.0);
    let t = j as f32 / (h - 1) as f32 * 2.0 - 1.0;
    // The inverse of `row_of`: z = t √(2 − t²).
    let z = (t * (2.0 - t * t).max(0.0).sqrt()).clamp(-1.0, 1.0);
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * x, s * y, z)
}

/// The two columns and the weight of the second for column coordinate `x` (wrapping) of a map `w` wide.
#[inline(always)]
pub(super) fn columns(w: usize, x: f32) -> (usize, usize, f32) {
    // floor without a call: x > -1 here (a column coordinate is at least -0.5); wrap without a modulo.
    let xi = (x + 1.0) as i32 - 1;
    let fx = x - xi as f32;
    let i0 = if xi < 0 { w - 1 } else { (xi as usize).min(w - 1) };
    let i1 = if i0 + 1 == w { 0 } else { i0 + 1 };
    (i0, i1, fx)
}

/// Bilinear read of a `w × h` map at the columns of [`columns`] and row coordinate `y` (clamped).
#[inline(always)]
fn bilinear_at(map: &[Vec3], w: usize, h: usize, (i0, i1, fx): (usize, usize, f32), y: f32) -> Vec3 {
    let y = y.clamp(0.0, (h - 1) as f32);
    let j0 = y as usize;
    let j1 = (j0 + 1).min(h - 1);
    let fy = y - j0 as f32;
    let a = map[j0 * w + i0] * (1.0 - fx) + map[j0 * w + i1] * fx;
    let b = map[j1 * w + i0] * (1.0 - fx) + map[j1 * w + i1] * fx;
    a * (1.0 - fy) + b * fy
}

/// Bilinear read of a `w × h` map at column coordinate `x` (wrapping) and row coordinate `y` (clamped).
#[inline(always)]
fn bilinear(map: &[Vec3], w: usize, h: usize, x: f32, y: f32) -> Vec3 {
    bilinear_at(map, w, h, columns(w, x), y)
}

/// Bilinear read of an `OUT`-sized map along unit direction `d`.
#[inline(always)]
fn read(map: &[Vec3], d: Vec3) -> Vec3 {
    let (w, h) = OUT;
    let x = diamond(d.x, d.y) / 4.0 * w as f32 - 0.5;
    let y = (row_of(d.z) + 1.0) * 0.5 * (h - 1) as f32;
    bilinear(map, w, h, x, y)
}

/// Size of the sky table (azimuth × rows over `√z` in `[0, 1]`) and of the horizon table.
const SKY: (usize, usize) = (512, 192);

/// Row parameter of height `z` in `[0, 1]` in the sky table: `(√z + 1 − √(1 − z)) / 2`, dense in angle both at
/// the horizon (`√z`) and at the zenith (`√(1 − z)` grows like the zenith angle).
#[inline(always)]
fn sky_row(z: f32) -> f32 {
    let z = z.clamp(0.0, 1.0);
    0.5 * (z.sqrt() + 1.0 - (1.0 - z).sqrt())
}

/// The `z` whose [`sky_row`] is `t` (bisection; the mapping is monotone).
fn sky_row_z(t: f32) -> f32 {
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if sky_row(mid) < t {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Sky radiance along unit direction `d` (`d.z` clamped to `[0, 1]`) from the `SKY` table.
#[inline(always)]
fn sky_read(table: &[Vec3], d: Vec3) -> Vec3 {
    let (w, h) = SKY;
    let x = diamond(d.x, d.y) / 4.0 * w as f32 - 0.5;
    let y = sky_row(d.z) * (h - 1) as f32;
    bilinear(table, w, h, x, y)
}

impl Lighting {
    /// Computes the lighting of `key` (tens of milliseconds; use [`Lighting::shared`]).
    pub fn new(key: &LightingKey) -> Self {
        let sky = Sky::new(Vec3::from_array(key.sun), key.turbidity, key.cloud);
        let sun_h = sky.sun_irradiance() * sky.sun.z.max(0.0);
        // Horizontal sky irradiance, from the upper half of the irradiance source grid.
        let (sw, sh) = SRC_IRR;
        let d_omega = 4.0 * std::f32::consts::PI / (sw * sh) as f32;
        let src: Vec<(Vec3, Vec3)> = (0..sh)
            .flat_map(|j| (0..sw).map(move |i| texel_dir(i, j, sw, sh)))
            .filter(|d| d.z > 0.0)
            .map(|d| (d, sky.radiance(d)))
            .collect();
        let sky_h: Vec3 = src.iter().map(|(d, l)| *l * d.z).sum::<Vec3>() * d_omega;
        let e_h = sky_h + sun_h;
        let ground = e_h * (key.ground_albedo / std::f32::consts::PI);
        let water_entering: Vec3 =
            src.iter().map(|(d, l)| *l * (d.z * (1.0 - fresnel_dielectric(d.z, WATER_IOR)))).sum::<Vec3>() * d_omega;
        let env = |d: Vec3| if d.z > 0.0 { sky.radiance(d) } else { ground };
        let (ow, oh) = OUT;
        // Irradiance: the upper hemisphere from the sky texels, the lower one from the uniform ground (its share
        // of a normal's cosine lobe in closed form: π (1 − n_z) / 2 for a uniform lower hemisphere).
        let mut irradiance = vec![Vec3::ZERO; ow * oh];
        for j in 0..oh {
            for i in 0..ow {
                let n = node_dir(i, j, ow, oh);
                let up: Vec3 = src.iter().map(|(d, l)| *l * n.dot(*d).max(0.0)).sum::<Vec3>() * d_omega;
                irradiance[j * ow + i] = up + ground_share(n) * ground;
            }
        }
        let (pw, ph) = SRC_PRE;
        let pre_src: Vec<(Vec3, Vec3)> =
            (0..ph).flat_map(|j| (0..pw).map(move |i| texel_dir(i, j, pw, ph))).map(|d| (d, env(d))).collect();
        let prefiltered = LEVELS
            .iter()
            .map(|&rough| {
                let alpha = rough * rough;
                let mut map = vec![Vec3::ZERO; ow * oh];
                for j in 0..oh {
                    for i in 0..ow {
                        let r = node_dir(i, j, ow, oh);
                        let (mut acc, mut wsum) = (Vec3::ZERO, 0.0f32);
                        for (d, l) in &pre_src {
                            let rd = r.dot(*d);
                            if rd <= 0.0 {
                                continue;
                            }
                            let hv = (r + *d).normalize_or_zero();
                            let hd = hv.dot(*d).max(1e-4);
                            let w = ggx_d(hv.dot(r), alpha) * hv.dot(r) / (4.0 * hd) * rd;
                            acc += *l * w;
                            wsum += w;
                        }
                        map[j * ow + i] = if wsum > 0.0 { acc / wsum } else { env(r) };
                    }
                }
                map
            })
            .collect();
        let (kw, kh) = SKY;
        let mut sky_table = vec![Vec3::ZERO; kw * kh];
        for j in 0..kh {
            let z = sky_row_z(j as f32 / (kh - 1) as f32);
            let s = (1.0 - z * z).max(0.0).sqrt();
            for i in 0..kw {
                let (x, y) = diamond_dir((i as f32 + 0.5) / kw as f32 * 4.0);
                sky_table[j * kw + i] = sky.radiance(Vec3::new(s * x, s * y, z));
            }
        }
        // What distant things fade into: the horizon sky at their azimuth, or in twilight the haze in the Earth's
        // shadow, lit by the sky alone (`twilight::shadowed_haze`).
        let shade_w = twilight::shadowed_haze_weight(sky.sun.z.clamp(-1.0, 1.0).asin());
        let haze = (shade_w > 0.0).then(|| {
            let mean = src.iter().map(|(_, l)| *l).sum::<Vec3>() * d_omega / std::f32::consts::TAU;
            twilight::shadowed_haze(mean)
        });
        let horizon = (0..kw)
            .map(|i| {
                let (x, y) = diamond_dir((i as f32 + 0.5) / kw as f32 * 4.0);
                let lit = sky.radiance(Vec3::new(x, y, 0.02).normalize());
                haze.map_or(lit, |air| lit * (1.0 - shade_w) + air * shade_w)
            })
            .collect();
        Self {
            sky,
            ground,
            horizontal_lux: luminance(e_h),
            water_entering,
            irradiance,
            prefiltered,
            sky_table,
            horizon,
            sky_lobe: SkyLobe::default(),
        }
    }

    /// The sky's radiance along unit `d` (no sun disc; below the horizon, the horizon's), read from a dense
    /// table of [`Sky::radiance`].
    #[inline(always)]
    pub fn sky_radiance(&self, d: Vec3) -> Vec3 {
        sky_read(&self.sky_table, d)
    }

    /// What distant things fade into along `d`'s azimuth: the sky's radiance just above the horizon there, or, with
    /// the sun a degree or more below the horizon, the haze in the Earth's shadow (the same at every azimuth).
    #[inline(always)]
    pub fn horizon_radiance(&self, d: Vec3) -> Vec3 {
        let (w, _) = SKY;
        let x = diamond(d.x, d.y) / 4.0 * w as f32 - 0.5;
        bilinear(&self.horizon, w, 1, x, 0.0)
    }

    /// [`Lighting::sky_radiance`] and [`Lighting::horizon_radiance`] along unit `d` at once (they share the
    /// azimuth's columns): the same values, for one azimuth computation instead of two.
    #[inline(always)]
    pub fn sky_and_horizon(&self, d: Vec3) -> (Vec3, Vec3) {
        let (w, h) = SKY;
        let cols = columns(w, diamond(d.x, d.y) / 4.0 * w as f32 - 0.5);
        let sky = bilinear_at(&self.sky_table, w, h, cols, sky_row(d.z) * (h - 1) as f32);
        (sky, bilinear_at(&self.horizon, w, 1, cols, 0.0))
    }

    /// The lighting of `key`, computed once per process and shared (a cache of the last few environments).
    pub fn shared(key: &LightingKey) -> Arc<Lighting> {
        static CACHE: Mutex<Vec<(LightingKey, Arc<Lighting>)>> = Mutex::new(Vec::new());
        if let Ok(cache) = CACHE.lock() {
            if let Some((_, l)) = cache.iter().find(|(k, _)| k == key) {
                return Arc::clone(l);
            }
        }
        let l = Arc::new(Lighting::new(key));
        if let Ok(mut cache) = CACHE.lock() {
            if cache.len() >= 8 {
                cache.remove(0);
            }
            cache.push((*key, Arc::clone(&l)));
        }
        l
    }

    /// `(sky, air)`: the means of [`Lighting::sky_radiance`] and [`Lighting::horizon_radiance`] over the
    /// single-scattering reflection lobe of level water of roughness `alpha` whose mirror direction is unit `r`,
    /// minus their values along `r` (`sky_lobe.rs`).
    #[inline]
    pub fn sky_lobe_correction(&self, r: Vec3, alpha: f32) -> (Vec3, Vec3) {
        self.sky_lobe.correction(self, r, alpha)
    }

    /// Radiance of the environment (sky above the horizon, ground below, no sun disc) along unit `d`.
    #[inline(always)]
    pub fn environment(&self, d: Vec3) -> Vec3 {
        if d.z > 0.0 {
            self.sky_radiance(d)
        } else {
            self.ground
        }
    }

    /// [`Lighting::environment`] along `d` (normalised here), plus the sun's disc when `sun_disc`.
    pub fn radiance_along(&self, d: [f32; 3], sun_disc: bool) -> [f32; 3] {
        let v = Vec3::from_array(d).normalize_or_zero();
        let disc = if sun_disc { self.sky.sun_disc(v) } else { Vec3::ZERO };
        (self.environment(v) + disc).to_array()
    }

    /// Irradiance (lux, linear RGB) on a surface with unit normal `n` from the sky and the ground (not the sun).
    #[inline(always)]
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        read(&self.irradiance, n)
    }

    /// The part of [`Lighting::irradiance`] that comes from the uniform ground below the horizon (lux, linear RGB).
    #[inline(always)]
    pub fn ground_irradiance(&self, n: Vec3) -> Vec3 {
        self.ground * ground_share(n)
    }

    /// GGX-prefiltered environment radiance around the mirror direction `r` for perceptual `roughness`.
    #[inline(always)]
    pub fn prefiltered(&self, r: Vec3, roughness: f32) -> Vec3 {
        if roughness <= MIRROR_UP_TO {
            return self.environment(r);
        }
        if roughness < LEVELS[0] {
            let f = (roughness - MIRROR_UP_TO) / (LEVELS[0] - MIRROR_UP_TO);
            return self.environment(r) * (1.0 - f) + read(&self.prefiltered[0], r) * f;
        }
        let k = LEVELS.iter().rposition(|&l| l <= roughness).unwrap_or(0);
        if k + 1 >= LEVELS.len() {
            return read(&self.prefiltered[k], r);
        }
        let f = (roughness - LEVELS[k]) / (LEVELS[k + 1] - LEVELS[k]);
        read(&self.prefiltered[k], r) * (1.0 - f) + read(&self.prefiltered[k + 1], r) * f
    }
}

/// `(1/π) ∫_{lower hemisphere} max(0, n·ω) dω` for unit `n`: the share of a cosine lobe that sees the ground,
/// `(1 − n_z) / 2`, times π.
#[inline(always)]
fn ground_share(n: Vec3) -> f32 {
    std::f32::consts::PI * (1.0 - n.z.clamp(-1.0, 1.0)) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(cloud: f32) -> LightingKey {
        LightingKey { sun: [0.5, 0.3, 0.81], turbidity: 3.0, cloud, ground_albedo: 0.06 }
    }

    #[test]
    fn uniform_sky_gives_pi_l_and_prefilter_keeps_it() {
        // A fully overcast sky under a zenith sun is not uniform, so test the integrals on their own closed
        // form: irradiance of the up normal equals the horizontal sky illuminance.
        let l = Lighting::new(&key(0.0));
        let e_up = luminance(l.irradiance(Vec3::Z));
        let sun_h = luminance(l.sky.sun_irradiance()) * l.sky.sun.z;
        assert!(
            (e_up + sun_h - l.horizontal_lux).abs() / l.horizontal_lux < 0.02,
            "{e_up} {sun_h} {}",
            l.horizontal_lux
        );
        // A downward normal sees only the ground: π L_g.
        let down = l.irradiance(-Vec3::Z);
        assert!((luminance(down) - std::f32::consts::PI * luminance(l.ground)).abs() < 0.02 * luminance(down));
        // The roughest prefiltered map straight down sees only the uniform ground.
        let p = l.prefiltered(-Vec3::Z, 1.0);
        assert!((luminance(p) - luminance(l.ground)).abs() < 0.1 * luminance(l.ground), "{p} {}", l.ground);
    }

    #[test]
    fn irradiance_matches_a_dense_integral() {
        let l = Lighting::new(&key(0.1));
        for n in [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.3, -0.4, 0.866).normalize(), Vec3::new(-0.7, 0.7, 0.1)] {
            let n = n.normalize();
            let (nt, np) = (400, 400);
            let mut e = Vec3::ZERO;
            for i in 0..nt {
                let z = (i as f32 + 0.5) / nt as f32 * 2.0 - 1.0;
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    let s = (1.0 - z * z).sqrt();
                    let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
                    e += l.environment(d) * n.dot(d).max(0.0);
                }
            }
            e *= 4.0 * std::f32::consts::PI / (nt * np) as f32;
            let got = l.irradiance(n);
            assert!((luminance(got) - luminance(e)).abs() < 0.03 * luminance(e), "n {n}: {got} vs {e}");
        }
    }

    #[test]
    fn sky_table_matches_the_model() {
        let l = Lighting::new(&key(0.1));
        let mut worst = 0.0f32;
        for i in 0..2000 {
            let a = i as f32 * 0.7311;
            let z = ((i as f32 * 0.37).sin() * 0.5 + 0.5).max(0.001);
            let s = (1.0 - z * z).sqrt();
            let d = Vec3::new(s * a.cos(), s * a.sin(), z);
            let want = l.sky.radiance(d);
            let got = l.sky_radiance(d);
            let e = (luminance(got) - luminance(want)).abs() / luminance(want);
            worst = worst.max(e);
        }
        assert!(worst < 0.01, "worst relative error {worst}");
        for p in [0.0f32, 0.3, 1.0, 1.7, 2.5, 3.9] {
            let (x, y) = diamond_dir(p);
            assert!((diamond(x, y) - p).abs() < 1e-5, "{p}");
        }
    }

    #[test]
    fn shared_is_cached() {
        let a = Lighting::shared(&key(0.3));
        let b = Lighting::shared(&key(0.3));
        assert!(Arc::ptr_eq(&a, &b));
    }

    #[test]
    fn distant_things_fade_into_the_horizon_by_day_and_into_shadowed_haze_in_twilight() {
        let at = |deg: f32| {
            let h = deg.to_radians();
            LightingKey {
                sun: [h.cos() * 0.6, h.cos() * 0.8, h.sin()],
                turbidity: 3.0,
                cloud: 0.0,
                ground_albedo: 0.06,
            }
        };
        // By day: the sky just over the horizon at the view's azimuth.
        let day = Lighting::new(&at(10.0));
        for d in [Vec3::new(0.6, 0.8, 0.0), Vec3::new(-1.0, 0.2, 0.0).normalize()] {
            let want = day.sky.radiance(Vec3::new(d.x, d.y, 0.02).normalize());
            assert!((day.horizon_radiance(d) - want).length() < 0.02 * want.length());
        }
        // Sun 3° down: the same for every azimuth, 0.9 / 2 of the sky's mean radiance over the upper hemisphere
        // (integrated here on its own grid, uniform in zenith angle).
        let dusk = Lighting::new(&at(-3.0));
        let (n_t, n_p) = (200, 96);
        let mut sum = Vec3::ZERO;
        for i in 0..n_t {
            let th = (i as f32 + 0.5) / n_t as f32 * std::f32::consts::FRAC_PI_2;
            for j in 0..n_p {
                let ph = (j as f32 + 0.5) / n_p as f32 * std::f32::consts::TAU;
                let d = Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                sum += dusk.sky.radiance(d) * th.sin();
            }
        }
        let mean = sum * (std::f32::consts::FRAC_PI_2 / n_t as f32 * std::f32::consts::TAU / n_p as f32)
            / std::f32::consts::TAU;
        let want = mean * 0.45;
        for d in [Vec3::new(0.6, 0.8, 0.0), Vec3::new(-1.0, 0.2, 0.0).normalize(), Vec3::new(0.0, -1.0, 0.0)] {
            let got = dusk.horizon_radiance(d);
            assert!((got - want).length() < 0.02 * want.length(), "{d}: {got} vs {want}");
        }
        // The glow over the sunward horizon is far brighter than the haze in the shadow.
        let glow = dusk.sky.radiance(Vec3::new(0.6, 0.8, 0.03).normalize());
        assert!(luminance(glow) > 3.0 * luminance(want), "{glow} vs {want}");
    }
}
