//! `mmusv._core`: thin pyo3 bindings over `mmusv-core`.
//!
//! One binding file per core module; numpy arrays in and out (C-contiguous, canonical dtypes — the Python
//! package coerces before calling); every long call goes through [`native::detached`], which releases the
//! GIL and turns a panic into an exception; core errors map to the exception tree in [`errors`].

use pyo3::prelude::*;

mod capture;
mod demo;
mod errors;
mod kinematics;
mod native;
mod ocean;
mod radar;
mod record;
mod scene;
mod sensors;

/// The compiled core of mmusv. Use the `mmusv` package rather than this module directly.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    scene::register(m)?;
    kinematics::register(m)?;
    ocean::register(m)?;
    sensors::register(m)?;
    radar::register(m)?;
    capture::register(m)?;
    record::register(m)?;
    demo::register(m)?;
    Ok(())
}
