//! A 4-wide BVH laid out for fast single-ray traversal, flattened from a tree that parry builds.
//!
//! parry's [`parry3d::partitioning::Bvh`] (binned SAH build, one primitive per leaf) does the building. Its
//! nodes are walked once with `traverse_indexed` to recover the binary tree, which is then collapsed into
//! 4-wide nodes (structure-of-arrays boxes, four slab tests per step that the compiler vectorises) with up to
//! [`LEAF_SIZE`] primitives per leaf stored contiguously. Traversal is ordered front to back with early
//! termination, which is what makes it several times faster than the generic best-first query on the binary
//! tree. The recovered tree is checked (every primitive exactly once, child boxes inside parent boxes); if the
//! check fails, [`Bvh4::from_parry`] returns `None` and callers keep using parry's own query.

use crate::packet::Packet;
use parry3d::bounding_volume::Aabb;
use parry3d::math::Vec3;
use parry3d::partitioning::{Bvh, TraversalAction};

/// Most primitives in one leaf.
pub const LEAF_SIZE: usize = 4;
const LEAF_BIT: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

/// One 4-wide node: boxes of its four children as `[min_x, min_y, min_z, max_x, max_y, max_z]` lanes.
#[derive(Debug, Clone, Copy)]
struct Node4 {
    bounds: [[f32; 4]; 6],
    /// Child reference: node index, or `LEAF_BIT | start << 3 | count` for a leaf, or `EMPTY`.
    child: [u32; 4],
}

/// A flattened 4-wide BVH over primitives `0..n`. Primitives are visited in [`Bvh4::order`] order.
#[derive(Debug, Clone, Default)]
pub struct Bvh4 {
    nodes: Vec<Node4>,
    /// Root reference (as in `Node4::child`).
    root: u32,
    /// Leaf order → original primitive index.
    order: Vec<u32>,
}

#[derive(Debug, Clone, Copy)]
struct BNode {
    aabb: Aabb,
    leaf: Option<u32>,
    children: Option<(usize, usize)>,
    count: usize,
}

/// Per-ray constants of the slab test.
#[derive(Debug, Clone, Copy)]
pub struct RayInv {
    origin: [f32; 3],
    inv: [f32; 3],
    near: [usize; 3],
}

impl RayInv {
    /// Precomputes the reciprocal direction and the near planes of a ray.
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let f = |d: f32| if d.abs() < 1e-20 { 1e20f32.copysign(d) } else { 1.0 / d };
        let inv = [f(dir.x), f(dir.y), f(dir.z)];
        let near =
            [if inv[0] < 0.0 { 3 } else { 0 }, if inv[1] < 0.0 { 4 } else { 1 }, if inv[2] < 0.0 { 5 } else { 2 }];
        Self { origin: origin.to_array(), inv, near }
    }
}

impl Bvh4 {
    /// Flattens `tree`, a parry BVH over primitives `0..n` (leaf data = primitive index).
    /// Returns `None` if the recovered tree does not pass its consistency check.
    pub fn from_parry(tree: &Bvh, n: usize) -> Option<Self> {
        Self::from_parry_with_cost(tree, n, |_| 0.0)
    }

    /// Like [`Bvh4::from_parry`], and within every leaf the primitives are ordered by increasing `cost`, so
    /// cheap tests run first and shorten the ray for expensive ones (for a top level: a 2-triangle water
    /// plane before a 500k-triangle terrain sharing its leaf).
    pub fn from_parry_with_cost(tree: &Bvh, n: usize, cost: impl Fn(u32) -> f32) -> Option<Self> {
        if n == 0 {
            return None;
        }
        let mut b: Vec<BNode> = vec![BNode { aabb: tree.root_aabb(), leaf: None, children: None, count: 0 }];
        let mut parent = 0usize;
        let mut stack: Vec<usize> = Vec::new();
        let mut left = usize::MAX;
        tree.traverse_indexed(None, |node, idx| {
            let (_, is_right) = idx.decompose();
            let id = b.len();
            b.push(BNode {
                aabb: node.aabb(),
                leaf: if node.is_leaf() { node.leaf_data() } else { None },
                children: None,
                count: 0,
            });
            if !is_right {
                left = id;
            } else {
                // A pair is complete: it is the child pair of `parent` (mirrors parry's own loop).
                b[parent].children = Some((left, id));
                match (b[left].leaf.is_none(), b[id].leaf.is_none()) {
                    (true, true) => {
                        parent = left;
                        stack.push(id);
                    }
                    (true, false) => parent = left,
                    (false, true) => parent = id,
                    (false, false) => {
                        if let Some(p) = stack.pop() {
                            parent = p;
                        }
                    }
                }
            }
            TraversalAction::Continue
        });
        // Single-leaf tree: parry visits only the root's left node.
        if b.len() == 2 && b[0].children.is_none() {
            b.swap(0, 1);
            b.truncate(1);
        }
        // Counts, bottom-up (children always come after parents in `b`).
        for i in (0..b.len()).rev() {
            b[i].count = match (b[i].leaf, b[i].children) {
                (Some(_), _) => 1,
                (None, Some((l, r))) => b[l].count + b[r].count,
                (None, None) => return None,
            };
        }
        if b[0].count != n {
            return None;
        }
        let mut out = Bvh4 { nodes: Vec::new(), root: EMPTY, order: Vec::with_capacity(n) };
        out.root = out.flatten(&b, 0, &cost)?;
        let mut seen = vec![false; n];
        for &p in &out.order {
            let slot = seen.get_mut(p as usize)?;
            if *slot {
                return None;
            }
            *slot = true;
        }
        (out.order.len() == n).then_some(out)
    }

