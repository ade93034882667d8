// Entry points: the path integrator's wavefront (gpu::ShadowDispatch under
// PATH_TRACE), in one submission a dispatch: `path_begin` (or
// `path_list_begin` over a pixel list) traces the camera rays of
// `params.sample_begin` to `params.sample_end` of each pixel; then, a
// bounce at a time, `path_shade` (a `path_vertex` of each live path: its
// emission, its light sample's shadow ray queued, its next direction or
// its end, the paths that go on appended to the next queue),
// `path_shadows` (the queued shadow rays: what each unblocked one's light
// adds), `path_extend` (the closest hit of each path that went on), each
// over as many workgroups as `path_advance` counted; last `path_resolve`
// (or `path_list_resolve`) adds each pixel's samples as `add_samples`
// does. A path draws its random numbers and adds its terms in the
// megakernel's order (`path_radiance`), so the image is the megakernel's.
// Bindings (naga's reflection): group 0 as the megakernel's (the extend
// and shadow passes only the scene's geometry); group 1 as
// gpu::bindings::PATH_WAVE lists.

// The path at `p` of `path_records` and the hit its ray found.
fn path_record_at(p: u32) -> PathState {
    let r = path_records[p];
    return PathState(Ray(r.origin, 0.0, r.dir, FAR), r.throughput, r.radiance, r.state,
        r.bsdf_pdf_before, r.origin_before, r.depth);
}

fn path_hit_at(p: u32) -> Hit {
    let r = path_records[p];
    return Hit(r.hit_t, r.hit_prim, r.hit_uv.x, r.hit_uv.y);
}

fn store_path(p: u32, path: PathState, hit: Hit) {
    path_records[p] = PathRecord(path.ray.origin, path.state, path.ray.dir, path.bsdf_pdf_before,
        path.throughput, path.depth, path.radiance, hit.t, path.origin_before, hit.prim,
        vec2<f32>(hit.u, hit.v));
}

// The camera rays of samples `params.sample_begin` to `params.sample_end`
// of `pixel`, the `index`th pixel of the dispatch: each one's path at
// index · samples + its sample's place, queued for the first bounce with
// one atomic add. With `store_prim`, the first sample's primitive stored
// at `slot`.
fn begin_paths(pixel: vec2<u32>, index: u32, slot: u32, store_prim: bool) {
    let samples = params.sample_end - params.sample_begin;
    let first = atomicAdd(&path_counts[0], samples);
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let ray = camera_ray(sample_position(pixel, sample));
        let hit = trace_closest(ray);
        if store_prim && sample == 0u {
            out_prim[slot] = hit.prim;
        }
        let p = index * samples + sample - params.sample_begin;
        store_path(p, path_start(ray, path_seed(pixel.x, pixel.y, sample, params.seed)), hit);
        append_path(first + sample - params.sample_begin, p);
    }
    report_cut_loops();
}

// The `n`th live path, and the `n`th place of the half of `path_queues`
// that the live paths append to.
fn live_path(n: u32) -> u32 {
    return path_queues[atomicLoad(&path_counts[4]) * (arrayLength(&path_queues) / 2u) + n];
}

fn append_path(n: u32, p: u32) {
    path_queues[(1u - atomicLoad(&path_counts[4])) * (arrayLength(&path_queues) / 2u) + n] = p;
}

// A tile pixel's place among the dispatch's pixels (row by row).
fn tile_index(pixel: vec2<u32>) -> u32 {
    let local = pixel - params.tile_origin;
    return local.y * params.tile_size.x + local.x;
}

@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn path_begin(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let pixel = tile_pixel(group, local, lane);
    if pixel.z == NO_HIT {
        return;
    }
    begin_paths(pixel.xy, tile_index(pixel.xy), pixel.z, true);
}

// Over a pixel list (adaptive sampling's later passes): the pixel at
// `slot` of `pixel_list`.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn path_list_begin(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let slot = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u)).x;
    stack_base = lane * STACK_ENTRIES;
    if slot >= arrayLength(&pixel_list) {
        return;
    }
    begin_paths(pixel_list[slot], slot, slot, false);
}

