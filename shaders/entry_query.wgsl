// Entry point: a ray query (`lambert trace`, the Python binding):
// `trace_rays`, one ray per invocation, closest hit or (ANY_HIT) any.
// Bindings: group 0's params, the scene's geometry and BVH (buffers and
// textures) and loop_status; group 1's rays (read) and hits (written).

// One ray of a `lambert trace` batch. Misses leave t = FAR, prim = NO_HIT.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn trace_rays(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    if id.x >= arrayLength(&rays) {
        return;
    }
    hits[id.x] = trace(rays[id.x], ANY_HIT);
    report_cut_loops();
}
