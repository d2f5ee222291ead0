//! Bindings for `mmusv_core::sensors`: ray patterns, the spinning LiDAR and the cameras.

use crate::native::{detached, flat, pose_arg, rows_to_array, RayArrays};
use mmusv_core::sensors::shade::ShadeEnv;
use mmusv_core::sensors::{camera, capture, lidar, rays};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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
    m.add_class::<SensorEnv>()?;
    m.add_class::<Lidar>()?;
    m.add_class::<Camera>()?;
    Ok(())
}

/// What every sensor sees of the environment at a frame: sun and sky (cameras), fog (cameras, LiDAR), rain
/// and waves (all three). Built once per scenario from the resolved environment; passed to every
/// `Lidar.scan`, `Camera.render` and `Radar.sweep`.
#[pyclass(frozen, module = "mmusv._core")]
pub struct SensorEnv {
    pub(crate) shade: ShadeEnv,
}

fn triple(v: Vec<f32>, field: &str) -> PyResult<[f32; 3]> {
    v.try_into().map_err(|_| crate::errors::InputError::new_err(format!("{field} must have 3 components")))
}

/// `value` if finite (and `>= 0` when `nonneg`), else a `ConfigError` naming `env.<field>`.
fn env_value(field: &str, value: f32, nonneg: bool) -> PyResult<f32> {
    if value.is_finite() && (!nonneg || value >= 0.0) {
        Ok(value)
    } else {
        let allowed = if nonneg { "a finite number >= 0" } else { "a finite number" };
        Err(crate::errors::ConfigError::new_err(format!("invalid config env.{field} = {value}: must be {allowed}")))
    }
}

impl SensorEnv {
    /// The LiDAR's share: fog, rain, waves.
    pub(crate) fn lidar(&self) -> lidar::LidarEnv {
        capture::lidar_env(&self.shade)
    }
}

#[pymethods]
impl SensorEnv {
    /// Lighting in linear RGB (`sun_direction` a world-frame unit vector towards the sun), `fog_extinction_per_m`
    /// (1/m, 3 / visibility), `rain_mm_per_h`, `wave_height_m` (significant height H), and whether cameras
    /// cast shadow rays. Every value must be finite; intensities, fog, rain and waves `>= 0`.
    #[new]
    #[pyo3(signature = (*, sun_direction, sun_color, sun_intensity, ambient, sky_zenith, sky_horizon,
        fog_extinction_per_m, fog_color, rain_mm_per_h, wave_height_m, shadows=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        sun_direction: Vec<f32>,
        sun_color: Vec<f32>,
        sun_intensity: f32,
        ambient: f32,
        sky_zenith: Vec<f32>,
        sky_horizon: Vec<f32>,
        fog_extinction_per_m: f32,
        fog_color: Vec<f32>,
        rain_mm_per_h: f32,
        wave_height_m: f32,
        shadows: bool,
    ) -> PyResult<Self> {
        let colours = [
            ("sun_direction", &sun_direction),
            ("sun_color", &sun_color),
            ("sky_zenith", &sky_zenith),
            ("sky_horizon", &sky_horizon),
            ("fog_color", &fog_color),
        ];
        for (name, v) in colours {
            for &x in v.iter() {
                env_value(name, x, false)?;
            }
        }
        let shade = ShadeEnv {
            sun_direction: triple(sun_direction, "sun_direction")?,
            sun_color: triple(sun_color, "sun_color")?,
            sun_intensity: env_value("sun_intensity", sun_intensity, true)?,
            ambient: env_value("ambient", ambient, true)?,
            sky_zenith: triple(sky_zenith, "sky_zenith")?,
            sky_horizon: triple(sky_horizon, "sky_horizon")?,
            fog_extinction_per_m: env_value("fog_extinction_per_m", fog_extinction_per_m, true)?,
            fog_color: triple(fog_color, "fog_color")?,
            rain_mm_per_h: env_value("rain_mm_per_h", rain_mm_per_h, true)?,
            wave_height_m: env_value("wave_height_m", wave_height_m, true)?,
            shadows,
        };
        Ok(Self { shade })
    }

    /// Atmospheric extinction, 1/m.
    #[getter]
    fn fog_extinction_per_m(&self) -> f32 {
        self.shade.fog_extinction_per_m
    }

    /// Rain rate, mm/h.
    #[getter]
    fn rain_mm_per_h(&self) -> f32 {
        self.shade.rain_mm_per_h
    }

    /// Significant wave height, metres.
    #[getter]
    fn wave_height_m(&self) -> f32 {
        self.shade.wave_height_m
    }
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
        water_probability, water_probability_per_wave_m, water_range_m, water_range_per_wave_m))]
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

    /// One sweep on the current state of `scene` from the LiDAR at `pose` (4×4 LiDAR → world) in `env` (fog, rain
    /// and waves are used). Returns a dict
    /// of equal-length columns: xyz (N,3) f32 LiDAR frame, range, intensity (f32), ring (u16), azimuth (f32
    /// rad), class (u16), instance (i32), ray_index (u32).
    #[pyo3(signature = (scene, *, pose, env, seed))]
    fn scan<'py>(
        &self,
        py: Python<'py>,
        scene: &crate::scene::Scene,
        pose: PyReadonlyArray2<'py, f64>,
        env: &SensorEnv,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pose = pose_arg(&pose, "pose")?;
        let env = env.lidar();
        let s = scene.read(|s| detached(py, || self.inner.scan(s, &pose, &env, seed)))?;
        scan_dict(py, s)
    }
}

