//! Packets of coherent rays traced through a [`Bvh`] together, with interval arithmetic at the nodes.
//!
//! Neighbouring camera pixels, neighbouring LiDAR columns and parallel top-view or shadow rays visit nearly
//! the same nodes. A packet of up to [`PACKET`] such rays, whose directions have the same sign on every axis,
//! is bounded by the interval of its origins and of its reciprocal directions. One 8-lane test of a node's
//! boxes against those intervals tells, conservatively, which children any ray of the packet can enter
//! before the packet's farthest current hit — the cost of one single-ray node test for the whole packet.
//! Leaves are then checked ray by ray (box first, then the leaf's triangles), so each ray's result is exactly
//! what it gets traced alone: the interval bounds are computed with the same correctly rounded operations as
//! the per-ray slab test, and rounding is monotone, so they can only be wider.

use super::{max, min, Box3, Bvh, Node, EMPTY, FAR_SCALE, LEAF, WIDTH};
use crate::ray::RayPrep;

/// Most rays in a packet.
pub const PACKET: usize = 16;

/// The rays of a packet: each ray prepared on its own, plus the packet's intervals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Packet {
    /// Number of rays (the first `n` entries are used).
    pub n: usize,
    /// Each ray, prepared for its exact tests.
    pub ray: [RayPrep; PACKET],
    /// Origins per axis and ray (for the per-ray box tests at leaves).
    o: [[f32; PACKET]; 3],
    /// Directions per axis and ray.
    d: [[f32; PACKET]; 3],
    /// Reciprocal directions per axis and ray.
    inv: [[f32; PACKET]; 3],
    /// Closest hit so far per ray; `-1` for unused or finished rays, which then enter no box.
    pub best: [f32; PACKET],
    /// The shear constants of every ray per component (`s[c][ray]`), for triangle tests across the rays.
    pub shear: [[f32; PACKET]; 2],
    /// Whether every ray has the same dominant axis `ray[0].k` (then triangles are tested across rays).
    pub uniform_k: bool,
    /// Near plane index per axis (the same for every ray: the packet shares direction signs).
    near: [usize; 3],
    /// Origin bound that gives the smallest entry (largest origin along a positive direction), per axis.
    o_entry: [f32; 3],
    /// Origin bound that gives the largest exit, per axis.
    o_exit: [f32; 3],
    /// Smallest and largest reciprocal direction, per axis.
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
}

impl Default for Packet {
    /// An empty packet (no ray), to [`Packet::fill`].
    fn default() -> Self {
        let ray = RayPrep::new([0.0; 3], [1.0, 0.0, 0.0]);
        Packet {
            n: 0,
            ray: [ray; PACKET],
            o: [[0.0; PACKET]; 3],
            d: [[1.0; PACKET]; 3],
            inv: [[1.0; PACKET]; 3],
            best: [-1.0; PACKET],
            shear: [[0.0; PACKET]; 2],
            uniform_k: true,
            near: ray.near.map(usize::from),
            o_entry: [0.0; 3],
            o_exit: [0.0; 3],
            inv_lo: [0.0; 3],
            inv_hi: [0.0; 3],
        }
    }
}

impl Packet {
    /// Builds a packet of the prepared rays `rays` (1 to [`PACKET`]) with range `t_max`, or `None` when their
    /// directions do not share a sign on every axis (interval bounds would then be useless).
    #[inline(always)]
    pub fn new(rays: &[RayPrep], t_max: f32) -> Option<Self> {
        let mut p = Self::default();
        p.fill(rays, t_max).then_some(p)
    }

