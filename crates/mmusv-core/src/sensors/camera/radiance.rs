//! The radiance of a set of camera rays whose primary hits are known: sun visibility by shadow rays, water
//! reflections by traced rays (with their own shadow rays), then the [`Shader`] per ray.
//!
//! Every stage is one batch over the scene (parallel, coherent packets in the order given), so a camera's
//! pixels, its anti-aliasing samples and any other ray set go through the same code. Hits are turned into
//! [`SurfaceHit`]s on the fly in each pass rather than stored (a stored hit per pixel costs more in memory
//! traffic than recomputing it).

use crate::error::Result;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::{Shader, SurfaceHit};
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Farthest a shadow ray looks for an occluder, metres.
const SHADOW_RANGE: f32 = 5_000.0;
/// Farthest a reflected ray looks for a surface, metres.
const REFLECTION_RANGE: f32 = 20_000.0;

/// The hit of ray `k` as shading needs it (normal turned towards the ray, the face's material, the swell's
/// normal on water), `None` for a miss.
#[inline]
pub(crate) fn surface_at(
    shader: &Shader,
    scene: &Scene,
    hits: &RayHits,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    k: usize,
) -> Option<SurfaceHit> {
    let t = hits.distance[k];
    if !t.is_finite() {
        return None;
    }
    let d = Vec3::from_array(dirs[k]);
    let mut normal = Vec3::new(hits.normal[3 * k], hits.normal[3 * k + 1], hits.normal[3 * k + 2]);
    if normal.dot(d) > 0.0 {
        normal = -normal;
    }
    let point = Vec3::from_array(origins[k]) + d * t;
    let (instance, triangle) = (hits.instance[k], hits.triangle[k]);
    let hit = SurfaceHit {
        t,
        point,
        normal,
        class: hits.class[k],
        instance,
        material: scene.material_index(instance, triangle),
        lights_on: scene.instances().get(instance as usize).is_some_and(|i| i.lights_on()),
        shading_normal: normal,
    };
    Some(shader.with_swell(d, hit))
}

/// Where a shadow ray from the hit of ray `k` starts (just off the surface, on the camera's side), if that hit
/// could see the sun (it faces it, or it is water, whose swell may face it), else `None`; `keep` filters hits
/// by class.
#[inline]
fn shadow_origin(
    hits: &RayHits,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    k: usize,
    sun: Vec3,
    keep: impl Fn(u16) -> bool,
) -> Option<[f32; 3]> {
    let t = hits.distance[k];
    if !t.is_finite() || !keep(hits.class[k]) {
        return None;
    }
    let d = Vec3::from_array(dirs[k]);
    let mut normal = Vec3::new(hits.normal[3 * k], hits.normal[3 * k + 1], hits.normal[3 * k + 2]);
    if normal.dot(d) > 0.0 {
        normal = -normal;
    }
    if normal.dot(sun) > 0.0 || hits.class[k] == 1 {
        let point = Vec3::from_array(origins[k]) + d * t;
        Some((point + normal * (0.02 + 1e-4 * t)).to_array())
    } else {
        None
    }
}

/// Which of the rays' hits see the sun (hits of the classes `keep` accepts): all false at night, all that could
/// when shadows are off.
fn sunlit(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    (hits, origins, dirs): (&RayHits, &[[f32; 3]], &[[f32; 3]]),
    keep: impl Fn(u16) -> bool + Sync + Copy,
) -> Result<Vec<bool>> {
    let n = origins.len();
    let mut lit = vec![false; n];
    if !shader.sun_up() {
        return Ok(lit);
    }
    let sun = shader.sun();
    let facing: Vec<(u32, [f32; 3])> = (0..n)
        .into_par_iter()
        .filter_map(|k| shadow_origin(hits, origins, dirs, k, sun, keep).map(|o| (k as u32, o)))
        .collect();
    if shadows {
        let origins: Vec<[f32; 3]> = facing.iter().map(|(_, o)| *o).collect();
        let dirs = vec![sun.to_array(); origins.len()];
        let blocked = scene.occluded_rays(&origins, &dirs, SHADOW_RANGE)?;
        for ((k, _), b) in facing.iter().zip(blocked) {
            lit[*k as usize] = !b;
        }
    } else {
        for (k, _) in &facing {
            lit[*k as usize] = true;
        }
    }
    Ok(lit)
}

