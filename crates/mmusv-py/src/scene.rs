//! Bindings for `mmusv_core::scene`, `mesh` and `export`: build a scene from numpy arrays, place and move
//! instances, cast rays, export the world triangles.

use crate::errors::InputError;
use crate::native::{c_order, detached, flat, pose_from, rows, rows_to_array};
use mmusv_core::export::{write_world_mesh, MeshFormat};
use mmusv_core::ocean::{sea_seed, SeaSpec, WaveField};
use mmusv_core::sea::{SurfaceSpec, WaveSurface};
use mmusv_core::{Mesh, Scene as CoreScene};
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, RwLock};

/// Tuple of arrays returned by `Scene.cast_rays` (see the `.pyi` for shapes and dtypes).
type RayHitArrays<'py> = (
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<i32>>,
    Bound<'py, PyArray1<i32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<u16>>,
    Bound<'py, PyArray1<bool>>,
);

/// Tuple of arrays returned by `Scene.world_mesh`.
type WorldMeshArrays<'py> = (
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<u32>>,
    Bound<'py, PyArray1<u16>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
);

/// A ray-casting scene: meshes (each with a BVH built once) placed as instances.
///
/// Concurrency: the lock guards only an `Arc` to the current scene and is held for a pointer copy (readers) or
/// a short in-place update (writers), never while the GIL is released or re-acquired, so a long cast in one
/// thread and a pose update in another cannot deadlock. A writer that finds a cast still using the old scene
/// copies it first (cheap: meshes are shared `Arc`s); the running cast finishes on the state it started with.
#[pyclass(frozen, module = "mmusv._core")]
pub struct Scene {
    inner: RwLock<Arc<CoreScene>>,
    /// The last wave field drawn by `set_wave_surface`, with its sea and seed (reused while they stay).
    wave_field: Mutex<Option<(SeaSpec, u64, Arc<WaveField>)>>,
    /// A wave surface being sampled ahead by `prefetch_wave_surface`, taken by the `set_wave_surface` that asks
    /// for the same one.
    prefetched: Mutex<Option<Prefetch>>,
}

/// What a wave surface is sampled from: `set_wave_surface`'s arguments, checked. The same key gives the same
/// surface bit for bit, whichever thread samples it.
#[derive(Debug, Clone, PartialEq)]
struct SurfaceKey {
    sea: SeaSpec,
    seed: u64,
    time_s: f64,
    level: f32,
    foci: Vec<[f32; 2]>,
    spec: SurfaceSpec,
}

/// The wave field and the surface of `key`, the field reused from `cached` when it is that sea's.
type Sampled = mmusv_core::Result<(Arc<WaveField>, WaveSurface)>;

/// A surface being sampled on a thread of its own, by process `pid` (a child forked since has no such thread).
struct Prefetch {
    key: SurfaceKey,
    handle: std::thread::JoinHandle<Sampled>,
    pid: u32,
}

/// Samples the surface of `key` (drawing its wave field unless `cached` holds it).
fn sample(key: &SurfaceKey, cached: Option<Arc<WaveField>>) -> Sampled {
    let field = match cached {
        Some(f) => f,
        None => Arc::new(WaveField::new(&key.sea, key.seed)?), // checks the sea (as `surface_key` did)
    };
    let surface = WaveSurface::new(field.components(), key.time_s, key.level, &key.foci, key.spec)?;
    Ok((field, surface))
}

