//! The physics of the marine radar, in one place: target echo power, rain attenuation, sea and rain clutter.
//!
//! Intensity unit: received power relative to the echo of a 1 m² target at [`REFERENCE_RANGE_M`] (1 km) in
//! clear air, linear (so `0.01` is −20 dB, a 1 m² target at ≈3.2 km). Every term below is the radar equation
//! `P ∝ σ / r⁴`, written as `σ · (R_ref / r)⁴ · L_rain(r)`.
//!
//! * **Targets** (every ray hit that is not water): a ray at elevation `e` standing for `Δφ` of the beamwidth
//!   and `Δe` of the fan stands for the solid angle `Ω = Δφ · Δe · cos e` (the `cos e` of the sphere's area
//!   element: until 2026-12-01 it was left out, and a target 40° above the horizon came out 1/cos 40° = 1.3 times
//!   too bright), so at range `r` it covers `Ω r²` m² of the plane facing the sensor and returns, for a surface
//!   of radar reflectivity `ρ` hit at incidence `θ`, `σ = ρ · |cos θ| · Ω r²`: a diffuse surface whose
//!   backscatter per unit of its own area is `σ⁰ = ρ cos²θ` (a quarter of a Lambertian reflector's
//!   `4 ρ cos²θ`; `ρ` is a per-class radar reflectivity, not an albedo), so a face-on patch of `A` m² is a
//!   target of `ρ A` m². Summing rays over a cell makes the echo grow with the target's visible size (more rays
//!   hit it). `ρ` per class: [`class_reflectivity`]. Each ray's echo is weighted by the fan's two-way elevation
//!   gain `G²(e)` (Gaussian main lobe, `radar/pattern.rs`; 1 on the fan's axis). This diffuse-target law and the
//!   per-class `ρ` are the project's own choice, not a published target model (none was found, 2026-12-02): the
//!   `cos²θ` is the Lambertian one, the factor ¼ and the `ρ` values only set how bright each class is.
//! * **Rain attenuation** (two-way): specific attenuation `γ = k · R^α` dB/km for a rain rate `R` in mm/h, with
//!   `k` and `α` of the radar's frequency `f` and polarisation from ITU-R P.838-3 (2005), "Specific attenuation
//!   model for rain for use in prediction methods", eqs. (2)–(3) and Tables 1–4: `log10 k = Σⱼ aⱼ exp(−((log10 f −
//!   bⱼ)/cⱼ)²) + m_k log10 f + c_k`, `α = Σⱼ aⱼ exp(−((log10 f − bⱼ)/cⱼ)²) + m_α log10 f + c_α` (fitted over
//!   1–1000 GHz; below 1 GHz, where rain's loss is under 10⁻⁴ dB/km, the fit is extrapolated);
//!   `L_rain(r) = 10^(−2 γ r_km / 10)` ([`RainLoss`]). At 9.41 GHz HH `k = 0.00930`, `α = 1.2895` (0.181 dB/km at
//!   10 mm/h); until 2026-12-01 every radar used the 10 GHz HH table values `k = 0.01217`, `α = 1.2571`
//!   (0.220 dB/km at 10 mm/h, 21 % too much for the 9.41 GHz radar).
//! * **Sea clutter**: mean `μ_sea = σ⁰(H) · A(r) · g(r) · (R_ref/r)⁴ · L_rain(r)` with wave height `H` (m),
//!   `σ⁰(H) = sea_sigma0_at_1m · H²`, the pulse-limited cell area `A = r · θ_az · Δr · sec ψ` at grazing ψ
//!   (Skolnik §13.2, [`CellShape::sea_area`]; until 2026-12-01 without the `sec ψ`), and past the critical range
//!   `R_c = critical_range_per_m · H` the interference fall-off `g = (R_c / r)⁴` (so clutter falls as `r⁻³`
//!   close in and `r⁻⁷` beyond `R_c`: higher waves give stronger clutter reaching farther); zero beyond
//!   `sea_max_range_m` and for `H = 0`. This flat-sea rule is the project's calibration, not a published model: no
//!   source for `σ⁰ ∝ H²` was found (2026-12-02), and `R_c = 300 m` per metre of `H` is a tuned constant (it does
//!   not follow the antenna's height or the wavelength). What is published is its fall-off: below a "critical
//!   angle" the direct field and the one the sea reflects interfere destructively (Katzin, M. (1957), "On the
//!   Mechanisms of Radar Sea Clutter", Proc. IRE 45(1), 44–54), and interference theory predicts `σ⁰ ∝ ψ⁴` at
//!   small grazing angles ψ, some measurements conforming, while empirical models give `ψ²` (Sittrop, the HYB
//!   model) or about `ψ` (the GIT model) (Nathanson, *Radar Design Principles*, 2nd ed., §7.8). With `ψ ≈ h / r`,
//!   `(R_c / r)⁴` is the `ψ⁴` law beyond `R_c`; within it the rule has no grazing dependence at all. It is used
//!   only where the scene has no displaced wave surface: `environment.motion: paper` scenarios (flat water),
//!   `Simulation.set_sea_surface(None)` or a sea of `Hs = 0`, and core users who set no wave surface; its knobs are
//!   the scenario's `sea_clutter_sigma0` (4·10⁻⁷) and `clutter_critical_range_per_m` (300). Scenarios by default
//!   (`motion: physical`) take the NRL model below.
//!   Over the physical sea (a scene with a displaced wave surface) σ⁰ instead follows sea state and grazing
//!   angle by the NRL model of Gregers-Hansen & Mital (2012), `sensors/radar/sea_clutter.rs`, and the sea part
//!   is `σ⁰ · A(r) · (R_ref/r)⁴ · L_rain(r)` ([`clutter_mean_sigma0`]). Either is weighted per beam by the fan's
//!   two-way gain `G²` at the elevation where that water lies in the sensor frame (`radar/pattern.rs`).
//! * **Rain clutter**: the volume reflectivity of rain is that of Rayleigh scattering by drops small against the
//!   wavelength λ, `η = π⁵ |K|² Z / λ⁴` (m²/m³, `Z` in m⁶/m³, `|K|² ≈ 0.93` for water), with the reflectivity
//!   factor of Marshall & Palmer (1948), `Z = 200 R^1.6` mm⁶/m³ for a rain rate `R` in mm/h (Skolnik, M. I.
//!   (2001), "Introduction to Radar Systems", 3rd ed., §13.6 Weather Clutter; Nathanson, F. E. (1991), "Radar
//!   Design Principles", 2nd ed.); at 9.41 GHz that is `5.5·10⁻⁸ R^1.6` m²/m³. Here
//!   `η = rain_eta_at_1mm_h · R^1.6 · (f / 9.41 GHz)⁴`: the knob is η at 1 mm/h for an X-band 9.41 GHz radar,
//!   and the `λ⁻⁴` of the formula carries it to the radar's frequency `f`
//!   (`|K|²` of water changes by under 1 % between 3 and 10 GHz; until 2026-12-01 η did not depend on the
//!   frequency, which was fixed). η times the cell volume `r² · θ_az · θ_el √(π / (8 ln 2)) · Δr` (the fan's
//!   Gaussian two-way elevation pattern integrated, `radar/pattern.rs`; until 2026-12-01 the full `θ_el`), same
//!   `(R_ref/r)⁴ · L_rain(r)`. (The scenario default `rain_clutter_eta` 5·10⁻⁹ is 10.4 dB below
//!   Marshall–Palmer's 5.5·10⁻⁸.)
//! * A cell's clutter intensity is exponentially distributed (Rayleigh amplitude) with mean `μ_sea + μ_rain`,
//!   drawn from `−ln u` with `u` uniform; so for a fixed seed the clutter of a cell grows monotonically with
//!   the wave height and rain rate, and a clutter-only cell is reported with probability `exp(−threshold/μ)`.

