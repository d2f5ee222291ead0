//! Rigid poses and the watertight ray–triangle test shared by every ray query (one triangle, or a block of four).
//!
//! Poses are rigid transforms `p_world = R · p_local + t` (no scale), stored in `f32` because the
//! scene itself is `f32`; kinematics works in `f64` and converts at the scene boundary.

use crate::error::{MmusvError, Result};
use crate::ray::RayPrep;
use parry3d::math::{Mat3, Vec3};

/// Tolerance on `RᵀR = I` and `det R = 1` when a pose is given as a 4×4 matrix.
pub const ROTATION_TOLERANCE: f64 = 1e-4;

/// A rigid transform from a local (body) frame into the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidPose {
    /// Rotation matrix, columns are the local axes expressed in the world frame.
    pub rotation: Mat3,
    /// Translation in metres (world frame).
    pub translation: Vec3,
}

impl Default for RigidPose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl RigidPose {
    /// The identity pose.
    pub const IDENTITY: Self = Self { rotation: Mat3::IDENTITY, translation: Vec3::ZERO };

    /// Builds a pose from a row-major 4×4 homogeneous matrix (`m[r*4 + c]`).
    ///
    /// The last row must be `[0, 0, 0, 1]`, every entry finite, and the upper-left 3×3 a proper rotation
    /// (orthonormal within [`ROTATION_TOLERANCE`], determinant +1). `field` names the argument in errors.
    pub fn from_matrix_row_major(m: &[f64; 16], field: &str) -> Result<Self> {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(MmusvError::input(field, "pose contains NaN or infinity; give a finite 4x4 matrix"));
        }
        let last = [m[12], m[13], m[14], m[15]];
        if (last[0].abs() + last[1].abs() + last[2].abs() + (last[3] - 1.0).abs()) > 1e-9 {
            return Err(MmusvError::input(field, format!("last row of a pose must be [0, 0, 0, 1], got {last:?}")));
        }
        let r = |i: usize, j: usize| m[i * 4 + j];
        // Orthonormality: columns unit length and mutually orthogonal, det = +1.
        for a in 0..3 {
            for b in 0..3 {
                let dot: f64 = (0..3).map(|k| r(k, a) * r(k, b)).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                if (dot - want).abs() > ROTATION_TOLERANCE {
                    return Err(MmusvError::input(
                        field,
                        "the 3x3 rotation block is not orthonormal (scale and shear are not supported; \
                         scale the mesh vertices instead)",
                    ));
                }
            }
        }
        let det = r(0, 0) * (r(1, 1) * r(2, 2) - r(1, 2) * r(2, 1)) - r(0, 1) * (r(1, 0) * r(2, 2) - r(1, 2) * r(2, 0))
            + r(0, 2) * (r(1, 0) * r(2, 1) - r(1, 1) * r(2, 0));
        if det < 0.0 {
            return Err(MmusvError::input(
                field,
                "the rotation block has determinant -1 (a reflection); give a proper rotation",
            ));
        }
        if let Some(t) = [m[3], m[7], m[11]].into_iter().find(|t| t.abs() > f64::from(f32::MAX)) {
            return Err(MmusvError::input(
                field,
                format!("translation {t} m is beyond the f32 range of the scene (|t| <= {:e} m)", f32::MAX),
            ));
        }
        let col = |j: usize| Vec3::new(r(0, j) as f32, r(1, j) as f32, r(2, j) as f32);
        Ok(Self {
            rotation: Mat3::from_cols(col(0), col(1), col(2)),
            translation: Vec3::new(r(0, 3) as f32, r(1, 3) as f32, r(2, 3) as f32),
        })
    }

    /// Checks that the pose is one [`RigidPose::from_matrix_row_major`] would give: every entry finite and the
    /// rotation proper (orthonormal within [`ROTATION_TOLERANCE`], determinant +1). The fields are public and
    /// [`RigidPose::from_xyz_rpy`] takes any number, so the scene and the sensors check the poses they are given;
    /// `field` names the pose in the error.
    pub fn validate(&self, field: &str) -> Result<()> {
        let m = self.to_matrix_row_major();
        Self::from_matrix_row_major(&m, field).map(|_| ())
    }

    /// Builds a pose from a translation and roll, pitch, yaw in radians, with `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
    /// Unchecked (a NaN gives a NaN pose): the scene and the sensors refuse such poses ([`RigidPose::validate`]).
    pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        let (sr, cr) = rpy[0].sin_cos();
        let (sp, cp) = rpy[1].sin_cos();
        let (sy, cy) = rpy[2].sin_cos();
        let rot = [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ];
        let col = |j: usize| Vec3::new(rot[0][j] as f32, rot[1][j] as f32, rot[2][j] as f32);
        Self {
            rotation: Mat3::from_cols(col(0), col(1), col(2)),
            translation: Vec3::new(xyz[0] as f32, xyz[1] as f32, xyz[2] as f32),
        }
    }

    /// The row-major 4×4 matrix of this pose.
    pub fn to_matrix_row_major(&self) -> [f64; 16] {
        let r = self.rotation;
        let t = self.translation;
        [
            r.x_axis.x as f64,
            r.y_axis.x as f64,
            r.z_axis.x as f64,
            t.x as f64,
            r.x_axis.y as f64,
            r.y_axis.y as f64,
            r.z_axis.y as f64,
            t.y as f64,
            r.x_axis.z as f64,
            r.y_axis.z as f64,
            r.z_axis.z as f64,
            t.z as f64,
            0.0,
            0.0,
            0.0,
            1.0,
        ]
    }

    /// Maps a local point into the world frame.
    #[inline(always)]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    /// Maps a local direction into the world frame.
    #[inline(always)]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// Maps a world point into the local frame.
    #[inline(always)]
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.transpose() * (p - self.translation)
    }

    /// Maps a world direction into the local frame.
    #[inline(always)]
    pub fn inverse_transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation.transpose() * v
    }
}

