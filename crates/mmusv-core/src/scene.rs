//! A scene: meshes placed as instances, a top-level BVH over the instances, and batch ray casting.
//!
//! Two levels, as in hardware ray tracers: every [`Mesh`] owns a bottom-level BVH built once; the scene
//! keeps one top-level BVH over the instances' world-space boxes. Moving instances recomputes their boxes and
//! rebuilds only the top level (tens of instances: microseconds); no mesh BVH is ever rebuilt. Static geometry
//! (terrain, quays) is simply an instance that never moves. Within a top-level leaf the instances are tested
//! cheapest first (fewest triangles), so a 2-triangle water plane shortens a ray before a 500k-triangle
//! terrain sharing its leaf is entered.
//!
//! Rays go through 8-wide nodes (see [`crate::bvh`]) one at a time or as packets of coherent rays, with AVX2
//! where the CPU has it ([`crate::simd`]); batches are cast in parallel over rayon (`scene/batch.rs`). The sea
//! shortcuts (rays settled from a height map of the scene, see [`crate::sea`]) live in `scene/sea_routes.rs`.
//! Distances are metres along the normalised direction.

use crate::bvh::{box_entry, Box3, Bvh, Packet, PacketStack, PacketVisit, Stack, Visit, PACKET};
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::mesh::Mesh;
use crate::ray::RayPrep;
use crate::sea::Sea;
use crate::simd::{Level, Portable};
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;
use std::sync::Arc;

mod batch;
mod sea_routes;

