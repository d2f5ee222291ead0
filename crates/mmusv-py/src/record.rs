//! Bindings for `mmusv_core::record`: the MCAP recorder, numpy arrays in.
//!
//! Concurrency: the core recorder sits behind a mutex that is only ever locked inside [`detached`] (GIL
//! released), so a thread waiting for it never holds the GIL and two Python threads cannot deadlock.
//! `images` encodes before it takes the lock: the lock is held only to append the finished messages.

mod arrays;

use crate::errors::InputError;
use crate::native::{detached, flat, rows};
use mmusv_core::record::{
    encode_images, AgentAnnotations, BevBox, Box2D, Box3D, BoxMarker, Column, ImageBox, ImageFormat, ImageJob,
    PackedType, Recorder as CoreRecorder, Transform, VesselState, WorldState,
};
use mmusv_core::MmusvError;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use arrays::{same_len, ColumnArray, ImageArray};

/// Streams messages into one MCAP file (see `mmusv.record.Recording` for the documented wrapper).
#[pyclass(frozen, module = "mmusv._core")]
pub struct Recorder {
    inner: Mutex<Option<CoreRecorder>>,
    path: PathBuf,
    /// Whether `finish()` (or a clean `with` exit) closed it: the file then has its final name.
    finished: AtomicBool,
}

impl Recorder {
    /// Runs `f` on the open recorder with the GIL released.
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut CoreRecorder) -> mmusv_core::Result<T> + Send,
    ) -> PyResult<T> {
        detached(py, || self.locked(f))
    }

    /// Runs `f` on the open recorder under its lock (call with the GIL released, inside [`detached`]).
    fn locked<T>(&self, f: impl FnOnce(&mut CoreRecorder) -> mmusv_core::Result<T>) -> mmusv_core::Result<T> {
        let mut guard = self.inner.lock().map_err(|_| self.closed_error("an earlier internal error"))?;
        let rec = guard.as_mut().ok_or_else(|| self.closed_error("finish() or abandon() was called"))?;
        f(rec)
    }

    /// Takes the recorder out (GIL released); `None` when it is already closed.
    fn take(&self, py: Python<'_>) -> PyResult<Option<CoreRecorder>> {
        detached(py, || Ok(self.inner.lock().map_err(|_| self.closed_error("an earlier internal error"))?.take()))
    }

    fn closed_error(&self, why: &str) -> MmusvError {
        MmusvError::Io { path: self.path.display().to_string(), reason: format!("the recording is closed: {why}") }
    }

    fn finish_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rec =
            self.take(py)?.ok_or_else(|| crate::errors::to_py(self.closed_error("finish() was already called")))?;
        let s = detached(py, || rec.finish())?;
        self.finished.store(true, Ordering::Relaxed);
        let d = PyDict::new(py);
        d.set_item("path", s.path.display().to_string())?;
        d.set_item("messages", s.messages)?;
        d.set_item("channels", s.channels)?;
        d.set_item("bytes", s.bytes)?;
        Ok(d)
    }
}

#[pymethods]
impl Recorder {
    /// Starts a recording named `path`, written as `<path>.partial` until `finish()`.
    #[new]
    #[pyo3(signature = (path, *, overwrite = false))]
    fn new(py: Python<'_>, path: PathBuf, overwrite: bool) -> PyResult<Self> {
        let rec = detached(py, || CoreRecorder::create(&path, overwrite))?;
        Ok(Self { inner: Mutex::new(Some(rec)), path, finished: AtomicBool::new(false) })
    }

    /// The final file name.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// The name written to until `finish()`.
    #[getter]
    fn partial_path(&self) -> String {
        mmusv_core::record::partial_path(&self.path).display().to_string()
    }

    /// True once `finish()` or `abandon()` ran.
    #[getter]
    fn closed(&self, py: Python<'_>) -> PyResult<bool> {
        detached(py, || Ok(self.inner.lock().map(|g| g.is_none()).unwrap_or(true)))
    }