use crate::sensors::radar::sea_clutter::{Polarisation, MARINE_FREQUENCY_GHZ};

/// Range at which a 1 m² target has intensity 1, metres.
pub const REFERENCE_RANGE_M: f64 = 1000.0;
/// ITU-R P.838-3 Tables 1 and 2: `(aⱼ, bⱼ, cⱼ)` and `(m_k, c_k)` of `log10 k`, horizontal then vertical.
const P838_K: [([[f64; 3]; 4], [f64; 2]); 2] = [
    (
        [
            [-5.33980, -0.10008, 1.13098],
            [-0.35351, 1.26970, 0.45400],
            [-0.23789, 0.86036, 0.15354],
            [-0.94158, 0.64552, 0.16817],
        ],
        [-0.18961, 0.71147],
    ),
    (
        [
            [-3.80595, 0.56934, 0.81061],
            [-3.44965, -0.22911, 0.51059],
            [-0.39902, 0.73042, 0.11899],
            [0.50167, 1.07319, 0.27195],
        ],
        [-0.16398, 0.63297],
    ),
];
/// ITU-R P.838-3 Tables 3 and 4: `(aⱼ, bⱼ, cⱼ)` and `(m_α, c_α)` of `α`, horizontal then vertical.
const P838_ALPHA: [([[f64; 3]; 5], [f64; 2]); 2] = [
    (
        [
            [-0.14318, 1.82442, -0.55187],
            [0.29591, 0.77564, 0.19822],
            [0.32177, 0.63773, 0.13164],
            [-5.37610, -0.96230, 1.47828],
            [16.1721, -3.29980, 3.43990],
        ],
        [0.67849, -1.95537],
    ),
    (
        [
            [-0.07771, 2.33840, -0.76284],
            [0.56727, 0.95545, 0.54039],
            [-0.20238, 1.14520, 0.26809],
            [-48.2991, 0.791669, 0.116226],
            [48.5833, 0.791459, 0.116479],
        ],
        [-0.053739, 0.83433],
    ),
];