/// Checks `set_wave_surface`'s arguments (errors name the argument); `None` for `hs_m = None` (no surface).
#[allow(clippy::too_many_arguments)]
fn surface_key(
    hs_m: Option<f64>,
    (tp_s, gamma, direction_rad, spread_s): (f64, f64, f64, f64),
    scenario_seed: u64,
    time_s: f64,
    foci: Option<&PyReadonlyArray2<'_, f32>>,
    level: f32,
    (tile_m, near_m, radius_m, taper_m): (f32, f32, f32, f32),
    (detail, slopes, fine_m): (bool, bool, f32),
) -> PyResult<Option<SurfaceKey>> {
    let Some(hs) = hs_m else { return Ok(None) };
    let foci: Vec<[f32; 2]> = match foci {
        Some(f) => rows::<f32, 2>(f, "foci")?.to_vec(),
        None => Vec::new(),
    };
    for (name, v) in [("tile_m", tile_m), ("near_m", near_m), ("radius_m", radius_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(InputError::new_err(format!("{name} = {v} is not allowed; give a distance > 0 metres")));
        }
    }
    if !(fine_m.is_finite() && fine_m >= 0.0) {
        return Err(InputError::new_err(format!("fine_m = {fine_m} is not allowed; give a distance >= 0 metres")));
    }
    if !(taper_m.is_finite() && (0.0..=radius_m).contains(&taper_m)) {
        return Err(InputError::new_err(format!("taper_m = {taper_m} must be in [0, radius_m]")));
    }
    if !(time_s.is_finite() && level.is_finite()) || foci.iter().any(|f| !(f[0].is_finite() && f[1].is_finite())) {
        return Err(InputError::new_err("wave surface: time_s, level and foci must be finite"));
    }
    mmusv_core::sea::check_time(time_s).map_err(crate::errors::to_py)?;
    let spec = SurfaceSpec { tile_m, near_m, radius_m, taper_m, detail, slopes, fine_m };
    // Before any tile is allocated. The sea itself too, here: `prefetch_wave_surface` promises its checks, and a
    // sea checked only where it is sampled (on the prefetch's thread) was refused later, or never.
    spec.check_extent(&foci).map_err(crate::errors::to_py)?;
    let sea = SeaSpec { hs, tp: tp_s, gamma, direction_rad, spread_s };
    sea.validate().map_err(crate::errors::to_py)?;
    Ok(Some(SurfaceKey { sea, seed: sea_seed(scenario_seed), time_s, level, foci, spec }))
}

fn poisoned() -> PyErr {
    crate::errors::InternalError::new_err("scene lock poisoned by an earlier internal error; rebuild the scene")
}

impl Scene {
    /// Wraps a core scene built in Rust.
    pub fn from_core(scene: CoreScene) -> Self {
        Self { inner: RwLock::new(Arc::new(scene)), wave_field: Mutex::new(None), prefetched: Mutex::new(None) }
    }

    /// The wave field last drawn, when it is `key`'s sea's.
    fn cached_field(&self, key: &SurfaceKey) -> PyResult<Option<Arc<WaveField>>> {
        Ok(self
            .wave_field
            .lock()
            .map_err(|_| poisoned())?
            .as_ref()
            .filter(|(s, k, _)| *s == key.sea && *k == key.seed)
            .map(|(_, _, f)| Arc::clone(f)))
    }

    /// Runs `f` on a snapshot of the scene (the lock is released before `f` runs).
    pub fn read<T>(&self, f: impl FnOnce(&CoreScene) -> PyResult<T>) -> PyResult<T> {
        let snapshot = Arc::clone(&*self.inner.read().map_err(|_| poisoned())?);
        f(&snapshot)
    }

    /// Applies `f` to the scene under the write lock (held only for `f`, which must not touch the GIL).
    fn write<T>(&self, f: impl FnOnce(&mut CoreScene) -> T) -> PyResult<T> {
        let mut guard = self.inner.write().map_err(|_| poisoned())?;
        Ok(f(Arc::make_mut(&mut guard)))
    }
}

#[pymethods]
impl Scene {
    #[new]
    fn new() -> Self {
        Self::from_core(CoreScene::new())
    }

    /// Adds a mesh; builds its BVH with the GIL released. Returns the mesh id. `materials`: one index or one
    /// per face into the scene's material table (0: none); an index past a table already set is an error.
    #[pyo3(signature = (vertices, faces, classes, name, materials=None))]
    fn add_mesh(
        &self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f32>,
        faces: PyReadonlyArray2<'_, i64>,
        classes: PyReadonlyArray1<'_, u16>,
        name: &str,
        materials: Option<PyReadonlyArray1<'_, u16>>,
    ) -> PyResult<u32> {
        let v = rows::<f32, 3>(&vertices, "vertices")?;
        let f = rows::<i64, 3>(&faces, "faces")?;
        let c = flat(&classes, "classes")?;
        let m: &[u16] = match &materials {
            Some(m) => flat(m, "materials")?,
            None => &[],
        };
        let mesh = detached(py, || Mesh::new(name, v, f, c).and_then(|mesh| mesh.with_materials(m)))?;
        let limit = self.read(|s| Ok(s.num_materials()))?;
        if mesh.max_material() > 0 && mesh.max_material() as usize >= limit {
            return Err(InputError::new_err(format!(
                "materials: mesh '{name}' uses material {} but the scene's table has {limit} rows (set_materials first)",
                mesh.max_material()
            )));
        }
        self.write(|s| s.add_mesh(mesh))
    }

