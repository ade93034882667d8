//! A tree's invariants checked and its statistics measured: the wide tree
//! against its primitives here (`Bvh::validate`), the compressed tree
//! against the wide one in `cwbvh::validate`. Tests, the fuzz harness and
//! `lambert info` call them; a failure names the node and what is wrong.

use std::fmt;

use glam::Vec3;

use super::{Aabb, Bvh, COST_INTERSECT, COST_TRAVERSAL, MAX_DEPTH, MAX_LEAF};
use super::{child_aabb, occupied_slots};
use crate::layout::{EMPTY_SLOT, LEAF_BIT, NO_HIT, PrimBlock, Sphere, Triangle, leaf_range};

/// What `validate` measures of a tree.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeStats {
    pub nodes: usize,
    pub leaves: usize,
    /// Levels from the root to the deepest leaf (0: no primitives).
    pub depth: usize,
    /// Primitives per leaf: fewest, most, mean (0 with no leaves).
    pub leaf_min: usize,
    pub leaf_max: usize,
    pub leaf_mean: f64,
    /// The SAH cost relative to the root's area (`Bvh::sah_cost`).
    pub sah_cost: f64,
    /// Nodes and leaf blocks on the device.
    pub bytes: usize,
}

impl fmt::Display for TreeStats {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} nodes, {} leaves, depth {}, {}–{} primitives per leaf (mean {:.2}), SAH cost {:.1}, {:.1} MiB",
            self.nodes,
            self.leaves,
            self.depth,
            self.leaf_min,
            self.leaf_max,
            self.leaf_mean,
            self.sah_cost,
            self.bytes as f64 / (1 << 20) as f64
        )
    }
}

/// A broken invariant: the tree ("BVH" or "compressed BVH"), the node where
/// it shows (None for one of the whole tree) and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    pub tree: &'static str,
    pub node: Option<usize>,
    pub what: String,
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.node {
            Some(node) => write!(f, "{} node {node}: {}", self.tree, self.what),
            None => write!(f, "{}: {}", self.tree, self.what),
        }
    }
}

impl std::error::Error for Invalid {}

/// The SAH cost summed node by node (a wide node visit and a block's 4-lane
/// test both cost 1), in the order `Bvh::sah_cost` has always summed it.
#[derive(Default)]
pub(crate) struct SahCost(f64);

impl SahCost {
    pub(crate) fn leaf(&mut self, blocks: u32, b: &Aabb) {
        self.0 += (COST_INTERSECT * blocks as f32 * b.half_area()) as f64;
    }

    pub(crate) fn node(&mut self, node_box: &Aabb) {
        self.0 += (COST_TRAVERSAL * node_box.half_area()) as f64;
    }

    /// The sum relative to the root's area: lower is better.
    pub(crate) fn relative_to(self, root: Option<Aabb>) -> f64 {
        match root {
            Some(root) => self.0 / (root.half_area() as f64).max(f64::MIN_POSITIVE),
            None => 0.0,
        }
    }
}

/// Primitives per leaf: fewest, most and their sum over the leaves.
#[derive(Default)]
pub(crate) struct LeafSizes {
    min: Option<usize>,
    max: usize,
    sum: usize,
    count: usize,
}

impl LeafSizes {
    pub(crate) fn add(&mut self, blocks: &[PrimBlock]) -> usize {
        let used = blocks
            .iter()
            .flat_map(|b| b.prims)
            .filter(|&p| p != NO_HIT)
            .count();
        self.min = Some(self.min.map_or(used, |m| m.min(used)));
        self.max = self.max.max(used);
        self.sum += used;
        self.count += 1;
        used
    }

    /// The statistics, given what the leaves do not tell.
    pub(crate) fn stats(
        self,
        nodes: usize,
        depth: usize,
        sah_cost: f64,
        bytes: usize,
    ) -> TreeStats {
        TreeStats {
            nodes,
            leaves: self.count,
            depth,
            leaf_min: self.min.unwrap_or(0),
            leaf_max: self.max,
            leaf_mean: self.sum as f64 / self.count.max(1) as f64,
            sah_cost,
            bytes,
        }
    }
}

