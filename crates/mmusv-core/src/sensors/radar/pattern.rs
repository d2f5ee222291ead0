//! Where the radar's rays go: beam and sample azimuths, the stratified elevation fan with its horizon band,
//! range bins, the trace order of the rays, and their world directions for one sweep; and how the beam weights
//! what it sees in elevation.
//!
//! Elevation pattern: a marine radar's fan beam is some 20–25° tall between its half-power points and tapers,
//! not a uniform slab. Its main lobe is taken Gaussian, the standard approximation of a radar beam's main lobe
//! (Probert-Jones, J. R. (1962), "The radar equation in meteorology", Q. J. R. Meteorol. Soc. 88, 485–495;
//! Doviak, R. J. & Zrnić, D. S. (1993), "Doppler Radar and Weather Observations", 2nd ed.): one-way power
//! gain `G(e) = exp(−4 ln 2 (e − e₀)² / θ_el²)` with `θ_el` the fan's height (`elevation_fan_rad`'s span: the
//! half-power beamwidth) and `e₀` its centre, so the two-way weight of an echo is `G² = exp(−8 ln 2 (e − e₀)² /
//! θ_el²)`: 1 on the axis, ¼ at the fan's edges. It weights every target ray ([`RadarConfig::two_way_gain`]), the
//! sea clutter of each cell at the elevation where that water lies in the (tilted) sensor frame, and the rain's
//! volume by `∫G² de = θ_el √(π / (8 ln 2))` (the rain fills the beam). The rays are still cast over the fan
//! only: a target beyond its edges (two-way gain below ¼) is not seen. Until 2026-12-01 the fan was uniform: a
//! target 8° off the axis of a 20° fan was as bright as one on it (2.4 times, 3.9 dB, too bright), and the sea
//! 17° below the axis, outside the fan, gave its full clutter (55 times, 17.4 dB, too much).

use crate::geometry::RigidPose;
use crate::sensors::radar::RadarConfig;
use crate::sensors::radar_model::CellShape;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Neighbouring azimuth samples traced together (one packet per elevation row).
const TRACE_BLOCK: usize = crate::sensors::rays::TRACE_BLOCK as usize;
/// Golden-ratio conjugate: the elevation offset of azimuth sample `g` is `frac(g · φ⁻¹)`.
const GOLDEN: f64 = 0.618_033_988_749_894_8;

impl RadarConfig {
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

    /// The strata of the elevation fan of `k_all` rays whose sea horizon lies at `horizon` (`None`: not in view).
    fn strata(&self, horizon: Option<f64>, k_all: usize) -> Strata {
        let [lo, hi] = self.elevation_fan_rad;
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
        Strata { lo, b0, b1, band, rest, k_band, k_rest: k_all - k_band }
    }

    /// Elevations (radians, sensor frame) and weights (the fan height in radians each ray stands for; they sum
    /// to the fan height) of the `rays_el` rays of azimuth sample `g`, whose sea horizon lies at elevation
    /// `horizon` (`None`: not in view). Written into `out` (length `rays_el`).
    pub fn sample_elevations(&self, g: u32, horizon: Option<f64>, out: &mut [(f64, f64)]) {
        let k_all = out.len();
        let Strata { lo, b0, b1, band, rest, k_band, k_rest } = self.strata(horizon, k_all);
        let offset = (g as f64 * GOLDEN).fract();
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = if k < k_band {
                (b0 + band * (k as f64 + offset) / k_band as f64, band / k_band as f64)
            } else if rest > 0.0 {
                let t = rest * ((k - k_band) as f64 + offset) / k_rest as f64;
                let below = b0 - lo;
                (if t < below { lo + t } else { b1 + (t - below) }, rest / k_rest as f64)
            } else {
                // A zero-height fan: every ray at the one elevation, sharing one beamwidth of height.
                (lo, self.fan_height() / k_all as f64)
            };
        }
    }

    /// The fan height (radians) of the elevation stratum that holds elevation `e` for an azimuth sample whose sea
    /// horizon lies at `horizon`: the weight [`RadarConfig::sample_elevations`] gives a ray there, the inverse of
    /// the fan's density of rays at `e` (`targets`).
    pub(super) fn stratum_height(&self, horizon: Option<f64>, e: f64) -> f64 {
        let k_all = self.rays_el as usize;
        let Strata { b0, b1, band, rest, k_band, k_rest, .. } = self.strata(horizon, k_all);
        if k_band > 0 && (e >= b0 && e <= b1 || rest <= 0.0) {
            band / k_band as f64
        } else if rest > 0.0 {
            rest / k_rest as f64
        } else {
            self.fan_height() / k_all as f64
        }
    }

    /// Two-way power gain `G²(e) = exp(−8 ln 2 (e − e₀)² / θ_el²)` of the fan's Gaussian main lobe at elevation `e`
    /// (radians, sensor frame): `θ_el` the fan's height, `e₀` its centre (see the module documentation).
    pub fn two_way_gain(&self, elevation: f64) -> f64 {
        let [lo, hi] = self.elevation_fan_rad;
        let q = (elevation - 0.5 * (lo + hi)) / self.fan_height();
        (-8.0 * std::f64::consts::LN_2 * q * q).exp()
    }

    /// The fan's height, radians (at least one azimuth beamwidth).
    pub(super) fn fan_height(&self) -> f64 {
        let [lo, hi] = self.elevation_fan_rad;
        (hi - lo).max(self.beamwidth_az_rad)
    }

    /// The beam's cell with the antenna `antenna_height` metres above the still water: azimuth beamwidth, fan
    /// height, range resolution and that height (for the intensity model).
    pub(super) fn cell_shape(&self, antenna_height: f64) -> CellShape {
        CellShape {
            beamwidth_az: self.beamwidth_az_rad,
            fan_height: self.fan_height(),
            range_resolution: self.range_resolution_m,
            antenna_height,
        }
    }
}

/// The elevation fan's strata: `k_band` rays over the horizon band `[b0, b1]` (height `band`), `k_rest` over the
/// rest of the fan from `lo` (height `rest`).
struct Strata {
    lo: f64,
    b0: f64,
    b1: f64,
    band: f64,
    rest: f64,
    k_band: usize,
    k_rest: usize,
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
pub(super) fn trace_index(g: usize, k: usize, samples: usize, rows: usize) -> usize {
    let start = g / TRACE_BLOCK * TRACE_BLOCK;
    let len = TRACE_BLOCK.min(samples - start);
    start * rows + k * len + (g - start)
}

/// The rays of one sweep from `sensor_to_world`, in trace order: world unit directions, and per ray its
/// elevation in the sensor frame (radians) and the fan height it stands for (radians).
pub(super) fn sweep_rays(cfg: &RadarConfig, sensor_to_world: &RigidPose) -> (Vec<[f32; 3]>, Vec<[f32; 2]>) {
    let samples = (cfg.azimuth_bins * cfg.rays_az) as usize;
    let rows = cfg.rays_el as usize;
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
    (dirs, meta)
}
