//! Image formation after the radiance: exposure, the filmic tone curve, sRGB encoding and sensor noise.
//!
//! * **Exposure** like an incident-light meter: the scene's horizontal illuminance `E_h` (sun and sky) sets the
//!   scale so that an 18 % grey Lambert card lying flat under that light, of radiance `0.18 E_h / π`, reaches
//!   0.18 before the tone curve: `k = π / E_h`. `E_h` is floored at [`MIN_METERED_LUX`], 3.46 lux: the
//!   camera's longest exposure and highest gain, f/1.4, 1/30 s (its frame time) and ISO 6 400 (EV100 −0.12),
//!   which is the light at the end of civil twilight (about 3.4 lux, sun 6° below the horizon): through civil
//!   twilight the camera opens up as the light falls, then holds, so nautical twilight darkens and nights stay
//!   dark with their lights standing out. A camera reaching another ISO has its floor scaled by `6 400 / ISO`
//!   ([`min_metered_lux`]), and its exposure compensation multiplies the result by `2^EV` ([`Exposure`]).
//!   A fixed `EV100` instead gives the
//!   saturation-based scale `k = 1 / (1.2 · 2^EV100)` (ISO 12232; S. Lagarde & C. de Rousiers, "Moving
//!   Frostbite to Physically Based Rendering", SIGGRAPH 2014 course notes).
//! * **Highlight limit** of the automatic exposure: a reflected-light reading of what the camera sees (the
//!   quantity a reflected-light meter reads, ISO 2720:1974, taken as the log-average luminance of the view, the
//!   "key" of E. Reinhard et al., "Photographic Tone Reproduction for Digital Images", SIGGRAPH 2002) caps the
//!   incident reading: where the view would average brighter than [`MAX_METERED_KEY`] (1.5 stops over middle grey)
//!   before the tone curve, the exposure is lowered to hold it there. By day a view of sea and sky averages
//!   0.1–0.4 and keeps the incident exposure; looking into an afterglow that outshines the sky light falling on
//!   the water (the sun a few degrees below the horizon), the incident reading alone would leave most of the
//!   picture white.
//! * **Tone curve**: K. Narkowicz's fit of the ACES filmic reference rendering transform (2016),
//!   `f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, clamped to `[0, 1]`, per channel.
//! * **sRGB**: the IEC 61966-2-1 transfer function, rounded to 8 bits.
//! * **Sensor noise** (optional): shot noise of `full_well · x` electrons (Poisson, drawn as a Gaussian with its
//!   variance) plus Gaussian read noise, in the linear exposed signal `x`, seeded per pixel.

use super::super::noise;
use parry3d::math::Vec3;

/// Darkest horizontal illuminance the automatic exposure adapts to, lux: the incident exposure `π / E` equals the
/// saturation-based scale `1 / (1.2 · 2^EV100)` of the camera's limit, f/1.4 at 1/30 s and ISO 6 400
/// (`EV100 = log2(N² / t) − log2(S / 100)`, −0.12), at `E = 1.2 π · 2^EV100` = 3.46 lux. Until 2026-11-30 the
/// floor was 10 lux (ISO 2 200 at the same aperture and time), held from 20:25 on (45° N in June), and the views
/// of the next fifty minutes darkened with the light itself, 550-fold by 21:15.
pub const MIN_METERED_LUX: f32 = 3.46;

/// The camera's aperture, f-number (fixed: the automatic exposure sets the time, then the gain).
pub const F_NUMBER: f32 = 1.4;
/// The camera's longest exposure, seconds (its frame time): darker, the gain rises instead.
pub const MAX_EXPOSURE_S: f32 = 1.0 / 30.0;

/// The exposure time (s) of the camera whose exposure scale (radiance to the tone curve's input) is `k`: at
/// ISO 100, `k = 1 / (1.2 · 2^EV100)` ([`fixed_exposure_scale`]) is `T = N² / 2^EV100 = 1.2 N² k` at
/// f/[`F_NUMBER`], held at [`MAX_EXPOSURE_S`] where longer (the gain makes up the rest).
pub fn exposure_time_s(k: f32) -> f32 {
    (1.2 * F_NUMBER * F_NUMBER * k).clamp(0.0, MAX_EXPOSURE_S)
}

/// The highest ISO of the default camera's automatic exposure, whose limit is [`MIN_METERED_LUX`].
pub const DEFAULT_MAX_ISO: f32 = 6_400.0;

