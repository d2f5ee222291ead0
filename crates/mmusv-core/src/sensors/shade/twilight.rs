//! The twilight sky: single scattering of sunlight in a spherical atmosphere with the Earth's shadow, for a sun
//! below the horizon, where Preetham's model (`sky.rs`) is not defined.
//!
//! * **Model**: T. Nishita, T. Sirai, K. Tadamura, E. Nakamae, "Display of the Earth taking into account
//!   atmospheric scattering", SIGGRAPH 1993 — the radiance along a view ray is the integral of the sunlight
//!   scattered once at each point `p`, `∫ T(o→p) [β_R(p) P_R(γ) + β_M(p) P_M(γ)] T(p→sun) E₀ dt`, zero where
//!   the Earth hides the sun from `p`. Both transmittances are integrated numerically through the shells.
//! * **Atmosphere** (E. Bruneton, "A qualitative and quantitative evaluation of 8 clear sky models", IEEE TVCG
//!   23(12), 2017, and its reference implementation's constants): Earth radius 6360 km, top at 60 km; Rayleigh
//!   `β_R = 1.24062·10⁻⁶ λ⁻⁴` m⁻¹ (λ in µm) with an 8 km scale height and phase `3 (1 + cos² γ) / 16π`;
//!   aerosols with a 1.2 km scale height, single-scattering albedo 0.9 and the Cornette–Shanks phase with
//!   `g = 0.8`, their optical depth set by the turbidity (`T = (τ_R + τ_M) / τ_R` at 550 nm, Preetham's
//!   definition); ozone absorbing only, in a tent between 10 and 40 km peaking at 25 km, 300 Dobson units, with
//!   the cross-sections of A. Serdyuchenko et al., Atmos. Meas. Tech. 7, 625–636 (2014), 233 K, averaged over
//!   10 nm either side of the channels' centres (0.61, 0.55, 0.465 µm): 4.66·10⁻²⁵, 3.30·10⁻²⁵, 3.67·10⁻²⁶ m².
//!   The ozone is what makes the twilight zenith blue (E. O. Hulburt, J. Opt. Soc. Am. 43(2), 113–118, 1953);
//!   the long tangent paths through the lower air redden the afterglow.
//! * **What it gives the sky**: the distribution and colour of the twilight sky, tabulated once per sun
//!   elevation over view elevation and azimuth from the sun. Single scattering underestimates the deep
//!   twilight's level (multiple scattering dominates beyond ~6° of depression), so `sky.rs` scales the table to
//!   the horizontal illuminance of its own twilight sky and keeps only the shape and colours. The table is that
//!   of pure air with its ozone, without aerosols: in single scattering, haze darkens the band over the sunward
//!   horizon a thousandfold at turbidity 3 (the long, low view path through haze still in the Earth's shadow),
//!   where the light it scatters forward, more than once, keeps real afterglows brightest at the horizon;
//!   without it the band is the orange afterglow under a blue zenith.
//! * **Haze in the Earth's shadow** ([`shadowed_haze`]): once the sun is a degree below the horizon the low air
//!   is in the shadow, lit by the sky alone; what distant things fade into (the aerial perspective's `L_air`,
//!   by day the horizon sky at the view's azimuth) is then that air's isotropic single scattering of the sky's
//!   mean radiance, `ω M / 2`, the same in every direction — not the afterglow behind it.
//!
//! Checked in the tests against closed forms: the vertical optical depths (Rayleigh and aerosol `β H`, the ozone
//! column `σ N`), and the zenith radiance of a high sun in a Rayleigh-only atmosphere, whose plane-parallel
//! single scattering integrates exactly; the shadowed haze against the sky's mean integrated on its own grid
//! (`envlight.rs`).

use parry3d::math::Vec3;

