//! Bindings for `mmusv_core::sensors::capture`: every sensor of a frame in one call, GIL released.

use crate::camera::{frame_dict, Camera};
use crate::errors::InputError;
use crate::lidar::{scan_dict, Lidar};
use crate::native::{detached, pose_arg};
use crate::radar::{returns_dict, Radar};
use crate::scene::Scene;
use crate::shade::SensorEnv;
use mmusv_core::sensors::capture::{self, PpiRequest, SensorOutput, SensorTask};
use mmusv_core::sensors::ppi::{PpiConfig, PpiOrientation};
use mmusv_core::RigidPose;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

/// One parsed task: the sensor object (kept alive while the core borrows it), pose, seed and PPI request.
struct Item<'py> {
    sensor: Bound<'py, PyAny>,
    pose: RigidPose,
    seed: u64,
    ppi: Option<PpiRequest>,
}

fn parse_item<'py>(i: usize, obj: &Bound<'py, PyAny>) -> PyResult<Item<'py>> {
    let shape = || {
        InputError::new_err(format!(
            "tasks[{i}] must be (sensor, pose, seed) or (radar, pose, seed, ppi) with ppi None or \
             (size_px, metres_per_pixel, orientation, sensor_yaw)"
        ))
    };
    let t = obj.cast::<PyTuple>().map_err(|_| shape())?;
    if !(3..=4).contains(&t.len()) {
        return Err(shape());
    }
    let pose: PyReadonlyArray2<'py, f64> = t.get_item(1)?.extract().map_err(|_| {
        InputError::new_err(format!("tasks[{i}].pose must be a (4, 4) float64 array (sensor -> world)"))
    })?;
    let pose = pose_arg(&pose, &format!("tasks[{i}].pose"))?;
    let seed: u64 = t
        .get_item(2)?
        .extract()
        .map_err(|_| InputError::new_err(format!("tasks[{i}].seed must be an integer in 0..2**64")))?;
    let ppi = match t.len() {
        4 if !t.get_item(3)?.is_none() => {
            let (size_px, metres_per_pixel, orientation, sensor_yaw): (u32, f32, String, f32) =
                t.get_item(3)?.extract().map_err(|_| shape())?;
            let orientation = PpiOrientation::parse(&orientation).map_err(crate::errors::to_py)?;
            Some(PpiRequest { config: PpiConfig { size_px, metres_per_pixel, orientation }, sensor_yaw })
        }
        _ => None,
    };
    Ok(Item { sensor: t.get_item(0)?, pose, seed, ppi })
}

fn task<'a>(i: usize, item: &'a Item<'_>) -> PyResult<SensorTask<'a>> {
    let (pose, seed) = (item.pose, item.seed);
    let task = if let Ok(l) = item.sensor.cast::<Lidar>() {
        SensorTask::Lidar { lidar: &l.get().inner, pose, seed }
    } else if let Ok(c) = item.sensor.cast::<Camera>() {
        let c = c.get();
        SensorTask::Camera { camera: &c.inner, rgb: c.rgb, pose, seed }
    } else if let Ok(r) = item.sensor.cast::<Radar>() {
        return Ok(SensorTask::Radar { radar: &r.get().cfg, pose, seed, ppi: item.ppi });
    } else {
        let got = item.sensor.get_type().name().map(|n| n.to_string()).unwrap_or_default();
        return Err(PyTypeError::new_err(format!("tasks[{i}][0] must be a Lidar, Camera or Radar, got {got}")));
    };
    if item.ppi.is_some() {
        return Err(InputError::new_err(format!("tasks[{i}]: only a radar task draws a PPI; give None")));
    }
    Ok(task)
}

/// Runs every sensor task of a frame on the current state of `scene` in `env`, concurrently (see
/// `mmusv_core::sensors::capture`), with the GIL released. `tasks`: `(sensor, pose, seed)` with sensor a
/// `Lidar`, `Camera` or `Radar`, pose `(4, 4)` float64 sensor → world, or `(radar, pose, seed, ppi)` with
/// `ppi = (size_px, metres_per_pixel, orientation, sensor_yaw)` or None. Returns, in task order,
/// `(outputs, seconds, ppi_seconds)`: the dict `scan` / `render` / `sweep` return (a radar's with `ppi`
/// `(size_px, size_px)` float32 when asked), and the task's wall seconds (profiling only). `wakes` (K, 6) to
/// (K, 9) float32 are the vessels under way (see `Camera.render`), whose wakes the cameras and LiDARs see.
#[pyfunction]
#[pyo3(signature = (scene, *, env, tasks, wakes=None))]
fn capture_frame<'py>(
    py: Python<'py>,
    scene: &Scene,
    env: &SensorEnv,
    tasks: Vec<Bound<'py, PyAny>>,
    wakes: Option<numpy::PyReadonlyArray2<'py, f32>>,
) -> PyResult<Bound<'py, PyList>> {
    let wakes = crate::shade::wakes_arg(wakes.as_ref())?;
    let items = tasks.iter().enumerate().map(|(i, t)| parse_item(i, t)).collect::<PyResult<Vec<_>>>()?;
    let core_tasks = items.iter().enumerate().map(|(i, it)| task(i, it)).collect::<PyResult<Vec<_>>>()?;
    let shade = &env.shade;
    let results = scene.read(|s| detached(py, || capture::capture_frame(s, shade, &wakes, &core_tasks)))?;
    let out = PyList::empty(py);
    for (r, t) in results.into_iter().zip(&core_tasks) {
        let d = match (r.output, t) {
            (SensorOutput::Lidar(s), _) => scan_dict(py, s)?,
            (SensorOutput::Camera(f), SensorTask::Camera { rgb, .. }) => frame_dict(py, f, *rgb)?,
            (SensorOutput::Radar { returns, ppi }, SensorTask::Radar { ppi: req, .. }) => {
                let d = returns_dict(py, returns)?;
                if let (Some(img), Some(req)) = (ppi, req) {
                    let n = req.config.size_px as usize;
                    let arr = Array2::from_shape_vec((n, n), img)
                        .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))?;
                    d.set_item("ppi", arr.into_pyarray(py))?;
                }
                d
            }
            _ => return Err(crate::errors::InternalError::new_err("a sensor output does not match its task")),
        };
        out.append((d, r.seconds, r.ppi_seconds))?;
    }
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(capture_frame, m)?)
}
