//! Bindings for `mmusv_core::sensors::radar` and `ppi`: one radar sweep as a dict of arrays, and its PPI.

use crate::errors::to_py;
use crate::native::{detached, flat, pose_arg};
use crate::scene::Scene;
use mmusv_core::sensors::ppi::{self, PpiConfig, PpiOrientation};
use mmusv_core::sensors::radar::{self, RadarConfig, RadarEnv, RadarReturns};
use mmusv_core::sensors::radar_model::ClutterModel;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// One radar revolution of `scene` from `pose`. Returns a dict of equal-length 1-D arrays sorted by
/// (azimuth bin, range bin): `range` f32 m, `azimuth` f32 rad (sensor frame, [0, 2π)), `elevation` f32 rad,
/// `intensity` f32 (relative to 1 m² at 1 km), `instance` i32 (−1 clutter), `class` u16.
#[pyfunction]
#[pyo3(signature = (
    scene, *, pose, range_min_m, range_max_m, range_resolution_m, azimuth_bins, beamwidth_az_rad,
    elevation_fan_rad, rays_az, rays_el, horizon_fraction, horizon_band_rad, detection_threshold,
    range_noise_std_m, sea_sigma0_at_1m, critical_range_per_m, sea_max_range_m, rain_eta_at_1mm_h,
    wave_height_m, rain_mm_per_h, seed
))]
#[allow(clippy::too_many_arguments)]
fn radar_sweep<'py>(
    py: Python<'py>,
    scene: &Bound<'py, Scene>,
    pose: PyReadonlyArray2<'py, f64>,
    range_min_m: f64,
    range_max_m: f64,
    range_resolution_m: f64,
    azimuth_bins: u32,
    beamwidth_az_rad: f64,
    elevation_fan_rad: (f64, f64),
    rays_az: u32,
    rays_el: u32,
    horizon_fraction: f64,
    horizon_band_rad: f64,
    detection_threshold: f64,
    range_noise_std_m: f64,
    sea_sigma0_at_1m: f64,
    critical_range_per_m: f64,
    sea_max_range_m: f64,
    rain_eta_at_1mm_h: f64,
    wave_height_m: f32,
    rain_mm_per_h: f32,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let pose = pose_arg(&pose, "pose")?;
    let cfg = RadarConfig {
        range_min_m,
        range_max_m,
        range_resolution_m,
        azimuth_bins,
        beamwidth_az_rad,
        elevation_fan_rad: [elevation_fan_rad.0, elevation_fan_rad.1],
        rays_az,
        rays_el,
        horizon_fraction,
        horizon_band_rad,
        detection_threshold,
        range_noise_std_m,
        clutter: ClutterModel { sea_sigma0_at_1m, critical_range_per_m, sea_max_range_m, rain_eta_at_1mm_h },
    };
    let env = RadarEnv { wave_height_m, rain_mm_per_h };
    let ret = scene.get().read(|s| detached(py, || radar::radar_sweep(s, &pose, &cfg, &env, seed)))?;
    let out = PyDict::new(py);
    out.set_item("range", ret.range.into_pyarray(py))?;
    out.set_item("azimuth", ret.azimuth.into_pyarray(py))?;
    out.set_item("elevation", ret.elevation.into_pyarray(py))?;
    out.set_item("intensity", ret.intensity.into_pyarray(py))?;
    out.set_item("instance", ret.instance.into_pyarray(py))?;
    out.set_item("class", ret.class.into_pyarray(py))?;
    Ok(out)
}

/// `(size_px, size_px)` float32 PPI of returns (`range` m, `azimuth` rad sensor frame, `intensity`; equal
/// length float32) at a fixed `metres_per_pixel`, ego at pixel (size/2, size/2), row 0 at the top;
/// `orientation` "north_up" (uses `sensor_yaw`, radians) or "head_up".
#[pyfunction]
#[pyo3(signature = (
    *, range, azimuth, intensity, size_px, metres_per_pixel, orientation, sensor_yaw, range_resolution_m,
    azimuth_bins
))]
#[allow(clippy::too_many_arguments)]
fn ppi_image<'py>(
    py: Python<'py>,
    range: PyReadonlyArray1<'py, f32>,
    azimuth: PyReadonlyArray1<'py, f32>,
    intensity: PyReadonlyArray1<'py, f32>,
    size_px: u32,
    metres_per_pixel: f32,
    orientation: &str,
    sensor_yaw: f32,
    range_resolution_m: f64,
    azimuth_bins: u32,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let returns = RadarReturns {
        range: flat(&range, "range")?.to_vec(),
        azimuth: flat(&azimuth, "azimuth")?.to_vec(),
        intensity: flat(&intensity, "intensity")?.to_vec(),
        ..RadarReturns::default()
    };
    let orientation = PpiOrientation::parse(orientation).map_err(to_py)?;
    let cfg = PpiConfig { size_px, metres_per_pixel, orientation };
    let radar = RadarConfig { range_resolution_m, azimuth_bins, ..RadarConfig::default() };
    let img = detached(py, || ppi::ppi_image(&returns, &cfg, sensor_yaw, &radar))?;
    let n = size_px as usize;
    Array2::from_shape_vec((n, n), img)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(radar_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(ppi_image, m)?)?;
    Ok(())
}
