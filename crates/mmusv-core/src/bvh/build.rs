//! Binned SAH construction of a binary BVH over primitive boxes.
//!
//! Top-down: a node's primitives are binned by centroid along each axis ([`BINS`] bins); the split with the
//! lowest surface-area-heuristic cost is taken and the primitives are partitioned in place. A node with at
//! most `max_leaf` primitives becomes a leaf. Costs count SIMD blocks of [`super::BLOCK`] primitives rather than
//! primitives (a leaf of four triangles costs one 4-wide test), as Embree does. One more candidate is tried
//! at every node: primitives much larger than the node's typical one (a water plane's two triangles over a
//! terrain) against the rest, which centroid binning cannot separate; so huge triangles end up near the root
//! instead of inflating every box on their path. Nodes whose centroids all coincide are split at the median.
//!
//! Large nodes are built in parallel (`rayon::join`); each parallel subtree is built into its own vector and
//! appended in a fixed order, so the tree is the same whatever the thread count.

use rayon::join;

/// Centroid bins per axis.
pub const BINS: usize = 16;
/// A primitive whose box has more than this share of its node's surface counts as large.
const LARGE_FRACTION: f32 = 0.1;
/// Primitives below which a subtree is built on one thread.
const PARALLEL_MIN: usize = 32 * 1024;

/// An axis-aligned box as `[min, max]` corners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Box3 {
    /// Lower corner.
    pub lo: [f32; 3],
    /// Upper corner.
    pub hi: [f32; 3],
}

impl Default for Box3 {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Box3 {
    /// The empty box (grows to anything).
    pub const EMPTY: Self = Self { lo: [f32::INFINITY; 3], hi: [f32::NEG_INFINITY; 3] };

    /// Grows `self` to contain `o`.
    #[inline(always)]
    pub fn grow(&mut self, o: &Box3) {
        for a in 0..3 {
            self.lo[a] = if o.lo[a] < self.lo[a] { o.lo[a] } else { self.lo[a] };
            self.hi[a] = if o.hi[a] > self.hi[a] { o.hi[a] } else { self.hi[a] };
        }
    }

    /// Grows `self` to contain the point `p`.
    #[inline(always)]
    pub fn grow_point(&mut self, p: [f32; 3]) {
        for a in 0..3 {
            self.lo[a] = if p[a] < self.lo[a] { p[a] } else { self.lo[a] };
            self.hi[a] = if p[a] > self.hi[a] { p[a] } else { self.hi[a] };
        }
    }

    /// Half the surface area (0 for an empty box).
    #[inline(always)]
    pub fn half_area(&self) -> f32 {
        let e = [self.hi[0] - self.lo[0], self.hi[1] - self.lo[1], self.hi[2] - self.lo[2]];
        if e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0 {
            return 0.0;
        }
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// Centre point.
    #[inline(always)]
    pub fn center(&self) -> [f32; 3] {
        [(self.lo[0] + self.hi[0]) * 0.5, (self.lo[1] + self.hi[1]) * 0.5, (self.lo[2] + self.hi[2]) * 0.5]
    }
}

/// A node of the binary tree: a box and either two children or a leaf range of `order`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinNode {
    /// Bounds of everything below.
    pub bounds: Box3,
    /// `Some((left, right))` node indices for an inner node.
    pub children: Option<(u32, u32)>,
    /// Leaf range `start..start + count` of `order` (count 0 for inner nodes).
    pub start: u32,
    /// Number of primitives below this node.
    pub count: u32,
}

/// A binary BVH: node 0 is the root; `order` lists primitive indices, each leaf owning a contiguous range.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BinTree {
    /// Nodes in depth-first order (parents before children).
    pub nodes: Vec<BinNode>,
    /// Leaf order → primitive index.
    pub order: Vec<u32>,
}

/// Builds a binary SAH tree over `boxes` (one per primitive) with leaves of at most `max_leaf` primitives.
/// Returns an empty tree for no boxes. Boxes must be finite (callers validate their geometry).
pub fn build(boxes: &[Box3], max_leaf: usize) -> BinTree {
    let n = boxes.len();
    if n == 0 {
        return BinTree::default();
    }
    let centroids: Vec<[f32; 3]> = boxes.iter().map(Box3::center).collect();
    let areas: Vec<f32> = boxes.iter().map(Box3::half_area).collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let ctx = Ctx { boxes, centroids: &centroids, areas: &areas, max_leaf: max_leaf.max(1) };
    let root = ctx.extent(&order);
    let nodes = ctx.subtree(&mut order, 0, root);
    BinTree { nodes, order }
}

struct Ctx<'a> {
    boxes: &'a [Box3],
    centroids: &'a [[f32; 3]],
    areas: &'a [f32],
    max_leaf: usize,
}

/// A node's box and the box of its primitives' centroids.
#[derive(Debug, Clone, Copy)]
struct Extent {
    bounds: Box3,
    centroids: Box3,
}

impl Extent {
    const EMPTY: Self = Self { bounds: Box3::EMPTY, centroids: Box3::EMPTY };
}