    /// Sets the material table `(M, 11)` float32, one row per material: r, g, b (linear base colour),
    /// roughness, metallic, er, eg, eb (emitted radiance, cd/m²), nav_light (0 or 1), the light's arc centre and
    /// half-width (degrees, body frame: 0 right ahead, +90 to port; 180 all round). Row 0 is never read.
    fn set_materials(&self, table: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let rows = rows::<f32, { mmusv_core::material::COLUMNS }>(&table, "materials")?;
        let mats = rows
            .iter()
            .enumerate()
            .map(|(i, r)| mmusv_core::material::Material::from_row(i, r))
            .collect::<mmusv_core::Result<Vec<_>>>()
            .map_err(crate::errors::to_py)?;
        self.write(|s| s.set_materials(mats))?.map_err(crate::errors::to_py)
    }

    /// Sets the seabed under the water for the cameras' shallow-water optics: heights `z` (ny, nx) float32
    /// metres (world z, negative below the surface) at vertices `(x0 + j·spacing, y0 + i·spacing)`; `None`
    /// clears it.
    #[pyo3(signature = (z, *, x0=0.0, y0=0.0, spacing=1.0))]
    fn set_seabed(&self, z: Option<PyReadonlyArray2<'_, f32>>, x0: f32, y0: f32, spacing: f32) -> PyResult<()> {
        let seabed = match z {
            None => None,
            Some(z) => {
                let shape = z.shape();
                let (ny, nx) = (shape[0], shape[1]);
                let data = c_order(&z, "seabed heights")?;
                Some(
                    mmusv_core::seabed::Seabed::new(x0, y0, spacing, nx, ny, data.to_vec())
                        .map_err(crate::errors::to_py)?,
                )
            }
        };
        self.write(|s| s.set_seabed(seabed))
    }

    /// Rows of the material table (0 before `set_materials`).
    #[getter]
    fn num_materials(&self) -> PyResult<usize> {
        self.read(|s| Ok(s.num_materials()))
    }

    /// Turns the navigation lights of instances `ids` (K,) uint32 on or off.
    fn set_lights(&self, ids: PyReadonlyArray1<'_, u32>, on: bool) -> PyResult<()> {
        let ids = flat(&ids, "instance_ids")?;
        self.write(|s| s.set_lights(ids, on))?.map_err(crate::errors::to_py)
    }

    /// Places mesh `mesh_id` at `pose` (4x4 float64); returns the instance id.
    #[pyo3(signature = (mesh_id, pose, class_override=None))]
    fn add_instance(
        &self,
        mesh_id: u32,
        pose: PyReadonlyArray2<'_, f64>,
        class_override: Option<u16>,
    ) -> PyResult<u32> {
        if pose.shape() != [4, 4] {
            return Err(InputError::new_err(format!("pose must have shape (4, 4), got {:?}", pose.shape())));
        }
        let p = pose_from(flat_2d(&pose)?, "pose")?;
        self.write(|s| s.add_instance(mesh_id, p, class_override))?.map_err(crate::errors::to_py)
    }