/// The box of primitive `p` (a triangle below `triangles.len()`, else a
/// sphere), as `Bvh::build` bounds it.
fn primitive_box(p: usize, triangles: &[Triangle], spheres: &[Sphere]) -> Aabb {
    match triangles.get(p) {
        Some(t) => {
            let v = [t.v0, t.v1, t.v2].map(Vec3::from);
            Aabb {
                min: v[0].min(v[1]).min(v[2]),
                max: v[0].max(v[1]).max(v[2]),
            }
        }
        None => {
            let s = &spheres[p - triangles.len()];
            let (c, r) = (Vec3::from(s.center), Vec3::splat(s.radius));
            Aabb {
                min: c - r,
                max: c + r,
            }
        }
    }
}

pub(crate) fn inside(inner: &Aabb, outer: &Aabb) -> bool {
    inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all()
}

impl Bvh {
    /// Checks the tree against the primitives it was built from: each node
    /// but the root the child of one node before it, `occupied` in step
    /// with the children, empty slots with inverted boxes, each leaf's
    /// blocks its own and full but for the last, at most `MAX_LEAF`
    /// primitives, their lanes holding their triangles' vertices, inside
    /// the leaf's box; each child node inside its slot's box; every
    /// primitive in exactly one leaf; depth within the traversal stack.
    /// Returns the tree's statistics, or the first broken invariant.
    pub fn validate(
        &self,
        triangles: &[Triangle],
        spheres: &[Sphere],
    ) -> Result<TreeStats, Invalid> {
        let fail = |node: Option<usize>, what: String| Invalid {
            tree: "BVH",
            node,
            what,
        };
        if self.nodes.is_empty() {
            return Err(fail(None, "no root node".into()));
        }
        let primitives = triangles.len() + spheres.len();
        // The node (and slot) that holds each primitive, block and node.
        let mut prim_in: Vec<Option<(usize, usize)>> = vec![None; primitives];
        let mut block_in: Vec<Option<(usize, usize)>> = vec![None; self.blocks.len()];
        let mut parent: Vec<Option<(usize, usize)>> = vec![None; self.nodes.len()];
        let mut sizes = LeafSizes::default();
        for (i, node) in self.nodes.iter().enumerate() {
            let fail = |what: String| fail(Some(i), what);
            for (slot, &child) in node.children.iter().enumerate() {
                let b = child_aabb(node, slot);
                let occupied = node.occupied & 1 << slot != 0;
                if occupied != (child != EMPTY_SLOT) {
                    return Err(fail(format!(
                        "slot {slot}: occupied bit {} but child reference {child:#x}",
                        occupied as u8
                    )));
                }
                if child == EMPTY_SLOT {
                    if !b.min.cmpgt(b.max).all() {
                        return Err(fail(format!("empty slot {slot} has a box {b:?}")));
                    }
                } else if child & LEAF_BIT != 0 {
                    let (first, count) = leaf_range(child);
                    let (first, end) = (first as usize, (first + count) as usize);
                    if end > self.blocks.len() {
                        return Err(fail(format!(
                            "slot {slot}: leaf blocks {first}..{end} beyond the tree's {}",
                            self.blocks.len()
                        )));
                    }
                    for (k, owner) in block_in[first..end].iter_mut().enumerate() {
                        if let Some((n, s)) = owner {
                            return Err(fail(format!(
                                "slot {slot}: block {} is also in node {n} slot {s}",
                                first + k
                            )));
                        }
                        *owner = Some((i, slot));
                    }
                    let blocks = &self.blocks[first..end];
                    let used = sizes.add(blocks);
                    if !(1..=MAX_LEAF).contains(&used) || used + 4 <= 4 * blocks.len() {
                        return Err(fail(format!(
                            "slot {slot}: a leaf of {used} primitives in {} blocks",
                            blocks.len()
                        )));
                    }
                    for (lane, block) in blocks.iter().flat_map(|b| (0..4).map(move |l| (l, b))) {
                        self.check_lane(
                            block,
                            lane,
                            &b,
                            triangles,
                            spheres,
                            &mut prim_in,
                            (i, slot),
                        )
                        .map_err(fail)?;
                    }
                } else {
                    let c = child as usize;
                    if c <= i || c >= self.nodes.len() {
                        return Err(fail(format!(
                            "slot {slot}: child node {c} is not after its parent (nodes {}..{})",
                            i + 1,
                            self.nodes.len()
                        )));
                    }
                    if let Some((n, s)) = parent[c] {
                        return Err(fail(format!(
                            "slot {slot}: node {c} is also the child of node {n} slot {s}"
                        )));
                    }
                    parent[c] = Some((i, slot));
                    let grandchild = &self.nodes[c];
                    for g in occupied_slots(grandchild) {
                        let inner = child_aabb(grandchild, g);
                        if !inside(&inner, &b) {
                            return Err(fail(format!(
                                "slot {slot}: node {c}'s slot {g} box {inner:?} is outside this slot's box {b:?}"
                            )));
                        }
                    }
                }
            }
        }
        if let Some(p) = prim_in.iter().position(Option::is_none) {
            return Err(fail(None, format!("primitive {p} is in no leaf")));
        }
        if let Some(b) = block_in.iter().position(Option::is_none) {
            return Err(fail(None, format!("block {b} is in no leaf")));
        }
        if let Some(n) = parent.iter().skip(1).position(Option::is_none) {
            return Err(fail(Some(n + 1), "is no node's child".into()));
        }
        let depth = self.depth();
        if depth > MAX_DEPTH {
            return Err(fail(
                None,
                format!("{depth} levels deep, past the traversal stack's {MAX_DEPTH}"),
            ));
        }
        Ok(sizes.stats(
            self.nodes.len(),
            depth,
            self.sah_cost(),
            self.device_bytes(),
        ))
    }

