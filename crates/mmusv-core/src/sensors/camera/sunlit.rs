//! Which hits of a batch of camera rays see the sun: one shadow ray per hit towards the sun's centre (T. Whitted,
//! "An Improved Illumination Model for Shaded Display", Communications of the ACM 23(6), 1980), the sun taken as a
//! directional point light: shadows are hard-edged, without the penumbra of its 0.533° disc (`shade/sky.rs`).
//!
//! Only a hit that could be lit casts one: a surface facing the sun, or water, whose shading normal (the waves')
//! may face it where the geometric one does not. At night nothing is lit; with shadows off, every such hit is.
//! `radiance.rs` asks for the rays it shades itself ([`sunlit`]) and for a list of them ([`sunlit_of`]).

use crate::error::Result;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Farthest a shadow ray looks for an occluder, metres.
const SHADOW_RANGE: f32 = 5_000.0;

/// Where a shadow ray from the hit of ray `k` starts (just off the surface, on the camera's side), if that hit
/// could see the sun (it faces it, or it is water, whose swell may face it), else `None`; `keep` filters the
/// rays.
#[inline]
fn shadow_origin(
    hits: &RayHits,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    k: usize,
    sun: Vec3,
    keep: impl Fn(usize) -> bool,
) -> Option<[f32; 3]> {
    let t = hits.distance[k];
    if !t.is_finite() || !keep(k) {
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

/// Which of the rays' hits see the sun (of the rays `keep` accepts; the others are false): all false at
/// night, all that could when shadows are off.
pub(super) fn sunlit(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    (hits, origins, dirs): (&RayHits, &[[f32; 3]], &[[f32; 3]]),
    keep: impl Fn(usize) -> bool + Sync + Copy,
) -> Result<Vec<bool>> {
    let n = origins.len();
    if !shader.sun_up() {
        return Ok(vec![false; n]);
    }
    let sun = shader.sun();
    let facing: Vec<(u32, [f32; 3])> = (0..n)
        .into_par_iter()
        .filter_map(|k| shadow_origin(hits, origins, dirs, k, sun, keep).map(|o| (k as u32, o)))
        .collect();
    lit_slots(scene, sun, shadows, &facing, n)
}

/// [`sunlit`] of the rays `which` only, in that order.
pub(super) fn sunlit_of(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    (hits, origins, dirs): (&RayHits, &[[f32; 3]], &[[f32; 3]]),
    which: &[u32],
) -> Result<Vec<bool>> {
    if !shader.sun_up() {
        return Ok(vec![false; which.len()]);
    }
    let sun = shader.sun();
    let facing: Vec<(u32, [f32; 3])> = which
        .par_iter()
        .enumerate()
        .filter_map(|(j, &k)| shadow_origin(hits, origins, dirs, k as usize, sun, |_| true).map(|o| (j as u32, o)))
        .collect();
    lit_slots(scene, sun, shadows, &facing, which.len())
}

/// `len` flags, true at the slots of `facing` (slot, shadow-ray origin) whose shadow ray towards `sun` is not
/// blocked (all of them when `shadows` is off).
fn lit_slots(scene: &Scene, sun: Vec3, shadows: bool, facing: &[(u32, [f32; 3])], len: usize) -> Result<Vec<bool>> {
    let mut lit = vec![false; len];
    if shadows {
        let origins: Vec<[f32; 3]> = facing.iter().map(|(_, o)| *o).collect();
        let dirs = vec![sun.to_array(); origins.len()];
        let blocked = scene.occluded_rays(&origins, &dirs, SHADOW_RANGE)?;
        for ((j, _), b) in facing.iter().zip(blocked) {
            lit[*j as usize] = !b;
        }
    } else {
        for (j, _) in facing {
            lit[*j as usize] = true;
        }
    }
    Ok(lit)
}