/// Cost of intersecting `n` primitives in blocks of [`super::BLOCK`].
#[inline(always)]
fn blocks(n: usize) -> f32 {
    n.div_ceil(super::BLOCK) as f32
}

impl Ctx<'_> {
    fn extent(&self, idx: &[u32]) -> Extent {
        let mut e = Extent::EMPTY;
        for &i in idx {
            e.bounds.grow(&self.boxes[i as usize]);
            e.centroids.grow_point(self.centroids[i as usize]);
        }
        e
    }

    /// Builds the subtree over `idx` (which starts at `base` in the global order) into a new vector.
    fn subtree(&self, idx: &mut [u32], base: u32, ext: Extent) -> Vec<BinNode> {
        if idx.len() < PARALLEL_MIN {
            let mut out = Vec::with_capacity(2 * idx.len().div_ceil(self.max_leaf));
            self.sequential(idx, base, ext, &mut out);
            return out;
        }
        let (mid, le, re) = self.split(idx, &ext);
        let (left, right) = idx.split_at_mut(mid);
        let (l, r) = join(|| self.subtree(left, base, le), || self.subtree(right, base + mid as u32, re));
        let mut out = Vec::with_capacity(1 + l.len() + r.len());
        let lo = 1u32;
        let ro = 1 + l.len() as u32;
        out.push(BinNode { bounds: ext.bounds, children: Some((lo, ro)), start: 0, count: idx.len() as u32 });
        out.extend(l.into_iter().map(|nd| shifted(nd, lo)));
        out.extend(r.into_iter().map(|nd| shifted(nd, ro)));
        out
    }

    fn sequential(&self, idx: &mut [u32], base: u32, ext: Extent, out: &mut Vec<BinNode>) -> u32 {
        let me = out.len() as u32;
        if idx.len() <= self.max_leaf {
            out.push(BinNode { bounds: ext.bounds, children: None, start: base, count: idx.len() as u32 });
            return me;
        }
        let (mid, le, re) = self.split(idx, &ext);
        out.push(BinNode { bounds: ext.bounds, children: None, start: 0, count: idx.len() as u32 });
        let (left, right) = idx.split_at_mut(mid);
        let l = self.sequential(left, base, le, out);
        let r = self.sequential(right, base + mid as u32, re, out);
        out[me as usize].children = Some((l, r));
        me
    }

    /// Chooses the SAH split of `idx` (more than one primitive, extent `ext`), partitions it in place and
    /// returns the size of the left part (always in `1..len`) and the extents of both parts.
    fn split(&self, idx: &mut [u32], ext: &Extent) -> (usize, Extent, Extent) {
        let cb = &ext.centroids;
        let n = idx.len();
        let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins in the left part)
        let mut scale = [0f32; 3];
        for axis in 0..3 {
            let extent = cb.hi[axis] - cb.lo[axis];
            scale[axis] = if extent > 0.0 { BINS as f32 * (1.0 - 1e-6) / extent } else { 0.0 };
        }
        // One pass bins every primitive on all three axes.
        let mut bin_box = [[Box3::EMPTY; BINS]; 3];
        let mut bin_n = [[0usize; BINS]; 3];
        let mut largest = 0f32;
        for &i in idx.iter() {
            let c = self.centroids[i as usize];
            let bx = &self.boxes[i as usize];
            let area = self.areas[i as usize];
            largest = if area > largest { area } else { largest };
            for axis in 0..3 {
                let b = bin_of(c[axis], cb.lo[axis], scale[axis]);
                bin_box[axis][b].grow(bx);
                bin_n[axis][b] += 1;
            }
        }
        for axis in 0..3 {
            if scale[axis] == 0.0 {
                continue;
            }
            let (bin_box, bin_n) = (&bin_box[axis], &bin_n[axis]);
            // Right-to-left sweep of areas and counts.
            let mut right_cost = [0f32; BINS];
            let mut acc = Box3::EMPTY;
            let mut cnt = 0usize;
            for b in (1..BINS).rev() {
                acc.grow(&bin_box[b]);
                cnt += bin_n[b];
                right_cost[b] = acc.half_area() * blocks(cnt);
            }
            let mut acc = Box3::EMPTY;
            let mut cnt = 0usize;
            for b in 0..BINS - 1 {
                acc.grow(&bin_box[b]);
                cnt += bin_n[b];
                if cnt == 0 || cnt == n {
                    continue;
                }
                let cost = acc.half_area() * blocks(cnt) + right_cost[b + 1];
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, b + 1));
                }
            }
        }
        // Candidate: the large primitives against the rest (only when there is a large one).
        let threshold = LARGE_FRACTION * ext.bounds.half_area();
        if largest > threshold {
            let (mut large, mut rest, mut n_large) = (Box3::EMPTY, Box3::EMPTY, 0usize);
            for &i in idx.iter() {
                if self.areas[i as usize] > threshold {
                    large.grow(&self.boxes[i as usize]);
                    n_large += 1;
                } else {
                    rest.grow(&self.boxes[i as usize]);
                }
            }
            if n_large < n {
                let cost = large.half_area() * blocks(n_large) + rest.half_area() * blocks(n - n_large);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    let areas = self.areas;
                    return self.partition(idx, |i| areas[i as usize] > threshold);
                }
            }
        }
        if let Some((_, axis, left_bins)) = best {
            let (lo, sc, c) = (cb.lo[axis], scale[axis], self.centroids);
            let (mid, le, re) = self.partition(idx, |i| bin_of(c[i as usize][axis], lo, sc) < left_bins);
            if mid > 0 && mid < n {
                return (mid, le, re);
            }
        }
        // Coincident centroids: split at the median position.
        let mid = n / 2;
        (mid, self.extent(&idx[..mid]), self.extent(&idx[mid..]))
    }

    /// Moves the primitives satisfying `left` to the front (deterministically) and returns how many there are
    /// with the extents of both parts.
    fn partition(&self, idx: &mut [u32], left: impl Fn(u32) -> bool) -> (usize, Extent, Extent) {
        let (mut le, mut re) = (Extent::EMPTY, Extent::EMPTY);
        let mut i = 0usize;
        let mut j = idx.len();
        while i < j {
            let p = idx[i];
            let e = if left(p) {
                i += 1;
                &mut le
            } else {
                j -= 1;
                idx.swap(i, j);
                &mut re
            };
            e.bounds.grow(&self.boxes[p as usize]);
            e.centroids.grow_point(self.centroids[p as usize]);
        }
        (i, le, re)
    }
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

