//! A scene: meshes placed as instances, a top-level BVH over the instances, and batch ray casting.
//!
//! Two levels, as in hardware ray tracers: every [`Mesh`] owns a bottom-level parry BVH built once; the scene
//! keeps one top-level parry BVH over the instances' world-space boxes. Moving instances recomputes their
//! boxes and rebuilds only the top level (tens of instances: microseconds); no mesh BVH is ever rebuilt.
//! Static geometry (terrain, quays) is simply an instance that never moves.
//!
//! Rays are cast in parallel over rayon. Distances are metres along the normalised direction.

use crate::bvh::{Bvh4, RayInv};
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::mesh::Mesh;
use crate::packet::{Packet, PACKET};
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;
use rayon::prelude::*;
use std::cell::Cell;
use std::sync::Arc;

/// Value of `instance`, `triangle` for a ray that hit nothing.
pub const NO_HIT: i32 = -1;
/// Semantic class reported for a ray that hit nothing (sky / no return).
pub const CLASS_NONE: u16 = 0;
/// Rays per rayon task: large enough to amortise scheduling, small enough to balance (a multiple of [`PACKET`]).
const CHUNK: usize = 512;
/// Rays whose directions lie within ≈8° of each other and whose origins lie within 4 m are traced as a packet
/// (camera pixels share an origin; the parallel rays of 8 neighbouring top-view pixels span ≈ 4 m).
const COHERENT_COS: f32 = 0.990;
/// See [`COHERENT_COS`].
const COHERENT_RADIUS: f32 = 4.0;

/// One placed copy of a mesh.
#[derive(Debug, Clone)]
pub struct Instance {
    mesh: u32,
    pose: RigidPose,
    class_override: Option<u16>,
}

impl Instance {
    /// Index of the mesh this instance places.
    pub fn mesh(&self) -> u32 {
        self.mesh
    }
    /// Current local → world pose.
    pub fn pose(&self) -> &RigidPose {
        &self.pose
    }
    /// If set, the semantic class of every face of this instance (else the mesh's per-face classes).
    pub fn class_override(&self) -> Option<u16> {
        self.class_override
    }
}

/// The closest hit of one ray, before normals are derived.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance in metres along the unit direction.
    pub distance: f32,
    /// Instance index.
    pub instance: u32,
    /// Triangle index within the instance's mesh.
    pub triangle: u32,
}

/// Results of a batch ray cast, one entry per ray, as parallel arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RayHits {
    /// Hit distance in metres along the normalised direction; `f32::INFINITY` for a miss.
    pub distance: Vec<f32>,
    /// Instance index hit, or [`NO_HIT`].
    pub instance: Vec<i32>,
    /// Triangle index within that instance's mesh, or [`NO_HIT`].
    pub triangle: Vec<i32>,
    /// Unit geometric normal in the world frame, following the triangle winding; zero for a miss.
    /// Flat `(N, 3)` row-major: ray `i` owns `normal[3i..3i+3]`.
    pub normal: Vec<f32>,
    /// Semantic class of the triangle hit, or [`CLASS_NONE`].
    pub class: Vec<u16>,
    /// Whether the ray hit the back side of the triangle (`normal · dir > 0`).
    pub backface: Vec<bool>,
}

impl RayHits {
    fn with_len(n: usize) -> Self {
        Self {
            distance: vec![f32::INFINITY; n],
            instance: vec![NO_HIT; n],
            triangle: vec![NO_HIT; n],
            normal: vec![0.0; 3 * n],
            class: vec![CLASS_NONE; n],
            backface: vec![false; n],
        }
    }
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.distance.len()
    }
    /// Whether there are no rays.
    pub fn is_empty(&self) -> bool {
        self.distance.is_empty()
    }
}

/// Per-thread traversal stacks, reused across rays.
#[derive(Debug, Default)]
pub struct Scratch {
    top: Vec<(u32, f32)>,
    bottom: Vec<(u32, f32)>,
}

