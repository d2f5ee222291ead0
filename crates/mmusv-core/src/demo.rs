//! A synthetic maritime scene for benchmarks, examples and comparisons with other ray tracers.
//!
//! A seabed-and-islands heightfield (`terrain_cells²·2` triangles), a water plane at z = 0, and vessel
//! instances of three tessellated hull meshes (≈5 m, ≈40 m, ≈180 m) scattered on the water around an ego
//! USV at the origin. Deterministic from the seed. With the defaults the world holds 775,170 triangles.

use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::sensors::rays;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Semantic classes used by the demo scene (the same ids as `mmusv.classes`).
const WATER: u16 = 1;
const TERRAIN: u16 = 2;
const VEGETATION: u16 = 3;
const VESSEL: u16 = 10;

/// Parameters of [`maritime_demo`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemoParams {
    /// Seed of every random draw.
    pub seed: u64,
    /// Side of the square map in metres, centred on the origin.
    pub extent: f32,
    /// Heightfield cells per side (triangles = 2·cells²).
    pub terrain_cells: u32,
    /// Number of vessel instances.
    pub vessels: u32,
}

impl Default for DemoParams {
    fn default() -> Self {
        Self { seed: 1, extent: 2000.0, terrain_cells: 512, vessels: 48 }
    }
}

/// The demo scene and what a benchmark needs to cast into it.
#[derive(Debug, Clone)]
pub struct DemoScene {
    /// The scene: instance 0 is the terrain, 1 the water plane, then the vessels.
    pub scene: Scene,
    /// Instance ids of the vessels.
    pub vessel_instances: Vec<u32>,
}

struct Island {
    x: f32,
    y: f32,
    height: f32,
    sigma: f32,
}

fn height(islands: &[Island], x: f32, y: f32) -> f32 {
    let mut h = -25.0 + 3.0 * (x * 0.013).sin() * (y * 0.011).cos();
    for i in islands {
        let r2 = (x - i.x).powi(2) + (y - i.y).powi(2);
        h += i.height * (-r2 / (2.0 * i.sigma * i.sigma)).exp();
    }
    h
}

/// A closed, tessellated hull: `stations` rings of `ring` points along x, superelliptic sections,
/// tapering to a bow at +x. Length `length`, beam `beam`, from z = -draft to z = freeboard.
pub fn hull_mesh(
    name: &str,
    length: f32,
    beam: f32,
    draft: f32,
    freeboard: f32,
    stations: u32,
    ring: u32,
) -> Result<Mesh> {
    if stations < 2 || ring < 3 {
        return Err(MmusvError::input("stations/ring", "need at least 2 stations and 3 points per ring"));
    }
    let mut v: Vec<[f32; 3]> = Vec::new();
    let mut f: Vec<[i64; 3]> = Vec::new();
    let zc = (freeboard - draft) / 2.0;
    let hz = (freeboard + draft) / 2.0;
    for s in 0..stations {
        let u = s as f32 / (stations - 1) as f32;
        let x = -length / 2.0 + u * length;
        // Full beam aft, fine bow: half-width falls to 5 % at the stem.
        let taper = if u < 0.6 { 1.0 } else { 1.0 - 0.95 * ((u - 0.6) / 0.4).powf(1.6) };
        let w = beam / 2.0 * taper;
        for k in 0..ring {
            let th = std::f32::consts::TAU * k as f32 / ring as f32;
            let (sn, cs) = th.sin_cos();
            // Superellipse (exponent 0.5 ⇒ boxy) keeps a flat deck and bottom.
            let y = w * cs.signum() * cs.abs().powf(0.5);
            let z = zc + hz * sn.signum() * sn.abs().powf(0.5);
            v.push([x, y, z]);
        }
    }
    let r = ring as i64;
    for s in 0..(stations as i64 - 1) {
        for k in 0..r {
            let a = s * r + k;
            let b = s * r + (k + 1) % r;
            let c = a + r;
            let d = b + r;
            f.push([a, c, b]);
            f.push([b, c, d]);
        }
    }
    // End caps as fans around their centres.
    let stern_c = v.len() as i64;
    v.push([-length / 2.0, 0.0, zc]);
    let bow_c = v.len() as i64;
    v.push([length / 2.0, 0.0, zc]);
    let last = (stations as i64 - 1) * r;
    for k in 0..r {
        f.push([stern_c, (k + 1) % r, k]);
        f.push([bow_c, last + k, last + (k + 1) % r]);
    }
    Mesh::new(name, &v, &f, &[VESSEL])
}