fn shifted(mut nd: BinNode, by: u32) -> BinNode {
    if let Some((l, r)) = nd.children {
        nd.children = Some((l + by, r + by));
    }
    nd
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_boxes(n: usize, seed: u64) -> Vec<Box3> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let c: [f32; 3] =
                    [rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), rng.random_range(-5.0..5.0)];
                let h: [f32; 3] = [rng.random_range(0.0..2.0), rng.random_range(0.0..2.0), rng.random_range(0.0..2.0)];
                Box3 { lo: [c[0] - h[0], c[1] - h[1], c[2] - h[2]], hi: [c[0] + h[0], c[1] + h[1], c[2] + h[2]] }
            })
            .collect()
    }

    /// Every primitive appears in exactly one leaf, leaves are small, child boxes lie inside parents and a leaf's
    /// box holds its primitives.
    fn check(tree: &BinTree, boxes: &[Box3], max_leaf: usize) {
        let mut seen = vec![0u32; boxes.len()];
        for nd in &tree.nodes {
            match nd.children {
                Some((l, r)) => {
                    for c in [l, r] {
                        let cb = tree.nodes[c as usize].bounds;
                        for a in 0..3 {
                            assert!(cb.lo[a] >= nd.bounds.lo[a] && cb.hi[a] <= nd.bounds.hi[a]);
                        }
                    }
                    assert_eq!(nd.count, tree.nodes[l as usize].count + tree.nodes[r as usize].count);
                }
                None => {
                    assert!(nd.count as usize <= max_leaf && nd.count >= 1);
                    for k in nd.start..nd.start + nd.count {
                        let p = tree.order[k as usize] as usize;
                        seen[p] += 1;
                        for a in 0..3 {
                            assert!(boxes[p].lo[a] >= nd.bounds.lo[a] && boxes[p].hi[a] <= nd.bounds.hi[a]);
                        }
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "every primitive in exactly one leaf");
        assert_eq!(tree.nodes[0].count as usize, boxes.len());
    }

    #[test]
    fn small_and_large_trees_are_consistent() {
        for (n, seed) in [(1, 1), (2, 2), (5, 3), (100, 4), (70_000, 5)] {
            let boxes = random_boxes(n, seed);
            let t = build(&boxes, 4);
            check(&t, &boxes, 4);
        }
    }

    #[test]
    fn coincident_centroids_still_split() {
        let b = Box3 { lo: [0.0; 3], hi: [1.0; 3] };
        let boxes = vec![b; 37];
        let t = build(&boxes, 4);
        check(&t, &boxes, 4);
    }

    #[test]
    fn build_is_deterministic_across_thread_counts() {
        let boxes = random_boxes(100_000, 9);
        let a = build(&boxes, 4);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build();
        let b = pool.map(|p| p.install(|| build(&boxes, 4))).unwrap_or_default();
        assert_eq!(a, b);
    }

    #[test]
    fn sah_separates_a_huge_primitive_from_small_ones() {
        // Two plane-sized triangles' boxes over a field of small ones: SAH isolates the big pair near the root
        // instead of spreading them over the tree.
        let mut boxes = random_boxes(5_000, 3);
        boxes.push(Box3 { lo: [-1000.0, -1000.0, 0.0], hi: [1000.0, 1000.0, 0.0] });
        boxes.push(Box3 { lo: [-1000.0, -1000.0, 0.0], hi: [1000.0, 1000.0, 0.0] });
        let t = build(&boxes, 4);
        check(&t, &boxes, 4);
        let huge_area = boxes[5_000].half_area();
        let big_nodes = t.nodes.iter().filter(|nd| nd.bounds.half_area() >= huge_area).count();
        assert!(big_nodes <= 4, "{big_nodes} nodes as large as the plane");
    }
}
