//! The physical sea: one spectrum-driven wave field for every consumer, and the vessel response to it.
//!
//! - [`spectrum`]: JONSWAP / Pierson–Moskowitz frequency spectra and cos-2s directional spreading.
//! - [`field`]: [`WaveField`], a seeded sum of linear deep-water waves realising a [`SeaSpec`]: elevation, slope
//!   and orbital velocity anywhere, at any time, and a hard crest bound.
//! - [`presets`]: WMO sea state codes 0–9 and the paper's W0–W3 as (Hs, Tp, γ, wind), fully developed seas.
//! - [`response`](mod@response): [`Hull`] particulars and closed-form RAOs (Jensen, Mansour & Olsen 2004 heave and pitch, a
//!   1-DOF roll oscillator), hull responses in the field, and their spectral prediction.
//!
//! Conventions: metres, seconds, radians; world frame x east, y north, z up, mean water level z = 0; wave
//! directions are the directions the waves travel towards, counter-clockwise from +x.

pub mod field;
pub mod presets;
pub mod response;
pub mod spectrum;

pub use field::{sea_seed, SeaSpec, WaveComponent, WaveField, DEFAULT_COMPONENTS};
pub use presets::{paper_sea_states, wmo_sea_states, SeaPreset};
pub use response::{response, response_variance, Hull, Rao};
pub use spectrum::{CosTwoS, Jonswap, GRAVITY};
