//! Sea clutter of the physical sea: the NRL empirical model of the normalised sea-clutter reflectivity σ⁰ as a
//! function of radar frequency, polarisation, sea state and grazing angle.
//!
//! Model: Gregers-Hansen, V. & Mital, R. (2012), "An Improved Empirical Model for Radar Sea Clutter
//! Reflectivity", IEEE Trans. Aerosp. Electron. Syst. 48(4), 3512–3524 (NRL/MR/5310--12-9346), fitted to the
//! tables of Nathanson (1991) for 0.5–35 GHz, sea states 0–6 and grazing angles 0.1–60°:
//!
//! ```text
//! σ⁰ (dB) = c1 + c2 log10(sin ψ) + (27.5 + c3 ψ) log10(f) / (1 + 0.95 ψ)
//!           + c4 (SS + 1)^(1 / (2 + 0.085 ψ + 0.033 SS)) + c5 ψ²
//! ```
//!
//! with ψ the grazing angle in degrees, `f` in GHz, `SS` the (continuous) Douglas sea state, and for the 0–60°
//! fit HH: `c = (−73.0, 20.781, 7.351, 25.65, 0.0054)`, VV: `c = (−50.796, 25.93, 0.7093, 21.588, 0.00211)`.
//! It is an *apparent* reflectivity: the shadowing of the troughs by the crests and the propagation close to the
//! surface at low grazing angles are in it (hence the steep fall with ψ). Marine radars are mostly X-band,
//! horizontally polarised ([`MARINE_FREQUENCY_GHZ`], HH, the radar's default); the radar's `frequency_ghz` (the
//! model's 0.5–35 GHz, [`FREQUENCY_RANGE_GHZ`]) and `polarisation` (HH or VV) choose others, e.g. an S-band
//! 3.05 GHz radar (until 2026-12-01 the frequency and polarisation were fixed at 9.41 GHz HH).
//!
//! The grazing angle at range `r` of an antenna `h` above the still water is that of the 4/3-earth geometry,
//! `sin ψ = h / r − r / (2 k R_e)` (Barton, D. K. (2013), "Radar Equations for Modern Radar", §8), clamped
//! into the model's 0.1°–60°. The sea state follows the significant wave height by the WMO/Douglas code (WMO
//! code table 3700: state `s` is a band of Hs, 0.1, 0.5, 1.25, 2.5, 4 and 6 m the upper bounds of states 1–6),
//! each state at the middle of its band, where the project's WMO presets put it (`ocean::presets`: 0.05, 0.3,
//! 0.875, 1.875, 3.25, 5 m), interpolated linearly between those middles and 6 from 5 m on: a sea configured as
//! `state: 4` is the NRL model's sea state 4 (until 2026-12-01 the states sat at the bands' upper bounds, so a
//! WMO state-4 sea, Hs 1.875 m, was the model's 3.5, 1.1–2.5 dB low between 18° and 0.6° grazing).

/// Carrier frequency of an X-band marine radar, GHz (the radar's default).
pub const MARINE_FREQUENCY_GHZ: f64 = 9.41;
/// The frequencies the NRL model was fitted over (Nathanson's tables), GHz: the radar's `frequency_ghz` range.
pub const FREQUENCY_RANGE_GHZ: [f64; 2] = [0.5, 35.0];
/// Effective earth radius factor `k` of the standard atmosphere.
const EARTH_K: f64 = 4.0 / 3.0;
/// Earth radius, metres.
const EARTH_RADIUS_M: f64 = 6_371_000.0;
/// The model's grazing-angle range, degrees.
const GRAZING_RANGE_DEG: [f64; 2] = [0.1, 60.0];

/// Antenna polarisation (transmit = receive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Polarisation {
    /// Horizontal (marine radars).
    Horizontal,
    /// Vertical.
    Vertical,
}

impl Polarisation {
    /// Parses `"HH"` or `"VV"`; the error names `radar.polarisation` and what is allowed.
    pub fn parse(name: &str) -> crate::error::Result<Self> {
        match name {
            "HH" => Ok(Self::Horizontal),
            "VV" => Ok(Self::Vertical),
            other => Err(crate::error::MmusvError::config(
                "radar.polarisation",
                other,
                "must be \"HH\" (horizontal) or \"VV\" (vertical)",
            )),
        }
    }