    /// [`Packet::new`] in place: makes `self` the packet of `rays` with range `t_max` (every field as `new`
    /// sets it) and returns `true`, or returns `false` (leaving `self` unspecified) when the rays' directions do
    /// not share a sign on every axis or there are none or too many. A packet reused across calls saves
    /// building and copying a new one each time.
    #[inline(always)]
    pub fn fill(&mut self, rays: &[RayPrep], t_max: f32) -> bool {
        let Some(first) = rays.first() else { return false };
        if rays.len() > PACKET || rays.iter().any(|r| r.near != first.near) {
            return false;
        }
        let near = first.near.map(usize::from);
        self.n = rays.len();
        self.uniform_k = rays.iter().all(|r| r.k == first.k);
        self.near = near;
        let mut o_lo = first.o;
        let mut o_hi = first.o;
        let mut inv_lo = first.inv;
        let mut inv_hi = first.inv;
        for r in 0..PACKET {
            let Some(ray) = rays.get(r) else {
                // Unused lanes: the first ray, finished (best < 0), neutral arrays.
                self.ray[r] = *first;
                self.best[r] = -1.0;
                self.shear[0][r] = 0.0;
                self.shear[1][r] = 0.0;
                for a in 0..3 {
                    self.o[a][r] = 0.0;
                    self.d[a][r] = 1.0;
                    self.inv[a][r] = 1.0;
                }
                continue;
            };
            self.ray[r] = *ray;
            self.best[r] = t_max;
            self.shear[0][r] = ray.s[0];
            self.shear[1][r] = ray.s[1];
            for a in 0..3 {
                self.o[a][r] = ray.o[a];
                self.d[a][r] = ray.d[a];
                self.inv[a][r] = ray.inv[a];
                o_lo[a] = o_lo[a].min(ray.o[a]);
                o_hi[a] = o_hi[a].max(ray.o[a]);
                inv_lo[a] = inv_lo[a].min(ray.inv[a]);
                inv_hi[a] = inv_hi[a].max(ray.inv[a]);
            }
        }
        for a in 0..3 {
            let neg = near[a] != a;
            self.o_entry[a] = if neg { o_lo[a] } else { o_hi[a] };
            self.o_exit[a] = if neg { o_hi[a] } else { o_lo[a] };
        }
        self.inv_lo = inv_lo;
        self.inv_hi = inv_hi;
        true
    }

    /// Origins per axis and ray.
    #[inline(always)]
    pub fn origins(&self) -> &[[f32; PACKET]; 3] {
        &self.o
    }

    /// Directions per axis and ray.
    #[inline(always)]
    pub fn directions(&self) -> &[[f32; PACKET]; 3] {
        &self.d
    }

    /// The largest current best distance (no box beyond it matters to any ray).
    #[inline(always)]
    pub fn max_best(&self) -> f32 {
        let mut m = -1f32;
        for &b in &self.best {
            m = max(m, b);
        }
        m
    }

    /// Conservative entry of the packet into the node's eight boxes: the mask of lanes that some ray may enter
    /// before `t_max`, and a lower bound of the entry distance per lane.
    #[inline(always)]
    fn node_entry(&self, node: &Node, t_max: f32) -> (u32, [f32; WIDTH]) {
        let b = &node.bounds;
        let mut t0 = [0f32; WIDTH];
        let mut t1 = [t_max; WIDTH];
        for a in 0..3 {
            let (near, far) = (&b[self.near[a]], &b[(self.near[a] + 3) % 6]);
            let (oe, ox, il, ih) = (self.o_entry[a], self.o_exit[a], self.inv_lo[a], self.inv_hi[a]);
            for l in 0..WIDTH {
                let e = near[l] - oe;
                let x = far[l] - ox;
                t0[l] = max(t0[l], min(e * il, e * ih));
                t1[l] = min(t1[l], max(x * il, x * ih) * FAR_SCALE);
            }
        }
        let mut mask = 0u32;
        for l in 0..WIDTH {
            mask |= u32::from(t0[l] <= t1[l]) << l;
        }
        (mask, t0)
    }

    /// The rays that enter lane `lane` of `node` before their own best distance, as a bit mask (the exact
    /// per-ray slab test of the single-ray traversal).
    #[inline(always)]
    pub fn rays_entering(&self, node: &Node, lane: usize) -> u32 {
        let b = &node.bounds;
        self.rays_entering_box(&Box3 {
            lo: [b[0][lane], b[1][lane], b[2][lane]],
            hi: [b[3][lane], b[4][lane], b[5][lane]],
        })
    }

