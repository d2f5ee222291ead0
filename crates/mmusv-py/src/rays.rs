//! Bindings for `mmusv_core::sensors::rays`: the pinhole camera's intrinsics and ray directions, the LiDAR's
//! elevations, sweep directions and trace order.

use crate::native::{detached, rows_to_array};
use mmusv_core::sensors::rays;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;

/// `[fx, fy, cx, cy]` (pixels) of a pinhole camera of `width × height` and horizontal FOV `hfov` (radians).
#[pyfunction]
#[pyo3(signature = (*, width, height, hfov))]
fn pinhole_intrinsics<'py>(py: Python<'py>, width: u32, height: u32, hfov: f64) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let k = rays::pinhole_intrinsics(width, height, hfov).map_err(crate::errors::to_py)?;
    Ok(k.to_vec().into_pyarray(py))
}

/// `(width·height, 3)` float32 unit ray directions through pixel centres, camera body frame, row-major.
/// Test and benchmark helper (private in Python: `_pinhole_directions`).
#[pyfunction]
#[pyo3(name = "_pinhole_directions", signature = (*, width, height, hfov))]
fn pinhole_directions<'py>(py: Python<'py>, width: u32, height: u32, hfov: f64) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let d = detached(py, || rays::pinhole_directions(width, height, hfov))?;
    rows_to_array(py, d)
}

/// `(azimuth_steps·len(elevations), 3)` float32 unit directions of one sweep, LiDAR frame, azimuth-major.
/// Test and benchmark helper (private in Python: `_lidar_directions`).
#[pyfunction]
#[pyo3(name = "_lidar_directions", signature = (*, elevations, azimuth_steps))]
fn lidar_directions<'py>(
    py: Python<'py>,
    elevations: Vec<f64>,
    azimuth_steps: u32,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let d = detached(py, || rays::lidar_directions(&elevations, azimuth_steps))?;
    rows_to_array(py, d)
}

/// Elevation angles (radians), lowest first, of `channels` beams spread uniformly over `[lower, upper]`.
#[pyfunction]
#[pyo3(signature = (*, channels, lower, upper))]
fn uniform_elevations<'py>(
    py: Python<'py>,
    channels: u32,
    lower: f64,
    upper: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let e = rays::uniform_elevations(channels, lower, upper).map_err(crate::errors::to_py)?;
    Ok(e.into_pyarray(py))
}

/// `(channels·azimuth_steps,)` uint32: the packet-friendly trace order of a sweep (indices into the
/// azimuth-major order of `lidar_directions`), blocks of `block` neighbouring columns.
#[pyfunction]
#[pyo3(signature = (*, channels, azimuth_steps, block=8))]
fn lidar_trace_order<'py>(
    py: Python<'py>,
    channels: u32,
    azimuth_steps: u32,
    block: u32,
) -> PyResult<Bound<'py, PyArray1<u32>>> {
    let order = detached(py, || rays::lidar_trace_order(channels, azimuth_steps, block))?;
    Ok(order.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pinhole_intrinsics, m)?)?;
    m.add_function(wrap_pyfunction!(pinhole_directions, m)?)?;
    m.add_function(wrap_pyfunction!(lidar_directions, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_elevations, m)?)?;
    m.add_function(wrap_pyfunction!(lidar_trace_order, m)?)?;
    Ok(())
}
