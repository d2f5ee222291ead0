//! The foam on the water for cameras and the LiDAR: whitecaps and wakes ([`Foam`]).
//!
//! * **Whitecaps** at Monahan & O'Muircheartaigh's coverage `W` ([`super::water::monahan_coverage`], the
//!   fraction of the surface). The foam is placed by a seeded fractal noise thresholded at its own
//!   `(1 − W)` quantile, so the covered fraction is `W`. Over a wave surface whitecaps form where waves break,
//!   on and just behind the crests (E. C. Monahan, "Oceanic whitecaps", J. Phys. Oceanogr. 1(2), 1971): the
//!   noise is then biased by the local elevation `η/σ_η` (`σ_η` the sampled sea's own, `H_s/4`; the elevation of a linear random sea
//!   being Gaussian: M. S. Longuet-Higgins, "On the statistical distribution of the heights of sea waves",
//!   J. Mar. Res. 11, 1952), thresholded at the `(1 − W)` quantile of that sum (noise and a standard normal),
//!   so the coverage stays `W` while the foam gathers on the crests. Foam is Lambertian with albedo 0.55, the
//!   reflectance of fresh dense foam (P. Koepke, "Effective reflectance of oceanic whitecaps", Appl. Opt.
//!   23(11), 1984). A whitecap is not all fresh foam: its foam thins as it ages, and Koepke finds the
//!   *effective* reflectance of whitecaps, over their area and lifetime, to be 0.22 — 0.4 of fresh foam's. So
//!   within the covered area the foam's density rises from 0 at a patch's edge with the noise's excess over the
//!   threshold, linearly up to full over a band chosen (from the same sample as the threshold) so that the mean
//!   density over the covered area is 0.4: bright cores fading into thin foam, not flat white patches. Where
//!   the elevation is not known (the still level beyond the sampled sea) the noise meets its own threshold.
//! * **Wakes** of the vessels under way: `wake.rs` ([`Wake`]); their foam is broken up by the same noise.

use super::super::noise;
pub use super::wake::Wake;
use super::wake::Wakes;

/// Albedo of dense foam.
pub const FOAM_ALBEDO: f32 = 0.55;
/// The seed that places the foam every sensor sees: the cameras' whitecaps and wakes and the LiDAR's wake returns
/// are the same foam at the same point.
pub const FOAM_SEED: u64 = 0x5EA;
/// Koepke's effective reflectance of whitecaps (0.22) over fresh foam's: the mean foam density over the whitecaps'
/// area.
pub const WHITECAP_MEAN_DENSITY: f32 = 0.22 / 0.55;
/// Stream of the foam noise.
const FOAM_STREAM: u64 = 0xF0A;

/// Smooth value noise in `[0, 1]` at `(x, y)` on a unit lattice (hashed corners, smoothstep blend).
#[inline(always)]
fn value_noise(seed: u64, x: f32, y: f32) -> f32 {
    let (xf, yf) = (x.floor(), y.floor());
    let (ix, iy) = (xf as i64, yf as i64);
    let (fx, fy) = (x - xf, y - yf);
    let corner = |i: i64, j: i64| {
        let key = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        (noise::hash3(seed, FOAM_STREAM, key) >> 40) as f32 / (1u64 << 24) as f32
    };
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let a = corner(ix, iy) * (1.0 - sx) + corner(ix + 1, iy) * sx;
    let b = corner(ix, iy + 1) * (1.0 - sx) + corner(ix + 1, iy + 1) * sx;
    a * (1.0 - sy) + b * sy
}

/// Three octaves of value noise at world `(x, y)` metres, in `[0, 1]` (feature size ~6 m).
#[inline(always)]
pub fn foam_noise(seed: u64, x: f32, y: f32) -> f32 {
    let mut s = 0.0;
    let mut w = 0.5;
    let mut f = 1.0 / 6.0;
    for o in 0..3u64 {
        s += w * value_noise(seed ^ o, x * f + o as f32 * 17.3, y * f - o as f32 * 9.1);
        w *= 0.5;
        f *= 2.3;
    }
    s / 0.875
}

/// [`foam_noise`] (the same bits) where it may exceed `need`, octave by octave: `None` as soon as the octaves
/// still to come cannot lift it above `need` (each is in `[0, 1]` times its weight).
#[inline(always)]
fn foam_noise_over(seed: u64, x: f32, y: f32, need: f32) -> Option<f32> {
    let mut s = 0.0;
    let mut w = 0.5;
    let mut f = 1.0 / 6.0;
    let mut rest = 0.375f32;
    for o in 0..3u64 {
        s += w * value_noise(seed ^ o, x * f + o as f32 * 17.3, y * f - o as f32 * 9.1);
        w *= 0.5;
        f *= 2.3;
        if (s + rest) / 0.875 <= need {
            return None;
        }
        rest -= w;
    }
    Some(s / 0.875)
}

