//! Physically based RGB shading of camera rays: radiance in cd/m² (linear sRGB primaries), then exposure and a
//! filmic tone curve into 8-bit sRGB.
//!
//! The models, each in its own file with its sources:
//! * [`sky`]: the Preetham clear sky, the CIE overcast sky, the sun's beam and its true-size disc;
//! * [`brdf`]: GGX/Smith microfacet specular with Schlick's Fresnel over a Lambert diffuse (metallic workflow);
//! * [`envlight`]: the sky (and the sea below the horizon) as image-based light, irradiance and split-sum
//!   prefiltered maps;
//! * [`water`]: Cox–Munk capillary roughness, Monahan whitecaps, Kelvin wakes and the water body;
//! * [`rough_water`]: the rough sea's single-scattering microfacet reflection (Beckmann, Smith, Fresnel);
//! * [`lamp_glitter`]: the navigation lamps' glitter on that water at night, by next-event estimation;
//! * [`lamp_light`]: the lamps' light on hulls and everything else but the water at night, the same way;
//! * [`sky_lobe`]: the sky's mean over the rough water's reflection lobe, tabulated per environment;
//! * [`sea_ms`]: the light reflected more than once between the wave facets (Heitz et al.'s random walk),
//!   restored over that lobe (Turquin's energy compensation);
//! * [`swell`]: the fixed four-component swell of linear waves, the water's normals where the scene has no
//!   displaced wave surface;
//! * [`tonemap`]: physical exposure from the scene's illuminance and the ACES filmic curve;
//! * [`rain`]: the drops near the lens as motion-blurred streaks (Garg & Nayar's photometric model), each as
//!   bright as the light it refracts ([`Shader::drop_radiance`]).
//!
//! [`ShadeEnv`] and [`SurfaceHit`] (what shading reads) live in `env.rs`, the water's shading from its models in
//! `water_shading.rs`, [`Lobes`] (a material's lobes for direct light) in [`brdf`].
//!
//! A surface of material `m` seen along `d` (`v = −d`) is lit by the sun (irradiance `E_s` along `s`, when the
//! camera's shadow ray finds it unoccluded) and by the environment:
//! `L = L_e + (f_d + f_s(v, s)) E_s (n·s) + f_d (V_sky E_sky(n) + V_ground E_ground(n)) + P(r', roughness)
//! (F0 A + B) S`, with `f_d = (1 − metallic) base / π`, `r'` the rough lobe's dominant direction (Lagarde & de
//! Rousiers 2014), `E_sky` and `E_ground` the environment's irradiance from above and below the horizon, `V_sky` and
//! `V_ground` the shares of them that the surface's own mesh leaves it and `S` the specular occlusion of the part
//! `r'` leans into ([`crate::sky_visibility`]; 1 at `draft` quality). Other instances do not occlude the
//! environment's light (a ship's side beside a quay sees the whole sky), a known limit of the model.
//! At night each lit navigation lamp adds its light the same way as the sun, `(f_d + f_s(v, l)) E_l (n·l)` behind a
//! shadow ray ([`lamp_light`]; the camera adds it to the rays it shades, `camera/lamp_light.rs`).
//! Water is a dielectric (IOR 1.33) whose normals and roughness come from the wave surface where the scene has one
//! (`WaveSurface::shading`, the far sea beyond its sampled part included), else from a fixed four-component swell
//! ([`swell`]): `L = F(θ_o) L_r + glint + L_body`, where `L_r` is the radiance along the reflected ray (traced by
//! the camera, so ships mirror in it; the sky's otherwise), the glint is the sun through a Cox–Munk GGX lobe, and
//! `L_body` the smooth-plastic water body; foam (whitecaps and wakes) is Lambertian on top. Aerial perspective:
//! `L·T + L_air (1 − T)`, `T = e^{−σ t}` (Koschmieder), `L_air` the horizon sky's radiance along the view's azimuth
//! (in twilight, the haze in the Earth's shadow, `twilight::shadowed_haze`).

use crate::material::Material;
use crate::scene::Scene;
use crate::sea::WaveSurface;
use crate::seabed::Seabed;
use crate::sky_visibility::{specular_occlusion, wants_sky_visibility, SkyVisibility};
use parry3d::math::Vec3;
use std::sync::Arc;