/// A triangle stored for intersection: its three vertices as given (never re-derived from edges, so triangles
/// that share an edge share its exact endpoints, which is what makes the test watertight) and its normal.
#[derive(Debug, Clone, Copy)]
pub struct PreparedTriangle {
    /// Vertices `a, b, c` in winding order.
    pub v: [Vec3; 3],
    /// The unnormalised normal `(b − a) × (c − a)`.
    pub n: Vec3,
}

impl PreparedTriangle {
    /// Prepares the triangle `(a, b, c)`.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Self { v: [a, b, c], n: (b - a).cross(c - a) }
    }

    /// The unnormalised geometric normal `(b − a) × (c − a)` (follows the winding `a → b → c`).
    #[inline(always)]
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// The centroid.
    pub fn centroid(&self) -> Vec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }

    /// Two-sided watertight test (see [`crate::ray`]): the ray parameter `t` in `(0, t_max)` of the hit, if any.
    ///
    /// Whether the ray hits is decided by the sheared edge functions (watertight); the distance is then taken
    /// from the triangle's plane, `t = n·(a − o) / n·d`, which stays accurate for triangles much larger than the
    /// distance to them (a water plane kilometres wide seen from a few metres). Both faces are hit (no culling);
    /// `t` is in units of `|dir|`. Gives bit for bit the `t` of [`TriBlock::intersect`] and
    /// [`triangle_across_rays`] for the same triangle and ray.
    #[inline(always)]
    pub fn intersect(&self, ray: &RayPrep, t_max: f32) -> Option<f32> {
        let [kx, ky, kz] = ray.k.map(usize::from);
        let [sx, sy] = ray.s;
        let o = ray.o;
        let rel = |p: Vec3| {
            let p = p.to_array();
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        };
        let (ra, rb, rc) = (rel(self.v[0]), rel(self.v[1]), rel(self.v[2]));
        let shear = |r: [f32; 3]| (r[kx] - sx * r[kz], r[ky] - sy * r[kz]);
        let (ax, ay) = shear(ra);
        let (bx, by) = shear(rb);
        let (cx, cy) = shear(rc);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            (u, v, w) = edges_f64([ax, ay, bx, by, cx, cy]);
        }
        let n = self.n.to_array();
        let num = n[0] * ra[0] + n[1] * ra[1] + n[2] * ra[2];
        let den = n[0] * ray.d[0] + n[1] * ray.d[1] + n[2] * ray.d[2];
        let neg = u < 0.0 || v < 0.0 || w < 0.0;
        let pos = u > 0.0 || v > 0.0 || w > 0.0;
        let t = num / den;
        (!(neg && pos) && u + v + w != 0.0 && t > 0.0 && t < t_max).then_some(t)
    }
}

/// Edge functions recomputed in `f64` when one of them is exactly zero in `f32` (an edge through the ray):
/// Woop, Benthin and Wald's (JCGT 2013, see [`crate::ray`]) fallback that decides such rays consistently for both
/// triangles of the edge.
#[inline(never)]
fn edges_f64(p: [f32; 6]) -> (f32, f32, f32) {
    let [ax, ay, bx, by, cx, cy] = p.map(f64::from);
    ((cx * by - cy * bx) as f32, (ax * cy - ay * cx) as f32, (bx * ay - by * ax) as f32)
}