    /// `"HH"` or `"VV"`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Horizontal => "HH",
            Self::Vertical => "VV",
        }
    }
}

/// NRL σ⁰ (m²/m², linear) at `f_ghz`, sea state `ss`, polarisation `pol` and grazing angle `psi_deg` (degrees).
pub fn nrl_sigma0(f_ghz: f64, ss: f64, pol: Polarisation, psi_deg: f64) -> f64 {
    let [c1, c2, c3, c4, c5] = match pol {
        Polarisation::Horizontal => [-73.0, 20.781, 7.351, 25.65, 0.0054],
        Polarisation::Vertical => [-50.796, 25.93, 0.7093, 21.588, 0.00211],
    };
    let psi = psi_deg;
    let db = c1
        + c2 * psi.to_radians().sin().log10()
        + (27.5 + c3 * psi) * f_ghz.log10() / (1.0 + 0.95 * psi)
        + c4 * (ss + 1.0).powf(1.0 / (2.0 + 0.085 * psi + 0.033 * ss))
        + c5 * psi * psi;
    10f64.powf(db / 10.0)
}

/// Highest sea state of the model's fit (Nathanson's tables: 0–6).
const MAX_SEA_STATE: usize = 6;

/// The continuous Douglas sea state of significant wave height `hs` (m): 0 for flat water; state `s` at the
/// middle of its WMO band (the WMO presets' Hs, [`crate::ocean::wmo_sea_states`]), linear between; 6 from 5 m on.
pub fn sea_state(hs: f64) -> f64 {
    let hs = hs.max(0.0);
    let presets = crate::ocean::wmo_sea_states();
    for s in 1..=MAX_SEA_STATE {
        let (lo, hi) = (presets[s - 1].hs_m, presets[s].hs_m);
        if hs <= hi {
            return (s - 1) as f64 + (hs - lo) / (hi - lo);
        }
    }
    MAX_SEA_STATE as f64
}

/// `sin ψ = h / r − r / (2 k R_e)`: the sine of the grazing angle at which an antenna `h` (m) above the still
/// water sees it at range `r` (m), 4/3 earth, not clamped (`≥ 1`: no water at that range, `r ≤ h`; `< 0`: beyond
/// the radar horizon).
pub fn sin_grazing(h: f64, r: f64) -> f64 {
    h.max(0.0) / r.max(1e-3) - r.max(1e-3) / (2.0 * EARTH_K * EARTH_RADIUS_M)
}

/// Grazing angle (degrees, clamped into 0.1°–60°) at range `r` (m) of an antenna `h` (m) above the
/// still water, 4/3 earth.
pub fn grazing_deg(h: f64, r: f64) -> f64 {
    let s = sin_grazing(h, r);
    let psi = s.clamp(-1.0, 1.0).asin().to_degrees();
    psi.clamp(GRAZING_RANGE_DEG[0], GRAZING_RANGE_DEG[1])
}

/// The sea clutter of one sweep over the physical sea: antenna height, sea state, the radar's frequency and
/// polarisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicalSea {
    /// Antenna height above the still water, metres.
    pub antenna_height_m: f64,
    /// Continuous Douglas sea state.
    pub sea_state: f64,
    /// Radar frequency, GHz.
    pub frequency_ghz: f64,
    /// Radar polarisation.
    pub polarisation: Polarisation,
}

impl PhysicalSea {
    /// The sea of significant wave height `hs` (m) seen by an X-band HH antenna `h` (m) above the still water
    /// ([`PhysicalSea::with_band`] sets another frequency and polarisation).
    pub fn new(hs: f64, h: f64) -> Self {
        Self {
            antenna_height_m: h.max(0.0),
            sea_state: sea_state(hs),
            frequency_ghz: MARINE_FREQUENCY_GHZ,
            polarisation: Polarisation::Horizontal,
        }
    }

    /// This sea seen by a radar at `frequency_ghz` with `polarisation`.
    pub fn with_band(self, frequency_ghz: f64, polarisation: Polarisation) -> Self {
        Self { frequency_ghz, polarisation, ..self }
    }

