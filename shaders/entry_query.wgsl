// Entry point: a ray query (`lambert trace`, the Python binding):
// `trace_rays`, one ray per invocation, closest hit or (ANY_HIT) any.
// Bindings (naga's reflection): group 0 (the scene's words and texels);
// group 1's rays (read) and hits (written), 1:2 and 1:3.

// One ray of a `lambert trace` batch. Misses leave t = FAR, prim = NO_HIT.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn trace_rays(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    stack_base = lane * STACK_ENTRIES;
    if id.x >= arrayLength(&rays) {
        return;
    }
    hits[id.x] = trace(rays[id.x], ANY_HIT);
    report_cut_loops();
}
