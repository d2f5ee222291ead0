//! The foam a breaking crest leaves behind as it moves on: where whitecaps are looked for at a point, and the
//! threshold and density band that keep their coverage Monahan's (`water.rs`'s [`super::water::Foam`] draws them).
//!
//! **Model.** A whitecap has two stages (E. C. Monahan & M. Lu, "Acoustically relevant bubble assemblages and
//! their dependence on meteorological parameters", IEEE J. Oceanic Eng. 15(4), 1990): the active crest (stage A)
//! and the patch of foam it leaves on the water (stage B), which stays where it formed while the crest travels on,
//! and fades. The patch's decay is close to exponential, `A(t) = A₀ e^{−t/τ}`, with `τ` from 0.5 to 8 s at sea
//! (A. H. Callaghan, G. B. Deane & M. D. Stokes, "Observed variation in the decay time of oceanic whitecap foam",
//! J. Geophys. Res. 117, C09015, 2012); here `τ` = [`FOAM_DECAY_S`] (3 s) thins the patch's density (foam thinning
//! as it ages: P. Koepke, Appl. Opt. 23(11), 1984).
//!
//! So the foam at a point is the densest of the foam its crest gives now and the foam crests left there
//! [`FOAM_AGES_S`] ago, each thinned by `e^{−age/τ}`. Where the crests were is read from the present surface: the
//! elevation `v · age` ahead along the crest velocity `v` ([`crate::sea::WaveSurface::crest_velocity`]) stands for
//! the past elevation at the point (correlation 0.92, 0.83, 0.64 after 1, 2, 4 s at W3,
//! [`crate::sea::WaveSurface::crest_recall`]). The coverage — the area with any foam — stays Monahan's `W`: the
//! threshold is the `(1 − W)` quantile of `noise + w · max_k e_k` over a sample in which the normalised
//! elevations `e_0..e_K` (now, and at the points read for each age) are correlated normals with the sea's own
//! elevation correlations at those lags ([`crate::sea::WaveSurface::elevation_correlation`]); and the density
//! band keeps the mean density over the covered area at Koepke's 0.4 of fresh foam, old patches included.

use super::water::CREST_WEIGHT;
use crate::sea::WaveSurface;

/// e-folding time of the foam a crest leaves behind, seconds (within the 0.5–8 s Callaghan et al. observed).
pub const FOAM_DECAY_S: f32 = 3.0;
/// Ages at which the foam crests left is looked for, seconds (ascending).
pub const FOAM_AGES_S: [f32; 3] = [1.0, 2.0, 4.0];
/// Normalised elevations the foam reads at a point: now and at each of [`FOAM_AGES_S`].
pub const READS: usize = 1 + FOAM_AGES_S.len();

/// The density left of a patch of each age of [`FOAM_AGES_S`]: `e^{−age/τ}` (decreasing).
pub fn decay() -> [f32; READS - 1] {
    FOAM_AGES_S.map(|a| (-a / FOAM_DECAY_S).exp())
}

/// Where a sea's crests were, as the foam reads it: their velocity, and the correlations between the normalised
/// elevations it reads (now at the point, and `v · age` ahead for each age).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrestTrail {
    /// Crest velocity, world `x, y`, m/s.
    pub velocity: [f32; 2],
    /// Correlation matrix of the reads (symmetric, unit diagonal).
    pub corr: [[f32; READS]; READS],
}

impl CrestTrail {
    /// The trail of the waves `surface` was sampled from; `None` without waves.
    pub fn of(surface: &WaveSurface) -> Option<Self> {
        let velocity = surface.crest_velocity()?;
        let lag = |k: usize| if k == 0 { 0.0 } else { FOAM_AGES_S[k - 1] };
        let mut corr = [[1.0f32; READS]; READS];
        for (j, row) in corr.iter_mut().enumerate() {
            for (k, c) in row.iter_mut().enumerate() {
                if j != k {
                    let d = lag(k) - lag(j);
                    *c = surface.elevation_correlation([velocity[0] * d, velocity[1] * d])?;
                }
            }
        }
        Some(Self { velocity, corr })
    }