/// Value of `instance`, `triangle` for a ray that hit nothing.
pub const NO_HIT: i32 = -1;
/// Semantic class reported for a ray that hit nothing (sky / no return).
pub const CLASS_NONE: u16 = 0;
/// Instances per top-level leaf.
const TLAS_LEAF: usize = 4;
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
    /// Zeroed arrays (cheap: fresh zero pages); the tracer writes every entry of every ray.
    fn zeroed(n: usize) -> Self {
        Self {
            distance: vec![0.0; n],
            instance: vec![0; n],
            triangle: vec![0; n],
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
    top: Stack,
    bottom: Stack,
    packet_top: PacketStack,
    packet_bottom: PacketStack,
    sub_packet: Packet,
}

/// Meshes, instances and the top-level BVH.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    meshes: Vec<Arc<Mesh>>,
    instances: Vec<Instance>,
    world_aabbs: Vec<Aabb>,
    /// Top-level BVH over `world_aabbs`.
    tlas: Bvh,
    /// `tlas.order()` with every leaf's instances sorted cheapest first.
    tlas_order: Vec<u32>,
    /// World box of the instance at each position of `tlas_order` (tested before a ray enters its mesh).
    tlas_boxes: Vec<Box3>,
    /// The sea surface and the height bound of everything else, once declared ([`Scene::set_sea`]).
    sea: Option<Sea>,
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
        let boxes: Vec<Box3> =
            self.world_aabbs.iter().map(|a| Box3 { lo: a.mins.to_array(), hi: a.maxs.to_array() }).collect();
        self.tlas = Bvh::new(&boxes, TLAS_LEAF);
        let mut order = self.tlas.order().to_vec();
        let cost = |i: u32| self.meshes[self.instances[i as usize].mesh as usize].num_triangles();
        for lf in self.tlas.leaves() {
            order[lf.start as usize..(lf.start + lf.count) as usize].sort_by_key(|&i| (cost(i), i));
        }
        self.tlas_boxes = order.iter().map(|&i| boxes[i as usize]).collect();
        self.tlas_order = order;
        if let Some(sea) = &mut self.sea {
            if changed.contains(&sea.instance) {
                self.sea = None; // the surface itself moved: no longer a known plane
            } else {
                for &id in changed {
                    sea.add_moving(id);
                }
                sea.update(sea.moving().to_vec().into_iter().map(|i| boxes[i as usize]));
            }
        }
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
    #[inline(always)]
    pub fn cast_ray_with(&self, origin: Vec3, dir: Vec3, max_range: f32, scratch: &mut Scratch) -> Option<Hit> {
        self.cast_prepared(Portable, &RayPrep::new(origin.to_array(), dir.to_array()), max_range, scratch)
    }

    /// [`Scene::cast_ray_with`] for a prepared world ray, the meshes walked at level `lv`.
    #[inline(always)]
    pub fn cast_prepared<L: Level>(&self, lv: L, ray: &RayPrep, max_range: f32, scratch: &mut Scratch) -> Option<Hit> {
        let mut v =
            Instances { lv, scene: self, ray, stack: &mut scratch.bottom, instance: u32::MAX, triangle: u32::MAX };
        let t = self.tlas.closest(ray, max_range, &mut scratch.top, &mut v);
        (v.instance != u32::MAX).then_some(Hit { distance: t, instance: v.instance, triangle: v.triangle })
    }

    /// Traces a packet of prepared world rays: for every ray `r`, `p.best[r]` becomes its closest hit distance
    /// (unchanged if nothing is hit closer) and the returned arrays hold the instance and triangle hit
    /// (`u32::MAX` for none). Each ray's hit is the one [`Scene::cast_ray_with`] finds for it. The meshes are
    /// walked at level `lv`.
    #[inline(always)]
    pub fn cast_packet_with<L: Level>(
        &self,
        lv: L,
        p: &mut Packet,
        scratch: &mut Scratch,
    ) -> ([u32; PACKET], [u32; PACKET]) {
        let mut v = PacketInstances {
            lv,
            scene: self,
            scratch_single: &mut scratch.bottom,
            stack: &mut scratch.packet_bottom,
            sub: &mut scratch.sub_packet,
            instance: [u32::MAX; PACKET],
            triangle: [u32::MAX; PACKET],
            any: false,
        };
        self.tlas.closest_packet(p, &mut scratch.packet_top, &mut v);
        (v.instance, v.triangle)
    }

    /// Occlusion for a packet of prepared world rays: afterwards `p.best[r] < 0` for every ray blocked below its
    /// starting `p.best[r]`. The meshes are walked at level `lv`.
    #[inline(always)]
    pub fn occluded_packet_with<L: Level>(&self, lv: L, p: &mut Packet, scratch: &mut Scratch) {
        let mut v = PacketInstances {
            lv,
            scene: self,
            scratch_single: &mut scratch.bottom,
            stack: &mut scratch.packet_bottom,
            sub: &mut scratch.sub_packet,
            instance: [u32::MAX; PACKET],
            triangle: [u32::MAX; PACKET],
            any: true,
        };
        self.tlas.any_packet(p, &mut scratch.packet_top, &mut v);
    }

    /// Whether the ray `origin + t·dir` (`dir` unit length) hits anything with `0 < t < max_range`: the shadow-ray
    /// query, which stops at the first hit found instead of looking for the closest.
    #[inline(always)]
    pub fn occluded_with(&self, origin: Vec3, dir: Vec3, max_range: f32, scratch: &mut Scratch) -> bool {
        self.occluded_prepared(Portable, &RayPrep::new(origin.to_array(), dir.to_array()), max_range, scratch)
    }

    /// [`Scene::occluded_with`] for a prepared world ray, the meshes walked at level `lv`.
    #[inline(always)]
    pub fn occluded_prepared<L: Level>(&self, lv: L, ray: &RayPrep, max_range: f32, scratch: &mut Scratch) -> bool {
        let mut v = AnyInstance { lv, scene: self, ray, stack: &mut scratch.bottom };
        self.tlas.any(ray, max_range, &mut scratch.top, &mut v)
    }

    /// Unit world normal (triangle winding) and semantic class of a hit.
    #[inline(always)]
    pub fn hit_normal_class(&self, hit: &Hit) -> (Vec3, u16) {
        let inst = &self.instances[hit.instance as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let n = inst.pose.transform_vector(mesh.triangle(hit.triangle).normal()).normalize_or_zero();
        let class = inst.class_override.unwrap_or(mesh.classes()[hit.triangle as usize]);
        (n, class)
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

/// The top-level leaf visitor of [`Scene::cast_ray_with`]: each instance's mesh, cheapest first, in its local
/// frame (instances at the identity pose use the world ray as it is).
struct Instances<'a, L> {
    lv: L,
    scene: &'a Scene,
    ray: &'a RayPrep,
    stack: &'a mut Stack,
    instance: u32,
    triangle: u32,
}

impl<L: Level> Visit for Instances<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, mut best: f32) -> f32 {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            if !box_entry(&sc.tlas_boxes[k], self.ray, best) {
                continue;
            }
            let id = sc.tlas_order[k];
            let inst = &sc.instances[id as usize];
            let mesh = &sc.meshes[inst.mesh as usize];
            let local = local_ray(self.ray, &inst.pose);
            if let Some(h) = mesh.closest(self.lv, local.as_ref().unwrap_or(self.ray), best, self.stack) {
                best = h.t;
                self.instance = id;
                self.triangle = h.triangle;
            }
        }
        best
    }
}

