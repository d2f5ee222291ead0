//! Rain in a camera image: the drops near the lens, each seen as a motion-blurred streak (or, in a short exposure,
//! a frozen dot) whose brightness is the light the drop refracts, not a fixed share of the image's range.
//!
//! Model: **the photometric model of a rain streak** of K. Garg & S. K. Nayar, "Detection and Removal of Rain
//! from Videos", CVPR 2004, and "Vision and Rain", *International Journal of Computer Vision* 75(1), 3–27, 2007
//! (section 3). A drop that covers a pixel for a time `τ` of the exposure `T` changes the pixel's radiance from the
//! background's `L_b` to `L_b + (τ/T)(L_d − L_b)`, `L_d` the drop's own radiance. Here `τ/T` is generalised to the
//! exposure-averaged fraction `c` of the pixel the drop covers (its image, a disc of diameter `w = D f / x` pixels
//! for a drop of diameter `D` at depth `x` and focal length `f`, swept along its streak): a drop's coverage summed
//! over the pixels is its image's area `π w² / 4` whatever its speed, spread over a streak `|ẋ_img| T` long.
//! Several drops over one pixel add their coverages (capped at the whole pixel).
//!
//! * **The drop's radiance.** A drop is a wide-angle lens: it refracts towards the camera the light of a field of
//!   view of about 165° behind it, so its brightness hardly depends on the background it is seen against
//!   (K. Garg & S. K. Nayar, "Photometric Model of a Rain Drop", Columbia University technical report, 2003). It
//!   is taken as the cosine-weighted mean radiance of the half of the environment it looks into (the sky above
//!   the horizon, the sea's light below; the sun where it is in that half) through two water surfaces:
//!   `L_d = T_w (E_env(d) + E_sun max(0, d·s)) / π`, `d` the drop's direction from the camera, `E_env(d)` the
//!   environment's irradiance on a plane facing `d` (`envlight.rs`), `T_w = (1 − R̄)²` with `R̄` the
//!   hemispherical mean of water's Fresnel reflectance (n = 1.333, [`DROP_TRANSMITTANCE`]). At night, with no sky
//!   light, a drop is dark: the streaks disappear, as they do in real night footage away from lights.
//! * **The drops.** Marshall & Palmer (1948) (`python/mmusv/world/rain.py`, whose law also gives the rain's
//!   extinction, the visibility the aerial perspective uses): `N(D) = N₀ e^{−ΛD}` per m³ per mm, `N₀ = 8000`,
//!   `Λ = 4.1 R^−0.21` mm⁻¹, diameters [`DIAMETER_RANGE_MM`], uniform in the camera's frustum from [`NEAR_M`] out to
//!   where a 2 mm drop's image shrinks to [`FAR_IMAGE_PX`] pixels (or fewer metres, so that at most [`MAX_DROPS`]
//!   drops are drawn); farther drops are the rain's extinction, which the visibility already holds.
//! * **Their fall.** Straight down at the terminal velocity of R. Gunn & G. D. Kinzer, "The terminal velocity of
//!   fall for water droplets in stagnant air", *Journal of Meteorology* 6, 243–248, 1949, in the fit of D. Atlas,
//!   R. C. Srivastava & R. S. Sekhon, "Doppler radar characteristics of precipitation at vertical incidence",
//!   *Reviews of Geophysics* 11(1), 1–35, 1973: `v = 9.65 − 10.3 e^{−0.6 D}` m/s ([`terminal_velocity_m_s`]).
//!   A drop's streak is its image's motion over the exposure, at its mid-exposure position (pinhole projection).
//! * **The exposure time.** The camera of `tonemap.rs` (f/1.4, at most 1/30 s, then gain): at ISO 100 an exposure
//!   scale `k = 1 / (1.2 · 2^EV100)` is `T = N² / 2^EV100 = 1.2 N² k`, held at 1/30 s when longer
//!   ([`super::tonemap::exposure_time_s`]). By day the shutter is a fraction of a millisecond and the drops are
//!   frozen dots; at dusk the streaks grow long and faint: the dependence on exposure time Garg & Nayar measured
//!   (2007, section 5).
//! * **Defocus.** The lens is focused at infinity, so a drop at depth `x` is blurred over a disc of `A f / x`
//!   pixels, `A = f p / N` the aperture's diameter for a pixel pitch `p` ([`PIXEL_PITCH_M`]): its coverage is
//!   spread over that disc where it is wider than the drop's image. A wide-angle camera's drops stay sharp (a 2 mm
//!   drop 0.5 m in front of a 90° 640-pixel camera is 1.3 px across, blurred over 0.5 px); a long lens's are blurred
//!   several times their size and fade into the haze, as Garg & Nayar found a shallow depth of field to hide rain
//!   (2007, section 5).
//! * **What is drawn.** A drop whose most-covered pixel it would change by less than [`MIN_COVERAGE`] of the
//!   difference between the drop and the background (under one 8-bit level at full contrast) is left out, as are
//!   drops whose image is under [`MIN_IMAGE_PX`]: what a long exposure smears or a long lens blurs below that is the
//!   rain's haze, which the visibility holds.
//!
//! The drops are a Poisson process, uniform in the image at each depth, so their mid-exposure points are drawn in
//! the image and a streak that leaves it re-enters at the opposite border (a toroidal wrap): every pixel then gets
//! exactly the expected coverage, the border's included, as if the drops of the whole frustum had been drawn. A
//! drop behind the surface a pixel shows (its depth beyond the pixel's) does not cover it.
//!
//! Checked against closed forms (the tests below): the coverage the drawn drops give, over many images, is the
//! frustum slab's geometric optical depth `(π/4) ∫∫ D² N(D) dD dx` (by quadrature, less the drops narrower than
//! [`MIN_IMAGE_PX`]); a drop's coverage sums to its image's area, runs along the fall's image and keeps its area
//! over its blur; a long lens draws no drop where a wide one draws hundreds; `T_w` is the Fresnel integral; the
//! velocity fit is within 3 % of Gunn & Kinzer's measured table. Not modelled: the drops' oscillations and the
//! speckle and highlights within a streak (Garg & Nayar, "Photorealistic Rendering of Rain Streaks", ACM TOG
//! 25(3), 2006), a lens focused nearer than infinity, the blur's shape (a square of its width here, not a disc),
//! wind and the camera's own motion (the streaks fall straight down the world's vertical), drops on the lens, the
//! lamps' light in the drops, splashes, and an orthographic top view (its pixels are metres across: a drop covers
//! nothing).

