//! What the shading reads: the environment as the cameras see it ([`ShadeEnv`]) and what a camera ray hit
//! ([`SurfaceHit`]). The models that use them are `shade.rs`'s and its files'.

use super::envlight::LightingKey;
use parry3d::math::Vec3;

/// The environment as the cameras see it (and, for fog, rain and waves, the LiDAR and the radar).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadeEnv {
    /// Unit vector towards the sun (world frame); below the horizon at night.
    pub sun_direction: [f32; 3],
    /// Preetham turbidity of the air (2 very clear .. 10 hazy).
    pub turbidity: f32,
    /// Cloud cover in `[0, 1]`: mixes in the CIE overcast sky and dims the sun's beam.
    pub cloud_cover: f32,
    /// Albedo of the lower hemisphere for image-based light (the sea: 0.06).
    pub ground_albedo: f32,
    /// Atmospheric extinction (1/m), 3 / visibility.
    pub fog_extinction_per_m: f32,
    /// Rain rate (mm/h).
    pub rain_mm_per_h: f32,
    /// Significant wave height (m).
    pub wave_height_m: f32,
    /// Wind speed at 10 m (m/s): capillary roughness and whitecaps.
    pub wind_speed_m_s: f32,
    /// Diffuse reflectance of the water body, linear RGB.
    pub water_albedo: [f32; 3],
    /// Fixed exposure value at ISO 100; `NaN` meters it from the scene's horizontal illuminance.
    pub exposure_ev100: f32,
    /// Whether to cast shadow rays.
    pub shadows: bool,
    /// Whether light reflecting more than once between the sea's wave facets is kept ([`super::sea_ms`]); `false`
    /// is the single-scattering microfacet model alone (as renderers' rough BSDFs, for comparisons).
    pub water_multiple_scattering: bool,
}

impl Default for ShadeEnv {
    /// Clear noon, a light breeze.
    fn default() -> Self {
        Self {
            sun_direction: [0.3, 0.2, 0.93],
            turbidity: 3.0,
            cloud_cover: 0.1,
            ground_albedo: 0.06,
            fog_extinction_per_m: 3.0 / 20_000.0,
            rain_mm_per_h: 0.0,
            wave_height_m: 0.5,
            wind_speed_m_s: 5.0,
            water_albedo: [0.004, 0.018, 0.03],
            exposure_ev100: f32::NAN,
            shadows: true,
            water_multiple_scattering: true,
        }
    }
}

impl ShadeEnv {
    /// The key of this environment's sky lighting.
    pub fn lighting_key(&self) -> LightingKey {
        LightingKey {
            sun: self.sun_direction,
            turbidity: self.turbidity,
            cloud: self.cloud_cover,
            ground_albedo: self.ground_albedo,
        }
    }
}

/// What a camera ray hit, as shading needs it.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceHit {
    /// Distance along the ray (m).
    pub t: f32,
    /// World hit point.
    pub point: Vec3,
    /// Unit world normal, facing the camera.
    pub normal: Vec3,
    /// Semantic class.
    pub class: u16,
    /// Scene instance id.
    pub instance: i32,
    /// The face's material: an index into the shader's table ([`super::Shader::with_materials`]), 0 for the class's
    /// default.
    pub material: u16,
    /// Whether the instance's navigation lights are on.
    pub lights_on: bool,
    /// The shading normal: the geometric one, or for water the swell's ([`super::Shader::with_swell`]).
    pub shading_normal: Vec3,
    /// For water on the displaced sea, the mean square slope of the waves too short for the surface's sampling
    /// there ([`crate::sea::SurfaceShading`]), added to the glint's roughness; 0 elsewhere.
    pub unresolved_mss: f32,
    /// `[V_sky, V_ground]`: the share of the sky's and of the ground's light that the hit's own mesh leaves it
    /// ([`crate::sky_visibility`]), scaling the environment's light on it; `[1, 1]` for water, a back face, or a
    /// render without it.
    pub sky_visibility: [f32; 2],
}

impl SurfaceHit {
    /// Whether this is the sea surface.
    #[inline]
    pub fn is_water(&self) -> bool {
        self.class == 1
    }
}