pub mod brdf;
mod class_material;
mod env;
pub mod envlight;
pub mod foam;
pub mod kelvin;
pub mod lamp_glitter;
pub mod lamp_halo;
pub mod lamp_light;
pub mod rain;
pub mod rough_water;
pub mod sea_ms;
mod sea_ms_table;
pub mod sky;
pub mod sky_lobe;
pub mod swell;
mod tables;
pub mod tonemap;
pub mod twilight;
pub mod wake;
pub mod water;
mod water_shading;

use brdf::dfg;
pub use brdf::Lobes;
pub use class_material::class_material;
pub use env::{ShadeEnv, SurfaceHit};
use envlight::{Lighting, WATER_IOR};
use foam::Foam;
use swell::Swell;
use wake::Wake;
use water::ShallowWater;

/// Shading of one render: the environment's lighting (shared between renders), swell, foam and exposure,
/// computed once; then [`Shader::shade`] per ray.
#[derive(Debug, Clone)]
pub struct Shader {
    env: ShadeEnv,
    light: Arc<Lighting>,
    swell: Swell,
    sun: Vec3,
    sun_e: Vec3,
    water_alpha: f32,
    water_fdr: f32,
    water_rho: Vec3,
    shallow: Arc<ShallowWater>,
    foam: Foam,
    /// The Kelvin waves of the vessels under way, added to the water's slopes ([`Shader::with_swell`]).
    kelvin: kelvin::KelvinWaves,
    /// The incident reading (or the fixed EV100's scale), before the compensation `exposure_gain`.
    exposure: f32,
    /// `2^compensation` of an automatic exposure ([`Shader::with_exposure`]); 1 otherwise.
    exposure_gain: f32,
    /// Whether the exposure is fixed (the environment's or the camera's EV100): no highlight limit.
    exposure_fixed: bool,
    /// Share of the sky's own radiance that reaches the camera through the fog (3 km of it).
    sky_keep: f32,
    materials: Arc<Vec<Material>>,
    seabed: Option<Arc<Seabed>>,
    /// The displaced sea surface, whose slopes replace the swell's normals ([`Shader::with_waves`]).
    waves: Option<Arc<WaveSurface>>,
    /// A pinhole pixel's angle (radians) and an orthographic pixel's width (metres): [`Shader::with_footprint`].
    pixel_rad: f32,
    pixel_m: f32,
    /// The lit navigation lamps whose glitter and direct light the camera samples ([`Shader::with_lamps`]).
    lamps: Arc<lamp_glitter::LampSet>,
    /// Per scene mesh, the sky's visibility over its own surfaces ([`Shader::with_sky_visibility`]); empty: none.
    sky_visibility: Vec<Option<Arc<SkyVisibility>>>,
}

impl Shader {
    /// Precomputes the shading of a render with environment `env`, seed `seed` (swell and rain streaks) and the
    /// vessels under way `wakes`.
    pub fn new(env: &ShadeEnv, seed: u64, wakes: &[Wake]) -> Self {
        let swell = Swell::new(env.wave_height_m, seed);
        let light = Lighting::shared(&env.lighting_key());
        let exposure = tonemap::exposure_scale(env.exposure_ev100, light.horizontal_lux);
        Self {
            env: *env,
            sun: light.sky.sun,
            sun_e: light.sky.sun_irradiance(),
            light,
            swell,
            water_alpha: water::cox_munk_alpha(env.wind_speed_m_s),
            water_fdr: water::internal_diffuse_reflectance(WATER_IOR),
            water_rho: Vec3::from_array(env.water_albedo),
            shallow: ShallowWater::shared(Vec3::from_array(env.water_albedo)),
            foam: Foam::new(water::monahan_coverage(env.wind_speed_m_s), wakes, foam::FOAM_SEED),
            kelvin: kelvin::KelvinWaves::new(wakes),
            exposure,
            exposure_gain: 1.0,
            exposure_fixed: env.exposure_ev100.is_finite(),
            sky_keep: (-env.fog_extinction_per_m * 3000.0).exp(),
            materials: Arc::new(Vec::new()),
            seabed: None,
            waves: None,
            pixel_rad: 0.0,
            pixel_m: 0.0,
            lamps: Arc::default(),
            sky_visibility: Vec::new(),
        }
    }