/// `Σⱼ aⱼ exp(−((x − bⱼ)/cⱼ)²) + m x + c` of ITU-R P.838-3 eqs. (2)–(3) at `x = log10 f`.
fn p838(terms: &[[f64; 3]], [m, c]: [f64; 2], x: f64) -> f64 {
    terms.iter().map(|&[a, b, cj]| a * (-((x - b) / cj).powi(2)).exp()).sum::<f64>() + m * x + c
}

/// Semantic class of the sea surface (`mmusv.classes.SemanticClass.WATER`).
pub const CLASS_WATER: u16 = 1;

/// The frequency (GHz) at which `ClutterModel::rain_eta_at_1mm_h` is given: an X-band marine radar.
pub const RAIN_ETA_REFERENCE_GHZ: f64 = MARINE_FREQUENCY_GHZ;

/// The radar's carrier: what its clutter depends on besides the geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// Carrier frequency, GHz.
    pub frequency_ghz: f64,
    /// Polarisation (transmit = receive).
    pub polarisation: Polarisation,
}

impl Band {
    /// An X-band marine radar, 9.41 GHz, HH.
    pub const MARINE_X: Band = Band { frequency_ghz: MARINE_FREQUENCY_GHZ, polarisation: Polarisation::Horizontal };

    /// ITU-R P.838-3's `(k, α)` of the specific rain attenuation `γ = k R^α` dB/km at this frequency and
    /// polarisation.
    pub fn rain_attenuation_coefficients(&self) -> (f64, f64) {
        let pol = match self.polarisation {
            Polarisation::Horizontal => 0,
            Polarisation::Vertical => 1,
        };
        let x = self.frequency_ghz.log10();
        let (kt, kl) = P838_K[pol];
        let (at, al) = P838_ALPHA[pol];
        (10f64.powf(p838(&kt, kl, x)), p838(&at, al, x))
    }

    /// The factor `(f / 9.41 GHz)⁴ = (λ_X / λ)⁴` that carries a rain reflectivity given at X band to this
    /// frequency (Rayleigh scattering, `η ∝ λ⁻⁴`); exactly 1 at 9.41 GHz.
    pub fn rain_eta_factor(&self) -> f64 {
        let q = self.frequency_ghz / RAIN_ETA_REFERENCE_GHZ;
        (q * q) * (q * q)
    }
}

/// Sea and rain clutter knobs (see the module documentation for the formulas).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClutterModel {
    /// Normalised sea-clutter cross-section σ⁰ (m²/m²) at 1 m wave height; scales with `H²`. `0` disables it.
    pub sea_sigma0_at_1m: f64,
    /// Critical range per metre of wave height (m/m): beyond `R_c = this · H` sea clutter falls as `r⁻⁷`.
    pub critical_range_per_m: f64,
    /// No sea clutter beyond this range, metres.
    pub sea_max_range_m: f64,
    /// Rain volume reflectivity η (m²/m³) at 1 mm/h; scales with `R^1.6`. `0` disables rain clutter.
    pub rain_eta_at_1mm_h: f64,
}