/// The top-level leaf visitor of [`Scene::occluded_with`].
struct AnyInstance<'a, L> {
    lv: L,
    scene: &'a Scene,
    ray: &'a RayPrep,
    stack: &'a mut Stack,
}

impl<L: Level> Visit for AnyInstance<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, best: f32) -> f32 {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            if !box_entry(&sc.tlas_boxes[k], self.ray, best) {
                continue;
            }
            let id = sc.tlas_order[k];
            let inst = &sc.instances[id as usize];
            let local = local_ray(self.ray, &inst.pose);
            if sc.meshes[inst.mesh as usize].any(self.lv, local.as_ref().unwrap_or(self.ray), best, self.stack) {
                return 0.0;
            }
        }
        best
    }
}

/// The ray in an instance's local frame, or `None` when the pose is the identity (the world ray then serves).
#[inline(always)]
fn local_ray(ray: &RayPrep, pose: &RigidPose) -> Option<RayPrep> {
    if *pose == RigidPose::IDENTITY {
        return None;
    }
    let rt = pose.rotation.transpose();
    let o = rt * (Vec3::from_array(ray.o) - pose.translation);
    let d = rt * Vec3::from_array(ray.d);
    Some(RayPrep::new(o.to_array(), d.to_array()))
}

/// The top-level leaf visitor of packets: each instance whose box some ray enters, cheapest first; its mesh
/// is traced with the rays that enter its box, as a packet in the instance's frame where their directions
/// still share signs there, else ray by ray.
struct PacketInstances<'a, L> {
    lv: L,
    scene: &'a Scene,
    scratch_single: &'a mut Stack,
    stack: &'a mut PacketStack,
    /// The packet of a moved instance's rays in its frame (filled anew for each such instance).
    sub: &'a mut Packet,
    instance: [u32; PACKET],
    triangle: [u32; PACKET],
    any: bool,
}

