//! The compressed tree checked against the wide one it was made from, and
//! measured: the same children and leaves node for node, siblings
//! consecutive, and the quantisation conservative (every child's box
//! contains the wide tree's exact one, which the watertight guarantee
//! needs).

use std::collections::VecDeque;

use crate::bvh::{Aabb, Bvh, Invalid, LeafSizes, SahCost, TreeStats, child_aabb, inside};
use crate::layout::{BVH_WIDTH, CompressedNode, LEAF_BIT, META_INTERIOR, META_LEAF, leaf_range};

/// A child of a compressed node, decoded from its meta byte.
#[derive(Clone, Copy, PartialEq)]
enum Child {
    Empty,
    Leaf { first: u32, count: u32 },
    Interior { rank: u32 },
}

fn decode(node: &CompressedNode, slot: usize) -> Result<Child, String> {
    let meta = CompressedNode::byte(node.child_meta, slot);
    Ok(if meta == 0 {
        Child::Empty
    } else if meta & META_LEAF != 0 {
        Child::Leaf {
            first: node.block_base.saturating_add(meta & 0xf),
            count: (meta >> 4 & 0x7) + 1,
        }
    } else if meta & !0x7 == META_INTERIOR {
        Child::Interior { rank: meta & 0x7 }
    } else {
        return Err(format!("slot {slot}: meta byte {meta:#04x} is no child"));
    })
}

fn slot_box(node: &CompressedNode, slot: usize) -> Aabb {
    let (min, max) = node.child_bounds(slot);
    Aabb {
        min: min.into(),
        max: max.into(),
    }
}

/// The first block under each node, children being after their parents
/// (`children(i)` lists node i's leaves' first blocks and child nodes).
fn first_blocks(
    len: usize,
    children: impl Fn(usize) -> Result<(Vec<u32>, Vec<usize>), (usize, String)>,
) -> Result<Vec<u32>, (usize, String)> {
    let mut first = vec![u32::MAX; len];
    for i in (0..len).rev() {
        let (leaves, nodes) = children(i)?;
        for &c in &nodes {
            if c <= i || c >= len {
                return Err((i, format!("child node {c} is not after its parent")));
            }
        }
        first[i] = leaves
            .into_iter()
            .chain(nodes.iter().map(|&c| first[c]))
            .min()
            .unwrap_or(u32::MAX);
    }
    Ok(first)
}

