//! The glitter of the navigation lamps on the rough sea: each lamp's light reflected by the water towards the
//! camera, estimated by next-event estimation (a light sampled explicitly at every shaded point) instead of by the
//! traced reflection rays that find a lamp only by chance.
//!
//! **Why.** A lamp is a small lens of a few thousand cd/m² (a masthead light of 94 cd, COLREG Annex I §8, over a
//! 0.04 m² lens: `materials.py` `COLREG_INTENSITY_CD`), the water's reflection lobe at W1 spans a tenth of a
//! steradian. The glossy reflections (`sensors/camera/glossy.rs`) draw a
//! direction per traced ray from that lobe and spread what it brings back over the lobe's footprint in the image:
//! a lamp drawn by one ray in a hundred thousand became a saturated hard-edged rectangle of water, and a lamp no
//! ray drew left none (the 640 × 480 view of a ferry 130 m off at midnight: 4,571 saturated water pixels at `high`
//! quality, none at `standard`). The expected value of both is the lamp's glitter path, which this gives each
//! water pixel directly, with no noise.
//!
//! **Model.** E. Veach, "Robust Monte Carlo Methods for Light Transport Simulation", PhD thesis, Stanford, 1997,
//! §9 (direct lighting by sampling the light source): the reflected radiance is `Σ_lamps V · E_l · f_s · cos`,
//! with
//! * `E_l = I(−l) e^{−σ r} / r²`: the lamp's intensity towards the water point (`scene/lamps.rs`: radiance
//!   times projected lens area, inside its COLREG arc) at distance `r`, through the fog's extinction `σ`;
//! * `f_s · cos` the water's microfacet reflection, the sun's glint's own (`rough_water.rs`: Beckmann slopes of
//!   Cox & Munk with the waves too short for the sampled surface, Smith masking, the exact Fresnel reflectance at
//!   the half vector, and the share of light scattered more than once, `sea_ms.rs`);
//! * the lamp's size folded into the lobe as a roughness (the "representative" widening of B. Karis, "Real
//!   Shading in Unreal Engine 4", SIGGRAPH 2013 course notes, for sphere lights): a lens of angular radius `ρ`
//!   tilts the half vector by up to `ρ/2`, so the lobe's mean square slope gains `ρ²/8`. On mirror-calm water the
//!   glitter is then the lamp's reflected image at its own size, not a point;
//! * `V` a shadow ray from the water point to the lamp (hulls, the lamp's own vessel, and wave crests occlude).
//!
//! The traced reflections then leave the lamps out (they would count them twice). Only while the sun stands less
//! than [`LAMP_GLITTER_SUN_DEG`] high: above, the sky's reflection outshines a lamp's glitter (a 94 cd lamp 10 m off
//! gives a glitter of about 2 cd/m² at its brightest at W1, the daylight sky's reflection there some hundreds), the
//! traced reflections keep the lamps, and every daylight image is as before.

use super::rough_water;
use super::tables::water_fresnel;
use super::{Shader, SurfaceHit};
use crate::scene::{Lamp, Scene};
use parry3d::math::Vec3;
use std::sync::Arc;

/// A lamp counts at a water point where the half vector between the view and the lamp leans from the shading
/// normal by `tan²θ_h ≤ GLITTER_TAN2 · α²`: beyond, the Beckmann distribution is below `e^{−9}` (1.2·10⁻⁴) of its
/// peak.
pub const GLITTER_TAN2: f32 = 9.0;

/// The sun's elevation (degrees) from which the lamps' glitter is left to the traced reflections
/// ([`Shader::lamps_by_glitter`]).
pub const LAMP_GLITTER_SUN_DEG: f32 = 10.0;

/// Lamps tested together by [`LampSet::near_lobe`].
const LANES: usize = 8;

/// The lit lamps of a render, their centres laid out for the per-point test.
#[derive(Debug, Clone, Default)]
pub struct LampSet {
    lamps: Vec<Lamp>,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    /// `ρ²·r²/8` of each lamp: its radius squared over 8 (the lobe's widening times the squared distance).
    widen: Vec<f32>,
}