use super::super::noise::{self, stream};
use super::tonemap::F_NUMBER;
use parry3d::math::{Mat3, Vec3};

/// Marshall–Palmer intercept `N₀`, drops per m³ per mm of diameter (its one definition: `mmusv.world.rain` reads it
/// for the visibility in rain, through `_core.marshall_palmer`).
pub const MP_N0: f64 = 8000.0;
/// Marshall–Palmer slope `Λ = 4.1 · R^−0.21` per mm (`R` in mm/h): the coefficient and the exponent (read there
/// too).
pub const MP_LAMBDA: (f64, f64) = (4.1, -0.21);
/// The diameters of the drops drawn, mm (smaller drops are sub-pixel at every depth drawn; larger ones break up).
pub const DIAMETER_RANGE_MM: (f64, f64) = (0.5, 6.0);
/// The nearest drop drawn, metres from the lens.
pub const NEAR_M: f64 = 0.2;
/// The drops are drawn out to where a 2 mm drop's image is this many pixels across.
pub const FAR_IMAGE_PX: f64 = 0.25;
/// The most drops drawn for one image (the far limit comes nearer for a long focal length in heavy rain).
pub const MAX_DROPS: f64 = 200_000.0;
/// A drop's transmittance `(1 − R̄)²`, `R̄ = 2 ∫₀^{π/2} F(θ) cos θ sin θ dθ` the cosine-weighted hemispherical mean
/// of the Fresnel reflectance of water (n = 1.333, unpolarised light), 0.0662: light enters and leaves the drop
/// through one surface each (the test below integrates it).
pub const DROP_TRANSMITTANCE: f32 = 0.8717;
/// Drops whose image is narrower than this (pixels) are left out: they cover under 0.8 % of a pixel.
pub const MIN_IMAGE_PX: f32 = 0.1;
/// Drops that would cover no pixel more than this share of the exposure are left out (1/255: one 8-bit level at
/// the full contrast between drop and background).
pub const MIN_COVERAGE: f32 = 1.0 / 255.0;
/// The sensor's pixel pitch, metres (3.45 µm, a common machine-vision sensor's: Sony IMX250, IMX264): with the
/// focal length in pixels and the f-number it sets the aperture, and so the drops' defocus.
pub const PIXEL_PITCH_M: f32 = 3.45e-6;
/// Most steps along one streak (its coverage is spread over them).
const MAX_STEPS: usize = 4096;
/// Most sub-steps across a drop's blur disc (per side): the disc is sampled `side × side` times, `side` its width
/// in pixels rounded up, clamped to `1..=MAX_SIDE`.
const MAX_SIDE: usize = 16;

