//! `mmusv._core`: thin pyo3 bindings over `mmusv-core`.
//!
//! One binding file per core module; numpy arrays in and out (C-contiguous, canonical dtypes — the Python
//! package coerces before calling); every long call goes through [`native::detached`], which releases the
//! GIL and turns a panic into an exception; core errors map to the exception tree in [`errors`].

use pyo3::prelude::*;

mod camera;
mod capture;
mod demo;
mod errors;
mod kinematics;
mod lidar;
mod native;
mod ocean;
mod radar;
mod rays;
mod record;
mod scene;
mod shade;
mod simd;

/// The compiled core of mmusv. Use the `mmusv` package rather than this module directly.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // This process runs the core's parallel work on rayon's global pool; a child forked from it, on its own
    // (`mmusv_core::threads`: the parent's pool has no threads in the child).
    mmusv_core::threads::set_owner();
    errors::register(m)?;
    scene::register(m)?;
    kinematics::register(m)?;
    ocean::register(m)?;
    rays::register(m)?;
    shade::register(m)?;
    lidar::register(m)?;
    camera::register(m)?;
    radar::register(m)?;
    capture::register(m)?;
    record::register(m)?;
    demo::register(m)?;
    simd::register(m)?;
    Ok(())
}
