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
        Self::InvalidInput { field: field.into(), reason: short_numbers(reason.into()) }
    }
    /// Shorthand for [`MmusvError::Geometry`].
    pub fn geometry(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Geometry { field: field.into(), reason: short_numbers(reason.into()) }
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
        Self::Config {
            field: field.into(),
            value: short_numbers(value.to_string()),
            reason: short_numbers(reason.into()),
        }
    }
}

/// Most digits a number keeps in a message: Rust prints a float in full, so `1e300` (given by a user, or an
/// `f64::MAX` bound) came out as 301 digits that hid the rest of the message, and `1e-300` as 302 characters of
/// `0.000…1`. Integers up to `u128` fit.
const MAX_MESSAGE_DIGITS: usize = 40;

/// `text` with every number of more than [`MAX_MESSAGE_DIGITS`] digits before or after its point written short,
/// as `1.7976931348623157e308` or `1e-300`.
fn short_numbers(text: String) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if !b[i].is_ascii_digit() || (i > 0 && (b[i - 1].is_ascii_digit() || b[i - 1] == b'.')) {
            let ch = text[i..].chars().next().unwrap_or(' ');
            out.push(ch);
            i += ch.len_utf8();
            continue;
        }
        let start = i;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        let mut digits = i - start;
        if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
            i += 1;
            let point = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            digits = digits.max(i - point);
        }
        match text[start..i].parse::<f64>() {
            Ok(v) if digits > MAX_MESSAGE_DIGITS => out.push_str(&format!("{v:e}")),
            _ => out.push_str(&text[start..i]),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_numbers_are_written_short_and_the_rest_kept() {
        let e = MmusvError::config("radar.detection_threshold", -1.0, format!("must be in [0, {}]", f64::MAX));
        assert_eq!(
            e.to_string(),
            "invalid config radar.detection_threshold = -1: must be in [0, 1.7976931348623157e308]"
        );
        let e = MmusvError::config("hs_m", 1e300, "must be in [0, 25] m");
        assert_eq!(e.to_string(), "invalid config hs_m = 1e300: must be in [0, 25] m");
        let t = format!("translation {} and seed {} at 0.25 é 3", 1e300 + 0.5, u64::MAX);
        let e = MmusvError::input("pose", t);
        assert_eq!(e.to_string(), "invalid pose: translation 1e300 and seed 18446744073709551615 at 0.25 é 3");
        // Tiny ones too (`0.000…1`, 302 characters for 1e-300), and the shortest float; ordinary decimals kept.
        let t = format!("{} and {} but {} in 0.25 s", 1e-300, 5e-324, 0.1 + 0.2);
        let e = MmusvError::input("omega", t);
        assert_eq!(e.to_string(), "invalid omega: 1e-300 and 5e-324 but 0.30000000000000004 in 0.25 s");
    }
}