/// Terminal fall velocity (m/s) of a drop of diameter `d_mm` (mm) in still air at sea level (Gunn & Kinzer 1949,
/// Atlas et al. 1973's fit; 0 for a drop too small for the fit).
pub fn terminal_velocity_m_s(d_mm: f64) -> f64 {
    (9.65 - 10.3 * (-0.6 * d_mm).exp()).max(0.0)
}

/// Marshall–Palmer slope `Λ` (per mm) of rain of `rain_mm_per_h`.
fn slope_per_mm(rain_mm_per_h: f64) -> f64 {
    MP_LAMBDA.0 * rain_mm_per_h.powf(MP_LAMBDA.1)
}

/// Drops per m³ with diameters in [`DIAMETER_RANGE_MM`], in rain of `rain_mm_per_h` (0 without rain).
pub fn drops_per_m3(rain_mm_per_h: f64) -> f64 {
    if rain_mm_per_h <= 0.0 {
        return 0.0;
    }
    let lam = slope_per_mm(rain_mm_per_h);
    let (a, b) = DIAMETER_RANGE_MM;
    MP_N0 / lam * ((-lam * a).exp() - (-lam * b).exp())
}

/// `∫ D² N(D) dD` over [`DIAMETER_RANGE_MM`] (mm² per m³): the drops' summed squared diameters per unit volume.
pub fn second_moment_mm2_per_m3(rain_mm_per_h: f64) -> f64 {
    if rain_mm_per_h <= 0.0 {
        return 0.0;
    }
    let lam = slope_per_mm(rain_mm_per_h);
    // ∫ D² e^{−ΛD} dD = −e^{−ΛD} (D²/Λ + 2D/Λ² + 2/Λ³)
    let primitive = |d: f64| -(-lam * d).exp() * (d * d / lam + 2.0 * d / (lam * lam) + 2.0 / (lam * lam * lam));
    MP_N0 * (primitive(DIAMETER_RANGE_MM.1) - primitive(DIAMETER_RANGE_MM.0))
}

/// A pinhole camera in the rain: what the drops' images depend on.
#[derive(Debug, Clone, Copy)]
pub struct RainView {
    /// Image width and height, pixels.
    pub size: (u32, u32),
    /// Focal length, pixels; the principal point is the image centre.
    pub f: f32,
    /// Camera body → world rotation (body x forward, y left, z up; image `u` right, `v` down).
    pub rotation: Mat3,
    /// Exposure time, seconds ([`super::tonemap::exposure_time_s`]).
    pub exposure_s: f32,
    /// Rain rate, mm/h.
    pub rain_mm_per_h: f32,
}

