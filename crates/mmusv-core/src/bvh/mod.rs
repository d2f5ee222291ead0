//! Bounding volume hierarchies: an 8-wide BVH built by binned SAH and traversed one ray at a time with every
//! node's eight box tests done together.
//!
//! * [`build`]: the binary SAH build over primitive boxes (parallel, deterministic).
//! * [`wide`]: the collapse into 8-wide nodes in structure-of-arrays layout.
//! * [`packet`]: coherent rays traced together, with interval arithmetic at the nodes.
//! * [`Bvh`] (here): the tree plus traversal, nearest child first with early termination ([`Bvh::closest`]) or
//!   stopping at the first hit ([`Bvh::any`]). What a leaf holds is the caller's business: a [`Visit`]
//!   implementation tests a leaf's primitives (a block of four triangles for a mesh, instances for a scene).
//!
//! The box tests are plain loops over the eight lanes of a node, written so the compiler turns them into SIMD
//! instructions; the callers compile the traversal once per CPU feature level (see [`crate::simd`]), so the
//! same binary uses AVX2 where the CPU has it and stays portable.

pub mod build;
pub mod packet;
pub mod wide;

use crate::ray::RayPrep;
pub use build::{BinTree, Box3};
pub use packet::{Packet, PacketStack, PacketVisit, PACKET};
pub use wide::{Leaf, Node, Wide, EMPTY, LEAF, WIDTH};

/// Primitives per SIMD block, the unit of leaf cost in the SAH build ([`crate::geometry::BLOCK`]).
pub const BLOCK: usize = crate::geometry::BLOCK;

/// `1 + 2γ₃` (pbrt's bound on the rounding of a slab test): far distances are scaled by it so rounding can never
/// make a box test miss a ray that the watertight triangle test inside it hits.
pub(crate) const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Tests a leaf's primitives for [`Bvh::closest`] and [`Bvh::any`].
pub trait Visit {
    /// Tests the primitives of leaf `leaf` against the ray and returns the new closest distance (`best` if
    /// nothing closer was hit). Implementations record what they hit themselves.
    fn leaf(&mut self, leaf: u32, best: f32) -> f32;
}

/// Traversal scratch space, reused across rays (one per thread).
#[derive(Debug, Default, Clone)]
pub struct Stack {
    entries: Vec<(u32, f32)>,
}

/// An 8-wide BVH over primitives `0..n`, with leaves of up to `max_leaf` primitives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bvh {
    wide: Wide,
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the tree over one box per primitive (boxes must be finite). An empty slice gives an empty tree.
    pub fn new(boxes: &[Box3], max_leaf: usize) -> Self {
        let tree = build::build(boxes, max_leaf);
        let wide = wide::collapse(&tree);
        Self { wide, order: tree.order }
    }

    /// Leaf order → primitive index.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The leaves (ranges of [`Bvh::order`]), by leaf index.
    pub fn leaves(&self) -> &[Leaf] {
        &self.wide.leaves
    }

    /// The nodes.
    pub fn nodes(&self) -> &[Node] {
        &self.wide.nodes
    }

    /// Bounds of everything in the tree ([`Box3::EMPTY`] when empty).
    pub fn bounds(&self) -> Box3 {
        self.wide.bounds
    }

    /// Whether the tree holds no primitive.
    pub fn is_empty(&self) -> bool {
        self.wide.root == EMPTY
    }

    /// Closest hit along `ray` below `t_max`: walks the tree nearest child first, calls `visit.leaf` for every
    /// leaf whose box the ray enters before the current best, and returns the final best distance (`t_max` if
    /// nothing was hit).
    #[inline(always)]
    pub fn closest<V: Visit>(&self, ray: &RayPrep, t_max: f32, stack: &mut Stack, visit: &mut V) -> f32 {
        let mut best = t_max;
        let st = &mut stack.entries;
        st.clear();
        let mut cur = self.wide.root;
        loop {
            if cur != EMPTY {
                if cur & LEAF != 0 {
                    best = visit.leaf(cur & !LEAF, best);
                } else {
                    let node = &self.wide.nodes[cur as usize];
                    let (mask, tn) = node_entry(node, ray, best);
                    if mask != 0 {
                        cur = push_nearest_last(node, mask, &tn, st);
                        continue;
                    }
                }
            }
            // Pop the next entry that can still hold a closer hit.
            loop {
                let Some((next, t)) = st.pop() else { return best };
                if t < best {
                    cur = next;
                    break;
                }
            }
        }
    }

    /// Whether anything is hit along `ray` below `t_max`: like [`Bvh::closest`] but stops at the first leaf
    /// that reports a hit (its returned distance below `t_max`).
    #[inline(always)]
    pub fn any<V: Visit>(&self, ray: &RayPrep, t_max: f32, stack: &mut Stack, visit: &mut V) -> bool {
        let st = &mut stack.entries;
        st.clear();
        let mut cur = self.wide.root;
        loop {
            if cur != EMPTY {
                if cur & LEAF != 0 {
                    if visit.leaf(cur & !LEAF, t_max) < t_max {
                        return true;
                    }
                } else {
                    let node = &self.wide.nodes[cur as usize];
                    let (mask, tn) = node_entry(node, ray, t_max);
                    if mask != 0 {
                        cur = push_nearest_last(node, mask, &tn, st);
                        continue;
                    }
                }
            }
            let Some((next, _)) = st.pop() else { return false };
            cur = next;
        }
    }
}

