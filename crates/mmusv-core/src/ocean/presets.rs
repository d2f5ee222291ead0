//! Sea-state presets: the WMO sea state code (Douglas scale) 0–9 and the paper's W0–W3, as (Hs, Tp, γ, wind).
//!
//! Sources:
//! - WMO code table 3700 "State of the sea" (WMO-No. 306, Manual on Codes), the Douglas sea scale: code `n` is a
//!   band of significant wave height (0 calm-glassy 0 m; 1 calm-rippled 0–0.1 m; 2 smooth 0.1–0.5 m; 3 slight
//!   0.5–1.25 m; 4 moderate 1.25–2.5 m; 5 rough 2.5–4 m; 6 very rough 4–6 m; 7 high 6–9 m; 8 very high 9–14 m;
//!   9 phenomenal over 14 m). The preset takes the band's middle (16 m for code 9).
//! - The paper's W0–W3 are wave-height bands 0–1, 1–2, 2–3, 3–4 m; the preset takes the paper's `H` (0.5, 1.5,
//!   2.5, 3.5 m, as in `kinematics::waves`) as Hs.
//! - Peak period and wind of a fully developed sea (Pierson & Moskowitz 1964): `Hs = 0.21 U²/g` and
//!   `ωp = 0.877 g/U` with `U` the wind speed at 19.5 m, hence `U = √(g Hs/0.21)`, `Tp = 2π U/(0.877 g)
//!   ≈ 4.99 √Hs` (Hs in m, Tp in s).
//! - Peak enhancement from the period (DNV-RP-C205 §3.5.5.5): `γ = exp(5.75 − 1.15 Tp/√Hs)` for
//!   `3.6 ≤ Tp/√Hs < 5`, 5 below and 1 above ([`dnv_gamma`]), for seas given with their own period; the presets
//!   are fully developed seas, γ = 1 (Pierson–Moskowitz), which DNV's relation also gives (≈ 1.01 at 4.99√Hs).

use super::field::SeaSpec;
use super::spectrum::GRAVITY;
use crate::error::{MmusvError, Result};
use std::f64::consts::TAU;

/// The cos-2s spreading of a wind sea used by the presets: s = 10 (Goda, Y. (1985), "Random Seas and Design of
/// Maritime Structures", recommends s_max = 10 for wind waves).
pub const WIND_SEA_SPREAD: f64 = 10.0;

/// Peak period used for a flat sea (Hs = 0), where it has no effect.
pub const FLAT_SEA_TP: f64 = 1.0;

/// A named sea state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeaPreset {
    /// `"0"`..`"9"` (WMO code) or `"W0"`..`"W3"` (paper).
    pub name: &'static str,
    /// WMO description or the paper's band.
    pub description: &'static str,
    /// Significant wave height (m).
    pub hs_m: f64,
    /// Peak period (s), fully developed.
    pub tp_s: f64,
    /// Peak enhancement γ: 1, a fully developed (Pierson–Moskowitz) sea.
    pub gamma: f64,
    /// Wind speed at 19.5 m (m/s) that fully develops this sea.
    pub wind_mps: f64,
}

impl SeaPreset {
    /// The sea spec of this preset, waves travelling towards `direction_rad`, cos-2s exponent `spread_s`.
    pub fn spec(&self, direction_rad: f64, spread_s: f64) -> SeaSpec {
        SeaSpec { hs: self.hs_m, tp: self.tp_s, gamma: self.gamma, direction_rad, spread_s }
    }
}

/// `(Tp s, U₁₉.₅ m/s)` of a fully developed Pierson–Moskowitz sea of significant height `hs` (m).
pub fn fully_developed(hs: f64) -> (f64, f64) {
    let u = (GRAVITY * hs / 0.21).sqrt();
    let tp = if hs > 0.0 { TAU * u / (0.877 * GRAVITY) } else { FLAT_SEA_TP };
    (tp, u)
}