impl<L: Level> PacketVisit for PacketInstances<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, rays: u32, p: &mut Packet) {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            let mask = p.rays_entering_box(&sc.tlas_boxes[k]) & rays;
            if mask == 0 {
                continue;
            }
            let id = sc.tlas_order[k];
            let inst = &sc.instances[id as usize];
            let mesh = &sc.meshes[inst.mesh as usize];
            if inst.pose == RigidPose::IDENTITY {
                // Trace the world packet, with the rays outside `mask` switched off for this instance.
                let saved = p.best;
                for r in 0..PACKET {
                    if mask & (1 << r) == 0 {
                        p.best[r] = -1.0;
                    }
                }
                let mut tri = [u32::MAX; PACKET];
                if self.any {
                    mesh.any_packet(self.lv, p, self.stack);
                } else {
                    mesh.closest_packet(self.lv, p, self.stack, &mut tri);
                }
                for r in 0..PACKET {
                    if mask & (1 << r) == 0 {
                        p.best[r] = saved[r];
                    } else if !self.any && p.best[r] < saved[r] {
                        self.instance[r] = id;
                        self.triangle[r] = tri[r];
                    }
                }
                continue;
            }
            // Moved instance: the rays in its frame.
            let mut local = [p.ray[0]; PACKET];
            let mut lane = [0usize; PACKET];
            let mut n = 0;
            let mut m = mask;
            while m != 0 {
                let r = m.trailing_zeros() as usize;
                m &= m - 1;
                local[n] = local_ray(&p.ray[r], &inst.pose).unwrap_or(p.ray[r]);
                lane[n] = r;
                n += 1;
            }
            let q = &mut *self.sub;
            if n > 1 && q.fill(&local[..n], 0.0) {
                for j in 0..n {
                    q.best[j] = p.best[lane[j]];
                }
                let mut tri = [u32::MAX; PACKET];
                if self.any {
                    mesh.any_packet(self.lv, q, self.stack);
                } else {
                    mesh.closest_packet(self.lv, q, self.stack, &mut tri);
                }
                for j in 0..n {
                    let r = lane[j];
                    if q.best[j] < p.best[r] {
                        p.best[r] = q.best[j];
                        self.instance[r] = id;
                        self.triangle[r] = tri[j];
                    }
                }
            } else {
                for j in 0..n {
                    let r = lane[j];
                    if self.any {
                        if mesh.any(self.lv, &local[j], p.best[r], self.scratch_single) {
                            p.best[r] = -1.0;
                        }
                    } else if let Some(h) = mesh.closest(self.lv, &local[j], p.best[r], self.scratch_single) {
                        p.best[r] = h.t;
                        self.instance[r] = id;
                        self.triangle[r] = h.triangle;
                    }
                }
            }
        }
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

#[cfg(test)]
mod tests {
    use super::batch::unit_direction;
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
    fn batch_matches_single_rays_and_brute_force() {
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
        // A 96x64 pinhole image from above.
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
                .filter_map(|(k, t)| t.intersect(&RayPrep::new(origins[i], d.to_array()), 100.0).map(|t| (t, k)))
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

    /// A small maritime world: the demo heightfield and hulls, a water plane, vessels that move.
    fn sea_world() -> (Scene, Vec<u32>) {
        let p = crate::demo::DemoParams { terrain_cells: 96, vessels: 24, extent: 600.0, ..Default::default() };
        let demo = crate::demo::maritime_demo(p).unwrap_or_else(|e| unreachable!("{e}"));
        let ids = demo.vessel_instances.clone();
        (demo.scene, ids)
    }

    /// Rays of the kinds the sensors cast: camera-like rays from a few metres up in every direction, steep
    /// and grazing, and shadow-like rays from the water surface towards a sun.
    fn sensor_rays(rng: &mut ChaCha8Rng, n: usize) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let mut o = Vec::with_capacity(n);
        let mut d = Vec::with_capacity(n);
        for k in 0..n {
            let origin =
                [rng.random_range(-250.0..250.0), rng.random_range(-250.0..250.0), rng.random_range(0.5..40.0)];
            let az: f32 = rng.random_range(0.0..std::f32::consts::TAU);
            let el: f32 = match k % 4 {
                0 => rng.random_range(-1.5..-0.01),
                1 => rng.random_range(-0.05..0.05),
                2 => rng.random_range(0.0..1.5),
                _ => -std::f32::consts::FRAC_PI_2,
            };
            o.push(origin);
            d.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
        }
        (o, d)
    }

