// Entry points: the wavefront render, its shadow rays in a dispatch of
// their own (gpu::ShadowDispatch): `render_primary`, `render_shadows`,
// `render_shade`, in that order, for `params.sample_begin` to
// `params.sample_end` of each tile pixel at once.
// Bindings (naga's reflection):
// `render_primary`: all of group 0 (0 to 17, 20); group 1's out_color
// (its size), split_hits, shadow_queue, shadow_count, shadow_workgroups
// (1:0, 1:7 to 1:10).
// `render_shadows`: group 0 but for triangle_normals, materials, lights,
// triangle_normals_hi and textures; group 1's shadow_queue,
// shadow_count (1:8, 1:9).
// `render_shade`: group 0 but for loop_status; group 1's out_color,
// out_prim, tile_sums, split_hits (1:0, 1:1, 1:6, 1:7).

// The number of a camera ray of the wavefront path: sample `sample` of
// the dispatch (0 for its first) of invocation `id`'s pixel, over the
// dispatch's grid (`groups` workgroups), so that a dispatch's rays are
// numbered densely from 0: its index in split_hits, and times
// SHADOW_WORDS in shadow_blocked.
fn wave_ray(id: vec3<u32>, groups: vec3<u32>, sample: u32) -> u32 {
    let columns = groups.x * RENDER_WORKGROUP_X;
    let rows = groups.y * RENDER_WORKGROUP_Y;
    return (sample * rows + id.y) * columns + id.x;
}

// Pass 1: a camera ray a sample (id.z) of each tile pixel, its hit kept
// and its shadow rays queued.
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
    let index = wave_ray(id, groups, id.z);
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin + id.z));
    let hit = trace_closest(ray);
    split_hits[index] = hit;
    if hit.prim != NO_HIT && HAS_SHADOWS && params.shadows != 0u {
        let surface = surface_at(ray, hit);
        let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
        for (var w = 0u; w < SHADOW_WORDS; w++) {
            atomicStore(&shadow_blocked[index * SHADOW_WORDS + w], 0u);
        }
        for (var i = 0u; i < params.num_lights; i++) {
            let sample = light_sample(surface, origin, lights[i]);
            if sample.lit {
                let q = atomicAdd(&shadow_count[0], 1u);
                // A workgroup of `render_shadows` each so many rays.
                if q % WORKGROUP_INVOCATIONS == 0u {
                    atomicAdd(&shadow_workgroups[0], 1u);
                }
                shadow_queue[q] = ShadowQuery(index, i, vec2<u32>(0u), sample.shadow_ray);
            }
        }
    }
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
    let q = shadow_queue[id.x];
    if trace_any(q.ray) {
        atomicOr(&shadow_blocked[q.slot * SHADOW_WORDS + q.light / 32u], 1u << (q.light % 32u));
    }
    report_cut_loops();
}

// Pass 3: each tile pixel's samples shaded in turn from their hits and
// the shadows found, added and written as `render` adds and writes them.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_shade(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y, 1u));
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    let pixel = params.tile_origin + id.xy;
    var result = SampleSums(sums_so_far(slot), NO_HIT);
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let index = wave_ray(id, groups, sample - params.sample_begin);
        shade_blocked = index * SHADOW_WORDS;
        let hit = split_hits[index];
        if sample == params.sample_begin {
            result.prim = hit.prim;
        }
        let ray = camera_ray(sample_position(pixel, sample));
        result.sums = add_sample(result.sums, shade(ray, hit));
    }
    store_samples(id, slot, result);
}
