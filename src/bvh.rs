//! Bounding volume hierarchy over all primitives (triangles and spheres):
//! built as a binary tree with a binned surface-area heuristic, then
//! collapsed into the 8-wide nodes that the CPU kernel traverses (one
//! 8-lane slab test per node; docs/bvh.md has the figures) and that
//! `cwbvh` compresses for the GPU.
//!
//! Node layout (`layout::BvhNode`, 256 bytes): the boxes of up to eight
//! children, one lane per child (`bounds[2a]` the minima along axis a,
//! `bounds[2a + 1]` the maxima), and one reference per child in `children`:
//! - an interior child: its node index (bit 31 clear);
//! - a leaf: `LEAF_BIT | (count − 1) << 28 | first`, the blocks
//!   `blocks[first .. first + count]` (`layout::PrimBlock`: four primitives
//!   each, triangles with their vertices), at most `MAX_LEAF` primitives;
//! - no child: `EMPTY_SLOT`, with an inverted box; bit i of `occupied` is
//!   set for the slots that hold a child, and traversal enters no other.
//!
//! Node 0 is the root. A wide node holds its binary node's children, or
//! their children where they are interior: two binary levels per wide level,
//! so the wide tree is at most `MAX_DEPTH` levels deep and the CPU
//! kernel's traversal fits its fixed stack of `STACK_SIZE` entries.

use glam::Vec3;
use rayon::prelude::*;

mod overlap;
mod sides;
mod validate;
mod winding;

pub use sides::Sides;
pub use validate::{Invalid, TreeStats};
pub(crate) use validate::{LeafSizes, SahCost, inside};
pub use winding::WindingTree;

use crate::layout::{
    BVH_WIDTH, BvhNode, LEAF_BIT, LEAF_FIRST_MASK, PrimBlock, Sphere, Triangle, leaf_range,
    leaf_ref,
};

/// Wide levels at most (root = 1): their 48 binary levels leave the SAH
/// 28 levels of slack over the median splits of 5 million primitives (20).
pub const MAX_DEPTH: usize = 24;
/// Binary levels at most: each wide level takes two.
const MAX_BINARY_DEPTH: usize = 2 * MAX_DEPTH;
/// The CPU kernel's traversal stack entries: a node visit pops
/// one entry and pushes at most `BVH_WIDTH`, so the stack holds at most
/// `BVH_WIDTH − 1` per level above plus the `BVH_WIDTH` of the deepest.
pub const STACK_SIZE: usize = (BVH_WIDTH - 1) * MAX_DEPTH + 1;
/// Most primitives a scene may hold: a leaf reference has 28 bits for its
/// first block, and `build` never makes more blocks than primitives
/// (`from_binary` checks the blocks of other trees).
pub const MAX_PRIMITIVES: usize = LEAF_FIRST_MASK as usize + 1;
const BINS: usize = 16;
/// Primitives per leaf at most (two blocks).
pub const MAX_LEAF: usize = 8;
/// SAH costs of a node visit and of a block's 4-lane test (measured on the
/// CPU: about the same).
const COST_TRAVERSAL: f32 = 1.0;
const COST_INTERSECT: f32 = 1.0;
/// Subtrees above this size are built in parallel.
const PARALLEL_THRESHOLD: usize = 4096;

#[derive(Clone, Debug)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// The leaves' primitives, four to a block, in leaf order.
    pub blocks: Vec<PrimBlock>,
    pub build_time: std::time::Duration,
    /// The winding tree, built on the first winding query
    /// (`winding_tree`): renders never pay for it.
    winding: std::sync::OnceLock<WindingTree>,
    /// The sides of its triangles' surface, built on the first inside
    /// test that asks (`sides`).
    sides: std::sync::OnceLock<Result<Sides, String>>,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    pub fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
}

/// A binary BVH before it is collapsed into wide nodes: what a builder
/// makes (ours, or obvhs's in the benches).
pub enum BinaryNode {
    /// At most `MAX_LEAF` primitives.
    Leaf { bounds: Aabb, prims: Vec<u32> },
    Interior {
        bounds: Aabb,
        children: Box<[BinaryNode; 2]>,
    },
}

impl BinaryNode {
    pub fn bounds(&self) -> Aabb {
        match self {
            BinaryNode::Leaf { bounds, .. } | BinaryNode::Interior { bounds, .. } => *bounds,
        }
    }
}