/// Earth's radius, m.
const EARTH_RADIUS: f64 = 6_360_000.0;
/// Radius of the atmosphere's top, m.
const TOP_RADIUS: f64 = 6_420_000.0;
/// Rayleigh scattering at 1 µm at sea level, m⁻¹ (scales as λ⁻⁴).
const RAYLEIGH_1UM: f64 = 1.240_62e-6;
/// Rayleigh scale height, m.
const RAYLEIGH_HEIGHT: f64 = 8_000.0;
/// Aerosol scale height, m.
const MIE_HEIGHT: f64 = 1_200.0;
/// Aerosol single-scattering albedo.
const MIE_ALBEDO: f64 = 0.9;
/// Aerosol phase asymmetry.
const MIE_G: f64 = 0.8;
/// Ozone cross-sections at the R, G, B centre wavelengths, m².
const OZONE_CROSS_SECTION: [f64; 3] = [4.66e-25, 3.30e-25, 3.67e-26];
/// Ozone column: 300 Dobson units, molecules per m².
const OZONE_COLUMN: f64 = 300.0 * 2.687e20;
/// Centre wavelengths of the R, G, B channels, µm: `sky::LAMBDA` in double precision (the table is integrated
/// in f64; widening the f32 values would move its last bits).
const LAMBDA: [f64; 3] = [0.61, 0.55, 0.465];
/// Steps along a view ray and along a ray towards the sun.
const VIEW_STEPS: usize = 96;
const SUN_STEPS: usize = 48;
/// Rows (view elevation, 0..90°, denser near the horizon) and columns (azimuth from the sun, 0..180°) of a table.
const ROWS: usize = 24;
const COLS: usize = 25;

/// The atmosphere's coefficients per channel, m⁻¹ at sea level (ozone: per unit of its tent profile).
#[derive(Debug, Clone, Copy)]
pub struct Atmosphere {
    /// Rayleigh scattering (= extinction).
    pub rayleigh: [f64; 3],
    /// Aerosol extinction (scattering is 0.9 of it, the single-scattering albedo).
    pub mie: [f64; 3],
    /// Ozone absorption at the profile's peak.
    pub ozone: [f64; 3],
}

impl Atmosphere {
    /// The atmosphere of Preetham turbidity `turbidity` (≥ 1; 1 is pure air), with ozone when `ozone`.
    pub fn new(turbidity: f64, ozone: bool) -> Self {
        let rayleigh = LAMBDA.map(|l| RAYLEIGH_1UM / l.powi(4));
        let tau_r = RAYLEIGH_1UM / LAMBDA[1].powi(4) * RAYLEIGH_HEIGHT;
        // Aerosol optical depth (turbidity − 1) τ_R at 550 nm, wavelength-neutral (Ångström exponent 0).
        let mie = [(turbidity.max(1.0) - 1.0) * tau_r / MIE_HEIGHT; 3];
        // The tent's integral is 15 km: peak density = column / 15 km.
        let peak = OZONE_COLUMN / 15_000.0;
        let ozone = if ozone { OZONE_CROSS_SECTION.map(|s| s * peak) } else { [0.0; 3] };
        Self { rayleigh, mie, ozone }
    }

    /// Extinction per channel at altitude `z` (m).
    fn extinction(&self, z: f64) -> [f64; 3] {
        let (r, m, o) = ((-z / RAYLEIGH_HEIGHT).exp(), (-z / MIE_HEIGHT).exp(), ozone_profile(z));
        std::array::from_fn(|c| self.rayleigh[c] * r + self.mie[c] * m + self.ozone[c] * o)
    }

    /// Optical depth per channel from `p` (m, from the Earth's centre) along unit `d` to the atmosphere's top;
    /// `None` where the ray meets the ground.
    fn optical_depth_to_top(&self, p: [f64; 3], d: [f64; 3], steps: usize) -> Option<[f64; 3]> {
        let pd = dot(p, d);
        let pp = dot(p, p);
        if pd < 0.0 && pp - pd * pd < EARTH_RADIUS * EARTH_RADIUS {
            return None;
        }
        let t_top = -pd + (pd * pd - pp + TOP_RADIUS * TOP_RADIUS).max(0.0).sqrt();
        Some(integrate(t_top, steps, |t| self.extinction(altitude(add(p, d, t)))))
    }

