//! The material a surface without one of its own gets from its semantic class (`crate::material` holds the
//! table of materials the assets carry): base colour, roughness and metallic per class, containers varied per
//! container-sized cell of space and vessels per instance by a seeded tint. Not a physical model: the colours are
//! chosen to look like their classes (sand, vegetation, concrete, containers, buoys, ...).

use super::super::noise;
use super::SurfaceHit;
use crate::material::Material;
use parry3d::math::Vec3;

#[inline]
fn hash_tint(id: u64, seed: u64) -> Vec3 {
    let h = noise::hash3(seed, 0xC0105, id);
    let f = |s: u32| 0.55 + 0.45 * ((h >> s) & 0xFF) as f32 / 255.0;
    Vec3::new(f(0), f(8), f(16))
}

/// The material a face without one gets from its class: base colour (containers varied per container-sized
/// cell of space, vessels per instance), roughness, metallic.
#[inline]
pub fn class_material(hit: &SurfaceHit) -> Material {
    let (base, roughness, metallic) = match hit.class {
        2 => (Vec3::new(0.33, 0.27, 0.18), 0.9, 0.0),
        3 => (Vec3::new(0.07, 0.18, 0.05), 0.85, 0.0),
        4 => (Vec3::new(0.38, 0.38, 0.37), 0.8, 0.0),
        5 => {
            let p = hit.point;
            let cell = ((p.x / 6.1).floor() as i64 as u64).wrapping_mul(73_856_093)
                ^ ((p.y / 2.5).floor() as i64 as u64).wrapping_mul(19_349_663)
                ^ ((p.z / 2.6).floor() as i64 as u64).wrapping_mul(83_492_791);
            const PALETTE: [[f32; 3]; 6] = [
                [0.5, 0.08, 0.05],
                [0.05, 0.2, 0.45],
                [0.1, 0.35, 0.12],
                [0.6, 0.45, 0.05],
                [0.45, 0.45, 0.45],
                [0.5, 0.22, 0.05],
            ];
            (Vec3::from_array(PALETTE[(noise::hash3(5, 5, cell) % 6) as usize]), 0.5, 0.0)
        }
        6 => (Vec3::new(0.6, 0.42, 0.04), 0.45, 0.0),
        7 => (Vec3::new(0.75, 0.15, 0.08), 0.4, 0.0),
        8 => (Vec3::new(0.42, 0.4, 0.38), 0.8, 0.0),
        10 => (Vec3::new(0.62, 0.62, 0.62) * hash_tint(hit.instance.max(0) as u64, 10), 0.5, 0.0),
        11 => (Vec3::new(0.15, 0.45, 0.45), 0.4, 0.0),
        _ => (Vec3::splat(0.3), 0.7, 0.0),
    };
    Material {
        base_color: base.to_array(),
        roughness,
        metallic,
        emissive: [0.0; 3],
        nav_light: false,
        arc_deg: [0.0, 180.0],
    }
}
