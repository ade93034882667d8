//! The GPU's BVH: the wide tree (`bvh`) with each node compressed to 80
//! bytes (`layout::CompressedNode`), after Ylitie, Karras and Laine,
//! "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs" (HPG 2017): the wide tree's nodes with the same children and
//! leaves (the leaf blocks are shared, untouched), the boxes quantised
//! outwards, the slots reordered by octant and the nodes renumbered so
//! that siblings are consecutive.
//!
//! Conservative by construction: each plane is rounded away from the box
//! on a grid whose every point is an f32 (a multiple of a power of two with
//! fewer than 24 significant bits), so the shader's dequantisation
//! `fma(q, scale, origin)` is exact on every device, fused or not, and the
//! box it gets contains the exact one. The slab test then sees a box at
//! least as large as the wide tree's, and the watertight guarantee holds.

mod validate;

pub use validate::validate;

use glam::Vec3;

use crate::bvh::{Aabb, Bvh, child_aabb, occupied_slots};
use crate::layout::{
    BVH_WIDTH, CompressedNode, LEAF_BIT, META_INTERIOR, META_LEAF, grid_point, leaf_range,
};

/// Traversal stack entries per invocation that the shader keeps in
/// workgroup memory: a handful, which Vaidyanathan, Woop and Benthin
/// (HPG 2019) found enough for wide trees; 8 holds the whole stack of
/// trees up to 9 levels (the dragon's). A deeper tree's oldest entries
/// spill to private memory (the shader's `STACK_SPILLS`, measured in
/// docs/bvh.md).
pub const SHORT_STACK_ENTRIES: usize = 8;

/// The short stack's entries for a tree of `depth` levels (which pushes at
/// most depth − 1 node groups) where a workgroup has `workgroup_bytes` of
/// memory, and whether its stack spills (the shader's `STACK_ENTRIES` and
/// `STACK_SPILLS`).
pub fn short_stack(depth: usize, workgroup_bytes: u32) -> (usize, bool) {
    let needed = depth.saturating_sub(1).max(1);
    let fits = workgroup_bytes as usize / (8 * crate::layout::WORKGROUP_INVOCATIONS as usize);
    let entries = needed.min(SHORT_STACK_ENTRIES).min(fits).max(1);
    (entries, needed > entries)
}

/// Workgroup memory every WebGPU device offers (the twin's short stack).
pub const MIN_WORKGROUP_BYTES: u32 = 16384;

/// Grid steps per axis: planes are bytes.
const STEPS: f64 = 255.0;
/// Integers below this are exact in f32: a grid point `k·2^E` with
/// |k| < 2^24 is an f32.
const EXACT: f64 = (1u64 << 24) as f64;

/// The compressed nodes of `bvh`, renumbered breadth first so that each
/// node's interior children are consecutive in slot order: child slot s is
/// node `child_base` + the number of interior slots below s, which
/// traversal counts from a mask it carries rather than reading the node
/// again. The root stays node 0.
pub fn compress(bvh: &Bvh) -> Vec<CompressedNode> {
    use rayon::prelude::*;
    if bvh.nodes.is_empty() {
        return Vec::new();
    }
    let nodes: Vec<(CompressedNode, Vec<u32>)> = (0..bvh.nodes.len())
        .into_par_iter()
        .map(|i| compress_node(bvh, i))
        .collect();
    // order[new] = old; new_index[old] = new.
    let mut order = vec![0usize];
    let mut new_index = vec![0u32; nodes.len()];
    let mut head = 0;
    while head < order.len() {
        for &child in &nodes[order[head]].1 {
            new_index[child as usize] = order.len() as u32;
            order.push(child as usize);
        }
        head += 1;
    }
    order
        .par_iter()
        .map(|&old| {
            let (node, interior) = &nodes[old];
            CompressedNode {
                child_base: interior.first().map_or(0, |&c| new_index[c as usize]),
                ..*node
            }
        })
        .collect()
}

