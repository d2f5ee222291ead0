//! Recording to MCAP: every USV's sensors and the world state of each frame streamed into one file that
//! opens in Foxglove and decodes with the `mcap` + `mcap-protobuf-support` Python readers.
//!
//! - [`writer`]: the file (`.partial` name until finished, zstd chunks, lazy channels, metadata).
//! - [`messages`]: one [`Recorder`] method per message kind (Foxglove well-known schemas and our own).
//! - [`own_schema`]: `mmusv.WorldState` / `mmusv.AgentAnnotations` and their descriptor set.
//! - [`points`]: packed point layouts; [`image`]: pixel kinds and PNG encoding.
//! - [`batch`]: images encoded in parallel outside the recorder, then appended in order.
//!
//! Times are simulation times in nanoseconds given by the caller (log time = publish time); the same calls
//! give byte-identical files. Schemas and topics are described in `docs/recording.md`.

pub mod batch;
pub mod image;
pub mod messages;
pub mod own_schema;
pub mod points;
pub mod writer;

#[cfg(test)]
mod tests;

pub use batch::{encode_images, ImageFormat, ImageJob};
pub use image::Pixels;
pub use messages::{BoxMarker, ImageBox, Transform};
pub use own_schema::{AgentAnnotations, BevBox, Box2D, Box3D, VesselState, WorldState};
pub use points::{pack_columns, Column, PackedPoints, PackedType};
pub use writer::{partial_path, EncodedMessage, RecordSummary, Recorder};
