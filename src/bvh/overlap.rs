//! Which triangles of a mesh cross another (`crossing`), for
//! `Sides::build`: each triangle against those whose boxes meet its own
//! (found through the BVH), in f64 on the triangles' f32 corners. Pairs
//! sharing a vertex or an edge (welded) meet there by construction, and
//! cross only where they meet beyond it. Where the answer is within
//! rounding of a touch, they count as crossing: a triangle wrongly kept
//! from the pseudo-normal signs loses speed, not correctness.

use glam::DVec3;
use rayon::prelude::*;

use super::{Bvh, occupied_slots};
use crate::layout::{LEAF_BIT, Triangle, leaf_range};

/// Relative size below which a signed volume or distance counts as zero.
const TOUCH: f64 = 1e-12;

/// Every triangle of non-zero area (`corners[t][0] != u32::MAX`, corners
/// welded) that crosses another, each once, in order.
pub fn crossing(bvh: &Bvh, triangles: &[Triangle], corners: &[[u32; 3]]) -> Vec<u32> {
    let vertices = |t: usize| {
        let t = &triangles[t];
        [t.v0, t.v1, t.v2].map(|v| DVec3::from(v.map(f64::from)))
    };
    let mut crossing = (0..triangles.len())
        .into_par_iter()
        .filter(|&a| corners[a][0] != u32::MAX)
        .map_init(Vec::new, |stack: &mut Vec<u32>, a| {
            let mut found = Vec::new();
            let t = &triangles[a];
            let lo = [0, 1, 2].map(|k| t.v0[k].min(t.v1[k]).min(t.v2[k]));
            let hi = [0, 1, 2].map(|k| t.v0[k].max(t.v1[k]).max(t.v2[k]));
            let va = vertices(a);
            stack.clear();
            stack.push(0);
            while let Some(node) = stack.pop() {
                if node & LEAF_BIT != 0 {
                    let (first, count) = leaf_range(node);
                    for block in &bvh.blocks[first as usize..(first + count) as usize] {
                        for (lane, &b) in block.prims.iter().enumerate() {
                            let b = b as usize;
                            // The lane's box against a's first: most pairs
                            // a leaf brings are apart.
                            let meets = (0..3).all(|k| {
                                let x = block.v.map(|v| v[k][lane]);
                                x[0].min(x[1]).min(x[2]) <= hi[k]
                                    && lo[k] <= x[0].max(x[1]).max(x[2])
                            });
                            if b > a
                                && meets
                                && b < triangles.len()
                                && corners[b][0] != u32::MAX
                                && cross(va, corners[a], vertices(b), corners[b])
                            {
                                found.extend([a as u32, b as u32]);
                            }
                        }
                    }
                    continue;
                }
                let node = &bvh.nodes[node as usize];
                for slot in occupied_slots(node) {
                    let (min, max) = node.child_bounds(slot);
                    if (0..3).all(|k| min[k] <= hi[k] && lo[k] <= max[k]) {
                        stack.push(node.children[slot]);
                    }
                }
            }
            found
        })
        .flatten_iter()
        .collect::<Vec<u32>>();
    crossing.par_sort_unstable();
    crossing.dedup();
    crossing
}

/// Whether triangles a and b (corners and their welded vertices) cross
/// anywhere but at what they share.
fn cross(a: [DVec3; 3], ia: [u32; 3], b: [DVec3; 3], ib: [u32; 3]) -> bool {
    // Which corner of b each corner of a is, if any.
    let same = ia.map(|v| ib.iter().position(|&w| w == v));
    match same.iter().filter(|s| s.is_some()).count() {
        0 => apart_cross(a, b),
        1 => {
            let i = same.iter().position(|s| s.is_some()).unwrap_or(0);
            vertex_cross(a, i, b, same[i].unwrap_or(0))
        }
        2 => {
            // An edge p–q: they cross only folded onto each other, flat.
            let lone = same.iter().position(|s| s.is_none()).unwrap_or(0);
            let (p, q) = (a[(lone + 1) % 3], a[(lone + 2) % 3]);
            let x = a[lone];
            let y = b[3 - same.iter().flatten().sum::<usize>()];
            let (e, ex, ey) = (q - p, x - p, y - p);
            let flat = e.dot(ex.cross(ey)).abs() <= TOUCH * e.length() * ex.length() * ey.length();
            flat && e.cross(ex).dot(e.cross(ey)) > 0.0
        }
        _ => true,
    }
}