    /// σ⁰ (m²/m²) at range `r` (m), at the radar's frequency and polarisation.
    pub fn sigma0(&self, r: f64) -> f64 {
        if self.sea_state <= 0.0 {
            return 0.0;
        }
        nrl_sigma0(self.frequency_ghz, self.sea_state, self.polarisation, grazing_deg(self.antenna_height_m, r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nrl_model_gives_the_published_values() {
        // MATLAB's seareflectivity (NRL model): sea state 2, 10° grazing, 30 GHz, H → 2.1555e-04.
        let s = nrl_sigma0(30.0, 2.0, Polarisation::Horizontal, 10.0);
        assert!((s / 2.1555e-4 - 1.0).abs() < 1e-3, "{s}");
        // The closed form term by term at X band, sea state 4, 1°, VV.
        let psi: f64 = 1.0;
        let want_db = -50.796
            + 25.93 * psi.to_radians().sin().log10()
            + (27.5 + 0.7093) * 9.41f64.log10() / 1.95
            + 21.588 * 5f64.powf(1.0 / (2.0 + 0.085 + 0.132))
            + 0.00211;
        let got = 10.0 * nrl_sigma0(9.41, 4.0, Polarisation::Vertical, 1.0).log10();
        assert!((got - want_db).abs() < 1e-9, "{got} vs {want_db}");
    }

    /// A sea configured as WMO state `s` (the preset's Hs, the middle of the band) is the NRL model's sea state
    /// `s`: its σ⁰ is the published formula's at `SS = s`, written out here term by term, at grazing angles from
    /// 0.2° to 30°. (The states used to sit at the bands' upper bounds: state 3, Hs 0.875 m, was the model's 2.5.)
    #[test]
    fn a_wmo_sea_state_is_the_models_sea_state() {
        let nrl_hh_db = |ss: f64, psi: f64| {
            -73.0
                + 20.781 * psi.to_radians().sin().log10()
                + (27.5 + 7.351 * psi) * 9.41f64.log10() / (1.0 + 0.95 * psi)
                + 25.65 * (ss + 1.0).powf(1.0 / (2.0 + 0.085 * psi + 0.033 * ss))
                + 0.0054 * psi * psi
        };
        for preset in crate::ocean::wmo_sea_states().iter().take(7).skip(1) {
            let state: f64 = preset.name.parse().unwrap_or(f64::NAN);
            assert_eq!(sea_state(preset.hs_m), state, "WMO state {}", preset.name);
            let h = 6.0;
            for psi in [0.2f64, 1.0, 5.0, 30.0] {
                // The range at which an antenna 6 m up sees the still water at grazing ψ (4/3 earth).
                let (s, k) = (psi.to_radians().sin(), 2.0 * EARTH_K * EARTH_RADIUS_M);
                let r = (-s + (s * s + 4.0 * h / k).sqrt()) / (2.0 / k);
                assert!((grazing_deg(h, r) - psi).abs() < 1e-6);
                let got = 10.0 * PhysicalSea::new(preset.hs_m, h).sigma0(r).log10();
                let want = nrl_hh_db(state, psi);
                assert!((got - want).abs() < 1e-6, "state {state}, ψ {psi}°: {got} dB vs NRL {want} dB");
            }
        }
    }

    #[test]
    fn clutter_follows_sea_state_and_grazing_angle() {
        let at = |hs: f64, r: f64| PhysicalSea::new(hs, 4.0).sigma0(r);
        // More sea, more clutter; lower grazing (farther), less.
        for r in [100.0, 500.0, 2000.0] {
            assert!(at(0.5, r) < at(1.5, r) && at(1.5, r) < at(3.5, r), "r = {r}");
        }
        assert!(at(2.5, 100.0) > at(2.5, 400.0) && at(2.5, 400.0) > at(2.5, 1600.0));
        assert_eq!(at(0.0, 100.0), 0.0);
        // Douglas sea states at the middles of their bands, and between.
        assert_eq!(sea_state(1.875), 4.0);
        assert_eq!(sea_state(3.25), 5.0);
        assert!((sea_state(2.5625) - 4.5).abs() < 1e-12);
        assert_eq!(sea_state(5.0), 6.0);
        assert_eq!(sea_state(9.0), 6.0);
        // Grazing: h / r close in, the earth's curvature far out, clamped into the model's range.
        assert!((grazing_deg(10.0, 100.0) - (0.1f64.asin().to_degrees())).abs() < 1e-3);
        assert_eq!(grazing_deg(10.0, 50_000.0), 0.1);
        assert_eq!(grazing_deg(100.0, 10.0), 60.0);
    }
}
