//! Bindings of `mmusv_core::simd`: which of the core's code paths this process runs.

use pyo3::prelude::*;

/// The core's code paths in this process: `"avx2"` (AVX2 + FMA, picked where the CPU has them) or `"portable"`
/// (any x86-64, or forced by `MMUSV_SIMD=portable` in the environment before the first call). Every level gives
/// the same bytes; benchmarks report it.
#[pyfunction]
fn simd_level() -> &'static str {
    mmusv_core::simd::level_name()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simd_level, m)?)
}
