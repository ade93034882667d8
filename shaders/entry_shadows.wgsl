// Entry points: a render with the shadow rays in a dispatch of their own
// (gpu::ShadowDispatch): `render_primary`, `render_shadows`,
// `render_shade`, in that order.
// Bindings (naga's reflection):
// `render_primary`: all of group 0 (0 to 14); group 1's out_color (its
// size), split_hits, shadow_queue, shadow_count, shadow_blocked (1:0,
// 1:7 to 1:10).
// `render_shadows`: group 0 but for triangle_normals, materials, lights
// and triangle_normals_hi (0:0, 0:1, 0:3, 0:6 to 0:8, 0:10 to 0:14);
// group 1's shadow_queue, shadow_count, shadow_blocked (1:8 to 1:10).
// `render_shade`: group 0 but for loop_status (0:0 to 0:11, 0:13, 0:14);
// group 1's out_color, out_prim, split_hits, shadow_blocked (1:0, 1:1,
// 1:7, 1:10).

// Shadow rays apart, pass 1: the pixel's primary hit (its one sample),
// and its shadow rays queued.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_primary(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin));
    let hit = trace_closest(ray);
    split_hits[slot] = hit;
    if hit.prim != NO_HIT && HAS_SHADOWS && params.shadows != 0u {
        let surface = surface_at(ray, hit);
        let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
        atomicStore(&shadow_blocked[slot], 0u);
        for (var i = 0u; i < params.num_lights; i++) {
            let sample = light_sample(surface, origin, lights[i]);
            if sample.lit {
                let q = atomicAdd(&shadow_count[0], 1u);
                shadow_queue[q] = ShadowQuery(slot, i, vec2<u32>(0u), sample.shadow_ray);
            }
        }
    }
    report_cut_loops();
}

// Pass 2: the queued shadow rays, side by side (as many invocations as
// the tile has pixels, each taking every so many: at most as many shadow
// rays as a `render` invocation traces).
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_shadows(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    stack_base = lane * STACK_ENTRIES;
    let count = atomicLoad(&shadow_count[0]);
    let stride = groups.x * WORKGROUP_INVOCATIONS;
    for (var i = id.x; i < count; i += stride) {
        let q = shadow_queue[i];
        if trace_any(q.ray) {
            atomicOr(&shadow_blocked[q.slot], 1u << q.light);
        }
    }
    report_cut_loops();
}

// Pass 3: shading from the hit and the shadows found (renders of one
// sample per pixel: gpu::GpuRenderer::shadows_apart), written as `render`
// writes its one sample.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    shade_blocked = atomicLoad(&shadow_blocked[slot]);
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin));
    let hit = split_hits[slot];
    let color = shade(ray, hit);
    let y = dot(color, LUMINANCE);
    textureStore(out_prim, id.xy, vec4<u32>(hit.prim, 0u, 0u, 0u));
    textureStore(out_color, id.xy, pixel_mean(vec4<f32>(color, y * y)));
}