// Between passes, one invocation: what was appended becomes what the next
// passes take, and their workgroups (the half of `path_queues` appended to
// the live one); the appends start again from 0.
@compute @workgroup_size(1)
fn path_advance() {
    let paths = atomicExchange(&path_counts[0], 0u);
    let shadows = atomicExchange(&path_counts[1], 0u);
    atomicStore(&path_counts[2], paths);
    atomicStore(&path_counts[3], shadows);
    atomicStore(&path_counts[4], 1u - atomicLoad(&path_counts[4]));
    path_workgroups[0] = (paths + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    path_workgroups[3] = (shadows + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
}

// The `n`th item of an indirect pass over `count` items, or NO_HIT past
// them; its traversal stack placed.
fn queued_item(group: vec3<u32>, groups: vec3<u32>, local: vec3<u32>, lane: u32, count: u32) -> u32 {
    let n = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u)).x;
    stack_base = lane * STACK_ENTRIES;
    return select(NO_HIT, n, n < count);
}

// A vertex of each live path: its light sample's shadow ray queued (its
// term added here where the render has no shadows, as `light_reaches`
// adds it), and the path appended to the next queue if it goes on.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn path_shade(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = queued_item(group, groups, local, lane, atomicLoad(&path_counts[2]));
    if n == NO_HIT {
        return;
    }
    let p = live_path(n);
    var path = path_record_at(p);
    let hit = path_hit_at(p);
    let step = path_vertex(&path, hit);
    if step.lit {
        if params.shadows == 0u {
            path.radiance += step.term;
        } else {
            let r = step.shadow;
            store_shadow_query(atomicAdd(&path_counts[1], 1u), ShadowQuery(vec4<f32>(r.origin, r.tmin),
                vec4<f32>(r.dir, r.tmax), step.term, p));
        }
    }
    if step.goes_on {
        append_path(atomicAdd(&path_counts[0], 1u), p);
    }
    store_path(p, path, hit);
    report_cut_loops();
}

// The queued shadow rays, one an invocation: an unblocked one's term added
// to its path (the `blocked` word of its query).
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn path_shadows(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = queued_item(group, groups, local, lane, atomicLoad(&path_counts[3]));
    if n == NO_HIT {
        return;
    }
    let o = bitcast<vec4<f32>>(shadow_queue[n][0]);
    let d = bitcast<vec4<f32>>(shadow_queue[n][1]);
    if !trace_any(Ray(o.xyz, o.w, d.xyz, d.w)) {
        let term_path = shadow_queue[n][2];
        let p = term_path.w;
        path_records[p].radiance += bitcast<vec3<f32>>(term_path.xyz);
    }
    report_cut_loops();
}

// The closest hit of each path that went on.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn path_extend(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = queued_item(group, groups, local, lane, atomicLoad(&path_counts[2]));
    if n == NO_HIT {
        return;
    }
    let p = live_path(n);
    let r = path_records[p];
    let hit = trace_closest(Ray(r.origin, 0.0, r.dir, FAR));
    path_records[p].hit_t = hit.t;
    path_records[p].hit_prim = hit.prim;
    path_records[p].hit_uv = vec2<f32>(hit.u, hit.v);
    report_cut_loops();
}

// The `index`th pixel's paths, added in sample order to its sums as
// `add_samples` adds them, stored at `slot`.
fn resolve_paths(index: u32, slot: u32) {
    let samples = params.sample_end - params.sample_begin;
    var sums = sums_so_far(slot);
    for (var s = 0u; s < samples; s++) {
        sums = add_sample(sums, path_records[index * samples + s].radiance);
    }
    store_sums(slot, sums);
}

@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn path_resolve(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let pixel = tile_pixel(group, local, lane);
    if pixel.z == NO_HIT {
        return;
    }
    resolve_paths(tile_index(pixel.xy), pixel.z);
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn path_list_resolve(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let slot = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u)).x;
    if slot >= arrayLength(&pixel_list) {
        return;
    }
    resolve_paths(slot, slot);
}
