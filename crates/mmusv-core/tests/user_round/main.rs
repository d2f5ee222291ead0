//! A user's round through the public API of `mmusv-core`, written from its rustdoc alone.
//!
//! (a) Results are checked against independent computations written here (analytic ray–triangle, ray–box and
//! ray–plane hits, a LiDAR's pattern from its documented configuration, a camera's pinhole projection, the wave
//! field as the documented sum of components, a route's length and arrival time, a recording read back).
//! (b) Bad input (NaN, infinities, huge, zero, negative, empty) must come back as an `Err` naming the field: never
//! a panic, an abort, a hang or a silently wrong value. Every call is made under `catch_unwind`, so a panic is a
//! test failure that says which call panicked.
//!
//! The round is one test binary split by concern: `common` holds the shared helpers and reference maths, and
//! each other module checks one part of the API: `poses`, `meshes` (meshes and scenes: analytic hits), `lidar`,
//! `cameras`, `radar` (radar and PPI), `wave_field`, `kinematics`, `recording` and `wave_surface` (the wave
//! surface in a scene).

// The reference computations index small fixed-size arrays by axis, as the formulas are written.
#![allow(clippy::needless_range_loop)]

mod common;

mod cameras;
mod kinematics;
mod lidar;
mod meshes;
mod poses;
mod radar;
mod recording;
mod wave_field;
mod wave_surface;