/// Weight of the normalised elevation `η/σ_η` added to the foam noise (range `[0, 1]`, standard deviation
/// about 0.1) over a wave surface: enough to gather the whitecaps on the crests, not to paint every crest.
pub const CREST_WEIGHT: f32 = 0.12;

/// The `(1 − coverage)` quantile of the foam noise (plus [`CREST_WEIGHT`] times a standard normal, the
/// normalised elevation, with `crests`), from a fixed sample of it, and the band of noise over which the foam's
/// density rises from 0 to full so that its mean over the covered part of the sample is
/// [`WHITECAP_MEAN_DENSITY`] (cached per coverage, seed and `crests`: every render of a run asks for the same
/// ones).
fn foam_threshold(coverage: f32, seed: u64, crests: bool) -> (f32, f32) {
    type Key = (u32, u64, bool);
    static CACHE: std::sync::Mutex<Vec<(Key, (f32, f32))>> = std::sync::Mutex::new(Vec::new());
    let key = (coverage.to_bits(), seed, crests);
    if let Ok(c) = CACHE.lock() {
        if let Some(&(_, t)) = c.iter().find(|(k, _)| *k == key) {
            return t;
        }
    }
    let mut v: Vec<f32> = (0..16_384u64)
        .map(|i| {
            let x = noise::uniform(seed, FOAM_STREAM + 1, 2 * i) as f32 * 4000.0;
            let y = noise::uniform(seed, FOAM_STREAM + 1, 2 * i + 1) as f32 * 4000.0;
            let crest = if crests { CREST_WEIGHT * standard_normal(seed, i) } else { 0.0 };
            foam_noise(seed, x, y) + crest
        })
        .collect();
    v.sort_by(f32::total_cmp);
    let th = v[((1.0 - coverage) * (v.len() - 1) as f32).round() as usize];
    let excess: Vec<f32> = v.iter().filter(|&&n| n > th).map(|&n| n - th).collect();
    let t = (th, density_band(&excess, WHITECAP_MEAN_DENSITY));
    if let Ok(mut c) = CACHE.lock() {
        if c.len() >= 16 {
            c.remove(0);
        }
        c.push((key, t));
    }
    t
}

