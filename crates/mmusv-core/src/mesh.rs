//! Triangle meshes with per-face semantic classes and a bottom-level BVH.
//!
//! A [`Mesh`] is built once (validated, triangles prepared, parry [`Bvh`] built over the face AABBs) and is
//! then shared, read-only, by every instance that places it in a [`crate::Scene`]. Moving an instance never
//! touches its mesh.

use crate::bvh::{Bvh4, RayInv};
use crate::error::{MmusvError, Result};
use crate::geometry::PreparedTriangle;
use crate::packet::{Packet, PACKET};
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;

/// A validated triangle mesh in its local frame, with a bottom-level BVH.
#[derive(Debug, Clone)]
pub struct Mesh {
    name: String,
    vertices: Vec<Vec3>,
    faces: Vec<[u32; 3]>,
    classes: Vec<u16>,
    triangles: Vec<PreparedTriangle>,
    bvh: Bvh,
    /// The flattened 4-wide copy of `bvh` used for traversal, with triangles in its leaf order.
    fast: Option<(Bvh4, Vec<PreparedTriangle>)>,
    aabb: Aabb,
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
        let bvh = Bvh::from_iter(
            BvhBuildStrategy::Binned,
            checked.iter().enumerate().map(|(i, f)| {
                let a = verts[f[0] as usize];
                let b = verts[f[1] as usize];
                let c = verts[f[2] as usize];
                (i, Aabb::new(a.min(b).min(c), a.max(b).max(c)))
            }),
        );
        let aabb = Aabb::from_points(verts.iter().copied());
        let fast = Bvh4::from_parry(&bvh, triangles.len()).map(|b4| {
            let ordered = b4.order().iter().map(|&i| triangles[i as usize]).collect();
            (b4, ordered)
        });
        Ok(Self { name, vertices: verts, faces: checked, classes, triangles, bvh, fast, aabb })
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
    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.faces.len()
    }
    /// Local-frame bounding box.
    pub fn aabb(&self) -> &Aabb {
        &self.aabb
    }
    /// The prepared triangle `i` (panics-free: callers only pass ids returned by the BVH).
    pub(crate) fn triangle(&self, i: u32) -> &PreparedTriangle {
        &self.triangles[i as usize]
    }

    /// Closest hit of the ray `origin + t·dir`, `0 < t < t_max`, in the local frame.
    #[inline]
    pub fn cast_local(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<LocalHit> {
        self.cast_local_with(origin, dir, t_max, &mut Vec::new())
    }

    /// [`Mesh::cast_local`] with caller-owned traversal scratch space (reuse it across rays).
    #[inline]
    pub fn cast_local_with(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<LocalHit> {
        match &self.fast {
            Some((b4, tris)) => b4
                .closest(&RayInv::new(origin, dir), t_max, stack, |k, best| {
                    tris[k as usize].intersect(origin, dir, best)
                })
                .map(|(k, t)| LocalHit { t, triangle: b4.order()[k as usize] }),
            None => self.cast_local_parry(origin, dir, t_max),
        }
    }

    /// Traces a packet (in this mesh's local frame). Rays that hit closer than their current best get the
    /// new distance and, in `prim`, the index of the triangle hit; other rays are left unchanged.
    #[inline]
    pub fn cast_packet_local(&self, p: &mut Packet, stack: &mut Vec<(u32, f32)>) {
        match &self.fast {
            Some((b4, tris)) => {
                p.prim = [u32::MAX; PACKET];
                b4.closest_packet(p, stack, |k, p| p.intersect_triangle(&tris[k as usize], k));
                for prim in p.prim.iter_mut().filter(|k| **k != u32::MAX) {
                    *prim = b4.order()[*prim as usize];
                }
            }
            None => {
                for r in 0..PACKET {
                    p.prim[r] = u32::MAX;
                    let o = Vec3::new(p.o[0][r], p.o[1][r], p.o[2][r]);
                    let d = Vec3::new(p.d[0][r], p.d[1][r], p.d[2][r]);
                    if p.best[r] > 0.0 {
                        if let Some(h) = self.cast_local_parry(o, d, p.best[r]) {
                            p.best[r] = h.t;
                            p.prim[r] = h.triangle;
                        }
                    }
                }
            }
        }
    }

    /// Closest hit using parry's own best-first BVH query (the fallback of [`Mesh::cast_local`]).
    pub fn cast_local_parry(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<LocalHit> {
        let ray = Ray::new(origin, dir);
        let tris = &self.triangles;
        self.bvh
            .cast_ray(&ray, t_max, |leaf, best| tris[leaf as usize].intersect(origin, dir, best))
            .map(|(triangle, t)| LocalHit { t, triangle })
    }

    /// Brute-force closest hit over every triangle: the independent reference the tests compare against.
    pub fn cast_local_brute_force(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<LocalHit> {
        let mut best: Option<LocalHit> = None;
        for (i, tri) in self.triangles.iter().enumerate() {
            let limit = best.map_or(t_max, |h| h.t);
            if let Some(t) = tri.intersect(origin, dir, limit) {
                best = Some(LocalHit { t, triangle: i as u32 });
            }
        }
        best
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
            let c = mesh.cast_local_parry(o, d, 1e3);
            assert_eq!(a.map(|h| h.triangle), c.map(|h| h.triangle));
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-4 * b.t.max(1.0), "{a:?} vs {b:?}");
                }
                (None, None) => {}
                other => panic!("bvh and brute force disagree: {other:?}"),
            }
        }
        assert!(hits > 300, "too few hits to be a meaningful test: {hits}");
    }

    #[test]
    fn fast_bvh_is_built_for_small_and_large_meshes() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for n in [1usize, 2, 3, 5, 17, 1000] {
            let (v, f) = random_soup(&mut rng, n);
            let mesh = Mesh::new("soup", &v, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}"));
            assert!(mesh.fast.is_some(), "flattening failed for {n} triangles");
            let o = Vec3::new(0.0, 0.0, 50.0);
            for (i, t) in mesh.triangles.iter().enumerate() {
                // Aim at each triangle's centroid: the hit must be found, at or before the centroid.
                let c = t.v0 + (t.e1 + t.e2) / 3.0;
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
