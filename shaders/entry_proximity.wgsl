// Entry points: the geometric queries (closest points, winding numbers,
// every hit along rays), one point or ray per invocation, in the scene's
// local frame. Bindings: group 0 (the scene: params, its words
// with the triangles and the BVH's nodes and blocks, or its texels) and group
// 1's PROXIMITY table (src/gpu/bindings.rs): each entry point reads and
// writes those named in its comment.

// Points (xyz) with their cull margin (w; the CPU's query_margin).
@group(1) @binding(11) var<storage, read> query_points: array<vec4<f32>>;
// x: the squared max distance of closest_points; y: the box pad of the
// all-hits traversal (the CPU's box_pad).
@group(1) @binding(12) var<storage, read> query_scalars: array<vec4<f32>, 1>;
@group(1) @binding(13) var<storage, read_write> closest_out: array<ClosestPoint>;
@group(1) @binding(14) var<storage, read_write> winding_out: array<f32>;
@group(1) @binding(15) var<storage, read> winding_nodes: array<WindingNode>;
@group(1) @binding(16) var<storage, read> winding_prims: array<u32>;
// count_hits writes each ray's count; list_hits reads each ray's first slot.
@group(1) @binding(17) var<storage, read_write> hit_counts: array<u32>;
@group(1) @binding(18) var<storage, read_write> listed_hits: array<ListedHit>;

// query_points, query_scalars → closest_out.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn closest_points(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    if id.x >= arrayLength(&closest_out) {
        return;
    }
    let q = query_points[id.x];
    closest_out[id.x] = closest_point(q.xyz, query_scalars[0].x, q.w);
    report_cut_loops();
}

// query_points, winding_nodes, winding_prims → winding_out.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn winding_numbers(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    if id.x >= arrayLength(&winding_out) {
        return;
    }
    winding_out[id.x] = winding_number(query_points[id.x].xyz);
    report_cut_loops();
}

// rays, query_scalars → hit_counts.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn count_hits(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    if id.x >= arrayLength(&rays) {
        return;
    }
    hit_counts[id.x] = every_hit(rays[id.x], id.x, query_scalars[0].y, false, 0u);
    report_cut_loops();
}

// rays, query_scalars, hit_counts (each ray's first slot) → listed_hits.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn list_hits(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    if id.x >= arrayLength(&rays) {
        return;
    }
    every_hit(rays[id.x], id.x, query_scalars[0].y, true, hit_counts[id.x]);
    report_cut_loops();
}