    /// The lower Cholesky factor of [`CrestTrail::corr`] (in `f64`; a tiny ridge keeps a nearly singular matrix,
    /// a sea whose reads are almost the same, factorable).
    fn cholesky(&self) -> [[f64; READS]; READS] {
        let mut l = [[0f64; READS]; READS];
        for i in 0..READS {
            for j in 0..=i {
                let mut s = f64::from(self.corr[i][j]) + if i == j { 1e-9 } else { 0.0 };
                for k in 0..j {
                    s -= l[i][k] * l[j][k];
                }
                l[i][j] = if i == j {
                    s.max(0.0).sqrt()
                } else if l[j][j] > 0.0 {
                    s / l[j][j]
                } else {
                    0.0
                };
            }
        }
        l
    }

    /// A map of independent standard normals `z` to reads correlated as [`CrestTrail::corr`] says.
    pub fn correlator(&self) -> impl Fn([f32; READS]) -> [f32; READS] {
        let l = self.cholesky();
        move |z| std::array::from_fn(|i| (0..=i).map(|k| l[i][k] * f64::from(z[k])).sum::<f64>() as f32)
    }
}

/// The foam density at a point whose noise is `n`, given the threshold and density band and the normalised
/// elevations `e` it reads (`None`: not known there): the densest of the present crest's foam and each age's,
/// thinned by [`decay`]. The same function draws the foam and calibrates it.
#[inline]
pub fn trail_density(n: f32, threshold: f32, band: f32, e: impl Fn(usize) -> Option<f32>) -> f32 {
    let at = |x: f32| ((n + CREST_WEIGHT * x - threshold) / band).clamp(0.0, 1.0);
    let mut c = e(0).map_or(0.0, at);
    for (k, d) in decay().into_iter().enumerate() {
        if d <= c {
            break; // an older patch is thinner than what is there already
        }
        if let Some(x) = e(k + 1) {
            c = c.max(d * at(x));
        }
    }
    c
}