/// The band `b` for which the mean of `min(1, e / b)` over the excesses `e > 0` is `mean` (past the widest
/// excess the mean is `mean(e) / b`, in closed form; below it, bisection; a tiny band without excesses).
fn density_band(excess: &[f32], mean: f32) -> f32 {
    let Some(&widest) = excess.iter().max_by(|a, b| a.total_cmp(b)) else { return 1e-3 };
    let mean_at = |b: f32| excess.iter().map(|&e| (e / b).min(1.0)).sum::<f32>() / excess.len() as f32;
    let (mut lo, mut hi) = (1e-6f32, widest.max(1e-6));
    if mean_at(hi) >= mean {
        return excess.iter().sum::<f32>() / excess.len() as f32 / mean;
    }
    // The mean falls as the band widens.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mean_at(mid) > mean {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A seeded standard normal deviate (Box–Muller), the `i`-th of the foam's threshold sample.
pub(super) fn standard_normal(seed: u64, i: u64) -> f32 {
    let u1 = noise::uniform(seed, FOAM_STREAM + 2, 2 * i).max(1e-12);
    let u2 = noise::uniform(seed, FOAM_STREAM + 2, 2 * i + 1);
    ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
}

/// The threshold that no noise value reaches, crests included: no whitecaps.
const NO_WHITECAPS: f32 = 1e6;

/// The foam of one render: whitecaps at a coverage and the wakes of the vessels under way.
#[derive(Debug, Clone, Default)]
pub struct Foam {
    /// Noise level above which the surface is a whitecap (`> 1 + CREST_WEIGHT·8`: none).
    threshold: f32,
    /// Noise band over which a whitecap's foam density rises from 0 to full.
    band: f32,
    /// The whitecap coverage asked for.
    coverage: f32,
    /// Whether the threshold is that of the noise biased by the crests ([`Foam::on_crests`]).
    crests: bool,
    /// The threshold and band of the noise alone: where the elevation is not known (see [`Foam::cover`]).
    plain: (f32, f32),
    seed: u64,
    /// The wakes of the vessels under way.
    wakes: Wakes,
}

impl Foam {
    /// Foam for whitecap `coverage` in `[0, 1]` and `wakes`, placed by `seed`.
    pub fn new(coverage: f32, wakes: &[Wake], seed: u64) -> Self {
        let (threshold, band) =
            if coverage <= 0.0 { (NO_WHITECAPS, 1.0) } else { foam_threshold(coverage.min(1.0), seed, false) };
        Self { threshold, band, coverage, crests: false, plain: (threshold, band), seed, wakes: Wakes::new(wakes) }
    }

    /// This foam with its wakes indexed on a grid over the square of half-side `radius` metres around `centre`
    /// (a sensor's position, `radius` the reach of its water hits): a point there tries only the wakes that may
    /// lay foam in its cell (the same cover, to the bit: a wake left out gives none); points outside try every
    /// wake. Nothing changes with no wakes or a radius that is not a positive number.
    pub fn around(mut self, centre: [f32; 2], radius: f32) -> Self {
        self.wakes = std::mem::take(&mut self.wakes).around(centre, radius);
        self
    }

    /// This foam with its whitecaps gathered on the wave crests (see the module docs): [`Foam::cover`] is then
    /// given each point's normalised elevation `η/σ_η`.
    pub fn on_crests(mut self) -> Self {
        if self.threshold < NO_WHITECAPS {
            (self.threshold, self.band) = foam_threshold(self.coverage.min(1.0), self.seed, true);
        }
        self.crests = true;
        self
    }

    /// Whether there is any foam at all.
    pub fn is_empty(&self) -> bool {
        self.threshold >= NO_WHITECAPS && self.wakes.is_empty()
    }

    /// Foam cover (density) in `[0, 1]` at world point `(x, y)`, whose normalised elevation is `crest` (`η/σ_η`; read
    /// only [`Foam::on_crests`]). `None`: the elevation is not known there (the still level beyond a wave
    /// surface's sampled part, where the sea goes on unsampled): the noise alone against its own threshold, so
    /// the whitecaps keep Monahan's coverage there too (the crest-biased threshold, met by the noise alone,
    /// would cover less).
    #[inline(always)]
    pub fn cover(&self, x: f32, y: f32, crest: Option<f32>) -> f32 {
        let mut c = 0.0f32;
        let mut nz = None;
        let (threshold, band, lift) = match crest {
            Some(e) if self.crests => (self.threshold, self.band, CREST_WEIGHT * e),
            _ => (self.plain.0, self.plain.1, 0.0),
        };
        // The noise octave by octave, while it can still reach the threshold (a hundredth and a half of slack for
        // the bound's rounding).
        if threshold < NO_WHITECAPS {
            if let Some(n) = foam_noise_over(self.seed, x, y, threshold - 0.015 - lift) {
                nz = Some(n);
                // Thin at the edge, dense in the core (see the module docs).
                c = ((n + lift - threshold) / band).clamp(0.0, 1.0);
            }
        }
        let mut noise_at = || *nz.get_or_insert_with(|| foam_noise(self.seed, x, y));
        c.max(self.wakes.cover(x, y, &mut noise_at))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monahan's coverage is the area with foam; over it the foam's mean density is Koepke's effective
    /// reflectance over fresh foam's, and it rises from thin edges to dense cores.
    #[test]
    fn whitecap_cover_matches_coverage() {
        for cov in [0.01f32, 0.05, 0.2] {
            let foam = Foam::new(cov, &[], 7);
            let n = 200_000u64;
            let (mut s, mut covered, mut dense) = (0.0f64, 0u64, 0u64);
            for i in 0..n {
                let x = noise::uniform(99, 1, 2 * i) as f32 * 3000.0 - 1500.0;
                let y = noise::uniform(99, 1, 2 * i + 1) as f32 * 3000.0 - 1500.0;
                let c = foam.cover(x, y, None);
                s += c as f64;
                covered += u64::from(c > 0.0);
                dense += u64::from(c >= 1.0);
            }
            let got = covered as f64 / n as f64;
            assert!((got - cov as f64).abs() < 0.2 * cov as f64 + 0.002, "coverage {cov}: {got}");
            let density = s / covered as f64;
            assert!((density - 0.4).abs() < 0.04, "coverage {cov}: mean density {density}");
            // Some of it is full foam (the cores), most of it thinner.
            let core = dense as f64 / covered as f64;
            assert!(core > 0.02 && core < 0.4, "coverage {cov}: cores {core}");
        }
        assert!((density_band(&[0.1, 0.2, 0.3, 0.4], 0.5) - 0.5).abs() < 1e-4);
        assert!(Foam::new(0.0, &[], 1).is_empty());
        assert!(Foam::new(0.0, &[], 1).on_crests().is_empty());
    }

    /// On a wave surface the whitecaps keep Monahan's coverage over a Gaussian sea (the normalised elevation a
    /// standard normal, independent of the noise) and gather on the crests: the covered points' mean elevation
    /// is well above the mean, and troughs below −1 σ carry almost none.
    #[test]
    fn whitecaps_keep_their_coverage_and_gather_on_the_crests() {
        for cov in [0.01f32, 0.05, 0.2] {
            let foam = Foam::new(cov, &[], 7).on_crests();
            let n = 200_000u64;
            let (mut s, mut crest_sum, mut troughs, mut trough_n) = (0.0f64, 0.0f64, 0.0f64, 0u64);
            for i in 0..n {
                let x = noise::uniform(99, 1, 2 * i) as f32 * 3000.0 - 1500.0;
                let y = noise::uniform(99, 1, 2 * i + 1) as f32 * 3000.0 - 1500.0;
                let g = standard_normal(1234, i);
                let c = foam.cover(x, y, Some(g)) as f64;
                s += c;
                crest_sum += c * g as f64;
                if g < -1.0 {
                    troughs += c;
                    trough_n += 1;
                }
            }
            let got = s / n as f64 / f64::from(WHITECAP_MEAN_DENSITY);
            assert!((got - cov as f64).abs() < 0.2 * cov as f64 + 0.002, "coverage {cov}: {got}");
            let mean_crest = crest_sum / s;
            assert!(mean_crest > 0.7, "coverage {cov}: foam at a mean elevation of {mean_crest} σ");
            let trough_cover = troughs / trough_n as f64;
            assert!(trough_cover < 0.25 * cov as f64, "coverage {cov}: {trough_cover} in the troughs");
            // Where the elevation is not known (beyond the sampled sea) the noise alone keeps the coverage: met by
            // the crests' threshold it would cover far less.
            let (mut plain, mut biased) = (0.0f64, 0.0f64);
            for i in 0..n {
                let x = noise::uniform(98, 1, 2 * i) as f32 * 3000.0 - 1500.0;
                let y = noise::uniform(98, 1, 2 * i + 1) as f32 * 3000.0 - 1500.0;
                plain += f64::from(foam.cover(x, y, None));
                biased += f64::from(foam.cover(x, y, Some(0.0)));
            }
            let area = |v: f64| v / n as f64 / f64::from(WHITECAP_MEAN_DENSITY);
            let (plain, biased) = (area(plain), area(biased));
            assert!((plain - cov as f64).abs() < 0.2 * cov as f64 + 0.002, "coverage {cov}: {plain} unsampled");
            assert!(biased < 0.8 * cov as f64, "coverage {cov}: {biased} at the mean level");
        }
        // The normal deviates are normal: mean 0, variance 1.
        let g: Vec<f64> = (0..50_000).map(|i| f64::from(standard_normal(5, i))).collect();
        let mean = g.iter().sum::<f64>() / g.len() as f64;
        let var = g.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / g.len() as f64;
        assert!(mean.abs() < 0.02 && (var - 1.0).abs() < 0.03, "{mean} {var}");
    }

    /// The noise read octave by octave is the noise's own bits where it may exceed the bar, and gives up only on
    /// points the full noise leaves at or below it.
    #[test]
    fn noise_over_a_bar_is_the_noise() {
        let mut refused = 0;
        for i in 0..20_000u64 {
            let x = noise::uniform(5, 1, 2 * i) as f32 * 500.0 - 250.0;
            let y = noise::uniform(5, 1, 2 * i + 1) as f32 * 500.0 - 250.0;
            let n = foam_noise(9, x, y);
            for need in [0.3f32, 0.5, 0.6, 0.7, 0.8] {
                match foam_noise_over(9, x, y, need) {
                    Some(m) => assert_eq!(m.to_bits(), n.to_bits(), "{x}, {y}"),
                    None => {
                        assert!(n <= need + 1e-6, "{x}, {y}: {n} refused at {need}");
                        refused += 1;
                    }
                }
            }
        }
        assert!(refused > 20_000, "{refused}");
    }
}
