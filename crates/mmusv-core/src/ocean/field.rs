//! The sea surface as a deterministic, seeded sum of linear deep-water waves (a random-phase realisation of a
//! directional JONSWAP spectrum).
//!
//! Model: first-order (Airy) linear wave theory in deep water, superposed (e.g. Faltinsen, O. M. (1990),
//! "Sea Loads on Ships and Offshore Structures", ch. 2; DNV-RP-C205 §3.2 and §3.5.8 for the random-phase
//! realisation of a spectrum). For components `i` with amplitude `aᵢ`, angular frequency `ωᵢ`, wavenumber
//! `kᵢ = ωᵢ²/g`, travel direction `θᵢ` and phase `φᵢ`:
//!
//! ```text
//! ψᵢ(x, y, t) = kᵢ (x cos θᵢ + y sin θᵢ) − ωᵢ t + φᵢ
//! η           = Σ aᵢ cos ψᵢ                                    (m, z up, mean level 0)
//! ∂η/∂x       = −Σ aᵢ kᵢ cos θᵢ sin ψᵢ,  ∂η/∂y = −Σ aᵢ kᵢ sin θᵢ sin ψᵢ
//! u, v        =  Σ aᵢ ωᵢ e^{kᵢ z} cos ψᵢ (cos θᵢ, sin θᵢ),  w = Σ aᵢ ωᵢ e^{kᵢ z} sin ψᵢ
//! ```
//!
//! Above the mean level (z > 0) the velocities are those at z = 0 (constant extension, a common stand-in for
//! Wheeler stretching).
//!
//! Sampling ([`WaveField::with_components`], `N` components, default [`DEFAULT_COMPONENTS`]):
//! - **Frequencies, stratified half by energy, half by log-frequency.** The `N` bins are equal-probability bins
//!   of the mixture `P(ω) = ½ F(ω) + ½ ln(ω/ω₀)/ln(ω₁/ω₀)` (clamped to [0, 1]), `F` the spectrum's cumulative
//!   variance, `[ω₀, ω₁] = [`[`LOG_BAND`]`]·ωp`: half the bins follow the energy (the peak), half cover the
//!   flanks evenly in log-frequency, so long waves (big ships' heave), short waves (slopes) and small craft's
//!   roll resonance are all sampled. Component `i` carries the variance of its whole bin,
//!   `aᵢ² = 2 m0 (F(eᵢ₊₁) − F(eᵢ))`, `eᵢ = P⁻¹(i/N)`, and sits where the spectrum itself puts a fraction `ξᵢ`
//!   (uniform in [0, 1); at most 15/16 in the unbounded last bin) of that variance:
//!   `ωᵢ = F⁻¹(F(eᵢ) + ξᵢ (F(eᵢ₊₁) − F(eᵢ)))`, an unbiased sample of the bin for any response operator. The
//!   variance is `m0 = Hs²/16` exactly and no two components share a frequency: the sea never repeats.
//! - **Directions, stratified twice.** The cos-2s distribution is cut into `N` equal-probability strata, grouped
//!   into [`DIRECTION_STRATA`] coarse strata of `G = N/DIRECTION_STRATA`. Each group of `DIRECTION_STRATA`
//!   consecutive frequency components takes every coarse stratum once (in shuffled order), and across the `G`
//!   groups each coarse stratum hands out its fine strata in shuffled order: `Δ = F_D⁻¹((fine + ξ)/N)`. So every
//!   frequency band carries the whole spread, and the `N` directions together sample every quantile once.
//! - **Phases** uniform in [0, 2π).
//!
//! Draw order from a `ChaCha8Rng` seeded with `seed`: all `N` frequency jitters `ξᵢ`; one Fisher–Yates shuffle
//! of the `G` groups per coarse stratum; then per group, a shuffle of the coarse strata followed, for each
//! component of the group, by its direction jitter and its phase. `N` is a multiple of [`DIRECTION_STRATA`]. The generator is platform-independent: one seed gives one sea everywhere.