    fn collect_leaves(&mut self, b: &[BNode], i: usize) -> Option<()> {
        match (b[i].leaf, b[i].children) {
            (Some(p), _) => self.order.push(p),
            (None, Some((l, r))) => {
                self.collect_leaves(b, l)?;
                self.collect_leaves(b, r)?;
            }
            (None, None) => return None,
        }
        Some(())
    }

    fn flatten(&mut self, b: &[BNode], i: usize, cost: &impl Fn(u32) -> f32) -> Option<u32> {
        if b[i].count <= LEAF_SIZE {
            let start = self.order.len();
            self.collect_leaves(b, i)?;
            self.order[start..].sort_by(|&x, &y| cost(x).total_cmp(&cost(y)).then(x.cmp(&y)));
            return Some(LEAF_BIT | ((start as u32) << 3) | b[i].count as u32);
        }
        // Pull grandchildren up until there are four children (largest surface area first).
        let mut kids: Vec<usize> = vec![i];
        while kids.len() < 4 {
            let pick = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| b[k].children.is_some() && (b[k].count > LEAF_SIZE || k == i))
                .max_by(|a, c| area(&b[*a.1].aabb).total_cmp(&area(&b[*c.1].aabb)))
                .map(|(pos, _)| pos);
            let Some(pos) = pick else { break };
            let (l, r) = b[kids[pos]].children?;
            kids.swap_remove(pos);
            kids.push(l);
            kids.push(r);
        }
        let me = self.nodes.len();
        self.nodes.push(Node4 {
            bounds: [
                [f32::INFINITY; 4],
                [f32::INFINITY; 4],
                [f32::INFINITY; 4],
                [f32::NEG_INFINITY; 4],
                [f32::NEG_INFINITY; 4],
                [f32::NEG_INFINITY; 4],
            ],
            child: [EMPTY; 4],
        });
        for (slot, &k) in kids.iter().enumerate() {
            let child = self.flatten(b, k, cost)?;
            let a = b[k].aabb;
            let node = &mut self.nodes[me];
            node.child[slot] = child;
            for (axis, (lo, hi)) in
                [(a.mins.x, a.maxs.x), (a.mins.y, a.maxs.y), (a.mins.z, a.maxs.z)].into_iter().enumerate()
            {
                node.bounds[axis][slot] = lo;
                node.bounds[axis + 3][slot] = hi;
            }
        }
        Some(me as u32)
    }

    /// Leaf order → original primitive index.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Closest hit along a ray. `leaf(k, best)` tests the primitive at leaf-order position `k` and returns its
    /// hit parameter if it is below `best`. Returns `(k, t)` of the closest hit with `t < t_max`.
    ///
    /// `stack` is scratch space (cleared here); reusing one per thread avoids an allocation per ray.
    #[inline]
    pub fn closest(
        &self,
        ray: &RayInv,
        t_max: f32,
        stack: &mut Vec<(u32, f32)>,
        mut leaf: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        let mut best = t_max;
        let mut best_k = u32::MAX;
        stack.clear();
        let mut cur = self.root;
        loop {
            if cur != EMPTY {
                if cur & LEAF_BIT != 0 {
                    let start = (cur & !LEAF_BIT) >> 3;
                    let count = cur & 7;
                    for k in start..start + count {
                        if let Some(t) = leaf(k, best) {
                            if t < best {
                                best = t;
                                best_k = k;
                            }
                        }
                    }
                } else {
                    let node = &self.nodes[cur as usize];
                    let tn = slab4(node, ray, best);
                    // Gather hit children, nearest first.
                    let mut hits: [(u32, f32); 4] = [(EMPTY, f32::INFINITY); 4];
                    let mut nh = 0;
                    for (lane, &t) in tn.iter().enumerate() {
                        if t < f32::INFINITY {
                            insert_nearest_first(&mut hits, &mut nh, (node.child[lane], t));
                        }
                    }
                    if nh > 0 {
                        stack.extend(hits[1..nh].iter().rev());
                        cur = hits[0].0;
                        continue;
                    }
                }
            }
            // Pop the next entry that can still hold a closer hit.
            loop {
                let Some(next) = stack.pop() else {
                    return (best_k != u32::MAX).then_some((best_k, best));
                };
                if next.1 < best {
                    cur = next.0;
                    break;
                }
            }
        }
    }
}

