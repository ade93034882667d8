// Entry points: the wavefront render, its shadow rays in a dispatch of
// their own (gpu::ShadowDispatch): `render_primary` (or
// `render_primary_samples`, or over a pixel list `render_list_primary`),
// `render_shadows`, `render_resolve`, in that order, for
// `params.sample_begin` to `params.sample_end` of each tile (or listed)
// pixel, in one submission. The primary
// pass shades each hit but for its shadows and queues them, and finishes
// the pixels none of whose samples queued any; the shadow pass marks the
// blocked rays; the last pass adds up what each listed pixel kept. A
// surface is looked up and shaded once (lavapipe runs all of a branch for
// every lane, masked, so a pass that shaded again cost what shading every
// pixel costs), and the last pass runs for the listed pixels only
// (docs/bvh.md).
// Bindings (naga's reflection):
// `render_primary`, `render_primary_samples`: all of group 0;
// group 1's out_prim, tile_sums, wave_shading, shadow_queue, wave_counts,
// wave_workgroups, resolve_pixels (1:1, 1:6 to 1:10, 1:19).
// `render_list_primary`: the same but out_prim, and pixel_list (1:4).
// `render_shadows`: group 0's params, arrays, scene words and texels;
// group 1's shadow_queue, wave_counts (1:8, 1:9).
// `render_resolve`: group 0's params; group 1's tile_sums, wave_shading,
// shadow_queue, wave_counts, resolve_pixels (1:6 to 1:9, 1:19).

// Takes `n` items of wavefront list `list` (0: shadow rays, 1: pixels to
// resolve); returns the first. The list's pass runs a workgroup for each
// WORKGROUP_INVOCATIONS items: one more for each multiple of it the items
// reach.
fn enqueue(list: u32, n: u32) -> u32 {
    let first = atomicAdd(&wave_counts[list], n);
    let started = (first + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    let reached = (first + n + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    if reached != started {
        atomicAdd(&wave_workgroups[3u * list], reached - started);
    }
    return first;
}

// A camera ray's kept shading, `wave_shading[i]`, as two words.
fn store_wave_shading(i: u32, kept: WaveShading) {
    wave_shading[i] = array<vec4<u32>, 2>(vec4<u32>(bitcast<vec3<u32>>(kept.color), kept.first),
        vec4<u32>(bitcast<vec3<u32>>(kept.emission), kept.count));
}

fn wave_shading_at(i: u32) -> WaveShading {
    let w = wave_shading[i];
    return WaveShading(bitcast<vec3<f32>>(w[0].xyz), w[0].w, bitcast<vec3<f32>>(w[1].xyz), w[1].w);
}

// Queued shadow ray q, as three words (`term` and `blocked` the last).
fn store_shadow_query(q: u32, query: ShadowQuery) {
    shadow_queue[q] = array<vec4<u32>, 3>(bitcast<vec4<u32>>(query.origin_tmin),
        bitcast<vec4<u32>>(query.dir_tmax), vec4<u32>(bitcast<vec3<u32>>(query.term), query.blocked));
}

// `resolved_color` of a camera ray that queued no shadow ray, without
// its loop over the queue, which lavapipe would run, masked, all the same.
fn unshadowed_color(kept: WaveShading) -> vec3<f32> {
    return kept.color + kept.emission;
}

// The colour a camera ray's shading kept, with the terms of its lights
// whose shadow rays were not blocked, added as `shade` adds them.
fn resolved_color(kept: WaveShading) -> vec3<f32> {
    var color = kept.color;
    for (var q = kept.first; q < kept.first + kept.count; q++) {
        let term_blocked = shadow_queue[q][2];
        if term_blocked.w == 0u {
            color += bitcast<vec3<f32>>(term_blocked.xyz);
        }
    }
    return color + kept.emission;
}

// `shade`'s work but for the shadow rays, which it queues, each with the
// term its light adds unless the ray is blocked: in light order, together
// (one atomic add for all of them), so `resolved_color` sums what `shade`
// sums in its order.
fn shade_but_shadows(ray: Ray, hit: Hit) -> WaveShading {
    // A miss: the background plus −0, which leaves every value's bits as
    // they are (+0 would turn a −0 into +0).
    var out = WaveShading(params.background, 0u, vec3<f32>(bitcast<f32>(0x80000000u)), 0u);
    if hit.prim == NO_HIT {
        return out;
    }
    let surface = surface_at(ray, hit);
    out.color = rounded3(params.ambient * surface.albedo);
    out.emission = rounded3(surface.emission);
    let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
    // Counted first, sampled again below: lights are cheap to sample, and
    // a camera ray's shadow rays then take one atomic add.
    for (var i = 0u; i < params.num_lights; i++) {
        if light_sample(surface, origin, light_at(i)).lit {
            out.count += 1u;
        }
    }
    if out.count == 0u {
        return out;
    }
    out.first = enqueue(0u, out.count);
    var q = out.first;
    for (var i = 0u; i < params.num_lights; i++) {
        let sample = light_sample(surface, origin, light_at(i));
        if sample.lit {
            let r = sample.shadow_ray;
            store_shadow_query(q, ShadowQuery(vec4<f32>(r.origin, r.tmin),
                vec4<f32>(r.dir, r.tmax), light_term(surface, sample), 0u));
            q += 1u;
        }
    }
    return out;
}

// Sample `sample` of `pixel` (at `slot`): its camera ray traced and
// shaded but for its shadows, which it queues; with `store_prim` (a
// tile's, not a pixel list's), the primitive stored from its first sample.
fn primary_sample(pixel: vec2<u32>, slot: u32, sample: u32, store_prim: bool) -> WaveShading {
    let ray = camera_ray(sample_position(pixel, sample));
    let hit = trace_closest(ray);
    if store_prim && sample == 0u {
        out_prim[slot] = hit.prim;
    }
    return shade_but_shadows(ray, hit);
}

// Lists the pixel at `slot` for `render_resolve` from sample `sample` on;
// returns its place in the list. Its sums before that sample are in
// `tile_sums` (`sums_before_kept`).
fn list_pixel(slot: u32, sample: u32) -> u32 {
    let listed = enqueue(1u, 1u);
    resolve_pixels[listed] = vec2<u32>(slot, sample);
    return listed;
}

// A listed pixel's sums before its first kept sample `first`: those of
// the dispatches before (none before the first), unless samples of this
// one came before it, whose sums the pixel stored when listed.
fn sums_before_kept(slot: u32, first: u32) -> vec4<f32> {
    if first == params.sample_begin {
        return sums_so_far(slot);
    }
    return tile_sums[slot];
}

// Pass 1 of a dispatch of one sample a pixel: the pixel finished if its
// sample queued no shadow ray, else listed with its shading kept.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_primary(
    @builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let pixel = tile_pixel(group, local, lane);
    let slot = pixel.z;
    if slot == NO_HIT {
        return;
    }
    let kept = primary_sample(pixel.xy, slot, params.sample_begin, true);
    if kept.count == 0u {
        store_sums(slot, add_sample(sums_so_far(slot), unshadowed_color(kept)));
    } else {
        store_wave_shading(list_pixel(slot, params.sample_begin), kept);
    }
    report_cut_loops();
}

// Pass 1 of a dispatch of several samples of `pixel` (at `slot`), in
// turn, as `add_samples` takes them. While none has queued a shadow ray
// the pixel's sums grow here, as `add_samples` grows them; from the first
// that has, the samples' shading is kept (the nth listed pixel's from
// n · samples) and the pixel listed. A loop over the samples rather than
// an invocation a sample: each sample then does not pay an invocation's
// fixed work, which made this 1.04–1.13× the megakernel's time at 4 to
// 64 spp; the loop around the trace costs one sample's pass a fifth more
// on lavapipe, hence `render_primary` (docs/bvh.md).
fn primary_samples(pixel: vec2<u32>, slot: u32, store_prim: bool) {
    let samples = params.sample_end - params.sample_begin;
    var sums = sums_so_far(slot);
    var listed = NO_HIT;
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let kept = primary_sample(pixel, slot, sample, store_prim);
        if listed == NO_HIT {
            if kept.count == 0u {
                sums = add_sample(sums, unshadowed_color(kept));
                continue;
            }
            listed = list_pixel(slot, sample);
            if sample != params.sample_begin {
                tile_sums[slot] = sums;
            }
        }
        store_wave_shading(listed * samples + sample - params.sample_begin, kept);
    }
    if listed == NO_HIT {
        store_sums(slot, sums);
    }
    report_cut_loops();
}