    /// Single-scattered radiance per channel towards an observer at sea level looking along unit `v` (z up),
    /// for a sun of unit irradiance towards unit `s`.
    pub fn radiance(&self, v: [f64; 3], s: [f64; 3]) -> [f64; 3] {
        let o = [0.0, 0.0, EARTH_RADIUS + 1.0];
        let ov = dot(o, v);
        let t_top = -ov + (ov * ov - dot(o, o) + TOP_RADIUS * TOP_RADIUS).sqrt();
        let cos_g = dot(v, s);
        let p_r = 3.0 * (1.0 + cos_g * cos_g) / (16.0 * std::f64::consts::PI);
        let g2 = MIE_G * MIE_G;
        let p_m = 3.0 * (1.0 - g2) * (1.0 + cos_g * cos_g)
            / (8.0 * std::f64::consts::PI * (2.0 + g2) * (1.0 + g2 - 2.0 * MIE_G * cos_g).powf(1.5));
        // March outwards with the view path's optical depth accumulated as we go (midpoint rule, quadratic
        // spacing: the air thins with height).
        let mut out = [0.0; 3];
        let mut depth = [0.0; 3];
        let mut prev = 0.0;
        for i in 0..VIEW_STEPS {
            let t = t_top * ((i as f64 + 1.0) / VIEW_STEPS as f64).powi(2);
            let dt = t - prev;
            let mid = prev + 0.5 * dt;
            prev = t;
            let p = add(o, v, mid);
            let z = altitude(p);
            let ext = self.extinction(z);
            let half: [f64; 3] = std::array::from_fn(|c| depth[c] + 0.5 * ext[c] * dt);
            depth = std::array::from_fn(|c| depth[c] + ext[c] * dt);
            let Some(sun_depth) = self.optical_depth_to_top(p, s, SUN_STEPS) else { continue };
            let (r, m) = ((-z / RAYLEIGH_HEIGHT).exp(), (-z / MIE_HEIGHT).exp());
            for c in 0..3 {
                let scatter = self.rayleigh[c] * r * p_r + self.mie[c] * MIE_ALBEDO * m * p_m;
                out[c] += (-(half[c] + sun_depth[c])).exp() * scatter * dt;
            }
        }
        out
    }
}

/// The twilight sky's shape and colour for one sun: single-scattered radiance on a grid of view elevation
/// and azimuth from the sun (see the module docs).
#[derive(Debug, Clone)]
pub struct TwilightTable {
    /// `ROWS × COLS` radiances (linear RGB, arbitrary unit), row-major.
    values: Vec<Vec3>,
}

impl TwilightTable {
    /// The table for a sun at elevation `h` (radians): pure air and ozone, without aerosols (see the module
    /// docs).
    pub fn new(h: f32) -> Self {
        let atm = Atmosphere::new(1.0, true);
        let hs = f64::from(h);
        let s = [hs.cos(), 0.0, hs.sin()];
        let mut values = Vec::with_capacity(ROWS * COLS);
        for i in 0..ROWS {
            let e = row_elevation(i);
            for j in 0..COLS {
                let a = std::f64::consts::PI * j as f64 / (COLS - 1) as f64;
                let v = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
                let l = atm.radiance(v, s);
                values.push(Vec3::new(l[0] as f32, l[1] as f32, l[2] as f32));
            }
        }
        Self { values }
    }

    /// Radiance towards unit `d` (z up; below the horizon: the horizon's) for a sun at azimuth `sun_azimuth`
    /// (radians, from +x towards +y), interpolated bilinearly.
    pub fn radiance(&self, d: Vec3, sun_azimuth: f32) -> Vec3 {
        let e = d.z.clamp(0.0, 1.0).asin();
        let fr = (e / std::f32::consts::FRAC_PI_2).sqrt() * (ROWS - 1) as f32;
        let mut a = (d.y.atan2(d.x) - sun_azimuth).abs() % std::f32::consts::TAU;
        if a > std::f32::consts::PI {
            a = std::f32::consts::TAU - a;
        }
        let fc = a / std::f32::consts::PI * (COLS - 1) as f32;
        let (r0, c0) = ((fr as usize).min(ROWS - 2), (fc as usize).min(COLS - 2));
        let (wr, wc) = (fr - r0 as f32, fc - c0 as f32);
        let at = |r: usize, c: usize| self.values[r * COLS + c];
        let top = at(r0, c0) * (1.0 - wc) + at(r0, c0 + 1) * wc;
        let bottom = at(r0 + 1, c0) * (1.0 - wc) + at(r0 + 1, c0 + 1) * wc;
        top * (1.0 - wr) + bottom * wr
    }
}

