//! Bindings for `mmusv_core::kinematics`: a fleet of vessels on spline routes with wave perturbations.

use crate::errors::{to_py, InputError};
use crate::native::{detached, flat, rows, rows_to_array};
use crate::ocean::{hull_from, WaveField};
use mmusv_core::kinematics::{
    BaseAmplitudes, EndBehaviour, Fleet as CoreFleet, Route, VesselDims, VesselMotion, VesselParams, WaveSetting,
    WaveSignals, REFERENCE_HULL,
};
use mmusv_core::MmusvError;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use std::sync::Arc;

/// Parses a wave setting: a preset name `"W0".."W3"` or a significant wave height in metres.
fn wave_from(obj: &Bound<'_, PyAny>) -> PyResult<WaveSetting> {
    if let Ok(name) = obj.extract::<String>() {
        return name.parse::<WaveSetting>().map_err(to_py);
    }
    let h: f64 = obj
        .extract()
        .map_err(|_| InputError::new_err("wave must be a preset name 'W0'..'W3' or a wave height in metres"))?;
    WaveSetting::from_height(h).map_err(to_py)
}

/// The vessels of a scenario moving along their routes (equations 1–3 of the MMUSV-Sim paper).
#[pyclass(frozen, module = "mmusv._core")]
pub struct Fleet {
    inner: CoreFleet,
}

#[pymethods]
impl Fleet {
    /// Builds a fleet. Per vessel `i`: `routes[i]` (K,2) waypoints in metres, `end_behaviours[i]` in
    /// {"stop", "loop", "ping_pong"}, `speeds[i]` m/s, `start_offsets[i]` m along the route, `z_base[i]` m,
    /// `dims[i]` = (length, beam, height) m, `amplitudes[i]` = (heave m, roll rad, pitch rad).
    #[new]
    #[pyo3(signature = (*, routes, end_behaviours, speeds, start_offsets, z_base, dims, amplitudes, seed, wave, sea=None, hulls=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        routes: Vec<PyReadonlyArray2<'_, f64>>,
        end_behaviours: Vec<String>,
        speeds: PyReadonlyArray1<'_, f64>,
        start_offsets: PyReadonlyArray1<'_, f64>,
        z_base: PyReadonlyArray1<'_, f64>,
        dims: PyReadonlyArray2<'_, f64>,
        amplitudes: PyReadonlyArray2<'_, f64>,
        seed: u64,
        wave: &Bound<'_, PyAny>,
        sea: Option<PyRef<'_, WaveField>>,
        hulls: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Self> {
        let n = routes.len();
        let speeds = flat(&speeds, "speeds")?;
        let offsets = flat(&start_offsets, "start_offsets")?;
        let z = flat(&z_base, "z_base")?;
        let dims = rows::<f64, 3>(&dims, "dims")?;
        let amps = rows::<f64, 3>(&amplitudes, "amplitudes")?;
        let hull_rows = match &hulls {
            Some(h) => Some(rows::<f64, 5>(h, "hulls")?),
            None if sea.is_some() => {
                return Err(InputError::new_err(
                    "a fleet in a sea needs hulls: (V, 5) [length, beam, draft, block_coefficient, gm] per vessel",
                ))
            }
            None => None,
        };
        if let Some(h) = hull_rows {
            if h.len() != n {
                return Err(InputError::new_err(format!(
                    "hulls has {} entries for {n} routes; give one per vessel",
                    h.len()
                )));
            }
        }
        for (name, len) in [
            ("end_behaviours", end_behaviours.len()),
            ("speeds", speeds.len()),
            ("start_offsets", offsets.len()),
            ("z_base", z.len()),
            ("dims", dims.len()),
            ("amplitudes", amps.len()),
        ] {
            if len != n {
                return Err(InputError::new_err(format!(
                    "{name} has {len} entries for {n} routes; give one per vessel"
                )));
            }
        }
        let wave = wave_from(wave)?;
        let mut vessels = Vec::with_capacity(n);
        for i in 0..n {
            let prefix = format!("vessels[{i}]");
            let wps = rows::<f64, 2>(&routes[i], &format!("{prefix}.route"))?;
            let build = || -> Result<VesselMotion, MmusvError> {
                let end = EndBehaviour::parse(&end_behaviours[i])?;
                let route = Route::new(wps, end)?;
                let params = VesselParams {
                    speed_mps: speeds[i],
                    start_offset_m: offsets[i],
                    z_base_m: z[i],
                    dims: VesselDims { length_m: dims[i][0], beam_m: dims[i][1], height_m: dims[i][2] },
                    amplitudes: BaseAmplitudes { heave_m: amps[i][0], roll_rad: amps[i][1], pitch_rad: amps[i][2] },
                    hull: match hull_rows {
                        Some(h) => hull_from(&h[i])?,
                        None => REFERENCE_HULL,
                    },
                };
                VesselMotion::new(route, params, WaveSignals::from_seed(seed, i as u64))
            };
            vessels.push(build().map_err(|e| to_py(e.within(&prefix)))?);
        }
        let fleet = CoreFleet::new(vessels, wave);
        Ok(Self { inner: if let Some(s) = sea { fleet.with_sea(Arc::clone(&s.inner)) } else { fleet } })
    }

