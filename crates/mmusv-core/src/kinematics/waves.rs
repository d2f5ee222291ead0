//! Wave-driven heave, roll and pitch perturbations (paper eq. 2: the MMUSV-Sim paper's pose perturbation, see
//! [`super`]'s header for the reference).
//!
//! For vessel `v` at time `t` (seconds):
//!
//! ```text
//! [Δz, Δφ, Δθ] = S_wave(H) · α_v · [r_z · g_z(t), r_φ · g_φ(t), r_θ · g_θ(t)]
//! ```
//!
//! - `S_wave(H) = H / 1 m` — dimensionless and linear in the wave height `H`, so every RMS is linear in `H`
//!   ([`WaveSetting::scale`]).
//! - `α_v = clamp((V_ref / V)^(1/3), 0.05, 2.0)` with `V = length · beam · height` the bounding-box volume and
//!   `V_ref` that of the reference USV, 5 m × 2.5 m × 1.5 m ([`VesselDims::alpha`]): smaller vessels move more.
//! - `r_z` (m), `r_φ`, `r_θ` (rad): base amplitudes per vessel ([`BaseAmplitudes`]).
//! - `g(t) = (sin(2π f₁ t + φ₁) + w · sin(2π f₂ t + φ₂)) / (1 + w)`, `w = 0.5`: bounded in `[-1, 1]`, with
//!   frequencies and phases drawn per vessel from a seed ([`PeriodicSignal`], [`WaveSignals::from_seed`]).
//!   Its long-run RMS is `G_RMS = √((1 + w²) / 2) / (1 + w) ≈ 0.527`, whatever the draw.
//!
//! The default amplitudes are `r = k / G_RMS`, where `k` is the RMS per metre of `H` that a least-squares fit
//! through the origin gives for Table I of the paper (heave 0.0550 m, roll 0.4122°, pitch 0.1363° per metre), so
//! the reference USV reproduces that table.

use crate::error::{MmusvError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::TAU;
use std::fmt;
use std::str::FromStr;

/// Weight `w` of the second sinusoid in every `g(t)`.
pub const SECOND_WEIGHT: f64 = 0.5;

/// Long-run RMS of every `g(t)`: `√((1 + w²) / 2) / (1 + w)` with `w` = [`SECOND_WEIGHT`].
pub const G_RMS: f64 = 0.527_046_276_694_729_9;

/// Heave RMS per metre of wave height for the reference USV, in metres (Table I of the paper).
pub const REFERENCE_HEAVE_RMS_PER_M: f64 = 0.0550;
/// Roll RMS per metre of wave height for the reference USV, in degrees (Table I of the paper).
pub const REFERENCE_ROLL_RMS_DEG_PER_M: f64 = 0.4122;
/// Pitch RMS per metre of wave height for the reference USV, in degrees (Table I of the paper).
pub const REFERENCE_PITCH_RMS_DEG_PER_M: f64 = 0.1363;

/// Lower clamp of the size factor `α_v`.
pub const ALPHA_MIN: f64 = 0.05;
/// Upper clamp of the size factor `α_v`.
pub const ALPHA_MAX: f64 = 2.0;

/// Range of the first heave frequency `f₁` in Hz; `f₂ = f₁ · ratio` with ratio in [`SECOND_RATIO`].
pub const HEAVE_FREQ_HZ: [f64; 2] = [0.10, 0.20];
/// Range of the first roll frequency `f₁` in Hz.
pub const ROLL_FREQ_HZ: [f64; 2] = [0.08, 0.15];
/// Range of the first pitch frequency `f₁` in Hz.
pub const PITCH_FREQ_HZ: [f64; 2] = [0.12, 0.21];
/// Range of `f₂ / f₁`; together with the ranges above every frequency lies in 0.08–0.34 Hz.
pub const SECOND_RATIO: [f64; 2] = [1.3, 1.6];

/// The scene wave setting: a wave height `H` in metres, from a preset W0–W3 or given freely.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveSetting {
    height_m: f64,
    preset: Option<u8>,
}

