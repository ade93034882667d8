// Stage: winding numbers. The solid angle of a triangle (Van Oosterom and
// Strackee) with an arctangent of plain arithmetic (approx_atan2 in
// math.wgsl: both paths give the same bits, where a library's atan2 would
// not), the far field of a winding-tree node (its dipole, first order) and
// the walk of the tree in one fixed order, its rounding errors carried
// (winding_sum), so that the sum is the CPU's bit for bit. CPU twin:
// src/cpu/winding.rs.

// One node of the winding tree (src/layout.rs WindingNode).
struct WindingNode {
    centre: vec3<f32>,
    radius: f32,
    normal: vec3<f32>,
    first_child: u32,
    child_count: u32,
    first_prim: u32,
    prim_count: u32,
    _pad: u32,
}

const WINDING_BETA: f32 = 6.0;
const WINDING_STACK: u32 = 7u * MAX_DEPTH + 1u;
// The twin's f32 constant, bit for bit: a suffixed literal, written as
// Rust prints it (the shortest that reads back as the same f32).
const INV_FOUR_PI: f32 = 0.07957747f;

// x, as a value no compiler can see is x (params.canary_loops is 2, so the
// mask is 0). Mesa factors a·c + b·c into (a + b)·c, the operations not
// being marked exact, which rounds otherwise than the CPU: a term given
// this copy of c shares no operand with the other.
fn opaque_copy(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) | (params.canary_loops >> 8u));
}

fn triangle_winding(q: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let qa = a - q;
    let qb = b - q;
    let qc = c - q;
    let la = sqrt(dot3(qa, qa));
    let lb = sqrt(dot3(qb, qb));
    let lc = sqrt(dot3(qc, qc));
    let cross = vec3<f32>(
        qb.y * qc.z - qb.z * qc.y,
        qb.z * qc.x - qb.x * qc.z,
        qb.x * qc.y - qb.y * qc.x,
    );
    let det = dot3(qa, cross);
    let den = la * lb * lc + dot3(qa, qb) * opaque_copy(lc) + dot3(qa, qc) * lb + dot3(qb, qc) * la;
    return approx_atan2(det, den) * INV_TWO_PI;
}

fn dipole_winding(q: vec3<f32>, centre: vec3<f32>, normal: vec3<f32>) -> f32 {
    let d = centre - q;
    let r2 = dot3(d, d);
    let r = sqrt(r2);
    return dot3(normal, d) / (r2 * r) * INV_FOUR_PI;
}

// a + b and its rounding error: two_sum, whose opaque_one is 0 in a scene
// without spheres (a winding query's), with opaque copies instead, so that
// no compiler rewrites (a + b) - a as b.
fn winding_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    let bb = s - opaque_copy(a);
    let aa = s - opaque_copy(bb);
    return vec2<f32>(s, (a - aa) + (b - bb));
}

fn winding_number(q: vec3<f32>) -> f32 {
    var w = 0.0;
    var error = 0.0;
    // Zero-initialised: entry 0 is the root.
    var stack: array<u32, WINDING_STACK>;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let node = winding_nodes[stack[sp]];
        let d = node.centre - q;
        let reach = WINDING_BETA * node.radius;
        if dot3(d, d) > reach * reach {
            let sum = winding_sum(w, dipole_winding(q, node.centre, node.normal));
            w = sum.x;
            error += sum.y;
            continue;
        }
        for (var i = node.first_prim; i < node.first_prim + node.prim_count; i++) {
            let t = triangle_at(winding_prims[i]);
            let sum = winding_sum(w, triangle_winding(q, t.v0, t.v1, t.v2));
            w = sum.x;
            error += sum.y;
        }
        for (var child = node.first_child; child < node.first_child + node.child_count; child++) {
            stack[sp] = child;
            sp += 1u;
        }
    }
    return w + error;
}