    #[test]
    fn sea_shortcuts_give_exactly_the_full_trace() {
        let (mut s, vessels) = sea_world();
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for frame in 0..3 {
            // Move the vessels (the height map follows their boxes), then compare with and without the sea.
            let poses: Vec<RigidPose> = vessels
                .iter()
                .map(|_| {
                    let (x, y) = (rng.random_range(-200.0..200.0), rng.random_range(-200.0..200.0));
                    RigidPose::from_xyz_rpy([x, y, 0.3], [0.02, -0.03, rng.random_range(0.0..std::f64::consts::TAU)])
                })
                .collect();
            s.set_poses(&vessels, &poses).unwrap_or_else(|e| unreachable!("{e}"));
            let mut with = s.clone();
            with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
            let (o, d) = sensor_rays(&mut rng, 20_000);
            let full = s.cast_rays(&o, &d, 800.0).unwrap_or_default();
            let fast = with.cast_rays(&o, &d, 800.0).unwrap_or_default();
            assert_eq!(full, fast, "frame {frame}");
            // The same directions from above everything: the rising ones are settled as misses.
            let high: Vec<[f32; 3]> = o.iter().map(|p| [p[0], p[1], 150.0]).collect();
            assert_eq!(s.cast_rays(&high, &d, 800.0).ok(), with.cast_rays(&high, &d, 800.0).ok(), "frame {frame}");
            let sky = |o: &[f32; 3], d: &[f32; 3]| with.sea_sky(&RayPrep::new(*o, unit_direction(d)), 800.0, None);
            let settled = high.iter().zip(&d).filter(|(o, d)| sky(o, d)).count();
            assert!(settled > 5_000, "only {settled} of 20000 rays settled by the sea shortcut");
            // Coherent sets, in 4x4 tiles as the cameras trace them: a pinhole fan from 3 m up looking at the
            // water and the horizon, and a top view's vertical rays.
            let (mut co, mut cd) = (Vec::new(), Vec::new());
            let eye = [rng.random_range(-150.0..150.0), rng.random_range(-150.0..150.0), 3.0f32];
            for top_view in [false, true] {
                for tile in 0..64u32 {
                    for k in 0..16u32 {
                        let (u, v) = ((tile % 8) * 4 + k % 4, (tile / 8) * 4 + k / 4);
                        if top_view {
                            co.push([eye[0] + 0.5 * u as f32, eye[1] + 0.5 * v as f32, 120.0]);
                            cd.push([0.0, 0.0, -1.0]);
                        } else {
                            let (az, el) = (0.03 * u as f32 - 0.5, -0.02 * v as f32 + 0.05);
                            co.push(eye);
                            cd.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
                        }
                    }
                }
            }
            assert_eq!(s.cast_rays(&co, &cd, 800.0).ok(), with.cast_rays(&co, &cd, 800.0).ok(), "frame {frame}");
            // Shadow rays: from just above the water towards the sun, and from above everything.
            let sun = [0.4f32, 0.3, 0.866];
            let so: Vec<[f32; 3]> =
                o.iter().enumerate().map(|(k, p)| [p[0], p[1], if k % 2 == 0 { 0.03 } else { 150.0 }]).collect();
            let sd = vec![sun; so.len()];
            let full_shadow = s.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
            let fast_shadow = with.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
            let differ = full_shadow.iter().zip(&fast_shadow).filter(|(a, b)| a != b).count();
            assert!(differ == 0 && fast_shadow.len() == so.len(), "{differ} shadow rays differ (frame {frame})");
            let shaded = full_shadow.iter().step_by(2).filter(|&&b| b).count();
            assert!(shaded > 100, "only {shaded} water points in shade: the comparison proves little");
            let clear = so.iter().filter(|p| with.sea_clear(&RayPrep::new(**p, sun), 5000.0)).count();
            assert!(clear >= 10_000, "only {clear} shadow rays settled");
            // The sun mask (one direction for the whole batch) settles most of the water points by itself.
            let unit = unit_direction(&sun);
            let mask = with.sea.as_ref().and_then(|sea| sea.sun_mask(unit));
            let by_mask = so.iter().filter(|p| with.sun_clear(mask.as_deref(), **p)).count();
            assert!(by_mask >= 6_000, "only {by_mask} shadow rays settled by the sun mask");
        }
        // A moving surface is no longer trusted; a tilted one is refused.
        let mut with = s.clone();
        with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
        with.set_poses(&[1], &[RigidPose::from_xyz_rpy([0.0, 0.0, 1.0], [0.0; 3])])
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(with.sea_instance(), None);
        let mut tilted = s.clone();
        tilted
            .set_poses(&[1], &[RigidPose::from_xyz_rpy([0.0; 3], [0.1, 0.0, 0.0])])
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert!(tilted.set_sea(1, &vessels).is_err());
    }

