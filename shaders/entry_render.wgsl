// Entry points: the render megakernel, every sample of a pixel in one
// invocation (`render`), and adaptive sampling's later passes over a list
// of pixels (`render_pixel_list`).
// Bindings (naga's reflection): both use all of group 0. Group 1:
// `render` writes out_prim and tile_sums (the sums between its
// dispatches, the means after the last); `render_pixel_list` reads
// pixel_list and writes pixel_results.

@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let pixel = tile_pixel(group, local, lane);
    if pixel.z == NO_HIT {
        return;
    }
    store_samples(pixel.z, add_samples(pixel.xy, sums_so_far(pixel.z)));
    report_cut_loops();
}

// Adaptive sampling's later passes: `params.spp` more samples (seeded by
// `params.seed`) for each listed pixel, in parts as `render` adds them.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_pixel_list(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    stack_base = lane * STACK_ENTRIES;
    if id.x >= arrayLength(&pixel_list) {
        return;
    }
    var sums = vec4<f32>(0.0);
    if params.sample_begin > 0u {
        sums = pixel_results[id.x];
    }
    let result = add_samples(pixel_list[id.x], sums);
    if params.sample_end == params.spp {
        pixel_results[id.x] = pixel_mean(result.sums);
    } else {
        pixel_results[id.x] = result.sums;
    }
    report_cut_loops();
}