impl WaveSetting {
    /// W0: waves 0–1 m, `H = 0.5` m.
    pub const W0: Self = Self { height_m: 0.5, preset: Some(0) };
    /// W1: waves 1–2 m, `H = 1.5` m.
    pub const W1: Self = Self { height_m: 1.5, preset: Some(1) };
    /// W2: waves 2–3 m, `H = 2.5` m.
    pub const W2: Self = Self { height_m: 2.5, preset: Some(2) };
    /// W3: waves 3–4 m, `H = 3.5` m.
    pub const W3: Self = Self { height_m: 3.5, preset: Some(3) };
    /// The presets in order W0, W1, W2, W3.
    pub const PRESETS: [Self; 4] = [Self::W0, Self::W1, Self::W2, Self::W3];

    /// A free wave height `H` in metres; it must be finite and ≥ 0 (`H = 0` is a flat sea).
    pub fn from_height(height_m: f64) -> Result<Self> {
        if !height_m.is_finite() || height_m < 0.0 {
            return Err(MmusvError::config("wave_height_m", height_m, "must be a finite wave height >= 0 m"));
        }
        Ok(Self { height_m, preset: None })
    }

    /// The wave height `H` in metres.
    pub fn height_m(&self) -> f64 {
        self.height_m
    }

    /// The wave amplitude `A = H / 2` in metres.
    pub fn amplitude_m(&self) -> f64 {
        self.height_m / 2.0
    }

    /// The perturbation scale `S_wave(H) = H / 1 m` (dimensionless, linear in `H`).
    pub fn scale(&self) -> f64 {
        self.height_m
    }

    /// `"W0"`..`"W3"` for a preset, `None` for a free height.
    pub fn preset_name(&self) -> Option<&'static str> {
        self.preset.and_then(|i| ["W0", "W1", "W2", "W3"].get(usize::from(i)).copied())
    }
}

impl fmt::Display for WaveSetting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.preset_name() {
            Some(name) => f.write_str(name),
            None => write!(f, "H={} m", self.height_m),
        }
    }
}

impl FromStr for WaveSetting {
    type Err = MmusvError;

    /// Parses `"W0"`..`"W3"` (case-insensitive, surrounding blanks ignored).
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_uppercase().as_str() {
            "W0" => Ok(Self::W0),
            "W1" => Ok(Self::W1),
            "W2" => Ok(Self::W2),
            "W3" => Ok(Self::W3),
            _ => Err(MmusvError::config(
                "wave",
                format!("{s:?}"),
                "allowed presets are W0, W1, W2, W3 (or give a wave height in metres)",
            )),
        }
    }
}

/// Approximate bounding box of a vessel, in metres, used for the size factor `α_v`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VesselDims {
    /// Length overall (m).
    pub length_m: f64,
    /// Beam (m).
    pub beam_m: f64,
    /// Height of the bounding box (m).
    pub height_m: f64,
}

impl VesselDims {
    /// The reference USV: 5 m × 2.5 m × 1.5 m, for which `α_v = 1`.
    pub const REFERENCE: Self = Self { length_m: 5.0, beam_m: 2.5, height_m: 1.5 };

    /// Checks that every dimension is finite and > 0; errors name `dims.<field>`.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in
            [("dims.length_m", self.length_m), ("dims.beam_m", self.beam_m), ("dims.height_m", self.height_m)]
        {
            if !v.is_finite() || v <= 0.0 {
                return Err(MmusvError::config(name, v, "must be a finite length > 0 m"));
            }
        }
        Ok(())
    }

    /// Bounding-box volume `V = length · beam · height` in m³.
    pub fn volume_m3(&self) -> f64 {
        self.length_m * self.beam_m * self.height_m
    }

    /// Size factor `α_v = clamp((V_ref / V)^(1/3), ALPHA_MIN, ALPHA_MAX)`.
    pub fn alpha(&self) -> f64 {
        (Self::REFERENCE.volume_m3() / self.volume_m3()).cbrt().clamp(ALPHA_MIN, ALPHA_MAX)
    }
}

impl Default for VesselDims {
    fn default() -> Self {
        Self::REFERENCE
    }
}

/// Base amplitudes `r_z` (m), `r_φ` and `r_θ` (rad) of one vessel, multiplied by `S_wave · α_v · g(t)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseAmplitudes {
    /// `r_z`, heave amplitude in metres per unit `S_wave · α_v`.
    pub heave_m: f64,
    /// `r_φ`, roll amplitude in radians per unit `S_wave · α_v`.
    pub roll_rad: f64,
    /// `r_θ`, pitch amplitude in radians per unit `S_wave · α_v`.
    pub pitch_rad: f64,
}

