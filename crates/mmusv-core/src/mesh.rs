//! Triangle meshes with per-face semantic classes and a bottom-level BVH.
//!
//! A [`Mesh`] is built once (validated, an 8-wide [`Bvh`] built over the face boxes, the faces packed four to a
//! [`TriBlock`] in leaf order) and is then shared, read-only, by every instance that places it in a
//! [`crate::Scene`]. Moving an instance never touches its mesh.

use crate::bvh::{Box3, Bvh, Packet, PacketStack, PacketVisit, Stack, Visit, PACKET};
use crate::error::{MmusvError, Result};
use crate::geometry::{PreparedTriangle, TriBlock, BLOCK};
use crate::ray::RayPrep;
use crate::simd::{Level, Portable};
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;

/// A validated triangle mesh in its local frame, with a bottom-level BVH.
#[derive(Debug, Clone)]
pub struct Mesh {
    name: String,
    vertices: Vec<Vec3>,
    faces: Vec<[u32; 3]>,
    classes: Vec<u16>,
    /// Material index per face into the scene's table (0: none); empty when no face has one.
    materials: Vec<u16>,
    triangles: Vec<PreparedTriangle>,
    bvh: Bvh,
    /// One block of up to [`BLOCK`] triangles per BVH leaf, by leaf index.
    blocks: Vec<TriBlock>,
    aabb: Aabb,
    /// A hash of the vertices and faces ([`Mesh::content_key`]).
    content_key: u64,
}

/// The closest hit of a ray against one mesh, in the mesh's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalHit {
    /// Ray parameter of the hit (metres when the direction is unit length).
    pub t: f32,
    /// Index of the triangle hit.
    pub triangle: u32,
}

