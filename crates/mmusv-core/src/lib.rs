//! # mmusv-core
//!
//! The plain-Rust heart of mmusv, a headless maritime simulator for multi-USV cooperative perception.
//! It has no Python in it: the `mmusv-py` crate wraps it for Python, and `cargo test -p mmusv-core`
//! runs on its own.
//!
//! Modules, one job each:
//! - [`error`]: the one error enum every fallible call returns.
//! - [`geometry`]: rigid poses and the watertight ray–triangle test (one triangle or a block of four).
//! - [`ray`]: a ray prepared once for its box and triangle tests.
//! - [`bvh`]: binned-SAH BVHs collapsed to 8-wide nodes, traversed nearest child first.
//! - [`simd`]: run-time CPU feature dispatch (AVX2 where available, portable otherwise).
//! - [`threads`]: thread pools that survive `fork()` (a forked child runs its parallel work on a pool of its own).
//! - [`seabed`]: the seabed's heights under the water, for the cameras' shallow-water optics.
//! - [`sea`]: exact shortcuts for rays that can only meet the sea surface or the sky (a height bound map).
//! - [`mesh`]: triangle meshes with per-face semantic classes and a bottom-level BVH built once.
//! - [`material`]: surface materials (base colour, roughness, metallic, emission) for the cameras' shading.
//! - [`sky_visibility`]: the sky's visibility over a mesh's own surfaces (ambient occlusion), baked once per mesh.
//! - [`scene`]: meshes placed as instances, a top-level BVH over them, and batch ray casting over rayon.
//! - [`export`]: the world triangles at the current poses as PLY or OBJ.
//! - [`sensors`]: sensor ray patterns (LiDAR sweeps, pinhole cameras), the marine radar and its PPI image.
//! - [`record`]: the MCAP recorder (Foxglove schemas plus the project's own world state and annotations).
//! - [`demo`]: a synthetic maritime scene for benchmarks and comparisons.
//! - [`kinematics`]: spline routes at nominal speed with wave-driven heave, roll and pitch.
//! - [`ocean`]: the physical sea (JONSWAP spectrum, seeded wave field) and the vessels' response to it.
//!
//! Conventions: metres, seconds, radians; world frame right-handed, x east, y north, z up, water at z = 0.
//!
//! ## Example
//!
//! A sea plane and a 10 m box of a hull 60 m east; a 64-channel LiDAR 2 m above the water sweeps them, and a
//! 64 × 48 camera looking east renders depth, semantic classes and instances (RGB too, with `rgb: true`):
//!
//! ```
//! use mmusv_core::sensors::camera::{Camera, CameraConfig, Projection};
//! use mmusv_core::sensors::lidar::{Lidar, LidarConfig, LidarEnv};
//! use mmusv_core::sensors::shade::ShadeEnv;
//! use mmusv_core::{Mesh, RigidPose, Scene};
//!
//! # fn main() -> mmusv_core::Result<()> {
//! let mut scene = Scene::new();
//! // The sea: two triangles of class 1 (water), declared the sea surface so the exact shortcuts apply.
//! let sea = [[-500.0, -500.0, 0.0], [500.0, -500.0, 0.0], [500.0, 500.0, 0.0], [-500.0, 500.0, 0.0]];
//! let water = scene.add_mesh(Mesh::new("sea", &sea, &[[0, 1, 2], [0, 2, 3]], &[1, 1])?);
//! let sea_id = scene.add_instance(water, RigidPose::IDENTITY, None)?;
//! // A hull: a 10 m cube (class 2) from 55 to 65 m east, standing 1 m in the water; it will move.
//! let v: Vec<[f32; 3]> = (0..8)
//!     .map(|i| [(i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32])
//!     .map(|[x, y, z]| [55.0 + 10.0 * x, -5.0 + 10.0 * y, -1.0 + 10.0 * z])
//!     .collect();
//! let f = [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4]];
//! let f = [f.as_slice(), &[[2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]]].concat();
//! let hull = scene.add_mesh(Mesh::new("hull", &v, &f, &[2; 12])?);
//! let hull_id = scene.add_instance(hull, RigidPose::IDENTITY, None)?;
//! scene.set_sea(sea_id, &[hull_id])?;
//!
//! // One ray east from 2 m up meets the hull's face at x = 55.
//! let hits = scene.cast_rays(&[[0.0, 0.0, 2.0]], &[[1.0, 0.0, 0.0]], 200.0)?;
//! assert_eq!((hits.instance[0], hits.class[0]), (hull_id as i32, 2));
//! assert!((hits.distance[0] - 55.0).abs() < 1e-4);
//!
//! // A LiDAR sweep (the paper's 64 channels over [-25°, 15°], 0.5–200 m), points in the LiDAR's frame.
//! let lidar = Lidar::new(LidarConfig::default())?;
//! let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]);
//! let scan = lidar.scan(&scene, &pose, &LidarEnv::default(), 7)?;
//! assert!(scan.instance.iter().any(|&i| i == hull_id as i32));
//!
//! // A camera: depth along the optical axis (x forward), classes and instances from the pixel centres.
//! let camera = Camera::new(CameraConfig {
//!     width: 64,
//!     height: 48,
//!     projection: Projection::Pinhole { hfov: 1.2 },
//!     range_max: 1000.0,
//!     image: Default::default(),
//! })?;
//! let frame = camera.render(&scene, &pose, &ShadeEnv::default(), false, 7)?;
//! let centre = 24 * 64 + 32;
//! assert_eq!(frame.semantic[centre], 2);
//! assert!((frame.depth[centre] - 55.0).abs() < 0.05);
//! # Ok(())
//! # }
//! ```

// SIMD-style code: loops over lanes index several parallel arrays at once (boxes, rays, triangles); iterating
// over one of them would hide the structure-of-arrays layout the compiler vectorises.
#![allow(clippy::needless_range_loop)]

pub mod bvh;
pub mod demo;
pub mod error;
pub mod export;
pub mod geometry;
pub mod kinematics;
pub mod material;
pub mod mesh;
pub mod ocean;
pub mod ray;
pub mod record;
pub mod scene;
pub mod sea;
pub mod seabed;
pub mod sensors;
pub mod simd;
pub mod sky_visibility;
pub mod threads;

pub use error::{MmusvError, Result};
pub use geometry::RigidPose;
pub use mesh::Mesh;
pub use scene::{RayHits, Scene};
