//! Bindings for `mmusv_core::sensors`: ray patterns, the spinning LiDAR and the cameras.

use crate::native::{c_order, detached, flat, pose_arg, rows, rows_to_array, RayArrays};
use mmusv_core::sensors::shade::wake::Wake;
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

/// The camera exposure settings' ranges, `{"ev100": (lo, hi), "compensation_ev": (lo, hi), "max_iso": (lo, hi),
/// "default_max_iso": iso}` (mmusv_core::sensors::shade::tonemap: their one definition, which the scenario schema
/// reads).
#[pyfunction]
fn exposure_limits(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    use mmusv_core::sensors::shade::tonemap::{COMPENSATION_RANGE_EV, DEFAULT_MAX_ISO, EV100_RANGE, MAX_ISO_RANGE};
    let d = pyo3::types::PyDict::new(py);
    d.set_item("ev100", EV100_RANGE)?;
    d.set_item("compensation_ev", COMPENSATION_RANGE_EV)?;
    d.set_item("max_iso", MAX_ISO_RANGE)?;
    d.set_item("default_max_iso", DEFAULT_MAX_ISO)?;
    Ok(d)
}

/// The Marshall–Palmer drop-size law, `(N₀, (c, e))`: `N(D) = N₀ e^{−ΛD}` drops per m³ per mm of diameter `D`
/// (mm), `Λ = c R^e` per mm in rain of `R` mm/h (mmusv_core::sensors::shade::rain: its one definition, which the
/// cameras' drops and the visibility in rain, `mmusv.world.rain`, both read).
#[pyfunction]
fn marshall_palmer() -> (f64, (f64, f64)) {
    use mmusv_core::sensors::shade::rain::{MP_LAMBDA, MP_N0};
    (MP_N0, MP_LAMBDA)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(exposure_limits, m)?)?;
    m.add_function(wrap_pyfunction!(marshall_palmer, m)?)?;
    m.add_function(wrap_pyfunction!(pinhole_intrinsics, m)?)?;
    m.add_function(wrap_pyfunction!(pinhole_directions, m)?)?;
    m.add_function(wrap_pyfunction!(lidar_directions, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_elevations, m)?)?;
    m.add_function(wrap_pyfunction!(lidar_trace_order, m)?)?;
    m.add_class::<SensorEnv>()?;
    m.add_class::<Lidar>()?;
    m.add_class::<Camera>()?;
    m.add("MAX_IMAGE_PIXELS", mmusv_core::sensors::camera::MAX_PIXELS)?;
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