/// One drop: where its image is at mid-exposure and how it moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drop {
    /// Mid-exposure image position, pixels (`u` right, `v` down, pixel `(i, j)` covering `[i, i+1) × [j, j+1)`).
    pub at: [f32; 2],
    /// The image's displacement over the exposure, pixels.
    pub streak: [f32; 2],
    /// The image's diameter, pixels.
    pub width_px: f32,
    /// The diameter of its defocus blur, pixels (the lens focused at infinity).
    pub blur_px: f32,
    /// Depth along the optical axis, metres.
    pub depth_m: f32,
    /// Unit direction from the camera to the drop, world frame.
    pub dir: Vec3,
}

impl Drop {
    /// The area of its image, pixels².
    pub fn area_px2(&self) -> f32 {
        std::f32::consts::FRAC_PI_4 * self.width_px * self.width_px
    }

    /// The length of its streak, pixels.
    pub fn streak_px(&self) -> f32 {
        self.streak[0].hypot(self.streak[1])
    }

    /// The diameter (pixels) its coverage is spread over across its path: its image's or its blur's, the wider.
    pub fn spread_px(&self) -> f32 {
        self.width_px.max(self.blur_px)
    }

    /// The largest share of one pixel's exposure it covers (about: its image's area over the footprint it sweeps
    /// across the pixel, the spread at least a pixel wide, for the share of the exposure it stays there).
    pub fn peak_coverage(&self) -> f32 {
        let spread = self.spread_px().max(1.0);
        self.area_px2() / (spread * spread) * (spread / self.streak_px().max(spread)).min(1.0)
    }
}

impl RainView {
    /// How far out (metres along the axis) the drops are drawn, and how many are expected in that slab.
    pub fn slab(&self) -> (f64, f64) {
        let n = drops_per_m3(f64::from(self.rain_mm_per_h));
        let (w, h) = (f64::from(self.size.0), f64::from(self.size.1));
        let f = f64::from(self.f);
        // The frustum's cross-section at depth x is (W x / f)(H x / f): the slab holds (x₁³ − x₀³) W H / (3 f²) m³.
        let per_cube = n * w * h / (3.0 * f * f);
        let mut far = (f * 2e-3 / FAR_IMAGE_PX).max(NEAR_M);
        if per_cube * (far.powi(3) - NEAR_M.powi(3)) > MAX_DROPS {
            far = (NEAR_M.powi(3) + MAX_DROPS / per_cube).cbrt();
        }
        (far, per_cube * (far.powi(3) - NEAR_M.powi(3)))
    }

    /// The drops of one image, drawn from `seed` (deterministic; none without rain or an exposure).
    pub fn drops(&self, seed: u64) -> Vec<Drop> {
        if !(self.rain_mm_per_h > 0.0 && self.exposure_s > 0.0 && self.f > 0.0) {
            return Vec::new();
        }
        let (far, expected) = self.slab();
        let whole = expected.floor();
        let count = whole as u64 + u64::from(noise::uniform(seed, stream::RAIN, 0) < expected - whole);
        let lam = slope_per_mm(f64::from(self.rain_mm_per_h));
        let (d0, d1) = DIAMETER_RANGE_MM;
        let (e0, e1) = ((-lam * d0).exp(), (-lam * d1).exp());
        let (c0, c1) = (NEAR_M.powi(3), far.powi(3));
        let (w, h) = (self.size.0 as f32, self.size.1 as f32);
        let (cx, cy) = (0.5 * w, 0.5 * h);
        let down = self.rotation.transpose() * Vec3::NEG_Z;
        let aperture = self.f * PIXEL_PITCH_M / F_NUMBER;
        let mut out = Vec::with_capacity(count as usize);
        for j in 0..count {
            let u = |k: u64| noise::uniform(seed, stream::RAIN, 1 + 4 * j + k);
            // Diameter from the truncated exponential, depth uniform in volume (pdf ∝ x²), position uniform.
            let d_mm = -(e0 - u(0) * (e0 - e1)).ln() / lam;
            let x = (c0 + u(1) * (c1 - c0)).cbrt() as f32;
            let width_px = (d_mm * 1e-3) as f32 * self.f / x;
            if width_px < MIN_IMAGE_PX {
                continue;
            }
            let blur_px = aperture * self.f / x;
            let (pu, pv) = (u(2) as f32 * w, u(3) as f32 * h);
            // The drop in the body frame, and its image's velocity (the pinhole u = cx − f y / x, v = cy − f z / x).
            let p = Vec3::new(x, -(pu - cx) * x / self.f, -(pv - cy) * x / self.f);
            let vel = down * terminal_velocity_m_s(d_mm) as f32;
            let du = -self.f * (vel.y * p.x - p.y * vel.x) / (p.x * p.x);
            let dv = -self.f * (vel.z * p.x - p.z * vel.x) / (p.x * p.x);
            let drop = Drop {
                at: [pu, pv],
                streak: [du * self.exposure_s, dv * self.exposure_s],
                width_px,
                blur_px,
                depth_m: x,
                dir: (self.rotation * p).normalize(),
            };
            if drop.peak_coverage() >= MIN_COVERAGE {
                out.push(drop);
            }
        }
        out
    }
}

