// Stage: every hit along a ray. crossing is the watertight test's
// arithmetic (intersect_triangle_watertight's: the same t, u, v) with the
// top-left rule (owns_edge) where the ray passes exactly through an edge or
// a vertex, so that each crossing counts once; the traversal enters every
// compressed box, grown by `pad` (enters_padded_box), that the ray meets in
// (tmin, tmax), tmax never shrunk. CPU twin: src/cpu/all_hits.rs (the CPU
// walks its own tree; the set of crossings is the same, sorted by the host).

// One crossing (src/layout.rs ListedHit).
struct ListedHit {
    ray: u32,
    prim: u32,
    t: f32,
    u: f32,
    v: f32,
}

fn owns_edge(dx: f32, dy: f32, det: f32) -> bool {
    var x = dx;
    var y = dy;
    if det < 0.0 {
        x = -dx;
        y = -dy;
    }
    return y > 0.0 || (y == 0.0 && x < 0.0);
}

// (t, u, v) of the crossing, t = FAR where there is none.
fn crossing(ray: Ray, shear: Shear, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    return watertight_test(ray, shear, a, b, c, true);
}

fn enters_padded_box(ray: Ray, inv_dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>, pad: f32) -> bool {
    let t0 = (lo - vec3<f32>(pad) - ray.origin) * inv_dir;
    let t1 = (hi + vec3<f32>(pad) - ray.origin) * inv_dir;
    let lower = min(t0, t1);
    let upper = max(t0, t1);
    let near = max(max(max(lower.x, lower.y), lower.z), ray.tmin);
    let far = min(min(min(upper.x, upper.y), upper.z), ray.tmax);
    return near <= far;
}

// Every crossing of `ray_in` (ray `index` of the query) with a triangle in
// (tmin, tmax): counted, and with `fill`, written to listed_hits from
// `base`. The ray is prepared as `trace` prepares it (the CPU's
// prepare_ray).
fn all_hits(ray_in: Ray, index: u32, pad: f32, fill: bool, base: u32) -> u32 {
    var ray = ray_in;
    let m = abs(ray.dir);
    let scale = direction_scale(max(max(m.x, m.y), m.z));
    ray.dir *= scale.x;
    ray.tmin *= scale.y;
    ray.tmax *= scale.y;
    ray.tmax = select(FAR, ray.tmax, ray.tmax < FAR);
    let shear = ray_shear(ray.dir);
    let sign_bits = bitcast<vec3<u32>>(ray.dir) & vec3<u32>(0x80000000u);
    let tiny = bitcast<vec3<f32>>(vec3<u32>(bitcast<u32>(MIN_SLAB_DIR)) | sign_bits);
    let inv_dir = 1.0 / select(ray.dir, tiny, abs(ray.dir) < vec3<f32>(MIN_SLAB_DIR));
    var count = 0u;
    // Zero-initialised: entry 0 is the root.
    var stack: array<u32, CLOSEST_STACK>;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let current = stack[sp];
        if (current & LEAF_REF) == 0u {
            let node = bvh_node_at(current);
            let grid = grid_scales(node);
            for (var slot = 0u; slot < 8u; slot++) {
                let child = compressed_child(node, grid, slot);
                if child.reference != NO_HIT && enters_padded_box(ray, inv_dir, child.lo, child.hi, pad) {
                    stack[sp] = child.reference;
                    sp += 1u;
                }
            }
            continue;
        }
        let first = current & 0x0fffffffu;
        let blocks = ((current >> 28u) & 7u) + 1u;
        for (var i = first; i < first + blocks; i++) {
            let prims = block_prims(i);
            let v = block_vertices(i);
            for (var lane = 0u; lane < 4u; lane++) {
                let prim = prims[lane];
                if prim >= params.num_triangles {
                    continue;
                }
                let h = crossing(ray, shear, lane_vertex(v, 0u, lane), lane_vertex(v, 1u, lane), lane_vertex(v, 2u, lane));
                if h.x < FAR {
                    if fill {
                        listed_hits[base + count] = ListedHit(index, prim, h.x * scale.x, h.y, h.z);
                    }
                    count += 1u;
                }
            }
        }
    }
    return count;
}