/// Radiance of haze in the Earth's shadow, lit by the twilight sky alone: isotropic single scattering of the
/// mean radiance `mean_sky` of the upper hemisphere (the dark ground adds nothing), `ω M / 2` with the aerosols'
/// single-scattering albedo `ω`. What distant things fade into once the sun has left the low air.
pub fn shadowed_haze(mean_sky: Vec3) -> Vec3 {
    mean_sky * (0.5 * MIE_ALBEDO as f32)
}

/// Weight of [`shadowed_haze`] against the sunlit horizon's radiance in the aerial perspective, for a sun at
/// elevation `h` (radians): 0 with the sun up, 1 from 1° below the horizon (where the Earth's shadow covers the
/// first hundred metres of air over the observer), linear between.
pub fn shadowed_haze_weight(h: f32) -> f32 {
    (-h / 1f32.to_radians()).clamp(0.0, 1.0)
}

/// View elevation of table row `i`, radians (rows uniform in √elevation: denser near the horizon).
fn row_elevation(i: usize) -> f64 {
    std::f64::consts::FRAC_PI_2 * (i as f64 / (ROWS - 1) as f64).powi(2)
}

/// Ozone density relative to its peak at altitude `z` (m): a tent from 10 to 40 km, 1 at 25 km.
fn ozone_profile(z: f64) -> f64 {
    (1.0 - (z - 25_000.0).abs() / 15_000.0).max(0.0)
}