/// Largest `terrain_cells` (a side: 4096² cells, 33 million terrain triangles) and `vessels` of the demo scene.
pub const MAX_DEMO_SIZE: u32 = 4096;

/// Builds the demo scene. Errors name `terrain_cells` (1..=[`MAX_DEMO_SIZE`]), `vessels` (at most
/// [`MAX_DEMO_SIZE`]) or `extent` (at least 100 m).
pub fn maritime_demo(p: DemoParams) -> Result<DemoScene> {
    if p.terrain_cells == 0 || p.terrain_cells > MAX_DEMO_SIZE {
        let why = format!("{} cells a side; give 1..={MAX_DEMO_SIZE}", p.terrain_cells);
        return Err(MmusvError::input("terrain_cells", why));
    }
    if p.vessels > MAX_DEMO_SIZE {
        return Err(MmusvError::input("vessels", format!("{} vessels; give 0..={MAX_DEMO_SIZE}", p.vessels)));
    }
    if !(p.extent >= 100.0 && p.extent.is_finite()) {
        return Err(MmusvError::input(
            "extent",
            format!("{} m is too small; the demo scene needs extent >= 100 m", p.extent),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    let islands: Vec<Island> = (0..7)
        .map(|_| {
            let a = rng.random_range(0.0..std::f32::consts::TAU);
            let r = rng.random_range(0.2..0.45) * p.extent;
            Island {
                x: r * a.cos(),
                y: r * a.sin(),
                height: rng.random_range(45.0..95.0),
                sigma: rng.random_range(0.03..0.07) * p.extent,
            }
        })
        .collect();
    let n = p.terrain_cells as usize;
    let step = p.extent / n as f32;
    let half = p.extent / 2.0;
    let mut tv = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let x = -half + i as f32 * step;
            let y = -half + j as f32 * step;
            tv.push([x, y, height(&islands, x, y)]);
        }
    }
    let mut tf = Vec::with_capacity(2 * n * n);
    let mut tc = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let a = (j * (n + 1) + i) as i64;
            let b = a + 1;
            let c = a + (n + 1) as i64;
            let d = c + 1;
            tf.push([a, b, d]);
            tf.push([a, d, c]);
            let zmax = tv[a as usize][2].max(tv[d as usize][2]);
            let class = if zmax > 20.0 { VEGETATION } else { TERRAIN };
            tc.push(class);
            tc.push(class);
        }
    }
    let mut scene = Scene::new();
    let terrain = scene.add_mesh(Mesh::new("terrain", &tv, &tf, &tc)?);
    scene.add_instance(terrain, RigidPose::IDENTITY, None)?;
    let water = scene.add_mesh(Mesh::new(
        "water",
        &[[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]],
        &[[0, 1, 2], [0, 2, 3]],
        &[WATER],
    )?);
    scene.add_instance(water, RigidPose::IDENTITY, None)?;
    let hulls = [
        scene.add_mesh(hull_mesh("boat_5m", 5.0, 2.0, 0.4, 1.2, 40, 24)?),
        scene.add_mesh(hull_mesh("ship_40m", 40.0, 9.0, 2.5, 6.0, 80, 32)?),
        scene.add_mesh(hull_mesh("ship_180m", 180.0, 28.0, 9.0, 18.0, 160, 48)?),
    ];
    let mut vessel_instances = Vec::new();
    let mut placed = 0;
    let mut attempts = 0;
    while placed < p.vessels && attempts < 100_000 {
        attempts += 1;
        let kind = if placed % 6 == 5 {
            2
        } else if placed % 3 == 1 {
            1
        } else {
            0
        };
        let r = rng.random_range(25.0..(0.4 * p.extent));
        let a = rng.random_range(0.0..std::f32::consts::TAU);
        let (x, y) = (r * a.cos(), r * a.sin());
        if height(&islands, x, y) > -12.0 {
            continue;
        }
        let yaw = rng.random_range(0.0..std::f64::consts::TAU);
        let pose = RigidPose::from_xyz_rpy([x as f64, y as f64, 0.0], [0.0, 0.0, yaw]);
        vessel_instances.push(scene.add_instance(hulls[kind], pose, None)?);
        placed += 1;
    }
    Ok(DemoScene { scene, vessel_instances })
}