impl BaseAmplitudes {
    /// Checks that every amplitude is finite and ≥ 0; errors name `amplitudes.<field>`.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("amplitudes.heave_m", self.heave_m),
            ("amplitudes.roll_rad", self.roll_rad),
            ("amplitudes.pitch_rad", self.pitch_rad),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(MmusvError::config(name, v, "must be a finite amplitude >= 0"));
            }
        }
        Ok(())
    }
}

impl Default for BaseAmplitudes {
    /// `r = k / G_RMS` with `k` the Table I slopes: `r_z ≈ 0.1044` m, `r_φ ≈ 0.01365` rad (0.782°),
    /// `r_θ ≈ 0.004514` rad (0.259°).
    fn default() -> Self {
        Self {
            heave_m: REFERENCE_HEAVE_RMS_PER_M / G_RMS,
            roll_rad: REFERENCE_ROLL_RMS_DEG_PER_M.to_radians() / G_RMS,
            pitch_rad: REFERENCE_PITCH_RMS_DEG_PER_M.to_radians() / G_RMS,
        }
    }
}

/// A bounded periodic function `g(t) = (sin(2π f₁ t + φ₁) + w · sin(2π f₂ t + φ₂)) / (1 + w)` in `[-1, 1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicSignal {
    /// `[f₁, f₂]` in Hz.
    pub freq_hz: [f64; 2],
    /// `[φ₁, φ₂]` in radians.
    pub phase_rad: [f64; 2],
}

impl PeriodicSignal {
    /// `g(t)`, in `[-1, 1]`.
    pub fn value(&self, t: f64) -> f64 {
        let a = (TAU * self.freq_hz[0] * t + self.phase_rad[0]).sin();
        let b = (TAU * self.freq_hz[1] * t + self.phase_rad[1]).sin();
        (a + SECOND_WEIGHT * b) / (1.0 + SECOND_WEIGHT)
    }

    /// `dg/dt` in 1/s.
    pub fn derivative(&self, t: f64) -> f64 {
        let w0 = TAU * self.freq_hz[0];
        let w1 = TAU * self.freq_hz[1];
        let a = w0 * (w0 * t + self.phase_rad[0]).cos();
        let b = w1 * (w1 * t + self.phase_rad[1]).cos();
        (a + SECOND_WEIGHT * b) / (1.0 + SECOND_WEIGHT)
    }

    fn draw(rng: &mut ChaCha8Rng, f1_range: [f64; 2]) -> Self {
        let f1 = f1_range[0] + (f1_range[1] - f1_range[0]) * rng.random::<f64>();
        let ratio = SECOND_RATIO[0] + (SECOND_RATIO[1] - SECOND_RATIO[0]) * rng.random::<f64>();
        let p1 = TAU * rng.random::<f64>();
        let p2 = TAU * rng.random::<f64>();
        Self { freq_hz: [f1, f1 * ratio], phase_rad: [p1, p2] }
    }
}

/// The three functions `g_z`, `g_φ`, `g_θ` of one vessel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveSignals {
    /// `g_z(t)`.
    pub heave: PeriodicSignal,
    /// `g_φ(t)`.
    pub roll: PeriodicSignal,
    /// `g_θ(t)`.
    pub pitch: PeriodicSignal,
}

impl WaveSignals {
    /// Draws the signals of vessel `vessel_index` from a scenario seed.
    ///
    /// A `ChaCha8Rng` seeded with [`mix_seed`]`(scenario_seed, vessel_index)` draws, for heave, roll and
    /// pitch in turn: `f₁` uniform in the axis range ([`HEAVE_FREQ_HZ`], [`ROLL_FREQ_HZ`], [`PITCH_FREQ_HZ`]),
    /// `f₂ = f₁ ·` a ratio uniform in [`SECOND_RATIO`], and two phases uniform in `[0, 2π)`. The generator and
    /// the draws are platform-independent, so the same seed gives the same signals on every machine.
    pub fn from_seed(scenario_seed: u64, vessel_index: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(mix_seed(scenario_seed, vessel_index));
        let heave = PeriodicSignal::draw(&mut rng, HEAVE_FREQ_HZ);
        let roll = PeriodicSignal::draw(&mut rng, ROLL_FREQ_HZ);
        let pitch = PeriodicSignal::draw(&mut rng, PITCH_FREQ_HZ);
        Self { heave, roll, pitch }
    }
}

