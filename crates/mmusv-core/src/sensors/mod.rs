//! Sensors, all sampling one frozen [`crate::Scene`] state:
//! - [`rays`]: ray patterns (spinning LiDAR sweeps, pinhole cameras);
//! - [`lidar`]: the spinning multi-channel LiDAR with noise, dropout, water returns and weather
//!   ([`lidar_water`]: returns from the displaced sea surface; [`lidar_rain`]: returns from rain drops);
//! - [`camera`]: pinhole and orthographic (top-view) cameras giving depth, semantic, instance and RGB;
//! - [`radar`]: the rotating ray-cast marine radar ([`radar_model`]: its intensity, rain and clutter
//!   formulas) and [`ppi`]: the PPI image at a fixed metres-per-pixel scale;
//! - [`shade`]: the RGB shading model (sun, sky, water, shadows, fog, rain);
//! - [`capture`]: every sensor of a frame in one call, as concurrent tasks over rayon;
//! - [`noise`]: counter-based random draws, so results never depend on thread scheduling.

#[allow(clippy::neg_cmp_op_on_partial_ord, reason = "`!(x > 0.0)` rejects NaN on purpose; `partial_cmp` hides that")]
pub mod camera;
pub mod capture;
pub mod lidar;
pub mod lidar_rain;
pub mod lidar_water;
pub mod noise;
pub mod ppi;
pub mod radar;
pub mod radar_model;
pub mod rays;
pub mod shade;
