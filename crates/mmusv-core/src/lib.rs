//! # mmusv-core
//!
//! The plain-Rust heart of mmusv, a headless maritime simulator for multi-USV cooperative perception.
//! It has no Python in it: the `mmusv-py` crate wraps it for Python, and `cargo test -p mmusv-core`
//! runs on its own.
//!
//! Modules, one job each:
//! - [`error`]: the one error enum every fallible call returns.
//! - [`geometry`]: rigid poses, rays and the ray–triangle test.
//! - [`bvh`]: the 4-wide traversal layout flattened from parry's BVH.
//! - [`packet`]: coherent rays traced together.
//! - [`mesh`]: triangle meshes with per-face semantic classes and a parry bottom-level BVH built once.
//! - [`scene`]: meshes placed as instances, a top-level BVH over them, and batch ray casting over rayon.
//! - [`export`]: the world triangles at the current poses as PLY or OBJ.
//! - [`sensors`]: sensor ray patterns (LiDAR sweeps, pinhole cameras), the marine radar and its PPI image.
//! - [`record`]: the MCAP recorder (Foxglove schemas plus the project's own world state and annotations).
//! - [`demo`]: a synthetic maritime scene for benchmarks and comparisons.
//! - [`kinematics`]: spline routes at nominal speed with wave-driven heave, roll and pitch.
//!
//! Conventions: metres, seconds, radians; world frame right-handed, x east, y north, z up, water at z = 0.

#[allow(
    clippy::needless_range_loop,
    reason = "4-wide lane loops index several per-lane arrays at once; an iterator over one of them hides the layout"
)]
pub mod bvh;
pub mod demo;
pub mod error;
pub mod export;
pub mod geometry;
pub mod kinematics;
pub mod mesh;
#[allow(
    clippy::manual_range_contains,
    reason = "packet.rs is being rewritten (its owner's branch); its barycentric test reads as the maths there"
)]
pub mod packet;
pub mod record;
#[allow(
    clippy::needless_range_loop,
    reason = "packet lane loops index several per-ray arrays at once; an iterator over one of them hides the layout"
)]
pub mod scene;
pub mod sensors;

pub use error::{MmusvError, Result};
pub use geometry::RigidPose;
pub use mesh::Mesh;
pub use scene::{RayHits, Scene};
