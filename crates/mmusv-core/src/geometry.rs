//! Rigid poses and the ray–triangle test shared by every ray query.
//!
//! Poses are rigid transforms `p_world = R · p_local + t` (no scale), stored in `f32` because the
//! scene itself is `f32`; kinematics works in `f64` and converts at the scene boundary.

use crate::error::{MmusvError, Result};
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
        let col = |j: usize| Vec3::new(r(0, j) as f32, r(1, j) as f32, r(2, j) as f32);
        Ok(Self {
            rotation: Mat3::from_cols(col(0), col(1), col(2)),
            translation: Vec3::new(r(0, 3) as f32, r(1, 3) as f32, r(2, 3) as f32),
        })
    }

    /// Builds a pose from a translation and roll, pitch, yaw in radians, with `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
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

/// A triangle stored for fast intersection: first vertex and the two edges from it.
#[derive(Debug, Clone, Copy)]
pub struct PreparedTriangle {
    /// First vertex.
    pub v0: Vec3,
    /// `v1 - v0`.
    pub e1: Vec3,
    /// `v2 - v0`.
    pub e2: Vec3,
}

impl PreparedTriangle {
    /// Prepares the triangle `(a, b, c)`.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Self { v0: a, e1: b - a, e2: c - a }
    }

    /// The unnormalised geometric normal `e1 × e2` (follows the winding `a → b → c`).
    #[inline(always)]
    pub fn normal(&self) -> Vec3 {
        self.e1.cross(self.e2)
    }

    /// Two-sided Möller–Trumbore test: the ray parameter `t` in `(0, t_max)` of the hit, if any.
    ///
    /// Both faces are hit (no culling); whether a hit is on the back face is decided by the caller from the
    /// sign of `normal · dir`. `dir` need not be unit length; `t` is in units of `|dir|`.
    #[inline(always)]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
        let p = dir.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > 0.0 && t < t_max).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hit_front_and_back() {
        let tri = PreparedTriangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let down = tri.intersect(Vec3::new(0.2, 0.2, 5.0), Vec3::NEG_Z, f32::MAX);
        assert!((down.unwrap_or(f32::NAN) - 5.0).abs() < 1e-6);
        let up = tri.intersect(Vec3::new(0.2, 0.2, -2.0), Vec3::Z, f32::MAX);
        assert!((up.unwrap_or(f32::NAN) - 2.0).abs() < 1e-6);
        assert!(tri.intersect(Vec3::new(0.8, 0.8, 1.0), Vec3::NEG_Z, f32::MAX).is_none());
        assert!(tri.intersect(Vec3::new(0.2, 0.2, 5.0), Vec3::NEG_Z, 4.0).is_none());
        assert!(tri.intersect(Vec3::new(0.2, 0.2, 5.0), Vec3::Z, f32::MAX).is_none());
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
