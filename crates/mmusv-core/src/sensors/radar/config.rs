//! What a radar is and what it sees through: [`RadarConfig`] and [`RadarEnv`], their limits and checks.

use crate::error::{MmusvError, Result};
use crate::sensors::radar::sea_clutter::{Polarisation, FREQUENCY_RANGE_GHZ, MARINE_FREQUENCY_GHZ};
use crate::sensors::radar_model::{Band, ClutterModel};

/// Most azimuth bins per revolution.
pub const MAX_AZIMUTH_BINS: u32 = 1 << 16;
/// Most range bins (`range_max_m / range_resolution_m`).
pub const MAX_RANGE_BINS: u64 = 1 << 20;
/// Most rays per sweep (`azimuth_bins · rays_az · rays_el`).
pub const MAX_RAYS: u64 = 1 << 24;
/// Most rays cast at one target per beam spacing ([`RadarConfig::target_rays`]).
pub const MAX_TARGET_RAYS: u32 = 1024;
/// Largest `range_max_m`, metres.
pub const MAX_RANGE_M: f64 = 100_000.0;
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
    /// Vertical fan `[lower, upper]` elevations, radians, `-π/2 < lower ≤ upper < π/2`: the rays span it, and its
    /// height is the half-power beamwidth of the Gaussian elevation pattern centred on it
    /// ([`RadarConfig::two_way_gain`]).
    pub elevation_fan_rad: [f64; 2],
    /// Rays per beam across the beamwidth (`≥ 1`).
    pub rays_az: u32,
    /// Rays per beam over the elevation fan (`≥ 1`).
    pub rays_el: u32,
    /// Rays cast straight at each target per beam spacing its angular box spans in azimuth (`0..=`
    /// [`MAX_TARGET_RAYS`]; 0: none, the fan's rays alone), combined with the fan's without bias (`targets`).
    pub target_rays: u32,
    /// Share of the elevation rays spread over the horizon band (`0..=1`; 0 = uniform over the fan).
    pub horizon_fraction: f64,
    /// Half-height of the horizon band, radians (`0..=π/4`).
    pub horizon_band_rad: f64,
    /// Smallest reported intensity (`≥ 0`; see [`crate::sensors::radar_model`] for the unit).
    pub detection_threshold: f64,
    /// Standard deviation of Gaussian noise added to the reported range, metres (`≥ 0`).
    pub range_noise_std_m: f64,
    /// Sea and rain clutter.
    pub clutter: ClutterModel,
    /// Carrier frequency, GHz (`0.5..=35`, the NRL sea-clutter model's range; 9.41 = X band): sea clutter's σ⁰,
    /// rain clutter's reflectivity (`∝ f⁴`) and rain attenuation follow it ([`crate::sensors::radar_model`]).
    pub frequency_ghz: f64,
    /// Polarisation (transmit = receive): sea clutter's σ⁰ and rain attenuation follow it.
    pub polarisation: Polarisation,
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
            target_rays: 16,
            horizon_fraction: 0.75,
            horizon_band_rad: 1.0f64.to_radians(),
            detection_threshold: 0.01,
            range_noise_std_m: 0.0,
            clutter: ClutterModel::tuning(),
            frequency_ghz: MARINE_FREQUENCY_GHZ,
            polarisation: Polarisation::Horizontal,
        }
    }

    /// The radar's frequency and polarisation.
    pub fn band(&self) -> Band {
        Band { frequency_ghz: self.frequency_ghz, polarisation: self.polarisation }
    }
}

pub(super) fn nonneg(field: &str, v: f64, max: f64) -> Result<()> {
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
        if self.target_rays > MAX_TARGET_RAYS {
            return Err(MmusvError::config(
                "radar.target_rays",
                self.target_rays,
                format!("must be in 0..={MAX_TARGET_RAYS} rays per target per beam spacing"),
            ));
        }
        nonneg("horizon_fraction", self.horizon_fraction, 1.0)?;
        nonneg("horizon_band_rad", self.horizon_band_rad, std::f64::consts::FRAC_PI_4)?;
        nonneg("detection_threshold", self.detection_threshold, f64::MAX)?;
        nonneg("range_noise_std_m", self.range_noise_std_m, MAX_RANGE_M)?;
        nonneg("clutter.sea_sigma0_at_1m", self.clutter.sea_sigma0_at_1m, 1.0)?;
        nonneg("clutter.critical_range_per_m", self.clutter.critical_range_per_m, MAX_RANGE_M)?;
        nonneg("clutter.sea_max_range_m", self.clutter.sea_max_range_m, MAX_RANGE_M)?;
        nonneg("clutter.rain_eta_at_1mm_h", self.clutter.rain_eta_at_1mm_h, 1.0)?;
        let [f_lo, f_hi] = FREQUENCY_RANGE_GHZ;
        if !(self.frequency_ghz.is_finite() && (f_lo..=f_hi).contains(&self.frequency_ghz)) {
            return Err(MmusvError::config(
                "radar.frequency_ghz",
                self.frequency_ghz,
                format!("must be in [{f_lo}, {f_hi}] GHz (the NRL sea-clutter model's range; 9.41 = X band)"),
            ));
        }
        Ok(())
    }

    /// Rays per sweep: `azimuth_bins · rays_az · rays_el`.
    pub fn num_rays(&self) -> u64 {
        self.azimuth_bins as u64 * self.rays_az as u64 * self.rays_el as u64
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
