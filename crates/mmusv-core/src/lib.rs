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
//! - [`scene`]: meshes placed as instances, a top-level BVH over them, and batch ray casting over rayon.
//! - [`export`]: the world triangles at the current poses as PLY or OBJ.
//! - [`sensors`]: sensor ray patterns (LiDAR sweeps, pinhole cameras), the marine radar and its PPI image.
//! - [`record`]: the MCAP recorder (Foxglove schemas plus the project's own world state and annotations).
//! - [`demo`]: a synthetic maritime scene for benchmarks and comparisons.
//! - [`kinematics`]: spline routes at nominal speed with wave-driven heave, roll and pitch.
//! - [`ocean`]: the physical sea (JONSWAP spectrum, seeded wave field) and the vessels' response to it.
//!
//! Conventions: metres, seconds, radians; world frame right-handed, x east, y north, z up, water at z = 0.

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
pub mod threads;

pub use error::{MmusvError, Result};
pub use geometry::RigidPose;
pub use mesh::Mesh;
pub use scene::{RayHits, Scene};
