//! Bindings for `mmusv_core::demo`: the synthetic maritime benchmark scene.

use crate::native::detached;
use crate::scene::Scene;
use mmusv_core::demo::{maritime_demo, DemoParams};
use pyo3::prelude::*;

/// Builds the synthetic maritime scene (terrain + water + vessel instances) used by the benchmarks.
/// Returns `(scene, vessel_instance_ids)`.
#[pyfunction]
#[pyo3(signature = (*, seed=1, extent=2000.0, terrain_cells=512, vessels=48))]
fn demo_scene(py: Python<'_>, seed: u64, extent: f32, terrain_cells: u32, vessels: u32) -> PyResult<(Scene, Vec<u32>)> {
    let demo = detached(py, || maritime_demo(DemoParams { seed, extent, terrain_cells, vessels }))?;
    Ok((Scene::from_core(demo.scene), demo.vessel_instances))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MAX_DEMO_SIZE", mmusv_core::demo::MAX_DEMO_SIZE)?;
    m.add_function(wrap_pyfunction!(demo_scene, m)?)
}
