//! The water's shading ([`Shader::water`] and what it reads): its normals from the wave surface or the swell with
//! the vessels' Kelvin waves, the reflected ray, the rough surface's reflectance, the sun's glint, the water body
//! and the foam. The models are `water.rs`, `rough_water.rs`, `sea_ms.rs`, `foam.rs`, `kelvin.rs` and `swell.rs`;
//! the module docs of `shade.rs` give the whole equation.

use super::envlight::WATER_IOR;
use super::foam::FOAM_ALBEDO;
use super::tables::water_fresnel;
use super::{kelvin, rough_water, sea_ms, water, Shader, SurfaceHit};
use parry3d::math::Vec3;

impl Shader {
    /// Swell normal of the water surface at `p` ([`super::swell::Swell::normal`]).
    #[inline(always)]
    pub fn water_normal(&self, p: Vec3) -> Vec3 {
        self.swell.normal(p)
    }

    /// `hit` with its shading normal set: for water seen along `d`, the wave surface's (with the roughness of the
    /// waves it does not draw), or without one the swell's, with the slopes of the vessels' Kelvin waves added
    /// (those the pixel cannot resolve as roughness; the geometric normal where the result would face away); for
    /// anything else, the geometric normal.
    #[inline(always)]
    pub fn with_swell(&self, d: Vec3, mut hit: SurfaceHit) -> SurfaceHit {
        hit.shading_normal = hit.normal;
        hit.unresolved_mss = 0.0;
        if hit.is_water() {
            let mut footprint = (self.pixel_m + hit.t * self.pixel_rad) / d.z.abs().max(0.05);
            if let Some(w) = self.waves.as_ref().filter(|_| self.pixel_rad == 0.0 && self.pixel_m > 0.0) {
                footprint = footprint.max(w.finest_cell_m());
            }
            let n = match self.waves.as_ref().and_then(|w| w.shading(hit.point.x, hit.point.y, footprint)) {
                Some(s) => {
                    hit.unresolved_mss = s.unresolved_mss;
                    Vec3::from_array(s.normal)
                }
                None => self.water_normal(hit.point),
            };
            let n = if self.kelvin.is_empty() {
                n
            } else {
                // The vessels' Kelvin waves add their slopes (those the footprint cannot resolve, roughness).
                let k = self.kelvin.slope(hit.point.x, hit.point.y, footprint);
                hit.unresolved_mss += k.unresolved_mss;
                kelvin::tilted(n, k.slope)
            };
            if n.dot(d) <= 0.0 {
                hit.shading_normal = n;
            }
        }
        hit
    }

    /// Origin and unit direction of the ray reflected by a water hit seen along `d` (never below the horizon),
    /// about its shading normal.
    #[inline(always)]
    pub fn reflection_ray(&self, d: Vec3, hit: &SurfaceHit) -> (Vec3, Vec3) {
        let n = hit.shading_normal;
        let mut r = d - n * (2.0 * d.dot(n));
        r.z = r.z.abs().max(1e-4);
        // A small offset off the surface (2 mm, growing with the distance like the coordinates' rounding), so a
        // reflected silhouette is not shifted by it.
        (hit.point + hit.normal * (2e-3 + 1e-5 * hit.t), r.normalize())
    }

    /// Mean square slope `α²` (both axes) of the water's roughness where the sampled surface leaves
    /// `unresolved_mss` out: the Cox–Munk slopes of the wind plus those. The sun's glint and the glossy
    /// reflections (`sensors/camera/glossy.rs`) both take it.
    #[inline]
    pub fn water_mss(&self, unresolved_mss: f32) -> f32 {
        self.water_alpha * self.water_alpha + unresolved_mss.max(0.0)
    }

    /// The rough water's directional reflectance seen at `cos_o` with roughness `alpha`, light scattered more than
    /// once between the facets included when the environment asks for it (`sea_ms.rs`), and its ratio to the
    /// single-scattering one (what a glint is scaled by).
    #[inline(always)]
    pub(super) fn water_reflectance(&self, cos_o: f32, alpha: f32) -> (f32, f32) {
        let e_single = rough_water::reflectance(cos_o, alpha);
        if self.env.water_multiple_scattering {
            let e = sea_ms::reflectance(cos_o, alpha);
            (e, if e_single > 0.0 { e / e_single } else { 1.0 })
        } else {
            (e_single, 1.0)
        }
    }

    /// Radiance (before aerial perspective) of the water seen along `d`: Fresnel-weighted `reflected` radiance
    /// (along [`Shader::reflection_ray`]; `None` reads the sky there), the sun's Cox–Munk glint when `sunlit`,
    /// the water body, and foam.
    #[inline(always)]
    pub fn water(&self, d: Vec3, hit: &SurfaceHit, sunlit: bool, reflected: Option<Vec3>) -> Vec3 {
        let n = hit.shading_normal;
        let v = -d;
        let cos_o = n.dot(v).clamp(1e-4, 1.0);
        let f_o = water_fresnel(cos_o);
        let l_r = match reflected {
            Some(l) => l,
            None => self.sky_no_sun(self.reflection_ray(d, hit).1),
        };
        // The reflection over the roughness lobe (its radiance spread over the lobe by the camera, `reflected`):
        // weighted by the rough surface's directional reflectance, not the mirror's Fresnel.
        let alpha_r = self.water_mss(hit.unresolved_mss).sqrt();
        // Light scattered more than once between the facets is spent over the same lobe (`sea_ms.rs`): the
        // reflection weighted by the reflectance of every order, the glitter scaled by its share over the first.
        let (e_r, ms_gain) = self.water_reflectance(cos_o, alpha_r);
        let mut c = l_r * e_r;
        let mut entering = self.light.water_entering;
        if sunlit {
            let ns = n.dot(self.sun);
            if ns > 0.0 {
                // The glint: Cox–Munk's Gaussian slopes (Beckmann, `rough_water.rs`) with the wind's roughness and
                // the slope variance of the waves too short for the surface's sampling there (α² adds as mean
                // square slopes do), weighted by the exact Fresnel at the half vector: the reflections' lobe too.
                let h = (v + self.sun).normalize_or_zero();
                let f = water_fresnel(v.dot(h));
                c += self.sun_e * (rough_water::specular_cos(n, v, self.sun, alpha_r) * f * ms_gain);
                entering += self.sun_e * (ns * (1.0 - water_fresnel(ns)));
            }
        }
        let rho = match self.seabed.as_ref().and_then(|s| s.depth(hit.point.x, hit.point.y, 0.0)) {
            Some(depth) => self.shallow.albedo(depth),
            None => self.water_rho,
        };
        c += water::body_factor(rho, self.water_fdr, f_o, WATER_IOR) * entering;
        if !self.foam.is_empty() {
            // The normalised elevation η/σ_η (σ_η the sampled sea's own, H_s/4) that gathers the whitecaps on the
            // crests, where the surface is sampled (beyond, the sea goes on at an elevation not known: the foam's
            // own coverage).
            let (x, y) = (hit.point.x, hit.point.y);
            let crest = (self.waves.as_ref())
                .filter(|w| w.elevation_std() > 0.0 && w.sampled_at(x, y))
                .map(|w| (hit.point.z - w.level()) / w.elevation_std());
            let cover = self.foam.cover(x, y, crest);
            if cover > 0.0 {
                let mut e = self.light.irradiance(n);
                if sunlit {
                    e += self.sun_e * n.dot(self.sun).max(0.0);
                }
                c = c * (1.0 - cover) + e * (cover * FOAM_ALBEDO / std::f32::consts::PI);
            }
        }
        c
    }
}
