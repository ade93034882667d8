// Stage: the traversal the stages above call (`trace_closest` and
// `trace_any` in shaders/traverse.wgsl, and the ray-query entry point):
// the compressed BVH, or every primitive under `--accel brute-force`; and
// the crossing queries' `every_hit`.
// Under `--accel hardware` the module holds shaders/hardware_trace.wgsl's
// `trace` instead (src/shader_source.rs composes both). CPU twin:
// `trace` in src/cpu/traverse.rs.

fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    if is_nan_ray(ray_in) {
        return miss();
    }
    let prepared = prepare_ray(ray_in);
    var hit: Hit;
    if USE_BVH {
        hit = trace_compressed(prepared.ray, prepared.shear, any_hit);
    } else {
        hit = trace_brute_force(prepared.ray, prepared.shear, any_hit);
    }
    return unscale(hit, prepared.shear);
}

// Every crossing of a ray (the count and list queries' entry points):
// shaders/all_hits.wgsl's walk of the compressed BVH. CPU twin:
// `all_hits` in src/cpu/all_hits.rs.
fn every_hit(ray: Ray, index: u32, pad: f32, fill: bool, base: u32) -> u32 {
    return all_hits(ray, index, pad, fill, base);
}