/// DNV-RP-C205 §3.5.5.5 peak enhancement: `exp(5.75 − 1.15 Tp/√Hs)` clamped to [1, 5] (1 for Hs = 0).
pub fn dnv_gamma(hs: f64, tp: f64) -> f64 {
    if hs <= 0.0 {
        return 1.0;
    }
    let r = tp / hs.sqrt();
    if r < 3.6 {
        5.0
    } else if r >= 5.0 {
        1.0
    } else {
        (5.75 - 1.15 * r).exp().clamp(1.0, 5.0)
    }
}

fn preset(name: &'static str, description: &'static str, hs: f64) -> SeaPreset {
    let (tp, wind) = fully_developed(hs);
    SeaPreset { name, description, hs_m: hs, tp_s: tp, gamma: 1.0, wind_mps: wind }
}

/// WMO sea state codes 0–9 (Douglas sea scale), in order.
pub fn wmo_sea_states() -> [SeaPreset; 10] {
    [
        preset("0", "calm (glassy), 0 m", 0.0),
        preset("1", "calm (rippled), 0-0.1 m", 0.05),
        preset("2", "smooth (wavelets), 0.1-0.5 m", 0.3),
        preset("3", "slight, 0.5-1.25 m", 0.875),
        preset("4", "moderate, 1.25-2.5 m", 1.875),
        preset("5", "rough, 2.5-4 m", 3.25),
        preset("6", "very rough, 4-6 m", 5.0),
        preset("7", "high, 6-9 m", 7.5),
        preset("8", "very high, 9-14 m", 11.5),
        preset("9", "phenomenal, over 14 m", 16.0),
    ]
}

/// The paper's W0–W3 (H = 0.5, 1.5, 2.5, 3.5 m taken as Hs), in order.
pub fn paper_sea_states() -> [SeaPreset; 4] {
    [
        preset("W0", "paper W0, waves 0-1 m", 0.5),
        preset("W1", "paper W1, waves 1-2 m", 1.5),
        preset("W2", "paper W2, waves 2-3 m", 2.5),
        preset("W3", "paper W3, waves 3-4 m", 3.5),
    ]
}

/// The preset of a WMO code `0`..`9`; errors name `sea.state`.
pub fn wmo_sea_state(code: u8) -> Result<SeaPreset> {
    wmo_sea_states()
        .get(usize::from(code))
        .copied()
        .ok_or_else(|| MmusvError::config("sea.state", code, "must be a WMO sea state code 0..9 (Douglas scale)"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ocean::WaveField;

    #[test]
    fn fully_developed_periods_follow_pierson_moskowitz() {
        for hs in [0.5, 1.0, 3.5, 10.0] {
            let (tp, u) = fully_developed(hs);
            // Back to the PM relations: Hs = 0.21 U²/g and ωp U / g = 0.877.
            assert!((0.21 * u * u / GRAVITY - hs).abs() < 1e-12);
            assert!(((TAU / tp) * u / GRAVITY - 0.877).abs() < 1e-12);
            assert!((tp / hs.sqrt() - 4.992).abs() < 2e-3);
            assert!((dnv_gamma(hs, tp) - 1.0).abs() < 0.02);
        }
        assert_eq!(dnv_gamma(2.0, 3.0 * 2f64.sqrt()), 5.0);
        assert!((dnv_gamma(4.0, 8.4) - (5.75f64 - 1.15 * 4.2).exp()).abs() < 1e-12);
    }

    #[test]
    fn every_preset_makes_a_valid_monotonic_sea() {
        let states = wmo_sea_states();
        assert!(states.windows(2).all(|w| w[1].hs_m > w[0].hs_m && w[1].wind_mps > w[0].wind_mps));
        for p in states.iter().chain(paper_sea_states().iter()) {
            let spec = p.spec(0.4, WIND_SEA_SPREAD);
            assert!(WaveField::new(&spec, 1).is_ok(), "{p:?}");
        }
        let w: Vec<f64> = paper_sea_states().iter().map(|p| p.hs_m).collect();
        let paper: Vec<f64> =
            crate::kinematics::WaveSetting::PRESETS.iter().map(crate::kinematics::WaveSetting::height_m).collect();
        assert_eq!(w, paper);
        assert!(matches!(wmo_sea_state(10), Err(MmusvError::Config { field, .. }) if field == "sea.state"));
    }
}
