//! The glow of the navigation lamps in the air around them: the lamp light the air (its aerosol, mist, fog)
//! scatters once towards the camera along each pixel's ray.
//!
//! **Why.** At night a lamp seen through haze or fog is a bright point inside a halo that widens as the visibility
//! falls: the air between the camera and the lamp scatters part of the lamp's light towards the camera. Before, a
//! lamp was its lens and its light on surfaces; the air around it stayed as dark as the night sky, in fog too.
//!
//! **Model.** Single scattering of a point source in a homogeneous medium, the airlight integral of B. Sun,
//! R. Ramamoorthi, S. G. Narasimhan and S. K. Nayar, "A practical analytic single scattering model for real time
//! rendering", ACM SIGGRAPH 2005 (its airlight of a point source), here with a Henyey–Greenstein phase function
//! (L. G. Henyey and J. L. Greenstein, "Diffuse radiation in the Galaxy", Astrophys. J. 93, 1941) in place of their
//! isotropic one.
//! A ray from `o` along unit `d` passes the lamp at `c` at distance `h` when it is `t₀ = (c − o)·d` along; a point
//! of the ray seen from the lamp at scattering angle `θ` (between the light's way on, lamp to point, and the way
//! back to the camera, `−d`) is `s = t₀ − h cot θ` along it, `r = h / sin θ` from the lamp, and `ds / r² = dθ / h`,
//! so that the radiance the ray gathers up to `t` metres is
//!
//! `L = σ_s / h · ∫_{θ₀}^{θ₁} I(w(θ)) p(cos θ) e^{−σ (t₀ + h tan(θ/2))} dθ`,
//!
//! `θ₀ = atan2(h, t₀)` at the camera, `θ₁ = atan2(h, t₀ − t)` at the ray's end (`π` for a ray that meets
//! nothing), `w(θ) = −(cos θ d + sin θ n)` the direction from the lamp to the point (`n` the unit vector from the
//! ray's closest point to the lamp), `I(w)` the lamp's intensity that way (`scene/lamps.rs`: inside its COLREG arc
//! only), `s + r = t₀ + h tan(θ/2)` the path through the air, `σ` the air's extinction (the scenario's
//! visibility) and `σ_s = σ`: fog droplets and sea-salt aerosol absorb next to nothing at visible wavelengths. The
//! phase function is Henyey–Greenstein's with asymmetry [`HALO_G`] = 0.8, between maritime aerosol's (about 0.75
//! at 550 nm) and fog droplets' (about 0.85). The lens radius `ρ` bounds `h` as it bounds the lamp's light
//! (`h² + ρ²`). The integral is 4-point Gauss–Legendre's on pieces over which the integrand is smooth: split where
//! the forward peak of the phase function has fallen, where the arc's sides cut the ray (the integrand jumps there),
//! where the ray passes the lamp and where the air beyond has dimmed the light by `e`; within 0.6 % of a dense sum
//! along the ray in the tests.
//!
//! A lamp counts for a ray where the most it could give, `σ e^{−σ D} I_max J(θ₀) / h` (`D` the lamp's distance
//! from the ray's origin, which bounds `s + r`; `J(θ₀) = ∫_{θ₀}^π p(cos θ) dθ`, the phase function falling with
//! `θ`), reaches [`LAMP_HALO_LEAST`] of the camera's tone-curve input, windowed as the lamps' light is (Karis
//! 2013: `(1 − u⁴)²`, `u` the least over that most). Only while the lamps shine (the sun below
//! `lamp_glitter::LAMP_GLITTER_SUN_DEG`). Left out: the shadows in the glow (the light between the lamp and a point
//! of the ray is not tested for occluders: a lamp's own screens and hulls cast no shafts), the glow in the water's
//! reflections, and light scattered more than once (in thick fog the halo would be wider).

use super::lamp_light::LAMP_LIGHT_LEAST;
use super::Shader;
use crate::scene::Lamp;
use parry3d::math::Vec3;
use std::f32::consts::PI;
use std::sync::OnceLock;