/// Triangles a and b sharing only corner i of a, corner j of b.
fn vertex_cross(a: [DVec3; 3], i: usize, b: [DVec3; 3], j: usize) -> bool {
    let v = a[i];
    let others = |t: [DVec3; 3], k: usize| [t[(k + 1) % 3] - v, t[(k + 2) % 3] - v];
    let (ea, eb) = (others(a, i), others(b, j));
    let (na, nb) = (ea[0].cross(ea[1]), eb[0].cross(eb[1]));
    // Signed distances of each one's other corners from the other's plane.
    let sides = |e: [DVec3; 2], n: DVec3| {
        let tolerance = TOUCH * n.length() * e[0].length().max(e[1].length());
        let s = e.map(|x| n.dot(x));
        (s, tolerance)
    };
    let (sa, ta) = sides(ea, nb);
    let (sb, tb) = sides(eb, na);
    let one_side = |s: [f64; 2], t: f64| (s[0] > t && s[1] > t) || (s[0] < -t && s[1] < -t);
    if one_side(sa, ta) || one_side(sb, tb) {
        return false;
    }
    let flat = |s: [f64; 2], t: f64| s.iter().all(|x| x.abs() <= t);
    if flat(sa, ta) || flat(sb, tb) {
        // In one plane: the two corners' wedges overlap.
        return wedges_overlap(ea, eb) || wedges_overlap(eb, ea);
    }
    // Each meets the other's plane in a segment from v (to a corner on
    // that plane, or to where its far edge cuts it); both segments lie on
    // the line the planes share, and overlap beyond v where they leave it
    // the same way.
    let end = |e: [DVec3; 2], s: [f64; 2], t: f64| {
        if s[0].abs() <= t {
            e[0]
        } else if s[1].abs() <= t {
            e[1]
        } else {
            e[0] + (e[1] - e[0]) * (s[0] / (s[0] - s[1]))
        }
    };
    end(ea, sa, ta).dot(end(eb, sb, tb)) > 0.0
}

/// Whether a direction of wedge `f` (its edges or their bisector) lies
/// strictly inside wedge `e` (two edges from one corner, in one plane).
fn wedges_overlap(e: [DVec3; 2], f: [DVec3; 2]) -> bool {
    let n = e[0].cross(e[1]);
    let inside = |d: DVec3| e[0].cross(d).dot(n) > 0.0 && d.cross(e[1]).dot(n) > 0.0;
    let bisector = f[0].normalize_or_zero() + f[1].normalize_or_zero();
    inside(f[0]) || inside(f[1]) || inside(bisector)
}

/// Triangles sharing no vertex (Möller's interval test, closed: a touch
/// counts).
fn apart_cross(a: [DVec3; 3], b: [DVec3; 3]) -> bool {
    let normal = |t: [DVec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]);
    let (na, nb) = (normal(a), normal(b));
    let size = a
        .iter()
        .chain(&b)
        .map(|&p| (p - a[0]).length())
        .fold(0.0, f64::max);
    let distances = |t: [DVec3; 3], n: DVec3, origin: DVec3| {
        let tolerance = TOUCH * n.length() * size;
        t.map(|p| {
            let d = n.dot(p - origin);
            if d.abs() <= tolerance { 0.0 } else { d }
        })
    };
    let (da, db) = (distances(a, nb, b[0]), distances(b, na, a[0]));
    let apart = |d: [f64; 3]| d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0);
    if apart(da) || apart(db) {
        return false;
    }
    if da == [0.0; 3] {
        return flat_cross(a, b, na);
    }
    let line = na.cross(nb);
    let interval = |t: [DVec3; 3], d: [f64; 3]| {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            let (dp, dq) = (d[k], d[(k + 1) % 3]);
            let mut add = |x: DVec3| {
                let s = line.dot(x);
                lo = lo.min(s);
                hi = hi.max(s);
            };
            if dp == 0.0 {
                add(p);
            }
            if dp * dq < 0.0 {
                add(p + (q - p) * (dp / (dp - dq)));
            }
        }
        (lo, hi)
    };
    let (la, ha) = interval(a, da);
    let (lb, hb) = interval(b, db);
    let slack = TOUCH * line.length() * size;
    la <= hb + slack && lb <= ha + slack
}

/// Triangles in one plane (normal `n`) sharing no vertex: an edge of one
/// meets an edge of the other, or a corner of one lies in the other
/// (closed: a touch counts).
fn flat_cross(a: [DVec3; 3], b: [DVec3; 3], n: DVec3) -> bool {
    let orient = |p: DVec3, q: DVec3, r: DVec3| (q - p).cross(r - p).dot(n);
    let meets = |p: DVec3, q: DVec3, r: DVec3, s: DVec3| {
        let (o1, o2) = (orient(p, q, r), orient(p, q, s));
        let (o3, o4) = (orient(r, s, p), orient(r, s, q));
        o1 * o2 <= 0.0 && o3 * o4 <= 0.0
    };
    let contains = |t: [DVec3; 3], p: DVec3| {
        let o = [0, 1, 2].map(|k| orient(t[k], t[(k + 1) % 3], p));
        o.iter().all(|&x| x >= 0.0) || o.iter().all(|&x| x <= 0.0)
    };
    (0..3).any(|i| (0..3).any(|j| meets(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])))
        || contains(a, b[0])
        || contains(b, a[0])
}
