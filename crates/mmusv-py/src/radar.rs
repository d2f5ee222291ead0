//! Bindings for `mmusv_core::sensors::radar` and `ppi`: the radar, configured once; a sweep as a dict of
//! arrays, and its PPI.

use crate::errors::to_py;
use crate::native::{detached, flat, pose_arg};
use crate::scene::Scene;
use crate::shade::SensorEnv;
use mmusv_core::sensors::capture;
use mmusv_core::sensors::ppi::{self, PpiConfig, PpiOrientation};
use mmusv_core::sensors::radar::sea_clutter::Polarisation;
use mmusv_core::sensors::radar::{self, RadarConfig, RadarReturns};
use mmusv_core::sensors::radar_model::ClutterModel;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A rotating marine radar with its configuration validated once (see `mmusv_core::sensors::radar`). Every
/// field is required: the defaults live in one place, the scenario schema `mmusv.sensors.config.RadarConfig`.
#[pyclass(frozen, module = "mmusv._core")]
pub struct Radar {
    pub(crate) cfg: RadarConfig,
}

#[pymethods]
impl Radar {
    /// Distances in metres, angles in radians; see `RadarConfig` and `ClutterModel` in the core for each field.
    #[new]
    #[pyo3(signature = (
        *, range_min_m, range_max_m, range_resolution_m, azimuth_bins, beamwidth_az_rad, elevation_fan_rad, rays_az,
        rays_el, target_rays, horizon_fraction, horizon_band_rad, detection_threshold, range_noise_std_m, sea_sigma0_at_1m,
        critical_range_per_m, sea_max_range_m, rain_eta_at_1mm_h, frequency_ghz, polarisation
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        range_min_m: f64,
        range_max_m: f64,
        range_resolution_m: f64,
        azimuth_bins: u32,
        beamwidth_az_rad: f64,
        elevation_fan_rad: (f64, f64),
        rays_az: u32,
        rays_el: u32,
        target_rays: u32,
        horizon_fraction: f64,
        horizon_band_rad: f64,
        detection_threshold: f64,
        range_noise_std_m: f64,
        sea_sigma0_at_1m: f64,
        critical_range_per_m: f64,
        sea_max_range_m: f64,
        rain_eta_at_1mm_h: f64,
        frequency_ghz: f64,
        polarisation: &str,
    ) -> PyResult<Self> {
        let cfg = RadarConfig {
            range_min_m,
            range_max_m,
            range_resolution_m,
            azimuth_bins,
            beamwidth_az_rad,
            elevation_fan_rad: [elevation_fan_rad.0, elevation_fan_rad.1],
            rays_az,
            rays_el,
            target_rays,
            horizon_fraction,
            horizon_band_rad,
            detection_threshold,
            range_noise_std_m,
            clutter: ClutterModel { sea_sigma0_at_1m, critical_range_per_m, sea_max_range_m, rain_eta_at_1mm_h },
            frequency_ghz,
            polarisation: Polarisation::parse(polarisation).map_err(to_py)?,
        };
        cfg.validate().map_err(to_py)?;
        Ok(Self { cfg })
    }

    /// Instrumented range, metres.
    #[getter]
    fn range_max_m(&self) -> f64 {
        self.cfg.range_max_m
    }

    /// Carrier frequency, GHz.
    #[getter]
    fn frequency_ghz(&self) -> f64 {
        self.cfg.frequency_ghz
    }

    /// Polarisation, `"HH"` or `"VV"`.
    #[getter]
    fn polarisation(&self) -> &'static str {
        self.cfg.polarisation.name()
    }

    /// Range bin size, metres.
    #[getter]
    fn range_resolution_m(&self) -> f64 {
        self.cfg.range_resolution_m
    }

    /// Beams per revolution.
    #[getter]
    fn azimuth_bins(&self) -> u32 {
        self.cfg.azimuth_bins
    }

    /// Smallest reported intensity.
    #[getter]
    fn detection_threshold(&self) -> f64 {
        self.cfg.detection_threshold
    }

    /// Sea-clutter σ⁰ at 1 m wave height.
    #[getter]
    fn sea_sigma0_at_1m(&self) -> f64 {
        self.cfg.clutter.sea_sigma0_at_1m
    }

    /// Rays per sweep (`azimuth_bins · rays_az · rays_el`).
    #[getter]
    fn num_rays(&self) -> u64 {
        self.cfg.num_rays()
    }

    /// One revolution on the current state of `scene` from `pose` (4×4 sensor → world) in `env` (waves and rain
    /// are used). Returns a dict of equal-length 1-D arrays sorted by (azimuth bin, range bin): `range` f32 m,
    /// `azimuth` f32 rad (sensor frame, [0, 2π)), `elevation` f32 rad, `intensity` f32 (relative to 1 m² at
    /// 1 km), `instance` i32 (−1 clutter), `class` u16.
    #[pyo3(signature = (scene, *, pose, env, seed))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        scene: &Bound<'py, Scene>,
        pose: PyReadonlyArray2<'py, f64>,
        env: &SensorEnv,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pose = pose_arg(&pose, "pose")?;
        let env = capture::radar_env(&env.shade);
        let cfg = &self.cfg;
        let ret = scene.get().read(|s| detached(py, || radar::radar_sweep(s, &pose, cfg, &env, seed)))?;
        returns_dict(py, ret)
    }

    /// `(size_px, size_px)` float32 PPI of returns of this radar (`range` m, `azimuth` rad sensor frame,
    /// `intensity`; equal length float32) at a fixed `metres_per_pixel`, ego at pixel (size/2, size/2), row 0
    /// at the top; `orientation` "north_up" (uses `sensor_yaw`, radians) or "head_up".
    #[pyo3(signature = (*, range, azimuth, intensity, size_px, metres_per_pixel, orientation, sensor_yaw))]
    #[allow(clippy::too_many_arguments)]
    fn ppi_image<'py>(
        &self,
        py: Python<'py>,
        range: PyReadonlyArray1<'py, f32>,
        azimuth: PyReadonlyArray1<'py, f32>,
        intensity: PyReadonlyArray1<'py, f32>,
        size_px: u32,
        metres_per_pixel: f32,
        orientation: &str,
        sensor_yaw: f32,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let returns = RadarReturns {
            range: flat(&range, "range")?.to_vec(),
            azimuth: flat(&azimuth, "azimuth")?.to_vec(),
            intensity: flat(&intensity, "intensity")?.to_vec(),
            ..RadarReturns::default()
        };
        let orientation = PpiOrientation::parse(orientation).map_err(to_py)?;
        let ppi = PpiConfig { size_px, metres_per_pixel, orientation };
        let cfg = &self.cfg;
        let img = detached(py, || ppi::ppi_image(&returns, &ppi, sensor_yaw, cfg))?;
        let n = size_px as usize;
        Array2::from_shape_vec((n, n), img)
            .map(|a| a.into_pyarray(py))
            .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))
    }
}

/// The dict of one sweep as `Radar.sweep` returns it (columns moved into numpy, no copy).
pub(crate) fn returns_dict(py: Python<'_>, ret: RadarReturns) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("range", ret.range.into_pyarray(py))?;
    out.set_item("azimuth", ret.azimuth.into_pyarray(py))?;
    out.set_item("elevation", ret.elevation.into_pyarray(py))?;
    out.set_item("intensity", ret.intensity.into_pyarray(py))?;
    out.set_item("instance", ret.instance.into_pyarray(py))?;
    out.set_item("class", ret.class.into_pyarray(py))?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Radar>()?;
    Ok(())
}
