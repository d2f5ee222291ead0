//! Bindings for `mmusv_core::ocean`: the wave field, sea-state presets, hull RAOs and response statistics.

use crate::errors::{to_py, InputError};
use crate::native::{all_finite, detached, finite_time, flat, not_allowed, rows, rows_finite, rows_to_array};
use mmusv_core::ocean::{paper_sea_states, presets, response, wmo_sea_states, Hull, SeaSpec, WaveField as CoreField};
use mmusv_core::MmusvError;
use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use std::sync::Arc;

/// A hull from `[length, beam, draft, block_coefficient, gm]` (m, m, m, -, m) with default roll gyradius/damping.
pub fn hull_from(row: &[f64; 5]) -> Result<Hull, MmusvError> {
    Hull::new(row[0], row[1], row[2], row[3], row[4])
}

/// A realised sea: a seeded sum of linear deep-water waves drawn from a directional JONSWAP spectrum.
#[pyclass(frozen, module = "mmusv._core")]
pub struct WaveField {
    pub(crate) inner: Arc<CoreField>,
}

fn same_len(a: &[f64], b: &[f64], na: &str, nb: &str) -> PyResult<()> {
    if a.len() != b.len() {
        return Err(InputError::new_err(format!(
            "{na} has {} entries but {nb} has {}; give one each",
            a.len(),
            b.len()
        )));
    }
    Ok(())
}

/// `f(x[i], y[i])` at each of the world points given as the columns `x`, `y` (m, one entry each; errors name them),
/// evaluated with the GIL released: the point-wise queries of [`WaveField`]. A point or time `t` that is not finite
/// is refused.
fn at_points<T: Send>(
    py: Python<'_>,
    x: &PyReadonlyArray1<'_, f64>,
    y: &PyReadonlyArray1<'_, f64>,
    t: f64,
    f: impl Fn(f64, f64) -> T + Sync,
) -> PyResult<Vec<T>> {
    let (xs, ys) = (flat(x, "x")?, flat(y, "y")?);
    same_len(xs, ys, "x", "y")?;
    all_finite(xs, "x")?;
    all_finite(ys, "y")?;
    finite_time(t, "t")?;
    detached(py, || Ok(xs.iter().zip(ys).map(|(&a, &b)| f(a, b)).collect()))
}

#[pymethods]
impl WaveField {
    /// Significant height `hs_m` (m), peak period `tp_s` (s), peak enhancement `gamma`, mean travel direction
    /// `direction_rad` (world frame, towards), cos-2s exponent `spread_s`, and the field's `seed`.
    #[new]
    #[pyo3(signature = (*, hs_m, tp_s, gamma, direction_rad, spread_s, seed))]
    fn new(hs_m: f64, tp_s: f64, gamma: f64, direction_rad: f64, spread_s: f64, seed: u64) -> PyResult<Self> {
        let spec = SeaSpec { hs: hs_m, tp: tp_s, gamma, direction_rad, spread_s };
        Ok(Self { inner: Arc::new(CoreField::new(&spec, seed).map_err(to_py)?) })
    }

    /// `(hs_m, tp_s, gamma, direction_rad, spread_s)` of the sea.
    #[getter]
    fn spec(&self) -> (f64, f64, f64, f64, f64) {
        let s = self.inner.spec();
        (s.hs, s.tp, s.gamma, s.direction_rad, s.spread_s)
    }