    /// Moves instances `ids` (K,) to `poses` (K, 4, 4); rebuilds only the top-level BVH.
    fn set_poses(&self, ids: PyReadonlyArray1<'_, u32>, poses: PyReadonlyArray3<'_, f64>) -> PyResult<()> {
        let ids = flat(&ids, "instance_ids")?;
        let shape = poses.shape();
        if shape[1] != 4 || shape[2] != 4 || shape[0] != ids.len() {
            return Err(InputError::new_err(format!(
                "poses must have shape ({}, 4, 4) for {} ids, got {shape:?}",
                ids.len(),
                ids.len()
            )));
        }
        let data = c_order(&poses, "poses")?;
        let parsed = data
            .chunks_exact(16)
            .enumerate()
            .map(|(i, m)| pose_from(m, &format!("poses[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        self.write(|s| s.set_poses(ids, &parsed))?.map_err(crate::errors::to_py)
    }

    /// Declares instance `surface` the sea surface (a horizontal plane) and `moving` the instances that will
    /// move, enabling the exact sea and sky shortcuts (see mmusv_core::sea). Builds the height map with the GIL
    /// released.
    #[pyo3(signature = (surface, moving))]
    fn set_sea(&self, py: Python<'_>, surface: u32, moving: PyReadonlyArray1<'_, u32>) -> PyResult<()> {
        let moving = flat(&moving, "moving")?.to_vec();
        // Built on a snapshot with the GIL released, installed under the write lock: the install keeps a
        // `set_poses` made meanwhile (writing the snapshot back lost it) and rebuilds a grid whose fixed geometry
        // changed.
        let snapshot = Arc::clone(&*self.inner.read().map_err(|_| poisoned())?);
        let prepared = detached(py, || snapshot.prepare_sea(surface, &moving))?;
        self.write(|s| s.install_sea(prepared))?.map_err(crate::errors::to_py)
    }

    /// Sets the displaced sea surface of the current frame (see mmusv_core::sea::WaveSurface): the wave field
    /// of the directional JONSWAP sea `hs_m`, `tp_s`, `gamma`, `direction_rad`, `spread_s` drawn from the scenario's
    /// sea seed (mmusv_core::ocean::WaveField, `sea_seed(scenario_seed)`: the field the hulls ride), sampled at `time_s` around `foci` (F, 2) float32 world x, y; `hs_m=None`
    /// clears it; `detail`: the finest tiles also carry the short waves' slopes for the cameras' shading
    /// (mmusv_core::sea::SurfaceSpec::detail); `slopes`: the tiles carry the slopes the cameras shade with at all
    /// (mmusv_core::sea::SurfaceSpec::slopes; off: heights alone, for scenes nothing renders); `fine_m`: with
    /// `detail`, the coarser tiles within this distance of a focus also carry the finest grid's slopes, so a top
    /// view shades every level alike (mmusv_core::sea::SurfaceSpec::fine_m; 0: none). Samples with the
    /// GIL released, or takes the surface `prefetch_wave_surface` sampled ahead with the same arguments.
    #[pyo3(signature = (hs_m, *, tp_s=8.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, scenario_seed=0, time_s=0.0, foci=None, level=0.0, tile_m=32.0, near_m=40.0, radius_m=320.0, taper_m=60.0, detail=false, slopes=true, fine_m=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn set_wave_surface(
        &self,
        py: Python<'_>,
        hs_m: Option<f64>,
        tp_s: f64,
        gamma: f64,
        direction_rad: f64,
        spread_s: f64,
        scenario_seed: u64,
        time_s: f64,
        foci: Option<PyReadonlyArray2<'_, f32>>,
        level: f32,
        tile_m: f32,
        near_m: f32,
        radius_m: f32,
        taper_m: f32,
        detail: bool,
        slopes: bool,
        fine_m: f32,
    ) -> PyResult<()> {
        let key = surface_key(
            hs_m,
            (tp_s, gamma, direction_rad, spread_s),
            scenario_seed,
            time_s,
            foci.as_ref(),
            level,
            (tile_m, near_m, radius_m, taper_m),
            (detail, slopes, fine_m),
        )?;
        let mut ahead = self.prefetched.lock().map_err(|_| poisoned())?.take();
        if ahead.as_ref().is_some_and(|p| p.pid != std::process::id()) {
            // Started by the process this one was forked from: its thread is not here, so it is neither joined
            // nor detached, just forgotten (and the surface is sampled again).
            std::mem::forget(ahead.take());
        }
        let Some(key) = key else {
            return self.write(|s| s.set_wave_surface(None))?.map_err(crate::errors::to_py);
        };
        if self.read(|s| Ok(s.sea_instance().is_none()))? {
            // Refused before the surface is sampled (seconds for a wide one), not after, as the core would.
            // An empty surface (no waves) costs nothing and gets the core's own refusal.
            let none = WaveSurface::new(&[], key.time_s, key.level, &[], key.spec).map_err(crate::errors::to_py)?;
            return self.write(|s| s.set_wave_surface(Some(none)))?.map_err(crate::errors::to_py);
        }
        let (field, surface) = match ahead {
            // Sampled ahead from the same arguments: the same surface, waited for (a panic there is re-raised
            // here, and reported as one).
            Some(p) if p.key == key => {
                detached(py, || p.handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))?
            }
            _ => {
                let cached = self.cached_field(&key)?;
                detached(py, || sample(&key, cached))?
            }
        };
        *self.wave_field.lock().map_err(|_| poisoned())? = Some((key.sea, key.seed, field));
        self.write(|s| s.set_wave_surface(Some(surface)))?.map_err(crate::errors::to_py)
    }

    /// Starts sampling, on a thread of its own, the wave surface that `set_wave_surface` with the same arguments
    /// will set (a later frame's, while the current one is annotated and written); that call then takes it
    /// instead of sampling it again, and any other call leaves it unused. The same surface bit for bit: the
    /// sampling depends on the arguments alone. Arguments are checked as `set_wave_surface` checks them;
    /// `hs_m=None` drops a surface being sampled ahead.
    #[pyo3(signature = (hs_m, *, tp_s=8.0, gamma=3.3, direction_rad=0.0, spread_s=10.0, scenario_seed=0, time_s=0.0, foci=None, level=0.0, tile_m=32.0, near_m=40.0, radius_m=320.0, taper_m=60.0, detail=false, slopes=true, fine_m=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn prefetch_wave_surface(
        &self,
        hs_m: Option<f64>,
        tp_s: f64,
        gamma: f64,
        direction_rad: f64,
        spread_s: f64,
        scenario_seed: u64,
        time_s: f64,
        foci: Option<PyReadonlyArray2<'_, f32>>,
        level: f32,
        tile_m: f32,
        near_m: f32,
        radius_m: f32,
        taper_m: f32,
        detail: bool,
        slopes: bool,
        fine_m: f32,
    ) -> PyResult<()> {
        let key = surface_key(
            hs_m,
            (tp_s, gamma, direction_rad, spread_s),
            scenario_seed,
            time_s,
            foci.as_ref(),
            level,
            (tile_m, near_m, radius_m, taper_m),
            (detail, slopes, fine_m),
        )?;
        let Some(key) = key else {
            *self.prefetched.lock().map_err(|_| poisoned())? = None;
            return Ok(());
        };
        let cached = self.cached_field(&key)?;
        let job = key.clone();
        // Where no thread can be started (a process at its limit), nothing is sampled ahead: the frame's own
        // `set_wave_surface` samples it, the same surface.
        let handle = std::thread::Builder::new()
            .name("mmusv-wave-surface".into())
            .spawn(move || mmusv_core::threads::run(|| sample(&job, cached)));
        let pid = std::process::id();
        *self.prefetched.lock().map_err(|_| poisoned())? = handle.ok().map(|handle| Prefetch { key, handle, pid });
        Ok(())
    }

