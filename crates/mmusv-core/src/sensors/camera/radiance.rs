//! The radiance of a set of camera rays whose primary hits are known: sun visibility by shadow rays, water
//! reflections by traced rays (with their own shadow rays), then the [`Shader`] per ray.
//!
//! Every stage is one batch over the scene (parallel, coherent packets in the order given), so a camera's
//! pixels, its anti-aliasing samples and any other ray set go through the same code.

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
        material: scene.material_of(instance, triangle).copied(),
        lights_on: scene.instances().get(instance as usize).is_some_and(|i| i.lights_on()),
        shading_normal: normal,
    };
    Some(shader.with_swell(d, hit))
}

/// Which of `surfaces` see the sun (all false at night; all that face it when shadows are off).
fn sunlit(scene: &Scene, shader: &Shader, shadows: bool, surfaces: &[Option<SurfaceHit>]) -> Result<Vec<bool>> {
    let n = surfaces.len();
    let mut lit = vec![false; n];
    if !shader.sun_up() {
        return Ok(lit);
    }
    let sun = shader.sun();
    let facing: Vec<(u32, [f32; 3])> = surfaces
        .par_iter()
        .enumerate()
        .filter_map(|(k, h)| {
            let h = h.as_ref()?;
            if h.normal.dot(sun) > 0.0 || h.is_water() {
                let eps = 0.02 + 1e-4 * h.t;
                Some((k as u32, (h.point + h.normal * eps).to_array()))
            } else {
                None
            }
        })
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

/// Radiance (linear RGB, cd/m², aerial perspective included) along every ray `origins[k] + t dirs[k]` whose
/// closest hits are `hits`. `reflections` traces the rays water reflects (else water reflects the sky);
/// `shadows` casts shadow rays (else every surface facing the sun is lit).
pub fn radiance(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    reflections: bool,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    hits: &RayHits,
) -> Result<Vec<Vec3>> {
    let n = origins.len();
    let surfaces: Vec<Option<SurfaceHit>> =
        (0..n).into_par_iter().map(|k| surface_at(shader, scene, hits, origins, dirs, k)).collect();
    let lit = sunlit(scene, shader, shadows, &surfaces)?;
    // Reflected rays of the water hits, traced, and the radiance they bring back.
    let mut reflected: Vec<Option<Vec3>> = vec![None; n];
    if reflections {
        let water: Vec<(u32, [f32; 3], [f32; 3])> = surfaces
            .par_iter()
            .enumerate()
            .filter_map(|(k, h)| {
                let h = h.as_ref().filter(|h| h.is_water())?;
                let (o, r) = shader.reflection_ray(Vec3::from_array(dirs[k]), h);
                Some((k as u32, o.to_array(), r.to_array()))
            })
            .collect();
        if !water.is_empty() {
            let ro: Vec<[f32; 3]> = water.iter().map(|w| w.1).collect();
            let rd: Vec<[f32; 3]> = water.iter().map(|w| w.2).collect();
            let rhits = scene.cast_rays(&ro, &rd, REFLECTION_RANGE)?;
            let rsurf: Vec<Option<SurfaceHit>> =
                (0..ro.len()).into_par_iter().map(|j| surface_at(shader, scene, &rhits, &ro, &rd, j)).collect();
            let rlit = sunlit(scene, shader, shadows, &rsurf)?;
            let values: Vec<Vec3> = (0..ro.len())
                .into_par_iter()
                .map(|j| {
                    let d = Vec3::from_array(rd[j]);
                    match rsurf[j].as_ref() {
                        // A reflection meeting the water again (a wave face) reads the sky along it.
                        Some(h) if h.is_water() => shader.reflected(d, None, false),
                        h => shader.reflected(d, h, rlit[j]),
                    }
                })
                .collect();
            for (w, v) in water.iter().zip(values) {
                reflected[w.0 as usize] = Some(v);
            }
        }
    }
    Ok((0..n)
        .into_par_iter()
        .map(|k| shader.shade(Vec3::from_array(dirs[k]), surfaces[k].as_ref(), lit[k], reflected[k]))
        .collect())
}
