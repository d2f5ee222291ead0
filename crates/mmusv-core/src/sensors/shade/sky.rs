//! Daylight: the Preetham clear sky, the CIE overcast sky, the sun's direct beam and its disc.
//!
//! * **Clear sky**: A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight",
//!   SIGGRAPH 1999 — zenith luminance and chromaticity from the turbidity `T` and the sun's zenith angle, and the
//!   Perez et al. (1993) all-weather distribution `F(θ, γ) = (1 + A e^{B / cos θ})(1 + C e^{D γ} + E cos² γ)`
//!   for `Y`, `x` and `y` (the paper's Appendix A.2 coefficients). `xyY` goes to CIE XYZ and then to linear
//!   sRGB (Rec. 709 primaries, D65), so the `Y` of every RGB value here is a luminance in cd/m².
//! * **Overcast sky**: the CIE standard overcast sky (Moon & Spencer 1942), `L(θ) = L_z (1 + 2 cos θ) / 3`,
//!   whose horizontal illuminance is `E_h = 7π L_z / 9`; mixed with the clear sky by the cloud cover.
//! * **Sun**: direct-normal illuminance from the ESRA clear-sky model (Rigollier, Bauer & Wald 2000, Solar
//!   Energy 68(1)): `E_b = E_0 exp(−0.8662 T_L m δ_R(m))`, with the Kasten & Young (1989) air mass `m` and
//!   Kasten's (1996) Rayleigh optical thickness `δ_R(m)`; `T_L` is taken equal to the Preetham turbidity.
//!   The optical depth is scaled per channel by `(λ_G / λ)²` (a Rayleigh–aerosol compromise between the
//!   exponents 4 and ~1.3), which reddens the low sun. The disc has its true angular radius 0.2665°, and its
//!   radiance is `E_b / Ω_sun`.
//! * **Twilight and night**: Preetham is defined for the sun above the horizon. Below it the sky is the
//!   model's horizon-sun sky scaled by `exp(h / 0.9°)` (`h` the sun's elevation in degrees: about 10⁻³ at the
//!   end of civil twilight, −6°, the fall the zenith luminance shows from sunset), over a night floor of
//!   0.002/π cd/m², a uniform sky whose horizontal illuminance `π L` is a moonless clear night's 0.002 lux (the
//!   figure was once taken as the luminance itself: 3.1 times too bright) — in level: its shape and colour are those of single scattering
//!   in a spherical atmosphere of pure air with the Earth's shadow and the ozone layer ([`super::twilight`]),
//!   the blue zenith over the orange band of the sunward horizon, scaled to the same horizontal illuminance (so
//!   what lights the scene and sets the metered exposure keeps its level). Between the horizon and 1° below it
//!   the two skies are blended; beyond 6° of depression the shape of 6° is kept (single scattering there comes
//!   from ever higher, thinner air, where light scattered more than once dominates) and only the level falls.
//!
//! Checked in the tests against the closed forms: the overcast sky's horizontal illuminance, Preetham's zenith
//! value equal to its zenith formula, the air mass at zenith, and the disc's solid angle; the twilight sky's
//! horizontal illuminance against Preetham's twilight sky's, integrated on a grid of its own.

use super::twilight::TwilightTable;
use parry3d::math::Vec3;
use std::sync::Arc;