    /// This shader with (the default) or without the vessels' Kelvin waves on the water.
    pub fn with_kelvin_waves(mut self, on: bool) -> Self {
        if !on {
            self.kelvin = kelvin::KelvinWaves::default();
        }
        self
    }

    /// This shader showing the bottom through shallow water over `seabed` (a scene's, [`crate::Scene::seabed`]).
    pub fn with_seabed(mut self, seabed: Option<Arc<Seabed>>) -> Self {
        self.seabed = seabed;
        self
    }

    /// This shader taking water normals from the displaced sea surface `waves` (a scene's,
    /// [`crate::Scene::wave_surface`]) instead of the swell.
    pub fn with_waves(mut self, waves: Option<Arc<WaveSurface>>) -> Self {
        if waves.as_ref().is_some_and(|w| w.elevation_std() > 0.0) {
            // The whitecaps gather on the crests.
            self.foam = self.foam.clone().on_crests();
        }
        self.waves = waves;
        self
    }

    /// This shader's wakes indexed around a camera at `centre` (world x, y) out to `radius` metres
    /// ([`Foam::around`]): the same foam to the bit, each water point trying only the wakes that may reach it.
    pub fn with_foam_around(mut self, centre: [f32; 2], radius: f32) -> Self {
        self.foam = std::mem::take(&mut self.foam).around(centre, radius);
        self
    }

    /// This shader seeing the water with pixels of `pixel_rad` radians (a pinhole camera's) or `pixel_m` metres
    /// (an orthographic one's): a hit's footprint on the water, `(pixel_m + t · pixel_rad) / |d_z|`, chooses
    /// which of the sea's detail bands it draws as normals ([`WaveSurface::shading`]). Both 0 (the default):
    /// every band. An orthographic view (`pixel_rad` 0, `pixel_m` > 0: a top view) sees the water with one
    /// footprint across an image much wider than the finest tiles, so its footprint is taken as at least the
    /// finest cell: every tile then draws the same waves (the finest grid's, `SurfaceSpec::fine_m`), the shorter
    /// ones as roughness, instead of the finest tiles alone drawing 2–4 m waves as a square of other texture.
    pub fn with_footprint(mut self, pixel_rad: f32, pixel_m: f32) -> Self {
        self.pixel_rad = pixel_rad.max(0.0);
        self.pixel_m = pixel_m.max(0.0);
        self
    }

    /// Whether face material `material` emits towards the viewer as far as its arc goes: a navigation lamp only
    /// towards bearings inside it (`body_dir`: the direction to the viewer in the instance's body frame, worked
    /// out only for a lamp; [`Material::emits_towards`]), every other material always.
    #[inline]
    pub fn lamp_shines(&self, material: u16, body_dir: impl FnOnce() -> Vec3) -> bool {
        match self.materials.get(material as usize) {
            Some(m) if material != 0 && m.nav_light => m.emits_towards(body_dir()),
            _ => true,
        }
    }

    /// This shader reading face materials from `table` (a scene's, [`crate::Scene::material_table`]).
    pub fn with_materials(mut self, table: Arc<Vec<Material>>) -> Self {
        self.materials = table;
        self
    }

    /// Darkens the environment's light where a mesh hides the sky from its own surfaces
    /// ([`crate::sky_visibility`]): each of `scene`'s meshes but the water's, baked on first use in the process.
    pub fn with_sky_visibility(mut self, scene: &Scene) -> Self {
        self.sky_visibility =
            scene.meshes().iter().map(|m| wants_sky_visibility(m).then(|| SkyVisibility::shared(m))).collect();
        self
    }

    /// [`Shader::with_sky_visibility`] when `on` (the cameras' `standard` and `high` qualities), else unchanged.
    pub fn with_sky_visibility_if(self, on: bool, scene: &Scene) -> Self {
        if on {
            self.with_sky_visibility(scene)
        } else {
            self
        }
    }

