//! A rotating ray-cast marine radar: one full revolution ("sweep") as sparse returns.
//!
//! The antenna turns through `azimuth_bins` beams per revolution; beam `b` points at azimuth
//! `2π b / azimuth_bins` in the sensor frame (0 = forward +x, counter-clockwise towards +y). Each beam is
//! sampled by `rays_az × rays_el` rays: `rays_az` azimuths at the centres of equal slices of the beamwidth,
//! and for each of them `rays_el` elevations spread uniformly (stratified) over the elevation fan. Surface
//! targets a kilometre away span a fraction of a degree of a fan some 20° tall, so (with `horizon_fraction` 0.75,
//! the scenario default) three quarters
//! of the elevation rays are spread uniformly over the band `±horizon_band_rad` around the sea horizon (where the
//! world's horizontal plane cuts the fan at that azimuth, from the sensor pose: it follows roll and pitch)
//! and the rest uniformly over the remainder of the fan; every ray carries the fan height it stands for as
//! its weight, so intensities stay unbiased (`horizon_fraction = 0` gives the plain uniform fan). Within its
//! stratum each ray sits at an offset that changes from azimuth sample to azimuth sample along the
//! golden-ratio sequence, so neighbouring samples fill the gaps between rows (no seed involved). All rays of
//! the sweep are cast in one [`Scene::cast_rays`] call.
//!
//! Range bin `k` covers `[k Δr, (k+1) Δr)` and is reported at its centre `(k + ½) Δr`; bins whose centre lies
//! outside `[range_min_m, range_max_m)` are blind. Hits are aggregated per cell (azimuth bin, range bin):
//! intensity is the sum of [`radar_model::ray_power`] over the rays hitting something other than water, plus
//! the cell's clutter draw ([`radar_model::clutter_mean`]); a cell is reported when its intensity is positive
//! and at least `detection_threshold`. Its instance and class are those of the object with the largest summed
//! echo in the cell, or instance −1 and class WATER (sea clutter) / NONE (rain clutter) when clutter
//! dominates. Rays that hit water end there and are not targets: the sea is seen only as clutter.
//!
//! Determinism: clutter and range noise of cell `(b, k)` come from a ChaCha8 generator seeded with `seed`,
//! stream `b`, at word offset `4k`, so they depend on nothing else (not on threads, other cells, or the
//! range limits), and for a fixed seed clutter grows monotonically with the wave height and rain rate.

use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::scene::{Scene, NO_HIT};
use crate::sensors::radar_model::{self, CellShape, ClutterModel, CLASS_WATER};
use parry3d::math::Vec3;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Most azimuth bins per revolution.
pub const MAX_AZIMUTH_BINS: u32 = 1 << 16;
/// Most range bins (`range_max_m / range_resolution_m`).
pub const MAX_RANGE_BINS: u64 = 1 << 20;
/// Most rays per sweep (`azimuth_bins · rays_az · rays_el`).
pub const MAX_RAYS: u64 = 1 << 24;
/// Largest `range_max_m`, metres.
pub const MAX_RANGE_M: f64 = 100_000.0;
/// Neighbouring azimuth samples traced together (one packet per elevation row).
const TRACE_BLOCK: usize = super::rays::TRACE_BLOCK as usize;
/// Golden-ratio conjugate: the elevation offset of azimuth sample `g` is `frac(g · φ⁻¹)`.
const GOLDEN: f64 = 0.618_033_988_749_894_8;
/// A clutter-only cell whose mean is below `threshold / CLUTTER_CUTOFF` is detected with probability
/// `< e⁻⁵⁰`; past the first such range the clutter-only scan of a beam stops.
const CLUTTER_CUTOFF: f64 = 50.0;