/// Meshes, instances and the top-level BVH.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    meshes: Vec<Arc<Mesh>>,
    instances: Vec<Instance>,
    world_aabbs: Vec<Aabb>,
    tlas: Bvh,
    /// Flattened copy of `tlas` used for traversal (`None` only if flattening failed or the scene is empty).
    tlas4: Option<Bvh4>,
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a mesh (its BVH is built here, once) and returns its mesh id.
    pub fn add_mesh(&mut self, mesh: Mesh) -> u32 {
        self.meshes.push(Arc::new(mesh));
        (self.meshes.len() - 1) as u32
    }

    /// Places mesh `mesh` at `pose`; returns the new instance id (instance ids count up from 0).
    ///
    /// `class_override`, when given, replaces the mesh's per-face classes for this instance.
    pub fn add_instance(&mut self, mesh: u32, pose: RigidPose, class_override: Option<u16>) -> Result<u32> {
        self.check_mesh(mesh)?;
        self.instances.push(Instance { mesh, pose, class_override });
        self.world_aabbs.push(Aabb::new_invalid());
        let id = (self.instances.len() - 1) as u32;
        self.refresh(&[id]);
        Ok(id)
    }

    /// Moves instances; `ids` and `poses` have the same length. Only the top-level BVH is rebuilt.
    ///
    /// Validates every id before changing anything, so a bad id leaves the scene as it was.
    pub fn set_poses(&mut self, ids: &[u32], poses: &[RigidPose]) -> Result<()> {
        if ids.len() != poses.len() {
            return Err(MmusvError::input(
                "poses",
                format!("{} poses for {} instance ids; give one pose per id", poses.len(), ids.len()),
            ));
        }
        for &id in ids {
            self.check_instance(id)?;
        }
        for (&id, pose) in ids.iter().zip(poses) {
            self.instances[id as usize].pose = *pose;
        }
        self.refresh(ids);
        Ok(())
    }

    fn refresh(&mut self, changed: &[u32]) {
        for &id in changed {
            let inst = &self.instances[id as usize];
            let local = self.meshes[inst.mesh as usize].aabb();
            let r = inst.pose.rotation;
            // World box of a rotated box: centre moved, half extents through |R|.
            let c = inst.pose.transform_point(local.center());
            let h = local.half_extents();
            let abs = parry3d::math::Mat3::from_cols(r.x_axis.abs(), r.y_axis.abs(), r.z_axis.abs());
            let he = abs * h;
            self.world_aabbs[id as usize] = Aabb::new(c - he, c + he);
        }
        self.tlas = Bvh::from_iter(BvhBuildStrategy::Binned, self.world_aabbs.iter().copied().enumerate());
        let (instances, meshes) = (&self.instances, &self.meshes);
        self.tlas4 = Bvh4::from_parry_with_cost(&self.tlas, instances.len(), |i| {
            meshes[instances[i as usize].mesh as usize].num_triangles() as f32
        });
    }

    fn check_mesh(&self, mesh: u32) -> Result<()> {
        if (mesh as usize) < self.meshes.len() {
            Ok(())
        } else {
            Err(MmusvError::UnknownId {
                kind: "mesh",
                id: mesh as i64,
                hint: format!("the scene has {} meshes (ids 0..{})", self.meshes.len(), self.meshes.len()),
            })
        }
    }

    fn check_instance(&self, id: u32) -> Result<()> {
        if (id as usize) < self.instances.len() {
            Ok(())
        } else {
            Err(MmusvError::UnknownId {
                kind: "instance",
                id: id as i64,
                hint: format!("the scene has {} instances (ids 0..{})", self.instances.len(), self.instances.len()),
            })
        }
    }

    /// The meshes, by mesh id.
    pub fn meshes(&self) -> &[Arc<Mesh>] {
        &self.meshes
    }
    /// The instances, by instance id.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }
    /// World-space bounding box of instance `id` at its current pose.
    pub fn instance_aabb(&self, id: u32) -> Result<Aabb> {
        self.check_instance(id)?;
        Ok(self.world_aabbs[id as usize])
    }
    /// Total number of triangles placed in the world (instances × their mesh's triangles).
    pub fn num_world_triangles(&self) -> usize {
        self.instances.iter().map(|i| self.meshes[i.mesh as usize].num_triangles()).sum()
    }

    /// Closest hit of one ray. `dir` must be unit length; `max_range` in metres.
    #[inline]
    pub fn cast_ray(&self, origin: Vec3, dir: Vec3, max_range: f32) -> Option<Hit> {
        self.cast_ray_with(origin, dir, max_range, &mut Scratch::default())
    }

    /// [`Scene::cast_ray`] with caller-owned traversal scratch space (reuse one per thread).
    #[inline]
    pub fn cast_ray_with(&self, origin: Vec3, dir: Vec3, max_range: f32, scratch: &mut Scratch) -> Option<Hit> {
        let best_tri = Cell::new(u32::MAX);
        let Scratch { top, bottom } = scratch;
        let mut cast_instance = |leaf: u32, best: f32| {
            let inst = &self.instances[leaf as usize];
            let mesh = &self.meshes[inst.mesh as usize];
            let o = inst.pose.inverse_transform_point(origin);
            let d = inst.pose.inverse_transform_vector(dir);
            let hit = mesh.cast_local_with(o, d, best, bottom)?;
            best_tri.set(hit.triangle);
            Some(hit.t)
        };
        let (instance, distance) = match &self.tlas4 {
            Some(t4) => {
                let (k, t) = t4.closest(&RayInv::new(origin, dir), max_range, top, |k, best| {
                    cast_instance(t4.order()[k as usize], best)
                })?;
                (t4.order()[k as usize], t)
            }
            None => {
                let cell = std::cell::RefCell::new(cast_instance);
                self.tlas.cast_ray(&Ray::new(origin, dir), max_range, |leaf, best| (cell.borrow_mut())(leaf, best))?
            }
        };
        Some(Hit { distance, instance, triangle: best_tri.get() })
    }

    /// Closest hits of up to [`PACKET`] coherent rays traced together (`dirs` unit length). Results are the
    /// same as [`Scene::cast_ray_with`] per ray.
    pub fn cast_packet_with(
        &self,
        origins: &[[f32; 3]],
        dirs: &[[f32; 3]],
        max_range: f32,
        scratch: &mut Scratch,
    ) -> [Option<Hit>; PACKET] {
        let mut out = [None; PACKET];
        let Some(t4) = &self.tlas4 else {
            for (r, (o, d)) in origins.iter().zip(dirs).take(PACKET).enumerate() {
                out[r] = self.cast_ray_with(Vec3::from_array(*o), Vec3::from_array(*d), max_range, scratch);
            }
            return out;
        };
        let mut p = Packet::new(origins, dirs, max_range);
        let mut tri = [u32::MAX; PACKET];
        let Scratch { top, bottom } = scratch;
        t4.closest_packet(&mut p, top, |k, p| {
            let id = t4.order()[k as usize];
            let inst = &self.instances[id as usize];
            let mut local = *p;
            let rt = inst.pose.rotation.transpose();
            for r in 0..PACKET {
                let o = rt * (Vec3::new(p.o[0][r], p.o[1][r], p.o[2][r]) - inst.pose.translation);
                let d = rt * Vec3::new(p.d[0][r], p.d[1][r], p.d[2][r]);
                for a in 0..3 {
                    local.o[a][r] = o[a];
                    local.d[a][r] = d[a];
                }
            }
            local.refresh_inverse();
            self.meshes[inst.mesh as usize].cast_packet_local(&mut local, bottom);
            for r in 0..PACKET {
                if local.prim[r] != u32::MAX {
                    p.best[r] = local.best[r];
                    p.prim[r] = id;
                    tri[r] = local.prim[r];
                }
            }
        });
        for r in 0..origins.len().min(PACKET) {
            if p.prim[r] != u32::MAX {
                out[r] = Some(Hit { distance: p.best[r], instance: p.prim[r], triangle: tri[r] });
            }
        }
        out
    }

    /// Unit world normal (triangle winding) and semantic class of a hit.
    #[inline]
    pub fn hit_normal_class(&self, hit: &Hit) -> (Vec3, u16) {
        let inst = &self.instances[hit.instance as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let n = inst.pose.transform_vector(mesh.triangle(hit.triangle).normal()).normalize_or_zero();
        let class = inst.class_override.unwrap_or(mesh.classes()[hit.triangle as usize]);
        (n, class)
    }

    /// Casts a batch of rays in parallel.
    ///
    /// * `origins`, `dirs`: the same length; finite; directions non-zero (normalised here).
    /// * `max_range`: metres, `> 0` (may be infinite).
    ///
    /// Errors name the first offending ray.
    pub fn cast_rays(&self, origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<RayHits> {
        validate_rays(origins, dirs, max_range)?;
        let mut out = RayHits::with_len(origins.len());
        let limit = if max_range.is_finite() { max_range } else { f32::MAX };
        (
            out.distance.par_chunks_mut(CHUNK),
            out.instance.par_chunks_mut(CHUNK),
            out.triangle.par_chunks_mut(CHUNK),
            out.normal.par_chunks_mut(3 * CHUNK),
            out.class.par_chunks_mut(CHUNK),
            out.backface.par_chunks_mut(CHUNK),
            origins.par_chunks(CHUNK),
            dirs.par_chunks(CHUNK),
        )
            .into_par_iter()
            .for_each(|(dist, inst, tri, nrm, cls, back, o, d)| {
                let mut scratch = Scratch::default();
                let mut store = |i: usize, dir: Vec3, hit: Option<Hit>| {
                    if let Some(hit) = hit {
                        let (n, c) = self.hit_normal_class(&hit);
                        dist[i] = hit.distance;
                        inst[i] = hit.instance as i32;
                        tri[i] = hit.triangle as i32;
                        nrm[3 * i..3 * i + 3].copy_from_slice(&n.to_array());
                        cls[i] = c;
                        back[i] = n.dot(dir) > 0.0;
                    }
                };
                for start in (0..o.len()).step_by(PACKET) {
                    let end = (start + PACKET).min(o.len());
                    let mut unit = [[0.0f32; 3]; PACKET];
                    for (u, src) in unit.iter_mut().zip(&d[start..end]) {
                        *u = unit_direction(src);
                    }
                    let unit = &unit[..end - start];
                    if end - start > 1 && Packet::is_coherent(&o[start..end], unit, COHERENT_COS, COHERENT_RADIUS) {
                        let hits = self.cast_packet_with(&o[start..end], unit, limit, &mut scratch);
                        for (r, hit) in hits.into_iter().take(end - start).enumerate() {
                            store(start + r, Vec3::from_array(unit[r]), hit);
                        }
                    } else {
                        for (r, u) in unit.iter().enumerate() {
                            let dir = Vec3::from_array(*u);
                            let hit = self.cast_ray_with(Vec3::from_array(o[start + r]), dir, limit, &mut scratch);
                            store(start + r, dir, hit);
                        }
                    }
                }
            });
        Ok(out)
    }

    /// Every triangle in the world frame at the current poses.
    pub fn world_mesh(&self) -> WorldMesh {
        let mut w = WorldMesh::default();
        for (id, inst) in self.instances.iter().enumerate() {
            let mesh = &self.meshes[inst.mesh as usize];
            let base = w.vertices.len() as u32;
            w.vertices.extend(mesh.vertices().iter().map(|&v| inst.pose.transform_point(v).to_array()));
            w.faces.extend(mesh.faces().iter().map(|f| [f[0] + base, f[1] + base, f[2] + base]));
            match inst.class_override {
                Some(c) => w.classes.extend(std::iter::repeat_n(c, mesh.num_triangles())),
                None => w.classes.extend_from_slice(mesh.classes()),
            }
            w.instances.extend(std::iter::repeat_n(id as u32, mesh.num_triangles()));
            w.triangles.extend(0..mesh.num_triangles() as u32);
        }
        w
    }
}

/// The world triangles of a scene at one instant, with per-face labels.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WorldMesh {
    /// Vertex positions, world frame, metres.
    pub vertices: Vec<[f32; 3]>,
    /// Faces as indices into `vertices`.
    pub faces: Vec<[u32; 3]>,
    /// Semantic class per face.
    pub classes: Vec<u16>,
    /// Instance id per face.
    pub instances: Vec<u32>,
    /// Triangle index within its instance's mesh, per face.
    pub triangles: Vec<u32>,
}

