//! Bindings for `mmusv_core::kinematics` (filled in once the core module lands).

use pyo3::prelude::*;

pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
