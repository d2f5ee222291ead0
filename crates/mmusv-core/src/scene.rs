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
//! shortcuts (rays settled from a height map of the scene, see [`crate::sea`]) live in `scene/sea_routes.rs`,
//! and the top-level leaf visitors (each instance traced in its own frame) in `scene/visit.rs`.
//! Distances are metres along the normalised direction.

use crate::bvh::{Box3, Bvh, Packet, PacketStack, Stack, PACKET};
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::ray::RayPrep;
use crate::sea::{Sea, WaveSurface};
use crate::seabed::Seabed;
use crate::simd::{Level, Portable};
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;
use std::sync::Arc;

mod batch;
pub use batch::KnownWater;
mod lamps;
pub use lamps::{Lamp, LAMP_GROUP_M};
mod sea_routes;
pub use sea_routes::{PreparedSea, SeaBeyond};
mod visit;
mod waves;

use visit::{AnyInstance, Instances, PacketInstances};

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
    /// Whether the instance's navigation lights are on (see [`crate::material::Material::nav_light`]).
    lights_on: bool,
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
    /// Whether the instance's navigation lights are on.
    pub fn lights_on(&self) -> bool {
        self.lights_on
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
    /// The hits of rays `which`, in that order.
    pub fn select(&self, which: &[u32]) -> RayHits {
        let at = |k: &u32| *k as usize;
        RayHits {
            distance: which.iter().map(|k| self.distance[at(k)]).collect(),
            instance: which.iter().map(|k| self.instance[at(k)]).collect(),
            triangle: which.iter().map(|k| self.triangle[at(k)]).collect(),
            normal: which.iter().flat_map(|k| self.normal[3 * at(k)..3 * at(k) + 3].iter().copied()).collect(),
            class: which.iter().map(|k| self.class[at(k)]).collect(),
            backface: which.iter().map(|k| self.backface[at(k)]).collect(),
        }
    }

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
    /// The material table faces index into ([`Scene::set_materials`]); index 0 is "no material".
    materials: Arc<Vec<Material>>,
    /// The seabed under the water, for shallow-water optics ([`Scene::set_seabed`]).
    seabed: Option<Arc<Seabed>>,
    /// The displaced sea surface of the current frame, which replaces the sea instance's flat mesh for every ray
    /// ([`Scene::set_wave_surface`], `scene/waves.rs`).
    waves: Option<Arc<WaveSurface>>,
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
    /// `class_override`, when given, replaces the mesh's per-face classes for this instance. The pose must be
    /// finite and rigid ([`RigidPose::validate`]; the error names `pose`).
    pub fn add_instance(&mut self, mesh: u32, pose: RigidPose, class_override: Option<u16>) -> Result<u32> {
        self.check_mesh(mesh)?;
        pose.validate("pose")?;
        self.instances.push(Instance { mesh, pose, class_override, lights_on: false });
        self.world_aabbs.push(Aabb::new_invalid());
        let id = (self.instances.len() - 1) as u32;
        self.refresh(&[id]);
        Ok(id)
    }

    /// Sets the material table every mesh's per-face indices refer to (row 0 is never read: index 0 means no
    /// material). Fails, changing nothing, when a mesh names an index past the table (naming the mesh).
    pub fn set_materials(&mut self, table: Vec<Material>) -> Result<()> {
        if let Some(m) = self.meshes.iter().find(|m| m.max_material() as usize >= table.len().max(1)) {
            return Err(MmusvError::input(
                "materials",
                format!(
                    "mesh '{}' uses material {} but the table has {} rows",
                    m.name(),
                    m.max_material(),
                    table.len()
                ),
            ));
        }
        self.materials = Arc::new(table);
        Ok(())
    }

    /// Sets (or clears) the seabed under the water, read by the cameras' water body.
    pub fn set_seabed(&mut self, seabed: Option<Seabed>) {
        self.seabed = seabed.map(Arc::new);
    }

    /// The seabed, if set (shared, cheap to clone).
    pub fn seabed(&self) -> Option<Arc<Seabed>> {
        self.seabed.clone()
    }

    /// The material table (shared, cheap to clone).
    pub fn material_table(&self) -> Arc<Vec<Material>> {
        Arc::clone(&self.materials)
    }

    /// Number of rows in the material table.
    pub fn num_materials(&self) -> usize {
        self.materials.len()
    }

    /// Turns the navigation lights of instances `ids` on or off. Validates every id first.
    pub fn set_lights(&mut self, ids: &[u32], on: bool) -> Result<()> {
        for &id in ids {
            self.check_instance(id)?;
        }
        for &id in ids {
            self.instances[id as usize].lights_on = on;
        }
        Ok(())
    }

    /// Material index of triangle `triangle` of instance `instance` (0 for none or a miss).
    #[inline(always)]
    pub fn material_index(&self, instance: i32, triangle: i32) -> u16 {
        match (usize::try_from(instance), u32::try_from(triangle)) {
            (Ok(i), Ok(t)) if i < self.instances.len() => {
                let t = if self.is_wave_hit(i as u32) { 0 } else { t };
                self.meshes[self.instances[i].mesh as usize].material(t)
            }
            _ => 0,
        }
    }

    /// The material of triangle `triangle` of instance `instance`, `None` for no material (index 0), a miss
    /// or an index past the table.
    #[inline]
    pub fn material_of(&self, instance: i32, triangle: i32) -> Option<&Material> {
        let inst = self.instances.get(usize::try_from(instance).ok()?)?;
        let triangle = if self.is_wave_hit(instance as u32) { 0 } else { u32::try_from(triangle).ok()? };
        let id = self.meshes[inst.mesh as usize].material(triangle);
        if id == 0 {
            None
        } else {
            self.materials.get(id as usize)
        }
    }

    /// Moves instances; `ids` and `poses` have the same length. Only the top-level BVH is rebuilt.
    ///
    /// Validates every id and pose (finite and rigid, [`RigidPose::validate`]; errors name `poses[i]`) before
    /// changing anything, so a bad id or pose leaves the scene as it was.
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
        let mut sorted = ids.to_vec();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            let at: Vec<String> =
                ids.iter().enumerate().filter(|(_, &id)| id == w[0]).map(|(i, _)| i.to_string()).collect();
            return Err(MmusvError::input(
                "instance_ids",
                format!(
                    "instance id {} is given {} times (at {}); give each instance one pose",
                    w[0],
                    at.len(),
                    at.join(", ")
                ),
            ));
        }
        for (i, pose) in poses.iter().enumerate() {
            pose.validate(&format!("poses[{i}]"))?;
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
                self.waves = None;
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
                hint: id_range(("mesh", "meshes"), self.meshes.len()),
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
                hint: id_range(("instance", "instances"), self.instances.len()),
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
        // The wave surface first (it shortens the ray before the tree is walked).
        let water = self.wave_hit(ray, max_range);
        self.cast_prepared_over(lv, ray, water, max_range, scratch)
    }

    /// [`Scene::cast_prepared`] with the ray's wave-surface hit below `max_range` already known (`water`).
    #[inline(always)]
    pub(crate) fn cast_prepared_over<L: Level>(
        &self,
        lv: L,
        ray: &RayPrep,
        water: Option<Hit>,
        max_range: f32,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        let limit = water.map_or(max_range, |h| h.distance);
        let hidden = self.hidden_instance();
        let mut v = Instances {
            lv,
            scene: self,
            ray,
            stack: &mut scratch.bottom,
            instance: u32::MAX,
            triangle: u32::MAX,
            hidden,
        };
        let t = self.tlas.closest(ray, limit, &mut scratch.top, &mut v);
        if v.instance != u32::MAX {
            Some(Hit { distance: t, instance: v.instance, triangle: v.triangle })
        } else {
            water
        }
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
        let water = self.wave_hits_packet(p);
        self.cast_packet_over(lv, p, water, scratch)
    }

    /// [`Scene::cast_packet_with`] with the packet's wave-surface hits already applied to `p.best` and given as
    /// `water` (see [`Scene::wave_hits_packet`]).
    #[inline(always)]
    pub(crate) fn cast_packet_over<L: Level>(
        &self,
        lv: L,
        p: &mut Packet,
        water: Option<(u32, [u32; PACKET])>,
        scratch: &mut Scratch,
    ) -> ([u32; PACKET], [u32; PACKET]) {
        let (mut v, top) = PacketInstances::new(lv, self, scratch, false);
        self.tlas.closest_packet(p, top, &mut v);
        if let Some((sid, pieces)) = water {
            for r in 0..p.n {
                if v.instance[r] == u32::MAX && pieces[r] != u32::MAX {
                    v.instance[r] = sid;
                    v.triangle[r] = pieces[r];
                }
            }
        }
        (v.instance, v.triangle)
    }

    /// Occlusion for a packet of prepared world rays: afterwards `p.best[r] < 0` for every ray blocked below its
    /// starting `p.best[r]`. The meshes are walked at level `lv`.
    #[inline(always)]
    pub fn occluded_packet_with<L: Level>(&self, lv: L, p: &mut Packet, scratch: &mut Scratch) {
        self.wave_block_packet(p);
        let (mut v, top) = PacketInstances::new(lv, self, scratch, true);
        self.tlas.any_packet(p, top, &mut v);
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
        if self.wave_hit(ray, max_range).is_some() {
            return true;
        }
        let hidden = self.hidden_instance();
        let mut v = AnyInstance { lv, scene: self, ray, stack: &mut scratch.bottom, hidden };
        self.tlas.any(ray, max_range, &mut scratch.top, &mut v)
    }

    /// Unit world normal (triangle winding) and semantic class of a hit.
    #[inline(always)]
    pub fn hit_normal_class(&self, hit: &Hit) -> (Vec3, u16) {
        if let Some(n) = self.wave_piece_normal(hit.instance, hit.triangle) {
            return (n, self.face_class(hit.instance, 0));
        }
        let inst = &self.instances[hit.instance as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let n = inst.pose.transform_vector(mesh.triangle(hit.triangle).normal()).normalize_or_zero();
        (n, self.face_class(hit.instance, hit.triangle))
    }

    /// Semantic class of triangle `triangle` of instance `instance` (both valid): the instance's override, else the
    /// mesh's class of that face.
    #[inline(always)]
    fn face_class(&self, instance: u32, triangle: u32) -> u16 {
        let inst = &self.instances[instance as usize];
        inst.class_override.unwrap_or(self.meshes[inst.mesh as usize].classes()[triangle as usize])
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

/// How many `(one, many)` a scene holds and their ids, both ends included (`"the scene has 2 instances (ids 0
/// to 1)"`; it said `ids 0..2`, which reads as including 2).
fn id_range((one, many): (&str, &str), n: usize) -> String {
    match n {
        0 => format!("the scene has no {many}"),
        1 => format!("the scene has 1 {one} (id 0)"),
        _ => format!("the scene has {n} {many} (ids 0 to {})", n - 1),
    }
}

#[cfg(test)]
pub(crate) mod tests;