/// Henyey–Greenstein asymmetry of the air's scattering (module docstring).
pub const HALO_G: f32 = 0.8;

/// Gauss–Legendre nodes and weights on `[−1, 1]`, 4 points (Abramowitz & Stegun, Table 25.4).
const GL4: [(f32, f32); 2] = [(0.339_981_04, 0.652_145_15), (0.861_136_3, 0.347_854_85)];

/// Henyey–Greenstein's phase function (1/sr) of asymmetry `g` at `cos θ`.
#[inline]
pub fn henyey_greenstein(g: f32, cos_theta: f32) -> f32 {
    let den = (1.0 + g * g - 2.0 * g * cos_theta).max(1e-12);
    (1.0 - g * g) / (4.0 * PI * den * den.sqrt())
}

/// Bins of [`halo_phase_tail`]'s table over `[0, π]`.
const TAIL_BINS: usize = 256;

/// `J(θ₀) = ∫_{θ₀}^π p(cos θ) dθ` of [`HALO_G`]'s phase function, at least (the table's straight lines between its
/// nodes, dense midpoint sums made once: `J` is convex, so they lie above it).
pub fn halo_phase_tail(theta0: f32) -> f32 {
    static TAIL: OnceLock<Vec<f32>> = OnceLock::new();
    let tail = TAIL.get_or_init(|| {
        let per = 200;
        let step = std::f64::consts::PI / (TAIL_BINS * per) as f64;
        let mut out = vec![0.0f32; TAIL_BINS + 1];
        let mut acc = 0.0f64;
        for i in (0..TAIL_BINS * per).rev() {
            acc += f64::from(henyey_greenstein(HALO_G, ((i as f64 + 0.5) * step).cos() as f32)) * step;
            if i % per == 0 {
                out[i / per] = acc as f32;
            }
        }
        out
    });
    let x = (theta0.max(0.0) / PI * TAIL_BINS as f32).min(TAIL_BINS as f32);
    let i = (x as usize).min(TAIL_BINS - 1);
    let f = x - i as f32;
    tail[i] * (1.0 - f) + tail[i + 1] * f
}

/// The least tone-curve input (radiance times the camera's exposure) the most a lamp's glow could give a ray must
/// reach for the glow to be worked out there: about the darkest 8-bit step (a third of it is the lamps' light's
/// [`super::lamp_light::LAMP_LIGHT_LEAST`]; the glow is spread over whole views, and it is windowed to zero below).
pub const LAMP_HALO_LEAST: f32 = 3.0 * LAMP_LIGHT_LEAST;

/// Gauss–Legendre (4 points) of `f` over `[a, b]`.
#[inline]
fn gauss4(a: f32, b: f32, f: impl Fn(f32) -> Vec3) -> Vec3 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut sum = Vec3::ZERO;
    for &(x, w) in &GL4 {
        let dx = half * x;
        sum += (f(mid - dx) + f(mid + dx)) * w;
    }
    sum * half
}

/// The scattering angles `θ` in `(0, π)` at which the direction from `lamp` to the ray's point,
/// `w(θ) = −(cos θ d + sin θ n)`, crosses a side of the lamp's arc (its level bearing, body frame, is the centre's
/// ± the half-width); none all round. The glow's integrand jumps there: the quadrature splits on them.
#[inline]
fn arc_crossings(lamp: &Lamp, d: Vec3, n: Vec3) -> [f32; 2] {
    let Some(arc) = lamp.arc() else { return [f32::NAN; 2] };
    let (c, s, cos_half) = (arc.cos_centre, arc.sin_centre, arc.cos_half);
    let (db, nb) = (lamp.to_body(d), lamp.to_body(n));
    let sin_half = (1.0 - cos_half * cos_half).max(0.0).sqrt();
    // The sides' bearings: centre ∓ half-width, as (cos, sin).
    let sides = [
        (c * cos_half + s * sin_half, s * cos_half - c * sin_half),
        (c * cos_half - s * sin_half, s * cos_half + c * sin_half),
    ];
    sides.map(|(cb, sb)| {
        // w's level part is parallel to the side where cos θ (D × e) + sin θ (N × e) = 0.
        let (a, b) = (db.x * sb - db.y * cb, nb.x * sb - nb.y * cb);
        let theta = (-a).atan2(b);
        if theta <= 0.0 {
            theta + PI
        } else {
            theta
        }
    })
}