impl ClutterModel {
    /// The clutter the core's unit tests and benchmarks are written against: with the 1.2° beam, 3 m cells and threshold
    /// 0.01 of [`crate::sensors::radar::RadarConfig::tuning`], sea clutter reaches ≈200 m at 0.5 m waves and
    /// ≈1 km at 3.5 m waves, and 10 mm/h of rain shows sparse clutter within ≈1 km. A test fixture: the user
    /// defaults (σ⁰ 4e-7 with threshold 0.3) live in the scenario schema, `mmusv.sensors.config.RadarConfig`.
    pub fn tuning() -> Self {
        Self {
            sea_sigma0_at_1m: 4.0e-6,
            critical_range_per_m: 300.0,
            sea_max_range_m: 2500.0,
            rain_eta_at_1mm_h: 5.0e-9,
        }
    }
}

/// Diffuse radar reflectivity `ρ` of a semantic class (ids of `mmusv.classes`): metal structures (vessels,
/// USVs, containers, cranes, buoys with reflectors) 1.0, quays and buildings 0.6, bare terrain 0.3,
/// vegetation 0.2, anything else 0.5.
pub fn class_reflectivity(class: u16) -> f64 {
    match class {
        5 | 6 | 7 | 10 | 11 => 1.0,
        4 | 8 => 0.6,
        2 => 0.3,
        3 => 0.2,
        _ => 0.5,
    }
}

/// Two-way rain loss of a radar in a band through rain of a given rate (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RainLoss {
    /// Specific attenuation `γ = k R^α`, dB/km (one way); 0 without rain.
    pub gamma_db_per_km: f64,
}

impl RainLoss {
    /// The loss of a radar in `band` through `rain_mm_per_h` of rain (ITU-R P.838-3).
    pub fn new(band: &Band, rain_mm_per_h: f64) -> Self {
        if rain_mm_per_h <= 0.0 {
            return Self { gamma_db_per_km: 0.0 };
        }
        let (k, alpha) = band.rain_attenuation_coefficients();
        Self { gamma_db_per_km: k * rain_mm_per_h.powf(alpha) }
    }

    /// Two-way loss factor `L_rain(r) = 10^(−2 γ r_km / 10) ∈ (0, 1]` at range `r` metres.
    pub fn at(&self, r: f64) -> f64 {
        if self.gamma_db_per_km <= 0.0 {
            return 1.0;
        }
        10f64.powf(-2.0 * self.gamma_db_per_km * (r / 1000.0) / 10.0)
    }
}

/// `(R_ref / r)⁴`, the radar-equation range term.
#[inline]
pub fn range_term(r: f64) -> f64 {
    let q = REFERENCE_RANGE_M / r.max(1e-3);
    (q * q) * (q * q)
}

/// Echo power of one ray: class reflectivity `ρ`, `|cos incidence|`, solid angle per ray `omega_sr`, hit
/// range `r` metres, the rain's loss. See the module documentation.
#[inline]
pub fn ray_power(class: u16, cos_incidence: f64, omega_sr: f64, r: f64, rain: &RainLoss) -> f64 {
    class_reflectivity(class) * cos_incidence.abs() * omega_sr * r * r * range_term(r) * rain.at(r)
}

/// Geometry of one radar cell: the beam's azimuth width and elevation height (radians), range bin size (m), and
/// the antenna's height above the still water (m), which sets the grazing angle of the sea in the cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellShape {
    /// Azimuth beamwidth, radians.
    pub beamwidth_az: f64,
    /// Elevation extent of the fan, radians.
    pub fan_height: f64,
    /// Range bin size, metres.
    pub range_resolution: f64,
    /// Antenna height above the still water, metres (`≤ 0`: grazing 0, `sec ψ = 1`).
    pub antenna_height: f64,
}