// Pass 1 of a tile's dispatch of several samples a pixel.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_primary_samples(
    @builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let pixel = tile_pixel(group, local, lane);
    if pixel.z == NO_HIT {
        return;
    }
    primary_samples(pixel.xy, pixel.z, true);
}

// Pass 1 over a list of pixels (adaptive sampling's later passes, as
// `render_pixel_list` renders them): `params.spp` more samples of each,
// in parts, its sums and then its mean in `tile_sums` (bound to the
// list's results) at its place in `pixel_list`.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_list_primary(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let slot = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u)).x;
    stack_base = lane * STACK_ENTRIES;
    if slot >= arrayLength(&pixel_list) {
        return;
    }
    primary_samples(pixel_list[slot], slot, false);
}

// Pass 2: the queued shadow rays, side by side, one an invocation,
// dispatched indirectly with as many workgroups as the queue fills
// (`wave_workgroups`): a workgroup a camera ray's worth cost lavapipe
// about a tenth of the 1-spp dragon's render in empty workgroups.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_shadows(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    stack_base = lane * STACK_ENTRIES;
    if id.x >= atomicLoad(&wave_counts[0]) {
        return;
    }
    let o = bitcast<vec4<f32>>(shadow_queue[id.x][0]);
    let d = bitcast<vec4<f32>>(shadow_queue[id.x][1]);
    if trace_any(Ray(o.xyz, o.w, d.xyz, d.w)) {
        shadow_queue[id.x][2].w = 1u;
    }
    report_cut_loops();
}

// Pass 3: the listed pixels, dispatched indirectly (`wave_workgroups` 3
// to 5): from their sums so far, their kept samples resolved in turn,
// added and written as `render` adds and writes them.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_resolve(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let n = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u)).x;
    if n >= atomicLoad(&wave_counts[1]) {
        return;
    }
    let listed = resolve_pixels[n];
    let slot = listed.x;
    let samples = params.sample_end - params.sample_begin;
    var sums = sums_before_kept(slot, listed.y);
    for (var sample = listed.y; sample < params.sample_end; sample++) {
        let kept = wave_shading_at(n * samples + sample - params.sample_begin);
        sums = add_sample(sums, resolved_color(kept));
    }
    store_sums(slot, sums);
}
