//! The physical sea: one spectrum-driven wave field for every consumer, and the vessel response to it.
//!
//! - [`spectrum`]: JONSWAP / Pierson–Moskowitz frequency spectra and cos-2s directional spreading.
//! - [`field`]: [`WaveField`], a seeded sum of linear deep-water waves realising a [`SeaSpec`]: elevation, slope
//!   and orbital velocity anywhere, at any time, and a hard crest bound.
//!
//! Conventions: metres, seconds, radians; world frame x east, y north, z up, mean water level z = 0; wave
//! directions are the directions the waves travel towards, counter-clockwise from +x.

pub mod field;
pub mod spectrum;

pub use field::{sea_seed, SeaSpec, WaveComponent, WaveField, DEFAULT_COMPONENTS};
pub use spectrum::{CosTwoS, Jonswap, GRAVITY};