/// Radar parameters. Angles in radians, distances in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadarConfig {
    /// Blind range, metres (`0 ≤ range_min_m < range_max_m`); hides the own ship.
    pub range_min_m: f64,
    /// Instrumented range, metres (`≤ 100 km`).
    pub range_max_m: f64,
    /// Range bin size, metres (`> 0`).
    pub range_resolution_m: f64,
    /// Beams per revolution (`1..=65536`).
    pub azimuth_bins: u32,
    /// Horizontal (azimuth) beamwidth, radians, in `(0, π/2]`.
    pub beamwidth_az_rad: f64,
    /// Vertical fan `[lower, upper]` elevations, radians, `-π/2 < lower ≤ upper < π/2`.
    pub elevation_fan_rad: [f64; 2],
    /// Rays per beam across the beamwidth (`≥ 1`).
    pub rays_az: u32,
    /// Rays per beam over the elevation fan (`≥ 1`).
    pub rays_el: u32,
    /// Share of the elevation rays spread over the horizon band (`0..=1`; 0 = uniform over the fan).
    pub horizon_fraction: f64,
    /// Half-height of the horizon band, radians (`0..=π/4`).
    pub horizon_band_rad: f64,
    /// Smallest reported intensity (`≥ 0`; see [`radar_model`] for the unit).
    pub detection_threshold: f64,
    /// Standard deviation of Gaussian noise added to the reported range, metres (`≥ 0`).
    pub range_noise_std_m: f64,
    /// Sea and rain clutter.
    pub clutter: ClutterModel,
}

/// No `Default`: the radar's defaults are defined once, in the scenario schema
/// (`mmusv.sensors.config.RadarConfig`), and the binding (`mmusv._core.Radar`) requires every field.
impl RadarConfig {
    /// The configuration the core's unit tests and benchmarks are written against (the paper rig's geometry;
    /// threshold 0.01 and [`ClutterModel::tuning`], which show plenty of clutter). A fixture, not a user default.
    pub fn tuning() -> Self {
        Self {
            range_min_m: 10.0,
            range_max_m: 3000.0,
            range_resolution_m: 3.0,
            azimuth_bins: 2048,
            beamwidth_az_rad: 1.2f64.to_radians(),
            elevation_fan_rad: [(-10f64).to_radians(), 10f64.to_radians()],
            rays_az: 3,
            rays_el: 16,
            horizon_fraction: 0.75,
            horizon_band_rad: 1.0f64.to_radians(),
            detection_threshold: 0.01,
            range_noise_std_m: 0.0,
            clutter: ClutterModel::tuning(),
        }
    }
}

fn nonneg(field: &str, v: f64, max: f64) -> Result<()> {
    if v.is_finite() && (0.0..=max).contains(&v) {
        Ok(())
    } else {
        Err(MmusvError::config(format!("radar.{field}"), v, format!("must be finite and in [0, {max}]")))
    }
}

/// Checks the range bin size (shared with the PPI).
pub(crate) fn validate_resolution(range_resolution_m: f64) -> Result<()> {
    if range_resolution_m.is_finite() && range_resolution_m > 0.0 {
        Ok(())
    } else {
        Err(MmusvError::config("radar.range_resolution_m", range_resolution_m, "must be a finite number of metres > 0"))
    }
}

/// Checks the number of azimuth bins (shared with the PPI).
pub(crate) fn validate_azimuth_bins(azimuth_bins: u32) -> Result<()> {
    if (1..=MAX_AZIMUTH_BINS).contains(&azimuth_bins) {
        Ok(())
    } else {
        Err(MmusvError::config("radar.azimuth_bins", azimuth_bins, format!("must be in 1..={MAX_AZIMUTH_BINS}")))
    }
}

