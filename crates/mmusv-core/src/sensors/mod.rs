//! Sensors. [`rays`] generates the ray patterns (spinning LiDAR, pinhole camera) every sensor casts.

pub mod rays;