impl LampSet {
    /// The set of `lamps`.
    pub fn new(lamps: Vec<Lamp>) -> Self {
        // Laid out in whole lanes of LANES (the padding's NaN centres pass no test).
        let pad = |v: Vec<f32>| {
            let mut v = v;
            v.resize(lamps.len().next_multiple_of(LANES), f32::NAN);
            v
        };
        Self {
            x: pad(lamps.iter().map(|l| l.centre.x).collect()),
            y: pad(lamps.iter().map(|l| l.centre.y).collect()),
            z: pad(lamps.iter().map(|l| l.centre.z).collect()),
            widen: pad(lamps.iter().map(|l| l.radius * l.radius / 8.0).collect()),
            lamps,
        }
    }

    /// Whether there are no lamps.
    pub fn is_empty(&self) -> bool {
        self.lamps.is_empty()
    }

    /// The lamps.
    pub fn lamps(&self) -> &[Lamp] {
        &self.lamps
    }

    /// Appends to `out` the lamps (indices) whose glitter may reach the camera from water point `p` with shading
    /// normal `n`, seen from `v` (towards the camera), with mean square slope `mss` ([`GLITTER_TAN2`]).
    #[inline]
    pub fn near_lobe(&self, p: Vec3, n: Vec3, v: Vec3, mss: f32, out: &mut Vec<u32>) {
        let lanes = self.x.chunks_exact(LANES).zip(self.y.chunks_exact(LANES));
        let lanes = lanes.zip(self.z.chunks_exact(LANES).zip(self.widen.chunks_exact(LANES)));
        for (c, ((xs, ys), (zs, ws))) in lanes.enumerate() {
            // One lane of lamps at a time, without branches (the compiler's vector lanes), then the ones that pass.
            let mut pass = [false; LANES];
            for i in 0..LANES {
                let (lx, ly, lz) = (xs[i] - p.x, ys[i] - p.y, zs[i] - p.z);
                let r2 = lx * lx + ly * ly + lz * lz;
                let inv = 1.0 / r2.sqrt();
                let (hx, hy, hz) = (v.x + lx * inv, v.y + ly * inv, v.z + lz * inv);
                let nh = n.x * hx + n.y * hy + n.z * hz;
                let hh = hx * hx + hy * hy + hz * hz;
                // tan²θ_h = (h·h − (n·h)²) / (n·h)², against GLITTER_TAN2 · (mss + ρ²/8).
                let a2 = mss + ws[i] / r2;
                pass[i] = nh > 0.0 && hh - nh * nh <= GLITTER_TAN2 * a2 * nh * nh;
            }
            for (i, &ok) in pass.iter().enumerate() {
                if ok {
                    out.push((c * LANES + i) as u32);
                }
            }
        }
    }
}

impl Shader {
    /// Whether the camera estimates the lamps' glitter ([`Shader::lamp_glitter`]) and leaves them out of its
    /// traced reflections: while the sun stands lower than [`LAMP_GLITTER_SUN_DEG`] (or is not lit at all).
    #[inline]
    pub fn lamps_by_glitter(&self) -> bool {
        !self.sun_up() || self.sun.z < LAMP_GLITTER_SUN_DEG.to_radians().sin()
    }

    /// This shader with the lit lamps of `scene` ([`Scene::nav_lamps`], gathered once per render) when it samples
    /// them ([`Shader::lamps_by_glitter`]); none otherwise.
    pub fn with_lamps(mut self, scene: &Scene) -> Self {
        if self.lamps_by_glitter() {
            self.lamps = Arc::new(LampSet::new(scene.nav_lamps()));
        }
        self
    }

    /// The lamps the camera samples ([`Shader::with_lamps`]; empty by day).
    #[inline]
    pub fn lamps(&self) -> &LampSet {
        &self.lamps
    }

