// Stage: the traversal the stages above call (`trace_closest` and
// `trace_any` in shaders/traverse.wgsl, and the ray-query entry point):
// the compressed BVH, or every primitive under `--accel brute-force`.
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
