//! Closest points, the twin of shaders/closest.wgsl: the nearest point of
//! a triangle to a point (`closest_point_triangle`, its arithmetic written
//! out operation by operation as in the shader, so both round alike), the
//! distance of a box (`box_distance2`), the order of candidates (`better`)
//! and the traversal (`closest_point`). The CPU walks its own 256-byte
//! nodes nearest first, the GPU its compressed ones: `better` is a total
//! order (distance, then primitive id) and both traversals visit every box
//! that could hold a candidate as good as the best so far
//! (`cull_bound`), so they find the same answer, bit for bit.

use glam::Vec3;

use crate::bvh::{Bvh, STACK_SIZE, occupied_slots};
use crate::layout::{BVH_WIDTH, LEAF_BIT, NO_HIT, leaf_range};

/// The nearest point found for a query point: its squared distance, the
/// triangle, (u, v) on it, and the point itself (all in the scene's local
/// frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    pub d2: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub point: Vec3,
}

/// a · b, summed left to right (WGSL's `dot` leaves its order open).
#[inline(always)]
pub fn dot3(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// The point of segment s0 + t·e (t in [0, 1]) nearest `p`: the point,
/// its squared distance and t (0 on a segment of zero length).
#[inline(always)]
pub fn closest_on_segment(p: Vec3, s0: Vec3, e: Vec3) -> (Vec3, f32, f32) {
    let ee = dot3(e, e);
    let mut t = 0.0;
    if ee > 0.0 {
        t = (dot3(p - s0, e) / ee).clamp(0.0, 1.0);
    }
    let q = s0 + e * t;
    let d = p - q;
    (q, dot3(d, d), t)
}

/// The point of triangle (a, b, c) nearest `p`: the point, its squared
/// distance and (u, v), the weights of b and c. Inside the triangle's
/// prism (Ericson's region test: every barycentric area positive) the
/// projection; else the nearest of the edges ab, ac, bc in that order,
/// the first kept on equal distances. A degenerate triangle (zero area)
/// takes its edges too, so nothing divides by zero.
#[inline(always)]
pub fn closest_point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, f32, f32, f32) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let bp = p - b;
    let cp = p - c;
    let d1 = dot3(ab, ap);
    let d2 = dot3(ac, ap);
    let d3 = dot3(ab, bp);
    let d4 = dot3(ac, bp);
    let d5 = dot3(ab, cp);
    let d6 = dot3(ac, cp);
    let va = d3 * d6 - d5 * d4;
    let vb = d5 * d2 - d1 * d6;
    let vc = d1 * d4 - d3 * d2;
    let sum = va + vb + vc;
    if va > 0.0 && vb > 0.0 && vc > 0.0 && sum > 0.0 {
        let v = vb / sum;
        let w = vc / sum;
        let q = a + ab * v + ac * w;
        let d = p - q;
        return (q, dot3(d, d), v, w);
    }
    let (mut q, mut best, t) = closest_on_segment(p, a, ab);
    let (mut u, mut v) = (t, 0.0);
    let (q2, d2_ac, t2) = closest_on_segment(p, a, ac);
    if d2_ac < best {
        (q, best, u, v) = (q2, d2_ac, 0.0, t2);
    }
    let (q3, d2_bc, t3) = closest_on_segment(p, b, c - b);
    if d2_bc < best {
        (q, best, u, v) = (q3, d2_bc, 1.0 - t3, t3);
    }
    (q, best, u, v)
}

/// The squared distance from `p` to the box (lo, hi): 0 inside.
#[inline(always)]
pub fn box_distance2(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let d = (lo - p).max(p - hi).max(Vec3::ZERO);
    dot3(d, d)
}

/// Whether a candidate at squared distance `d2` on triangle `prim` beats
/// the best so far: nearer, or as near with a lower id (so that shared
/// edges and vertices go to the same triangle whatever the order of
/// visits).
#[inline(always)]
pub fn better(d2: f32, prim: u32, best_d2: f32, best_prim: u32) -> bool {
    d2 < best_d2 || (d2 == best_d2 && prim < best_prim)
}

/// The squared distance beyond which a box can hold no candidate as good
/// as one at squared distance `d2`: (√d2 + margin)², where `margin`
/// bounds the rounding of a candidate's distance and of a box's (see
/// `query_margin`).
#[inline(always)]
pub fn cull_bound(d2: f32, margin: f32) -> f32 {
    let d = d2.sqrt() + margin;
    d * d
}

/// How far a computed distance may be from the exact one for a point of
/// largest coordinate `point_extent` in a scene of radius `scene_radius`
/// (local frame): a few hundred units in the last place of the largest
/// coordinate involved, far more than the few that the arithmetic loses.
pub fn query_margin(point_extent: f32, scene_radius: f32) -> f32 {
    1e-5 * point_extent.max(scene_radius)
}

/// The nearest point of the BVH's triangles (ids below `triangle_count`)
/// to `p` within squared distance `max_d2` (None when none is), nearest
/// box first, boxes beyond `cull_bound` of the best so far skipped.
pub fn closest_point(
    bvh: &Bvh,
    triangle_count: usize,
    p: Vec3,
    max_d2: f32,
    margin: f32,
) -> Option<Nearest> {
    let mut best = Nearest {
        d2: max_d2,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
        point: Vec3::ZERO,
    };
    let mut bound = cull_bound(max_d2, margin);
    let mut stack = [(0u32, 0.0f32); STACK_SIZE];
    let mut sp = 0;
    let mut current = 0u32;
    loop {
        if current & LEAF_BIT == 0 {
            let node = &bvh.nodes[current as usize];
            // Children within the bound, nearest last (popped first).
            let base = sp;
            for slot in occupied_slots(node) {
                let (lo, hi) = node.child_bounds(slot);
                let d2 = box_distance2(p, Vec3::from(lo), Vec3::from(hi));
                if d2 > bound {
                    continue;
                }
                let mut j = sp;
                while j > base && stack[j - 1].1 < d2 {
                    stack[j] = stack[j - 1];
                    j -= 1;
                }
                stack[j] = (node.children[slot], d2);
                sp += 1;
            }
            debug_assert!(sp - base <= BVH_WIDTH);
        } else {
            let (first, count) = leaf_range(current);
            for block in &bvh.blocks[first as usize..(first + count) as usize] {
                for lane in 0..4 {
                    let prim = block.prims[lane];
                    if prim as usize >= triangle_count {
                        continue;
                    }
                    let vertex = |k: usize| {
                        Vec3::new(
                            block.v[k][0][lane],
                            block.v[k][1][lane],
                            block.v[k][2][lane],
                        )
                    };
                    let (q, d2, u, v) = closest_point_triangle(p, vertex(0), vertex(1), vertex(2));
                    if better(d2, prim, best.d2, best.prim) {
                        best = Nearest {
                            d2,
                            prim,
                            u,
                            v,
                            point: q,
                        };
                        bound = cull_bound(d2, margin);
                    }
                }
            }
        }
        // The nearest entry still within the bound.
        loop {
            if sp == 0 {
                return (best.prim != NO_HIT).then_some(best);
            }
            sp -= 1;
            if stack[sp].1 <= bound {
                current = stack[sp].0;
                break;
            }
        }
    }
}