/// Extraterrestrial solar illuminance `E_0`, lux.
pub const SOLAR_CONSTANT_LUX: f32 = 128_000.0;
/// Angular radius of the sun's disc, radians (0.2665°, 0.533° across).
pub const SUN_RADIUS_RAD: f32 = 0.004_651;
/// `sin²` of [`SUN_RADIUS_RAD`] (`sin r = 0.004_650_98`).
const SIN2_SUN_RADIUS: f32 = 2.163_164_6e-5;
/// `cos 2r`: directions farther from the sun than twice its radius are outside the disc, whatever the rounding.
const COS_SUN_GUARD: f32 = 0.999_956_7;
/// Night-sky floor, cd/m²: a uniform sky lighting the ground with a moonless clear night's 0.002 lux (`π L`).
const NIGHT_FLOOR: f32 = 0.002 / std::f32::consts::PI;
/// Centre wavelengths of the R, G, B channels, µm (`twilight.rs` holds them in double precision).
const LAMBDA: [f32; 3] = [0.61, 0.55, 0.465];
/// Depression below which the twilight sky keeps its shape (only its level falls), radians (6°).
const TWILIGHT_SHAPE_LIMIT: f32 = 0.104_72;
/// Depression over which Preetham's horizon-sun sky gives way to the twilight sky, radians (1°).
const TWILIGHT_BLEND: f32 = 0.017_453;

/// Solid angle of the sun's disc, sr: `2π (1 − cos r)`, evaluated as `4π sin²(r/2)` (in f32, `1 − cos r` at
/// r = 0.27° keeps three digits and came out 0.25 % small, the disc 0.25 % too bright).
pub fn sun_solid_angle() -> f32 {
    let s = (0.5 * SUN_RADIUS_RAD).sin();
    2.0 * std::f32::consts::TAU * s * s
}

/// Linear sRGB (D65) from CIE XYZ.
#[inline]
pub fn xyz_to_rgb(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(
        3.240_6 * x - 1.537_2 * y - 0.498_6 * z,
        -0.968_9 * x + 1.875_8 * y + 0.041_5 * z,
        0.055_7 * x - 0.204 * y + 1.057 * z,
    )
}

/// Luminance (cd/m² for a radiance, lux for an irradiance) of a linear sRGB value.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.212_6 * c.x + 0.715_2 * c.y + 0.072_2 * c.z
}

/// Perez coefficients `A..E` of one quantity.
#[derive(Debug, Clone, Copy)]
struct Perez([f32; 5]);

impl Perez {
    #[inline]
    fn f(&self, cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
        let [a, b, c, d, e] = self.0;
        (1.0 + a * (b / cos_theta).exp()) * (1.0 + c * (d * gamma).exp() + e * cos_gamma * cos_gamma)
    }
}

/// Kasten & Young (1989) relative optical air mass at solar elevation `h` (radians).
pub fn air_mass(h: f32) -> f32 {
    let hd = h.to_degrees().max(0.0);
    1.0 / (h.max(0.0).sin() + 0.505_72 * (hd + 6.079_95).powf(-1.636_4))
}

/// Kasten (1996) Rayleigh optical thickness at air mass `m`.
pub fn rayleigh_thickness(m: f32) -> f32 {
    if m <= 20.0 {
        1.0 / (6.629_6 + 1.751_3 * m - 0.120_2 * m * m + 0.006_5 * m * m * m - 0.000_13 * m * m * m * m)
    } else {
        1.0 / (10.4 + 0.718 * m)
    }
}

/// `∫ L(d) cos θ dω` over the upper hemisphere (lux for a radiance in cd/m²), by the midpoint rule on 256 rings
/// (uniform in `cos θ`, fine enough for the afterglow's band, a degree or two over the horizon) of 64 directions.
fn horizontal_illuminance(radiance: impl Fn(Vec3) -> Vec3) -> f32 {
    let (rings, n) = (256, 64);
    let mut e = 0.0f64;
    for i in 0..rings {
        let mu = (i as f32 + 0.5) / rings as f32;
        let s = (1.0 - mu * mu).sqrt();
        for j in 0..n {
            let phi = std::f32::consts::TAU * (j as f32 + 0.5) / n as f32;
            e += f64::from(luminance(radiance(Vec3::new(s * phi.cos(), s * phi.sin(), mu))) * mu);
        }
    }
    (e * std::f64::consts::TAU / (rings * n) as f64) as f32
}

