//! A ray prepared once for every box and triangle test along its traversal.
//!
//! * Box (slab) tests use the reciprocal direction, with tiny components clamped so no `inf · 0` can occur.
//! * Triangle tests follow Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013): the
//!   axis where the direction is largest becomes z, and a shear maps the ray onto the +z axis through the
//!   origin, so the edge functions of triangles sharing an edge are computed from the same numbers and no ray
//!   slips between them. [`RayPrep::new`] computes the permutation `k` and the shear `s` once per ray.

/// A ray with everything its box and triangle tests need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayPrep {
    /// Origin.
    pub o: [f32; 3],
    /// Direction (unit length for metric distances; any non-zero length works, `t` is then in units of it).
    pub d: [f32; 3],
    /// Reciprocal direction, components clamped to `±1e20`.
    pub inv: [f32; 3],
    /// Per axis, the index of the near box plane in [`crate::bvh::Node::bounds`] (the max plane, `axis + 3`, when
    /// the direction component is negative); the far plane is the other one.
    pub near: [u8; 3],
    /// Axis permutation `[kx, ky, kz]`: `kz` is the axis of the largest direction component, `kx = kz + 1`,
    /// `ky = kz + 2` (mod 3).
    pub k: [u8; 3],
    /// Shear constants `[d[kx]/d[kz], d[ky]/d[kz]]` (the paper's third, `1/d[kz]`, is not needed: distances come
    /// from the triangle's plane).
    pub s: [f32; 2],
}

impl RayPrep {
    /// Prepares the ray `o + t·d`. `d` must be finite and non-zero.
    #[inline(always)]
    pub fn new(o: [f32; 3], d: [f32; 3]) -> Self {
        let f = |x: f32| if x.abs() < 1e-20 { 1e20f32.copysign(x) } else { 1.0 / x };
        let inv = [f(d[0]), f(d[1]), f(d[2])];
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        let kz = if ax > ay {
            if ax > az {
                0
            } else {
                2
            }
        } else if ay > az {
            1
        } else {
            2
        };
        // The paper swaps kx and ky when d[kz] < 0 to keep the winding; the tests here are two-sided, where the
        // swap only flips the signs of all three edge functions together, so it is left out.
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let sz = 1.0 / d[kz]; // d[kz] is the largest component, never zero for a non-zero direction
        Self {
            o,
            d,
            inv,
            near: [u8::from(inv[0] < 0.0) * 3, 1 + u8::from(inv[1] < 0.0) * 3, 2 + u8::from(inv[2] < 0.0) * 3],
            k: [kx as u8, ky as u8, kz as u8],
            s: [d[kx] * sz, d[ky] * sz],
        }
    }
}
