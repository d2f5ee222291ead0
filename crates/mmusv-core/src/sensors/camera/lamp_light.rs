//! The navigation lamps' light on the hits of a camera's batch that are not water (`shade/lamp_light.rs` gives
//! one lamp's at one point): every lamp within its reach of the hit and in front of it, each behind a shadow ray
//! from the surface to the lamp. `radiance.rs` adds it to the rays it shades itself.

use super::radiance::{surface_at, PASS_CHUNK};
use crate::scene::{RayHits, Scene, Scratch};
use crate::sensors::shade::lamp_glitter::LampSet;
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// The lamps' light (`shade/lamp_light.rs`) that each non-water ray of `which` brings to the camera through the
/// fog, in that order: every lamp whose reach ([`Shader::lamp_reach2`]) holds the hit, each behind a shadow ray
/// from the surface to the lamp, stopped short of the lamp's lantern.
pub(super) fn lamp_light(
    scene: &Scene,
    shader: &Shader,
    set: &LampSet,
    (origins, dirs, hits): (&[[f32; 3]], &[[f32; 3]], &RayHits),
    which: &[u32],
) -> Vec<Vec3> {
    let reach2: Vec<f32> = set.lamps().iter().map(|l| shader.lamp_reach2(l)).collect();
    // (slot in `which`, its light through the fog, shadow-ray origin, direction and length) per lamp in reach.
    let pairs: Vec<(u32, Vec3, Vec3, Vec3, f32)> = which
        .par_iter()
        .enumerate()
        .with_min_len(PASS_CHUNK / 8)
        .flat_map_iter(|(j, &k)| {
            let k = k as usize;
            let mut out = Vec::new();
            let Some(h) = surface_at(shader, scene, hits, origins, dirs, k) else { return out };
            let d = Vec3::from_array(dirs[k]);
            for (lamp, &reach2) in set.lamps().iter().zip(&reach2) {
                let to = lamp.centre - h.point;
                if to.length_squared() > reach2 || to.dot(h.normal) <= 0.0 {
                    continue;
                }
                if let Some((value, l, r)) = shader.lamp_light(d, &h, lamp) {
                    let origin = h.point + h.normal * (0.02 + 1e-4 * h.t);
                    out.push((j as u32, shader.transmitted(value, h.t), origin, l, r - 1.5 * lamp.radius));
                }
            }
            out
        })
        .collect();
    let seen: Vec<bool> = pairs
        .par_iter()
        .map_init(Scratch::default, |scratch, &(_, _, o, l, range)| {
            range <= 0.0 || !scene.occluded_with(o, l, range, scratch)
        })
        .collect();
    let mut light = vec![Vec3::ZERO; which.len()];
    for (&(j, value, ..), seen) in pairs.iter().zip(seen) {
        if seen {
            light[j as usize] += value;
        }
    }
    light
}