    /// The glitter of `lamp` at water hit `hit` seen along `d`, before the lamp's visibility and the camera's
    /// aerial perspective: the radiance (linear RGB, cd/m²), the unit direction from the water to the lamp and its
    /// distance (m); `None` where it is nothing (outside the lobe or the lamp's arc).
    #[inline]
    pub fn lamp_glitter(&self, d: Vec3, hit: &SurfaceHit, lamp: &Lamp) -> Option<(Vec3, Vec3, f32)> {
        let n = hit.shading_normal;
        let v = -d;
        let to = lamp.centre - hit.point;
        let r = to.length();
        if r.is_nan() || r <= 0.0 {
            return None;
        }
        let l = to / r;
        let rho = lamp.radius / r;
        let alpha = (self.water_mss(hit.unresolved_mss) + rho * rho / 8.0).sqrt();
        let spec = rough_water::specular_cos(n, v, l, alpha);
        if spec <= 0.0 {
            return None;
        }
        let i = lamp.intensity(-l);
        if i == Vec3::ZERO {
            return None;
        }
        let e = i * ((-self.env.fog_extinction_per_m * r).exp() / (r * r));
        let h = (v + l).normalize_or_zero();
        let cos_o = n.dot(v).clamp(1e-4, 1.0);
        let (_, ms_gain) = self.water_reflectance(cos_o, self.water_mss(hit.unresolved_mss).sqrt());
        Some((e * (spec * water_fresnel(v.dot(h)) * ms_gain), l, r))
    }