impl Mesh {
    /// Validates and builds a mesh.
    ///
    /// * `vertices`: `(V, 3)` positions in metres, all finite, `V ≥ 3`.
    /// * `faces`: `(F, 3)` vertex indices, `F ≥ 1`, each in `0..V`.
    /// * `classes`: one semantic class for the whole mesh (length 1) or one per face (length `F`).
    ///
    /// Errors name the array and the first offending row.
    pub fn new(name: impl Into<String>, vertices: &[[f32; 3]], faces: &[[i64; 3]], classes: &[u16]) -> Result<Self> {
        let name = name.into();
        if vertices.is_empty() {
            return Err(MmusvError::geometry("vertices", "mesh has no vertices; give a (V, 3) array with V >= 3"));
        }
        if vertices.len() < 3 {
            return Err(MmusvError::geometry(
                "vertices",
                format!(
                    "mesh has {} vertices; a triangle needs three, give a (V, 3) array with V >= 3",
                    vertices.len()
                ),
            ));
        }
        if faces.is_empty() {
            return Err(MmusvError::geometry("faces", "mesh has no faces; give a (F, 3) integer array with F >= 1"));
        }
        if let Some(i) = vertices.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
            return Err(MmusvError::geometry(
                format!("vertices[{i}]"),
                format!("vertex {:?} is not finite; remove NaN/inf vertices", vertices[i]),
            ));
        }
        let nv = vertices.len() as i64;
        let mut checked = Vec::with_capacity(faces.len());
        for (i, f) in faces.iter().enumerate() {
            if f.iter().any(|&k| k < 0 || k >= nv) {
                return Err(MmusvError::geometry(
                    format!("faces[{i}]"),
                    format!("face {f:?} indexes outside the {nv} vertices; indices must be in 0..{}", nv - 1),
                ));
            }
            checked.push([f[0] as u32, f[1] as u32, f[2] as u32]);
        }
        let classes = match classes.len() {
            1 => vec![classes[0]; faces.len()],
            n if n == faces.len() => classes.to_vec(),
            n => {
                return Err(MmusvError::input(
                    "classes",
                    format!("got {n} classes for {} faces; give one class or one per face", faces.len()),
                ))
            }
        };
        let verts: Vec<Vec3> = vertices.iter().map(|v| Vec3::from_array(*v)).collect();
        let triangles: Vec<PreparedTriangle> = checked
            .iter()
            .map(|f| PreparedTriangle::new(verts[f[0] as usize], verts[f[1] as usize], verts[f[2] as usize]))
            .collect();
        let boxes: Vec<Box3> = triangles
            .iter()
            .map(|t| {
                let mut b = Box3::EMPTY;
                for p in t.v {
                    b.grow_point(p.to_array());
                }
                b
            })
            .collect();
        let bvh = Bvh::new(&boxes, BLOCK);
        let blocks = bvh
            .leaves()
            .iter()
            .map(|lf| {
                let ids = &bvh.order()[lf.start as usize..(lf.start + lf.count) as usize];
                let tris: Vec<(u32, PreparedTriangle)> = ids.iter().map(|&i| (i, triangles[i as usize])).collect();
                TriBlock::new(&tris)
            })
            .collect();
        let aabb = Aabb::from_points(verts.iter().copied());
        let content_key = {
            use std::hash::{Hash, Hasher};
            let mut h = std::hash::DefaultHasher::new();
            verts.iter().for_each(|v| v.to_array().map(f32::to_bits).hash(&mut h));
            checked.hash(&mut h);
            h.finish()
        };
        Ok(Self {
            name,
            vertices: verts,
            faces: checked,
            classes,
            materials: Vec::new(),
            triangles,
            bvh,
            blocks,
            aabb,
            content_key,
        })
    }

    /// A 64-bit hash of the vertices and faces: meshes of the same geometry share it (the process-wide caches of
    /// what depends on the geometry alone, [`crate::sky_visibility::SkyVisibility::shared`]).
    pub fn content_key(&self) -> u64 {
        self.content_key
    }

    /// The mesh's name (free text, used in exports and errors).
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Vertex positions, local frame.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }
    /// Faces as vertex index triples.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// Semantic class per face.
    pub fn classes(&self) -> &[u16] {
        &self.classes
    }

    /// Gives the faces materials: one index for the whole mesh (length 1) or one per face (length `F`), into the
    /// table of the scene the mesh is added to (0: no material). The error names `materials`.
    pub fn with_materials(mut self, materials: &[u16]) -> Result<Self> {
        self.materials = match materials.len() {
            0 => Vec::new(),
            1 if materials[0] == 0 => Vec::new(),
            1 => vec![materials[0]; self.faces.len()],
            n if n == self.faces.len() => materials.to_vec(),
            n => {
                return Err(MmusvError::input(
                    "materials",
                    format!("got {n} materials for {} faces; give one or one per face", self.faces.len()),
                ))
            }
        };
        Ok(self)
    }

    /// Material index of face `triangle` (0 when the mesh has none).
    #[inline(always)]
    pub fn material(&self, triangle: u32) -> u16 {
        self.materials.get(triangle as usize).copied().unwrap_or(0)
    }

    /// Largest material index any face names (0 when none).
    pub fn max_material(&self) -> u16 {
        self.materials.iter().copied().max().unwrap_or(0)
    }
    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.faces.len()
    }
    /// Local-frame bounding box.
    pub fn aabb(&self) -> &Aabb {
        &self.aabb
    }
    /// The BVH over the faces.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
    /// The prepared triangle `i` (panics-free: callers only pass ids returned by the BVH).
    pub(crate) fn triangle(&self, i: u32) -> &PreparedTriangle {
        &self.triangles[i as usize]
    }

    /// Closest hit of the ray `origin + t·dir`, `0 < t < t_max`, in the local frame.
    #[inline]
    pub fn cast_local(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<LocalHit> {
        self.closest(Portable, &RayPrep::new(origin.to_array(), dir.to_array()), t_max, &mut Stack::default())
    }

    /// Closest hit of a prepared ray (local frame) below `t_max`, with caller-owned traversal scratch space;
    /// the walk runs at level `lv`.
    #[inline(always)]
    pub fn closest<L: Level>(&self, lv: L, ray: &RayPrep, t_max: f32, stack: &mut Stack) -> Option<LocalHit> {
        closest_kernel(lv, self, ray, t_max, stack)
    }

    /// Whether the prepared ray (local frame) hits any triangle below `t_max`; the walk runs at level `lv`.
    #[inline(always)]
    pub fn any<L: Level>(&self, lv: L, ray: &RayPrep, t_max: f32, stack: &mut Stack) -> bool {
        any_kernel(lv, self, ray, t_max, stack)
    }

    /// Traces a packet (local frame): every ray `r` that hits closer than `p.best[r]` gets the new distance and,
    /// in `tri[r]`, the triangle hit; other rays are left unchanged. The walk runs at level `lv`.
    #[inline(always)]
    pub fn closest_packet<L: Level>(&self, lv: L, p: &mut Packet, stack: &mut PacketStack, tri: &mut [u32; PACKET]) {
        closest_packet_kernel(lv, self, p, stack, tri);
    }

    /// Occlusion for a packet (local frame): every ray `r` that hits anything below `p.best[r]` gets
    /// `p.best[r] = -1`. The walk runs at level `lv`.
    #[inline(always)]
    pub fn any_packet<L: Level>(&self, lv: L, p: &mut Packet, stack: &mut PacketStack) {
        any_packet_kernel(lv, self, p, stack);
    }

    /// Brute-force closest hit over every triangle: the independent reference the tests compare against.
    pub fn cast_local_brute_force(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<LocalHit> {
        let ray = RayPrep::new(origin.to_array(), dir.to_array());
        let mut best: Option<LocalHit> = None;
        for (i, tri) in self.triangles.iter().enumerate() {
            let limit = best.map_or(t_max, |h| h.t);
            if let Some(t) = tri.intersect(&ray, limit) {
                best = Some(LocalHit { t, triangle: i as u32 });
            }
        }
        best
    }
}

crate::kernel! {
    /// [`Mesh::closest`]'s walk, out of line per level.
    fn closest_kernel(mesh: &Mesh, ray: &RayPrep, t_max: f32, stack: &mut Stack) -> Option<LocalHit> {
        let mut v = Blocks { blocks: &mesh.blocks, ray, hit: u32::MAX };
        let t = mesh.bvh.closest(ray, t_max, stack, &mut v);
        (v.hit != u32::MAX).then_some(LocalHit { t, triangle: v.hit })
    }
}

crate::kernel! {
    /// [`Mesh::any`]'s walk, out of line per level.
    fn any_kernel(mesh: &Mesh, ray: &RayPrep, t_max: f32, stack: &mut Stack) -> bool {
        let mut v = Blocks { blocks: &mesh.blocks, ray, hit: u32::MAX };
        mesh.bvh.any(ray, t_max, stack, &mut v)
    }
}

crate::kernel! {
    /// [`Mesh::closest_packet`]'s walk, out of line per level.
    fn closest_packet_kernel(mesh: &Mesh, p: &mut Packet, stack: &mut PacketStack, tri: &mut [u32; PACKET]) {
        let mut v = PacketBlocks { blocks: &mesh.blocks, tri, any: false };
        mesh.bvh.closest_packet(p, stack, &mut v);
    }
}

crate::kernel! {
    /// [`Mesh::any_packet`]'s walk, out of line per level.
    fn any_packet_kernel(mesh: &Mesh, p: &mut Packet, stack: &mut PacketStack) {
        let mut tri = [0u32; PACKET];
        let mut v = PacketBlocks { blocks: &mesh.blocks, tri: &mut tri, any: true };
        mesh.bvh.any_packet(p, stack, &mut v);
    }
}

/// The leaf visitor of a mesh: one triangle block per leaf.
struct Blocks<'a> {
    blocks: &'a [TriBlock],
    ray: &'a RayPrep,
    hit: u32,
}