/// The band `b` for which the mean of [`trail_density`] over the covered points of a sample (noise `n` and reads
/// `e` per point, all covered at `threshold`) is `mean`, by bisection (the mean falls as the band widens).
pub fn trail_band(covered: &[(f32, [f32; READS])], threshold: f32, mean: f32) -> f32 {
    if covered.is_empty() {
        return 1e-3;
    }
    let mean_at = |b: f32| {
        covered.iter().map(|(n, e)| f64::from(trail_density(*n, threshold, b, |k| Some(e[k])))).sum::<f64>()
            / covered.len() as f64
    };
    let (mut lo, mut hi) = (1e-6f32, 4.0f32);
    if mean_at(lo) <= f64::from(mean) {
        return lo;
    }
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if mean_at(mid) > f64::from(mean) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::super::water::{standard_normal, Foam, WHITECAP_MEAN_DENSITY};
    use super::*;
    use crate::ocean::{paper_sea_states, WaveField};
    use crate::sea::SurfaceSpec;
    use crate::sensors::noise;

    /// The trail of a W3 sea (waves towards +x).
    fn w3_trail() -> CrestTrail {
        let f = WaveField::new(&paper_sea_states()[3].spec(0.0, 10.0), 5).unwrap_or_else(|e| unreachable!("{e}"));
        let s = WaveSurface::new(f.components(), 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
        CrestTrail::of(&s).unwrap_or_else(|| unreachable!("waves"))
    }

    /// Coverage, mean density over the covered area, and the covered share below the mean level, of `foam`
    /// over 200,000 points whose reads are drawn as the sea's (correlated by `trail`, a sample of its own).
    fn stats(foam: &Foam, trail: &CrestTrail, with_past: bool) -> (f64, f64, f64) {
        let correlate = trail.correlator();
        let (n, mut sum, mut covered, mut low) = (200_000u64, 0f64, 0u64, 0u64);
        for i in 0..n {
            let x = noise::uniform(77, 1, 2 * i) as f32 * 3000.0 - 1500.0;
            let y = noise::uniform(77, 1, 2 * i + 1) as f32 * 3000.0 - 1500.0;
            let e = correlate(std::array::from_fn(|k| standard_normal(4321, READS as u64 * i + k as u64)));
            let v = trail.velocity;
            let past = |dx: f32, dy: f32| {
                let k = FOAM_AGES_S.iter().position(|a| (v[0] * a - dx).abs() + (v[1] * a - dy).abs() < 1e-3)?;
                with_past.then_some(e[k + 1])
            };
            let c = foam.cover(x, y, Some(e[0]), past);
            sum += f64::from(c);
            covered += u64::from(c > 0.0);
            low += u64::from(c > 0.0 && e[0] < 0.0);
        }
        (covered as f64 / n as f64, sum / covered as f64, low as f64 / covered as f64)
    }

    /// With the foam crests left behind, the whitecaps keep Monahan's coverage and Koepke's mean density, and
    /// a large share of them lies off the crests (below the mean level, where a crest passed seconds ago), against
    /// almost none without.
    #[test]
    fn the_trail_keeps_the_coverage_and_leaves_foam_behind_the_crests() {
        let trail = w3_trail();
        // The W3 reads: the read 1 s ahead correlates with the present one as the sea does 12 m apart.
        assert!(trail.corr[0][1] > 0.5 && trail.corr[0][1] < 0.99 && trail.corr[0][3] < trail.corr[0][1]);
        for cov in [0.01f32, 0.05] {
            let crests = Foam::new(cov, &[], 7).on_crests();
            let trailed = Foam::new(cov, &[], 7).with_trail(trail, 8.0);
            let (c0, d0, low0) = stats(&crests, &trail, false);
            let (c1, d1, low1) = stats(&trailed, &trail, true);
            for (c, d) in [(c0, d0), (c1, d1)] {
                assert!((c - f64::from(cov)).abs() < 0.2 * f64::from(cov) + 0.002, "coverage {cov}: {c}");
                assert!((d - f64::from(WHITECAP_MEAN_DENSITY)).abs() < 0.04, "coverage {cov}: density {d}");
            }
            assert!(low0 < 0.1 && low1 > 0.25, "coverage {cov}: below the mean level {low0} → {low1}");
        }
    }

    /// A patch left by a crest thins with its age: a point in a trough now, on a crest 1 s or 4 s ago, has at
    /// most `e^{−1/3}` or `e^{−4/3}` of fresh foam.
    #[test]
    fn old_patches_are_thinner() {
        let d = decay();
        assert!((d[0] - (-1.0f32 / 3.0).exp()).abs() < 1e-6 && (d[2] - (-4.0f32 / 3.0).exp()).abs() < 1e-6);
        let (th, band) = (0.6, 0.05);
        let trough = -3.0;
        let read = |hot: usize| {
            move |k: usize| {
                Some(if k == 0 {
                    trough
                } else if k == hot {
                    4.0
                } else {
                    -3.0
                })
            }
        };
        assert_eq!(trail_density(0.7, th, band, read(1)), d[0]);
        assert_eq!(trail_density(0.7, th, band, read(3)), d[2]);
        assert_eq!(trail_density(0.7, th, band, |_| Some(trough)), 0.0);
        // A fresh crest wins over an old patch.
        assert_eq!(trail_density(0.7, th, band, |k| Some(if k < 2 { 4.0 } else { trough })), 1.0);
        // Unknown reads add nothing.
        assert_eq!(trail_density(0.7, th, band, |k| (k == 0).then_some(trough)), 0.0);
    }

    /// The correlated reads have the trail's correlations.
    #[test]
    fn correlator_gives_the_trails_correlations() {
        let trail = w3_trail();
        let correlate = trail.correlator();
        let n = 50_000u64;
        let mut acc = [[0f64; READS]; READS];
        for i in 0..n {
            let e = correlate(std::array::from_fn(|k| standard_normal(99, READS as u64 * i + k as u64)));
            for j in 0..READS {
                for k in 0..READS {
                    acc[j][k] += f64::from(e[j] * e[k]) / n as f64;
                }
            }
        }
        for j in 0..READS {
            for k in 0..READS {
                assert!((acc[j][k] - f64::from(trail.corr[j][k])).abs() < 0.02, "{j},{k}: {}", acc[j][k]);
            }
        }
    }
}
