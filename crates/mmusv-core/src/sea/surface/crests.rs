//! Where the crests of the sampled sea were a moment ago: the velocity that carries the present elevation back in
//! time, and the correlation of the elevation between two points (what the whitecaps' decaying foam needs to know,
//! `sensors/shade/water.rs`).
//!
//! Model: the linear random sea `η(x, t) = Σ a cos(k·x − ω t + φ)` (the components the surface was sampled from).
//! * **Crest velocity**: the variance-weighted mean of the components' phase velocities,
//!   `v = Σ (a²/2) (ω/k) k̂ / Σ (a²/2)` (a single wave's phase velocity; for a directional sea the peak waves',
//!   which carry most of the elevation, along the mean direction). The present elevation `v τ` ahead stands for the
//!   past one at a point: `η(x, t − τ) ≈ η(x + v τ, t)`. A real sea's crest pattern is not carried rigidly (the
//!   components disperse), so this is an approximation whose quality is the correlation
//!   `Σ (a²/2) cos((k·v − ω) τ) / Σ (a²/2)` between the two ([`WaveSurface::crest_recall`]; at W3, 0.92 after 1 s,
//!   0.83 after 2 s, 0.64 after 4 s, tested against the field's sample correlations). Over lags of seconds it
//!   recalls better than 30 % slower or faster velocities (a least-squares fit for infinitesimal lags would be
//!   pulled down by the short waves, which decorrelate within a second anyway).
//! * **Elevation correlation** at a horizontal lag `r`: `ρ(r) = Σ (a²/2) cos(k·r) / Σ (a²/2)`, the
//!   normalised autocovariance of a Gaussian random-phase sea (M. S. Longuet-Higgins, "The statistical analysis of
//!   a random, moving surface", Phil. Trans. R. Soc. A 249, 1957).
//!
//! Checked in the parent's tests against a single wave (the phase velocity, a cosine correlation) and against
//! sample statistics of the summed field.

use super::WaveSurface;

impl WaveSurface {
    /// The crest velocity (world `x, y`, m/s) of the waves the surface was sampled from (see the module docs);
    /// `None` without waves.
    pub fn crest_velocity(&self) -> Option<[f32; 2]> {
        let vx = self.variance_weighted(|c| c.omega_rad_s / c.k_rad_m * c.direction_rad.cos())?;
        let vy = self.variance_weighted(|c| c.omega_rad_s / c.k_rad_m * c.direction_rad.sin())?;
        Some([vx, vy])
    }

    /// The standard deviation of the elevation, metres: `√(Σ a²/2)`, `H_s / 4` of the sea the components realise
    /// (0 without waves).
    #[inline]
    pub fn elevation_std(&self) -> f32 {
        self.elevation_std
    }

    /// The correlation of the elevation between two points `r` (metres, world `x, y`) apart at one time (see the
    /// module docs): 1 at `r = 0`; `None` without waves.
    pub fn elevation_correlation(&self, r: [f32; 2]) -> Option<f32> {
        self.variance_weighted(|c| (c.kx * f64::from(r[0]) + c.ky * f64::from(r[1])).cos())
    }

    /// The correlation between the elevation at a point `lag_s` seconds ago and the present one `v · lag_s`
    /// further along the crest velocity `v` ([`WaveSurface::crest_velocity`]): how well the present surface
    /// recalls where the crests were; `None` without waves.
    pub fn crest_recall(&self, lag_s: f32) -> Option<f32> {
        let v = self.crest_velocity()?;
        let t = f64::from(lag_s);
        self.variance_weighted(|c| ((c.kx * f64::from(v[0]) + c.ky * f64::from(v[1]) - c.omega_rad_s) * t).cos())
    }

    /// `Σ (a²/2) f(c) / Σ (a²/2)` over the components, `None` without any.
    fn variance_weighted(&self, f: impl Fn(&crate::ocean::WaveComponent) -> f64) -> Option<f32> {
        let (mut num, mut den) = (0f64, 0f64);
        for c in &self.components {
            let w = 0.5 * c.amplitude_m * c.amplitude_m;
            num += w * f(c);
            den += w;
        }
        (den > 0.0).then(|| (num / den) as f32)
    }
}