    /// `foxglove.PointCloud` from named 1-D columns (one value per point), packed row-interleaved.
    #[pyo3(signature = (topic, *, log_time_ns, frame_id, names, columns, pose = None))]
    #[allow(clippy::too_many_arguments)]
    fn point_cloud(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        names: Vec<String>,
        columns: Vec<Bound<'_, PyAny>>,
        pose: Option<[f64; 7]>,
    ) -> PyResult<()> {
        same_len(names.len(), "names", &[("columns", columns.len())])?;
        let arrays =
            names.iter().zip(&columns).map(|(n, c)| ColumnArray::from_any(c, n)).collect::<PyResult<Vec<_>>>()?;
        let cols = names
            .iter()
            .zip(&arrays)
            .map(|(n, a)| Ok((n.as_str(), a.column(n)?)))
            .collect::<PyResult<Vec<(&str, Column<'_>)>>>()?;
        self.with(py, |r| {
            let packed = mmusv_core::record::pack_columns(&cols)?;
            let fields: Vec<(&str, PackedType)> = packed.fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
            r.point_cloud(topic, log_time_ns, frame_id, pose, &fields, packed.stride, &packed.data)
        })
    }

    /// `foxglove.RawImage`; the encoding follows from the array (mono8, rgb8, 16UC1, 32FC1).
    #[pyo3(signature = (topic, *, log_time_ns, frame_id, image))]
    fn raw_image(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        image: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let arr = ImageArray::from_any(image)?;
        let (w, h, px) = arr.pixels()?;
        self.with(py, |r| r.pixels(topic, log_time_ns, frame_id, w, h, &px))
    }

    /// `foxglove.CompressedImage` (PNG) of a uint8 gray/RGB or uint16 gray image.
    #[pyo3(signature = (topic, *, log_time_ns, frame_id, image))]
    fn png_image(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        image: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let arr = ImageArray::from_any(image)?;
        let (w, h, px) = arr.pixels()?;
        self.with(py, |r| r.png_image(topic, log_time_ns, frame_id, w, h, &px))
    }

    /// Several images at one time: image `i` goes to `topics[i]` in `frame_ids[i]`, stored as `formats[i]`
    /// (`"png"`: `foxglove.CompressedImage`, `"raw"`: `foxglove.RawImage`). They are encoded in parallel
    /// before the recorder is locked, then written in list order (the bytes of one call per image). Returns
    /// the wall seconds spent encoding and writing (for profiling).
    #[pyo3(signature = (*, log_time_ns, topics, frame_ids, images, formats))]
    fn images(
        &self,
        py: Python<'_>,
        log_time_ns: u64,
        topics: Vec<String>,
        frame_ids: Vec<String>,
        images: Vec<Bound<'_, PyAny>>,
        formats: Vec<String>,
    ) -> PyResult<(f64, f64)> {
        let n = topics.len();
        same_len(n, "topics", &[("frame_ids", frame_ids.len()), ("images", images.len()), ("formats", formats.len())])?;
        let arrays = images.iter().map(ImageArray::from_any).collect::<PyResult<Vec<_>>>()?;
        let mut jobs = Vec::with_capacity(n);
        for (i, arr) in arrays.iter().enumerate() {
            let (width, height, pixels) = arr.pixels()?;
            let format = match formats[i].as_str() {
                "png" => ImageFormat::Png,
                "raw" => ImageFormat::Raw,
                other => {
                    return Err(InputError::new_err(format!("formats[{i}] must be \"png\" or \"raw\", got {other:?}")))
                }
            };
            jobs.push(ImageJob { topic: &topics[i], frame_id: &frame_ids[i], width, height, pixels, format });
        }
        detached(py, || {
            let start = Instant::now();
            let encoded = encode_images(log_time_ns, &jobs)?;
            let encoded_at = Instant::now();
            self.locked(|r| r.write_messages(log_time_ns, &encoded))?;
            Ok(((encoded_at - start).as_secs_f64(), encoded_at.elapsed().as_secs_f64()))
        })
    }

    /// `foxglove.FrameTransforms`: transform `i` is the pose of `children[i]` in `parents[i]`.
    #[pyo3(signature = (topic, *, log_time_ns, parents, children, translations, rotations))]
    #[allow(clippy::too_many_arguments)]
    fn frame_transforms(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        parents: Vec<String>,
        children: Vec<String>,
        translations: PyReadonlyArray2<'_, f64>,
        rotations: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let t = rows::<f64, 3>(&translations, "translations")?;
        let q = rows::<f64, 4>(&rotations, "rotations")?;
        let n = parents.len();
        same_len(n, "parents", &[("children", children.len()), ("translations", t.len()), ("rotations", q.len())])?;
        let transforms: Vec<Transform> = parents
            .into_iter()
            .zip(children)
            .zip(t.iter().zip(q))
            .map(|((parent, child), (translation, rotation))| Transform {
                parent,
                child,
                translation: *translation,
                rotation: *rotation,
            })
            .collect();
        self.with(py, |r| r.frame_transforms(topic, log_time_ns, &transforms))
    }

    /// `foxglove.CameraCalibration` of a pinhole camera: intrinsics `(fx, fy, cx, cy)` pixels in OpenCV's
    /// convention (pixel centres at whole numbers), `distortion` `(k1, k2, p1, p2, k3)` (`plumb_bob`).
    #[pyo3(signature = (topic, *, log_time_ns, frame_id, width, height, intrinsics, distortion))]
    #[allow(clippy::too_many_arguments)]
    fn camera_calibration(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        width: u32,
        height: u32,
        intrinsics: [f64; 4],
        distortion: [f64; 5],
    ) -> PyResult<()> {
        self.with(py, |r| r.camera_calibration(topic, log_time_ns, frame_id, width, height, intrinsics, distortion))
    }

    /// `foxglove.ImageAnnotations` of 2D boxes: `corners` `(N, 4)` float64 `[x0, y0, x1, y1]` pixels (origin at the
    /// top-left corner of the top-left pixel), `colors` `(N, 4)` float32 RGBA in [0, 1], `labels` N strings.
    #[pyo3(signature = (topic, *, log_time_ns, corners, colors, labels))]
    fn image_boxes(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        corners: PyReadonlyArray2<'_, f64>,
        colors: PyReadonlyArray2<'_, f32>,
        labels: Vec<String>,
    ) -> PyResult<()> {
        let c = rows::<f64, 4>(&corners, "corners")?;
        let col = rows::<f32, 4>(&colors, "colors")?;
        same_len(c.len(), "corners", &[("colors", col.len()), ("labels", labels.len())])?;
        let boxes: Vec<ImageBox> =
            labels.into_iter().enumerate().map(|(i, label)| ImageBox { corners: c[i], color: col[i], label }).collect();
        self.with(py, |r| r.image_boxes(topic, log_time_ns, &boxes))
    }

    /// `foxglove.SceneUpdate` with one entity of cubes (and labels).
    #[pyo3(signature = (topic, *, log_time_ns, frame_id, entity_id, ids, centers, quaternions, sizes, colors, labels))]
    #[allow(clippy::too_many_arguments)]
    fn boxes(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        entity_id: &str,
        ids: Vec<String>,
        centers: PyReadonlyArray2<'_, f64>,
        quaternions: PyReadonlyArray2<'_, f64>,
        sizes: PyReadonlyArray2<'_, f64>,
        colors: PyReadonlyArray2<'_, f32>,
        labels: Vec<String>,
    ) -> PyResult<()> {
        let c = rows::<f64, 3>(&centers, "centers")?;
        let q = rows::<f64, 4>(&quaternions, "quaternions")?;
        let s = rows::<f64, 3>(&sizes, "sizes")?;
        let col = rows::<f32, 4>(&colors, "colors")?;
        let n = ids.len();
        same_len(
            n,
            "ids",
            &[
                ("centers", c.len()),
                ("quaternions", q.len()),
                ("sizes", s.len()),
                ("colors", col.len()),
                ("labels", labels.len()),
            ],
        )?;
        let boxes: Vec<BoxMarker> = ids
            .into_iter()
            .zip(labels)
            .enumerate()
            .map(|(i, (id, label))| BoxMarker { id, center: c[i], quaternion: q[i], size: s[i], color: col[i], label })
            .collect();
        self.with(py, |r| r.boxes(topic, log_time_ns, frame_id, entity_id, &boxes))
    }

    /// The project's own `mmusv.WorldState`, one row per vessel.
    #[pyo3(signature = (topic, *, log_time_ns, frame, time_s, ids, assets, roles, classes, instance_ids, poses, velocities, box_centers, box_sizes))]
    #[allow(clippy::too_many_arguments)]
    fn world_state(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame: u64,
        time_s: f64,
        ids: Vec<String>,
        assets: Vec<String>,
        roles: Vec<String>,
        classes: PyReadonlyArray1<'_, u32>,
        instance_ids: PyReadonlyArray1<'_, u32>,
        poses: PyReadonlyArray2<'_, f64>,
        velocities: PyReadonlyArray2<'_, f64>,
        box_centers: PyReadonlyArray2<'_, f64>,
        box_sizes: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let cls = flat(&classes, "classes")?;
        let inst = flat(&instance_ids, "instance_ids")?;
        let p = rows::<f64, 6>(&poses, "poses")?;
        let v = rows::<f64, 3>(&velocities, "velocities")?;
        let bc = rows::<f64, 3>(&box_centers, "box_centers")?;
        let bs = rows::<f64, 3>(&box_sizes, "box_sizes")?;
        let n = ids.len();
        same_len(
            n,
            "ids",
            &[
                ("assets", assets.len()),
                ("roles", roles.len()),
                ("classes", cls.len()),
                ("instance_ids", inst.len()),
                ("poses", p.len()),
                ("velocities", v.len()),
                ("box_centers", bc.len()),
                ("box_sizes", bs.len()),
            ],
        )?;
        let vessels = (0..n)
            .map(|i| VesselState {
                id: ids[i].clone(),
                asset: assets[i].clone(),
                role: roles[i].clone(),
                semantic_class: cls[i],
                instance_id: inst[i],
                pose: p[i].to_vec(),
                velocity: v[i].to_vec(),
                box_center: bc[i].to_vec(),
                box_size: bs[i].to_vec(),
            })
            .collect();
        let state = WorldState { frame, time_s, vessels };
        self.with(py, |r| r.world_state(topic, log_time_ns, &state))
    }

    /// The project's own `mmusv.AgentAnnotations` from packed columns (see the stub for the column order).
    #[pyo3(signature = (topic, *, log_time_ns, frame, time_s, agent_id, lidar_ids, lidar_ints, lidar_values, bev_ids, bev_values, camera_ids, camera_names, camera_ints, camera_values))]
    #[allow(clippy::too_many_arguments)]
    fn annotations(
        &self,
        py: Python<'_>,
        topic: &str,
        log_time_ns: u64,
        frame: u64,
        time_s: f64,
        agent_id: String,
        lidar_ids: Vec<String>,
        lidar_ints: PyReadonlyArray2<'_, u32>,
        lidar_values: PyReadonlyArray2<'_, f64>,
        bev_ids: Vec<String>,
        bev_values: PyReadonlyArray2<'_, f64>,
        camera_ids: Vec<String>,
        camera_names: Vec<String>,
        camera_ints: PyReadonlyArray2<'_, u32>,
        camera_values: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let li = rows::<u32, 3>(&lidar_ints, "lidar_ints")?;
        let lv = rows::<f64, 13>(&lidar_values, "lidar_values")?;
        same_len(lidar_ids.len(), "lidar_ids", &[("lidar_ints", li.len()), ("lidar_values", lv.len())])?;
        let bv = rows::<f64, 5>(&bev_values, "bev_values")?;
        same_len(bev_ids.len(), "bev_ids", &[("bev_values", bv.len())])?;
        let ci = rows::<u32, 2>(&camera_ints, "camera_ints")?;
        let cv = rows::<f64, 7>(&camera_values, "camera_values")?;
        same_len(
            camera_ids.len(),
            "camera_ids",
            &[("camera_names", camera_names.len()), ("camera_ints", ci.len()), ("camera_values", cv.len())],
        )?;
        let boxes_lidar = lidar_ids
            .into_iter()
            .zip(li.iter().zip(lv))
            .map(|(target_id, (i, v))| Box3D {
                target_id,
                instance_id: i[0],
                semantic_class: i[1],
                center: v[0..3].to_vec(),
                size: v[3..6].to_vec(),
                rotation: v[6..10].to_vec(),
                yaw: v[10],
                lidar_points: i[2],
                range_m: v[11],
                wave_occlusion: v[12],
            })
            .collect();
        let boxes_bev = bev_ids
            .into_iter()
            .zip(bv)
            .map(|(target_id, v)| BevBox { target_id, x: v[0], y: v[1], length: v[2], width: v[3], yaw: v[4] })
            .collect();
        let boxes_camera = camera_ids
            .into_iter()
            .zip(camera_names)
            .zip(ci.iter().zip(cv))
            .map(|((target_id, camera), (i, v))| Box2D {
                target_id,
                camera,
                x_min: v[0],
                y_min: v[1],
                x_max: v[2],
                y_max: v[3],
                truncation: v[4],
                visible_pixels: i[0],
                box_pixels: i[1],
                occlusion: v[5],
                wave_occlusion: v[6],
            })
            .collect();
        let ann = AgentAnnotations { frame, time_s, agent_id, boxes_lidar, boxes_bev, boxes_camera };
        self.with(py, |r| r.annotations(topic, log_time_ns, &ann))
    }

    /// An MCAP metadata record `name` holding `mapping`.
    fn metadata(&self, py: Python<'_>, name: &str, mapping: BTreeMap<String, String>) -> PyResult<()> {
        self.with(py, |r| r.metadata(name, &mapping))
    }

    /// An MCAP attachment (e.g. the scenario file).
    #[pyo3(signature = (name, *, media_type, data, log_time_ns = 0))]
    fn attachment(
        &self,
        py: Python<'_>,
        name: &str,
        media_type: &str,
        data: Vec<u8>,
        log_time_ns: u64,
    ) -> PyResult<()> {
        self.with(py, |r| r.attachment(name, media_type, log_time_ns, &data))
    }

    /// Completes the file and renames it into place; returns `{path, messages, channels, bytes}`.
    fn finish<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.finish_dict(py)
    }