use super::spectrum::{CosTwoS, Jonswap, GRAVITY};
use crate::error::{MmusvError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Components of a field made by [`WaveField::new`].
pub const DEFAULT_COMPONENTS: usize = 256;
/// Directional strata per group of consecutive frequency components.
pub const DIRECTION_STRATA: usize = 8;
/// Allowed number of components.
pub const COMPONENTS_RANGE: [usize; 2] = [8, 4096];
/// Largest allowed peak steepness `2π Hs / (g Tp²)`: waves break beyond about 1/7 (DNV-RP-C205 §3.5.5.4 gives
/// 1/15 as the upper end of observed average seas).
pub const MAX_STEEPNESS: f64 = 1.0 / 7.0;

/// Most points of one [`WaveField::elevation_grid`] (2²⁸: 1 GiB of f32 per array).
pub const MAX_GRID_POINTS: usize = 1 << 28;

/// Significant wave heights a [`SeaSpec`] takes, metres (0: a flat sea).
pub const HS_RANGE_M: (f64, f64) = (0.0, 25.0);
/// Peak periods a [`SeaSpec`] takes, seconds.
pub const TP_RANGE_S: (f64, f64) = (0.5, 30.0);

/// The sea state: a directional JONSWAP spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeaSpec {
    /// Significant wave height Hs (m), finite, in `[0, 25]`; 0 is a flat sea.
    pub hs: f64,
    /// Peak period Tp (s), finite, in `[0.5, 30]`.
    pub tp: f64,
    /// JONSWAP peak enhancement γ in `[1, 7]` (1 is Pierson–Moskowitz, 3.3 the JONSWAP mean).
    pub gamma: f64,
    /// Mean travel direction θ̄ of the waves (rad, world frame, counter-clockwise from +x, towards which they
    /// travel), finite.
    pub direction_rad: f64,
    /// cos-2s spreading exponent s in `[0.5, 100]` (larger is more long-crested).
    pub spread_s: f64,
}

impl SeaSpec {
    /// Checks every field; errors are [`MmusvError::Config`] naming `hs_m`, `tp_s`, `gamma`, `direction_rad`
    /// or `spread_s` and the allowed range.
    pub fn validate(&self) -> Result<()> {
        let (hs, tp) = (HS_RANGE_M, TP_RANGE_S);
        if !self.hs.is_finite() || !(hs.0..=hs.1).contains(&self.hs) {
            return Err(MmusvError::config(
                "hs_m",
                self.hs,
                format!("must be a significant wave height in [{}, {}] m", hs.0, hs.1),
            ));
        }
        if !self.tp.is_finite() || !(tp.0..=tp.1).contains(&self.tp) {
            return Err(MmusvError::config(
                "tp_s",
                self.tp,
                format!("must be a peak period in [{}, {}] s", tp.0, tp.1),
            ));
        }
        if !self.direction_rad.is_finite() {
            return Err(MmusvError::config("direction_rad", self.direction_rad, "must be a finite angle in radians"));
        }
        let steep = self.steepness();
        if steep > MAX_STEEPNESS {
            return Err(MmusvError::config(
                "hs_m",
                self.hs,
                format!(
                    "with tp_s = {} the peak steepness 2π·Hs/(g·Tp²) is {steep:.3}, above the breaking limit 1/7; \
                     lower hs_m or raise tp_s (tp_s >= {:.2} s for this height)",
                    self.tp,
                    (TAU * self.hs / (GRAVITY * MAX_STEEPNESS)).sqrt()
                ),
            ));
        }
        Jonswap::new(self.hs, self.tp, self.gamma)?;
        CosTwoS::new(self.spread_s)?;
        Ok(())
    }

    /// Peak steepness `2π Hs / (g Tp²)`.
    pub fn steepness(&self) -> f64 {
        TAU * self.hs / (GRAVITY * self.tp * self.tp)
    }

    /// Peak wavelength `λp = g Tp² / (2π)` (m), deep water.
    pub fn peak_wavelength(&self) -> f64 {
        GRAVITY * self.tp * self.tp / TAU
    }
}

/// One linear wave of the sum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveComponent {
    /// Amplitude `a` (m).
    pub amplitude_m: f64,
    /// Angular frequency `ω` (rad/s).
    pub omega_rad_s: f64,
    /// Wavenumber `k = ω²/g` (rad/m).
    pub k_rad_m: f64,
    /// Travel direction `θ` (rad, world frame).
    pub direction_rad: f64,
    /// Phase `φ` (rad) in [0, 2π).
    pub phase_rad: f64,
    /// `k cos θ` (rad/m).
    pub kx: f64,
    /// `k sin θ` (rad/m).
    pub ky: f64,
}

impl WaveComponent {
    /// The phase `ψ = kx·x + ky·y − ω t + φ` (rad).
    #[inline]
    pub fn phase_at(&self, x: f64, y: f64, t: f64) -> f64 {
        self.kx * x + self.ky * y - self.omega_rad_s * t + self.phase_rad
    }