impl RadarConfig {
    /// Checks every field; the error names the first bad one as `radar.<field>`.
    pub fn validate(&self) -> Result<()> {
        if !(self.range_max_m.is_finite() && self.range_max_m > 0.0 && self.range_max_m <= MAX_RANGE_M) {
            return Err(MmusvError::config(
                "radar.range_max_m",
                self.range_max_m,
                format!("must be in (0, {MAX_RANGE_M}] metres"),
            ));
        }
        if !(self.range_min_m.is_finite() && self.range_min_m >= 0.0 && self.range_min_m < self.range_max_m) {
            return Err(MmusvError::config(
                "radar.range_min_m",
                self.range_min_m,
                format!("must be >= 0 and below range_max_m = {}", self.range_max_m),
            ));
        }
        validate_resolution(self.range_resolution_m)?;
        let bins = (self.range_max_m / self.range_resolution_m).ceil();
        if bins > MAX_RANGE_BINS as f64 {
            return Err(MmusvError::config(
                "radar.range_resolution_m",
                self.range_resolution_m,
                format!("gives {bins} range bins over {} m; at most {MAX_RANGE_BINS}", self.range_max_m),
            ));
        }
        validate_azimuth_bins(self.azimuth_bins)?;
        let bw = self.beamwidth_az_rad;
        if !(bw.is_finite() && bw > 0.0 && bw <= std::f64::consts::FRAC_PI_2) {
            return Err(MmusvError::config(
                "radar.beamwidth_az_rad",
                bw,
                "must be in (0, π/2] radians (0 to 90 degrees)",
            ));
        }
        let [lo, hi] = self.elevation_fan_rad;
        let half_pi = std::f64::consts::FRAC_PI_2;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi && lo > -half_pi && hi < half_pi) {
            return Err(MmusvError::config(
                "radar.elevation_fan_rad",
                format!("[{lo}, {hi}]"),
                "need lower <= upper, both strictly between -π/2 and π/2 radians",
            ));
        }
        if self.rays_az == 0 {
            return Err(MmusvError::config(
                "radar.rays_az",
                self.rays_az,
                "a beam needs at least 1 ray across its width",
            ));
        }
        if self.rays_el == 0 {
            return Err(MmusvError::config("radar.rays_el", self.rays_el, "a beam needs at least 1 ray over the fan"));
        }
        if self.num_rays() > MAX_RAYS {
            return Err(MmusvError::config(
                "radar.rays_el",
                self.rays_el,
                format!("azimuth_bins · rays_az · rays_el = {} rays per sweep; at most {MAX_RAYS}", self.num_rays()),
            ));
        }
        nonneg("horizon_fraction", self.horizon_fraction, 1.0)?;
        nonneg("horizon_band_rad", self.horizon_band_rad, std::f64::consts::FRAC_PI_4)?;
        nonneg("detection_threshold", self.detection_threshold, f64::MAX)?;
        nonneg("range_noise_std_m", self.range_noise_std_m, MAX_RANGE_M)?;
        nonneg("clutter.sea_sigma0_at_1m", self.clutter.sea_sigma0_at_1m, 1.0)?;
        nonneg("clutter.critical_range_per_m", self.clutter.critical_range_per_m, MAX_RANGE_M)?;
        nonneg("clutter.sea_max_range_m", self.clutter.sea_max_range_m, MAX_RANGE_M)?;
        nonneg("clutter.rain_eta_at_1mm_h", self.clutter.rain_eta_at_1mm_h, 1.0)
    }

    /// Rays per sweep: `azimuth_bins · rays_az · rays_el`.
    pub fn num_rays(&self) -> u64 {
        self.azimuth_bins as u64 * self.rays_az as u64 * self.rays_el as u64
    }

    /// The range bins that are not blind: `first..end` (bin centres in `[range_min_m, range_max_m)`).
    pub fn range_bins(&self) -> (u32, u32) {
        let res = self.range_resolution_m;
        let first = (self.range_min_m / res - 0.5).ceil().max(0.0) as u32;
        let end = (self.range_max_m / res - 0.5).ceil().max(0.0) as u32;
        (first, end.max(first))
    }

    /// Centre of range bin `k`, metres.
    pub fn bin_centre(&self, k: u32) -> f64 {
        (k as f64 + 0.5) * self.range_resolution_m
    }

    /// Azimuth of beam `b` in the sensor frame, radians in `[0, 2π)`.
    pub fn beam_azimuth(&self, b: u32) -> f64 {
        std::f64::consts::TAU * b as f64 / self.azimuth_bins as f64
    }

    /// Azimuth (radians, sensor frame) of azimuth sample `g = b · rays_az + j`, the `j`-th ray across beam `b`.
    pub fn sample_azimuth(&self, g: u32) -> f64 {
        let (b, j) = (g / self.rays_az, g % self.rays_az);
        self.beam_azimuth(b) + ((j as f64 + 0.5) / self.rays_az as f64 - 0.5) * self.beamwidth_az_rad
    }

    /// Elevations (radians, sensor frame) and weights (the fan height in radians each ray stands for; they sum
    /// to the fan height) of the `rays_el` rays of azimuth sample `g`, whose sea horizon lies at elevation
    /// `horizon` (`None`: not in view). Written into `out` (length `rays_el`).
    pub fn sample_elevations(&self, g: u32, horizon: Option<f64>, out: &mut [(f64, f64)]) {
        let [lo, hi] = self.elevation_fan_rad;
        let k_all = out.len();
        let offset = (g as f64 * GOLDEN).fract();
        let (b0, b1) = match horizon {
            Some(e) if self.horizon_fraction > 0.0 && self.horizon_band_rad > 0.0 => {
                ((e - self.horizon_band_rad).max(lo), (e + self.horizon_band_rad).min(hi))
            }
            _ => (lo, lo),
        };
        let band = (b1 - b0).max(0.0);
        let rest = (hi - lo) - band;
        let k_band = if band <= 0.0 {
            0
        } else if rest <= 0.0 {
            k_all
        } else {
            ((self.horizon_fraction * k_all as f64).round() as usize).min(k_all - 1)
        };
        let k_rest = k_all - k_band;
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = if k < k_band {
                (b0 + band * (k as f64 + offset) / k_band as f64, band / k_band as f64)
            } else if rest > 0.0 {
                let t = rest * ((k - k_band) as f64 + offset) / k_rest as f64;
                let below = b0 - lo;
                (if t < below { lo + t } else { b1 + (t - below) }, rest / k_rest as f64)
            } else {
                // A zero-height fan: every ray at the one elevation, sharing one beamwidth of height.
                (lo, self.cell_shape().fan_height / k_all as f64)
            };
        }
    }

    fn cell_shape(&self) -> CellShape {
        let [lo, hi] = self.elevation_fan_rad;
        CellShape {
            beamwidth_az: self.beamwidth_az_rad,
            fan_height: (hi - lo).max(self.beamwidth_az_rad),
            range_resolution: self.range_resolution_m,
        }
    }
}