/// `value` if in `[0, 1]`, else a `ConfigError` naming `env.<field>`.
fn env_fraction(field: &str, value: f32) -> PyResult<f32> {
    if value.is_finite() && (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(crate::errors::ConfigError::new_err(format!("invalid config env.{field} = {value}: must be in [0, 1]")))
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
    /// The physical environment: `sun_direction` a world-frame unit vector towards the sun (below the horizon
    /// at night), `turbidity` (Preetham, 1.7..10), `cloud_cover` in [0, 1], `ground_albedo` in [0, 1] (the sea
    /// below the horizon for sky light), `fog_extinction_per_m` (1/m, 3 / visibility), `rain_mm_per_h`,
    /// `wave_height_m` (significant height H), `wind_speed_m_s` (capillary roughness, whitecaps),
    /// `water_albedo` (linear RGB diffuse reflectance of the water body), `exposure_ev100` (None: metered from
    /// the scene's light), whether cameras cast shadow rays, and whether the water keeps the light reflected
    /// more than once between its wave facets (`water_multiple_scattering`; off: the single-scattering
    /// microfacet model alone, as a renderer's rough BSDF). Every value must be finite and in range.
    #[new]
    #[pyo3(signature = (*, sun_direction, turbidity, cloud_cover, ground_albedo, fog_extinction_per_m,
        rain_mm_per_h, wave_height_m, wind_speed_m_s, water_albedo, exposure_ev100=None, shadows=true,
        water_multiple_scattering=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        sun_direction: Vec<f32>,
        turbidity: f32,
        cloud_cover: f32,
        ground_albedo: f32,
        fog_extinction_per_m: f32,
        rain_mm_per_h: f32,
        wave_height_m: f32,
        wind_speed_m_s: f32,
        water_albedo: Vec<f32>,
        exposure_ev100: Option<f32>,
        shadows: bool,
        water_multiple_scattering: bool,
    ) -> PyResult<Self> {
        for &x in sun_direction.iter() {
            env_value("sun_direction", x, false)?;
        }
        for &x in water_albedo.iter() {
            env_fraction("water_albedo", x)?;
        }
        let sun = triple(sun_direction, "sun_direction")?;
        if sun.iter().map(|x| x * x).sum::<f32>() < 1e-12 {
            return Err(crate::errors::ConfigError::new_err(
                "invalid config env.sun_direction = [0, 0, 0]: must be a non-zero vector",
            ));
        }
        if !(turbidity.is_finite() && (1.7..=10.0).contains(&turbidity)) {
            return Err(crate::errors::ConfigError::new_err(format!(
                "invalid config env.turbidity = {turbidity}: must be in [1.7, 10]"
            )));
        }
        let exposure_ev100 = match exposure_ev100 {
            // The range a camera's fixed exposure takes (an EV100 of 1e9 exposed every image black).
            Some(ev) => {
                let (lo, hi) = mmusv_core::sensors::shade::tonemap::EV100_RANGE;
                if !(ev.is_finite() && (lo..=hi).contains(&ev)) {
                    return Err(crate::errors::ConfigError::new_err(format!(
                        "invalid config env.exposure_ev100 = {ev}: must be a finite EV100 in [{lo}, {hi}]"
                    )));
                }
                ev
            }
            None => f32::NAN,
        };
        let shade = ShadeEnv {
            sun_direction: sun,
            turbidity,
            cloud_cover: env_fraction("cloud_cover", cloud_cover)?,
            ground_albedo: env_fraction("ground_albedo", ground_albedo)?,
            fog_extinction_per_m: env_value("fog_extinction_per_m", fog_extinction_per_m, true)?,
            rain_mm_per_h: env_value("rain_mm_per_h", rain_mm_per_h, true)?,
            wave_height_m: env_value("wave_height_m", wave_height_m, true)?,
            wind_speed_m_s: env_value("wind_speed_m_s", wind_speed_m_s, true)?,
            water_albedo: triple(water_albedo, "water_albedo")?,
            exposure_ev100,
            shadows,
            water_multiple_scattering,
        };
        Ok(Self { shade })
    }

    /// Horizontal illuminance of the sun and sky (lux) and the exposure scale the cameras use (radiance in
    /// cd/m² times it is the tone curve's input).
    #[getter]
    fn exposure(&self) -> (f32, f32) {
        let l = mmusv_core::sensors::shade::envlight::Lighting::shared(&self.shade.lighting_key());
        let k = mmusv_core::sensors::shade::tonemap::exposure_scale(self.shade.exposure_ev100, l.horizontal_lux);
        (l.horizontal_lux, k)
    }

    /// Radiance of the sky (cd/m², linear sRGB primaries) along unit world directions `dirs` (N, 3) float32,
    /// without the sun's disc (`sun_disc=False`) or with it; below the horizon, the ground's radiance.
    #[pyo3(signature = (dirs, *, sun_disc=false))]
    fn sky_radiance<'py>(
        &self,
        py: Python<'py>,
        dirs: PyReadonlyArray2<'py, f32>,
        sun_disc: bool,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let d = crate::native::rows::<f32, 3>(&dirs, "dirs")?;
        // Unit directions, as documented: a NaN or zero one read as the ground's radiance, without a word.
        if let Some((k, v)) = d.iter().enumerate().find(|(_, v)| {
            let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            !(n.is_finite() && (n - 1.0).abs() <= 1e-3)
        }) {
            return Err(crate::errors::InputError::new_err(format!(
                "invalid dirs[{k}] = {v:?}: must be a unit vector (length 1 within 1e-3; normalise it)"
            )));
        }
        let l = mmusv_core::sensors::shade::envlight::Lighting::shared(&self.shade.lighting_key());
        let out: Vec<[f32; 3]> = d.iter().map(|v| l.radiance_along(*v, sun_disc)).collect();
        rows_to_array(py, out)
    }

    /// Direct-normal irradiance of the sun (lux, linear sRGB primaries), zero at night.
    #[getter]
    fn sun_irradiance(&self) -> [f32; 3] {
        let l = mmusv_core::sensors::shade::envlight::Lighting::shared(&self.shade.lighting_key());
        l.sky.sun_irradiance().to_array()
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
    /// rad), class (u16), instance (i32), ray_index (u32); and beam_instance (M,) i32: per ray of the full
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

/// Wakes from a `(K, 6)` to `(K, 9)` float32 array (`x, y, heading, speed, length, beam[, reach_m[, age_s[,
/// displacement_m3]]]`), checked. Eight columns or more are the pieces of wakes that follow their vessels' bends
/// (`mmusv.Simulation.wakes`): each piece's foam is `age_s` old at its start and ends at `reach_m` at full
/// strength, where the next piece goes on; a vessel's pieces come one after another, newest first, and the Kelvin
/// arms bend along them. The ninth, the vessel's displaced volume, sets its Kelvin waves (none without it).
pub(crate) fn wakes_arg(wakes: Option<&PyReadonlyArray2<'_, f32>>) -> PyResult<Vec<Wake>> {
    let Some(w) = wakes else { return Ok(Vec::new()) };
    let shape = numpy::PyUntypedArrayMethods::shape(&**w);
    let columns = shape[1];
    if !(6..=9).contains(&columns) {
        return Err(crate::errors::InputError::new_err(format!(
            "wakes must have shape (K, 6) to (K, 9): x, y, heading, speed, length, beam[, reach_m[, age_s[, \
             displacement_m3]]]; got {shape:?}"
        )));
    }
    let flat = c_order(w, "wakes")?;
    // The columns given, then the defaults of those left out: reach_m unlimited, age_s 0, no displacement.
    let rows: Vec<[f32; 9]> = flat
        .chunks_exact(columns)
        .map(|given| {
            let mut r = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, f32::INFINITY, 0.0, 0.0];
            r[..columns].copy_from_slice(given);
            r
        })
        .collect();
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            if r[..6].iter().any(|x| !x.is_finite())
                || r[3] < 0.0
                || r[4] <= 0.0
                || r[5] <= 0.0
                || r[6].is_nan()
                || r[6] < 0.0
                || !(r[7].is_finite() && r[7] >= 0.0)
                || !(r[8].is_finite() && r[8] >= 0.0)
            {
                return Err(crate::errors::InputError::new_err(format!(
                    "wakes[{i}] = {:?}: x, y, heading, speed, length, beam must be finite, with speed >= 0 and \
                     length, beam > 0; reach_m >= 0 (inf: unlimited); age_s finite and >= 0; displacement_m3 \
                     finite and >= 0",
                    &r[..columns]
                )));
            }
            Ok(Wake {
                x: r[0],
                y: r[1],
                heading: r[2],
                speed: r[3],
                length: r[4],
                beam: r[5],
                reach_m: r[6],
                age_s: r[7],
                displacement_m3: r[8],
                goes_on: columns >= 8,
            })
        })
        .collect()
}