    /// With the sea declared and one sun direction (the sun mask settles rays from their origins alone), a bad
    /// origin is still an error naming it, and the settled rays are those of the full trace.
    #[test]
    fn shadow_batches_with_a_sun_mask_name_bad_origins() {
        let (mut s, vessels) = sea_world();
        let full = s.clone();
        s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
        let mut o: Vec<[f32; 3]> =
            (0..2000).map(|k| [(k % 50) as f32 * 9.0 - 220.0, (k / 50) as f32 * 9.0 - 180.0, 0.05]).collect();
        let sun = vec![[0.2f32, -0.4, 0.7]; o.len()];
        let want = full.occluded_rays(&o, &sun, 5000.0).unwrap_or_default();
        assert_eq!(s.occluded_rays(&o, &sun, 5000.0).ok(), Some(want));
        for bad in [[f32::NAN, 0.0, 3.0], [10.0, f32::INFINITY, 3.0], [10.0, 0.0, f32::NAN]] {
            o[1234] = bad;
            let err = s.occluded_rays(&o, &sun, 5000.0).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(err.contains("origins[1234]"), "{bad:?}: {err}");
        }
    }

    #[test]
    fn horizons_of_one_origin_batches_give_exactly_the_full_trace() {
        let (mut s, vessels) = sea_world();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let poses: Vec<RigidPose> = vessels
            .iter()
            .map(|_| {
                let (x, y) = (rng.random_range(-200.0..200.0), rng.random_range(-200.0..200.0));
                RigidPose::from_xyz_rpy([x, y, 0.2], [0.03, -0.02, rng.random_range(0.0..std::f64::consts::TAU)])
            })
            .collect();
        s.set_poses(&vessels, &poses).unwrap_or_else(|e| unreachable!("{e}"));
        let mut with = s.clone();
        with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
        // Viewpoints: over open water, on (and in) the vessels' boxes as a USV's cameras are, high above all.
        let mut eyes: Vec<[f32; 3]> = (0..6)
            .map(|_| [rng.random_range(-250.0..250.0), rng.random_range(-250.0..250.0), rng.random_range(0.5..6.0)])
            .collect();
        for &v in vessels.iter().take(8) {
            let b = with.world_aabbs[v as usize];
            let (c, h) = (b.center(), b.half_extents());
            eyes.push([c.x + 0.3 * h.x, c.y - 0.2 * h.y, b.maxs.z - 0.3 * h.z]);
            eyes.push([c.x, c.y, b.maxs.z + 0.5]);
            eyes.push([b.maxs.x + 0.05, c.y, c.z]);
        }
        eyes.push([0.0, 0.0, 400.0]);
        // Every direction on a 96 × 64 grid (the pole rows included), most of them rising.
        let mut dirs = Vec::new();
        for i in 0..96 {
            for j in 0..64 {
                let az = i as f32 * std::f32::consts::TAU / 96.0 + 0.001;
                let el = -0.3 + 1.8708 * j as f32 / 63.0;
                dirs.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
            }
        }
        // (settled, rising) over the open-water viewpoints and over those on the decks.
        let (mut water, mut decks) = ((0, 0), (0, 0));
        for (k, eye) in eyes.iter().enumerate() {
            let o = vec![*eye; dirs.len()];
            let full = s.cast_rays(&o, &dirs, 900.0).unwrap_or_default();
            let fast = with.cast_rays(&o, &dirs, 900.0).unwrap_or_default();
            assert_eq!(full, fast, "viewpoint {eye:?}");
            let Some(h) = with.horizon(*eye) else { continue };
            let tally = if k < 6 {
                &mut water
            } else if k % 3 == 1 {
                &mut decks
            } else {
                continue;
            };
            for d in &dirs {
                let ray = RayPrep::new(*eye, unit_direction(d));
                tally.1 += usize::from(ray.d[2] >= 0.0);
                tally.0 += usize::from(h.clear(ray.d));
            }
        }
        // Islands of 45-95 m hide some of the sky over the water; a deck's own mast and neighbours more.
        assert!(water.0 * 10 > water.1 * 6, "the horizons settled only {water:?} rising rays over the water");
        assert!(decks.0 * 10 > decks.1 * 4, "the horizons settled only {decks:?} rising rays on the decks");
        assert!(with.horizon([0.0, 0.0, -1.0]).is_none(), "no horizon under the surface");
    }