/// How a ray passes a lamp: the lamp from the ray's origin (`to`, world frame, m), its distance along the ray
/// (`t0`), the ray's nearest approach to it across the ray (`across`, its length squared `h2`), and that distance
/// widened by the lens radius (`h = √(h2 + ρ²)`, m).
#[derive(Debug, Clone, Copy)]
struct Passing {
    to: Vec3,
    t0: f32,
    across: Vec3,
    h2: f32,
    h: f32,
}

impl Passing {
    #[inline]
    fn new(o: Vec3, d: Vec3, lamp: &Lamp) -> Self {
        let to = lamp.centre - o;
        let t0 = to.dot(d);
        let across = to - d * t0;
        let h2 = across.length_squared();
        Self { to, t0, across, h2, h: (h2 + lamp.radius * lamp.radius).sqrt() }
    }

    /// The scattering angle at the ray's origin, `atan2(h, t0)`.
    #[inline]
    fn theta0(&self) -> f32 {
        self.h.atan2(self.t0)
    }
}

impl Shader {
    /// The farthest (m) a ray may pass `lamp` and still be reached by its glow (the most it could be with
    /// `J(0)` and no extinction on the way, [`Shader::lamp_halo`]); 0 without air to scatter.
    #[inline]
    pub fn halo_reach(&self, lamp: &Lamp) -> f32 {
        self.halo_air()
            .map_or(0.0, |(sigma, k)| k * sigma * lamp.max_intensity() * halo_phase_tail(0.0) / LAMP_HALO_LEAST)
    }

    /// The air's extinction (1/m) and the exposure, when there is air to scatter the lamps' light; `None` without.
    #[inline]
    pub fn halo_air(&self) -> Option<(f32, f32)> {
        let sigma = self.env.fog_extinction_per_m;
        (sigma > 0.0 && sigma.is_finite()).then(|| (sigma, self.exposure()))
    }

    /// The glow of `lamp` (linear RGB, cd/m²) that the ray from `o` along unit `d` gathers over its first `t`
    /// metres (`f32::INFINITY`: a ray that meets nothing), through the air's extinction on the way: nothing where
    /// the most it could be, `σ e^{−σ D} I_max J(θ₀) / h` (`D` the lamp's distance, which bounds the light's path
    /// `s + r`; `J` [`halo_phase_tail`], `p` falling with `θ`), times the exposure is under [`LAMP_HALO_LEAST`];
    /// else [`Shader::halo_integral`] windowed to zero towards that least (`(1 − u⁴)²`, `u` their ratio).
    #[inline]
    pub fn lamp_halo(&self, o: Vec3, d: Vec3, t: f32, lamp: &Lamp) -> Vec3 {
        let Some((sigma, k)) = self.halo_air() else { return Vec3::ZERO };
        let ray = Passing::new(o, d, lamp);
        let most =
            k * sigma * (-sigma * ray.to.length()).exp() * lamp.max_intensity() * halo_phase_tail(ray.theta0()) / ray.h;
        let u = LAMP_HALO_LEAST / most;
        if u.is_nan() || u >= 1.0 {
            return Vec3::ZERO;
        }
        self.passing_integral(d, t, lamp, &ray) * ((1.0 - u * u * u * u) * (1.0 - u * u * u * u))
    }

    /// The airlight integral of the module docstring for `lamp` and the ray from `o` along unit `d` up to `t`
    /// metres (linear RGB, cd/m²), in pieces of 4-point Gauss–Legendre.
    #[inline]
    pub fn halo_integral(&self, o: Vec3, d: Vec3, t: f32, lamp: &Lamp) -> Vec3 {
        self.passing_integral(d, t, lamp, &Passing::new(o, d, lamp))
    }