/// The leaf visitor of a mesh for packets.
struct PacketBlocks<'a> {
    blocks: &'a [TriBlock],
    tri: &'a mut [u32; PACKET],
    any: bool,
}

impl PacketVisit for PacketBlocks<'_> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, rays: u32, p: &mut Packet) {
        let block = &self.blocks[leaf as usize];
        if p.uniform_k && rays.count_ones() > 2 {
            match p.ray[0].k[2] {
                0 => self.across::<0>(block, rays, p),
                1 => self.across::<1>(block, rays, p),
                _ => self.across::<2>(block, rays, p),
            }
            return;
        }
        let mut m = rays;
        while m != 0 {
            let r = m.trailing_zeros() as usize;
            m &= m - 1;
            if let Some((t, id)) = block.intersect(&p.ray[r], p.best[r]) {
                if self.any {
                    p.best[r] = -1.0;
                } else {
                    p.best[r] = t;
                    self.tri[r] = id;
                }
            }
        }
    }
}

impl PacketBlocks<'_> {
    /// The block's triangles tested across the packet's rays (lanes = rays), one triangle at a time in lane
    /// order, keeping a hit only when strictly closer: the same result as testing each ray on its own.
    #[inline(always)]
    fn across<const KZ: usize>(&mut self, block: &TriBlock, rays: u32, p: &mut Packet) {
        let mut best = [-1f32; PACKET];
        for r in 0..PACKET {
            if rays & (1 << r) != 0 {
                best[r] = p.best[r];
            }
        }
        let start = best;
        let mut hit = [u32::MAX; PACKET];
        let mut lane_best = [f32::INFINITY; PACKET];
        for lane in 0..BLOCK {
            if lane > 0 && block.id[lane] == block.id[0] {
                break; // padding repeats lane 0
            }
            let (tri, n) = block.lane(lane);
            let t = crate::geometry::triangle_across_rays::<KZ, PACKET>(
                tri,
                n,
                p.origins(),
                p.directions(),
                &p.shear,
                &start,
            );
            for r in 0..PACKET {
                if t[r] < lane_best[r] {
                    lane_best[r] = t[r];
                    hit[r] = block.id[lane];
                }
            }
        }
        for r in 0..PACKET {
            if hit[r] != u32::MAX && lane_best[r] < best[r] {
                if self.any {
                    p.best[r] = -1.0;
                } else {
                    p.best[r] = lane_best[r];
                    self.tri[r] = hit[r];
                }
            }
        }
    }
}