/// Tests one triangle (vertices `tri[vertex][axis]`, normal `n`) against every ray of a packet whose rays
/// share the dominant axis `KZ` (the lanes of the arrays are rays: origins `o[axis][ray]`, directions
/// `d[axis][ray]`, shear constants `s[c][ray]`), with the arithmetic of [`PreparedTriangle::intersect`], so each
/// lane's `t` is bit for bit the one-ray result. Returns the hit distance per ray, `+inf` where the triangle
/// is missed or not closer than `best`.
#[inline(always)]
pub fn triangle_across_rays<const KZ: usize, const N: usize>(
    tri: [[f32; 3]; 3],
    n: [f32; 3],
    o: &[[f32; N]; 3],
    d: &[[f32; N]; 3],
    s: &[[f32; N]; 2],
    best: &[f32; N],
) -> [f32; N] {
    let (kx, ky) = ((KZ + 1) % 3, (KZ + 2) % 3);
    let mut sh = [[[0f32; N]; 2]; 3];
    let mut num = [0f32; N];
    for (vert, p) in tri.iter().enumerate() {
        for r in 0..N {
            let rel = [p[0] - o[0][r], p[1] - o[1][r], p[2] - o[2][r]];
            sh[vert][0][r] = rel[kx] - s[0][r] * rel[KZ];
            sh[vert][1][r] = rel[ky] - s[1][r] * rel[KZ];
            if vert == 0 {
                num[r] = n[0] * rel[0] + n[1] * rel[1] + n[2] * rel[2];
            }
        }
    }
    let [a, b, c] = &sh;
    let mut u = [0f32; N];
    let mut v = [0f32; N];
    let mut w = [0f32; N];
    let mut zero = false;
    for r in 0..N {
        u[r] = c[0][r] * b[1][r] - c[1][r] * b[0][r];
        v[r] = a[0][r] * c[1][r] - a[1][r] * c[0][r];
        w[r] = b[0][r] * a[1][r] - b[1][r] * a[0][r];
        zero |= (u[r] == 0.0) | (v[r] == 0.0) | (w[r] == 0.0);
    }
    if zero {
        for r in 0..N {
            if u[r] == 0.0 || v[r] == 0.0 || w[r] == 0.0 {
                (u[r], v[r], w[r]) = edges_f64([a[0][r], a[1][r], b[0][r], b[1][r], c[0][r], c[1][r]]);
            }
        }
    }
    let mut t = [0f32; N];
    for r in 0..N {
        let neg = (u[r] < 0.0) | (v[r] < 0.0) | (w[r] < 0.0);
        let pos = (u[r] > 0.0) | (v[r] > 0.0) | (w[r] > 0.0);
        let den = n[0] * d[0][r] + n[1] * d[1][r] + n[2] * d[2][r];
        let tl = num[r] / den;
        let ok = !(neg & pos) & (u[r] + v[r] + w[r] != 0.0) & (tl > 0.0) & (tl < best[r]);
        t[r] = if ok { tl } else { f32::INFINITY };
    }
    t
}

/// Triangles per [`TriBlock`].
pub const BLOCK: usize = 4;

/// Up to [`BLOCK`] triangles in structure-of-arrays form, tested against one ray at once. Unused lanes repeat
/// lane 0 (same triangle, same id), so they can never change a result.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(16))]
pub struct TriBlock {
    /// `v[vertex][axis][lane]`.
    pub v: [[[f32; BLOCK]; 3]; 3],
    /// `n[axis][lane]`: each triangle's unnormalised normal.
    pub n: [[f32; BLOCK]; 3],
    /// The triangle index of each lane.
    pub id: [u32; BLOCK],
}