/// The coverage of each pixel of a `size` image by `drops` (row-major; drops over one pixel add up, past 1 where
/// they overlap, which [`apply`] caps) and the coverage-weighted sum of the drops' radiance `radiance(drop)`,
/// passing over the pixels whose axis depth `depth` (metres, row-major; +inf for sky) is nearer than the drop.
pub fn coverage(
    size: (u32, u32),
    drops: &[Drop],
    depth: &[f32],
    radiance: impl Fn(&Drop) -> Vec3,
) -> (Vec<f32>, Vec<Vec3>) {
    let (w, h) = (size.0 as usize, size.1 as usize);
    let mut cover = vec![0f32; w * h];
    let mut light = vec![Vec3::ZERO; w * h];
    if w == 0 || h == 0 {
        return (cover, light);
    }
    for drop in drops {
        let l_d = radiance(drop);
        // Steps of at most a pixel along the streak (each splat bilinear), sub-steps of about a pixel across a wide
        // image (one, at the centre, for a drop narrower than a pixel).
        let steps = (drop.streak_px().ceil() as usize + 1).min(MAX_STEPS);
        let spread = drop.spread_px();
        let side = (spread.ceil() as usize).clamp(1, MAX_SIDE);
        // The sub-step offsets across (at most MAX_SIDE: an array, not an allocation per drop on this hot path).
        let mut offsets = [0f32; MAX_SIDE];
        for (k, o) in offsets.iter_mut().enumerate().take(side) {
            *o = ((k as f32 + 0.5) / side as f32 - 0.5) * spread;
        }
        let share = drop.area_px2() / (steps * side * side) as f32;
        for s in 0..steps {
            let t = if steps == 1 { 0.0 } else { s as f32 / (steps - 1) as f32 - 0.5 };
            for &ou in &offsets[..side] {
                for &ov in &offsets[..side] {
                    let (pu, pv) = (drop.at[0] + t * drop.streak[0] + ou, drop.at[1] + t * drop.streak[1] + ov);
                    splat(&mut cover, &mut light, (w, h), (pu, pv), share, l_d, drop.depth_m, depth);
                }
            }
        }
    }
    (cover, light)
}