impl CellShape {
    /// The sea surface a range cell at (slant) range `r` metres illuminates, m²: the pulse-limited clutter cell
    /// `A = r · θ_az · Δr · sec ψ` (Skolnik, "Introduction to Radar Systems", 3rd ed., §13.2; Barton (2013),
    /// "Radar Equations for Modern Radar": the beam's width `r θ_az` across, the slant-range bin `Δr`
    /// stretched to `Δr / cos ψ` along the water) at the 4/3-earth grazing angle ψ of
    /// [`crate::sensors::radar::sea_clutter::sin_grazing`], `ψ ≥ 0` (beyond the horizon the NRL model's own
    /// clamp to 0.1° stands: `sec ψ = 1`); zero where no water lies at that slant range (`r ≤ h`). The cell is
    /// pulse-limited while `Δr sec ψ < r θ_el / sin ψ`, i.e. `tan ψ < r θ_el / Δr`: everywhere beyond the blind
    /// range for a fan of a few degrees and metre-sized bins (the beam-limited `r² θ_az θ_el csc ψ` is not used).
    /// Until 2026-12-01 the `sec ψ` was left out (1.5 times too little clutter 20 m from an antenna 15 m up).
    pub fn sea_area(&self, r: f64) -> f64 {
        let s = crate::sensors::radar::sea_clutter::sin_grazing(self.antenna_height, r).max(0.0);
        if s >= 1.0 {
            return 0.0;
        }
        r * self.beamwidth_az * self.range_resolution / (1.0 - s * s).sqrt()
    }
}

/// Mean clutter intensity `(sea, rain)` of the cell at range `r` metres of a radar in `band` (see the module
/// documentation).
pub fn clutter_mean(
    model: &ClutterModel,
    cell: &CellShape,
    band: &Band,
    wave_height_m: f64,
    rain_mm_per_h: f64,
    r: f64,
) -> (f64, f64) {
    let loss = RainLoss::new(band, rain_mm_per_h).at(r);
    let common = range_term(r) * loss;
    let sea = if wave_height_m > 0.0 && r <= model.sea_max_range_m {
        let sigma0 = model.sea_sigma0_at_1m * wave_height_m * wave_height_m;
        let area = cell.sea_area(r);
        let rc = model.critical_range_per_m * wave_height_m;
        let falloff = if r > rc {
            let q = rc / r;
            (q * q) * (q * q)
        } else {
            1.0
        };
        sigma0 * area * falloff * common
    } else {
        0.0
    };
    (sea, rain_mean(model, cell, band, rain_mm_per_h, r, common))
}

/// The rain part of [`clutter_mean`] at range `r`, `common` its range term times the rain's two-way loss there.
fn rain_mean(model: &ClutterModel, cell: &CellShape, band: &Band, rain_mm_per_h: f64, r: f64, common: f64) -> f64 {
    if rain_mm_per_h <= 0.0 {
        return 0.0;
    }
    let eta = model.rain_eta_at_1mm_h * rain_mm_per_h.powf(1.6) * band.rain_eta_factor();
    // The fan's Gaussian two-way pattern integrated over elevation: ∫G² de = θ_el √(π / (8 ln 2)).
    let fan = cell.fan_height * (std::f64::consts::PI / (8.0 * std::f64::consts::LN_2)).sqrt();
    eta * r * r * cell.beamwidth_az * fan * cell.range_resolution * common
}