/// Where water reflections are traced.
#[derive(Clone, Copy)]
pub enum Reflections<'a> {
    /// Not at all: water reflects the sky.
    Sky,
    /// For every water ray.
    Every,
    /// Once per group: ray `k` takes the reflected radiance of ray `representative(k)` when that one is water
    /// too (its own otherwise); a representative is its own.
    Shared(&'a (dyn Fn(usize) -> usize + Sync)),
}

/// Radiance (linear RGB, cd/m², aerial perspective included) along every ray `origins[k] + t dirs[k]` whose
/// closest hits are `hits`, with water `reflections` traced as asked; `shadows` casts shadow rays (else every
/// surface facing the sun is lit).
pub fn radiance(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    reflections: Reflections<'_>,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    hits: &RayHits,
) -> Result<Vec<Vec3>> {
    let n = origins.len();
    let surface = |k: usize| surface_at(shader, scene, hits, origins, dirs, k);
    let is_water = |k: usize| hits.distance[k].is_finite() && hits.class[k] == 1;
    let lit = sunlit(scene, shader, shadows, (hits, origins, dirs), |_| true)?;
    // Reflected rays of the water hits (their representatives'), traced, and the radiance they bring back:
    // `slot[k]` is the index into `values` of ray k's reflected radiance.
    let mut slot: Vec<u32> = Vec::new();
    let mut values: Vec<Vec3> = Vec::new();
    if !matches!(reflections, Reflections::Sky) {
        let owner = |k: usize| match reflections {
            Reflections::Shared(rep) => {
                let r = rep(k);
                if r < n && is_water(r) {
                    r
                } else {
                    k
                }
            }
            _ => k,
        };
        let traced: Vec<u32> = (0..n).filter(|&k| is_water(k) && owner(k) == k).map(|k| k as u32).collect();
        let rays: Vec<([f32; 3], [f32; 3])> = traced
            .par_iter()
            .map(|&k| {
                let k = k as usize;
                let h = surface(k).unwrap_or_else(|| unreachable!("ray {k} was a water hit"));
                let (o, r) = shader.reflection_ray(Vec3::from_array(dirs[k]), &h);
                (o.to_array(), r.to_array())
            })
            .collect();
        let (ro, rd): (Vec<[f32; 3]>, Vec<[f32; 3]>) = rays.into_iter().unzip();
        let rhits = scene.cast_rays(&ro, &rd, REFLECTION_RANGE)?;
        let rsurface = |j: usize| surface_at(shader, scene, &rhits, &ro, &rd, j).filter(|h| !h.is_water());
        let rlit = sunlit(scene, shader, shadows, (&rhits, &ro, &rd), |class| class != 1)?;
        values = (0..ro.len())
            .into_par_iter()
            .map(|j| {
                // A reflection meeting the water again (a wave face) reads the sky along it.
                let h = rsurface(j);
                shader.reflected(Vec3::from_array(rd[j]), h.as_ref(), rlit[j])
            })
            .collect();
        let mut index = vec![u32::MAX; n];
        for (j, &k) in traced.iter().enumerate() {
            index[k as usize] = j as u32;
        }
        slot = (0..n).map(|k| if is_water(k) { index[owner(k)] } else { u32::MAX }).collect();
    }
    Ok((0..n)
        .into_par_iter()
        .map(|k| {
            let h = surface(k);
            let refl = slot.get(k).and_then(|&j| values.get(j as usize)).copied();
            shader.shade(Vec3::from_array(dirs[k]), h.as_ref(), lit[k], refl)
        })
        .collect())
}