/// Bilinear splat of coverage `share` at image point `(pu, pv)` (wrapped into the image) over the four nearest
/// pixel centres, each unless its surface lies nearer than `depth_m`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn splat(
    cover: &mut [f32],
    light: &mut [Vec3],
    (w, h): (usize, usize),
    (pu, pv): (f32, f32),
    share: f32,
    l_d: Vec3,
    depth_m: f32,
    depth: &[f32],
) {
    // Pixel centres sit at half-integers.
    let (x, y) = (pu - 0.5, pv - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wrap = |v: i64, n: usize| v.rem_euclid(n as i64) as usize;
    for (dx, wx) in [(0i64, 1.0 - fx), (1, fx)] {
        for (dy, wy) in [(0i64, 1.0 - fy), (1, fy)] {
            let weight = wx * wy * share;
            if weight <= 0.0 {
                continue;
            }
            let i = wrap(y0 as i64 + dy, h) * w + wrap(x0 as i64 + dx, w);
            if depth.get(i).is_some_and(|&z| z < depth_m) {
                continue;
            }
            cover[i] += weight;
            light[i] += l_d * weight;
        }
    }
}

/// The radiance of a pixel whose background radiance is `background`, covered `cover` by drops whose
/// coverage-weighted radiance sums to `light`: `(1 − c) L_b + Σ c_i L_i`, the coverage capped at the whole pixel.
#[inline]
pub fn apply(background: Vec3, cover: f32, light: Vec3) -> Vec3 {
    if cover <= 0.0 {
        return background;
    }
    if cover >= 1.0 {
        return light / cover;
    }
    background * (1.0 - cover) + light
}

#[cfg(test)]
mod tests {
    use super::super::brdf::fresnel_dielectric;
    use super::super::tonemap::MAX_EXPOSURE_S;
    use super::*;

    fn level_view(rain: f32, exposure_s: f32) -> RainView {
        // A level camera looking north: body x = world y, body y (left) = world −x, body z = world z.
        let rotation = Mat3::from_cols(Vec3::Y, Vec3::NEG_X, Vec3::Z);
        RainView { size: (160, 120), f: 80.0, rotation, exposure_s, rain_mm_per_h: rain }
    }

    #[test]
    fn the_drop_transmittance_is_the_fresnel_integral() {
        let n = 20_000;
        let mut r = 0.0f64;
        for i in 0..n {
            let theta = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let f = f64::from(fresnel_dielectric(theta.cos() as f32, 1.333));
            r += 2.0 * f * theta.cos() * theta.sin() * std::f64::consts::FRAC_PI_2 / n as f64;
        }
        let t = (1.0 - r) * (1.0 - r);
        assert!((t - f64::from(DROP_TRANSMITTANCE)).abs() < 5e-4, "{r} {t}");
    }

    #[test]
    fn the_velocity_fit_follows_gunn_and_kinzer() {
        // Gunn & Kinzer (1949), Table 2: diameter (mm) → terminal velocity (m/s) at 1013 mb, 20 °C.
        for (d, v) in [(0.5, 2.06), (1.0, 4.03), (2.0, 6.49), (3.0, 8.06), (4.0, 8.83), (5.0, 9.09)] {
            let fit = terminal_velocity_m_s(d);
            assert!((fit / v - 1.0).abs() < 0.03, "{d} mm: {fit} against {v}");
        }
    }

    #[test]
    fn the_moments_are_the_integrals() {
        for rain in [1.0, 4.0, 25.0] {
            let lam = slope_per_mm(rain);
            let (mut n, mut m2) = (0.0, 0.0);
            let steps = 200_000;
            let (a, b) = DIAMETER_RANGE_MM;
            for i in 0..steps {
                let d = a + (i as f64 + 0.5) / steps as f64 * (b - a);
                let nd = MP_N0 * (-lam * d).exp() * (b - a) / steps as f64;
                n += nd;
                m2 += nd * d * d;
            }
            assert!((drops_per_m3(rain) / n - 1.0).abs() < 1e-6);
            assert!((second_moment_mm2_per_m3(rain) / m2 - 1.0).abs() < 1e-6);
        }
        assert_eq!(drops_per_m3(0.0), 0.0);
    }

    #[test]
    fn the_coverage_is_the_slab_s_geometric_optical_depth() {
        // Over many images the mean coverage of a pixel (no surface in front) is the share of its solid angle the
        // drawn drops' images fill: (π/4) ∫∫ D² N(D) dD dx over the slab, the diameters in metres, less the drops
        // narrower than MIN_IMAGE_PX (D f / x < MIN_IMAGE_PX), which are left out: a quadrature here. A frozen
        // drop's image (this short exposure) of at least MIN_IMAGE_PX, with f = 80 px (its blur a tenth of a pixel),
        // covers a pixel by more than MIN_COVERAGE: no other drop is left out.
        let view = level_view(25.0, 1e-4);
        let (far, _) = view.slab();
        let lam = slope_per_mm(25.0);
        let (nd, nx) = (2_000, 400);
        let (d0, d1) = DIAMETER_RANGE_MM;
        let mut want = 0.0;
        for i in 0..nd {
            let d = d0 + (i as f64 + 0.5) / nd as f64 * (d1 - d0);
            for j in 0..nx {
                let x = NEAR_M + (j as f64 + 0.5) / nx as f64 * (far - NEAR_M);
                if d * 1e-3 * f64::from(view.f) / x >= f64::from(MIN_IMAGE_PX) {
                    want +=
                        MP_N0 * (-lam * d).exp() * d * d * 1e-6 * (d1 - d0) / nd as f64 * (far - NEAR_M) / nx as f64;
                }
            }
        }
        want *= std::f64::consts::FRAC_PI_4;
        // Without the narrow drops' cut, the closed form: the cut leaves out a few per cent.
        let whole = std::f64::consts::FRAC_PI_4 * second_moment_mm2_per_m3(25.0) * 1e-6 * (far - NEAR_M);
        assert!(want < whole && want > 0.9 * whole, "{want} {whole}");
        let depth = vec![f32::INFINITY; 160 * 120];
        let mut sum = 0.0f64;
        let images = 40;
        for seed in 0..images {
            let (cover, _) = coverage(view.size, &view.drops(seed), &depth, |_| Vec3::ONE);
            sum += cover.iter().map(|&c| f64::from(c)).sum::<f64>() / cover.len() as f64;
        }
        let got = sum / f64::from(images as u32);
        assert!((got / want - 1.0).abs() < 0.03, "{got} against {want}");
    }

    #[test]
    fn a_drop_s_coverage_is_its_image_spread_down_its_fall() {
        let view = level_view(4.0, 1.0 / 60.0);
        let drops = view.drops(7);
        let Some(&drop) = drops.iter().find(|d| d.width_px > 0.3 && d.at[1] > 20.0 && d.at[1] < 40.0) else {
            panic!("no drop of 0.3 px or more in rows 20..40 among {}", drops.len());
        };
        // A level camera sees the fall straight down the image: v grows, u stays; the streak is v f T / x long
        // (at the image centre; off it the perspective lengthens it by at most (1 + ((v − cy)/f)²)).
        let d_mm = f64::from(drop.width_px * drop.depth_m / view.f) * 1e3;
        let centre = terminal_velocity_m_s(d_mm) as f32 * view.f * view.exposure_s / drop.depth_m;
        let lift = 1.0 + ((drop.at[1] - 60.0) / view.f).powi(2);
        assert!(drop.streak[1] >= centre * 0.999 && drop.streak[1] <= centre * lift * 1.001, "{drop:?}");
        assert!(drop.streak[0].abs() < 1e-3 * drop.streak[1]);
        let depth = vec![f32::INFINITY; 160 * 120];
        let (cover, light) = coverage(view.size, &[drop], &depth, |_| Vec3::splat(2.0));
        let area = std::f32::consts::FRAC_PI_4 * drop.width_px * drop.width_px;
        assert!((cover.iter().sum::<f32>() / area - 1.0).abs() < 1e-4);
        assert!((light.iter().map(|l| l.x).sum::<f32>() / (2.0 * area) - 1.0).abs() < 1e-4);
        // Every covered pixel lies within the streak's column band and rows.
        for (i, &c) in cover.iter().enumerate() {
            if c > 0.0 {
                let (u, v) = ((i % 160) as f32 + 0.5, (i / 160) as f32 + 0.5);
                assert!((u - drop.at[0]).abs() <= 1.0 + drop.spread_px(), "{u} {drop:?}");
                assert!((v - drop.at[1]).abs() <= 1.0 + drop.spread_px() + 0.5 * drop.streak[1], "{v} {drop:?}");
            }
        }
        // A surface nearer than the drop hides it.
        let near = vec![0.1f32; 160 * 120];
        assert!(coverage(view.size, &[drop], &near, |_| Vec3::ONE).0.iter().all(|&c| c == 0.0));
    }

    #[test]
    fn a_rolled_camera_sees_the_rain_fall_at_its_roll() {
        // Rolled 30° about its optical axis (not pitched; its left side up), the camera sees the world's vertical
        // as parallel lines turned 30° from its columns, down and to the right, and every streak along them.
        let roll = 30f32.to_radians();
        let level = level_view(25.0, 1.0 / 60.0);
        let view = RainView { rotation: level.rotation * Mat3::from_rotation_x(roll), ..level };
        let mut seen = 0;
        for seed in 0..8 {
            for d in view.drops(seed) {
                if d.streak[0].hypot(d.streak[1]) > 1.0 {
                    let angle = d.streak[0].atan2(d.streak[1]);
                    assert!((angle - roll).abs() < 1e-3, "{angle} {d:?}");
                    seen += 1;
                }
            }
        }
        assert!(seen > 20, "{seen}");
    }

    #[test]
    fn a_long_lens_blurs_its_drops_into_the_haze() {
        // The same sensor (640 × 480 pixels of 3.45 µm) behind a 90° lens and a 1.8° one (f = 20,000 px, an
        // aperture of 4.9 cm at f/1.4), in the same rain at dusk (1/30 s): the wide lens draws its drops, the long
        // lens none (each blurred over many times its image and smeared down a long streak).
        let wide = RainView { size: (640, 480), f: 320.0, ..level_view(25.0, MAX_EXPOSURE_S) };
        let long = RainView { f: 20_000.0, ..wide };
        assert!(wide.drops(2).len() > 100, "{}", wide.drops(2).len());
        assert!(long.drops(2).is_empty());
        // A blurred drop keeps its coverage, spread over its blur.
        let drop =
            Drop { at: [50.0, 40.0], streak: [0.0, 0.0], width_px: 0.5, blur_px: 6.0, depth_m: 3.0, dir: Vec3::X };
        let (cover, _) = coverage((160, 120), &[drop], &vec![f32::INFINITY; 160 * 120], |_| Vec3::ONE);
        let area = std::f32::consts::FRAC_PI_4 * 0.25;
        assert!((cover.iter().sum::<f32>() / area - 1.0).abs() < 1e-4);
        assert!(cover.iter().filter(|&&c| c > 0.0).count() >= 36);
        assert!((drop.peak_coverage() - area / 36.0).abs() < 1e-6);
    }

    #[test]
    fn the_pixel_mixes_background_and_drops() {
        let b = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(apply(b, 0.0, Vec3::ZERO), b);
        // A quarter covered by drops of radiance 8: 3/4 of the background plus 2.
        let got = apply(b, 0.25, Vec3::splat(8.0) * 0.25);
        assert!((got - (b * 0.75 + Vec3::splat(2.0))).abs().max_element() < 1e-6);
        // Covered twice over: the drops' mean.
        assert!((apply(b, 2.0, Vec3::splat(8.0) * 2.0) - Vec3::splat(8.0)).abs().max_element() < 1e-6);
        // No rain, no exposure: no drops.
        assert!(level_view(0.0, 0.01).drops(1).is_empty());
        assert!(level_view(4.0, 0.0).drops(1).is_empty());
        // The same seed, the same drops; another seed, others.
        assert_eq!(level_view(4.0, 0.01).drops(3), level_view(4.0, 0.01).drops(3));
        assert_ne!(level_view(4.0, 0.01).drops(3), level_view(4.0, 0.01).drops(4));
    }
}