/// Entry distances of `ray` into the node's eight boxes and the mask of lanes it enters before `t_max`.
#[inline(always)]
pub fn node_entry(node: &Node, ray: &RayPrep, t_max: f32) -> (u32, [f32; WIDTH]) {
    let [ox, oy, oz] = ray.o;
    let [ix, iy, iz] = ray.inv;
    let [nx, ny, nz] = ray.near.map(usize::from);
    let b = &node.bounds;
    let (near_x, near_y, near_z) = (&b[nx], &b[ny], &b[nz]);
    let (far_x, far_y, far_z) = (&b[(nx + 3) % 6], &b[(ny + 3) % 6], &b[(nz + 3) % 6]);
    let mut t0 = [0f32; WIDTH];
    let mut hit = [false; WIDTH];
    for l in 0..WIDTH {
        let a = max(max((near_x[l] - ox) * ix, (near_y[l] - oy) * iy), max((near_z[l] - oz) * iz, 0.0));
        let f = min(min((far_x[l] - ox) * ix, (far_y[l] - oy) * iy), (far_z[l] - oz) * iz) * FAR_SCALE;
        t0[l] = a;
        hit[l] = a <= min(f, t_max);
    }
    let mut mask = 0u32;
    for (l, &h) in hit.iter().enumerate() {
        mask |= u32::from(h) << l;
    }
    (mask, t0)
}

/// Whether `ray` enters the box `b` before `t_max` (the same slab test as [`node_entry`], for one box).
#[inline(always)]
pub fn box_entry(b: &Box3, ray: &RayPrep, t_max: f32) -> bool {
    let mut t0 = 0f32;
    let mut t1 = t_max;
    for a in 0..3 {
        let (lo, hi) = (b.lo[a], b.hi[a]);
        let (n, f) = if usize::from(ray.near[a]) == a { (lo, hi) } else { (hi, lo) };
        t0 = max(t0, (n - ray.o[a]) * ray.inv[a]);
        t1 = min(t1, (f - ray.o[a]) * ray.inv[a] * FAR_SCALE);
    }
    t0 <= t1
}

/// Pushes the hit children of `node` (lanes in `mask`, at least one) on `stack` farthest first, except the
/// nearest, which is returned to be visited next; or, when the entry on top of the stack (an ancestor's
/// sibling) is nearer than every child, pushes them all under it and returns that entry instead. (A huge
/// primitive near the root, a water plane over a terrain, is then hit before the walk goes down the terrain
/// below it.)
#[inline(always)]
fn push_nearest_last(node: &Node, mask: u32, tn: &[f32; WIDTH], stack: &mut Vec<(u32, f32)>) -> u32 {
    if mask & (mask - 1) == 0 {
        let l = mask.trailing_zeros() as usize;
        return match stack.last_mut() {
            // The entry on top of the stack (an ancestor's sibling) is nearer than the only child: visit it first.
            Some(top) if top.1 < tn[l] => std::mem::replace(top, (node.child[l], tn[l])).0,
            _ => node.child[l],
        };
    }
    // Sort the hits by distance, descending, into a small array (insertion sort of at most eight).
    let mut hits = [(EMPTY, 0f32); WIDTH];
    let mut n = 0usize;
    let mut m = mask;
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        let e = (node.child[l], tn[l]);
        let mut j = n;
        while j > 0 && hits[j - 1].1 < e.1 {
            hits[j] = hits[j - 1];
            j -= 1;
        }
        hits[j] = e;
        n += 1;
    }
    match stack.pop() {
        // Every child is farther than the entry on top of the stack (an ancestor's sibling): visit that first.
        Some(top) if top.1 < hits[n - 1].1 => {
            stack.extend_from_slice(&hits[..n]);
            top.0
        }
        top => {
            stack.extend(top);
            stack.extend_from_slice(&hits[..n - 1]);
            hits[n - 1].0
        }
    }
}