/// Per-primitive bounds and centroid.
struct Item {
    prim: u32,
    bounds: Aabb,
    centre: Vec3,
}

impl Default for Bvh {
    /// The BVH of an empty scene: a root with no children.
    fn default() -> Bvh {
        Bvh {
            nodes: vec![BvhNode::EMPTY],
            blocks: Vec::new(),
            build_time: std::time::Duration::ZERO,
            winding: std::sync::OnceLock::new(),
            sides: std::sync::OnceLock::new(),
        }
    }
}

impl Bvh {
    pub fn build(triangles: &[Triangle], spheres: &[Sphere]) -> Bvh {
        let start = web_time::Instant::now();
        let triangle_items = triangles.par_iter().enumerate().map(|(i, t)| {
            let mut b = Aabb::EMPTY;
            for v in [t.v0, t.v1, t.v2] {
                b.grow_point(Vec3::from(v));
            }
            (i as u32, b)
        });
        let offset = triangles.len() as u32;
        let sphere_items = spheres.par_iter().enumerate().map(|(i, s)| {
            let c = Vec3::from(s.center);
            let r = Vec3::splat(s.radius);
            (
                offset + i as u32,
                Aabb {
                    min: c - r,
                    max: c + r,
                },
            )
        });
        let items: Vec<Item> = triangle_items
            .chain(sphere_items)
            .map(|(prim, bounds)| Item {
                prim,
                bounds,
                centre: bounds.centre(),
            })
            .collect();
        let mut bvh = if items.is_empty() {
            Bvh::default()
        } else {
            Bvh::from_binary(build_node(items, 0), triangles)
        };
        bvh.build_time = start.elapsed();
        bvh
    }

    /// The wide tree of a binary one, whose primitive ids below
    /// `triangles.len()` are those triangles (their vertices go into the
    /// leaves' blocks). Its leaves must hold at most `MAX_LEAF` primitives,
    /// at most `MAX_PRIMITIVES` in all, and the wide
    /// tree must be at most `MAX_DEPTH` levels deep, so that it fits the
    /// traversal stack (a binary tree of at most `2 * MAX_DEPTH` levels, as
    /// `build` makes, always does); panics otherwise.
    pub fn from_binary(root: BinaryNode, triangles: &[Triangle]) -> Bvh {
        let mut bvh = Bvh::default();
        bvh.flatten(root, 0, triangles);
        // Grown by pushes, the arrays' spare capacity would stay alive with
        // the scene: a third more than the 5M-triangle scene needs.
        bvh.nodes.shrink_to_fit();
        bvh.blocks.shrink_to_fit();
        assert!(
            bvh.blocks.len() <= MAX_PRIMITIVES,
            "{} primitive blocks in a BVH",
            bvh.blocks.len()
        );
        assert!(
            bvh.depth() <= MAX_DEPTH,
            "a BVH {} levels deep",
            bvh.depth()
        );
        bvh
    }

    /// The winding tree of this BVH, whose primitives below
    /// `triangle_count` are triangles; built on the first call.
    pub fn winding_tree(&self, triangle_count: usize) -> &WindingTree {
        self.winding
            .get_or_init(|| WindingTree::build(self, triangle_count))
    }

    /// The sides of the surface of this BVH's triangles (`triangles`, its
    /// primitives below their count), or why their winding number is no
    /// integer (`Sides::build`); built on the first call.
    pub fn sides(&self, triangles: &[Triangle]) -> Result<&Sides, &str> {
        self.sides
            .get_or_init(|| Sides::build(self, triangles))
            .as_ref()
            .map_err(String::as_str)
    }