impl Visit for Blocks<'_> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, best: f32) -> f32 {
        match self.blocks[leaf as usize].intersect(self.ray, best) {
            Some((t, id)) => {
                self.hit = id;
                t
            }
            None => best,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    pub(crate) fn random_soup(rng: &mut ChaCha8Rng, n: usize) -> (Vec<[f32; 3]>, Vec<[i64; 3]>) {
        let mut v = Vec::new();
        let mut f = Vec::new();
        for i in 0..n {
            let c = [rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0)];
            for _ in 0..3 {
                v.push([
                    c[0] + rng.random_range(-1.5..1.5f32),
                    c[1] + rng.random_range(-1.5..1.5f32),
                    c[2] + rng.random_range(-1.5..1.5f32),
                ]);
            }
            let k = 3 * i as i64;
            f.push([k, k + 1, k + 2]);
        }
        (v, f)
    }

    #[test]
    fn bvh_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (v, f) = random_soup(&mut rng, 500);
        let mesh = Mesh::new("soup", &v, &f, &[3]).unwrap_or_else(|e| unreachable!("{e}"));
        let mut hits = 0;
        for _ in 0..3000 {
            let o =
                Vec3::new(rng.random_range(-15.0..15.0), rng.random_range(-15.0..15.0), rng.random_range(-15.0..15.0));
            let d = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                .normalize();
            let a = mesh.cast_local(o, d, 1e3);
            let b = mesh.cast_local_brute_force(o, d, 1e3);
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    // The same triangle test on the same numbers: the same hit, bit for bit.
                    assert_eq!(a, b);
                }
                (None, None) => {}
                other => panic!("bvh and brute force disagree: {other:?}"),
            }
        }
        assert!(hits > 300, "too few hits to be a meaningful test: {hits}");
    }

    #[test]
    fn bvh_finds_every_triangle_of_small_and_large_meshes() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for n in [1usize, 2, 3, 5, 17, 1000] {
            let (v, f) = random_soup(&mut rng, n);
            let mesh = Mesh::new("soup", &v, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}"));
            assert_eq!(mesh.blocks.len(), mesh.bvh.leaves().len());
            let o = Vec3::new(0.0, 0.0, 50.0);
            for (i, t) in mesh.triangles.iter().enumerate() {
                // Aim at each triangle's centroid: the hit must be found, at or before the centroid.
                let c = t.centroid();
                let d = (c - o).normalize();
                let brute = mesh.cast_local_brute_force(o, d, 1e3);
                let fast = mesh.cast_local(o, d, 1e3);
                assert_eq!(brute.map(|h| h.triangle), fast.map(|h| h.triangle), "triangle {i} of {n}");
            }
        }
    }

    #[test]
    fn rejects_bad_geometry() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(Mesh::new("m", &v, &[[0, 1, 3]], &[0]), Err(MmusvError::Geometry { .. })));
        assert!(matches!(Mesh::new("m", &v, &[[0, -1, 2]], &[0]), Err(MmusvError::Geometry { .. })));
        assert!(Mesh::new("m", &v, &[], &[0]).is_err());
        assert!(Mesh::new("m", &[], &[[0, 1, 2]], &[0]).is_err());
        assert!(Mesh::new("m", &[[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]], &[0]).is_err());
        assert!(matches!(Mesh::new("m", &v, &[[0, 1, 2]], &[0, 1]), Err(MmusvError::InvalidInput { .. })));
        assert!(Mesh::new("m", &v, &[[0, 1, 2]], &[5]).is_ok());
    }
}