/// Multiplier from radiance (cd/m²) to the tone curve's input: metered from `horizontal_lux` when `ev100` is
/// `NaN`, else the saturation-based scale of `ev100`.
pub fn exposure_scale(ev100: f32, horizontal_lux: f32) -> f32 {
    if ev100.is_finite() {
        fixed_exposure_scale(ev100)
    } else {
        incident_exposure_scale(horizontal_lux, MIN_METERED_LUX)
    }
}

/// The saturation-based scale of a fixed exposure value at ISO 100: `1 / (1.2 · 2^EV100)` (ISO 12232).
pub fn fixed_exposure_scale(ev100: f32) -> f32 {
    1.0 / (1.2 * 2f32.powf(ev100))
}

/// The incident reading `π / E_h`, `E_h` floored at `min_lux` (the camera's limit, [`min_metered_lux`]).
pub fn incident_exposure_scale(horizontal_lux: f32, min_lux: f32) -> f32 {
    std::f32::consts::PI / horizontal_lux.max(min_lux)
}

/// The darkest light (lux) the automatic exposure of a camera reaching `max_iso` at f/1.4 and 1/30 s adapts
/// to: [`MIN_METERED_LUX`] at [`DEFAULT_MAX_ISO`], inversely proportional to the ISO (one stop of gain, one stop
/// of light: `E = 1.2 π · 2^EV100` with `EV100 = log2(N² / t) − log2(S / 100)`).
pub fn min_metered_lux(max_iso: f32) -> f32 {
    MIN_METERED_LUX * (DEFAULT_MAX_ISO / max_iso)
}

/// How a camera sets its exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exposure {
    /// A fixed (manual) exposure value at ISO 100; `None` meters it automatically from the scene's light.
    pub ev100: Option<f32>,
    /// Stops added to the automatic exposure (+1 doubles it; the highlight limit shifts with it). Must be 0 with a
    /// fixed `ev100` ([`Exposure::validate`] refuses both); ignored when the environment fixes the exposure
    /// (`ShadeEnv::exposure_ev100`).
    pub compensation_ev: f32,
    /// The highest ISO the automatic exposure reaches at f/1.4 and 1/30 s: sets the darkest light it adapts to
    /// ([`min_metered_lux`]); below it pictures darken with the light.
    pub max_iso: f32,
}

impl Default for Exposure {
    /// Automatic, uncompensated, the ISO 6 400 camera of [`MIN_METERED_LUX`].
    fn default() -> Self {
        Self { ev100: None, compensation_ev: 0.0, max_iso: DEFAULT_MAX_ISO }
    }
}

/// Allowed fixed exposure values: EV100 −6 (a starlit scene at long exposure) to 20 (beyond snow in full sun).
pub const EV100_RANGE: (f32, f32) = (-6.0, 20.0);
/// Allowed exposure compensation, stops.
pub const COMPENSATION_RANGE_EV: (f32, f32) = (-5.0, 5.0);
/// Allowed highest ISO of the automatic exposure.
pub const MAX_ISO_RANGE: (f32, f32) = (100.0, 409_600.0);

impl Exposure {
    /// Checks the settings; errors name `camera.exposure.<field>` and the range allowed.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::MmusvError;
        let within = |v: f32, (lo, hi): (f32, f32)| v.is_finite() && (lo..=hi).contains(&v);
        if let Some(ev) = self.ev100 {
            if !within(ev, EV100_RANGE) {
                let allowed = format!("must be a finite EV100 in [{}, {}]", EV100_RANGE.0, EV100_RANGE.1);
                return Err(MmusvError::config("camera.exposure.ev100", ev, allowed));
            }
            if self.compensation_ev != 0.0 {
                let why = "applies to the automatic exposure only; give ev100 or compensation_ev, not both";
                return Err(MmusvError::config("camera.exposure.compensation_ev", self.compensation_ev, why));
            }
        }
        if !within(self.compensation_ev, COMPENSATION_RANGE_EV) {
            let (lo, hi) = COMPENSATION_RANGE_EV;
            let allowed = format!("must be a finite number of stops in [{lo}, {hi}]");
            return Err(MmusvError::config("camera.exposure.compensation_ev", self.compensation_ev, allowed));
        }
        if !within(self.max_iso, MAX_ISO_RANGE) {
            let allowed = format!("must be an ISO in [{}, {}]", MAX_ISO_RANGE.0, MAX_ISO_RANGE.1);
            return Err(MmusvError::config("camera.exposure.max_iso", self.max_iso, allowed));
        }
        Ok(())
    }
}