    /// Fills node `index` from `node`'s children (or their children), then
    /// the subtrees of its interior children, depth first.
    fn flatten(&mut self, node: BinaryNode, index: usize, triangles: &[Triangle]) {
        let slots = wide_slots(node);
        let mut wide = BvhNode::EMPTY;
        let mut interior = Vec::new();
        for (slot, child) in slots.into_iter().enumerate() {
            let b = child.bounds();
            let reference = match child {
                BinaryNode::Leaf { prims, .. } => {
                    assert!(
                        (1..=MAX_LEAF).contains(&prims.len()),
                        "a leaf of {} primitives",
                        prims.len()
                    );
                    let first = self.blocks.len() as u32;
                    let blocks = prims.chunks(4).map(|ids| PrimBlock::new(ids, triangles));
                    self.blocks.extend(blocks);
                    leaf_ref(first, prims.len().div_ceil(4) as u32)
                }
                child => {
                    interior.push((child, self.nodes.len()));
                    self.nodes.push(BvhNode::EMPTY);
                    (self.nodes.len() - 1) as u32
                }
            };
            wide.set_child(slot, reference, b.min.to_array(), b.max.to_array());
        }
        self.nodes[index] = wide;
        for (child, i) in interior {
            self.flatten(child, i, triangles);
        }
    }

    /// The box around every primitive; None for an empty scene.
    pub fn bounds(&self) -> Option<Aabb> {
        let mut b = Aabb::EMPTY;
        for slot in occupied_slots(&self.nodes[0]) {
            b.grow(&child_aabb(&self.nodes[0], slot));
        }
        (b.min.x <= b.max.x).then_some(b)
    }

    /// Expected cost of a random ray by the SAH (a wide node visit and a
    /// block's 4-lane test both cost 1), relative to the root's area: lower
    /// is better.
    pub fn sah_cost(&self) -> f64 {
        let mut cost = SahCost::default();
        for node in &self.nodes {
            let mut node_box = Aabb::EMPTY;
            for slot in occupied_slots(node) {
                let b = child_aabb(node, slot);
                node_box.grow(&b);
                if node.children[slot] & LEAF_BIT != 0 {
                    cost.leaf(leaf_range(node.children[slot]).1, &b);
                }
            }
            cost.node(&node_box);
        }
        cost.relative_to(self.bounds())
    }

    /// Wide levels from the root to the deepest leaf (1: the root's children
    /// are all leaves; 0: no primitives).
    pub fn depth(&self) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        fn depth_of(bvh: &Bvh, index: usize) -> usize {
            let node = &bvh.nodes[index];
            1 + occupied_slots(node)
                .filter(|&slot| node.children[slot] & LEAF_BIT == 0)
                .map(|slot| depth_of(bvh, node.children[slot] as usize))
                .max()
                .unwrap_or(0)
        }
        depth_of(self, 0)
    }

    /// Leaves (child references with `LEAF_BIT`).
    pub fn leaf_count(&self) -> usize {
        self.nodes
            .iter()
            .flat_map(|n| occupied_slots(n).map(move |s| n.children[s]))
            .filter(|c| c & LEAF_BIT != 0)
            .count()
    }

    /// Bytes on the device: nodes plus blocks.
    pub fn device_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.blocks.as_slice())
    }
}

/// The children of the wide node made from `node`: its children, each
/// interior one replaced by its own two (so that every path descends two
/// binary levels per wide level, which bounds the depth); then, while there
/// are fewer than `BVH_WIDTH`, the interior one of largest area replaced by
/// its two. Fuller nodes mean fewer visits per ray.
fn wide_slots(node: BinaryNode) -> Vec<BinaryNode> {
    let mut slots = Vec::with_capacity(BVH_WIDTH);
    let expand = |node: BinaryNode, slots: &mut Vec<BinaryNode>| match node {
        BinaryNode::Interior { children, .. } => slots.extend(*children),
        leaf => slots.push(leaf),
    };
    match node {
        BinaryNode::Interior { children, .. } => {
            for child in *children {
                expand(child, &mut slots);
            }
        }
        leaf => return vec![leaf],
    }
    while slots.len() < BVH_WIDTH {
        let largest = slots
            .iter()
            .enumerate()
            .filter(|(_, s)| matches!(s, BinaryNode::Interior { .. }))
            .max_by(|(_, a), (_, b)| a.bounds().half_area().total_cmp(&b.bounds().half_area()));
        let Some((i, _)) = largest else { break };
        let node = slots.swap_remove(i);
        expand(node, &mut slots);
    }
    slots
}

/// The slots of `node` that hold a child.
pub fn occupied_slots(node: &BvhNode) -> impl Iterator<Item = usize> + '_ {
    (0..BVH_WIDTH).filter(|&s| node.occupied & 1 << s != 0)
}