impl Bvh4 {
    /// Traces a packet: `leaf(k, packet)` tests the primitive at leaf-order position `k` against the packet and
    /// updates the rays it hits closer. Children are visited nearest first; a subtree is skipped once no ray of
    /// the packet can still hit it before its current best.
    #[inline]
    pub fn closest_packet(&self, p: &mut Packet, stack: &mut Vec<(u32, f32)>, mut leaf: impl FnMut(u32, &mut Packet)) {
        stack.clear();
        let mut cur = self.root;
        loop {
            if cur != EMPTY {
                if cur & LEAF_BIT != 0 {
                    let start = (cur & !LEAF_BIT) >> 3;
                    for k in start..start + (cur & 7) {
                        leaf(k, p);
                    }
                } else {
                    let node = &self.nodes[cur as usize];
                    let b = &node.bounds;
                    let mut hits: [(u32, f32); 4] = [(EMPTY, f32::INFINITY); 4];
                    let mut nh = 0;
                    for lane in 0..4 {
                        if node.child[lane] == EMPTY {
                            continue;
                        }
                        let t = p.entry([b[0][lane], b[1][lane], b[2][lane]], [b[3][lane], b[4][lane], b[5][lane]]);
                        if t < f32::INFINITY {
                            insert_nearest_first(&mut hits, &mut nh, (node.child[lane], t));
                        }
                    }
                    if nh > 0 {
                        stack.extend(hits[1..nh].iter().rev());
                        cur = hits[0].0;
                        continue;
                    }
                }
            }
            loop {
                let Some(next) = stack.pop() else { return };
                if next.1 < p.max_best() {
                    cur = next.0;
                    break;
                }
            }
        }
    }
}

/// Entry distance of the ray into each of the node's four boxes, `INFINITY` where missed or beyond `t_max`.
#[inline(always)]
fn slab4(node: &Node4, ray: &RayInv, t_max: f32) -> [f32; 4] {
    let b = &node.bounds;
    let [ox, oy, oz] = ray.origin;
    let [ix, iy, iz] = ray.inv;
    let [nx, ny, nz] = ray.near;
    let (near_x, near_y, near_z) = (&b[nx], &b[ny], &b[nz]);
    let (far_x, far_y, far_z) = (&b[(nx + 3) % 6], &b[(ny + 3) % 6], &b[(nz + 3) % 6]);
    let mut out = [f32::INFINITY; 4];
    for l in 0..4 {
        let t0 = fmax(fmax((near_x[l] - ox) * ix, (near_y[l] - oy) * iy), fmax((near_z[l] - oz) * iz, 0.0));
        let t1 = fmin(fmin((far_x[l] - ox) * ix, (far_y[l] - oy) * iy), fmin((far_z[l] - oz) * iz, t_max));
        out[l] = if t0 <= t1 { t0 } else { f32::INFINITY };
    }
    out
}

/// Inserts `entry` into the first `*len` slots of `hits`, kept sorted by entry distance (nearest first).
#[inline(always)]
fn insert_nearest_first(hits: &mut [(u32, f32); 4], len: &mut usize, entry: (u32, f32)) {
    let mut j = *len;
    while j > 0 && hits[j - 1].1 > entry.1 {
        hits[j] = hits[j - 1];
        j -= 1;
    }
    hits[j] = entry;
    *len += 1;
}

/// `max` without NaN handling, so it compiles to a single `maxps` lane (no NaN reaches here: see [`RayInv`]).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `min` without NaN handling, so it compiles to a single `minps` lane.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

fn area(a: &Aabb) -> f32 {
    let e = a.maxs - a.mins;
    if e.x < 0.0 {
        return 0.0;
    }
    e.x * e.y + e.y * e.z + e.z * e.x
}