/// Conditions that change the radar picture.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RadarEnv {
    /// Significant wave height, metres (`0..=30`): sea clutter.
    pub wave_height_m: f32,
    /// Rain rate, mm/h (`0..=500`): attenuation and rain clutter.
    pub rain_mm_per_h: f32,
}

impl RadarEnv {
    /// Checks both fields; errors name `radar.wave_height_m` / `radar.rain_mm_per_h`.
    pub fn validate(&self) -> Result<()> {
        nonneg("wave_height_m", self.wave_height_m as f64, 30.0)?;
        nonneg("rain_mm_per_h", self.rain_mm_per_h as f64, 500.0)
    }
}

/// The returns of one sweep, parallel arrays sorted by (azimuth bin, range bin), at most one per cell.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RadarReturns {
    /// Range, metres: the bin centre plus the optional range noise (never negative).
    pub range: Vec<f32>,
    /// Beam azimuth in the sensor frame, radians in `[0, 2π)`, 0 = forward, counter-clockwise.
    pub azimuth: Vec<f32>,
    /// Elevation in the sensor frame, radians: echo-weighted mean of the rays hitting the cell, or for
    /// clutter the elevation of the sea surface at that range seen from the sensor height (level sensor).
    pub elevation: Vec<f32>,
    /// Intensity, linear, relative to a 1 m² target at 1 km (see [`radar_model`]).
    pub intensity: Vec<f32>,
    /// Scene instance of the strongest echo, or −1 for clutter.
    pub instance: Vec<i32>,
    /// Semantic class of the strongest echo; WATER (1) for sea clutter, NONE (0) for rain clutter.
    pub class: Vec<u16>,
}

impl RadarReturns {
    /// Number of returns.
    pub fn len(&self) -> usize {
        self.range.len()
    }
    /// Whether there are no returns.
    pub fn is_empty(&self) -> bool {
        self.range.is_empty()
    }
}

/// Elevation (sensor frame, radians) at which the world's horizontal plane through the sensor cuts azimuth
/// `az`, for a sensor whose rotation (sensor → world) is `pose`; `None` when the sensor is tipped 90° or more.
pub fn horizon_elevation(pose: &RigidPose, az: f64) -> Option<f64> {
    let r = pose.rotation;
    let (r20, r21, r22) = (r.x_axis.z as f64, r.y_axis.z as f64, r.z_axis.z as f64);
    (r22 > 1e-6).then(|| (-(r20 * az.cos() + r21 * az.sin()) / r22).atan())
}