    /// Number of vessels.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Whether the fleet moves physically in a wave field (else by the paper's formula).
    #[getter]
    fn physical(&self) -> bool {
        self.inner.sea().is_some()
    }

    /// Wave height H in metres of the fleet's wave setting.
    #[getter]
    fn wave_height_m(&self) -> f64 {
        self.inner.wave().height_m()
    }

    /// `(V,)` route lengths in metres.
    fn route_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.vessels().iter().map(|v| v.route().length()).collect::<Vec<_>>().into_pyarray(py)
    }

    /// `(V,)` size factors α_v.
    fn alphas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.vessels().iter().map(|v| v.alpha()).collect::<Vec<_>>().into_pyarray(py)
    }

    /// `(V, 6)` float64 poses η = [x, y, z, roll, pitch, yaw] (world frame, metres, radians) at time `t` s.
    fn poses_at<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows_to_array(py, self.inner.poses_at(t).map_err(to_py)?)
    }

    /// `(V, 3)` float64 world-frame linear velocities (m/s) at time `t` s.
    fn velocities_at<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows_to_array(py, self.inner.velocities_at(t).map_err(to_py)?)
    }

    /// `(M, 6)` float64 rows `vessel, x, y, heading, reach_m, age_s`: the path behind each vessel at time `t`
    /// (s) as straight pieces, newest first (`VesselMotion::wake_pieces`): where each starts (metres, radians: the
    /// vessel's centre and direction of travel when it passed there), how far back from there the path ran straight
    /// within `tolerances_m` (V,) metres of that line (checked every 2 m; inf: on to the wake's end), and how long
    /// ago the vessel passed there (s); out to its wake's reach (`speed · WAKE_REACH_S` of path), at most
    /// `WAKE_MAX_PIECES` pieces a vessel. A vessel at rest at a `stop` route's end keeps the pieces it had on
    /// arriving, each as much older as it has lain there (its first row's `age_s`); none for a speed of 0 or one
    /// parked there from the start.
    fn wake_pieces<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        tolerances_m: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let tol = flat(&tolerances_m, "tolerances_m")?;
        let vessels = self.inner.vessels();
        if tol.len() != vessels.len() {
            return Err(InputError::new_err(format!(
                "tolerances_m must hold one tolerance per vessel ({}), got {}",
                vessels.len(),
                tol.len()
            )));
        }
        let reach_s = f64::from(mmusv_core::sensors::shade::wake::WAKE_REACH_S);
        let most = mmusv_core::sensors::shade::wake::WAKE_MAX_PIECES;
        let mut rows: Vec<[f64; 6]> = Vec::new();
        for (i, (v, &tol)) in vessels.iter().zip(tol).enumerate() {
            let max_m = v.params().speed_mps * reach_s;
            if max_m <= 0.0 {
                continue;
            }
            for p in v.wake_pieces(t, max_m, 2.0, tol, most).map_err(to_py)? {
                rows.push([i as f64, p.x, p.y, p.heading, p.reach_m, p.age_s]);
            }
        }
        rows_to_array(py, rows)
    }

    /// `(T, V, 6)` float64 poses at every time in `times` (s), computed in parallel with the GIL released.
    fn poses_at_times<'py>(
        &self,
        py: Python<'py>,
        times: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let ts = flat(&times, "times")?;
        let poses = detached(py, || self.inner.poses_at_times(ts))?;
        let v = self.inner.len();
        Array3::from_shape_vec((ts.len(), v, 6), poses.into_iter().flatten().collect())
            .map(|a| a.into_pyarray(py))
            .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))
    }
}

/// `(heave_m, roll_rad, pitch_rad)`: the default base amplitudes r of a vessel (calibrated so that the
/// reference 5 m USV reproduces Table I of the paper).
#[pyfunction]
fn default_amplitudes() -> (f64, f64, f64) {
    let a = BaseAmplitudes::default();
    (a.heave_m, a.roll_rad, a.pitch_rad)
}

/// `(length_m, beam_m, height_m)` of the paper's reference USV, whose size factor `α_v` is 1 (the vessel the
/// default amplitudes are calibrated on: the paper's formula gives it Table I).
#[pyfunction]
fn reference_usv_dims() -> (f64, f64, f64) {
    let d = VesselDims::REFERENCE;
    (d.length_m, d.beam_m, d.height_m)
}

/// Wave height H (m) of a preset name `"W0".."W3"` or a height given in metres (validated).
#[pyfunction]
fn wave_height(wave: &Bound<'_, PyAny>) -> PyResult<f64> {
    Ok(wave_from(wave)?.height_m())
}

/// `[(name, H metres), ...]` of the wave presets W0..W3 in order: the one definition of the presets.
#[pyfunction]
fn wave_presets() -> Vec<(&'static str, f64)> {
    WaveSetting::PRESETS.iter().filter_map(|w| w.preset_name().map(|n| (n, w.height_m()))).collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Fleet>()?;
    m.add_function(wrap_pyfunction!(wave_presets, m)?)?;
    m.add_function(wrap_pyfunction!(default_amplitudes, m)?)?;
    m.add_function(wrap_pyfunction!(reference_usv_dims, m)?)?;
    m.add_function(wrap_pyfunction!(wave_height, m)?)?;
    Ok(())
}
