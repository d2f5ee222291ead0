//! Bindings for `mmusv_core::sensors::camera`: pinhole and orthographic cameras, configured once; an image set as
//! a dict of numpy arrays.

use crate::native::{detached, flat, pose_arg, rows, rows_to_array, RayArrays};
use crate::shade::{wakes_arg, SensorEnv};
use mmusv_core::sensors::camera;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Camera>()?;
    m.add("MAX_IMAGE_PIXELS", camera::MAX_PIXELS)?;
    Ok(())
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
    #[pyo3(signature = (*, width, height, rgb, hfov=None, metres_per_pixel=None, range_max=f32::INFINITY,
        quality="standard", distortion=None, noise=None, exposure=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        width: u32,
        height: u32,
        rgb: bool,
        hfov: Option<f64>,
        metres_per_pixel: Option<f64>,
        range_max: f32,
        quality: &str,
        distortion: Option<[f64; 5]>,
        noise: Option<(f32, f32)>,
        exposure: Option<(Option<f32>, f32, f32)>,
    ) -> PyResult<Self> {
        let quality = match quality {
            "draft" => camera::Quality::Draft,
            "standard" => camera::Quality::Standard,
            "high" => camera::Quality::High,
            other => {
                return Err(crate::errors::ConfigError::new_err(format!(
                    "invalid config camera.quality = {other:?}: allowed values are draft, standard, high"
                )))
            }
        };
        let noise = match noise {
            Some((full_well, read_noise)) => {
                if !(full_well.is_finite() && full_well > 0.0 && read_noise.is_finite() && read_noise >= 0.0) {
                    return Err(crate::errors::ConfigError::new_err(format!(
                        "invalid config camera.noise = ({full_well}, {read_noise}): full well must be > 0 \
                         electrons and read noise >= 0"
                    )));
                }
                Some(mmusv_core::sensors::shade::tonemap::SensorNoise { full_well, read_noise })
            }
            None => None,
        };
        let image = camera::ImageOptions {
            quality,
            distortion: distortion.map(|coefficients| camera::Distortion { coefficients }),
            noise,
            exposure: exposure.map_or_else(Default::default, |(ev100, compensation_ev, max_iso)| {
                mmusv_core::sensors::shade::tonemap::Exposure { ev100, compensation_ev, max_iso }
            }),
        };
        let projection = match (hfov, metres_per_pixel) {
            (Some(hfov), None) => camera::Projection::Pinhole { hfov },
            (None, Some(m)) => camera::Projection::Orthographic { metres_per_pixel: m },
            _ => {
                return Err(crate::errors::ConfigError::new_err(
                    "give exactly one of hfov (pinhole camera) or metres_per_pixel (orthographic camera)",
                ))
            }
        };
        let cfg = camera::CameraConfig { width, height, projection, range_max, image };
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

    /// Brown–Conrady `[k1, k2, p1, p2, k3]` (OpenCV's order), `None` without distortion.
    #[getter]
    fn distortion(&self) -> Option<[f64; 5]> {
        self.inner.config().image.distortion.map(|d| d.coefficients)
    }

    /// Distorted normalised image coordinates `(N, 2)` float64 of undistorted ones `points` `(N, 2)` float64
    /// (`x / z`, `y / z` in the optical frame): the camera's Brown–Conrady model (mmusv_core's
    /// `Distortion::distort`, the one the render uses); the points themselves without distortion.
    fn distort<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pts = rows::<f64, 2>(&points, "points")?;
        let out = match &self.inner.config().image.distortion {
            Some(d) => pts.iter().map(|&[x, y]| d.distort(x, y).into()).collect(),
            None => pts.to_vec(),
        };
        rows_to_array(py, out)
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
    /// for a camera built with `rgb=True`, rgb (H,W,3) u8 sRGB; with `radiance=True`, radiance (H,W,3) f32
    /// linear cd/m² (before noise and exposure). `wakes` (K, 6) to (K, 9) float32 rows `x, y, heading,
    /// speed, length, beam[, reach_m[, age_s[, displacement_m3]]]` (world metres, radians, m/s, s, m³; `reach_m`
    /// how far behind the stern the path ran straight, inf when not given; with `age_s`, the rows are pieces of wakes that follow their
    /// vessels' bends, `Simulation.wakes`: the foam is `age_s` old at the piece's start and ends at `reach_m`,
    /// where the next piece goes on; `displacement_m3` the vessel's displaced volume, which sets its Kelvin waves,
    /// none without it) are the vessels under way whose wakes the water shows.
    #[pyo3(signature = (scene, *, pose, env, seed, wakes=None, radiance=false))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: &crate::scene::Scene,
        pose: PyReadonlyArray2<'py, f64>,
        env: &SensorEnv,
        seed: u64,
        wakes: Option<PyReadonlyArray2<'py, f32>>,
        radiance: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pose = pose_arg(&pose, "pose")?;
        let wakes = wakes_arg(wakes.as_ref())?;
        let (env, rgb) = (&env.shade, self.rgb);
        let options = camera::RenderOptions { rgb, radiance, seed, wakes: &wakes };
        let f = scene.read(|s| detached(py, || self.inner.render_with(s, &pose, env, &options)))?;
        frame_dict(py, f, rgb)
    }
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
    if !f.radiance.is_empty() {
        d.set_item("radiance", Array3::from_shape_vec((h, w, 3), f.radiance).map_err(shape_err)?.into_pyarray(py))?;
    }
    Ok(d)
}
