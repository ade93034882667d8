// Entry points: the wavefront render, its shadow rays in a dispatch of
// their own (gpu::ShadowDispatch): `render_primary`, `render_shadows`,
// `render_shade`, in that order, for `params.sample_begin` to
// `params.sample_end` of each tile pixel at once. The primary pass shades
// each hit but for its shadows, the shadow pass marks the blocked rays,
// and the shade pass adds up what each pixel kept: a surface is looked up
// and shaded once, where lavapipe ran all of `shade` for every pixel
// again, masked, in the last pass (1.10x faster, docs/bvh.md).
// Bindings (naga's reflection):
// `render_primary`: all of group 0 (0 to 17); group 1's out_color (its
// size), out_prim, wave_shading, shadow_queue, shadow_count,
// shadow_workgroups (1:0, 1:1, 1:7 to 1:10).
// `render_shadows`: group 0 but for triangle_normals, materials, lights,
// triangle_normals_hi and textures; group 1's shadow_queue,
// shadow_count (1:8, 1:9).
// `render_shade`: group 0's params; group 1's out_color, tile_sums,
// wave_shading, shadow_queue (1:0, 1:6 to 1:8).

// The number of a camera ray of the wavefront path: sample `sample` of
// the dispatch (0 for its first) of invocation `id`'s pixel, over the
// dispatch's grid (`groups` workgroups), so that a dispatch's rays are
// numbered densely from 0: its index in wave_shading.
fn wave_ray(id: vec3<u32>, groups: vec3<u32>, sample: u32) -> u32 {
    let columns = groups.x * RENDER_WORKGROUP_X;
    let rows = groups.y * RENDER_WORKGROUP_Y;
    return (sample * rows + id.y) * columns + id.x;
}

// `shade`'s work but for the shadow rays, which it queues, each with the
// term its light adds unless the ray is blocked: in light order, together
// (one atomic add for all of them), so `render_shade` sums what `shade`
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
        if light_sample(surface, origin, lights[i]).lit {
            out.count += 1u;
        }
    }
    if out.count == 0u {
        return out;
    }
    out.first = atomicAdd(&shadow_count[0], out.count);
    // `render_shadows` runs a workgroup for each WORKGROUP_INVOCATIONS
    // queued rays: one more for each multiple of it the rays reach.
    let started = (out.first + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    let reached = (out.first + out.count + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    if reached != started {
        atomicAdd(&shadow_workgroups[0], reached - started);
    }
    var q = out.first;
    for (var i = 0u; i < params.num_lights; i++) {
        let sample = light_sample(surface, origin, lights[i]);
        if sample.lit {
            let r = sample.shadow_ray;
            shadow_queue[q] = ShadowQuery(vec4<f32>(r.origin, r.tmin), vec4<f32>(r.dir, r.tmax),
                light_term(surface, sample), 0u);
            q += 1u;
        }
    }
    return out;
}

// Pass 1: a camera ray a sample (id.z) of each tile pixel, shaded but for
// its shadows, which it queues.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_primary(
    @builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let id = spread_invocation(group, groups, local, vec3<u32>(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y, 1u));
    stack_base = lane * STACK_ENTRIES;
    if tile_slot(id) == NO_HIT {
        return;
    }
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin + id.z));
    let hit = trace_closest(ray);
    // What the pixel's first sample hit.
    if params.sample_begin == 0u && id.z == 0u {
        textureStore(out_prim, id.xy, vec4<u32>(hit.prim, 0u, 0u, 0u));
    }
    wave_shading[wave_ray(id, groups, id.z)] = shade_but_shadows(ray, hit);
    report_cut_loops();
}

// Pass 2: the queued shadow rays, side by side, one an invocation,
// dispatched indirectly with as many workgroups as the queue fills
// (`shadow_workgroups`): a workgroup a camera ray's worth cost lavapipe
// about a tenth of the 1-spp dragon's render in empty workgroups.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_shadows(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    stack_base = lane * STACK_ENTRIES;
    if id.x >= atomicLoad(&shadow_count[0]) {
        return;
    }
    let o = shadow_queue[id.x].origin_tmin;
    let d = shadow_queue[id.x].dir_tmax;
    if trace_any(Ray(o.xyz, o.w, d.xyz, d.w)) {
        shadow_queue[id.x].blocked = 1u;
    }
    report_cut_loops();
}

// Pass 3: each tile pixel's samples in turn: what the primary pass kept,
// with the terms of its lights whose shadow rays were not blocked, added
// as `shade` adds them, and the samples added and written as `render`
// adds and writes them.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_shade(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y, 1u));
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    var sums = sums_so_far(slot);
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let kept = wave_shading[wave_ray(id, groups, sample - params.sample_begin)];
        var color = kept.color;
        for (var q = kept.first; q < kept.first + kept.count; q++) {
            if shadow_queue[q].blocked == 0u {
                color += shadow_queue[q].term;
            }
        }
        sums = add_sample(sums, color + kept.emission);
    }
    store_sums(id, slot, sums);
}
