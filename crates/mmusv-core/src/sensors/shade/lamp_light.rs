//! The navigation lamps' light on every surface but the water (hulls, superstructures, buoys, the shore): each lamp
//! sampled explicitly at the shaded point (next-event estimation), as its glitter on the water is
//! (`lamp_glitter.rs`).
//!
//! **Why.** A moonless clear night lights the scene with 0.002 lux (`sky.rs`), while a masthead light of 94 cd
//! (COLREG Annex I §8) gives 0.94 lux 10 m off and still 0.002 lux 200 m off. A ship's foredeck under its own
//! masthead light, a hull passing another's sidelight, a buoy beside a moored ship are lit by the lamps, not by the
//! sky. Before, the lamps themselves and their glitter showed, but every hull stayed as dark as the sky left it.
//!
//! **Model.** Direct lighting by sampling the light source (E. Veach, "Robust Monte Carlo Methods for Light
//! Transport Simulation", PhD thesis, Stanford, 1997, §9), with the photometric inverse-square and cosine laws
//! (CIE S 017:2020, 17-21-050 "illuminance"): `L = Σ_lamps V (f_d + f_s(v, l)) (n·l) E_l`, with
//! * `E_l = I(−l) e^{−σ r} / (r² + ρ²)`: the lamp's intensity towards the point (`scene/lamps.rs`: radiance times
//!   projected lens area, inside its COLREG arc and nothing outside it), through the fog's extinction `σ`, over
//!   the distance squared. The lens radius `ρ` bounds it at the lantern: a Lambertian disc of radiance `L_e` and
//!   radius `ρ` gives `E = π L_e ρ² / (r² + ρ²)` on its axis, exactly, and `I = π ρ² L_e` is its intensity there;
//! * `f_d + f_s` the surface's BRDF as the sun sees it ([`super::Lobes`], `brdf.rs`: Lambert under GGX/Smith with
//!   Schlick's Fresnel);
//! * `V` a shadow ray from the point to the lamp, stopped short of its lantern (hulls, the lamp's own vessel and
//!   wave crests occlude).
//!
//! A lamp counts within its reach `R` of a point ([`Shader::lamp_reach2`]): where the most it can give a white
//! surface face on, `I_max / (π r²)` cd/m², still reaches [`LAMP_LIGHT_LEAST`] of the camera's tone-curve input
//! (its exposure before the highlight limit; a third of the darkest 8-bit step). So that no edge shows where a lamp
//! stops counting (in the linear radiance too), its light is windowed as Unreal Engine's point lights are
//! (B. Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course notes, eq. 9): times `(1 − (r/R)⁴)²`, which
//! leaves it whole near the lamp and takes it smoothly to zero at `R` (12 % less at `R/2`, where it is four times
//! that least step). The lenses of the lamps are not lit by lamps (their own radiance is thousands of times more).
//! Only while the lamps' glitter is (the sun lower than `lamp_glitter::LAMP_GLITTER_SUN_DEG`): by day a lamp adds
//! nothing a camera can see. The camera adds it to what its traced water reflections meet too, so a lamp-lit hull
//! mirrors lit (not at `draft` quality, which traces no reflections). The glow of a lamp in the air around it is
//! `lamp_halo.rs`'s.

use super::{Lobes, Shader, SurfaceHit};
use crate::scene::Lamp;
use parry3d::math::Vec3;

/// The least tone-curve input (the radiance times the camera's exposure) that a lamp's light on a white surface
/// face on must reach at a point to be sampled there ([`Shader::lamp_reach2`]).
pub const LAMP_LIGHT_LEAST: f32 = 1e-4;

impl Shader {
    /// The squared distance `R²` (m²) within which `lamp` can light a white surface face on to
    /// [`LAMP_LIGHT_LEAST`] of the tone curve's input or more: `k I_max / (π · least)`, `k` the exposure.
    #[inline]
    pub fn lamp_reach2(&self, lamp: &Lamp) -> f32 {
        self.exposure() * lamp.max_intensity() / (std::f32::consts::PI * LAMP_LIGHT_LEAST)
    }

