//! The one wrapper for every long native call, and array helpers.

use crate::errors::{to_py, InputError, InternalError};
use mmusv_core::RigidPose;
use numpy::ndarray::Array2;
use numpy::ndarray::Dimension;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Runs `f` with the GIL released; a core error becomes its Python exception, a panic an `InternalError`. In a
/// process forked from the one that imported mmusv, `f` runs on that process's own thread pool
/// ([`mmusv_core::threads::run`]: the parent's has no threads there).
pub fn detached<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    F: FnOnce() -> mmusv_core::Result<T> + Send,
    T: Send,
{
    let outcome = py.detach(|| catch_unwind(AssertUnwindSafe(|| mmusv_core::threads::run(f))));
    match outcome {
        Ok(result) => result.map_err(to_py),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(InternalError::new_err(format!(
                "internal error in mmusv (please report it with the input that caused it): {what}"
            )))
        }
    }
}

/// Borrows a C-contiguous `(N, K)` array as rows of `K`; `name` is used in the error.
pub fn rows<'a, T: numpy::Element, const K: usize>(
    arr: &'a PyReadonlyArray2<'_, T>,
    name: &str,
) -> PyResult<&'a [[T; K]]> {
    let shape = arr.shape();
    if shape[1] != K {
        return Err(InputError::new_err(format!("{name} must have shape (N, {K}), got {shape:?}")));
    }
    let flat = c_order(arr, name)?;
    let (chunks, rest) = flat.as_chunks::<K>();
    debug_assert!(rest.is_empty());
    Ok(chunks)
}

/// Borrows a C-contiguous 1-D array; `name` is used in the error.
pub fn flat<'a, T: numpy::Element>(arr: &'a PyReadonlyArray1<'_, T>, name: &str) -> PyResult<&'a [T]> {
    c_order(arr, name)
}

/// Borrows the elements of a C-contiguous array of any dimension, in row-major order; `name` is used in the
/// error. The one check every borrowed array goes through: numpy's own `as_slice` also accepts a Fortran-ordered
/// array, whose elements would then be read transposed (a `(4, 4)` pose as its transpose, `(N, K)` rows as
/// columns) without an error.
pub fn c_order<'a, T: numpy::Element, D: Dimension>(
    arr: &'a PyReadonlyArray<'_, T, D>,
    name: &str,
) -> PyResult<&'a [T]> {
    let refused = || {
        InputError::new_err(format!(
            "{name} must be a C-contiguous (row-major) array, got shape {:?} with strides {:?} (use \
             numpy.ascontiguousarray)",
            arr.shape(),
            arr.strides()
        ))
    };
    if !arr.is_c_contiguous() {
        return Err(refused());
    }
    arr.as_slice().map_err(|_| refused())
}

/// Refuses the first entry of `values` that is not finite, naming it `name[i]` with its value: the wave field's
/// point queries and the hull's RAOs return NaN for it, which every later sum would carry without a word.
pub fn all_finite(values: &[f64], name: &str) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(not_allowed(&format!("{name}[{i}]"), values[i], "a finite number")),
        None => Ok(()),
    }
}

/// [`all_finite`] over rows of `K`, naming the entry `name[i][j]`.
pub fn rows_finite<const K: usize>(rows: &[[f64; K]], name: &str) -> PyResult<()> {
    match rows.as_flattened().iter().position(|v| !v.is_finite()) {
        Some(n) => Err(not_allowed(&format!("{name}[{}][{}]", n / K, n % K), rows[n / K][n % K], "a finite number")),
        None => Ok(()),
    }
}

/// Refuses a time `t` (s) that is not finite, naming `name`.
pub fn finite_time(t: f64, name: &str) -> PyResult<()> {
    if t.is_finite() {
        return Ok(());
    }
    Err(not_allowed(name, t, "a finite time in seconds"))
}

/// The error of a number `value` that `field` does not take: "invalid FIELD: VALUE is not allowed; give WHAT",
/// the core's [`MmusvError::InvalidInput`](mmusv_core::MmusvError) (huge numbers written short).
pub fn not_allowed(field: &str, value: f64, what: &str) -> PyErr {
    to_py(mmusv_core::MmusvError::input(field, format!("{value} is not allowed; give {what}")))
}

/// A rigid pose from 16 row-major numbers of a 4×4 matrix; `field` names the argument in errors.
pub fn pose_from(m: &[f64], field: &str) -> PyResult<RigidPose> {
    let m: [f64; 16] = m.try_into().map_err(|_| InputError::new_err(format!("{field} must be a 4x4 matrix")))?;
    RigidPose::from_matrix_row_major(&m, field).map_err(to_py)
}

/// A rigid pose from a C-contiguous `(4, 4)` float64 array (body → world); `field` names the argument in errors.
pub fn pose_arg(pose: &PyReadonlyArray2<'_, f64>, field: &str) -> PyResult<RigidPose> {
    if pose.shape() != [4, 4] {
        return Err(InputError::new_err(format!("{field} must have shape (4, 4), got {:?}", pose.shape())));
    }
    let m = c_order(pose, field)?;
    pose_from(m, field)
}

/// Ray origins and unit directions, each an `(N, 3)` float32 numpy array.
pub type RayArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>);

/// Moves rows of `K` into a new owned `(N, K)` numpy array.
pub fn rows_to_array<'py, T: numpy::Element, const K: usize>(
    py: Python<'py>,
    rows: Vec<[T; K]>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let n = rows.len();
    Array2::from_shape_vec((n, K), rows.into_iter().flatten().collect())
        .map(|a| a.into_pyarray(py))
        .map_err(|e| InternalError::new_err(e.to_string()))
}