    /// Its elevation's variance `a²/2` (m²).
    #[inline]
    pub fn elevation_variance(&self) -> f64 {
        0.5 * self.amplitude_m * self.amplitude_m
    }

    /// Its mean square slope, both axes together: `a²k²/2`.
    #[inline]
    pub fn slope_variance(&self) -> f64 {
        0.5 * (self.amplitude_m * self.k_rad_m).powi(2)
    }
}

/// A realised sea: elevation, slope and orbital velocity anywhere, at any time.
#[derive(Debug, Clone)]
pub struct WaveField {
    spec: SeaSpec,
    seed: u64,
    components: Vec<WaveComponent>,
    max_elevation: f64,
}

impl WaveField {
    /// The field of `spec` with [`DEFAULT_COMPONENTS`] components drawn from `seed`.
    pub fn new(spec: &SeaSpec, seed: u64) -> Result<Self> {
        Self::with_components(spec, seed, DEFAULT_COMPONENTS)
    }

    /// The field of `spec` with `n` components (in [`COMPONENTS_RANGE`]; errors name `components`). A flat sea
    /// (`hs = 0`) has no components.
    pub fn with_components(spec: &SeaSpec, seed: u64, n: usize) -> Result<Self> {
        spec.validate()?;
        if !(COMPONENTS_RANGE[0]..=COMPONENTS_RANGE[1]).contains(&n) || !n.is_multiple_of(DIRECTION_STRATA) {
            return Err(MmusvError::config("components", n, "must be a multiple of 8 wave components in [8, 4096]"));
        }
        if spec.hs == 0.0 {
            return Ok(Self { spec: *spec, seed, components: Vec::new(), max_elevation: 0.0 });
        }
        let spectrum = Jonswap::new(spec.hs, spec.tp, spec.gamma)?;
        let spread = CosTwoS::new(spec.spread_s)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let nf = n as f64;
        let jitter: Vec<f64> = (0..n).map(|_| rng.random::<f64>()).collect();
        let mix = Mixture::new(&spectrum);
        // Bin edges e_0 = 0 .. e_N = ∞ (rad/s) and the cumulative variance fraction F there.
        let edge_w: Vec<f64> = (0..=n)
            .map(|i| match i {
                0 => 0.0,
                i if i == n => f64::INFINITY,
                i => mix.quantile(i as f64 / nf),
            })
            .collect();
        let edges: Vec<f64> = edge_w
            .iter()
            .enumerate()
            .map(|(i, &w)| match i {
                0 => 0.0,
                i if i == n => 1.0,
                _ => spectrum.cumulative(w),
            })
            .collect();
        let groups = n / DIRECTION_STRATA;
        // Fine direction stratum of (group g, coarse stratum j): j·groups + fine[j][g].
        let fine: Vec<Vec<usize>> = (0..DIRECTION_STRATA).map(|_| shuffled(&mut rng, groups)).collect();
        let mut components = Vec::with_capacity(n);
        for g in 0..groups {
            for (m, stratum) in shuffled(&mut rng, DIRECTION_STRATA).into_iter().enumerate() {
                let i = g * DIRECTION_STRATA + m;
                // Within its bin, the component's frequency follows the spectrum itself, so that it is an unbiased
                // sample of the bin's variance for any response operator.
                let mass = (edges[i + 1] - edges[i]).max(0.0);
                let xi = if i + 1 == n { jitter[i].min(LAST_BIN_QUANTILE) } else { jitter[i] };
                let lo = if i == 0 { 0.05 * spectrum.omega_p() } else { edge_w[i] };
                let hi = edge_w[i + 1].min(200.0 * spectrum.omega_p());
                let omega = spectrum.quantile(edges[i] + xi * mass).clamp(lo, hi);
                let amplitude = (2.0 * spectrum.m0() * mass).sqrt();
                let k = omega * omega / GRAVITY;
                let q = ((stratum * groups + fine[stratum][g]) as f64 + rng.random::<f64>()) / nf;
                let direction = spec.direction_rad + spread.quantile(q);
                let phase = TAU * rng.random::<f64>();
                components.push(WaveComponent {
                    amplitude_m: amplitude,
                    omega_rad_s: omega,
                    k_rad_m: k,
                    direction_rad: direction,
                    phase_rad: phase,
                    kx: k * direction.cos(),
                    ky: k * direction.sin(),
                });
            }
        }
        let max_elevation = components.iter().map(|c| c.amplitude_m).sum();
        Ok(Self { spec: *spec, seed, components, max_elevation })
    }