/// Which slot each child takes (`slot_of[c]`), children given by their
/// centres' offsets from the node's centre: slot s wants the child lying
/// most toward the corner that s's bits name (bit a set: +a), and the best
/// pairs are taken first (Ylitie et al.'s greedy assignment).
fn octant_slots(offsets: &[Vec3]) -> Vec<usize> {
    let corner = |s: usize| {
        Vec3::from_array(std::array::from_fn(|a| {
            if s >> a & 1 == 1 { 1.0 } else { -1.0 }
        }))
    };
    let mut pairs: Vec<(f32, usize, usize)> = offsets
        .iter()
        .enumerate()
        .flat_map(|(c, d)| (0..BVH_WIDTH).map(move |s| (d.dot(corner(s)), c, s)))
        .collect();
    // Largest first; ties by child, then slot, so the layout is deterministic.
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut slot_of = vec![usize::MAX; offsets.len()];
    let mut taken = [false; BVH_WIDTH];
    for (_, c, s) in pairs {
        if slot_of[c] == usize::MAX && !taken[s] {
            slot_of[c] = s;
            taken[s] = true;
        }
    }
    slot_of
}

/// The grid of one axis of a node whose children span [lo, hi]: (biased
/// exponent e, origin) with scale 2^(e − 127), the origin a multiple of
/// the scale, every plane from the origin up to 255 steps an f32, and hi
/// within those steps.
fn axis_grid(lo: f32, hi: f32) -> (u32, f32) {
    let extent = (hi as f64 - lo as f64).max(0.0);
    let mut exponent = if extent > 0.0 {
        (extent / STEPS).log2().ceil() as i32
    } else {
        -126
    };
    exponent = exponent.max(-126);
    loop {
        assert!(exponent <= 127, "no grid holds [{lo}, {hi}]");
        let scale = 2f64.powi(exponent);
        // lo / scale is exact (a power of two), so the origin is not above lo.
        let k = (lo as f64 / scale).floor();
        if k.abs() + STEPS < EXACT {
            let origin = (k * scale) as f32;
            // Compared in f32, where the grid's points are exact: in f64,
            // hi − origin may round (hi = 8e-17 against an origin of −1.3).
            if grid_point(STEPS as u32, scale as f32, origin) >= hi {
                return ((exponent + 127) as u32, origin);
            }
        }
        exponent += 1;
    }
}