/// A pinhole or orthographic camera with its rays computed once (see `mmusv_core::sensors::camera`), and
/// whether it shades RGB (depth, semantic and instance images are always produced).
#[pyclass(frozen, module = "mmusv._core")]
pub struct Camera {
    pub(crate) inner: camera::Camera,
    pub(crate) rgb: bool,
}

#[pymethods]
impl Camera {
    #[new]
    #[pyo3(signature = (*, width, height, rgb, hfov=None, metres_per_pixel=None, range_max=f32::INFINITY))]
    fn new(
        width: u32,
        height: u32,
        rgb: bool,
        hfov: Option<f64>,
        metres_per_pixel: Option<f64>,
        range_max: f32,
    ) -> PyResult<Self> {
        let projection = match (hfov, metres_per_pixel) {
            (Some(hfov), None) => camera::Projection::Pinhole { hfov },
            (None, Some(m)) => camera::Projection::Orthographic { metres_per_pixel: m },
            _ => {
                return Err(crate::errors::ConfigError::new_err(
                    "give exactly one of hfov (pinhole camera) or metres_per_pixel (orthographic camera)",
                ))
            }
        };
        let cfg = camera::CameraConfig { width, height, projection, range_max };
        Ok(Self { inner: camera::Camera::new(cfg).map_err(crate::errors::to_py)?, rgb })
    }

    /// Whether `render` shades an RGB image.
    #[getter]
    fn rgb(&self) -> bool {
        self.rgb
    }

    /// `[fx, fy, cx, cy]` in pixels for a pinhole camera, `None` for an orthographic one.
    #[getter]
    fn intrinsics(&self) -> Option<[f64; 4]> {
        self.inner.intrinsics()
    }

    /// `(width, height)` in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.inner.config().width, self.inner.config().height)
    }

    /// World ray origins and unit directions `(H·W, 3)` float32 for the camera at `pose`, row-major.
    fn world_rays<'py>(&self, py: Python<'py>, pose: PyReadonlyArray2<'py, f64>) -> PyResult<RayArrays<'py>> {
        let pose = pose_arg(&pose, "pose")?;
        let (o, d) = self.inner.world_rays(&pose);
        Ok((rows_to_array(py, o)?, rows_to_array(py, d)?))
    }

    /// World ray origins and unit directions `(N, 3)` float32 of the row-major pixel indices `pixels` (N,)
    /// int64, in that order: the rows of `world_rays` for those pixels.
    fn pixel_rays<'py>(
        &self,
        py: Python<'py>,
        pose: PyReadonlyArray2<'py, f64>,
        pixels: PyReadonlyArray1<'py, i64>,
    ) -> PyResult<RayArrays<'py>> {
        let pose = pose_arg(&pose, "pose")?;
        let pixels = flat(&pixels, "pixels")?;
        let (o, d) = self.inner.pixel_rays(&pose, pixels).map_err(crate::errors::to_py)?;
        Ok((rows_to_array(py, o)?, rows_to_array(py, d)?))
    }

    /// Renders the current state of `scene` from `pose` (4×4 camera body → world) in `env`. Returns a dict:
    /// depth (H,W) f32 metres along the axis (inf = sky), semantic (H,W) u16, instance (H,W) i32 (−1 = sky) and,
    /// for a camera built with `rgb=True`, rgb (H,W,3) u8 sRGB.
    #[pyo3(signature = (scene, *, pose, env, seed))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: &crate::scene::Scene,
        pose: PyReadonlyArray2<'py, f64>,
        env: &SensorEnv,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pose = pose_arg(&pose, "pose")?;
        let (env, rgb) = (&env.shade, self.rgb);
        let f = scene.read(|s| detached(py, || self.inner.render(s, &pose, env, rgb, seed)))?;
        frame_dict(py, f, rgb)
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
    Ok(d)
}

/// The dict of one image set as `Camera.render` returns it (`rgb` only when shaded).
pub(crate) fn frame_dict(py: Python<'_>, f: camera::CameraFrame, rgb: bool) -> PyResult<Bound<'_, PyDict>> {
    let (w, h) = (f.width as usize, f.height as usize);
    let shape_err = |e: numpy::ndarray::ShapeError| crate::errors::InternalError::new_err(e.to_string());
    let d = PyDict::new(py);
    d.set_item("depth", Array2::from_shape_vec((h, w), f.depth).map_err(shape_err)?.into_pyarray(py))?;
    d.set_item("semantic", Array2::from_shape_vec((h, w), f.semantic).map_err(shape_err)?.into_pyarray(py))?;
    d.set_item("instance", Array2::from_shape_vec((h, w), f.instance).map_err(shape_err)?.into_pyarray(py))?;
    if rgb {
        d.set_item("rgb", Array3::from_shape_vec((h, w, 3), f.rgb).map_err(shape_err)?.into_pyarray(py))?;
    }
    Ok(d)
}