    /// The sea state it realises.
    pub fn spec(&self) -> &SeaSpec {
        &self.spec
    }

    /// The seed it was drawn from.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The components, in increasing frequency.
    pub fn components(&self) -> &[WaveComponent] {
        &self.components
    }

    /// A hard bound on `|η|` (m): the sum of amplitudes. No crest rises above it, no trough sinks below minus it.
    pub fn max_elevation(&self) -> f64 {
        self.max_elevation
    }

    /// A hard bound on the slope magnitude `|∇η|`: `Σ aᵢ kᵢ`.
    pub fn max_slope(&self) -> f64 {
        self.components.iter().map(|c| c.amplitude_m * c.k_rad_m).sum()
    }

    /// Surface elevation `η(x, y, t)` (m) above the mean level, world frame.
    pub fn elevation(&self, x: f64, y: f64, t: f64) -> f64 {
        self.components.iter().map(|c| c.amplitude_m * c.phase_at(x, y, t).cos()).sum()
    }

    /// Surface slope `[∂η/∂x, ∂η/∂y]` (dimensionless).
    pub fn slope(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        let mut s = [0.0, 0.0];
        for c in &self.components {
            let a = c.amplitude_m * c.phase_at(x, y, t).sin();
            s[0] -= a * c.kx;
            s[1] -= a * c.ky;
        }
        s
    }

    /// Rate of rise `∂η/∂t` (m/s).
    pub fn elevation_rate(&self, x: f64, y: f64, t: f64) -> f64 {
        self.components.iter().map(|c| c.amplitude_m * c.omega_rad_s * c.phase_at(x, y, t).sin()).sum()
    }

    /// Orbital velocity `[u, v, w]` (m/s, world frame) of the water at `(x, y, z)` (z up, m; values above the
    /// mean level are those at z = 0), deep-water linear theory. A NaN coordinate gives NaN.
    pub fn orbital_velocity(&self, x: f64, y: f64, z: f64, t: f64) -> [f64; 3] {
        // Not `z.min(0.0)`: that reads a NaN depth as the surface.
        let z = if z > 0.0 { 0.0 } else { z };
        let mut v = [0.0; 3];
        for c in &self.components {
            let decay = c.amplitude_m * c.omega_rad_s * (c.k_rad_m * z).exp();
            let (s, co) = c.phase_at(x, y, t).sin_cos();
            let h = decay * co;
            v[0] += h * c.direction_rad.cos();
            v[1] += h * c.direction_rad.sin();
            v[2] += decay * s;
        }
        v
    }

    /// Elevations on a regular grid, row-major `ny × nx`: entry `j·nx + i` is `η(x0 + i·dx, y0 + j·dx, t)` (m,
    /// f32). Each row advances every component's phasor by one complex multiplication per point; rows run over
    /// rayon. `dx` must be finite and > 0 (errors name `dx`), and the grid at most [`MAX_GRID_POINTS`] points
    /// (errors name `nx·ny`).
    pub fn elevation_grid(&self, x0: f64, y0: f64, dx: f64, nx: usize, ny: usize, t: f64) -> Result<Vec<f32>> {
        Ok(self.surface_grid(x0, y0, dx, nx, ny, t, false)?.0)
    }

    /// Elevations and slopes on the grid of [`elevation_grid`](Self::elevation_grid): `(η, ∂η/∂x, ∂η/∂y)`, each
    /// row-major `ny × nx` f32.
    pub fn elevation_slope_grid(
        &self,
        x0: f64,
        y0: f64,
        dx: f64,
        nx: usize,
        ny: usize,
        t: f64,
    ) -> Result<(Vec<f32>, Vec<f32>, Vec<f32>)> {
        self.surface_grid(x0, y0, dx, nx, ny, t, true)
    }