    /// `[V_sky, V_ground]`, the sky's and the ground's visibility at world point `point` on triangle `triangle` of
    /// instance `instance` of `scene` (the scene of [`Shader::with_sky_visibility`]); `[1, 1]` without it.
    #[inline]
    pub fn sky_visibility(&self, scene: &Scene, instance: i32, triangle: i32, point: Vec3) -> [f32; 2] {
        if self.sky_visibility.is_empty() {
            return [1.0; 2];
        }
        let (Ok(i), Ok(t)) = (usize::try_from(instance), u32::try_from(triangle)) else {
            return [1.0; 2];
        };
        let Some(inst) = scene.instances().get(i) else {
            return [1.0; 2];
        };
        let m = inst.mesh() as usize;
        match (self.sky_visibility.get(m), scene.meshes().get(m)) {
            (Some(Some(v)), Some(mesh)) => v.at(mesh, t, inst.pose().inverse_transform_point(point)),
            _ => [1.0; 2],
        }
    }

    /// The lighting (sky, sun, image-based light).
    pub fn lighting(&self) -> &Lighting {
        &self.light
    }

    /// This shader exposing as a camera set to `exposure`: its fixed EV100 replaces the environment's and the
    /// metered one; otherwise, unless the environment fixes the exposure, the incident reading is floored at the
    /// camera's limit ([`tonemap::min_metered_lux`] of its highest ISO) and the compensation applies.
    pub fn with_exposure(mut self, exposure: &tonemap::Exposure) -> Self {
        if let Some(ev100) = exposure.ev100 {
            self.exposure = tonemap::fixed_exposure_scale(ev100);
            self.exposure_fixed = true;
            self.exposure_gain = 1.0;
        } else if !self.env.exposure_ev100.is_finite() {
            let floor = tonemap::min_metered_lux(exposure.max_iso);
            self.exposure = tonemap::incident_exposure_scale(self.light.horizontal_lux, floor);
            self.exposure_gain = 2f32.powf(exposure.compensation_ev);
        }
        self
    }

    /// Multiplier from radiance (cd/m²) to the tone curve's input: the incident reading, compensated (or the
    /// fixed EV100's scale).
    pub fn exposure(&self) -> f32 {
        self.exposure * self.exposure_gain
    }

    /// The exposure of a `width × height` view whose pixel `p` (row-major) has the centre-ray radiance
    /// `radiance(p)`: the automatic one with its highlight limit ([`tonemap::highlight_limited`], reading
    /// [`tonemap::metered_pixels`]), or the fixed EV100's.
    pub fn metered_exposure(&self, width: usize, height: usize, radiance: impl Fn(usize) -> Vec3) -> f32 {
        if self.exposure_fixed {
            return self.exposure;
        }
        let limited = tonemap::highlight_limited(self.exposure, tonemap::metered_pixels(width, height).map(radiance));
        limited * self.exposure_gain
    }

    /// Unit vector towards the sun.
    pub fn sun(&self) -> Vec3 {
        self.sun
    }

    /// Whether the sun lights anything (it is up and not behind full cloud).
    pub fn sun_up(&self) -> bool {
        self.sun_e.max_element() > 0.0 && self.sun.z > 0.0
    }

    /// Radiance of the sky along unit `d`, with the sun's disc, veiled by fog.
    #[inline(always)]
    pub fn sky(&self, d: Vec3) -> Vec3 {
        let (sky, air) = self.light.sky_and_horizon(d);
        let c = sky + self.light.sky.sun_disc(d);
        c * self.sky_keep + air * (1.0 - self.sky_keep)
    }

    /// Radiance of the sky without the sun's disc along unit `d` (what a reflected ray sees; the sun's
    /// reflection is the glint), veiled by fog.
    #[inline(always)]
    fn sky_no_sun(&self, d: Vec3) -> Vec3 {
        let (sky, air) = self.light.sky_and_horizon(d);
        sky * self.sky_keep + air * (1.0 - self.sky_keep)
    }

    /// The sky as water of roughness `alpha` reflects it around unit mirror direction `r`: its mean over the
    /// single-scattering lobe (`sky_lobe.rs`; `r` read as level water's mirror direction), blended into the air
    /// light by visibility as [`Shader::reflected`] blends the sky along a ray that meets nothing.
    #[inline]
    pub fn sky_lobe(&self, r: Vec3, alpha: f32) -> Vec3 {
        let (sky, air) = self.light.sky_and_horizon(r);
        let (dsky, dair) = self.light.sky_lobe_correction(r, alpha);
        (sky + dsky) * self.sky_keep + (air + dair) * (1.0 - self.sky_keep)
    }

    /// Radiance distant objects fade into along `d`: the horizon sky's, at `d`'s azimuth.
    #[inline(always)]
    pub fn air_light(&self, d: Vec3) -> Vec3 {
        self.light.horizon_radiance(d)
    }