/// SplitMix64 finaliser, a bijective 64-bit mixer.
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Combines a scenario seed and a vessel index into one 64-bit seed:
/// `splitmix64(scenario_seed ^ splitmix64(vessel_index))`.
pub fn mix_seed(scenario_seed: u64, vessel_index: u64) -> u64 {
    splitmix64(scenario_seed ^ splitmix64(vessel_index))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g_rms_constant_matches_formula() {
        let want = ((1.0 + SECOND_WEIGHT * SECOND_WEIGHT) / 2.0).sqrt() / (1.0 + SECOND_WEIGHT);
        assert!((G_RMS - want).abs() < 1e-15);
    }

    #[test]
    fn signals_are_bounded_and_in_band() {
        for idx in 0..50 {
            let s = WaveSignals::from_seed(11, idx);
            for g in [s.heave, s.roll, s.pitch] {
                assert!(g.freq_hz.iter().all(|f| (0.08..=0.35).contains(f)), "{g:?}");
                assert!(g.phase_rad.iter().all(|p| (0.0..TAU).contains(p)));
                for k in 0..2000 {
                    assert!(g.value(k as f64 * 0.37).abs() <= 1.0);
                }
                // Derivative agrees with a central difference.
                let (t, h) = (12.3, 1e-5);
                let fd = (g.value(t + h) - g.value(t - h)) / (2.0 * h);
                assert!((fd - g.derivative(t)).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn seeding_is_deterministic_and_seed_sensitive() {
        let a = WaveSignals::from_seed(7, 3);
        let b = WaveSignals::from_seed(7, 3);
        assert_eq!(a, b);
        assert_ne!(a.heave.phase_rad, WaveSignals::from_seed(8, 3).heave.phase_rad);
        assert_ne!(a.heave.phase_rad, WaveSignals::from_seed(7, 4).heave.phase_rad);
        assert_ne!(mix_seed(1, 0), mix_seed(0, 1));
    }

    #[test]
    fn wave_settings_parse_and_validate() {
        assert_eq!("W2".parse::<WaveSetting>(), Ok(WaveSetting::W2));
        assert_eq!(" w0 ".parse::<WaveSetting>(), Ok(WaveSetting::W0));
        assert_eq!(WaveSetting::W3.to_string(), "W3");
        assert!((WaveSetting::W1.amplitude_m() - 0.75).abs() < 1e-15);
        let heights: Vec<f64> = WaveSetting::PRESETS.iter().map(WaveSetting::height_m).collect();
        assert_eq!(heights, vec![0.5, 1.5, 2.5, 3.5]);
        match "W4".parse::<WaveSetting>() {
            Err(MmusvError::Config { field, reason, .. }) => {
                assert_eq!(field, "wave");
                assert!(reason.contains("W0, W1, W2, W3"));
            }
            other => unreachable!("expected a config error, got {other:?}"),
        }
        for bad in [-0.1, f64::NAN, f64::INFINITY] {
            assert!(matches!(WaveSetting::from_height(bad), Err(MmusvError::Config { .. })));
        }
        let free = WaveSetting::from_height(1.2).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(free.preset_name(), None);
        assert!((free.scale() - 1.2).abs() < 1e-15);
    }

    #[test]
    fn alpha_favours_small_vessels() {
        assert!((VesselDims::REFERENCE.alpha() - 1.0).abs() < 1e-12);
        let dinghy = VesselDims { length_m: 3.0, beam_m: 1.2, height_m: 1.0 };
        let ship = VesselDims { length_m: 300.0, beam_m: 48.0, height_m: 60.0 };
        assert!(dinghy.alpha() > 1.0 && dinghy.alpha() <= ALPHA_MAX);
        assert!((ship.alpha() - ALPHA_MIN).abs() < 1e-12);
        let bad = VesselDims { length_m: 0.0, ..VesselDims::REFERENCE };
        assert!(matches!(bad.validate(), Err(MmusvError::Config { field, .. }) if field == "dims.length_m"));
        let amp = BaseAmplitudes { roll_rad: -1.0, ..BaseAmplitudes::default() };
        assert!(matches!(amp.validate(), Err(MmusvError::Config { field, .. }) if field == "amplitudes.roll_rad"));
    }
}
