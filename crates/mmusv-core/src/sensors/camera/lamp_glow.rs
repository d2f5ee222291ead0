//! The navigation lamps' glitter on the water rays of a camera's batch (`shade/lamp_glitter.rs` gives one lamp's at
//! one point): the lamps near each hit's reflection lobe, each behind a shadow ray from the water to the lamp.
//! `radiance.rs` adds it to the water rays it shades itself.

use super::radiance::{surface_at, PASS_CHUNK};
use crate::scene::{RayHits, Scene, Scratch};
use crate::sensors::shade::lamp_glitter::LampSet;
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// The lamps' glitter (`shade/lamp_glitter.rs`) that each water ray of `which` brings to the camera through the
/// fog, in that order: every lamp near the lobe of its hit ([`LampSet::near_lobe`]), each behind a shadow ray from
/// the water to the lamp, stopped short of the lamp's lantern.
pub(super) fn lamp_glow(
    scene: &Scene,
    shader: &Shader,
    set: &LampSet,
    (origins, dirs, hits): (&[[f32; 3]], &[[f32; 3]], &RayHits),
    which: &[u32],
) -> Vec<Vec3> {
    // (slot in `which`, its glitter through the fog, shadow-ray origin, direction and length) per lamp near a hit.
    let pairs: Vec<(u32, Vec3, Vec3, Vec3, f32)> = which
        .par_iter()
        .enumerate()
        .with_min_len(PASS_CHUNK / 8)
        .flat_map_iter(|(j, &k)| {
            let k = k as usize;
            let mut out = Vec::new();
            let Some(h) = surface_at(shader, scene, hits, origins, dirs, k) else { return out };
            let d = Vec3::from_array(dirs[k]);
            let mut near = Vec::new();
            set.near_lobe(h.point, h.shading_normal, -d, shader.water_mss(h.unresolved_mss), &mut near);
            for i in near {
                let lamp = &set.lamps()[i as usize];
                if let Some((value, l, r)) = shader.lamp_glitter(d, &h, lamp) {
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
    let mut glow = vec![Vec3::ZERO; which.len()];
    for (&(j, value, ..), seen) in pairs.iter().zip(seen) {
        if seen {
            glow[j as usize] += value;
        }
    }
    glow
}