    /// Heights (N,) float32 of the displaced sea surface at `xy` (N, 2) float32 world x, y (the still level
    /// where no surface is set or outside it). GIL released.
    fn wave_heights<'py>(
        &self,
        py: Python<'py>,
        xy: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let xy = rows::<f32, 2>(&xy, "xy")?;
        let out = self.read(|s| {
            detached(py, || {
                Ok(match s.wave_surface() {
                    Some(w) => xy.iter().map(|p| w.height(p[0], p[1])).collect::<Vec<f32>>(),
                    None => vec![0.0; xy.len()],
                })
            })
        })?;
        Ok(out.into_pyarray(py))
    }

    /// The crest bound (highest world z) of the displaced sea surface, or None when none is set.
    #[getter]
    fn wave_top(&self) -> PyResult<Option<f32>> {
        self.read(|s| Ok(s.wave_surface().map(|w| w.zmax())))
    }

    /// Forgets the sea surface: every ray is traced fully again.
    fn clear_sea(&self) -> PyResult<()> {
        self.write(|s| s.clear_sea())
    }

    /// The sea surface instance id, or None.
    #[getter]
    fn sea_instance(&self) -> PyResult<Option<u32>> {
        self.read(|s| Ok(s.sea_instance()))
    }

    /// Casts rays (GIL released, all cores). Returns
    /// `(distance, instance_id, triangle_id, normal, semantic_class, backface)`.
    #[pyo3(signature = (origins, directions, max_range))]
    fn cast_rays<'py>(
        &self,
        py: Python<'py>,
        origins: PyReadonlyArray2<'py, f32>,
        directions: PyReadonlyArray2<'py, f32>,
        max_range: f32,
    ) -> PyResult<RayHitArrays<'py>> {
        let o = rows::<f32, 3>(&origins, "origins")?;
        let d = rows::<f32, 3>(&directions, "directions")?;
        let hits = self.read(|s| detached(py, || s.cast_rays(o, d, max_range)))?;
        let n = hits.len();
        let normal = Array2::from_shape_vec((n, 3), hits.normal)
            .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))?;
        Ok((
            hits.distance.into_pyarray(py),
            hits.instance.into_pyarray(py),
            hits.triangle.into_pyarray(py),
            normal.into_pyarray(py),
            hits.class.into_pyarray(py),
            hits.backface.into_pyarray(py),
        ))
    }

    /// The world triangles at the current poses:
    /// `(vertices (V,3) f32, faces (F,3) u32, classes (F,) u16, instance_ids (F,) u32, triangle_ids (F,) u32)`.
    fn world_mesh<'py>(&self, py: Python<'py>) -> PyResult<WorldMeshArrays<'py>> {
        let w = self.read(|s| detached(py, || Ok(s.world_mesh())))?;
        Ok((
            rows_to_array(py, w.vertices)?,
            rows_to_array(py, w.faces)?,
            w.classes.into_pyarray(py),
            w.instances.into_pyarray(py),
            w.triangles.into_pyarray(py),
        ))
    }

    /// Writes the world triangles at the current poses to `path` (`.ply` or `.obj`).
    fn export(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.read(|s| {
            detached(py, || {
                let format = MeshFormat::from_path(&path)?;
                write_world_mesh(&s.world_mesh(), &path, format)
            })
        })
    }

    /// World-space AABB of an instance at its current pose, `(2, 3)` float32: min row, max row.
    fn instance_aabb<'py>(&self, py: Python<'py>, instance_id: u32) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let aabb = self.read(|s| s.instance_aabb(instance_id).map_err(crate::errors::to_py))?;
        rows_to_array(py, vec![aabb.mins.to_array(), aabb.maxs.to_array()])
    }

    /// The current pose of an instance as a 4x4 float64 matrix.
    fn instance_pose<'py>(&self, py: Python<'py>, instance_id: u32) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.read(|s| {
            let inst = s.instances().get(instance_id as usize).ok_or_else(|| {
                crate::errors::NotFoundError::new_err(format!(
                    "unknown instance id {instance_id}: the scene has {} instances",
                    s.instances().len()
                ))
            })?;
            Ok(inst.pose().to_matrix_row_major())
        })?;
        rows_to_array(py, m.as_chunks::<4>().0.to_vec())
    }

    /// Mesh id placed by each instance, `(K,)` uint32.
    fn instance_meshes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let v = self.read(|s| Ok(s.instances().iter().map(|i| i.mesh()).collect::<Vec<u32>>()))?;
        Ok(v.into_pyarray(py))
    }

    /// Number of meshes.
    #[getter]
    fn num_meshes(&self) -> PyResult<usize> {
        self.read(|s| Ok(s.meshes().len()))
    }

    /// Number of instances.
    #[getter]
    fn num_instances(&self) -> PyResult<usize> {
        self.read(|s| Ok(s.instances().len()))
    }

    /// Number of triangles placed in the world.
    #[getter]
    fn num_world_triangles(&self) -> PyResult<usize> {
        self.read(|s| Ok(s.num_world_triangles()))
    }

    fn __repr__(&self) -> PyResult<String> {
        self.read(|s| {
            Ok(format!(
                "Scene(meshes={}, instances={}, world_triangles={})",
                s.meshes().len(),
                s.instances().len(),
                s.num_world_triangles()
            ))
        })
    }
}

fn flat_2d<'a>(arr: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    c_order(arr, "pose")
}

/// How many tiles the displaced sea surface around `foci` (F, 2) float32 (world x, y, metres) out to `radius_m`
/// holds, in tiles of `tile_m` (mmusv_core::sea::SurfaceSpec::tiles_for; saturated, 0 without foci): what
/// `Scene.set_wave_surface` refuses above `MAX_SURFACE_TILES`.
#[pyfunction]
#[pyo3(signature = (foci, *, radius_m=320.0, tile_m=32.0))]
fn surface_tiles(foci: PyReadonlyArray2<'_, f32>, radius_m: f32, tile_m: f32) -> PyResult<u64> {
    let foci = rows::<f32, 2>(&foci, "foci")?;
    Ok(SurfaceSpec { tile_m, radius_m, ..SurfaceSpec::default() }.tiles_for(foci))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MAX_SURFACE_TILES", mmusv_core::sea::MAX_TILES)?;
    m.add_function(wrap_pyfunction!(surface_tiles, m)?)?;
    m.add_class::<Scene>()
}
