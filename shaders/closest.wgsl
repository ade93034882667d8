// Stage: closest points. The nearest point of a triangle to a point
// (closest_point_triangle, operation by operation as the CPU twin, so both
// round alike), a box's distance, the order of candidates (better: nearer,
// then the lower id) and the traversal of the compressed BVH, nearest
// sibling first, boxes beyond cull_bound of the best skipped. The CPU walks
// its own tree best first; the order of candidates is total and both skip
// only boxes that cannot hold one as good as the best, so both find the same
// answer. CPU twin: src/cpu/closest.rs.

// One point's answer (src/layout.rs ClosestPoint).
struct ClosestPoint {
    point: vec3<f32>,
    prim: u32,
    u: f32,
    v: f32,
    distance: f32,
    _pad: u32,
}

// A leaf on the closest-point stack: LEAF_REF | (count − 1) << 28 | first
// block, as the CPU's leaf references.
const LEAF_REF: u32 = 0x80000000u;
// Entries on the closest-point stack at most: a node visit pops one and
// pushes at most eight, over at most MAX_DEPTH levels.
const CLOSEST_STACK: u32 = 7u * MAX_DEPTH + 1u;

// a · b, summed left to right (dot's order is left open).
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// The point of segment s0 + t·e (t in [0, 1]) nearest p: the point (xyz),
// its squared distance (w); t apart.
struct SegmentPoint {
    q: vec3<f32>,
    d2: f32,
    t: f32,
}

fn closest_on_segment(p: vec3<f32>, s0: vec3<f32>, e: vec3<f32>) -> SegmentPoint {
    let ee = dot3(e, e);
    var t = 0.0;
    if ee > 0.0 {
        t = clamp(dot3(p - s0, e) / ee, 0.0, 1.0);
    }
    let q = s0 + e * t;
    let d = p - q;
    return SegmentPoint(q, dot3(d, d), t);
}

// The point of triangle (a, b, c) nearest p, its squared distance and (u, v),
// the weights of b and c: inside the triangle's prism (every barycentric area
// positive) the projection, else the nearest of the edges ab, ac, bc, the
// first kept on equal distances.
struct TrianglePoint {
    q: vec3<f32>,
    d2: f32,
    u: f32,
    v: f32,
}

fn closest_point_triangle(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> TrianglePoint {
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
        return TrianglePoint(q, dot3(d, d), v, w);
    }
    var best = closest_on_segment(p, a, ab);
    var r = TrianglePoint(best.q, best.d2, best.t, 0.0);
    let on_ac = closest_on_segment(p, a, ac);
    if on_ac.d2 < r.d2 {
        r = TrianglePoint(on_ac.q, on_ac.d2, 0.0, on_ac.t);
    }
    let on_bc = closest_on_segment(p, b, c - b);
    if on_bc.d2 < r.d2 {
        r = TrianglePoint(on_bc.q, on_bc.d2, 1.0 - on_bc.t, on_bc.t);
    }
    return r;
}

fn box_distance2(p: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let d = max(max(lo - p, p - hi), vec3<f32>(0.0));
    return dot3(d, d);
}

fn better(d2: f32, prim: u32, best_d2: f32, best_prim: u32) -> bool {
    return d2 < best_d2 || (d2 == best_d2 && prim < best_prim);
}

fn cull_bound(d2: f32, margin: f32) -> f32 {
    let d = sqrt(d2) + margin;
    return d * d;
}

// Slot `slot` of a compressed node (its grid's scales `scale`): the child's
// box, dequantised exactly, and its reference (a node, or a LEAF_REF leaf
// of absolute blocks); reference NO_HIT for an empty slot. The walks of
// closest_point and all_hits take children so.
struct CompressedChild {
    lo: vec3<f32>,
    hi: vec3<f32>,
    reference: u32,
}

fn grid_scales(node: CompressedNode) -> vec3<f32> {
    let exponents = (vec3<u32>(node.exponents) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu);
    return bitcast<vec3<f32>>(exponents << vec3<u32>(23u));
}