    /// Aerial perspective over a path of `t` metres along `d`.
    #[inline(always)]
    pub fn fog(&self, c: Vec3, d: Vec3, t: f32) -> Vec3 {
        let f = (-self.env.fog_extinction_per_m * t).exp();
        c * f + self.air_light(d) * (1.0 - f)
    }

    /// The material of a non-water hit: its face's from the table, else its class's default.
    #[inline(always)]
    pub fn material_of(&self, hit: &SurfaceHit) -> Material {
        match self.materials.get(hit.material as usize) {
            Some(m) if hit.material != 0 => *m,
            _ => class_material(hit),
        }
    }

    /// Radiance (before aerial perspective) of a non-water surface seen along `d`, lit by the sun when `sunlit`.
    #[inline(always)]
    pub fn surface(&self, d: Vec3, hit: &SurfaceHit, sunlit: bool) -> Vec3 {
        let m = self.material_of(hit);
        let n = hit.normal;
        let v = -d;
        let nv = n.dot(v).max(1e-4);
        let lobes = Lobes::of(&m);
        let Lobes { diffuse, f0, alpha } = lobes;
        // The environment's light, less what the surface's own mesh hides of the sky's and of the ground's
        // (`sky_visibility.rs`).
        let [v_sky, v_ground] = hit.sky_visibility;
        let e_ground = self.light.ground_irradiance(n);
        let mut c = diffuse * ((self.light.irradiance(n) - e_ground) * v_sky + e_ground * v_ground);
        let r = d - n * (2.0 * d.dot(n));
        // The rough lobe's dominant direction leans from the mirror direction towards the normal (Lagarde & de
        // Rousiers 2014, "Moving Frostbite to PBR", section 4.9.3), where the split sum reads the environment.
        let lean = (1.0 - alpha) * ((1.0 - alpha).sqrt() + alpha);
        let dominant = (n + (r - n) * lean).normalize_or(r);
        let [a, b] = dfg(nv, m.roughness);
        let v_lobe = if dominant.z >= 0.0 { v_sky } else { v_ground };
        c += self.light.prefiltered(dominant, m.roughness)
            * (f0 * a + Vec3::splat(b))
            * specular_occlusion(nv, v_lobe, alpha);
        if sunlit {
            c += lobes.direct(n, v, self.sun, self.sun_e);
        }
        if !m.nav_light || hit.lights_on {
            c += Vec3::from_array(m.emissive);
        }
        c
    }

    /// Radiance along camera ray `d` with its hit (or `None` for the sky), whether the hit sees the sun, and for
    /// water the radiance along its reflected ray (`None`: the sky's); aerial perspective included.
    #[inline(always)]
    pub fn shade(&self, d: Vec3, hit: Option<&SurfaceHit>, sunlit: bool, reflected: Option<Vec3>) -> Vec3 {
        let Some(hit) = hit else {
            return self.sky(d);
        };
        let c = if hit.is_water() { self.water(d, hit, sunlit, reflected) } else { self.surface(d, hit, sunlit) };
        self.fog(c, d, hit.t)
    }

    /// Radiance a reflected ray `d` brings back: its hit's (no further reflection), or the sky without the
    /// sun's disc.
    #[inline(always)]
    pub fn reflected(&self, d: Vec3, hit: Option<&SurfaceHit>, sunlit: bool) -> Vec3 {
        match hit {
            None => self.sky_no_sun(d),
            Some(h) => self.shade(d, Some(h), sunlit, None),
        }
    }

    /// The radiance of a rain drop seen along unit `d` ([`rain`]): the cosine-weighted mean of the environment's
    /// radiance (and the sun's, where it lies ahead) over the half of the sphere the drop looks into, through two
    /// water surfaces, `T_w (E_env(d) + E_sun max(0, d·s)) / π` (cd/m², linear RGB).
    pub fn drop_radiance(&self, d: Vec3) -> Vec3 {
        let sun = if self.sun.z > 0.0 { self.sun_e * self.sun.dot(d).max(0.0) } else { Vec3::ZERO };
        (self.light.irradiance(d) + sun) * (rain::DROP_TRANSMITTANCE / std::f32::consts::PI)
    }
}

#[cfg(test)]
mod tests;
