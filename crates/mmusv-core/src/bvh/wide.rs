//! Collapsing a binary tree into [`WIDTH`]-wide nodes in structure-of-arrays layout.
//!
//! Each wide node takes the place of a binary node and pulls up its descendants (largest surface area first)
//! until it has [`WIDTH`] children or only leaves left to open; leaves of the binary tree stay leaves.

use super::build::{BinTree, Box3};

/// Children per node.
pub const WIDTH: usize = 8;
/// Marks a leaf reference: `LEAF | leaf index`.
pub const LEAF: u32 = 1 << 31;
/// An unused child slot.
pub const EMPTY: u32 = u32::MAX;

/// One wide node: the boxes of its children as lanes, `bounds[plane][lane]` with planes `[min_x, min_y, min_z,
/// max_x, max_y, max_z]`, and their references. Unused lanes have an empty box (`min = +inf`, `max = -inf`)
/// that no ray enters, and the reference [`EMPTY`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// Box planes per lane.
    pub bounds: [[f32; WIDTH]; 6],
    /// Child references: a node index, `LEAF | leaf index`, or [`EMPTY`].
    pub child: [u32; WIDTH],
}

impl Node {
    const BLANK: Node = Node {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
    };
}

/// A leaf: the range `start..start + count` of the tree's primitive order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leaf {
    /// First position in the order.
    pub start: u32,
    /// Number of primitives.
    pub count: u32,
}

/// Wide nodes, leaves and the root reference of a collapsed tree.
#[derive(Debug, Clone, PartialEq)]
pub struct Wide {
    /// Nodes; children come after their parent.
    pub nodes: Vec<Node>,
    /// Leaves in depth-first order.
    pub leaves: Vec<Leaf>,
    /// Root reference (a node index, a leaf reference, or [`EMPTY`] for an empty tree).
    pub root: u32,
    /// Bounds of the whole tree.
    pub bounds: Box3,
}

impl Default for Wide {
    fn default() -> Self {
        Self { nodes: Vec::new(), leaves: Vec::new(), root: EMPTY, bounds: Box3::EMPTY }
    }
}

/// Collapses `tree` (see the module docs).
pub fn collapse(tree: &BinTree) -> Wide {
    let mut w = Wide::default();
    if tree.nodes.is_empty() {
        return w;
    }
    w.bounds = tree.nodes[0].bounds;
    w.root = flatten(tree, 0, &mut w);
    w
}

fn flatten(tree: &BinTree, i: u32, w: &mut Wide) -> u32 {
    let nd = &tree.nodes[i as usize];
    if nd.children.is_none() {
        w.leaves.push(Leaf { start: nd.start, count: nd.count });
        return LEAF | (w.leaves.len() as u32 - 1);
    }
    let mut kids: Vec<u32> = vec![i];
    while kids.len() < WIDTH {
        let pick = kids
            .iter()
            .enumerate()
            .filter(|(_, &k)| tree.nodes[k as usize].children.is_some())
            .max_by(|a, b| {
                let (x, y) =
                    (tree.nodes[*a.1 as usize].bounds.half_area(), tree.nodes[*b.1 as usize].bounds.half_area());
                x.total_cmp(&y).then(b.0.cmp(&a.0))
            })
            .map(|(pos, _)| pos);
        let Some(pos) = pick else { break };
        let Some((l, r)) = tree.nodes[kids[pos] as usize].children else { break };
        kids[pos] = l;
        kids.insert(pos + 1, r);
    }
    let me = w.nodes.len();
    w.nodes.push(Node::BLANK);
    for (lane, &k) in kids.iter().enumerate() {
        let child = flatten(tree, k, w);
        let b = tree.nodes[k as usize].bounds;
        let node = &mut w.nodes[me];
        node.child[lane] = child;
        for a in 0..3 {
            node.bounds[a][lane] = b.lo[a];
            node.bounds[a + 3][lane] = b.hi[a];
        }
    }
    me as u32
}