/// Child `slot`'s box.
pub fn child_aabb(node: &BvhNode, slot: usize) -> Aabb {
    let (min, max) = node.child_bounds(slot);
    Aabb {
        min: Vec3::from(min),
        max: Vec3::from(max),
    }
}

fn bounds_of(items: &[Item]) -> (Aabb, Aabb) {
    let mut bounds = Aabb::EMPTY;
    let mut centres = Aabb::EMPTY;
    for item in items {
        bounds.grow(&item.bounds);
        centres.grow_point(item.centre);
    }
    (bounds, centres)
}

/// Blocks (4-lane tests) that `n` primitives take: what a leaf costs.
fn blocks_of(n: usize) -> f32 {
    n.div_ceil(4) as f32
}

fn leaf(bounds: Aabb, items: &[Item]) -> BinaryNode {
    BinaryNode::Leaf {
        bounds,
        prims: items.iter().map(|i| i.prim).collect(),
    }
}

/// Binary levels that halving `n` primitives takes to reach leaves of
/// `MAX_LEAF`.
fn median_levels(n: usize) -> usize {
    n.div_ceil(MAX_LEAF).next_power_of_two().trailing_zeros() as usize
}

/// Builds the subtree of `items` at binary depth `depth`. Invariant:
/// depth + median_levels(n) < MAX_BINARY_DEPTH, so that median splits can
/// always finish within the depth limit; an SAH split is taken only while
/// it keeps the invariant for both children.
fn build_node(mut items: Vec<Item>, depth: usize) -> BinaryNode {
    let (bounds, centres) = bounds_of(&items);
    let n = items.len();
    if n == 1 {
        return leaf(bounds, &items);
    }
    let extent = centres.max - centres.min;
    let sah_allowed = depth + 1 + median_levels(n - 1) < MAX_BINARY_DEPTH;
    let split = if sah_allowed && extent.max_element() > 0.0 {
        best_binned_split(&items, &centres, bounds.half_area())
    } else {
        None
    };
    let right = match split {
        Some((axis, bin, cost)) => {
            if cost >= COST_INTERSECT * blocks_of(n) && n <= MAX_LEAF {
                return leaf(bounds, &items);
            }
            let scale = BINS as f32 / extent[axis];
            let min = centres.min[axis];
            let (left, right): (Vec<Item>, Vec<Item>) = items
                .into_iter()
                .partition(|it| bin_of(it.centre[axis], min, scale) < bin);
            items = left;
            right
        }
        // Centres coincide, no split separates them, or the tree is near
        // its depth limit: halve at the median centre along the longest
        // axis, so that even identical primitives give a balanced tree.
        None => {
            if n <= MAX_LEAF {
                return leaf(bounds, &items);
            }
            let axis = extent.max_position();
            items.select_nth_unstable_by(n / 2, |a, b| a.centre[axis].total_cmp(&b.centre[axis]));
            items.split_off(n / 2)
        }
    };
    let (left, right) = if n > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(items, depth + 1),
            || build_node(right, depth + 1),
        )
    } else {
        (build_node(items, depth + 1), build_node(right, depth + 1))
    };
    BinaryNode::Interior {
        bounds,
        children: Box::new([left, right]),
    }
}

fn bin_of(x: f32, min: f32, scale: f32) -> usize {
    (((x - min) * scale) as usize).min(BINS - 1)
}

/// (axis, first bin of the right side, SAH cost) of the cheapest split.
fn best_binned_split(items: &[Item], centres: &Aabb, area: f32) -> Option<(usize, usize, f32)> {
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        let extent = centres.max[axis] - centres.min[axis];
        if extent <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent;
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for it in items {
            let b = &mut bins[bin_of(it.centre[axis], centres.min[axis], scale)];
            b.0.grow(&it.bounds);
            b.1 += 1;
        }
        // Sweep from the right, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in (1..BINS).rev() {
            acc.grow(&bins[i].0);
            count += bins[i].1;
            right_area[i] = acc.half_area();
            right_count[i] = count;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for i in 1..BINS {
            acc.grow(&bins[i - 1].0);
            count += bins[i - 1].1;
            if count == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = COST_TRAVERSAL
                + COST_INTERSECT
                    * (acc.half_area() * blocks_of(count)
                        + right_area[i] * blocks_of(right_count[i]))
                    / area.max(f32::MIN_POSITIVE);
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, i, cost));
            }
        }
    }
    best
}