/// The sky and the sun of one environment (see the module docs).
#[derive(Debug, Clone)]
pub struct Sky {
    /// Unit vector towards the sun (world frame; may point below the horizon).
    pub sun: Vec3,
    /// Sun zenith angle used by the Preetham model (clamped to the horizon).
    theta_s: f32,
    perez: [Perez; 3],
    /// Zenith `Y` (cd/m²), `x`, `y`, each divided by its `F(0, θ_s)`.
    zenith_over_f0: [f32; 3],
    /// Weight of the clear sky (1 − cloud cover) times the twilight factor.
    clear_weight: f32,
    /// CIE overcast zenith luminance (cd/m²) times the cloud cover and the twilight factor.
    overcast_lz: f32,
    /// Direct-normal irradiance of the sun (linear RGB, lux), 0 when it is set or hidden by cloud.
    sun_irradiance: Vec3,
    /// Radiance of the sun's disc (linear RGB, cd/m²).
    sun_radiance: Vec3,
    /// With the sun below the horizon, the twilight sky.
    twilight: Option<Twilight>,
}

/// The twilight sky of a [`Sky`] whose sun is below the horizon.
#[derive(Debug, Clone)]
struct Twilight {
    table: Arc<TwilightTable>,
    /// The sun's azimuth (radians, from +x towards +y), which the table is read around.
    sun_azimuth: f32,
    /// Weight against Preetham's horizon-sun sky.
    weight: f32,
    /// Scale giving the table that sky's horizontal illuminance.
    scale: f32,
}

impl Sky {
    /// The sky for a sun towards `sun` (unit, world frame), Preetham turbidity `turbidity` (clamped to
    /// `[1.7, 10]`) and cloud cover `cloud` in `[0, 1]`.
    pub fn new(sun: Vec3, turbidity: f32, cloud: f32) -> Self {
        let sun = sun.normalize_or(Vec3::Z);
        let t = turbidity.clamp(1.7, 10.0);
        let cloud = cloud.clamp(0.0, 1.0);
        let h = sun.z.clamp(-1.0, 1.0).asin();
        let theta_s = (std::f32::consts::FRAC_PI_2 - h).min(std::f32::consts::FRAC_PI_2 - 1e-3);
        let twilight = if h >= 0.0 { 1.0 } else { (h.to_degrees() / 0.9).exp() };
        let perez = [
            Perez([
                0.178_7 * t - 1.463,
                -0.355_4 * t + 0.427_5,
                -0.022_7 * t + 5.325_1,
                0.120_6 * t - 2.577_1,
                -0.067 * t + 0.370_3,
            ]),
            Perez([
                -0.019_3 * t - 0.259_2,
                -0.066_5 * t + 0.000_8,
                -0.000_4 * t + 0.212_5,
                -0.064_1 * t - 0.898_9,
                -0.003_3 * t + 0.045_2,
            ]),
            Perez([
                -0.016_7 * t - 0.260_8,
                -0.095 * t + 0.009_2,
                -0.007_9 * t + 0.210_2,
                -0.044_1 * t - 1.653_7,
                -0.010_9 * t + 0.052_9,
            ]),
        ];
        let chi = (4.0 / 9.0 - t / 120.0) * (std::f32::consts::PI - 2.0 * theta_s);
        let yz = ((4.045_3 * t - 4.971) * chi.tan() - 0.215_5 * t + 2.419_2).max(0.0) * 1000.0;
        let (t1, t2, t3) = (theta_s, theta_s * theta_s, theta_s * theta_s * theta_s);
        let xz = t * t * (0.001_66 * t3 - 0.003_75 * t2 + 0.002_09 * t1)
            + t * (-0.029_03 * t3 + 0.063_77 * t2 - 0.032_02 * t1 + 0.003_94)
            + (0.116_93 * t3 - 0.211_96 * t2 + 0.060_52 * t1 + 0.258_86);
        let yz_c = t * t * (0.002_75 * t3 - 0.006_1 * t2 + 0.003_17 * t1)
            + t * (-0.042_14 * t3 + 0.089_7 * t2 - 0.041_53 * t1 + 0.005_16)
            + (0.153_46 * t3 - 0.267_56 * t2 + 0.066_7 * t1 + 0.266_88);
        let (cs, gs) = (theta_s.cos(), theta_s);
        let f0 = |p: &Perez| p.f(1.0, gs, cs);
        let zenith_over_f0 = [yz / f0(&perez[0]), xz / f0(&perez[1]), yz_c / f0(&perez[2])];
        // The sun's beam (ESRA) and the overcast sky's level, both following the real elevation.
        let up = h.max(0.0);
        let m = air_mass(up);
        let tau = 0.866_2 * t * m * rayleigh_thickness(m);
        let beam = |i: usize| {
            let tau_c = tau * (LAMBDA[1] / LAMBDA[i]).powi(2);
            SOLAR_CONSTANT_LUX * (-tau_c).exp()
        };
        let sun_irradiance = if h > 0.0 { Vec3::new(beam(0), beam(1), beam(2)) * (1.0 - cloud) } else { Vec3::ZERO };
        // Overcast horizontal illuminance: ~20 klux under a high sun, less as it sinks.
        let e_overcast = 20_000.0 * up.sin().max(0.0).powf(1.2) + 400.0 * twilight * (h > -0.2) as i32 as f32;
        let mut sky = Self {
            sun,
            theta_s,
            perez,
            zenith_over_f0,
            clear_weight: (1.0 - cloud) * twilight,
            overcast_lz: cloud * 9.0 * e_overcast / (7.0 * std::f32::consts::PI) * twilight.min(1.0),
            sun_irradiance,
            sun_radiance: sun_irradiance / sun_solid_angle(),
            twilight: None,
        };
        if h < 0.0 {
            // The twilight sky, scaled to the horizontal illuminance of Preetham's horizon-sun sky (what lights
            // the scene and sets the metered exposure stays as it was; the light's distribution and colour change).
            let table = TwilightTable::new(h.max(-TWILIGHT_SHAPE_LIMIT));
            let sun_azimuth = sky.sun.y.atan2(sky.sun.x);
            let scale = horizontal_illuminance(|d| sky.preetham(d))
                / horizontal_illuminance(|d| table.radiance(d, sun_azimuth)).max(f32::MIN_POSITIVE);
            let weight = (-h / TWILIGHT_BLEND).min(1.0);
            sky.twilight = Some(Twilight { table: Arc::new(table), sun_azimuth, weight, scale });
        }
        sky
    }

