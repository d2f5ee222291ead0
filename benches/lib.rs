//! Shared fixtures for the mmusv criterion benchmarks: the synthetic maritime scene and the ray sets
//! (one 64×2048 LiDAR sweep; four 640×480 surround cameras) cast from an ego USV at the origin.

use mmusv_core::demo::{lidar_rays, maritime_demo, surround_camera_rays, DemoParams, DemoScene};
use mmusv_core::{Mesh, Result, RigidPose, Scene};

/// LiDAR mount height above the waterline, metres.
pub const LIDAR_HEIGHT: f32 = 2.5;
/// Camera mount height above the waterline, metres.
pub const CAMERA_HEIGHT: f32 = 2.0;
/// Radar antenna height above the waterline, metres.
pub const RADAR_HEIGHT: f32 = 3.0;

/// Rays as parallel origin / direction arrays.
pub type Rays = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// The benchmark scene (defaults of [`DemoParams`]: 775,170 triangles, 48 vessel instances).
pub fn scene() -> Result<DemoScene> {
    maritime_demo(DemoParams::default())
}

/// [`scene`] with the sea declared as `mmusv` worlds declare it (instance 1 the water plane, the vessels moving),
/// so the sea shortcuts apply.
pub fn sea_scene() -> Result<DemoScene> {
    let mut demo = scene()?;
    demo.scene.set_sea(1, &demo.vessel_instances)?;
    Ok(demo)
}

/// One 64-channel × 2048-azimuth LiDAR sweep.
pub fn lidar() -> Result<Rays> {
    lidar_rays([0.0, 0.0, LIDAR_HEIGHT], 64, 2048)
}

/// Four 640×480 pinhole cameras with 90° horizontal FOV looking forward, left, back, right.
pub fn cameras() -> Result<Rays> {
    surround_camera_rays([0.0, 0.0, CAMERA_HEIGHT], 4, 640, 480, std::f64::consts::FRAC_PI_2)
}

/// The triangles of `scene` at their current poses as one mesh in a scene of its own (one instance at the
/// identity pose, per-face classes kept): the "single-mesh" layout of the benchmarks.
pub fn single_mesh(scene: &Scene) -> Result<Scene> {
    let w = scene.world_mesh();
    let faces: Vec<[i64; 3]> = w.faces.iter().map(|f| [i64::from(f[0]), i64::from(f[1]), i64::from(f[2])]).collect();
    let mut out = Scene::new();
    let mesh = out.add_mesh(Mesh::new("world", &w.vertices, &faces, &w.classes)?);
    out.add_instance(mesh, RigidPose::IDENTITY, None)?;
    Ok(out)
}