/// `d / |d|` computed in `f64`, so any finite non-zero `f32` direction (even 1e-30 or 1e30 long) normalises
/// exactly instead of under- or overflowing in `f32`.
#[inline]
fn unit_direction(d: &[f32; 3]) -> [f32; 3] {
    let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
    let n = (x * x + y * y + z * z).sqrt();
    [(x / n) as f32, (y / n) as f32, (z / n) as f32]
}

fn validate_rays(origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<()> {
    if origins.len() != dirs.len() {
        return Err(MmusvError::input(
            "directions",
            format!("{} directions for {} origins; give one direction per origin", dirs.len(), origins.len()),
        ));
    }
    if max_range.is_nan() || max_range <= 0.0 {
        return Err(MmusvError::input("max_range", format!("{max_range} is not allowed; give a range > 0 metres")));
    }
    if let Some(i) = origins.par_iter().position_first(|o| o.iter().any(|c| !c.is_finite())) {
        return Err(MmusvError::input(format!("origins[{i}]"), format!("{:?} is not finite", origins[i])));
    }
    if let Some(i) = dirs.par_iter().position_first(|d| d.iter().any(|c| !c.is_finite()) || d.iter().all(|&c| c == 0.0))
    {
        return Err(MmusvError::input(
            format!("directions[{i}]"),
            format!("{:?} is zero-length or not finite; directions must be finite and non-zero", dirs[i]),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn box_mesh(half: [f32; 3]) -> Mesh {
        let [a, b, c] = half;
        let v = [[-a, -b, -c], [a, -b, -c], [a, b, -c], [-a, b, -c], [-a, -b, c], [a, -b, c], [a, b, c], [-a, b, c]];
        let f = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        Mesh::new("box", &v, &f, &[9]).unwrap_or_else(|e| unreachable!("{e}"))
    }

    #[test]
    fn analytic_box_hit_and_backface() {
        let mut s = Scene::new();
        let m = s.add_mesh(box_mesh([2.0, 1.0, 0.5]));
        let pose = RigidPose::from_xyz_rpy([10.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
        let id = s.add_instance(m, pose, None).unwrap_or(99);
        let hits = s.cast_rays(&[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]], &[[3.0, 0.0, 0.0], [1.0, 0.0, 0.0]], 100.0);
        let hits = hits.unwrap_or_default();
        assert!((hits.distance[0] - 8.0).abs() < 1e-5);
        assert_eq!(hits.instance[0], id as i32);
        assert_eq!(hits.class[0], 9);
        assert!(!hits.backface[0]);
        assert!((hits.normal[0] + 1.0).abs() < 1e-6, "outward normal of the -x face");
        // From inside the box the ray leaves through the +x face's back side.
        assert!((hits.distance[1] - 2.0).abs() < 1e-5);
        assert!(hits.backface[1]);
    }

    #[test]
    fn instance_pose_equals_pretransformed_mesh() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (v, f) = crate::mesh::tests::random_soup(&mut rng, 200);
        let pose = RigidPose::from_xyz_rpy([5.0, -3.0, 2.0], [0.3, -0.2, 1.1]);
        let moved: Vec<[f32; 3]> = v.iter().map(|p| pose.transform_point(Vec3::from_array(*p)).to_array()).collect();
        let mut a = Scene::new();
        let ma = a.add_mesh(Mesh::new("a", &v, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}")));
        let _ = a.add_instance(ma, RigidPose::IDENTITY, None);
        a.set_poses(&[0], &[pose]).unwrap_or_else(|e| unreachable!("{e}"));
        let mut b = Scene::new();
        let mb = b.add_mesh(Mesh::new("b", &moved, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}")));
        let _ = b.add_instance(mb, RigidPose::IDENTITY, None);
        let n = 4000;
        let origins: Vec<[f32; 3]> =
            (0..n).map(|_| [rng.random_range(-20.0..20.0), rng.random_range(-20.0..20.0), 30.0]).collect();
        let dirs: Vec<[f32; 3]> =
            (0..n).map(|_| [rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5), -1.0]).collect();
        let ha = a.cast_rays(&origins, &dirs, 1e3).unwrap_or_default();
        let hb = b.cast_rays(&origins, &dirs, 1e3).unwrap_or_default();
        let mut hits = 0;
        for i in 0..n {
            assert_eq!(ha.triangle[i], hb.triangle[i], "ray {i}");
            if ha.distance[i].is_finite() {
                hits += 1;
                assert!((ha.distance[i] - hb.distance[i]).abs() <= 1e-4 * hb.distance[i]);
                for k in 0..3 {
                    assert!((ha.normal[3 * i + k] - hb.normal[3 * i + k]).abs() < 1e-4);
                }
            }
        }
        assert!(hits > 200, "{hits}");
    }

    #[test]
    fn bad_rays_and_ids_are_errors_not_panics() {
        let mut s = Scene::new();
        let m = s.add_mesh(box_mesh([1.0, 1.0, 1.0]));
        assert!(matches!(s.add_instance(m + 1, RigidPose::IDENTITY, None), Err(MmusvError::UnknownId { .. })));
        assert!(s.set_poses(&[3], &[RigidPose::IDENTITY]).is_err());
        assert!(s.cast_rays(&[[0.0; 3]], &[[0.0; 3]], 10.0).is_err());
        assert!(s.cast_rays(&[[f32::NAN, 0.0, 0.0]], &[[1.0, 0.0, 0.0]], 10.0).is_err());
        assert!(s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], 10.0).is_err());
        assert!(s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], -1.0).is_err());
        // Empty scene / empty batch: misses, not errors.
        assert!(Scene::new().cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 10.0).is_ok_and(|h| h.instance[0] == NO_HIT));
        assert!(s.cast_rays(&[], &[], 10.0).is_ok_and(|h| h.is_empty()));
    }

    #[test]
    fn coherent_packets_match_single_rays_and_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (v, f) = crate::mesh::tests::random_soup(&mut rng, 300);
        let mut s = Scene::new();
        let soup = s.add_mesh(Mesh::new("soup", &v, &f, &[2]).unwrap_or_else(|e| unreachable!("{e}")));
        let boxm = s.add_mesh(box_mesh([1.5, 0.7, 0.5]));
        let _ = s.add_instance(soup, RigidPose::from_xyz_rpy([0.0, 0.0, -3.0], [0.1, 0.0, 0.4]), None);
        for k in 0..12 {
            let a = k as f64 * 0.5;
            let _ =
                s.add_instance(boxm, RigidPose::from_xyz_rpy([8.0 * a.cos(), 8.0 * a.sin(), 0.0], [0.0, 0.0, a]), None);
        }
        // A 96x64 pinhole image from above: rows of 8 neighbouring pixels form coherent packets.
        let body = crate::sensors::rays::pinhole_directions(96, 64, 1.6).unwrap_or_default();
        let cam = RigidPose::from_xyz_rpy([0.0, 0.0, 25.0], [0.0, 1.3, 0.2]);
        let dirs: Vec<[f32; 3]> = body.iter().map(|d| cam.transform_vector(Vec3::from_array(*d)).to_array()).collect();
        let origins = vec![cam.translation.to_array(); dirs.len()];
        let batch = s.cast_rays(&origins, &dirs, 100.0).unwrap_or_default();
        let world = s.world_mesh();
        let tris: Vec<crate::geometry::PreparedTriangle> = world
            .faces
            .iter()
            .map(|f| {
                let p = |i: u32| Vec3::from_array(world.vertices[i as usize]);
                crate::geometry::PreparedTriangle::new(p(f[0]), p(f[1]), p(f[2]))
            })
            .collect();
        let mut hits = 0;
        for i in 0..dirs.len() {
            let d = Vec3::from_array(dirs[i]).normalize();
            let single = s.cast_ray(Vec3::from_array(origins[i]), d, 100.0);
            assert_eq!(single.map(|h| h.instance as i32).unwrap_or(NO_HIT), batch.instance[i], "ray {i}");
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(k, t)| t.intersect(Vec3::from_array(origins[i]), d, 100.0).map(|t| (t, k)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match brute {
                Some((t, k)) => {
                    hits += 1;
                    assert!(
                        (batch.distance[i] - t).abs() <= 1e-4 * t.max(1.0),
                        "ray {i}: {} vs {t}",
                        batch.distance[i]
                    );
                    assert_eq!(world.instances[k] as i32, batch.instance[i]);
                    assert_eq!(world.triangles[k] as i32, batch.triangle[i]);
                }
                None => assert_eq!(batch.instance[i], NO_HIT),
            }
        }
        assert!(hits > 400, "{hits}");
    }

    #[test]
    fn max_range_is_honoured() {
        let mut s = Scene::new();
        let m = s.add_mesh(box_mesh([1.0, 1.0, 1.0]));
        let _ = s.add_instance(m, RigidPose::from_xyz_rpy([10.0, 0.0, 0.0], [0.0; 3]), None);
        let h = s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 8.5).unwrap_or_default();
        assert_eq!(h.instance[0], NO_HIT);
        let h = s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 9.5).unwrap_or_default();
        assert_eq!(h.instance[0], 0);
    }
}