    /// The seed the components were drawn from.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed()
    }

    /// Hard bound on |elevation| (m): the sum of the amplitudes.
    #[getter]
    fn max_elevation(&self) -> f64 {
        self.inner.max_elevation()
    }

    /// Hard bound on the slope magnitude: the sum of amplitude × wavenumber.
    #[getter]
    fn max_slope(&self) -> f64 {
        self.inner.max_slope()
    }

    /// `(N, 5)` float64 components: amplitude m, ω rad/s, k rad/m, direction rad, phase rad (increasing ω).
    fn components<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = self.inner.components();
        rows_to_array(
            py,
            c.iter().map(|c| [c.amplitude_m, c.omega_rad_s, c.k_rad_m, c.direction_rad, c.phase_rad]).collect(),
        )
    }

    /// `(N,)` float64 elevations (m) at world points `x`, `y` (m, `(N,)` each) and time `t` (s).
    fn elevation<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let f = &self.inner;
        Ok(at_points(py, &x, &y, t, |a, b| f.elevation(a, b, t))?.into_pyarray(py))
    }

    /// `(N, 2)` float64 slopes `[∂η/∂x, ∂η/∂y]` at world points `x`, `y` (m) and time `t` (s).
    fn slope<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let f = &self.inner;
        rows_to_array(py, at_points(py, &x, &y, t, |a, b| f.slope(a, b, t))?)
    }

    /// `(N, 3)` float64 orbital velocities (m/s, world) at `(N, 3)` world points (m) and time `t` (s).
    fn orbital_velocity<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = rows::<f64, 3>(&points, "points")?;
        rows_finite(p, "points")?;
        finite_time(t, "t")?;
        let f = &self.inner;
        let out = detached(py, || Ok(p.iter().map(|q| f.orbital_velocity(q[0], q[1], q[2], t)).collect::<Vec<_>>()))?;
        rows_to_array(py, out)
    }

    /// `(ny, nx)` float32 elevations (m): entry `[j, i]` at `(x0 + i·dx, y0 + j·dx)`, time `t` (s).
    #[pyo3(signature = (*, x0, y0, dx, nx, ny, t))]
    #[allow(clippy::too_many_arguments)]
    fn elevation_grid<'py>(
        &self,
        py: Python<'py>,
        x0: f64,
        y0: f64,
        dx: f64,
        nx: usize,
        ny: usize,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let f = &self.inner;
        let g = detached(py, || f.elevation_grid(x0, y0, dx, nx, ny, t))?;
        Array2::from_shape_vec((ny, nx), g)
            .map(|a| a.into_pyarray(py))
            .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))
    }

    /// `(T, 3)` float64 `[heave m, roll rad, pitch rad]` of a hull (`[length, beam, draft, block_coefficient,
    /// gm]`) at `(T, 2)` world positions (m), `(T,)` headings (rad), `(T, 2)` world velocities (m/s) and `(T,)`
    /// times (s), through its closed-form RAOs.
    #[pyo3(signature = (*, hull, positions, yaw, velocities, times))]
    fn hull_response<'py>(
        &self,
        py: Python<'py>,
        hull: [f64; 5],
        positions: PyReadonlyArray2<'py, f64>,
        yaw: PyReadonlyArray1<'py, f64>,
        velocities: PyReadonlyArray2<'py, f64>,
        times: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let h = hull_from(&hull).map_err(to_py)?;
        let (p, v) = (rows::<f64, 2>(&positions, "positions")?, rows::<f64, 2>(&velocities, "velocities")?);
        let (yw, ts) = (flat(&yaw, "yaw")?, flat(&times, "times")?);
        for (name, len) in [("positions", p.len()), ("yaw", yw.len()), ("velocities", v.len())] {
            if len != ts.len() {
                return Err(InputError::new_err(format!("{name} has {len} entries for {} times", ts.len())));
            }
        }
        rows_finite(p, "positions")?;
        all_finite(yw, "yaw")?;
        rows_finite(v, "velocities")?;
        all_finite(ts, "times")?;
        let f = &self.inner;
        let out = detached(py, || {
            use rayon::prelude::*;
            Ok((0..ts.len())
                .into_par_iter()
                .map(|i| response::response(f, &h, p[i][0], p[i][1], yw[i], v[i][0], v[i][1], ts[i])[0])
                .collect::<Vec<_>>())
        })?;
        rows_to_array(py, out)
    }
}

/// The seed of a scenario's wave field (the one every consumer uses).
#[pyfunction]
fn sea_seed(scenario_seed: u64) -> u64 {
    mmusv_core::ocean::sea_seed(scenario_seed)
}

/// `[(name, description, hs_m, tp_s, gamma, wind_mps), ...]`: WMO sea states "0".."9", then the paper's W0..W3.
#[pyfunction]
fn sea_presets() -> Vec<(&'static str, &'static str, f64, f64, f64, f64)> {
    wmo_sea_states()
        .iter()
        .chain(paper_sea_states().iter())
        .map(|p| (p.name, p.description, p.hs_m, p.tp_s, p.gamma, p.wind_mps))
        .collect()
}

/// `(tp_s, wind_mps)` of a fully developed Pierson–Moskowitz sea of significant height `hs_m` (m): the peak
/// period (s) and the wind at 19.5 m, `√(g·hs_m/0.21)` (m/s); the 10 m wind mmusv's sensors take is that / 1.026.
#[pyfunction]
fn fully_developed(hs_m: f64) -> PyResult<(f64, f64)> {
    if !hs_m.is_finite() || hs_m < 0.0 {
        return Err(to_py(MmusvError::config("hs_m", hs_m, "must be a finite significant wave height >= 0 m")));
    }
    Ok(presets::fully_developed(hs_m))
}