    /// The AVX2 and portable versions of the batch casts (and of the mesh kernels they call) give the same
    /// bits: LiDAR-like and camera-like ray sets, packets and single rays, with and without the sea shortcuts,
    /// closest hits and shadow rays.
    #[test]
    fn every_simd_level_gives_the_same_bits() {
        let (mut s, vessels) = sea_world();
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut origins = Vec::new();
        let mut dirs = Vec::new();
        for k in 0..6000 {
            let o = if k < 4096 { [3.0, -2.0, 2.5] } else { [rng.random_range(-250.0..250.0), 0.0, 30.0] };
            origins.push(o);
            dirs.push([rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-0.6..0.3)]);
        }
        let sun = vec![[0.3, 0.2, 0.9]; origins.len()];
        let mut runs = Vec::new();
        for sea in [false, true] {
            if sea {
                s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
            }
            for portable in [true, false] {
                crate::simd::set_portable(portable);
                let hits = s.cast_rays(&origins, &dirs, 900.0).unwrap_or_default();
                let shadow = s.occluded_rays(&origins, &sun, 900.0).unwrap_or_default();
                runs.push((sea, portable, hits, shadow));
            }
        }
        crate::simd::set_portable(false);
        for pair in runs.chunks(2) {
            let ((sea, _, a, sa), (_, _, b, sb)) = (&pair[0], &pair[1]);
            assert!(a.instance.iter().filter(|&&i| i >= 0).count() > 2000, "sea {sea}: too few hits");
            assert!(sa.iter().filter(|&&x| x).count() > 100, "sea {sea}: too few shadowed rays");
            let bits = |h: &RayHits| h.distance.iter().chain(&h.normal).map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(a), bits(b), "sea {sea}: distances or normals differ between the levels");
            assert_eq!(
                (&a.instance, &a.triangle, &a.class, &a.backface),
                (&b.instance, &b.triangle, &b.class, &b.backface)
            );
            assert_eq!(sa, sb, "sea {sea}: shadow rays differ between the levels");
        }
        // The mesh kernels called directly with each token.
        if let Some(avx2) = crate::simd::Avx2::detect() {
            let mesh = &s.meshes()[0];
            let mut stack = Stack::default();
            for (o, d) in origins.iter().zip(&dirs) {
                let ray = RayPrep::new(*o, unit_direction(d));
                let a = mesh.closest(Portable, &ray, 900.0, &mut stack);
                let b = mesh.closest(avx2, &ray, 900.0, &mut stack);
                assert_eq!(a.map(|h| (h.t.to_bits(), h.triangle)), b.map(|h| (h.t.to_bits(), h.triangle)));
                assert_eq!(mesh.any(Portable, &ray, 900.0, &mut stack), mesh.any(avx2, &ray, 900.0, &mut stack));
            }
        }
    }
}