    /// `c` (radiance leaving a point `t` metres along a camera ray) as it arrives through the fog: the part of
    /// [`Shader::fog`] that scales with it.
    #[inline]
    pub fn transmitted(&self, c: Vec3, t: f32) -> Vec3 {
        c * (-self.env.fog_extinction_per_m * t).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RigidPose;
    use crate::material::Material;
    use crate::sensors::shade::ShadeEnv;

    /// A lamp at `centre` whose lens shows `area` m² along ±x (two opposite faces), radius 5 cm.
    fn lamp(centre: Vec3, area: f32, arc: [f32; 2]) -> Lamp {
        let material = Material::test_lamp([2e4; 3], arc);
        Lamp::new(centre, 0.05, &[Vec3::X * area, -Vec3::X * area], material, RigidPose::IDENTITY, 0)
    }

    fn water_hit(point: Vec3) -> SurfaceHit {
        SurfaceHit {
            t: 10.0,
            point,
            normal: Vec3::Z,
            class: 1,
            instance: 0,
            material: 0,
            lights_on: false,
            shading_normal: Vec3::Z,
            unresolved_mss: 0.0,
            sky_visibility: [1.0; 2],
        }
    }

    /// The night shader of the default environment with wind `u` m/s and no multiple scattering, no fog.
    fn night(u: f32) -> Shader {
        let env = ShadeEnv {
            sun_direction: [0.0, 0.866, -0.5],
            wind_speed_m_s: u,
            water_multiple_scattering: false,
            fog_extinction_per_m: 0.0,
            ..ShadeEnv::default()
        };
        Shader::new(&env, 1, &[])
    }

    #[test]
    fn glitter_is_the_closed_form_point_light_reflection() {
        // A lamp 10 m up, 40 m along x from a camera 2 m up; a water point on the line between them. The glitter
        // written out by hand: E = I/r² with I = L·A, times Beckmann D·G/(4 n·v) times the Fresnel reflectance at
        // the half vector (Walter et al. 2007, eq. 20).
        let shader = night(5.0);
        assert!(shader.lamps_by_glitter());
        let cam = Vec3::new(0.0, 0.0, 2.0);
        let lp = lamp(Vec3::new(40.0, 0.0, 10.0), 0.01, [0.0, 180.0]);
        for x in [4.0f32, 6.0, 6.67, 8.0, 12.0] {
            let p = Vec3::new(x, 0.3, 0.0);
            let d = (p - cam).normalize();
            let Some((value, l, r)) = shader.lamp_glitter(d, &water_hit(p), &lp) else {
                panic!("no glitter at x = {x}");
            };
            let to = lp.centre - p;
            assert!((r - to.length()).abs() < 1e-4 && (l - to / to.length()).length() < 1e-6);
            // By hand (f64).
            let f = |a: Vec3| [f64::from(a.x), f64::from(a.y), f64::from(a.z)];
            let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let (v, l) = (f(-d), f(l));
            let hs = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
            let hn = dot(hs, hs).sqrt();
            let h = hs.map(|c| c / hn);
            let a2 = f64::from(shader.water_mss(0.0)) + (0.05 / f64::from(r)).powi(2) / 8.0;
            let cos_h = h[2];
            let tan2 = (1.0 - cos_h * cos_h) / (cos_h * cos_h);
            let dd = (-tan2 / a2).exp() / (std::f64::consts::PI * a2 * cos_h.powi(4));
            let g = rough_water::smith_g1(l[2], a2.sqrt()) * rough_water::smith_g1(v[2], a2.sqrt());
            // The exact Fresnel reflectance of water (unpolarised, IOR 1.33) at the half vector.
            let c = dot(v, h);
            let gg = (1.33f64 * 1.33 - 1.0 + c * c).sqrt();
            let fres =
                0.5 * ((gg - c) / (gg + c)).powi(2) * (1.0 + ((c * (gg + c) - 1.0) / (c * (gg - c) + 1.0)).powi(2));
            // The lens seen from the water point: projected area 0.01 · |l_x|.
            let e = 2e4 * 0.01 * l[0].abs() / f64::from(r * r);
            let want = e * dd * g / (4.0 * v[2]) * fres;
            let got = f64::from(value.x);
            assert!((got - want).abs() <= 2e-3 * want + 1e-9, "x = {x}: {got} vs {want}");
        }
    }

    #[test]
    fn glitter_lies_only_near_the_mirror_point_and_inside_the_arc() {
        let shader = night(3.0);
        let cam = Vec3::new(0.0, 0.0, 2.0);
        // The mirror point of a lamp 10 m up, 40 m off, for a camera 2 m up: 40·2/12 = 6.67 m out.
        let lp = lamp(Vec3::new(40.0, 0.0, 10.0), 0.01, [0.0, 180.0]);
        let at = |x: f32, y: f32| {
            let p = Vec3::new(x, y, 0.0);
            let d = (p - cam).normalize();
            shader.lamp_glitter(d, &water_hit(p), &lp).map_or(0.0, |g| g.0.x)
        };
        let peak = at(6.67, 0.0);
        assert!(peak > 0.0);
        assert!(at(6.67, 3.0) < 1e-3 * peak, "far to the side of the glitter path");
        assert!(at(1.0, 0.0) < 1e-3 * peak, "right below the camera, far off the path's near end");
        // The near-lobe test keeps the point on the path and drops the one beside it.
        let set = LampSet::new(vec![lp.clone()]);
        let mut out = Vec::new();
        let p = Vec3::new(6.67, 0.0, 0.0);
        set.near_lobe(p, Vec3::Z, (cam - p).normalize(), shader.water_mss(0.0), &mut out);
        assert_eq!(out, [0]);
        out.clear();
        let p = Vec3::new(6.67, 3.0, 0.0);
        set.near_lobe(p, Vec3::Z, (cam - p).normalize(), shader.water_mss(0.0), &mut out);
        assert!(out.is_empty());
        // A lamp shining only ahead (+x, away from the camera): no glitter on this side.
        let ahead = lamp(Vec3::new(40.0, 0.0, 10.0), 0.01, [0.0, 20.0]);
        let p = Vec3::new(6.67, 0.0, 0.0);
        let d = (p - cam).normalize();
        assert!(shader.lamp_glitter(d, &water_hit(p), &ahead).is_none());
    }

    #[test]
    fn daylight_keeps_the_traced_reflections() {
        let at = |deg: f32| {
            let (s, c) = deg.to_radians().sin_cos();
            Shader::new(&ShadeEnv { sun_direction: [0.0, c, s], ..ShadeEnv::default() }, 1, &[]).lamps_by_glitter()
        };
        assert!(!at(20.0) && !at(10.5));
        assert!(at(9.5) && at(1.0) && at(-5.0));
    }
}