/// `{"hs_m": (lo, hi), "tp_s": (lo, hi)}`: the significant heights (m) and peak periods (s) a sea takes
/// (mmusv_core::ocean::field: their one definition, which the scenario schema reads).
#[pyfunction]
fn sea_limits(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    use mmusv_core::ocean::field::{HS_RANGE_M, TP_RANGE_S};
    let d = pyo3::types::PyDict::new(py);
    d.set_item("hs_m", HS_RANGE_M)?;
    d.set_item("tp_s", TP_RANGE_S)?;
    Ok(d)
}

/// DNV-RP-C205 peak enhancement γ for `hs_m`, `tp_s`.
#[pyfunction]
fn dnv_gamma(hs_m: f64, tp_s: f64) -> f64 {
    presets::dnv_gamma(hs_m, tp_s)
}

/// The wave frequencies (rad/s) [`hull_rao`] takes; its encounter frequencies lie within ± the upper one.
const RAO_OMEGA_RAD_S: (f64, f64) = (1e-6, 1e6);

/// `(N, 3)` complex128 RAOs (heave m/m, roll rad/m, pitch rad/m) of a hull `[length, beam, draft,
/// block_coefficient, gm]` for waves of frequency `omega` (rad/s), heading `beta` (rad, 0 following, π head) and
/// encounter frequency `omega_e` (rad/s), all `(N,)`.
#[pyfunction]
#[pyo3(signature = (*, hull, omega, beta, omega_e))]
fn hull_rao<'py>(
    py: Python<'py>,
    hull: [f64; 5],
    omega: PyReadonlyArray1<'py, f64>,
    beta: PyReadonlyArray1<'py, f64>,
    omega_e: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<Complex64>>> {
    let h = hull_from(&hull).map_err(to_py)?;
    let (w, b, we) = (flat(&omega, "omega")?, flat(&beta, "beta")?, flat(&omega_e, "omega_e")?);
    same_len(w, b, "omega", "beta")?;
    same_len(w, we, "omega", "omega_e")?;
    // Outside [1e-6, 1e6] rad/s (periods of 73 days to 6 µs) the closed forms lose every digit to under- and
    // overflow: below about 1e-155 rad/s and above 1e77 they were NaN.
    let (lo, hi) = RAO_OMEGA_RAD_S;
    if let Some(i) = w.iter().position(|v| !(lo..=hi).contains(v)) {
        return Err(not_allowed(
            &format!("omega[{i}]"),
            w[i],
            &format!("a wave frequency within [{lo:e}, {hi:e}] rad/s"),
        ));
    }
    all_finite(b, "beta")?;
    if let Some(i) = we.iter().position(|v| !(-hi..=hi).contains(v)) {
        return Err(not_allowed(
            &format!("omega_e[{i}]"),
            we[i],
            &format!("an encounter frequency within ±{hi:e} rad/s"),
        ));
    }
    let rows: Vec<[Complex64; 3]> = (0..w.len())
        .map(|i| {
            let r = h.rao(w[i], b[i], we[i]);
            [r.heave, r.roll, r.pitch].map(|z| Complex64::new(z[0], z[1]))
        })
        .collect();
    rows_to_array(py, rows)
}

/// `(heave m², roll rad², pitch rad²)`: the spectral prediction ∫∫|RAO|² S D of a hull `[length, beam, draft,
/// block_coefficient, gm]` at heading `yaw` (rad) and speed `speed_mps` in the sea given by its parameters.
#[pyfunction]
#[pyo3(signature = (*, hull, hs_m, tp_s, gamma, direction_rad, spread_s, yaw, speed_mps))]
#[allow(clippy::too_many_arguments)]
fn response_variance(
    py: Python<'_>,
    hull: [f64; 5],
    hs_m: f64,
    tp_s: f64,
    gamma: f64,
    direction_rad: f64,
    spread_s: f64,
    yaw: f64,
    speed_mps: f64,
) -> PyResult<(f64, f64, f64)> {
    let h = hull_from(&hull).map_err(to_py)?;
    let spec = SeaSpec { hs: hs_m, tp: tp_s, gamma, direction_rad, spread_s };
    let v = detached(py, || response::response_variance(&h, &spec, yaw, speed_mps))?;
    Ok((v[0], v[1], v[2]))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<WaveField>()?;
    m.add_function(wrap_pyfunction!(sea_seed, m)?)?;
    m.add_function(wrap_pyfunction!(sea_presets, m)?)?;
    m.add_function(wrap_pyfunction!(fully_developed, m)?)?;
    m.add_function(wrap_pyfunction!(sea_limits, m)?)?;
    m.add_function(wrap_pyfunction!(dnv_gamma, m)?)?;
    m.add_function(wrap_pyfunction!(hull_rao, m)?)?;
    m.add_function(wrap_pyfunction!(response_variance, m)?)?;
    Ok(())
}