    #[allow(clippy::too_many_arguments)]
    fn surface_grid(
        &self,
        x0: f64,
        y0: f64,
        dx: f64,
        nx: usize,
        ny: usize,
        t: f64,
        slopes: bool,
    ) -> Result<(Vec<f32>, Vec<f32>, Vec<f32>)> {
        if !dx.is_finite() || dx <= 0.0 {
            return Err(MmusvError::input("dx", format!("grid spacing must be finite and > 0 m, got {dx}")));
        }
        for (name, v) in [("x0", x0), ("y0", y0), ("t", t)] {
            if !v.is_finite() {
                return Err(MmusvError::input(name, format!("must be finite, got {v}")));
            }
        }
        let n = match nx.checked_mul(ny) {
            Some(n) if n <= MAX_GRID_POINTS => n,
            _ => {
                return Err(MmusvError::input(
                    "nx·ny",
                    format!("a grid of {nx} × {ny} points is more than the {MAX_GRID_POINTS} allowed"),
                ))
            }
        };
        let mut eta = vec![0f32; n];
        let (mut sx, mut sy) = if slopes { (vec![0f32; n], vec![0f32; n]) } else { (Vec::new(), Vec::new()) };
        if n == 0 || self.components.is_empty() {
            return Ok((eta, sx, sy));
        }
        let steps: Vec<(f64, f64)> = self.components.iter().map(|c| (c.kx * dx).sin_cos()).collect();
        let row = |j: usize, e: &mut [f32], gx: &mut [f32], gy: &mut [f32]| {
            let y = y0 + j as f64 * dx;
            // Phasor p = a·exp(iψ) at the row start.
            let mut p: Vec<(f64, f64)> = self
                .components
                .iter()
                .map(|c| {
                    let (s, co) = c.phase_at(x0, y, t).sin_cos();
                    (c.amplitude_m * co, c.amplitude_m * s)
                })
                .collect();
            for i in 0..nx {
                let (mut h, mut ax, mut ay) = (0.0, 0.0, 0.0);
                for ((pr, pi), (c, &(ss, sc))) in p.iter_mut().zip(self.components.iter().zip(&steps)) {
                    h += *pr;
                    ax -= *pi * c.kx;
                    ay -= *pi * c.ky;
                    let r = *pr * sc - *pi * ss;
                    *pi = *pr * ss + *pi * sc;
                    *pr = r;
                }
                e[i] = h as f32;
                if slopes {
                    gx[i] = ax as f32;
                    gy[i] = ay as f32;
                }
            }
        };
        if slopes {
            eta.par_chunks_mut(nx)
                .zip(sx.par_chunks_mut(nx))
                .zip(sy.par_chunks_mut(nx))
                .enumerate()
                .for_each(|(j, ((e, gx), gy))| row(j, e, gx, gy));
        } else {
            eta.par_chunks_mut(nx).enumerate().for_each(|(j, e)| row(j, e, &mut [], &mut []));
        }
        Ok((eta, sx, sy))
    }
}

/// Stream index of the sea in [`crate::kinematics::mix_seed`], far from the vessel indices 0, 1, 2, ...
pub const SEA_STREAM: u64 = 0x0CEA_0000_0000_0001;

/// The seed of a scenario's wave field: `mix_seed(scenario_seed, SEA_STREAM)`. Every consumer (vessel response,
/// water surface, shading) builds the scenario's field with `WaveField::new(&spec, sea_seed(scenario_seed))`.
pub fn sea_seed(scenario_seed: u64) -> u64 {
    crate::kinematics::mix_seed(scenario_seed, SEA_STREAM)
}

/// The highest quantile of the last (unbounded) bin's variance at which its component may sit.
const LAST_BIN_QUANTILE: f64 = 0.9375;

/// Band `[ω₀, ω₁]` of the log-uniform half of the frequency sampling, in units of ωp.
pub const LOG_BAND: [f64; 2] = [0.6, 8.0];

/// The sampling mixture `P(ω) = ½ F(ω) + ½ clamp(ln(ω/ω₀)/ln(ω₁/ω₀), 0, 1)`.
struct Mixture<'a> {
    spectrum: &'a Jonswap,
    lo: f64,
    hi: f64,
}

impl<'a> Mixture<'a> {
    fn new(spectrum: &'a Jonswap) -> Self {
        let wp = spectrum.omega_p();
        Self { spectrum, lo: LOG_BAND[0] * wp, hi: LOG_BAND[1] * wp }
    }

    fn cdf(&self, omega: f64) -> f64 {
        let log = ((omega / self.lo).ln() / (self.hi / self.lo).ln()).clamp(0.0, 1.0);
        0.5 * self.spectrum.cumulative(omega) + 0.5 * log
    }

    /// `P⁻¹(u)` by bisection (1e-12 relative).
    fn quantile(&self, u: f64) -> f64 {
        let wp = self.spectrum.omega_p();
        let (mut lo, mut hi) = (0.05 * wp, 200.0 * wp);
        while hi - lo > 1e-12 * wp {
            let mid = 0.5 * (lo + hi);
            if self.cdf(mid) < u {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// A Fisher–Yates shuffle of `0..n` (draws `n − 1` integers).
fn shuffled(rng: &mut ChaCha8Rng, n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
    v
}

#[cfg(test)]
mod tests;
