//! Packets of coherent rays traced together through a [`Bvh4`](crate::bvh::Bvh4).
//!
//! Rays from one sensor that point in nearly the same direction (neighbouring camera pixels, neighbouring
//! LiDAR beams) visit nearly the same BVH nodes. A packet of [`PACKET`] such rays walks the tree once: each
//! node's four boxes are tested against all rays of the packet in loops the compiler vectorises, a child is
//! visited if any ray can still hit it, and leaf triangles are tested against all rays at once. Each ray
//! keeps its own closest hit, so results are identical to tracing the rays one by one.

use crate::geometry::PreparedTriangle;

/// Rays per packet.
pub const PACKET: usize = 8;

/// A packet of rays in structure-of-arrays form with each ray's current closest hit.
#[derive(Debug, Clone, Copy)]
pub struct Packet {
    /// Origins.
    pub o: [[f32; PACKET]; 3],
    /// Unit directions.
    pub d: [[f32; PACKET]; 3],
    /// Reciprocal directions (never infinite: tiny components are clamped).
    pub inv: [[f32; PACKET]; 3],
    /// Closest hit distance so far (starts at the range limit; `-1` for padding lanes that never hit).
    pub best: [f32; PACKET],
    /// Leaf-order index of the closest primitive per ray, `u32::MAX` if none.
    pub prim: [u32; PACKET],
}

impl Packet {
    /// Builds a packet from up to [`PACKET`] rays; missing lanes are padding that can never hit.
    pub fn new(origins: &[[f32; 3]], dirs: &[[f32; 3]], t_max: f32) -> Self {
        let mut p = Packet {
            o: [[0.0; PACKET]; 3],
            d: [[1.0; PACKET]; 3],
            inv: [[1.0; PACKET]; 3],
            best: [-1.0; PACKET],
            prim: [u32::MAX; PACKET],
        };
        for (r, (o, d)) in origins.iter().zip(dirs).take(PACKET).enumerate() {
            for a in 0..3 {
                p.o[a][r] = o[a];
                p.d[a][r] = d[a];
            }
            p.best[r] = t_max;
        }
        p.refresh_inverse();
        p
    }

    /// Recomputes `inv` from `d`.
    pub fn refresh_inverse(&mut self) {
        for a in 0..3 {
            for r in 0..PACKET {
                let d = self.d[a][r];
                self.inv[a][r] = if d.abs() < 1e-20 { 1e20f32.copysign(d) } else { 1.0 / d };
            }
        }
    }

    /// Largest current best distance over the packet (no child beyond it can matter).
    #[inline(always)]
    pub fn max_best(&self) -> f32 {
        self.best.iter().fold(f32::NEG_INFINITY, |m, &b| if b > m { b } else { m })
    }

    /// Whether all rays point within a cone of half-angle ≈ `acos(min_cos)` of the first ray and share an
    /// origin within `radius`: only then is tracing them together worthwhile.
    pub fn is_coherent(origins: &[[f32; 3]], dirs: &[[f32; 3]], min_cos: f32, radius: f32) -> bool {
        let (Some(o0), Some(d0)) = (origins.first(), dirs.first()) else { return false };
        origins.iter().zip(dirs).all(|(o, d)| {
            let dc = d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2];
            let r2 = (o[0] - o0[0]).powi(2) + (o[1] - o0[1]).powi(2) + (o[2] - o0[2]).powi(2);
            dc >= min_cos && r2 <= radius * radius
        })
    }

    /// Entry distance of the packet into box `(mins, maxs)`: the smallest entry over rays that hit it before
    /// their current best, or `INFINITY` if none does.
    #[inline(always)]
    pub fn entry(&self, mins: [f32; 3], maxs: [f32; 3]) -> f32 {
        let mut tn = [0.0f32; PACKET];
        let mut tf = self.best;
        for a in 0..3 {
            for r in 0..PACKET {
                let t1 = (mins[a] - self.o[a][r]) * self.inv[a][r];
                let t2 = (maxs[a] - self.o[a][r]) * self.inv[a][r];
                let (lo, hi) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
                tn[r] = if lo > tn[r] { lo } else { tn[r] };
                tf[r] = if hi < tf[r] { hi } else { tf[r] };
            }
        }
        let mut m = f32::INFINITY;
        for r in 0..PACKET {
            let e = if tn[r] <= tf[r] { tn[r] } else { f32::INFINITY };
            m = if e < m { e } else { m };
        }
        m
    }

    /// Tests triangle `tri` (leaf-order index `k`) against every ray, keeping closer hits.
    #[inline(always)]
    pub fn intersect_triangle(&mut self, tri: &PreparedTriangle, k: u32) {
        let (v0, e1, e2) = (tri.v0.to_array(), tri.e1.to_array(), tri.e2.to_array());
        for r in 0..PACKET {
            let (dx, dy, dz) = (self.d[0][r], self.d[1][r], self.d[2][r]);
            // p = d × e2
            let px = dy * e2[2] - dz * e2[1];
            let py = dz * e2[0] - dx * e2[2];
            let pz = dx * e2[1] - dy * e2[0];
            let det = e1[0] * px + e1[1] * py + e1[2] * pz;
            let inv = 1.0 / det;
            let sx = self.o[0][r] - v0[0];
            let sy = self.o[1][r] - v0[1];
            let sz = self.o[2][r] - v0[2];
            let u = (sx * px + sy * py + sz * pz) * inv;
            // q = s × e1
            let qx = sy * e1[2] - sz * e1[1];
            let qy = sz * e1[0] - sx * e1[2];
            let qz = sx * e1[1] - sy * e1[0];
            let v = (dx * qx + dy * qy + dz * qz) * inv;
            let t = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inv;
            let ok = det != 0.0 && u >= 0.0 && u <= 1.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < self.best[r];
            if ok {
                self.best[r] = t;
                self.prim[r] = k;
            }
        }
    }
}
