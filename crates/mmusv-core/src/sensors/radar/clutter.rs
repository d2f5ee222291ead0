//! Clutter: the mean sea and rain clutter of each range bin (shared by every beam, cut off where clutter
//! alone can no longer be detected) and the seeded per-cell draws that make it a random picture.

use crate::sensors::radar::sea_clutter::PhysicalSea;
use crate::sensors::radar::{RadarConfig, RadarEnv};
use crate::sensors::radar_model;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A clutter-only cell whose mean is below `threshold / CLUTTER_CUTOFF` is detected with probability
/// `< e⁻⁵⁰`; past the first such range the clutter-only scan of a beam stops.
const CLUTTER_CUTOFF: f64 = 50.0;

/// Per-cell random draws: clutter `u ∈ (0, 1]` and a standard normal for the range noise.
pub(super) struct CellDraws {
    rng: ChaCha8Rng,
    next: Option<u32>,
}

impl CellDraws {
    /// The draws of beam `beam` (stream `beam` of the generator seeded with `seed`).
    pub(super) fn new(seed: u64, beam: u32) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(beam as u64);
        Self { rng, next: None }
    }

    /// The draws of cell `bin`: `(u, w)` with `u` uniform in `(0, 1]` for clutter and `w` the raw word that
    /// [`CellDraws::normal`] turns into the range noise.
    pub(super) fn at(&mut self, bin: u32) -> (f64, u64) {
        if self.next != Some(bin) {
            self.rng.set_word_pos(bin as u128 * 4);
        }
        self.next = Some(bin + 1);
        let a = self.rng.next_u64();
        let w = self.rng.next_u64();
        (((a >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64), w)
    }

    /// A standard normal from one 64-bit word (Box–Muller on its two 32-bit halves).
    pub(super) fn normal(w: u64) -> f64 {
        let u1 = ((w >> 32) + 1) as f64 * (1.0 / 4_294_967_296.0);
        let u2 = (w & 0xffff_ffff) as f64 * (1.0 / 4_294_967_296.0);
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Clutter of one range bin: mean intensity, whether sea (not rain) dominates, and the probability that
/// clutter alone passes the threshold; and the sea and rain parts of the mean.
#[derive(Debug, Clone, Copy)]
pub(super) struct ClutterBin {
    pub(super) mean: f64,
    pub(super) sea: bool,
    pub(super) p_detect: f64,
    sea_mean: f64,
    rain_mean: f64,
}

impl ClutterBin {
    /// The clutter of range bin `bin`, the antenna `flat_height` metres above the flat sea (z = 0).
    /// Over the physical sea (`physical`), σ⁰ is the NRL model's ([`super::sea_clutter`]) and the antenna's height
    /// is the one above its still level.
    pub(super) fn at(
        cfg: &RadarConfig,
        env: &RadarEnv,
        physical: Option<&PhysicalSea>,
        flat_height: f64,
        bin: u32,
    ) -> Self {
        let r = cfg.bin_centre(bin);
        let antenna_height = physical.map_or(flat_height, |p| p.antenna_height_m);
        let (sea, rain) = match physical {
            None => radar_model::clutter_mean(
                &cfg.clutter,
                &cfg.cell_shape(antenna_height),
                &cfg.band(),
                env.wave_height_m as f64,
                env.rain_mm_per_h as f64,
                r,
            ),
            Some(p) => radar_model::clutter_mean_sigma0(
                &cfg.clutter,
                &cfg.cell_shape(antenna_height),
                &cfg.band(),
                p.sigma0(r),
                env.rain_mm_per_h as f64,
                r,
            ),
        };
        Self::of(cfg, sea, rain)
    }

    fn of(cfg: &RadarConfig, sea: f64, rain: f64) -> Self {
        let mean = sea + rain;
        let p_detect = if mean > 0.0 { (-cfg.detection_threshold / mean).exp() } else { 0.0 };
        Self { mean, sea: sea >= rain, p_detect, sea_mean: sea, rain_mean: rain }
    }

    /// This bin with its sea part scaled by `share` (`0..=1`: the share of the beam's width that sees the sea,
    /// the rest land or shadow; or the fan's two-way gain where the water lies), the rain part as it is;
    /// `share = 1` is `self`, to the bit.
    pub(super) fn in_view(self, cfg: &RadarConfig, share: f64) -> Self {
        if share >= 1.0 {
            self
        } else {
            Self::of(cfg, self.sea_mean * share, self.rain_mean)
        }
    }
}

/// Clutter of the range bins from `first` on, shared by every beam, up to the first bin beyond the antenna's
/// height where clutter alone cannot be detected (`mean < threshold / CLUTTER_CUTOFF`; from there on the means
/// fall monotonically with range).
pub(super) fn clutter_table(
    cfg: &RadarConfig,
    env: &RadarEnv,
    physical: Option<&PhysicalSea>,
    flat_height: f64,
    first: u32,
    end: u32,
) -> Vec<ClutterBin> {
    let mut table = Vec::new();
    // No water lies at a slant range below the antenna's height: those bins have no sea clutter, and do not end
    // the table (the sea's clutter begins beyond them).
    let water_from = physical.map_or(flat_height, |p| p.antenna_height_m);
    for k in first..end {
        let c = ClutterBin::at(cfg, env, physical, flat_height, k);
        if cfg.bin_centre(k) <= water_from {
            table.push(c);
            continue;
        }
        let negligible = if cfg.detection_threshold > 0.0 {
            c.mean * CLUTTER_CUTOFF < cfg.detection_threshold
        } else {
            c.mean <= 0.0
        };
        if negligible {
            break;
        }
        table.push(c);
    }
    table
}