/// Node `index` compressed but for `child_base`, and its interior
/// children (wide tree indices) in slot order.
fn compress_node(bvh: &Bvh, index: usize) -> (CompressedNode, Vec<u32>) {
    let node = &bvh.nodes[index];
    let slots: Vec<usize> = occupied_slots(node).collect();
    let boxes: Vec<Aabb> = slots.iter().map(|&s| child_aabb(node, s)).collect();
    let mut parent = Aabb::EMPTY;
    for b in &boxes {
        parent.grow(b);
    }
    let mut out = CompressedNode {
        // Empty slots: inverted boxes (and meta 0, which traversal masks).
        q: [[0xffff_ffff, 0xffff_ffff], [0, 0]]
            .repeat(3)
            .try_into()
            .expect("six rows"),
        ..CompressedNode::default()
    };
    if slots.is_empty() {
        return (out, Vec::new());
    }
    let mut scales = [0f64; 3];
    for axis in 0..3 {
        let (e, origin) = axis_grid(parent.min[axis], parent.max[axis]);
        out.exponents |= e << (8 * axis);
        out.origin[axis] = origin;
        scales[axis] = 2f64.powi(e as i32 - 127);
    }
    let children: Vec<u32> = slots.iter().map(|&s| node.children[s]).collect();
    let leaves = || children.iter().copied().filter(|c| c & LEAF_BIT != 0);
    out.block_base = leaves().map(|c| leaf_range(c).0).min().unwrap_or(0);
    let centre = parent.centre();
    let offsets: Vec<Vec3> = boxes.iter().map(|b| b.centre() - centre).collect();
    let slot_of = octant_slots(&offsets);
    // Interior children in slot order: their ranks below.
    let mut interior: Vec<(usize, u32)> = children
        .iter()
        .zip(&slot_of)
        .filter(|(c, _)| *c & LEAF_BIT == 0)
        .map(|(&c, &slot)| (slot, c))
        .collect();
    interior.sort();
    let set_byte = |row: &mut [u32; 2], slot: usize, value: u32| {
        let shift = 8 * (slot % 4);
        row[slot / 4] = row[slot / 4] & !(0xff << shift) | value << shift;
    };
    for (c, (&child, b)) in children.iter().zip(&boxes).enumerate() {
        let slot = slot_of[c];
        let meta = if child & LEAF_BIT == 0 {
            let rank = interior
                .iter()
                .position(|&(s, _)| s == slot)
                .expect("listed");
            META_INTERIOR | rank as u32
        } else {
            let (first, count) = leaf_range(child);
            let offset = first - out.block_base;
            assert!(
                offset < 16 && count <= 8,
                "node {index}: leaf blocks are not contiguous"
            );
            META_LEAF | (count - 1) << 4 | offset
        };
        set_byte(&mut out.child_meta, slot, meta);
        for axis in 0..3 {
            let (origin, scale) = (out.origin[axis], scales[axis]);
            let estimate = |x: f32| (x as f64 - origin as f64) / scale;
            // Rounded outwards in f64, then moved until the f32 grid point
            // (exact) is outside the box: the f64 difference may round.
            let mut lo = (estimate(b.min[axis]).floor().max(0.0)) as u32;
            while lo > 0 && grid_point(lo, scale as f32, origin) > b.min[axis] {
                lo -= 1;
            }
            let mut hi = (estimate(b.max[axis]).ceil().min(STEPS)) as u32;
            while hi < STEPS as u32 && grid_point(hi, scale as f32, origin) < b.max[axis] {
                hi += 1;
            }
            set_byte(&mut out.q[2 * axis], slot, lo);
            set_byte(&mut out.q[2 * axis + 1], slot, hi);
        }
        let (min, max) = out.child_bounds(slot);
        for axis in 0..3 {
            assert!(
                min[axis] <= b.min[axis] && max[axis] >= b.max[axis],
                "node {index} slot {slot}: the quantised box {min:?}..{max:?} does not hold the child's {b:?} (origin {:?}, exponents {:x})",
                out.origin,
                out.exponents
            );
        }
    }
    (out, interior.into_iter().map(|(_, c)| c).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_hold_their_range_exactly() {
        for (lo, hi) in [
            (0.0f32, 1.0f32),
            (-1.0, 1.0),
            (1000.0, 1000.001),
            (5.0, 5.0),
            (-3e7, 4e7),
            (1e-30, 2e-30),
            (-1e30, 1e30),
        ] {
            let (e, origin) = axis_grid(lo, hi);
            let scale = f32::from_bits(e << 23);
            assert!(origin <= lo, "[{lo}, {hi}]: origin {origin}");
            assert!(255f32.mul_add(scale, origin) >= hi, "[{lo}, {hi}]");
            // Every grid point is exact: stepping up one by one in f64
            // gives the f32 the shader computes.
            for q in 0..=255u32 {
                let exact = origin as f64 + q as f64 * scale as f64;
                assert_eq!(
                    (q as f32).mul_add(scale, origin) as f64,
                    exact,
                    "[{lo}, {hi}] q {q}"
                );
            }
        }
    }

    #[test]
    fn boxes_hold_children_whose_planes_round_away_in_f64() {
        // A child reaching 8e-17 beside one at −1.3: in f64, 8e-17 + 1.3125
        // is 1.3125, so a plane rounded up from that difference fell short
        // of 8e-17 (found on trimesh's torus).
        use crate::layout::Triangle;
        let triangle = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| Triangle {
            v0: a,
            v1: b,
            v2: c,
            ..Triangle::default()
        };
        let mut triangles = Vec::new();
        for i in 0..64 {
            let y = i as f32 * 0.02;
            triangles.push(triangle(
                [-1.3, y, 0.0],
                [7.960204e-17, y, 0.1],
                [-0.7, y + 0.01, 0.3],
            ));
            triangles.push(triangle(
                [1.3, y, 0.0],
                [0.2, y, 0.1],
                [0.7, y + 0.01, -0.3],
            ));
        }
        let bvh = Bvh::build(&triangles, &[]);
        let nodes = compress(&bvh);
        // compress checks every child's box; and every leaf's triangles lie
        // in their quantised box.
        assert_eq!(nodes.len(), bvh.nodes.len());
    }

    #[test]
    fn octant_slots_put_children_in_their_corners() {
        let offsets: Vec<Vec3> = (0..8)
            .map(|s| {
                Vec3::from_array(std::array::from_fn(|a| {
                    if s >> a & 1 == 1 { 1.0 } else { -1.0 }
                }))
            })
            .collect();
        assert_eq!(octant_slots(&offsets), (0..8).collect::<Vec<_>>());
        // Fewer children still take distinct slots.
        let slots = octant_slots(&offsets[..3]);
        assert_eq!(slots, vec![0, 1, 2]);
    }
}