/// `max` without NaN handling, so it compiles to one SIMD lane operation.
#[inline(always)]
pub(crate) fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `min` without NaN handling, so it compiles to one SIMD lane operation.
#[inline(always)]
pub(crate) fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The leaf visitor of the tests: primitive `p` is hit at `t(p, ray)` (exactly, by the test's own formula).
    struct Prims<'a, F> {
        bvh: &'a Bvh,
        t: F,
        ray: RayPrep,
        hit: Option<u32>,
        leaves_visited: usize,
    }

    impl<'a, F: Fn(u32, &RayPrep) -> Option<f32>> Prims<'a, F> {
        fn new(bvh: &'a Bvh, t: F, ray: RayPrep) -> Self {
            Self { bvh, t, ray, hit: None, leaves_visited: 0 }
        }
    }

    impl<F: Fn(u32, &RayPrep) -> Option<f32>> Visit for Prims<'_, F> {
        fn leaf(&mut self, leaf: u32, mut best: f32) -> f32 {
            self.leaves_visited += 1;
            let lf = self.bvh.leaves()[leaf as usize];
            for k in lf.start..lf.start + lf.count {
                let p = self.bvh.order()[k as usize];
                if let Some(t) = (self.t)(p, &self.ray).filter(|&t| t < best) {
                    best = t;
                    self.hit = Some(p);
                }
            }
            best
        }
    }

    fn sphere_t(c: [f32; 3], r: f32, ray: &RayPrep) -> Option<f32> {
        let oc = [ray.o[0] - c[0], ray.o[1] - c[1], ray.o[2] - c[2]];
        let b = oc[0] * ray.d[0] + oc[1] * ray.d[1] + oc[2] * ray.d[2];
        let cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r;
        let disc = b * b - cc;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        (t > 0.0).then_some(t)
    }

    #[test]
    fn closest_and_any_match_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let spheres: Vec<([f32; 3], f32)> = (0..3000)
            .map(|_| {
                let c = [rng.random_range(-60.0..60.0), rng.random_range(-60.0..60.0), rng.random_range(-10.0..10.0)];
                (c, rng.random_range(0.2..2.0))
            })
            .collect();
        let boxes: Vec<Box3> = spheres
            .iter()
            .map(|&(c, r)| Box3 { lo: [c[0] - r, c[1] - r, c[2] - r], hi: [c[0] + r, c[1] + r, c[2] + r] })
            .collect();
        let bvh = Bvh::new(&boxes, 4);
        let sphere_at = |p: u32, ray: &RayPrep| sphere_t(spheres[p as usize].0, spheres[p as usize].1, ray);
        let mut stack = Stack::default();
        let mut hits = 0;
        let mut visited = 0;
        for _ in 0..3000 {
            let o = [rng.random_range(-70.0..70.0), rng.random_range(-70.0..70.0), rng.random_range(-15.0..15.0)];
            let mut d: [f32; 3] =
                [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-0.3..0.3)];
            if rng.random_range(0..4) == 0 {
                d = [d[0], 0.0, 0.0]; // axis-parallel rays exercise the clamped reciprocal
            }
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if n < 1e-3 {
                continue;
            }
            let d = [d[0] / n, d[1] / n, d[2] / n];
            let ray = RayPrep::new(o, d);
            let brute = spheres
                .iter()
                .enumerate()
                .filter_map(|(i, &(c, r))| sphere_t(c, r, &ray).filter(|&t| t < 100.0).map(|t| (t, i as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let mut v = Prims::new(&bvh, sphere_at, ray);
            let best = bvh.closest(&ray, 100.0, &mut stack, &mut v);
            visited += v.leaves_visited;
            match brute {
                Some((t, i)) => {
                    hits += 1;
                    assert_eq!(v.hit, Some(i));
                    assert_eq!(best, t);
                }
                None => assert!(v.hit.is_none() && best == 100.0),
            }
            let mut v = Prims::new(&bvh, sphere_at, ray);
            assert_eq!(bvh.any(&ray, 100.0, &mut stack, &mut v), brute.is_some());
        }
        assert!(hits > 500, "{hits}");
        // The tree culls: far fewer leaves than primitives are visited per ray.
        assert!(visited < 3000 * 40, "{visited} leaves visited");
    }

    /// Where a ray from outside box `b` enters it.
    fn box_t(b: &Box3, ray: &RayPrep) -> Option<f32> {
        let (mut t0, mut t1) = (0f32, f32::INFINITY);
        for a in 0..3 {
            let (lo, hi) = ((b.lo[a] - ray.o[a]) / ray.d[a], (b.hi[a] - ray.o[a]) / ray.d[a]);
            t0 = t0.max(lo.min(hi));
            t1 = t1.min(lo.max(hi));
        }
        (t0 <= t1 && t0 > 0.0).then_some(t0)
    }

    /// A flat sheet over the whole map (a water plane) above a grid of small boxes (a seabed) with a few tall
    /// ones (islands): rays going down from just above the sheet, away from the islands, hit it first. The walk visits the sheet's leaf (near the root) before it goes
    /// down the field's subtree that the ray enters first, so it needs about one leaf per ray, and the hits are
    /// those of brute force.
    #[test]
    fn a_near_entry_high_in_the_tree_is_visited_before_a_far_subtree() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut boxes: Vec<Box3> = (0..10_000)
            .map(|i| {
                let (x, y, z) = ((i % 100) as f32 * 10.0 - 500.0, (i / 100) as f32 * 10.0 - 500.0, -20.0);
                Box3 {
                    lo: [x, y, z - rng.random_range(1.0..3.0)],
                    hi: [x + 10.0, y + 10.0, z + rng.random_range(0.0..3.0)],
                }
            })
            .collect();
        // Islands: a few tall boxes, so the field's upper nodes reach above the rays' origins.
        let islands: Vec<Box3> = (0..24)
            .map(|_| {
                let (x, y) = (rng.random_range(-500.0..500.0), rng.random_range(-500.0..500.0));
                Box3 { lo: [x - 20.0, y - 20.0, -20.0], hi: [x + 20.0, y + 20.0, 40.0] }
            })
            .collect();
        boxes.extend_from_slice(&islands);
        boxes.push(Box3 { lo: [-510.0, -510.0, -0.01], hi: [510.0, 510.0, 0.0] });
        let sheet = (boxes.len() - 1) as u32;
        let bvh = Bvh::new(&boxes, 4);
        let mut stack = Stack::default();
        let (mut leaves, mut rays) = (0, 0);
        for _ in 0..2000 {
            let o = [rng.random_range(-400.0..400.0), rng.random_range(-400.0..400.0), 2.5];
            if islands.iter().any(|b| (0..2).all(|a| b.lo[a] - 10.0 < o[a] && o[a] < b.hi[a] + 10.0)) {
                continue; // over an island (or close to one)
            }
            let (az, el) = (rng.random_range(0.0..std::f32::consts::TAU), rng.random_range(0.3f32..1.5));
            let ray = RayPrep::new(o, [az.cos() * el.cos(), az.sin() * el.cos(), -el.sin()]);
            let brute = (0..boxes.len())
                .filter_map(|i| box_t(&boxes[i], &ray).map(|t| (t, i as u32)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let mut v = Prims::new(&bvh, |p, ray: &RayPrep| box_t(&boxes[p as usize], ray), ray);
            let best = bvh.closest(&ray, 1e4, &mut stack, &mut v);
            assert_eq!(v.hit, Some(sheet));
            assert_eq!(brute, Some((best, sheet)));
            leaves += v.leaves_visited;
            rays += 1;
        }
        assert!(rays > 1000, "{rays}");
        assert!(leaves < rays * 5 / 4, "{leaves} leaves visited for {rays} rays");
    }

    #[test]
    fn tiny_trees_and_empty_trees() {
        let empty = Bvh::new(&[], 4);
        assert!(empty.is_empty());
        let one = Bvh::new(&[Box3 { lo: [-1.0; 3], hi: [1.0; 3] }], 4);
        assert_eq!(one.leaves().len(), 1);
        assert!(one.nodes().is_empty(), "a single leaf needs no node");
    }
}
