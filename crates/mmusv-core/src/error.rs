//! The error type of the core. Every message names the offending field or value and says what is allowed,
//! so that the Python layer can raise it unchanged.

use thiserror::Error;

/// Result alias used across the core.
pub type Result<T> = std::result::Result<T, MmusvError>;

/// Everything that can go wrong in the core. The binding crate maps each variant to a Python exception.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MmusvError {
    /// An input array or value has the wrong shape, length, or a value outside what is allowed.
    #[error("invalid {field}: {reason}")]
    InvalidInput {
        /// The argument or field at fault, e.g. `faces` or `directions[12]`.
        field: String,
        /// What is wrong and what is allowed.
        reason: String,
    },
    /// Geometry that cannot be used: an empty mesh, a face index out of range, a non-finite vertex.
    #[error("invalid geometry in {field}: {reason}")]
    Geometry {
        /// The mesh or array at fault.
        field: String,
        /// What is wrong and how to fix it.
        reason: String,
    },
    /// A mesh or instance id that the scene does not hold.
    #[error("unknown {kind} id {id}: {hint}")]
    UnknownId {
        /// `mesh` or `instance`.
        kind: &'static str,
        /// The id that was asked for.
        id: i64,
        /// Which ids exist.
        hint: String,
    },
    /// A configuration value (route, speed, wave setting, ...) outside what is allowed.
    #[error("invalid config {field} = {value}: {reason}")]
    Config {
        /// The config field at fault, e.g. `vessels[2].speed_mps`.
        field: String,
        /// The value given.
        value: String,
        /// What is allowed.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("I/O error on {path}: {reason}")]
    Io {
        /// The file involved.
        path: String,
        /// The operating system's message.
        reason: String,
    },
}

impl MmusvError {
    /// Shorthand for [`MmusvError::InvalidInput`].
    pub fn input(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::InvalidInput { field: field.into(), reason: reason.into() }
    }
    /// Shorthand for [`MmusvError::Geometry`].
    pub fn geometry(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Geometry { field: field.into(), reason: reason.into() }
    }
    /// The same error with `prefix.` put in front of its field name, e.g. `vessels[2].` + `speed_mps`.
    pub fn within(self, prefix: &str) -> Self {
        match self {
            Self::InvalidInput { field, reason } => Self::InvalidInput { field: format!("{prefix}.{field}"), reason },
            Self::Geometry { field, reason } => Self::Geometry { field: format!("{prefix}.{field}"), reason },
            Self::Config { field, value, reason } => Self::Config { field: format!("{prefix}.{field}"), value, reason },
            other @ (Self::UnknownId { .. } | Self::Io { .. }) => other,
        }
    }

    /// Shorthand for [`MmusvError::Config`].
    pub fn config(field: impl Into<String>, value: impl ToString, reason: impl Into<String>) -> Self {
        Self::Config { field: field.into(), value: value.to_string(), reason: reason.into() }
    }
}