/// Brightest log-average an automatically exposed view keeps before the tone curve (middle grey is 0.18).
pub const MAX_METERED_KEY: f32 = 0.5;
/// Pixels the reflected-light reading takes along each image axis: every `METER_STEP`-th of every
/// `METER_STEP`-th row (a camera meters on a grid of zones, not every pixel).
const METER_STEP: usize = 4;

/// The pixels the highlight limit reads in a `width × height` image, row-major indices: every
/// `METER_STEP`-th pixel of every `METER_STEP`-th row, from the top-left one (even pixels all: shaded each
/// for itself, never shared).
pub fn metered_pixels(width: usize, height: usize) -> impl Iterator<Item = usize> {
    (0..height).step_by(METER_STEP).flat_map(move |y| (0..width).step_by(METER_STEP).map(move |x| y * width + x))
}

/// The automatic exposure `k` (the incident reading, [`exposure_scale`]) with the highlight limit of a view
/// whose metered pixels ([`metered_pixels`], in that order) have the radiances `metered`: `k` lowered so that
/// their log-average luminance, exposed, is at most [`MAX_METERED_KEY`] (see the module docs). Black pixels
/// count as `10⁻⁶` cd/m².
pub fn highlight_limited(k: f32, metered: impl IntoIterator<Item = Vec3>) -> f32 {
    let (mut sum, mut n) = (0f64, 0u32);
    for c in metered {
        let l = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        sum += f64::from(l.max(1e-6)).ln();
        n += 1;
    }
    if n == 0 {
        return k;
    }
    let key = (sum / f64::from(n)).exp() as f32;
    if key * k > MAX_METERED_KEY {
        MAX_METERED_KEY / key
    } else {
        k
    }
}