    /// [`Shader::halo_integral`] of the ray along unit `d` passing `lamp` as `ray` says.
    #[inline]
    fn passing_integral(&self, d: Vec3, t: f32, lamp: &Lamp, ray: &Passing) -> Vec3 {
        let Some((sigma, _)) = self.halo_air() else { return Vec3::ZERO };
        if t.is_nan() || t <= 0.0 {
            return Vec3::ZERO;
        }
        let Passing { t0, across, h2, h, .. } = *ray;
        let theta0 = ray.theta0();
        let n = if h2 > 0.0 { across / h2.sqrt() } else { d.any_orthonormal_vector() };
        let theta1 = if t.is_finite() { h.atan2(t0 - t) } else { PI };
        if theta1.is_nan() || theta0.is_nan() || theta1 <= theta0 {
            return Vec3::ZERO;
        }
        let f = |theta: f32| {
            let (sin, cos) = theta.sin_cos();
            let w = -(d * cos + n * sin);
            let path = t0 + h * (0.5 * theta).tan();
            lamp.intensity(w) * (henyey_greenstein(HALO_G, cos) * (-sigma * path).exp())
        };
        // Split where the forward peak has fallen (about (1 − g) wide), where the arc's sides cut the ray, where it
        // passes the lamp (θ = π/2: the lens faces that face along the ray turn there) and where the air beyond has
        // dimmed the light by e (σ h tan(θ/2) = 1), so that each piece is smooth; a piece outside the arc is skipped.
        let peak = (theta0 + 2.0 * (1.0 - HALO_G)).min(0.5 * (theta0 + theta1));
        let mut cuts = [theta0, peak, theta1, theta1, theta1, theta1, theta1];
        let [c0, c1] = arc_crossings(lamp, d, n);
        let dimmed = 2.0 * (1.0 / (sigma * h)).atan();
        for (slot, c) in cuts[2..6].iter_mut().zip([c0, c1, 0.5 * PI, dimmed]) {
            if c > theta0 && c < theta1 {
                *slot = c;
            }
        }
        cuts.sort_unstable_by(f32::total_cmp);
        let mut sum = Vec3::ZERO;
        for pair in cuts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            if b > a && (lamp.arc().is_none() || f(0.5 * (a + b)) != Vec3::ZERO) {
                sum += gauss4(a, b, f);
            }
        }
        sum * (sigma / h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RigidPose;
    use crate::material::Material;
    use crate::sensors::shade::ShadeEnv;

    /// An all-round lamp at `centre` whose lens shows 0.01 m² every horizontal way (two pairs of faces), radiance
    /// 1e4 cd/m² in every channel: 100 cd; radius 1 mm.
    fn lamp(centre: Vec3, arc: [f32; 2]) -> Lamp {
        let material = Material::test_lamp([1e4; 3], arc);
        let faces = [Vec3::X * 0.01, -Vec3::X * 0.01, Vec3::Z * 0.01, -Vec3::Z * 0.01];
        Lamp::new(centre, 0.001, &faces, material, RigidPose::IDENTITY, 0)
    }

    fn night(sigma: f32) -> Shader {
        let env = ShadeEnv { sun_direction: [0.0, 0.866, -0.5], fog_extinction_per_m: sigma, ..ShadeEnv::default() };
        Shader::new(&env, 0, &[])
    }

    /// The airlight integral summed densely along the ray itself (midpoints in `s`, f64), with the lamp's
    /// intensity worked out from its faces here: `Σ σ I(w) p e^{−σ(s + r)} / (r² + ρ²) Δs`.
    fn dense(sigma: f64, o: [f64; 3], d: [f64; 3], t: f64, l: &Lamp) -> [f64; 3] {
        let c = [f64::from(l.centre.x), f64::from(l.centre.y), f64::from(l.centre.z)];
        let g = f64::from(HALO_G);
        let n = 400_000;
        let ds = t / f64::from(n);
        let mut sum = [0.0f64; 3];
        for i in 0..n {
            let s = (f64::from(i) + 0.5) * ds;
            let x = [o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]];
            let v = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
            let r2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            let r = r2.sqrt();
            let w = [v[0] / r, v[1] / r, v[2] / r];
            // intensity: radiance times half the sum of |area · w| over the faces, inside the arc (all round here
            // or a half-width checked by the caller's choice of geometry)
            let area: f64 = 0.5
                * l.faces()
                    .iter()
                    .map(|a| (f64::from(a.x) * w[0] + f64::from(a.y) * w[1] + f64::from(a.z) * w[2]).abs())
                    .sum::<f64>();
            // the arc (identity pose): the level bearing within the half-width of the centre
            let [centre, half] = l.material.arc_deg.map(|x| f64::from(x).to_radians());
            let off = (w[1].atan2(w[0]) - centre + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            let area = if off.abs() <= half { area } else { 0.0 };
            let mu = -(w[0] * d[0] + w[1] * d[1] + w[2] * d[2]);
            let p = (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * mu).powf(1.5));
            let rho2 = f64::from(l.radius) * f64::from(l.radius);
            let k = sigma * area * p * (-sigma * (s + r)).exp() / (r2 + rho2) * ds;
            for (j, e) in l.material.emissive.iter().enumerate() {
                sum[j] += k * f64::from(*e);
            }
        }
        sum
    }