/// Index in the trace order of ray `k` (elevation) of azimuth sample `g`: blocks of [`TRACE_BLOCK`]
/// neighbouring azimuth samples, each elevation row of a block consecutive (coherent packets).
#[inline]
fn trace_index(g: usize, k: usize, samples: usize, rows: usize) -> usize {
    let start = g / TRACE_BLOCK * TRACE_BLOCK;
    let len = TRACE_BLOCK.min(samples - start);
    start * rows + k * len + (g - start)
}

/// One cell's target echo: summed power, winning instance and class, echo-weighted elevation.
#[derive(Debug, Clone, Copy)]
struct TargetCell {
    bin: u32,
    power: f64,
    instance: i32,
    class: u16,
    elevation: f64,
}

/// One ray's contribution.
#[derive(Debug, Clone, Copy)]
struct RayEcho {
    bin: u32,
    instance: i32,
    class: u16,
    power: f64,
    elevation: f64,
}

/// Groups the ray echoes of one beam into cells (sorted by bin).
fn group_cells(mut echoes: Vec<RayEcho>) -> Vec<TargetCell> {
    echoes.sort_by(|a, b| (a.bin, a.instance).cmp(&(b.bin, b.instance)).then(b.power.total_cmp(&a.power)));
    let mut cells: Vec<TargetCell> = Vec::new();
    let mut i = 0;
    while i < echoes.len() {
        let bin = echoes[i].bin;
        let mut cell = TargetCell { bin, power: 0.0, instance: NO_HIT, class: 0, elevation: 0.0 };
        let (mut best, mut weighted_el) = (f64::NEG_INFINITY, 0.0);
        while i < echoes.len() && echoes[i].bin == bin {
            // Within the bin, echoes of one instance are consecutive, strongest ray first.
            let (inst, class) = (echoes[i].instance, echoes[i].class);
            let mut sum = 0.0;
            while i < echoes.len() && echoes[i].bin == bin && echoes[i].instance == inst {
                sum += echoes[i].power;
                weighted_el += echoes[i].power * echoes[i].elevation;
                i += 1;
            }
            cell.power += sum;
            if sum > best {
                best = sum;
                cell.instance = inst;
                cell.class = class;
            }
        }
        cell.elevation = if cell.power > 0.0 { weighted_el / cell.power } else { 0.0 };
        cells.push(cell);
    }
    cells
}

/// Per-cell random draws: clutter `u ∈ (0, 1]` and a standard normal for the range noise.
struct CellDraws {
    rng: ChaCha8Rng,
    next: Option<u32>,
}