    /// Sky radiance (linear RGB, cd/m²) towards unit direction `d`, without the sun's disc. Directions below the
    /// horizon get the horizon's value.
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let mut c = Vec3::splat(NIGHT_FLOOR);
        if self.clear_weight > 0.0 {
            let mut rgb = self.preetham(d);
            if let Some(t) = &self.twilight {
                let dusk = t.table.radiance(d, t.sun_azimuth) * t.scale;
                rgb = rgb * (1.0 - t.weight) + dusk * t.weight;
            }
            c += rgb * self.clear_weight;
        }
        if self.overcast_lz > 0.0 {
            c += Vec3::splat(self.overcast_lz * (1.0 + 2.0 * d.z.max(0.0)) / 3.0);
        }
        c
    }

    /// Preetham's clear sky towards unit `d` (linear RGB, cd/m², before the cloud cover and the twilight factor).
    #[inline]
    fn preetham(&self, d: Vec3) -> Vec3 {
        let cos_theta = d.z.max(0.01);
        let cos_gamma = d.dot(self.sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let y = self.zenith_over_f0[0] * self.perez[0].f(cos_theta, gamma, cos_gamma);
        let x = self.zenith_over_f0[1] * self.perez[1].f(cos_theta, gamma, cos_gamma);
        let yc = (self.zenith_over_f0[2] * self.perez[2].f(cos_theta, gamma, cos_gamma)).max(1e-4);
        xyz_to_rgb(x * y / yc, y, (1.0 - x - yc) * y / yc).max(Vec3::ZERO)
    }

    /// Radiance of the sun's disc (linear RGB, cd/m²) if `d` points into it, else zero. Inside is within
    /// [`SUN_RADIUS_RAD`] of the sun: `|d × s|² ≤ sin²r |d|²` on the sun's side. The cross product gives the
    /// angle to about 10⁻⁷ rad; `d·s ≥ cos r` does not (in f32, a cosine this close to 1 is resolved to 6·10⁻⁸
    /// against `1 − cos r` = 1.1·10⁻⁵: the disc's edge moved with the sun's direction, its diameter by up to 0.7 %
    /// and the light it carries by up to 1.7 %).
    #[inline(always)]
    pub fn sun_disc(&self, d: Vec3) -> Vec3 {
        if d.dot(self.sun) >= COS_SUN_GUARD
            && d.cross(self.sun).length_squared() <= SIN2_SUN_RADIUS * d.length_squared()
        {
            self.sun_radiance
        } else {
            Vec3::ZERO
        }
    }

    /// Direct-normal irradiance of the sun's beam (linear RGB, lux); zero at night or under full cloud.
    #[inline]
    pub fn sun_irradiance(&self) -> Vec3 {
        self.sun_irradiance
    }

    /// The sun's zenith angle used by the model, radians.
    pub fn sun_zenith(&self) -> f32 {
        self.theta_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ (L − night floor) cos θ dω` of `sky` over the upper hemisphere, by the midpoint rule on `n_t` rings
    /// uniform in the zenith angle θ, `n_p` directions each (a grid of its own, not the model's).
    fn horizontal_illuminance_theta(sky: &Sky, n_t: usize, n_p: usize) -> f64 {
        let mut e = 0.0f64;
        for i in 0..n_t {
            let th = (i as f64 + 0.5) / n_t as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..n_p {
                let ph = (j as f64 + 0.5) / n_p as f64 * std::f64::consts::TAU;
                let d = Vec3::new((th.sin() * ph.cos()) as f32, (th.sin() * ph.sin()) as f32, th.cos() as f32);
                let l = luminance(sky.radiance(d)) as f64 - NIGHT_FLOOR as f64;
                e += l * th.cos() * th.sin();
            }
        }
        e * (std::f64::consts::FRAC_PI_2 / n_t as f64) * (std::f64::consts::TAU / n_p as f64)
    }

    #[test]
    fn zenith_value_is_the_zenith_formula() {
        // At the zenith θ = 0, γ = θ_s: F(0, θ_s) / F(0, θ_s) = 1, so Y is the zenith luminance itself.
        let sun = Vec3::new(0.6, 0.0, 0.8);
        let sky = Sky::new(sun, 3.0, 0.0);
        let t = 3.0f32;
        let theta_s = sky.sun_zenith();
        let chi = (4.0 / 9.0 - t / 120.0) * (std::f32::consts::PI - 2.0 * theta_s);
        let yz = ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192) * 1000.0;
        let y = luminance(sky.radiance(Vec3::Z)) - NIGHT_FLOOR;
        assert!((y - yz).abs() / yz < 0.01, "{y} vs {yz}");
        // Clear blue sky: blue exceeds red at the zenith; brighter towards the sun than away from it.
        let z = sky.radiance(Vec3::Z);
        assert!(z.z > z.x);
        let towards = sky.radiance(Vec3::new(0.7, 0.0, 0.714).normalize());
        let away = sky.radiance(Vec3::new(-0.7, 0.0, 0.714).normalize());
        assert!(luminance(towards) > 2.0 * luminance(away));
    }

    #[test]
    fn overcast_sky_gives_its_horizontal_illuminance() {
        let sky = Sky::new(Vec3::new(0.0, 0.0, 1.0), 3.0, 1.0);
        let e = horizontal_illuminance_theta(&sky, 400, 64);
        let want = 20_000.0 + 400.0;
        assert!((e - want).abs() / want < 0.01, "{e} vs {want}");
    }

    #[test]
    fn sun_beam_follows_air_mass_and_disc_has_its_size() {
        assert!((air_mass(std::f32::consts::FRAC_PI_2) - 1.0).abs() < 1e-3);
        // Kasten & Young at 10° elevation: m ≈ 5.6.
        assert!((air_mass(10f32.to_radians()) - 5.6).abs() < 0.1);
        let high = Sky::new(Vec3::new(0.0, 0.0, 1.0), 3.0, 0.0);
        let low = Sky::new(Vec3::new(0.98, 0.0, 0.199).normalize(), 3.0, 0.0);
        let (eh, el) = (high.sun_irradiance(), low.sun_irradiance());
        assert!(luminance(eh) > 70_000.0 && luminance(eh) < SOLAR_CONSTANT_LUX, "{eh}");
        assert!(el.x / el.z > eh.x / eh.z, "the low sun is redder");
        let inside = Vec3::new(SUN_RADIUS_RAD * 0.9, 0.0, 1.0).normalize();
        let outside = Vec3::new(SUN_RADIUS_RAD * 1.1, 0.0, 1.0).normalize();
        assert!(high.sun_disc(inside).y > 0.0);
        assert_eq!(high.sun_disc(outside), Vec3::ZERO);
        // Disc radiance × solid angle = irradiance.
        let omega = sun_solid_angle();
        assert!(((high.sun_disc(Vec3::Z) * omega).y - eh.y).abs() / eh.y < 1e-3);
        let night = Sky::new(Vec3::new(0.0, 0.9, -0.3).normalize(), 3.0, 0.0);
        assert_eq!(night.sun_irradiance(), Vec3::ZERO);
        assert!(luminance(night.radiance(Vec3::Z)) < 1.0);
    }

    /// The disc seen as the cameras see it (unit f32 directions on a fine grid around the sun, for suns in
    /// several directions): its radiance times its solid angle, `2π (1 − cos r)` evaluated exactly, is the sun's
    /// irradiance, and the directions it covers add up to that same irradiance over a cone of radius
    /// [`SUN_RADIUS_RAD`] (the cone's edge within 0.1 %: a direction's angle from the sun is read to within
    /// 10⁻⁷ rad, where `1 − cos r` in f32 is only good to 0.3 %).
    #[test]
    fn sun_disc_carries_the_beam_over_its_true_cone() {
        let r = f64::from(SUN_RADIUS_RAD);
        let omega = std::f64::consts::TAU * 2.0 * (0.5 * r).sin().powi(2);
        for (az, el) in [(0.93f64, 70f64), (0.2, 30.0), (2.5, 10.0), (4.0, 45.0), (5.5, 85.0)] {
            let el = el.to_radians();
            let s = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
            let sky = Sky::new(Vec3::new(s[0] as f32, s[1] as f32, s[2] as f32), 3.0, 0.0);
            let e = f64::from(sky.sun_irradiance().y);
            let sun = [f64::from(sky.sun.x), f64::from(sky.sun.y), f64::from(sky.sun.z)];
            assert!((f64::from(sky.sun_disc(sky.sun).y) * omega / e - 1.0).abs() < 1e-5, "el {el}: radiance");
            // Gnomonic grid of half-width 1.3 r on the plane tangent to the sun's direction.
            let u = {
                let c = [sun[1], -sun[0], 0.0];
                let n = (c[0] * c[0] + c[1] * c[1]).sqrt();
                [c[0] / n, c[1] / n, 0.0]
            };
            let w = [sun[1] * u[2] - sun[2] * u[1], sun[2] * u[0] - sun[0] * u[2], sun[0] * u[1] - sun[1] * u[0]];
            let (n, half) = (800, 1.3 * r);
            let cell = 2.0 * half / n as f64;
            let (mut flux, mut cone) = (0.0f64, 0.0f64);
            for i in 0..n {
                let x = -half + (i as f64 + 0.5) * cell;
                for j in 0..n {
                    let y = -half + (j as f64 + 0.5) * cell;
                    let d = [sun[0] + x * u[0] + y * w[0], sun[1] + x * u[1] + y * w[1], sun[2] + x * u[2] + y * w[2]];
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let df = Vec3::new((d[0] / len) as f32, (d[1] / len) as f32, (d[2] / len) as f32);
                    let d_omega = cell * cell / (1.0 + x * x + y * y).powf(1.5);
                    flux += f64::from(sky.sun_disc(df).y) * d_omega;
                    if (x * x + y * y).sqrt().atan() <= r {
                        cone += d_omega;
                    }
                }
            }
            // The grid resolves the cone to 0.2 %; the disc must fill the grid's own cone to 0.1 % of it.
            assert!((cone / omega - 1.0).abs() < 2e-3, "the grid's cone: {cone} vs {omega}");
            assert!((flux / e - cone / omega).abs() < 1e-3, "el {el}, az {az}: ∫ disc {flux} vs {e}, cone {cone}");
        }
    }

    #[test]
    fn twilight_sky_keeps_the_horizontal_illuminance_and_takes_the_twilight_colours() {
        // The sun on the horizon: Preetham's sky, which the twilight sky continues.
        let dawn = Sky::new(Vec3::X, 3.0, 0.0);
        // (integrated uniformly in θ, unlike the model's own rings)
        let e_h = |s: &Sky| horizontal_illuminance_theta(s, 300, 128);
        let e_dawn = e_h(&dawn);
        for deg in [-0.5f32, -2.0, -4.0, -8.0] {
            let h = deg.to_radians();
            let sky = Sky::new(Vec3::new(h.cos(), 0.0, h.sin()), 3.0, 0.0);
            // The horizontal illuminance is that of Preetham's horizon-sun sky (with the sun where it is) dimmed
            // by exp(h / 0.9°), which the twilight sky replaces; that one is within 6 % of the horizon sun's (its
            // circumsolar brightening follows the sun down).
            let mut preetham = sky.clone();
            preetham.twilight = None;
            let (got, want) = (e_h(&sky), e_h(&preetham));
            assert!((got - want).abs() / want < 0.01, "{deg}°: {got} vs {want}");
            let dimmed = e_dawn * f64::from((deg / 0.9).exp());
            assert!((want - dimmed).abs() / dimmed < 0.06, "{deg}°: {want} vs {dimmed}");
            if deg <= -2.0 {
                // Blue overhead, the sunward sky at 10° bluer than the horizon sun's at the same place (Preetham's
                // stays yellow there), and the band over the sunward horizon redder than the zenith.
                let z = sky.radiance(Vec3::Z);
                assert!(z.z > 1.3 * z.x, "{deg}°: zenith {z}");
                let up10 = Vec3::new(1.0, 0.0, 0.176).normalize();
                let (a, b) = (sky.radiance(up10), dawn.radiance(up10));
                assert!(a.z / a.x > 1.3 * (b.z / b.x), "{deg}°: {a} vs {b}");
                let band = sky.radiance(Vec3::new(1.0, 0.0, 0.035).normalize());
                assert!(band.x > 1.3 * band.y && band.y > 2.0 * band.z, "{deg}°: band {band}");
                assert!(luminance(band) > luminance(z), "{deg}°: the afterglow outshines the zenith");
            }
        }
        // Just below the horizon the sky is still the horizon sun's.
        let h = -0.01f32.to_radians();
        let just = Sky::new(Vec3::new(h.cos(), 0.0, h.sin()), 3.0, 0.0);
        let fall = (-0.01f32 / 0.9).exp();
        for d in [Vec3::Z, Vec3::new(1.0, 0.0, 0.2), Vec3::new(-0.5, 0.7, 0.3), Vec3::new(0.9, 0.1, 0.05)] {
            let d = d.normalize();
            let (a, b) =
                (just.radiance(d) - Vec3::splat(NIGHT_FLOOR), (dawn.radiance(d) - Vec3::splat(NIGHT_FLOOR)) * fall);
            assert!((a - b).length() < 0.02 * b.length(), "{d}: {a} vs {b}");
        }
    }
}
