//! The navigation lamps' glitter on the water rays of a camera's batch (`shade/lamp_glitter.rs` gives one lamp's at
//! one point): the lamps near each hit's reflection lobe, each behind a shadow ray from the water to the lamp
//! (`lamp_shadows.rs`). `radiance.rs` adds it to the water rays it shades itself.

use super::lamp_shadows::shadowed_lamp_sum;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::lamp_glitter::LampSet;
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;

/// The lamps' glitter (`shade/lamp_glitter.rs`) that each water ray of `which` brings to the camera through the
/// fog, in that order: every lamp near the lobe of its hit ([`LampSet::near_lobe`]), each behind a shadow ray from
/// the water to the lamp, stopped short of the lamp's lantern.
pub(super) fn lamp_glow(
    scene: &Scene,
    shader: &Shader,
    set: &LampSet,
    rays: (&[[f32; 3]], &[[f32; 3]], &RayHits),
    which: &[u32],
) -> Vec<Vec3> {
    shadowed_lamp_sum(scene, shader, rays, which, |d, h, out| {
        let mut near = Vec::new();
        set.near_lobe(h.point, h.shading_normal, -d, shader.water_mss(h.unresolved_mss), &mut near);
        for i in near {
            let lamp = &set.lamps()[i as usize];
            if let Some((value, l, r)) = shader.lamp_glitter(d, h, lamp) {
                out.push((value, l, r, lamp.radius));
            }
        }
    })
}