    /// Completes the file but keeps the `.partial` name; returns that path. A no-op once closed, returning where
    /// the file is: the final name after `finish()` (it returned the `.partial` name, a file no longer there).
    fn abandon(&self, py: Python<'_>) -> PyResult<String> {
        if let Some(rec) = self.take(py)? {
            return Ok(detached(py, || rec.abandon())?.display().to_string());
        }
        if self.finished.load(Ordering::Relaxed) {
            return Ok(self.path.display().to_string());
        }
        Ok(self.partial_path())
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// Finishes on a clean exit; on an exception completes the file under the `.partial` name. Never
    /// swallows the exception.
    #[pyo3(signature = (exc_type = None, exc_value = None, traceback = None))]
    fn __exit__(
        &self,
        py: Python<'_>,
        exc_type: Option<&Bound<'_, PyAny>>,
        exc_value: Option<&Bound<'_, PyAny>>,
        traceback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        let _ = (exc_value, traceback);
        let Some(rec) = self.take(py)? else { return Ok(false) };
        match exc_type {
            Some(_) => detached(py, || rec.abandon().map(|_| ()))?,
            None => {
                detached(py, || rec.finish().map(|_| ()))?;
                self.finished.store(true, Ordering::Relaxed);
            }
        }
        Ok(false)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let state = detached(py, || {
            Ok(match self.inner.lock().as_deref() {
                Ok(Some(r)) => format!("open, {} messages", r.messages()),
                _ => "closed".to_string(),
            })
        })?;
        Ok(format!("Recorder(path={:?}, {state})", self.path.display().to_string()))
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Recorder>()
}
