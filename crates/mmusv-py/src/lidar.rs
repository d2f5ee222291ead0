//! Bindings for `mmusv_core::sensors::lidar`: the spinning LiDAR, configured once; a sweep as a dict of numpy
//! columns.

use crate::native::{detached, pose_arg, rows_to_array};
use crate::shade::{wakes_arg, SensorEnv};
use mmusv_core::sensors::lidar;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Lidar>()?;
    Ok(())
}

/// A spinning multi-channel LiDAR with its ray pattern computed once (see `mmusv_core::sensors::lidar`).
#[pyclass(frozen, module = "mmusv._core")]
pub struct Lidar {
    pub(crate) inner: lidar::Lidar,
}

#[pymethods]
impl Lidar {
    #[new]
    #[pyo3(signature = (*, elevations, azimuth_steps, range_min, range_max, range_noise_std, dropout,
        water_probability, water_probability_per_wave_m, water_range_m, water_range_per_wave_m, beam_divergence))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        elevations: Vec<f64>,
        azimuth_steps: u32,
        range_min: f32,
        range_max: f32,
        range_noise_std: f32,
        dropout: f32,
        water_probability: f32,
        water_probability_per_wave_m: f32,
        water_range_m: f32,
        water_range_per_wave_m: f32,
        beam_divergence: f32,
    ) -> PyResult<Self> {
        let cfg = lidar::LidarConfig {
            elevations,
            azimuth_steps,
            range_min,
            range_max,
            range_noise_std,
            dropout,
            water_probability,
            water_probability_per_wave_m,
            water_range_m,
            water_range_per_wave_m,
            beam_divergence,
        };
        Ok(Self { inner: lidar::Lidar::new(cfg).map_err(crate::errors::to_py)? })
    }

    /// Number of rays in one sweep (channels × azimuth steps).
    #[getter]
    fn num_rays(&self) -> usize {
        self.inner.pattern().len()
    }

    /// `(channels·azimuth_steps, 3)` float32 unit directions of the pattern, LiDAR frame, azimuth-major.
    fn pattern<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        rows_to_array(py, self.inner.pattern().to_vec())
    }

    /// One sweep on the current state of `scene` from the LiDAR at `pose` (4×4 LiDAR → world) in `env` (the fog
    /// extinction, the rain's drops included, waves, wind and the rain rate are used). Returns a dict
    /// of equal-length columns: xyz (N,3) f32 LiDAR frame, range, intensity (f32), ring (u16), azimuth (f32
    /// rad), class (u16; 0 for a rain drop's return), instance (i32; -1 for a drop), ray_index (u32); and beam_instance (M,) i32: per ray of the full
    /// pattern, the instance its cast met first within the range (-1: none). `wakes` (K, 6) to (K, 9) float32
    /// rows `x, y, heading, speed, length, beam[, reach_m[, age_s[, displacement_m3]]]` (world metres, radians,
    /// m/s, s, m³; see `Camera.render`): the vessels under way, whose wake foam returns over a wave surface.
    #[pyo3(signature = (scene, *, pose, env, seed, wakes=None))]
    fn scan<'py>(
        &self,
        py: Python<'py>,
        scene: &crate::scene::Scene,
        pose: PyReadonlyArray2<'py, f64>,
        env: &SensorEnv,
        seed: u64,
        wakes: Option<PyReadonlyArray2<'py, f32>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pose = pose_arg(&pose, "pose")?;
        let wakes = wakes_arg(wakes.as_ref())?;
        let env = env.lidar();
        let s = scene.read(|s| detached(py, || self.inner.scan_with_wakes(s, &pose, &env, seed, &wakes)))?;
        scan_dict(py, s)
    }
}

/// The dict of one sweep as `Lidar.scan` returns it (columns moved into numpy, no copy).
pub(crate) fn scan_dict(py: Python<'_>, s: lidar::LidarScan) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("xyz", rows_to_array(py, s.xyz)?)?;
    d.set_item("range", s.range.into_pyarray(py))?;
    d.set_item("intensity", s.intensity.into_pyarray(py))?;
    d.set_item("ring", s.ring.into_pyarray(py))?;
    d.set_item("azimuth", s.azimuth.into_pyarray(py))?;
    d.set_item("class", s.class.into_pyarray(py))?;
    d.set_item("instance", s.instance.into_pyarray(py))?;
    d.set_item("ray_index", s.ray_index.into_pyarray(py))?;
    d.set_item("beam_instance", s.beam_instance.into_pyarray(py))?;
    Ok(d)
}