/// `∫₀^t_max f(t) dt` per channel, midpoint rule on `steps` quadratically spaced intervals.
fn integrate(t_max: f64, steps: usize, f: impl Fn(f64) -> [f64; 3]) -> [f64; 3] {
    let mut acc = [0.0; 3];
    let mut prev = 0.0;
    for i in 0..steps {
        let t = t_max * ((i as f64 + 1.0) / steps as f64).powi(2);
        let v = f(0.5 * (prev + t));
        for c in 0..3 {
            acc[c] += v[c] * (t - prev);
        }
        prev = t;
    }
    acc
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn add(p: [f64; 3], d: [f64; 3], t: f64) -> [f64; 3] {
    [p[0] + d[0] * t, p[1] + d[1] * t, p[2] + d[2] * t]
}

fn altitude(p: [f64; 3]) -> f64 {
    dot(p, p).sqrt() - EARTH_RADIUS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertical_optical_depths_are_the_closed_forms() {
        let atm = Atmosphere::new(3.0, true);
        let o = [0.0, 0.0, EARTH_RADIUS];
        let Some(tau) = atm.optical_depth_to_top(o, [0.0, 0.0, 1.0], 4000) else { panic!("the zenith is open") };
        let h = TOP_RADIUS - EARTH_RADIUS;
        for c in 0..3 {
            let rayleigh = atm.rayleigh[c] * RAYLEIGH_HEIGHT * (1.0 - (-h / RAYLEIGH_HEIGHT).exp());
            let mie = atm.mie[c] * MIE_HEIGHT;
            let ozone = OZONE_CROSS_SECTION[c] * OZONE_COLUMN;
            let want = rayleigh + mie + ozone;
            assert!((tau[c] - want).abs() / want < 1e-3, "channel {c}: {} vs {want}", tau[c]);
        }
        // Rayleigh at 550 nm: 0.108; turbidity 3 doubles it in aerosols; ozone: 0.038, 0.027, 0.003.
        assert!((atm.rayleigh[1] * RAYLEIGH_HEIGHT - 0.1085).abs() < 1e-3);
        assert!((OZONE_CROSS_SECTION[0] * OZONE_COLUMN - 0.0376).abs() < 1e-3);
        // A ray towards the ground has no way out.
        assert!(atm.optical_depth_to_top(o, [0.6, 0.0, -0.8], 10).is_none());
    }

    #[test]
    fn zenith_of_a_high_sun_in_pure_air_is_the_plane_parallel_closed_form() {
        // Rayleigh only, sun at zenith angle θs, looking up: with τ₀ = β H and μ = sec θs,
        // L = E P(γ) e^{−τ₀} (1 − e^{−τ₀ (μ − 1)}) / (μ − 1) (exponential air, plane-parallel, single scattering).
        let atm = Atmosphere { rayleigh: Atmosphere::new(1.0, false).rayleigh, mie: [0.0; 3], ozone: [0.0; 3] };
        let theta: f64 = 40f64.to_radians();
        let s = [theta.sin(), 0.0, theta.cos()];
        let l = atm.radiance([0.0, 0.0, 1.0], s);
        let h = TOP_RADIUS - EARTH_RADIUS;
        for c in 0..3 {
            let tau0 = atm.rayleigh[c] * RAYLEIGH_HEIGHT * (1.0 - (-h / RAYLEIGH_HEIGHT).exp());
            let mu = 1.0 / theta.cos();
            let p = 3.0 * (1.0 + theta.cos().powi(2)) / (16.0 * std::f64::consts::PI);
            let want = p * (-tau0).exp() * (1.0 - (-tau0 * (mu - 1.0)).exp()) / (mu - 1.0);
            assert!((l[c] - want).abs() / want < 0.01, "channel {c}: {} vs {want}", l[c]);
        }
        // Blue sky: the blue channel scatters most.
        assert!(l[2] > l[1] && l[1] > l[0]);
    }

    #[test]
    fn twilight_zenith_is_blue_by_ozone_and_the_afterglow_red() {
        let s = |deg: f64| [deg.to_radians().cos(), 0.0, deg.to_radians().sin()];
        let zen = [0.0, 0.0, 1.0];
        let (with, without) = (Atmosphere::new(3.0, true), Atmosphere::new(3.0, false));
        let mut last = f64::INFINITY;
        for deg in [-1.0, -3.0, -5.0, -6.5] {
            let a = with.radiance(zen, s(deg));
            let b = without.radiance(zen, s(deg));
            // Hulburt: the ozone turns the zenith blue; without it, the reddened sunlight leaves it yellowish.
            assert!(a[2] / a[0] > 1.3 * (b[2] / b[0]), "{deg}°: {a:?} vs {b:?}");
            assert!(a[2] > a[0], "{deg}°: {a:?}");
            // The Earth's shadow rises: the zenith darkens.
            let y = a[1];
            assert!(y < last, "{deg}°");
            last = y;
        }
        // The afterglow: just over the horizon towards the sun, red over blue.
        let low = [5f64.to_radians().cos(), 0.0, 5f64.to_radians().sin()];
        let glow = with.radiance(low, s(-3.0));
        assert!(glow[0] > glow[2], "{glow:?}");
    }

    #[test]
    fn table_reads_back_its_nodes_and_is_symmetric() {
        let t = TwilightTable::new(-4f32.to_radians());
        let atm = Atmosphere::new(1.0, true);
        let s = [(-4f64).to_radians().cos(), 0.0, (-4f64).to_radians().sin()];
        let (i, j) = (10usize, 6usize);
        let e = row_elevation(i);
        let a = std::f64::consts::PI * j as f64 / (COLS - 1) as f64;
        let v = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
        let want = atm.radiance(v, s);
        // The sun at azimuth 0.3 rad: turn the view with it.
        let d = Vec3::new((e.cos() * (a + 0.3).cos()) as f32, (e.cos() * (a + 0.3).sin()) as f32, e.sin() as f32);
        let got = t.radiance(d, 0.3);
        assert!((f64::from(got.y) - want[1]).abs() / want[1] < 1e-3, "{got} vs {want:?}");
        let mirrored = t.radiance(Vec3::new(d.x, -d.y, d.z), -0.3);
        assert!((mirrored - got).length() < 1e-4 * got.length());
    }
}