/// Mean clutter intensity `(sea, rain)` of the cell at range `r` metres over the physical sea, whose
/// normalised reflectivity there is `sigma0` (m²/m², see [`crate::sensors::radar::sea_clutter`]): the sea part is
/// `σ⁰ · A(r) · (R_ref/r)⁴ · L_rain(r)` (no fall-off factor: the low-grazing fall is in σ⁰), zero beyond
/// `sea_max_range_m`; the rain part as in [`clutter_mean`].
pub fn clutter_mean_sigma0(
    model: &ClutterModel,
    cell: &CellShape,
    band: &Band,
    sigma0: f64,
    rain_mm_per_h: f64,
    r: f64,
) -> (f64, f64) {
    let (loss, rt) = (RainLoss::new(band, rain_mm_per_h).at(r), range_term(r));
    let sea = if sigma0 > 0.0 && r <= model.sea_max_range_m { sigma0 * cell.sea_area(r) * rt * loss } else { 0.0 };
    (sea, rain_mean(model, cell, band, rain_mm_per_h, r, rt * loss))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CELL: CellShape =
        CellShape { beamwidth_az: 0.0209, fan_height: 0.349, range_resolution: 3.0, antenna_height: 4.0 };

    #[test]
    fn reference_target_has_unit_intensity_and_rain_attenuates() {
        // A face-on 1 m² metal patch at 1 km: Ω r² = 1 m².
        let omega = 1.0 / (REFERENCE_RANGE_M * REFERENCE_RANGE_M);
        let dry = RainLoss::new(&Band::MARINE_X, 0.0);
        assert!((ray_power(10, 1.0, omega, REFERENCE_RANGE_M, &dry) - 1.0).abs() < 1e-12);
        // 10 mm/h over 1 km two-way at 9.41 GHz HH: 2 · 0.00930 · 10^1.2895 dB = 0.362 dB.
        let db = -10.0 * RainLoss::new(&Band::MARINE_X, 10.0).at(1000.0).log10();
        assert!((db - 0.362).abs() < 0.002, "{db}");
        assert_eq!(RainLoss::new(&Band::MARINE_X, 0.0).at(5000.0), 1.0);
        // Echo of the same target falls as r^-2 at fixed ray density (r^2 footprint, r^-4 radar equation).
        let near = ray_power(10, 1.0, 1e-4, 500.0, &dry);
        let far = ray_power(10, 1.0, 1e-4, 1000.0, &dry);
        assert!((near / far - 4.0).abs() < 1e-9);
    }

    /// Rain attenuation is ITU-R P.838-3's at the radar's frequency and polarisation: at 10 GHz the
    /// Recommendation's tabulated `k` and `α` (H 0.01217, 1.2571; V 0.01129, 1.2156); at the X-band radar's
    /// 9.41 GHz HH `k = 0.00930`, `α = 1.2895` (from the Recommendation's equations, evaluated independently);
    /// S band (3.05 GHz) loses almost nothing. Until 2026-12-01 every radar used the 10 GHz HH values: the
    /// 9.41 GHz radar lost 0.220 dB/km at 10 mm/h instead of 0.181.
    #[test]
    fn rain_attenuation_is_p838_at_the_radars_band() {
        let band = |f: f64, polarisation: Polarisation| Band { frequency_ghz: f, polarisation };
        for (pol, k_want, a_want) in
            [(Polarisation::Horizontal, 0.01217, 1.2571), (Polarisation::Vertical, 0.01129, 1.2156)]
        {
            let (k, a) = band(10.0, pol).rain_attenuation_coefficients();
            assert!((k / k_want - 1.0).abs() < 5e-4 && (a - a_want).abs() < 1e-4, "{pol:?}: k {k}, α {a}");
        }
        let (k, a) = Band::MARINE_X.rain_attenuation_coefficients();
        assert!((k / 0.009299 - 1.0).abs() < 1e-3 && (a - 1.28951).abs() < 1e-4, "9.41 GHz: k {k}, α {a}");
        let gamma = RainLoss::new(&Band::MARINE_X, 10.0).gamma_db_per_km;
        assert!((gamma - 0.18112).abs() < 2e-4, "{gamma} dB/km");
        let s_band = RainLoss::new(&band(3.05, Polarisation::Vertical), 10.0).gamma_db_per_km;
        assert!(s_band > 0.0 && s_band < 0.02 * gamma, "S band {s_band} dB/km");
    }

    #[test]
    fn sea_clutter_grows_with_waves_and_falls_with_range() {
        let m = ClutterModel::tuning();
        let at = |h: f64, r: f64| clutter_mean(&m, &CELL, &Band::MARINE_X, h, 0.0, r).0;
        assert_eq!(at(0.0, 100.0), 0.0);
        for r in [50.0, 200.0, 800.0, 2000.0] {
            assert!(at(3.5, r) > at(0.5, r), "r = {r}");
        }
        for h in [0.5, 1.5, 3.5] {
            assert!(at(h, 100.0) > at(h, 300.0) && at(h, 300.0) > at(h, 1200.0), "h = {h}");
        }
        assert_eq!(at(3.5, m.sea_max_range_m + 1.0), 0.0);
        // Rain clutter exists only with rain.
        assert_eq!(clutter_mean(&m, &CELL, &Band::MARINE_X, 0.0, 0.0, 300.0).1, 0.0);
        assert!(clutter_mean(&m, &CELL, &Band::MARINE_X, 0.0, 5.0, 300.0).1 > 0.0);
    }
}
