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
    /// Whether the ray leaves the water ([`crate::sea::WaveSurface::leaves`] of the scene's wave surface), when a
    /// batch worked it out once for every test that asks: [`LEAVES_UNKNOWN`] (work it out), [`LEAVES_NO`] or
    /// [`LEAVES_YES`]. It sits in what was padding: the struct is no larger.
    pub leaves: u8,
}

/// [`RayPrep::leaves`]: not worked out.
pub const LEAVES_UNKNOWN: u8 = 0;
/// [`RayPrep::leaves`]: the ray does not leave the water.
pub const LEAVES_NO: u8 = 1;
/// [`RayPrep::leaves`]: the ray leaves the water.
pub const LEAVES_YES: u8 = 2;

impl RayPrep {
    /// Prepares the ray `o + t·d`. `d` must be finite and non-zero.
    #[inline(always)]
    pub fn new(o: [f32; 3], d: [f32; 3]) -> Self {
        let inv = d.map(recip);
        let kz = dominant_axis(d);
        // The paper swaps kx and ky when d[kz] < 0 to keep the winding; the tests here are two-sided, where the
        // swap only flips the signs of all three edge functions together, so it is left out.
        let k = axes(kz);
        let [kx, ky, kz] = k.map(usize::from);
        let sz = 1.0 / d[kz]; // d[kz] is the largest component, never zero for a non-zero direction
        Self { o, d, inv, near: near_planes(inv), k, s: [d[kx] * sz, d[ky] * sz], leaves: LEAVES_UNKNOWN }
    }

    /// [`RayPrep::leaves`] as known: `Some(leaves)` once a batch worked it out, else `None`.
    #[inline(always)]
    pub fn leaves_known(&self) -> Option<bool> {
        match self.leaves {
            LEAVES_YES => Some(true),
            LEAVES_NO => Some(false),
            _ => None,
        }
    }
}

/// `1 / x`, with components below `1e-20` in magnitude clamped to `±1e20` (no `inf · 0` in slab tests).
#[inline(always)]
fn recip(x: f32) -> f32 {
    if x.abs() < 1e-20 {
        1e20f32.copysign(x)
    } else {
        1.0 / x
    }
}

/// The axis of the largest direction component (`kz`; ties go to the later axis).
#[inline(always)]
fn dominant_axis(d: [f32; 3]) -> u8 {
    let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
    if ax > ay {
        if ax > az {
            0
        } else {
            2
        }
    } else if ay > az {
        1
    } else {
        2
    }
}

/// The permutation `[kx, ky, kz]` for dominant axis `kz`.
#[inline(always)]
fn axes(kz: u8) -> [u8; 3] {
    [(kz + 1) % 3, (kz + 2) % 3, kz]
}

/// [`RayPrep::near`] from the reciprocal direction.
#[inline(always)]
fn near_planes(inv: [f32; 3]) -> [u8; 3] {
    [u8::from(inv[0] < 0.0) * 3, 1 + u8::from(inv[1] < 0.0) * 3, 2 + u8::from(inv[2] < 0.0) * 3]
}

/// [`RayPrep::new`] for `N` rays at once: ray `j` has origin `o[j]` and direction `(d[0][j], d[1][j], d[2][j])`
/// (finite, non-zero; fill unused lanes with any such direction). The arithmetic runs across the lanes, so it
/// vectorises, and each ray gets exactly what [`RayPrep::new`] gives it (the same correctly rounded operations
/// in the same order).
#[inline(always)]
pub fn prepare_lanes<const N: usize>(o: &[[f32; 3]; N], d: &[[f32; N]; 3]) -> [RayPrep; N] {
    let mut inv = [[0f32; N]; 3];
    for a in 0..3 {
        for j in 0..N {
            inv[a][j] = recip(d[a][j]);
        }
    }
    let mut kz = [2u8; N];
    let mut sc = [[0f32; N]; 2];
    for j in 0..N {
        let (x, y, z) = (d[0][j], d[1][j], d[2][j]);
        let k = dominant_axis([x, y, z]);
        // (d[kx], d[ky], d[kz]) as `axes` orders them, spelled out so the lanes vectorise.
        let (dkx, dky, dkz) = match k {
            0 => (y, z, x),
            1 => (z, x, y),
            _ => (x, y, z),
        };
        let sz = 1.0 / dkz;
        kz[j] = k;
        sc[0][j] = dkx * sz;
        sc[1][j] = dky * sz;
    }
    // A plain loop over a filled array: `std::array::from_fn` was compiled out of line (`try_from_fn`, 3.7 % of
    // a frame's samples).
    let blank = RayPrep { o: [0.0; 3], d: [0.0; 3], inv: [0.0; 3], near: [0; 3], k: [0; 3], s: [0.0; 2], leaves: 0 };
    let mut out = [blank; N];
    for (j, r) in out.iter_mut().enumerate() {
        let inv = [inv[0][j], inv[1][j], inv[2][j]];
        *r = RayPrep {
            o: o[j],
            d: [d[0][j], d[1][j], d[2][j]],
            inv,
            near: near_planes(inv),
            k: axes(kz[j]),
            s: [sc[0][j], sc[1][j]],
            leaves: LEAVES_UNKNOWN,
        };
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Directions that stress the preparation: axis-aligned, signed zeros, ties between axes, components tiny
    /// enough to be clamped, huge and small magnitudes together.
    pub(crate) const SPECIAL_DIRECTIONS: [[f32; 3]; 12] = [
        [0.0, 0.0, -1.0],
        [-0.0, 0.0, 1.0],
        [1.0, -0.0, 0.0],
        [0.0, -3.0, -0.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 0.0],
        [1e-30, -1e-25, -1.0],
        [-2e-18, 6e-17, -1.0],
        [3e-21, 1.0, 1.0],
        [1e30, 1e-30, 0.0],
        [0.5, -0.5, 0.5],
        [-7.0, 7.0, -7.0],
    ];

    /// Lane by lane, [`prepare_lanes`] is [`RayPrep::new`]: random and special directions (axis-aligned, tiny,
    /// signed zeros, ties between axes, long and short vectors).
    #[test]
    fn lanes_match_ray_by_ray_preparation() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let special = SPECIAL_DIRECTIONS;
        for round in 0..2_000 {
            let mut o = [[0f32; 3]; 16];
            let mut d = [[0f32; 16]; 3];
            let mut want = Vec::new();
            for j in 0..16 {
                o[j] = [rng.random_range(-1e3..1e3), rng.random_range(-1e3..1e3), rng.random_range(-10.0..100.0)];
                let dir = if (round + j) % 4 == 0 {
                    special[(round * 16 + j) % special.len()]
                } else {
                    [rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0)]
                };
                for a in 0..3 {
                    d[a][j] = dir[a];
                }
                want.push(RayPrep::new(o[j], dir));
            }
            assert_eq!(prepare_lanes(&o, &d).to_vec(), want, "round {round}");
        }
    }
}