fn compressed_child(node: CompressedNode, scale: vec3<f32>, slot: u32) -> CompressedChild {
    let half = slot / 4u;
    let shift = 8u * (slot % 4u);
    let m = (node.child_meta[half] >> shift) & 0xffu;
    var child: CompressedChild;
    child.reference = NO_HIT;
    if m == 0u {
        return child;
    }
    for (var a = 0u; a < 3u; a++) {
        child.lo[a] = fma(f32((node.q[2u * a][half] >> shift) & 0xffu), scale[a], node.origin[a]);
        child.hi[a] = fma(f32((node.q[2u * a + 1u][half] >> shift) & 0xffu), scale[a], node.origin[a]);
    }
    child.reference = node.child_base + (m & 7u);
    if (m & META_LEAF) != 0u {
        child.reference = LEAF_REF | (((m >> 4u) & 7u) << 28u) | (node.block_base + (m & 0xfu));
    }
    return child;
}

// Block i's vertices (v[k][a]: coordinate a of vertex k, a lane per
// primitive), and lane `lane`'s vertex k.
fn block_vertices(i: u32) -> array<array<vec4<f32>, 3>, 3> {
    var v: array<array<vec4<f32>, 3>, 3>;
    for (var k = 0u; k < 3u; k++) {
        for (var a = 0u; a < 3u; a++) {
            v[k][a] = block_lanes(i, k, a);
        }
    }
    return v;
}

fn lane_vertex(v: array<array<vec4<f32>, 3>, 3>, k: u32, lane: u32) -> vec3<f32> {
    return vec3<f32>(v[k][0][lane], v[k][1][lane], v[k][2][lane]);
}

// The nearest point of the triangles to p within squared distance max_d2
// (prim NO_HIT where none is), in the scene's local frame.
fn closest_point(p: vec3<f32>, max_d2: f32, margin: f32) -> ClosestPoint {
    var best = ClosestPoint(vec3<f32>(0.0), NO_HIT, 0.0, 0.0, max_d2, 0u);
    var bound = cull_bound(max_d2, margin);
    var stack: array<vec2<u32>, CLOSEST_STACK>;
    var sp = 0u;
    var current = 0u;
    loop {
        if (current & LEAF_REF) == 0u {
            let node = bvh_node_at(current);
            let scale = grid_scales(node);
            let base = sp;
            for (var slot = 0u; slot < 8u; slot++) {
                let child = compressed_child(node, scale, slot);
                if child.reference == NO_HIT {
                    continue;
                }
                let d2 = box_distance2(p, child.lo, child.hi);
                if d2 > bound {
                    continue;
                }
                // Nearest last (popped first).
                var j = sp;
                while j > base && bitcast<f32>(stack[j - 1u].y) < d2 {
                    stack[j] = stack[j - 1u];
                    j -= 1u;
                }
                stack[j] = vec2<u32>(child.reference, bitcast<u32>(d2));
                sp += 1u;
            }
        } else {
            let first = current & 0x0fffffffu;
            let count = ((current >> 28u) & 7u) + 1u;
            for (var i = first; i < first + count; i++) {
                let prims = block_prims(i);
                let v = block_vertices(i);
                for (var lane = 0u; lane < 4u; lane++) {
                    let prim = prims[lane];
                    if prim >= params.num_triangles {
                        continue;
                    }
                    let r = closest_point_triangle(p, lane_vertex(v, 0u, lane), lane_vertex(v, 1u, lane), lane_vertex(v, 2u, lane));
                    if better(r.d2, prim, best.distance, best.prim) {
                        best = ClosestPoint(r.q, prim, r.u, r.v, r.d2, 0u);
                        bound = cull_bound(r.d2, margin);
                    }
                }
            }
        }
        // The nearest entry still within the bound.
        var next = false;
        while sp > 0u {
            sp -= 1u;
            if bitcast<f32>(stack[sp].y) <= bound {
                current = stack[sp].x;
                next = true;
                break;
            }
        }
        if !next {
            break;
        }
    }
    if best.prim == NO_HIT {
        return ClosestPoint(vec3<f32>(0.0), NO_HIT, 0.0, 0.0, 0.0, 0u);
    }
    best.distance = sqrt(best.distance);
    return best;
}