    /// The light of `lamp` on the non-water hit `hit` seen along `d`, before the lamp's visibility and the
    /// camera's aerial perspective: the radiance (linear RGB, cd/m²), the unit direction from the point to the
    /// lamp and its distance (m); `None` where it is nothing (the lamp behind the surface, outside its arc or out
    /// of reach, the hit a lamp's lens itself).
    #[inline]
    pub fn lamp_light(&self, d: Vec3, hit: &SurfaceHit, lamp: &Lamp) -> Option<(Vec3, Vec3, f32)> {
        let m = self.material_of(hit);
        if m.nav_light {
            return None;
        }
        let n = hit.normal;
        let to = lamp.centre - hit.point;
        let r2 = to.length_squared();
        let r = r2.sqrt();
        if r.is_nan() || r <= 0.0 {
            return None;
        }
        let l = to / r;
        if n.dot(l) <= 0.0 {
            return None;
        }
        let i = lamp.intensity(-l);
        if i == Vec3::ZERO {
            return None;
        }
        let reach2 = self.lamp_reach2(lamp);
        let q = r2 / reach2;
        // (Out of reach, or a reach that is not a number: nothing.)
        if q.is_nan() || q >= 1.0 {
            return None;
        }
        let window = (1.0 - q * q) * (1.0 - q * q);
        let e = i * (window * (-self.env.fog_extinction_per_m * r).exp() / (r2 + lamp.radius * lamp.radius));
        let value = Lobes::of(&m).direct(n, -d, l, e);
        (value != Vec3::ZERO).then_some((value, l, r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RigidPose;
    use crate::material::Material;
    use crate::sensors::shade::ShadeEnv;
    use std::sync::Arc;

    /// A lamp at `centre` whose lens shows `area` m² along ±x (two opposite faces), radius `radius`.
    fn lamp(centre: Vec3, area: f32, radius: f32, arc: [f32; 2]) -> Lamp {
        let material = Material::test_lamp([2e4, 1e4, 5e3], arc);
        Lamp::new(centre, radius, &[Vec3::X * area, -Vec3::X * area], material, RigidPose::IDENTITY, 0)
    }

    /// A hit on a wall of material 1 at `point`, normal `normal`, 10 m from the camera.
    fn wall(point: Vec3, normal: Vec3) -> SurfaceHit {
        SurfaceHit {
            t: 10.0,
            point,
            normal,
            class: 3,
            instance: 1,
            material: 1,
            lights_on: false,
            shading_normal: normal,
            unresolved_mss: 0.0,
            sky_visibility: [1.0; 2],
        }
    }

    /// The night shader of the default environment, no fog, its material 1 `base` grey with roughness `rough`.
    fn night(base: f32, rough: f32, fog: f32) -> Shader {
        let env = ShadeEnv { sun_direction: [0.0, 0.866, -0.5], fog_extinction_per_m: fog, ..ShadeEnv::default() };
        let grey = Material {
            base_color: [base; 3],
            roughness: rough,
            metallic: 0.0,
            emissive: [0.0; 3],
            nav_light: false,
            arc_deg: [0.0, 180.0],
        };
        Shader::new(&env, 1, &[]).with_materials(Arc::new(vec![grey, grey]))
    }

    /// The GGX/Smith/Schlick specular term `f_s (n·l)` written out by hand (f64): Walter et al. 2007, eqs. 33 and
    /// 34, the separable Smith masking, Schlick's Fresnel with `F0 = 0.04`.
    fn ggx_by_hand(n: [f64; 3], v: [f64; 3], l: [f64; 3], alpha: f64) -> f64 {
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let hs = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
        let hn = dot(hs, hs).sqrt();
        let h = hs.map(|c| c / hn);
        let a2 = alpha * alpha;
        let nh = dot(n, h);
        let d = a2 / (std::f64::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
        let g1 = |c: f64| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
        let (nl, nv) = (dot(n, l), dot(n, v));
        let f = 0.04 + 0.96 * (1.0 - dot(v, h)).powi(5);
        d * g1(nl) * g1(nv) * f / (4.0 * nl * nv) * nl
    }

    #[test]
    fn a_wall_under_a_lamp_gets_the_inverse_square_and_cosine_laws() {
        // A rough grey wall (normal +x) lit by a lamp 3..40 m off along +x and above, seen from the side: the
        // diffuse part is ρ/π · I cos θ / (r² + ρ²) with I the lens's projected area times its radiance, the
        // specular part the GGX lobe by hand.
        let (base, rough) = (0.5f32, 0.9f32);
        let shader = night(base, rough, 0.0);
        assert!(shader.lamps_by_glitter());
        let lp = lamp(Vec3::new(0.0, 0.0, 6.0), 0.01, 0.05, [0.0, 180.0]);
        for (x, z) in [(3.0f32, 1.0f32), (8.0, 4.0), (40.0, 5.5), (12.0, 0.0)] {
            // The wall point x m aft of the lamp (the wall's normal towards it), z m up.
            let p = Vec3::new(-x, 0.0, z);
            let hit = wall(p, Vec3::X);
            let cam = Vec3::new(-x + 4.0, 6.0, 2.0);
            let d = (p - cam).normalize();
            let Some((value, l, r)) = shader.lamp_light(d, &hit, &lp) else { panic!("no light at {p}") };
            let to = lp.centre - p;
            assert!((r - to.length()).abs() < 1e-4 && (l - to / to.length()).length() < 1e-6);
            let f = |a: Vec3| [f64::from(a.x), f64::from(a.y), f64::from(a.z)];
            let (lf, vf) = (f(l), f(-d));
            let r2 = f64::from(to.length_squared());
            // The lens seen from the point: 0.01 m² times |l_x|; the red channel's radiance 2e4.
            let reach2 = f64::from(shader.exposure()) * 200.0 / (std::f64::consts::PI * 1e-4);
            let window = (1.0 - (r2 / reach2).powi(2)).powi(2);
            let e = 2e4 * 0.01 * lf[0].abs() / (r2 + 0.05f64.powi(2)) * window;
            let cos = lf[0];
            let alpha = f64::from(rough * rough);
            let want = e * (f64::from(base) / std::f64::consts::PI * cos + ggx_by_hand([1.0, 0.0, 0.0], vf, lf, alpha));
            let got = f64::from(value.x);
            assert!((got - want).abs() <= 1e-4 * want, "{p}: {got} vs {want}");
            // The other channels follow the lens's colour.
            assert!((value.y / value.x - 0.5).abs() < 1e-5 && (value.z / value.x - 0.25).abs() < 1e-5);
        }
    }

    #[test]
    fn fog_the_arc_and_the_back_of_the_wall_take_it_away() {
        let lp = lamp(Vec3::new(0.0, 0.0, 6.0), 0.01, 0.05, [0.0, 180.0]);
        let p = Vec3::new(-20.0, 0.0, 2.0);
        let d = (p - Vec3::new(-16.0, 6.0, 2.0)).normalize();
        let clear = night(0.5, 0.9, 0.0).lamp_light(d, &wall(p, Vec3::X), &lp).map(|v| v.0.x);
        let fog = night(0.5, 0.9, 0.01).lamp_light(d, &wall(p, Vec3::X), &lp).map(|v| v.0.x);
        let (Some(clear), Some(fog)) = (clear, fog) else { panic!("no light") };
        let r = (lp.centre - p).length();
        assert!((fog / clear - (-0.01 * r).exp()).abs() < 1e-5, "Beer–Lambert over {r} m");
        let shader = night(0.5, 0.9, 0.0);
        // The wall facing away from the lamp.
        assert!(shader.lamp_light(d, &wall(p, -Vec3::X), &lp).is_none());
        // A lamp shining only ahead (+x, bow 0° ± 20°): the wall aft of it (−x) gets nothing.
        let ahead = lamp(lp.centre, 0.01, 0.05, [0.0, 20.0]);
        assert!(shader.lamp_light(d, &wall(p, Vec3::X), &ahead).is_none());
        // A lamp's lens is not lit by a lamp.
        let mut lens = wall(p, Vec3::X);
        lens.material = 2;
        let grey = night(0.5, 0.9, 0.0).material_of(&wall(p, Vec3::X));
        let lit = night(0.5, 0.9, 0.0).with_materials(Arc::new(vec![grey, grey, lp.material]));
        assert!(lit.lamp_light(d, &lens, &lp).is_none());
    }

    #[test]
    fn the_reach_is_where_a_white_wall_shows_the_least_step_and_the_window_fades_to_it() {
        // A fixed exposure (EV100 0: k = 1/1.2 per cd/m²), as a camera set by hand; no fog.
        let env = ShadeEnv {
            sun_direction: [0.0, 0.866, -0.5],
            exposure_ev100: 0.0,
            fog_extinction_per_m: 0.0,
            ..ShadeEnv::default()
        };
        let white = Material {
            base_color: [1.0; 3],
            roughness: 1.0,
            metallic: 0.0,
            emissive: [0.0; 3],
            nav_light: false,
            arc_deg: [0.0, 180.0],
        };
        let shader = Shader::new(&env, 1, &[]).with_materials(Arc::new(vec![white, white]));
        let k = shader.exposure();
        assert!((k - 1.0 / 1.2).abs() < 1e-6);
        let lp = lamp(Vec3::ZERO, 0.01, 0.05, [0.0, 180.0]);
        // ½ Σ|A| = 0.01 m², brightest channel 2e4 cd/m²: 200 cd at most.
        assert!((lp.max_intensity() - 200.0).abs() < 1e-3);
        let reach = shader.lamp_reach2(&lp).sqrt();
        // At the reach, a white wall face on would show the least step (before the window).
        let shown = k * 200.0 / (std::f32::consts::PI * reach * reach);
        assert!((shown / LAMP_LIGHT_LEAST - 1.0).abs() < 1e-4, "{shown}");
        assert!(reach > 500.0 && reach < 1000.0, "{reach} m");
        // The red channel's diffuse light on the white wall face on at r, before the window: I/(r² + ρ²)/π.
        let light = |r: f32| {
            let p = Vec3::new(-r, 0.0, 0.0);
            let d = (p - Vec3::new(-r + 0.3, 0.2, 0.0)).normalize();
            shader.lamp_light(d, &wall(p, Vec3::X), &lp).map(|v| v.0.x)
        };
        let bare = |r: f32| 200.0 / (r * r + 0.0025) / std::f32::consts::PI;
        for (r, window) in [(0.5 * reach, (15.0f32 / 16.0).powi(2)), (0.9 * reach, (1.0 - 0.9f32.powi(4)).powi(2))] {
            let Some(got) = light(r) else { panic!("no light at {r} m") };
            let want = bare(r) * window;
            // (The GGX lobe of roughness 1 adds a little to the Lambert term seen this way.)
            assert!(got >= want && got < 1.1 * want, "{r} m: {got} vs {want}");
        }
        // Near the lamp the window leaves it whole; beyond the reach there is nothing.
        let Some(near) = light(10.0) else { panic!("no light at 10 m") };
        assert!(near >= bare(10.0) && near < 1.1 * bare(10.0));
        assert!(light(1.001 * reach).is_none() && light(2.0 * reach).is_none());
    }
}
