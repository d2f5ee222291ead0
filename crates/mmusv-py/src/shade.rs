//! Bindings for `mmusv_core::sensors::shade`: the environment every sensor sees (`SensorEnv`), the cameras'
//! exposure limits, the Marshall–Palmer drop-size law and the wakes argument the sensors share.

use crate::native::{c_order, rows_to_array};
use mmusv_core::sensors::capture;
use mmusv_core::sensors::lidar;
use mmusv_core::sensors::shade::wake::Wake;
use mmusv_core::sensors::shade::ShadeEnv;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

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
    m.add_class::<SensorEnv>()?;
    Ok(())
}

/// What every sensor sees of the environment at a frame: sun and sky (cameras), the fog extinction, the rain's
/// drops included (cameras, LiDAR), the rain rate (the cameras' near drops, the radar) and waves (all three). Built
/// once per scenario from the resolved environment; passed to every `Lidar.scan`, `Camera.render` and `Radar.sweep`.
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
    /// The LiDAR's share: the fog extinction (rain's drops included), waves, wind.
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