    /// The rays that enter box `bx` before their own best distance, as a bit mask: for every ray the slab test
    /// of [`super::box_entry`], with the same operations, done across the rays.
    #[inline(always)]
    pub fn rays_entering_box(&self, bx: &Box3) -> u32 {
        let mut t0 = [0f32; PACKET];
        let mut t1 = self.best;
        for a in 0..3 {
            let (near, far) = if self.near[a] == a { (bx.lo[a], bx.hi[a]) } else { (bx.hi[a], bx.lo[a]) };
            let (o, inv) = (&self.o[a], &self.inv[a]);
            for r in 0..PACKET {
                t0[r] = max(t0[r], (near - o[r]) * inv[r]);
                t1[r] = min(t1[r], (far - o[r]) * inv[r] * FAR_SCALE);
            }
        }
        let mut mask = 0u32;
        for r in 0..PACKET {
            mask |= u32::from(t0[r] <= t1[r]) << r;
        }
        mask
    }
}

/// Tests a leaf's primitives for the rays of a packet ([`Bvh::closest_packet`], [`Bvh::any_packet`]).
pub trait PacketVisit {
    /// Tests leaf `leaf` against the rays in `rays` (a bit mask of packet lanes) and lowers `p.best[r]` for
    /// every ray `r` that hits closer (for any-hit queries: sets it below zero once the ray is blocked).
    fn leaf(&mut self, leaf: u32, rays: u32, p: &mut Packet);
}

/// Traversal scratch space of packets, reused across packets.
#[derive(Debug, Default, Clone)]
pub struct PacketStack {
    /// (child reference, entry bound, parent node, lane in the parent)
    entries: Vec<(u32, f32, u32, u32)>,
}

impl Bvh {
    /// Traces a packet: every ray ends with its closest hit below its starting `best` (recorded by `visit`).
    /// Children are visited nearest first; a subtree is skipped once no ray can still hit it.
    #[inline(always)]
    pub fn closest_packet<V: PacketVisit>(&self, p: &mut Packet, stack: &mut PacketStack, visit: &mut V) {
        self.walk(p, stack, visit, false);
    }

    /// Occlusion for a packet: `visit` marks blocked rays (`best < 0`); the walk ends when every ray is
    /// blocked or the tree is exhausted.
    #[inline(always)]
    pub fn any_packet<V: PacketVisit>(&self, p: &mut Packet, stack: &mut PacketStack, visit: &mut V) {
        self.walk(p, stack, visit, true);
    }

