//! Shared helpers of the round: guarded calls that turn a panic into a failure naming the call, error-field
//! checks, the independent reference maths (vectors, rotations, ray–triangle and ray–box hits), test meshes and
//! scenes, a deterministic ray generator and scratch directories.

use mmusv_core::error::MmusvError;
use mmusv_core::geometry::RigidPose;
use mmusv_core::mesh::Mesh;
use mmusv_core::ocean::SeaSpec;
use mmusv_core::scene::Scene;
use mmusv_core::sensors::camera::{CameraConfig, Projection};
use mmusv_core::Result;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Runs `f`, turning a panic into a test failure that names the call.
pub(crate) fn guarded<T>(what: &str, f: impl FnOnce() -> T) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => v,
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            unreachable!("{what} panicked instead of returning an error: {msg}")
        }
    }
}

/// The field an error names.
pub(crate) fn field_of(e: &MmusvError) -> String {
    match e {
        MmusvError::InvalidInput { field, .. }
        | MmusvError::Geometry { field, .. }
        | MmusvError::Config { field, .. } => field.clone(),
        MmusvError::UnknownId { kind, .. } => (*kind).to_string(),
        MmusvError::Io { path, .. } => path.clone(),
    }
}

/// Runs `f` guarded and checks that it fails with an error whose field contains `field`.
pub(crate) fn refuses<T: std::fmt::Debug>(what: &str, field: &str, f: impl FnOnce() -> Result<T>) {
    match guarded(what, f) {
        Ok(v) => {
            let shown = format!("{v:?}");
            let shown: String = shown.chars().take(200).collect();
            unreachable!("{what}: accepted (no error naming `{field}`), gave {shown}")
        }
        Err(e) => {
            let got = field_of(&e);
            assert!(got.contains(field), "{what}: error names `{got}`, expected `{field}` ({e})");
            assert!(!e.to_string().is_empty());
        }
    }
}

/// Runs `f` guarded and returns its value, failing the test with the error when it fails.
pub(crate) fn ok<T>(what: &str, f: impl FnOnce() -> Result<T>) -> T {
    match guarded(what, f) {
        Ok(v) => v,
        Err(e) => unreachable!("{what} failed: {e}"),
    }
}

pub(crate) fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

/// `R = Rz(yaw)·Ry(pitch)·Rx(roll)` written out independently, row-major.
pub(crate) fn rpy_matrix(rpy: [f64; 3]) -> [[f64; 3]; 3] {
    let rx = [[1.0, 0.0, 0.0], [0.0, rpy[0].cos(), -rpy[0].sin()], [0.0, rpy[0].sin(), rpy[0].cos()]];
    let ry = [[rpy[1].cos(), 0.0, rpy[1].sin()], [0.0, 1.0, 0.0], [-rpy[1].sin(), 0.0, rpy[1].cos()]];
    let rz = [[rpy[2].cos(), -rpy[2].sin(), 0.0], [rpy[2].sin(), rpy[2].cos(), 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        m
    };
    mul(rz, mul(ry, rx))
}

pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

pub(crate) fn mat_t_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2])
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(crate) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
pub(crate) fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / norm(a))
}
pub(crate) fn f32x3(a: [f64; 3]) -> [f32; 3] {
    a.map(|x| x as f32)
}
pub(crate) fn f64x3(a: [f32; 3]) -> [f64; 3] {
    a.map(f64::from)
}

/// Möller–Trumbore in f64: `(t, u, v)` of the ray `o + t d` against triangle `(a, b, c)`.
pub(crate) fn ray_triangle(o: [f64; 3], d: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<(f64, f64, f64)> {
    let e1 = sub(b, a);
    let e2 = sub(c, a);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = sub(o, a);
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    let t = dot(e2, q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some((t, u, v))
}

/// Slab test in f64 against the box `[-h, h]` (local frame): entry distance (or exit from inside) and the axis.
pub(crate) fn ray_box(o: [f64; 3], d: [f64; 3], h: [f64; 3]) -> Option<(f64, usize)> {
    let (mut t0, mut t1, mut axis0, mut axis1) = (f64::NEG_INFINITY, f64::INFINITY, 0, 0);
    for i in 0..3 {
        if d[i].abs() < 1e-15 {
            if o[i].abs() > h[i] {
                return None;
            }
            continue;
        }
        let (a, b) = ((-h[i] - o[i]) / d[i], (h[i] - o[i]) / d[i]);
        let (near, far) = if a < b { (a, b) } else { (b, a) };
        if near > t0 {
            t0 = near;
            axis0 = i;
        }
        if far < t1 {
            t1 = far;
            axis1 = i;
        }
    }
    if t0 > t1 || t1 <= 0.0 {
        None
    } else if t0 > 0.0 {
        Some((t0, axis0))
    } else {
        Some((t1, axis1))
    }
}

/// A closed box `[-h, h]` of 12 triangles wound counter-clockwise seen from outside (outward normals).
pub(crate) fn box_mesh(name: &str, h: [f32; 3], class: u16) -> Result<Mesh> {
    let v: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { -h[0] } else { h[0] },
                if i & 2 == 0 { -h[1] } else { h[1] },
                if i & 4 == 0 { -h[2] } else { h[2] },
            ]
        })
        .collect();
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let mut f = Vec::new();
    for q in quads {
        f.push([q[0], q[1], q[2]]);
        f.push([q[0], q[2], q[3]]);
    }
    Mesh::new(name, &v, &f, &[class])
}

/// A square `[-s, s]²` in the local z = 0 plane, normal +z.
pub(crate) fn square_mesh(name: &str, s: f32, class: u16) -> Result<Mesh> {
    let v = [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]];
    Mesh::new(name, &v, &[[0, 1, 2], [0, 2, 3]], &[class])
}

/// A tiny deterministic generator for test rays (no dependency on the crate's own noise).
pub(crate) struct Lcg(pub(crate) u64);
impl Lcg {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

pub(crate) fn scratch_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mmusv-user-round-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::create_dir_all(&d);
    d
}

/// A room: the inside of a box `[-h, h]³` around `centre` (class 5).
pub(crate) fn room(centre: [f64; 3], h: f32) -> Scene {
    let mut s = Scene::new();
    if let Ok(m) = box_mesh("room", [h, h, h], 5) {
        let id = s.add_mesh(m);
        let _ = s.add_instance(id, RigidPose::from_xyz_rpy(centre, [0.0; 3]), None);
    }
    s
}

pub(crate) fn pinhole(w: u32, h: u32, hfov: f64) -> CameraConfig {
    CameraConfig {
        width: w,
        height: h,
        projection: Projection::Pinhole { hfov },
        range_max: 1000.0,
        image: Default::default(),
    }
}

pub(crate) fn spec() -> SeaSpec {
    SeaSpec { hs: 2.0, tp: 8.0, gamma: 3.3, direction_rad: 0.6, spread_s: 10.0 }
}