/// Origins and unit directions of a set of rays: `(origins, directions)`, each `(N, 3)`, world frame, metres.
pub type Rays = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// Origins and unit directions of one sweep (`channels` beams over −25°…+15°, `azimuth_steps` columns) from a
/// LiDAR at `position` with the body axes aligned to the world, in [`rays::lidar_trace_order`] (blocks of 8
/// columns), the order the LiDAR sensor traces them in.
pub fn lidar_rays(position: [f32; 3], channels: u32, azimuth_steps: u32) -> Result<Rays> {
    let el = rays::uniform_elevations(channels, (-25f64).to_radians(), 15f64.to_radians())?;
    let dirs = rays::lidar_directions(&el, azimuth_steps)?;
    let order = rays::lidar_trace_order(channels, azimuth_steps, rays::TRACE_BLOCK)?;
    let traced: Vec<[f32; 3]> = order.iter().map(|&i| dirs[i as usize]).collect();
    Ok((vec![position; traced.len()], traced))
}

/// Origins and unit world directions of `count` surround pinhole cameras (yaw 0, 360/count, ...) at `position`.
pub fn surround_camera_rays(position: [f32; 3], count: u32, width: u32, height: u32, hfov: f64) -> Result<Rays> {
    let body = rays::pinhole_directions(width, height, hfov)?;
    let mut dirs = Vec::with_capacity(body.len() * count as usize);
    for c in 0..count {
        let pose = RigidPose::from_xyz_rpy([0.0; 3], [0.0, 0.0, std::f64::consts::TAU * c as f64 / count as f64]);
        dirs.extend(body.iter().map(|d| pose.transform_vector(parry3d::math::Vec3::from_array(*d)).to_array()));
    }
    Ok((vec![position; dirs.len()], dirs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_is_deterministic_and_sized() {
        let p = DemoParams { terrain_cells: 64, vessels: 12, ..DemoParams::default() };
        let a = maritime_demo(p).unwrap_or_else(|e| unreachable!("{e}"));
        let b = maritime_demo(p).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(a.scene.world_mesh(), b.scene.world_mesh());
        assert_eq!(a.vessel_instances.len(), 12);
        let (o, d) = lidar_rays([0.0, 0.0, 2.5], 16, 256).unwrap_or_default();
        let hits = a.scene.cast_rays(&o, &d, 2000.0).unwrap_or_default();
        // Downward beams hit the water around the ego.
        assert!(hits.class.iter().filter(|&&c| c == WATER).count() > 256);
        let full = DemoParams::default();
        let cells = full.terrain_cells as usize;
        assert!(2 * cells * cells > 500_000);
    }

    /// Sizes past the bounds are refused before anything is allocated, naming the parameter.
    #[test]
    fn oversized_demos_are_refused() {
        for (p, field) in [
            (DemoParams { terrain_cells: 0, ..DemoParams::default() }, "terrain_cells"),
            (DemoParams { terrain_cells: 1_000_000, ..DemoParams::default() }, "terrain_cells"),
            (DemoParams { vessels: 1_000_000_000, ..DemoParams::default() }, "vessels"),
            (DemoParams { extent: f32::NAN, ..DemoParams::default() }, "extent"),
        ] {
            let Err(e) = maritime_demo(p) else { panic!("{p:?} was accepted") };
            assert!(e.to_string().contains(field), "{p:?}: {e}");
        }
    }
}