/// Checks `nodes` (from `compress`) against `bvh`, which should itself be
/// valid (`Bvh::validate`): as many nodes, each compressed node holding
/// its wide node's leaves and children (paired by the first block under
/// them), interior children consecutive from `child_base` in slot order,
/// empty slots with inverted boxes, every child's quantised box containing
/// the wide tree's exact one, every node reached once. Returns the
/// compressed tree's statistics (SAH cost on the quantised boxes), or the
/// first broken invariant, naming the compressed node.
pub fn validate(nodes: &[CompressedNode], bvh: &Bvh) -> Result<TreeStats, Invalid> {
    let fail = |node: Option<usize>, what: String| Invalid {
        tree: "compressed BVH",
        node,
        what,
    };
    if nodes.len() != bvh.nodes.len() {
        return Err(fail(
            None,
            format!(
                "{} nodes for the wide tree's {}",
                nodes.len(),
                bvh.nodes.len()
            ),
        ));
    }
    let wide_first = first_blocks(bvh.nodes.len(), |i| {
        let n = &bvh.nodes[i];
        let refs = crate::bvh::occupied_slots(n).map(|s| n.children[s]);
        let (leaves, inner): (Vec<u32>, Vec<u32>) = refs.partition(|c| c & LEAF_BIT != 0);
        Ok((
            leaves.into_iter().map(|c| leaf_range(c).0).collect(),
            inner.into_iter().map(|c| c as usize).collect(),
        ))
    })
    .map_err(|(i, what)| fail(None, format!("wide node {i}: {what}")))?;
    let compressed_first = first_blocks(nodes.len(), |i| {
        let (mut leaves, mut inner) = (Vec::new(), Vec::new());
        for slot in 0..BVH_WIDTH {
            match decode(&nodes[i], slot).map_err(|e| (i, e))? {
                Child::Leaf { first, .. } => leaves.push(first),
                Child::Interior { rank } => {
                    inner.push(nodes[i].child_base as usize + rank as usize)
                }
                Child::Empty => {}
            }
        }
        Ok((leaves, inner))
    })
    .map_err(|(i, what)| fail(Some(i), what))?;

    let mut reached = vec![false; nodes.len()];
    reached[0] = true;
    let (mut sizes, mut sah, mut depth) = (LeafSizes::default(), SahCost::default(), 0);
    let mut root = Aabb::EMPTY;
    // (compressed node, its wide node, level)
    let mut queue = VecDeque::from([(0usize, 0usize, 1usize)]);
    while let Some((c, w, level)) = queue.pop_front() {
        let fail = |what: String| fail(Some(c), what);
        depth = depth.max(level);
        let (node, wide) = (&nodes[c], &bvh.nodes[w]);
        let mut unpaired: Vec<usize> = crate::bvh::occupied_slots(wide).collect();
        let (mut node_box, mut next_rank) = (Aabb::EMPTY, 0);
        for slot in 0..BVH_WIDTH {
            let b = slot_box(node, slot);
            let child = decode(node, slot).map_err(fail)?;
            let wanted = |ws: &usize| {
                let r = wide.children[*ws];
                match child {
                    Child::Leaf { first, count } => {
                        r & LEAF_BIT != 0 && leaf_range(r) == (first, count)
                    }
                    Child::Interior { rank } => {
                        let i = node.child_base as usize + rank as usize;
                        r & LEAF_BIT == 0 && wide_first[r as usize] == compressed_first[i]
                    }
                    Child::Empty => false,
                }
            };
            if child == Child::Empty {
                if !b.min.cmpgt(b.max).all() {
                    return Err(fail(format!("empty slot {slot} has a box {b:?}")));
                }
                continue;
            }
            let Some(k) = unpaired.iter().position(wanted) else {
                return Err(fail(format!(
                    "slot {slot}: no child of wide node {w} is this one"
                )));
            };
            let ws = unpaired.swap_remove(k);
            let exact = child_aabb(wide, ws);
            if !inside(&exact, &b) {
                return Err(fail(format!(
                    "slot {slot}: the quantised box {b:?} does not contain the exact one {exact:?}"
                )));
            }
            node_box.grow(&b);
            match child {
                Child::Leaf { first, count } => {
                    let blocks = (first as usize)..(first as usize + count as usize);
                    let Some(blocks) = bvh.blocks.get(blocks.clone()) else {
                        return Err(fail(format!(
                            "slot {slot}: leaf blocks {blocks:?} beyond the tree's {}",
                            bvh.blocks.len()
                        )));
                    };
                    sizes.add(blocks);
                    sah.leaf(count, &b);
                }
                Child::Interior { rank } => {
                    if rank != next_rank {
                        return Err(fail(format!(
                            "slot {slot}: interior rank {rank} where {next_rank} comes next"
                        )));
                    }
                    next_rank += 1;
                    let i = node.child_base as usize + rank as usize;
                    if std::mem::replace(&mut reached[i], true) {
                        return Err(fail(format!("slot {slot}: node {i} is reached twice")));
                    }
                    queue.push_back((i, wide.children[ws] as usize, level + 1));
                }
                Child::Empty => unreachable!("skipped above"),
            }
        }
        if let Some(ws) = unpaired.first() {
            return Err(fail(format!("wide node {w}'s slot {ws} has no slot here")));
        }
        sah.node(&node_box);
        if c == 0 {
            root = node_box;
        }
    }
    if let Some(i) = reached.iter().position(|&r| !r) {
        return Err(fail(Some(i), "is no node's child".into()));
    }
    let bytes = std::mem::size_of_val(nodes) + std::mem::size_of_val(bvh.blocks.as_slice());
    let root = (root.min.x <= root.max.x).then_some(root);
    Ok(sizes.stats(nodes.len(), depth, sah.relative_to(root), bytes))
}