    #[inline(always)]
    fn walk<V: PacketVisit>(&self, p: &mut Packet, stack: &mut PacketStack, visit: &mut V, any: bool) {
        let st = &mut stack.entries;
        st.clear();
        let root = self.wide.root;
        if root == EMPTY {
            return;
        }
        if root & LEAF != 0 {
            let all = (u64::MAX >> (64 - p.n)) as u32;
            visit.leaf(root & !LEAF, all, p);
            return;
        }
        let mut limit = p.max_best();
        st.push((root, 0.0, u32::MAX, 0));
        while let Some((cur, t, parent, lane)) = st.pop() {
            if t > limit {
                continue;
            }
            if cur & LEAF != 0 {
                let rays = self.rays_into(p, parent, lane);
                if rays != 0 {
                    visit.leaf(cur & !LEAF, rays, p);
                    limit = p.max_best();
                    if any && limit < 0.0 {
                        return;
                    }
                }
                continue;
            }
            let node = &self.wide.nodes[cur as usize];
            let (mask, tn) = p.node_entry(node, limit);
            if mask == 0 {
                continue;
            }
            // Push the hit children farthest first, so the nearest is popped next.
            let mut hits = [(EMPTY, 0f32, 0u32); WIDTH];
            let mut n = 0usize;
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let e = (node.child[l], tn[l], l as u32);
                let mut j = n;
                while j > 0 && hits[j - 1].1 < e.1 {
                    hits[j] = hits[j - 1];
                    j -= 1;
                }
                hits[j] = e;
                n += 1;
            }
            // ... under the entry on top of the stack when that is nearer than every child (as in `Bvh::closest`).
            let top = match st.last() {
                Some(top) if top.1 < hits[n - 1].1 => st.pop(),
                _ => None,
            };
            for &(c, t, l) in &hits[..n] {
                st.push((c, t, cur, l));
            }
            st.extend(top);
        }
    }

    /// The rays of `p` that enter the box of lane `lane` of node `parent` (all rays for the root).
    #[inline(always)]
    fn rays_into(&self, p: &Packet, parent: u32, lane: u32) -> u32 {
        let live = (u64::MAX >> (64 - p.n)) as u32;
        if parent == u32::MAX {
            return live;
        }
        p.rays_entering(&self.wide.nodes[parent as usize], lane as usize) & live
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::box_entry;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A packet refilled in place is the packet `new` builds: every field, the unused lanes included, after a
    /// fuller packet of other rays; rays whose directions differ in sign make no packet.
    #[test]
    fn fill_in_place_equals_new() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut p = Packet::default();
        for _ in 0..200 {
            let n = rng.random_range(1..=PACKET);
            let o = [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)];
            let rays: Vec<RayPrep> = (0..n)
                .map(|_| {
                    let d: [f32; 3] =
                        [rng.random_range(0.2..1.0), rng.random_range(-1.0..-0.2), rng.random_range(-0.3..0.3)];
                    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    RayPrep::new(o, d.map(|x| x / l))
                })
                .collect();
            let t = rng.random_range(1.0..100.0);
            let mixed = rays.iter().any(|r| r.near != rays[0].near);
            assert_eq!(p.fill(&rays, t), !mixed);
            match Packet::new(&rays, t) {
                Some(q) => assert_eq!(p, q),
                None => assert!(mixed),
            }
        }
        assert!(!p.fill(&[], 1.0), "no rays, no packet");
    }

    /// The packet's box test gives every ray exactly the single-ray slab test's answer (rays with a negative best,
    /// finished or unused lanes, enter nothing), for boxes in front, behind, around and beside the rays.
    #[test]
    fn rays_entering_a_box_equals_the_single_ray_test() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let (mut entered, mut missed) = (0, 0);
        for _ in 0..2000 {
            let o = [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)];
            let base = [rng.random_range(0.1..1.0), rng.random_range(-1.0..-0.1), rng.random_range(-1.0..1.0)];
            let n = rng.random_range(1..=PACKET);
            let rays: Vec<RayPrep> = (0..n)
                .map(|_| {
                    let mut d = base.map(|x: f32| x + rng.random_range(-0.08..0.08));
                    if d[2].abs() < 0.1 {
                        d[2] = 0.0; // axis-parallel in z: the clamped reciprocal
                    }
                    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    RayPrep::new(o, d.map(|x| x / l))
                })
                .collect();
            let Some(mut p) = Packet::new(&rays, rng.random_range(1.0..40.0)) else { continue };
            for r in 0..n {
                if rng.random_range(0..5) == 0 {
                    p.best[r] = -1.0;
                }
            }
            // Around a point on the packet's way (or behind its origin), give or take a few metres.
            let t = rng.random_range(-10.0..40.0);
            let c = [0, 1, 2].map(|a| o[a] + t * base[a] + rng.random_range(-4.0..4.0));
            let h = [rng.random_range(0.0..8.0), rng.random_range(0.0..8.0), rng.random_range(0.0..8.0)];
            let bx = Box3 { lo: [c[0] - h[0], c[1] - h[1], c[2] - h[2]], hi: [c[0] + h[0], c[1] + h[1], c[2] + h[2]] };
            let mask = p.rays_entering_box(&bx);
            for (r, ray) in rays.iter().enumerate() {
                let want = p.best[r] >= 0.0 && box_entry(&bx, ray, p.best[r]);
                assert_eq!(mask & (1 << r) != 0, want, "ray {r} of {n}");
                if want {
                    entered += 1;
                } else {
                    missed += 1;
                }
            }
            assert_eq!(mask >> n, 0, "unused lanes enter nothing");
        }
        assert!(entered > 1000 && missed > 1000, "{entered} entered, {missed} missed");
    }
}
