//! The pass the lamps' glitter (`lamp_glow.rs`) and their light on other surfaces (`lamp_light.rs`) share: per hit
//! of a batch, the lamps' samples a caller finds there, each behind a shadow ray from the surface to the lamp
//! (stopped short of its lantern), summed per ray through the fog of the ray's own length.

use super::radiance::{surface_at, PASS_CHUNK};
use crate::scene::{RayHits, Scene, Scratch};
use crate::sensors::shade::{Shader, SurfaceHit};
use parry3d::math::Vec3;
use rayon::prelude::*;

/// One lamp's sample at a hit: its radiance there, the unit direction to the lamp, its distance (m) and the
/// lamp's radius (m).
pub(super) type LampSample = (Vec3, Vec3, f32, f32);

/// The sum, per ray of `which` (in that order), of the samples `sample(d, hit, out)` pushes for its hit seen along
/// `d`, each kept where its shadow ray reaches the lamp, through the fog of the ray's length.
pub(super) fn shadowed_lamp_sum<F>(
    scene: &Scene,
    shader: &Shader,
    (origins, dirs, hits): (&[[f32; 3]], &[[f32; 3]], &RayHits),
    which: &[u32],
    sample: F,
) -> Vec<Vec3>
where
    F: Fn(Vec3, &SurfaceHit, &mut Vec<LampSample>) + Sync,
{
    // (slot in `which`, its sample through the fog, shadow-ray origin, direction and length) per sample.
    let pairs: Vec<(u32, Vec3, Vec3, Vec3, f32)> = which
        .par_iter()
        .enumerate()
        .with_min_len(PASS_CHUNK / 8)
        .flat_map_iter(|(j, &k)| {
            let k = k as usize;
            let mut found = Vec::new();
            let Some(h) = surface_at(shader, scene, hits, origins, dirs, k) else { return Vec::new() };
            sample(Vec3::from_array(dirs[k]), &h, &mut found);
            let origin = h.point + h.normal * (0.02 + 1e-4 * h.t);
            found
                .into_iter()
                .map(|(value, l, r, radius)| (j as u32, shader.transmitted(value, h.t), origin, l, r - 1.5 * radius))
                .collect()
        })
        .collect();
    let seen: Vec<bool> = pairs
        .par_iter()
        .map_init(Scratch::default, |scratch, &(_, _, o, l, range)| {
            range <= 0.0 || !scene.occluded_with(o, l, range, scratch)
        })
        .collect();
    let mut sum = vec![Vec3::ZERO; which.len()];
    for (&(j, value, ..), seen) in pairs.iter().zip(seen) {
        if seen {
            sum[j as usize] += value;
        }
    }
    sum
}