/// Narkowicz's ACES fit on one exposed channel value.
#[inline]
pub fn aces(x: f32) -> f32 {
    let x = x.max(0.0);
    (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// IEC 61966-2-1 sRGB encoding of a display-linear value in `[0, 1]`, to 8 bits.
#[inline]
pub fn srgb8(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Entries of the sRGB encoding table over `[0, 1]`.
const SRGB_LUT: usize = 1 << 16;

/// [`srgb8`] tabulated at `SRGB_LUT` points (the table's step, 1.5·10⁻⁵, is a twentieth of the finest 8-bit
/// step of the curve, so an entry differs from the formula only for values within that of a rounding edge).
fn srgb_lut() -> &'static [u8] {
    static LUT: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    LUT.get_or_init(|| (0..SRGB_LUT).map(|i| srgb8(i as f32 / (SRGB_LUT - 1) as f32)).collect())
}

/// Exposed, tone-mapped, sRGB-encoded pixel of radiance `c` under exposure `k`.
#[inline]
pub fn to_srgb8(c: Vec3, k: f32) -> [u8; 3] {
    let lut = srgb_lut();
    let enc = |x: f32| lut[((aces(x * k) * (SRGB_LUT - 1) as f32 + 0.5) as usize).min(SRGB_LUT - 1)];
    [enc(c.x), enc(c.y), enc(c.z)]
}

/// Colours tone-mapped per block of [`to_srgb8_all`].
const BLOCK: usize = 8;

crate::dispatch! {
    /// [`to_srgb8`] of every colour of `linear` under exposure `k`, into `out` (three bytes per colour, as many
    /// colours as both hold): the same bytes, eight colours at a time, so that the tone curve's arithmetic
    /// runs in vector lanes (the table lookups stay one by one).
    pub fn to_srgb8_all(linear: &[Vec3], k: f32, out: &mut [u8]) {
        let lut = srgb_lut();
        for (cs, px) in linear.chunks(BLOCK).zip(out.chunks_mut(3 * BLOCK)) {
            let mut v = [0f32; 3 * BLOCK];
            for (j, c) in cs.iter().enumerate() {
                v[3 * j..3 * j + 3].copy_from_slice(&[c.x * k, c.y * k, c.z * k]);
            }
            let mut idx = [0u32; 3 * BLOCK];
            for (i, x) in idx.iter_mut().zip(v) {
                *i = ((aces(x) * (SRGB_LUT - 1) as f32 + 0.5) as u32).min(SRGB_LUT as u32 - 1);
            }
            let m = px.len().min(3 * cs.len());
            for (p, &i) in px[..m].iter_mut().zip(&idx) {
                *p = lut[i as usize];
            }
        }
    }
}

/// Shot and read noise of a sensor (electrons).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    /// Electrons at an exposed signal of 1.0 (`> 0`).
    pub full_well: f32,
    /// Read noise, electrons RMS (`>= 0`).
    pub read_noise: f32,
}

impl SensorNoise {
    /// Adds noise to the exposed linear signal `x` of channel `ch` of pixel `pixel`, drawn from `seed`.
    #[inline]
    pub fn apply(&self, x: f32, seed: u64, pixel: u64, ch: u64) -> f32 {
        let e = x.max(0.0) * self.full_well;
        let sigma = (e + self.read_noise * self.read_noise).sqrt();
        let z = noise::normal(seed, 0x5E_4501, pixel * 3 + ch) as f32;
        (e + sigma * z).max(0.0) / self.full_well
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The highlight limit: a uniform view keeps the incident exposure up to the key and is held at the key
    /// above it; the reading is the log-average of every fourth pixel of every fourth row, the others unread.
    #[test]
    fn highlight_limit_holds_bright_views_at_the_key() {
        let k = 2e-4; // π / E_h at about 16 klux
        for l in [10.0f32, 500.0, 2000.0, 2500.0, 1e4, 1e5] {
            let img = vec![Vec3::splat(l); 64 * 48];
            let got = highlight_limited(k, metered_pixels(64, 48).map(|p| img[p]));
            let want = if l * k <= MAX_METERED_KEY { k } else { MAX_METERED_KEY / l };
            assert!((got - want).abs() <= 1e-6 * want, "L = {l}: {got} vs {want}");
        }
        // An 8 × 8 view: the metered pixels (0, 0), (0, 4), (4, 0), (4, 4) hold 1, 10, 100 and 1000 cd/m², the
        // rest a glare that would dominate a mean of every pixel.
        let mut img = vec![Vec3::splat(1e7); 64];
        for (q, l) in [(0usize, 1.0f32), (4, 10.0), (32, 100.0), (36, 1000.0)] {
            img[q] = Vec3::splat(l);
        }
        let key = (1.0f64 * 10.0 * 100.0 * 1000.0).powf(0.25) as f32; // 31.6
        let read = || metered_pixels(8, 8).map(|p| img[p]);
        assert_eq!(metered_pixels(8, 8).collect::<Vec<_>>(), [0, 4, 32, 36]);
        assert!((highlight_limited(1.0, read()) - MAX_METERED_KEY / key).abs() < 1e-6);
        assert_eq!(highlight_limited(0.01, read()), 0.01); // 0.316 exposed: under the key, kept
        assert_eq!(highlight_limited(0.01, []), 0.01);
        // Black pixels count as 10⁻⁶ cd/m² (no logarithm of zero): a night view keeps its exposure.
        assert_eq!(highlight_limited(0.3, [Vec3::ZERO; 4]), 0.3);
    }

    #[test]
    fn grey_card_meters_to_0_18_and_curve_is_monotone() {
        let e_h = 100_000.0f32;
        let k = exposure_scale(f32::NAN, e_h);
        let card = 0.18 * e_h / std::f32::consts::PI;
        assert!((card * k - 0.18).abs() < 1e-6);
        // EV100 15 (sunny 16): L_max = 1.2 · 2^15 cd/m² maps to 1.
        assert!((exposure_scale(15.0, 0.0) * 1.2 * 32768.0 - 1.0).abs() < 1e-6);
        let mut last = -1.0;
        for i in 0..1000 {
            let y = aces(i as f32 * 0.02);
            assert!(y >= last);
            last = y;
        }
        assert_eq!(aces(0.0), 0.0);
        assert!(aces(1e6) == 1.0);
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        // 0.5 display-linear is sRGB 188.
        assert_eq!(srgb8(0.5), 188);
    }

    /// Below the floor the automatic exposure is the camera's limit, f/1.4, 1/30 s, ISO 6 400, given as a fixed
    /// EV100 (within the floor's rounding to three figures, 0.2 %); above it the incident reading still governs.
    #[test]
    fn the_exposure_floor_is_the_low_light_cameras_limit() {
        let ev100 = (F_NUMBER * F_NUMBER / MAX_EXPOSURE_S).log2() - (6_400.0f32 / 100.0).log2();
        assert!((ev100 + 0.12).abs() < 0.01, "{ev100}");
        let limit = exposure_scale(ev100, 0.0);
        for lux in [0.0, 1e-3, 0.08, 0.5, 3.0, MIN_METERED_LUX] {
            let k = exposure_scale(f32::NAN, lux);
            assert!((k / limit - 1.0).abs() < 0.002, "{lux} lux: {k} against the camera's limit {limit}");
        }
        // Brighter light is exposed from its own reading: a grey card under 20 lux still meters to 0.18.
        assert!((exposure_scale(f32::NAN, 20.0) * 20.0 - std::f32::consts::PI).abs() < 1e-5);
    }

    /// The exposure time is the exposure value's at f/1.4: a fixed EV100 of 15 (full sun) gives N² / 2^15 s;
    /// EV100 0 would be 1.96 s, held at 1/30 s.
    #[test]
    fn the_exposure_time_is_the_cameras() {
        assert!((exposure_time_s(fixed_exposure_scale(15.0)) - 1.96 / 32_768.0).abs() < 1e-9);
        assert_eq!(exposure_time_s(fixed_exposure_scale(0.0)), MAX_EXPOSURE_S);
    }

    /// A camera's highest ISO sets its floor as the same f/1.4, 1/30 s limit at that ISO (one stop of gain, one
    /// stop of light), the default camera's exactly [`MIN_METERED_LUX`]; settings out of range are refused,
    /// naming the field.
    #[test]
    fn the_floor_follows_the_highest_iso_and_settings_are_checked() {
        assert_eq!(min_metered_lux(DEFAULT_MAX_ISO), MIN_METERED_LUX);
        for iso in [400.0f32, 1_600.0, 25_600.0, 102_400.0] {
            let ev100 = (F_NUMBER * F_NUMBER / MAX_EXPOSURE_S).log2() - (iso / 100.0).log2();
            let limit = fixed_exposure_scale(ev100);
            let k = incident_exposure_scale(0.0, min_metered_lux(iso));
            assert!((k / limit - 1.0).abs() < 0.002, "ISO {iso}: {k} against {limit}");
        }
        assert!(Exposure::default().validate().is_ok());
        let bad = [
            (Exposure { ev100: Some(25.0), ..Default::default() }, "camera.exposure.ev100"),
            (Exposure { ev100: Some(f32::NAN), ..Default::default() }, "camera.exposure.ev100"),
            (Exposure { ev100: Some(10.0), compensation_ev: 1.0, ..Default::default() }, "compensation_ev"),
            (Exposure { compensation_ev: 6.0, ..Default::default() }, "camera.exposure.compensation_ev"),
            (Exposure { max_iso: 50.0, ..Default::default() }, "camera.exposure.max_iso"),
            (Exposure { max_iso: f32::INFINITY, ..Default::default() }, "camera.exposure.max_iso"),
        ];
        for (e, field) in bad {
            let Err(err) = e.validate() else { panic!("{e:?} was accepted") };
            let msg = err.to_string();
            assert!(msg.contains(field), "{e:?}: {msg}");
        }
    }

    /// The blockwise tone mapping gives [`to_srgb8`]'s bytes for every colour, odd lengths, out-of-range and
    /// non-finite values included.
    #[test]
    fn tone_mapping_a_whole_image_matches_pixel_by_pixel() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut colours: Vec<Vec3> = (0..1001).map(|_| Vec3::new(next() * 3.0, next() * 0.01, next() * 40.0)).collect();
        colours.extend([Vec3::splat(-1.0), Vec3::splat(f32::NAN), Vec3::splat(f32::INFINITY), Vec3::ZERO]);
        for k in [1.0f32, 0.37, 2.0e-4] {
            let mut out = vec![0u8; 3 * colours.len()];
            to_srgb8_all(&colours, k, &mut out);
            for (c, px) in colours.iter().zip(out.chunks(3)) {
                assert_eq!(px, to_srgb8(*c, k), "{c:?} at {k}");
            }
        }
    }

    #[test]
    fn srgb_table_is_within_one_step_of_the_formula() {
        for i in 0..=100_000 {
            let x = i as f32 / 100_000.0;
            let a = to_srgb8(Vec3::splat(x), 1.0)[0] as i32;
            let b = srgb8(aces(x)) as i32;
            assert!((a - b).abs() <= 1, "{x}: {a} vs {b}");
        }
    }

    #[test]
    fn sensor_noise_has_its_variance() {
        let n = SensorNoise { full_well: 1000.0, read_noise: 5.0 };
        let x = 0.4;
        let m = 20_000u64;
        let v: Vec<f32> = (0..m).map(|i| n.apply(x, 3, i, 0)).collect();
        let mean = v.iter().sum::<f32>() / m as f32;
        let var = v.iter().map(|a| (a - mean).powi(2)).sum::<f32>() / m as f32;
        let want = (x * 1000.0 + 25.0) / 1e6;
        assert!((mean - x).abs() < 0.002, "{mean}");
        assert!((var - want).abs() < 0.05 * want, "{var} vs {want}");
    }
}