impl TriBlock {
    /// Packs `tris` (1 to [`BLOCK`] of them) with their ids.
    pub fn new(tris: &[(u32, PreparedTriangle)]) -> Self {
        let mut b = TriBlock { v: [[[0.0; BLOCK]; 3]; 3], n: [[0.0; BLOCK]; 3], id: [0; BLOCK] };
        let zero = (0, PreparedTriangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
        for lane in 0..BLOCK {
            let (id, t) = tris.get(lane).or(tris.first()).copied().unwrap_or(zero);
            b.id[lane] = id;
            for (vert, p) in t.v.iter().enumerate() {
                let p = p.to_array();
                for a in 0..3 {
                    b.v[vert][a][lane] = p[a];
                }
            }
            let n = t.n.to_array();
            for a in 0..3 {
                b.n[a][lane] = n[a];
            }
        }
        b
    }

    /// The vertices of lane `lane` as `[vertex][axis]`, and its normal.
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> ([[f32; 3]; 3], [f32; 3]) {
        let v = &self.v;
        (
            [
                [v[0][0][lane], v[0][1][lane], v[0][2][lane]],
                [v[1][0][lane], v[1][1][lane], v[1][2][lane]],
                [v[2][0][lane], v[2][1][lane], v[2][2][lane]],
            ],
            [self.n[0][lane], self.n[1][lane], self.n[2][lane]],
        )
    }

    /// The closest hit in `(0, t_max)` over the block's triangles: `(t, triangle id)`. Ties go to the lowest lane.
    #[inline(always)]
    pub fn intersect(&self, ray: &RayPrep, t_max: f32) -> Option<(f32, u32)> {
        // One monomorphic version per dominant axis, so every load has a fixed offset and the lanes vectorise.
        match ray.k[2] {
            0 => self.intersect_k::<0>(ray, t_max),
            1 => self.intersect_k::<1>(ray, t_max),
            _ => self.intersect_k::<2>(ray, t_max),
        }
    }

    #[inline(always)]
    fn intersect_k<const KZ: usize>(&self, ray: &RayPrep, t_max: f32) -> Option<(f32, u32)> {
        let (kx, ky) = ((KZ + 1) % 3, (KZ + 2) % 3);
        let [sx, sy] = ray.s;
        let o = ray.o;
        let mut sh = [[[0f32; BLOCK]; 2]; 3]; // sh[vertex][0: x, 1: y][lane], sheared
        let mut num = [0f32; BLOCK];
        for vert in 0..3 {
            let p = &self.v[vert];
            for l in 0..BLOCK {
                let rel = [p[0][l] - o[0], p[1][l] - o[1], p[2][l] - o[2]];
                sh[vert][0][l] = rel[kx] - sx * rel[KZ];
                sh[vert][1][l] = rel[ky] - sy * rel[KZ];
                if vert == 0 {
                    num[l] = self.n[0][l] * rel[0] + self.n[1][l] * rel[1] + self.n[2][l] * rel[2];
                }
            }
        }
        let [a, b, c] = &sh;
        let mut u = [0f32; BLOCK];
        let mut v = [0f32; BLOCK];
        let mut w = [0f32; BLOCK];
        for l in 0..BLOCK {
            u[l] = c[0][l] * b[1][l] - c[1][l] * b[0][l];
            v[l] = a[0][l] * c[1][l] - a[1][l] * c[0][l];
            w[l] = b[0][l] * a[1][l] - b[1][l] * a[0][l];
        }
        let mut zero = false;
        for l in 0..BLOCK {
            zero |= (u[l] == 0.0) | (v[l] == 0.0) | (w[l] == 0.0);
        }
        if zero {
            for l in 0..BLOCK {
                if u[l] == 0.0 || v[l] == 0.0 || w[l] == 0.0 {
                    (u[l], v[l], w[l]) = edges_f64([a[0][l], a[1][l], b[0][l], b[1][l], c[0][l], c[1][l]]);
                }
            }
        }
        let d = ray.d;
        let mut t = [0f32; BLOCK];
        for l in 0..BLOCK {
            let neg = (u[l] < 0.0) | (v[l] < 0.0) | (w[l] < 0.0);
            let pos = (u[l] > 0.0) | (v[l] > 0.0) | (w[l] > 0.0);
            let den = self.n[0][l] * d[0] + self.n[1][l] * d[1] + self.n[2][l] * d[2];
            let tl = num[l] / den;
            let ok = !(neg & pos) & (u[l] + v[l] + w[l] != 0.0) & (tl > 0.0) & (tl < t_max);
            t[l] = if ok { tl } else { f32::INFINITY };
        }
        let mut best = (t[0], 0usize);
        for (l, &tl) in t.iter().enumerate().skip(1) {
            if tl < best.0 {
                best = (tl, l);
            }
        }
        (best.0 < f32::INFINITY).then(|| (best.0, self.id[best.1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prep(o: [f32; 3], d: [f32; 3]) -> RayPrep {
        RayPrep::new(o, d)
    }

    #[test]
    fn triangle_hit_front_and_back() {
        let tri = PreparedTriangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let down = tri.intersect(&prep([0.2, 0.2, 5.0], [0.0, 0.0, -1.0]), f32::MAX);
        assert!((down.unwrap_or(f32::NAN) - 5.0).abs() < 1e-6);
        let up = tri.intersect(&prep([0.2, 0.2, -2.0], [0.0, 0.0, 1.0]), f32::MAX);
        assert!((up.unwrap_or(f32::NAN) - 2.0).abs() < 1e-6);
        assert!(tri.intersect(&prep([0.8, 0.8, 1.0], [0.0, 0.0, -1.0]), f32::MAX).is_none());
        assert!(tri.intersect(&prep([0.2, 0.2, 5.0], [0.0, 0.0, -1.0]), 4.0).is_none());
        assert!(tri.intersect(&prep([0.2, 0.2, 5.0], [0.0, 0.0, 1.0]), f32::MAX).is_none());
        // An oblique ray, distance in units of |d|: from (0.1, 0.1, 3) along (0.1, 0.1, -1) · 2.
        let t = tri.intersect(&prep([0.1, 0.1, 3.0], [0.2, 0.2, -2.0]), f32::MAX).unwrap_or(f32::NAN);
        assert!((t - 1.5).abs() < 1e-6, "{t}");
    }

    #[test]
    fn block_lanes_equal_the_scalar_test_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut p = || Vec3::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
        for _ in 0..2000 {
            let tris: Vec<(u32, PreparedTriangle)> =
                (0..4).map(|i| (i, PreparedTriangle::new(p(), p(), p()))).collect();
            let n = 1 + (p().x.abs() * 1.4) as usize % 4;
            let block = TriBlock::new(&tris[..n]);
            let o = p() * 3.0;
            let d = p();
            if d.length() < 1e-3 {
                continue;
            }
            let ray = prep(o.to_array(), d.to_array());
            let scalar = tris[..n].iter().filter_map(|(id, t)| t.intersect(&ray, 50.0).map(|t| (t, *id))).fold(
                None,
                |best: Option<(f32, u32)>, h| match best {
                    Some(b) if b.0 <= h.0 => Some(b),
                    _ => Some(h),
                },
            );
            assert_eq!(block.intersect(&ray, 50.0), scalar);
        }
    }

    #[test]
    fn shared_edges_leak_no_ray() {
        // A fan of triangles around a vertex that every ray is aimed at, and rays along their shared edges:
        // each ray must hit (the two-sided watertight test hits an edge or vertex from both sides).
        let c = Vec3::new(0.3, -0.2, 0.0);
        let ring: Vec<Vec3> = (0..7)
            .map(|k| {
                let a = k as f32 * 0.9;
                c + Vec3::new(a.cos(), a.sin(), 0.05 * a)
            })
            .collect();
        let tris: Vec<PreparedTriangle> =
            (0..7).map(|k| PreparedTriangle::new(c, ring[k], ring[(k + 1) % 7])).collect();
        for k in 0..7 {
            for f in [0.0f32, 0.25, 0.5, 0.75, 0.999] {
                let target = c + (ring[k] - c) * f;
                for o in [Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.3, 2.1, 4.0), Vec3::new(-3.0, 0.5, -2.0)] {
                    let ray = prep(o.to_array(), (target - o).to_array());
                    assert!(tris.iter().any(|t| t.intersect(&ray, 2.0).is_some()), "edge {k} at {f} from {o:?}");
                }
            }
        }
    }

    #[test]
    fn pose_roundtrip_and_validation() {
        let p = RigidPose::from_xyz_rpy([1.0, 2.0, 3.0], [0.1, -0.2, 1.3]);
        let m = p.to_matrix_row_major();
        let q = RigidPose::from_matrix_row_major(&m, "pose").unwrap_or_default();
        assert!((q.rotation - p.rotation).abs_diff_eq(Mat3::ZERO, 1e-6));
        let x = Vec3::new(0.3, -4.0, 2.0);
        assert!(p.inverse_transform_point(p.transform_point(x)).abs_diff_eq(x, 1e-5));
        let mut scaled = m;
        scaled[0] *= 2.0;
        assert!(RigidPose::from_matrix_row_major(&scaled, "pose").is_err());
        let mut nan = m;
        nan[5] = f64::NAN;
        assert!(RigidPose::from_matrix_row_major(&nan, "pose").is_err());
        let mut reflect = RigidPose::IDENTITY.to_matrix_row_major();
        reflect[10] = -1.0;
        assert!(RigidPose::from_matrix_row_major(&reflect, "pose").is_err());
    }

    #[test]
    fn rpy_convention_is_z_y_x() {
        // Yaw of 90°: local x maps to world y.
        let p = RigidPose::from_xyz_rpy([0.0; 3], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        assert!(p.transform_vector(Vec3::X).abs_diff_eq(Vec3::Y, 1e-6));
        // Pitch of +90° about y: local x maps to world -z (nose down), right-handed.
        let p = RigidPose::from_xyz_rpy([0.0; 3], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
        assert!(p.transform_vector(Vec3::X).abs_diff_eq(Vec3::NEG_Z, 1e-6));
    }
}
