//! The navigation lamps' light on the hits of a camera's batch that are not water (`shade/lamp_light.rs` gives
//! one lamp's at one point): every lamp within its reach of the hit and in front of it, each behind a shadow ray
//! from the surface to the lamp (`lamp_shadows.rs`). `radiance.rs` adds it to the rays it shades itself.

use super::lamp_shadows::shadowed_lamp_sum;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::lamp_glitter::LampSet;
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;

/// The lamps' light (`shade/lamp_light.rs`) that each non-water ray of `which` brings to the camera through the
/// fog, in that order: every lamp whose reach ([`Shader::lamp_reach2`]) holds the hit, each behind a shadow ray
/// from the surface to the lamp, stopped short of the lamp's lantern.
pub(super) fn lamp_light(
    scene: &Scene,
    shader: &Shader,
    set: &LampSet,
    rays: (&[[f32; 3]], &[[f32; 3]], &RayHits),
    which: &[u32],
) -> Vec<Vec3> {
    let reach2: Vec<f32> = set.lamps().iter().map(|l| shader.lamp_reach2(l)).collect();
    shadowed_lamp_sum(scene, shader, rays, which, |d, h, out| {
        for (lamp, &reach2) in set.lamps().iter().zip(&reach2) {
            let to = lamp.centre - h.point;
            if to.length_squared() > reach2 || to.dot(h.normal) <= 0.0 {
                continue;
            }
            if let Some((value, l, r)) = shader.lamp_light(d, h, lamp) {
                out.push((value, l, r, lamp.radius));
            }
        }
    })
}