    /// Lane `lane` of a block of the leaf in `at` (node, slot) with box `b`:
    /// an id in range, not seen before (recorded in `prim_in`), inside the
    /// box, with its triangle's vertices (zeros for a sphere or no one).
    #[allow(clippy::too_many_arguments)]
    fn check_lane(
        &self,
        block: &PrimBlock,
        lane: usize,
        b: &Aabb,
        triangles: &[Triangle],
        spheres: &[Sphere],
        prim_in: &mut [Option<(usize, usize)>],
        at: (usize, usize),
    ) -> Result<(), String> {
        let slot = at.1;
        let p = block.prims[lane];
        let vertices = [0, 1, 2].map(|k| [0, 1, 2].map(|a| block.v[k][a][lane]));
        match triangles.get(p as usize) {
            Some(t) if vertices != [t.v0, t.v1, t.v2] => {
                return Err(format!(
                    "slot {slot}: the lane of triangle {p} holds {vertices:?}, not its vertices"
                ));
            }
            None if vertices != [[0.0; 3]; 3] => {
                return Err(format!(
                    "slot {slot}: the lane of {p} (no triangle) has vertices {vertices:?}"
                ));
            }
            _ => {}
        }
        if p == NO_HIT {
            return Ok(());
        }
        let Some(owner) = prim_in.get_mut(p as usize) else {
            return Err(format!(
                "slot {slot}: primitive {p} out of range (there are {})",
                prim_in.len()
            ));
        };
        if let Some((n, s)) = owner {
            return Err(format!(
                "slot {slot}: primitive {p} is also in node {n} slot {s}"
            ));
        }
        *owner = Some(at);
        let pb = primitive_box(p as usize, triangles, spheres);
        if !inside(&pb, b) {
            return Err(format!(
                "slot {slot}: primitive {p}'s box {pb:?} is outside the leaf's box {b:?}"
            ));
        }
        Ok(())
    }
}