impl CellDraws {
    fn new(seed: u64, beam: u32) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(beam as u64);
        Self { rng, next: None }
    }

    /// The draws of cell `bin`: `(u, w)` with `u` uniform in `(0, 1]` for clutter and `w` the raw word that
    /// [`CellDraws::normal`] turns into the range noise.
    fn at(&mut self, bin: u32) -> (f64, u64) {
        if self.next != Some(bin) {
            self.rng.set_word_pos(bin as u128 * 4);
        }
        self.next = Some(bin + 1);
        let a = self.rng.next_u64();
        let w = self.rng.next_u64();
        (((a >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64), w)
    }

    /// A standard normal from one 64-bit word (Box–Muller on its two 32-bit halves).
    fn normal(w: u64) -> f64 {
        let u1 = ((w >> 32) + 1) as f64 * (1.0 / 4_294_967_296.0);
        let u2 = (w & 0xffff_ffff) as f64 * (1.0 / 4_294_967_296.0);
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Clutter of one range bin: mean intensity, whether sea (not rain) dominates, and the probability that
/// clutter alone passes the threshold.
#[derive(Debug, Clone, Copy)]
struct ClutterBin {
    mean: f64,
    sea: bool,
    p_detect: f64,
}

impl ClutterBin {
    fn at(cfg: &RadarConfig, env: &RadarEnv, bin: u32) -> Self {
        let (sea, rain) = radar_model::clutter_mean(
            &cfg.clutter,
            &cfg.cell_shape(),
            env.wave_height_m as f64,
            env.rain_mm_per_h as f64,
            cfg.bin_centre(bin),
        );
        let mean = sea + rain;
        let p_detect = if mean > 0.0 { (-cfg.detection_threshold / mean).exp() } else { 0.0 };
        Self { mean, sea: sea >= rain, p_detect }
    }
}

/// Clutter of the range bins from `first` on, shared by every beam, up to the first bin where clutter alone
/// cannot be detected (`mean < threshold / CLUTTER_CUTOFF`; the means fall monotonically with range).
fn clutter_table(cfg: &RadarConfig, env: &RadarEnv, first: u32, end: u32) -> Vec<ClutterBin> {
    let mut table = Vec::new();
    for k in first..end {
        let c = ClutterBin::at(cfg, env, k);
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

/// Everything one beam's aggregation needs.
struct BeamContext<'a> {
    cfg: &'a RadarConfig,
    env: &'a RadarEnv,
    seed: u64,
    first: u32,
    end: u32,
    table: &'a [ClutterBin],
    sensor_height: f64,
    pose: &'a RigidPose,
}

/// A finished return before it is split into the parallel arrays.
#[derive(Debug, Clone, Copy)]
struct Return {
    range: f32,
    azimuth: f32,
    elevation: f32,
    intensity: f32,
    instance: i32,
    class: u16,
}

impl BeamContext<'_> {
    /// Merges the target cells of beam `b` with its clutter draws into returns, by range bin.
    fn returns(&self, b: u32, cells: &[TargetCell]) -> Vec<Return> {
        let mut draws = CellDraws::new(self.seed, b);
        let azimuth = self.cfg.beam_azimuth(b) as f32;
        let horizon = horizon_elevation(self.pose, azimuth as f64).unwrap_or(0.0);
        let mut out = Vec::with_capacity(self.table.len() + cells.len());
        let thr = self.cfg.detection_threshold;
        let mut emit = |bin: u32, target: Option<&TargetCell>, clutter: Option<ClutterBin>| {
            let (u, w) = draws.at(bin);
            let ClutterBin { mean, sea, p_detect } = clutter.unwrap_or_else(|| ClutterBin::at(self.cfg, self.env, bin));
            // Clutter alone is detected iff mean · (−ln u) ≥ threshold, i.e. u ≤ exp(−threshold / mean).
            if target.is_none() && u > p_detect {
                return;
            }
            let clutter_power = if mean > 0.0 { mean * -u.ln() } else { 0.0 };
            let target_power = target.map_or(0.0, |t| t.power);
            let total = target_power + clutter_power;
            if !(total > 0.0 && total >= thr) {
                return;
            }
            let centre = self.cfg.bin_centre(bin);
            let noise = self.cfg.range_noise_std_m;
            let range = if noise > 0.0 { (centre + noise * CellDraws::normal(w)).max(0.0) } else { centre };
            let (instance, class, elevation) = match target {
                Some(t) if t.power >= clutter_power => (t.instance, t.class, t.elevation),
                _ => (NO_HIT, if sea { CLASS_WATER } else { 0 }, horizon - self.sensor_height.atan2(centre)),
            };
            out.push(Return {
                range: range as f32,
                azimuth,
                elevation: elevation as f32,
                intensity: total as f32,
                instance,
                class,
            });
        };
        let mut t = 0;
        for (i, &c) in self.table.iter().enumerate() {
            let bin = self.first + i as u32;
            let target = cells.get(t).filter(|cell| cell.bin == bin);
            if target.is_some() {
                t += 1;
            }
            emit(bin, target, Some(c));
        }
        for cell in &cells[t..] {
            if cell.bin < self.end {
                emit(cell.bin, Some(cell), None);
            }
        }
        out
    }
}

/// One full revolution of the radar at `sensor_to_world` (sensor frame: x forward, y left, z up).
///
/// Casts `cfg.num_rays()` rays in one batch, aggregates them per (azimuth bin, range bin) cell, adds seeded
/// sea / rain clutter and returns the detections sorted by (azimuth bin, range bin). See the module
/// documentation for the ray pattern and [`radar_model`] for the intensity model. Deterministic for a given
/// scene, pose, configuration and seed.
pub fn radar_sweep(
    scene: &Scene,
    sensor_to_world: &RigidPose,
    cfg: &RadarConfig,
    env: &RadarEnv,
    seed: u64,
) -> Result<RadarReturns> {
    cfg.validate()?;
    env.validate()?;
    let samples = (cfg.azimuth_bins * cfg.rays_az) as usize;
    let rows = cfg.rays_el as usize;
    // Ray directions (world) and per-ray (elevation, fan-height weight), both in trace order.
    let mut dirs = vec![[0.0f32; 3]; samples * rows];
    let mut meta = vec![[0.0f32; 2]; samples * rows];
    dirs.par_chunks_mut(TRACE_BLOCK * rows).zip(meta.par_chunks_mut(TRACE_BLOCK * rows)).enumerate().for_each(
        |(block, (chunk, meta))| {
            let start = block * TRACE_BLOCK;
            let len = TRACE_BLOCK.min(samples - start);
            let mut column = vec![(0.0, 0.0); rows];
            for g in start..start + len {
                let az = cfg.sample_azimuth(g as u32);
                cfg.sample_elevations(g as u32, horizon_elevation(sensor_to_world, az), &mut column);
                let (sa, ca) = az.sin_cos();
                for (k, &(el, weight)) in column.iter().enumerate() {
                    let (se, ce) = el.sin_cos();
                    let body = Vec3::new((ce * ca) as f32, (ce * sa) as f32, se as f32);
                    chunk[k * len + g - start] = sensor_to_world.transform_vector(body).to_array();
                    meta[k * len + g - start] = [el as f32, weight as f32];
                }
            }
        },
    );
    let origins = vec![sensor_to_world.translation.to_array(); dirs.len()];
    let hits = scene.cast_rays(&origins, &dirs, cfg.range_max_m as f32)?;
    drop(origins);

    let (first, end) = cfg.range_bins();
    let table = clutter_table(cfg, env, first, end);
    // Solid angle of a ray = (beamwidth / rays_az) · its fan-height weight.
    let az_width = cfg.beamwidth_az_rad / cfg.rays_az as f64;
    let rain = env.rain_mm_per_h as f64;
    let ctx = BeamContext {
        cfg,
        env,
        seed,
        first,
        end,
        table: &table,
        sensor_height: sensor_to_world.translation.z.max(0.0) as f64,
        pose: sensor_to_world,
    };
    let per_beam: Vec<Vec<Return>> = (0..cfg.azimuth_bins)
        .into_par_iter()
        .map(|b| {
            let mut echoes = Vec::new();
            for j in 0..cfg.rays_az {
                let g = b * cfg.rays_az + j;
                for k in 0..cfg.rays_el {
                    let i = trace_index(g as usize, k as usize, samples, rows);
                    let (instance, class, d) = (hits.instance[i], hits.class[i], hits.distance[i] as f64);
                    if instance == NO_HIT || class == CLASS_WATER || !d.is_finite() {
                        continue;
                    }
                    let bin = (d / cfg.range_resolution_m).floor() as u32;
                    if bin < first || bin >= end {
                        continue;
                    }
                    let n = &hits.normal[3 * i..3 * i + 3];
                    let dir = dirs[i];
                    let cos = (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]) as f64;
                    let [elevation, weight] = meta[i];
                    let power = radar_model::ray_power(class, cos, az_width * weight as f64, d, rain);
                    echoes.push(RayEcho { bin, instance, class, power, elevation: elevation as f64 });
                }
            }
            ctx.returns(b, &group_cells(echoes))
        })
        .collect();

    let n: usize = per_beam.iter().map(Vec::len).sum();
    let mut out = RadarReturns {
        range: Vec::with_capacity(n),
        azimuth: Vec::with_capacity(n),
        elevation: Vec::with_capacity(n),
        intensity: Vec::with_capacity(n),
        instance: Vec::with_capacity(n),
        class: Vec::with_capacity(n),
    };
    for r in per_beam.into_iter().flatten() {
        out.range.push(r.range);
        out.azimuth.push(r.azimuth);
        out.elevation.push(r.elevation);
        out.intensity.push(r.intensity);
        out.instance.push(r.instance);
        out.class.push(r.class);
    }
    Ok(out)
}

#[cfg(test)]
#[path = "radar_tests.rs"]
mod tests;