    #[test]
    fn the_quadrature_is_the_dense_sum_along_the_ray() {
        // Rays passing a lamp 40 m ahead at 0.05-30 m, ending before it, beside it and far beyond it, in clear air
        // and in fog: within 1 % of the dense sum (8 nodes; the worst, 0.6 %, where the ray passes the lamp: this
        // lamp's intensity, 0.01 (|w_x| + |w_z|), has a kink there that the nodes do not see; 16 nodes gave 0.07 %).
        let l = lamp(Vec3::new(40.0, 0.0, 5.0), [0.0, 180.0]);
        for sigma in [1.5e-4f32, 3e-3, 0.03] {
            let s = night(sigma);
            for h in [0.05f32, 0.5, 3.0, 30.0] {
                for t in [20.0f32, 40.0, 80.0, 400.0] {
                    let o = Vec3::new(0.0, 0.0, 5.0 - h);
                    let d = Vec3::X;
                    let got = s.halo_integral(o, d, t, &l);
                    let want =
                        dense(f64::from(sigma), [0.0, 0.0, f64::from(5.0 - h)], [1.0, 0.0, 0.0], f64::from(t), &l);
                    let err = (f64::from(got.x) - want[0]).abs() / want[0];
                    assert!(err < 0.01, "sigma {sigma} h {h} t {t}: {} against {} ({err})", got.x, want[0]);
                }
            }
        }
    }

    #[test]
    fn a_sidelights_glow_is_the_dense_sum_inside_its_arc() {
        // A starboard sidelight (arc 56.25° either side of 90° to starboard) 40 m ahead: rays passing it on either
        // side at 0.5-20 m, in fog, within 1 % of the dense sum that applies the arc itself (without splitting
        // the quadrature where the arc's sides cut the ray, up to 100 % off; measured 0.5 % at most).
        let l = lamp(Vec3::new(40.0, 0.0, 5.0), [-90.0, 56.25]);
        let s = night(0.02);
        let mut lit = 0;
        for y in [-20.0f32, -3.0, -0.5, 0.5, 3.0, 20.0] {
            for t in [30.0f32, 60.0, 1000.0] {
                let dir = Vec3::new(40.0, y, 0.0).normalize();
                let got = s.halo_integral(Vec3::new(0.0, 0.0, 5.0), dir, t, &l);
                let d = [f64::from(dir.x), f64::from(dir.y), f64::from(dir.z)];
                let want = dense(0.02, [0.0, 0.0, 5.0], d, f64::from(t), &l)[0];
                let err = (f64::from(got.x) - want).abs();
                assert!(err <= 0.01 * want + 1e-12, "y {y} t {t}: {} against {want}", got.x);
                lit += usize::from(want > 0.0);
            }
        }
        assert!(lit >= 6, "{lit}");
    }
}
