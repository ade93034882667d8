// Entry point: `probe_lights`, the lights stage's functions on a list of
// queries, one per invocation: what tests compare with the CPU twin
// (`GpuRenderer::probe_lights`; tests/lights_gpu.rs). Bindings: group 0's
// lights and what they read; group 1's queries (read) and answers
// (written), 1:20 and 1:21.

// One query: `sample_emitter(position, normal, u_pick, u)`, and
// `environment_radiance`, `environment_pdf` and
// `emitter_pdf(position, hit_prim, dir, distance)` of `dir`.
struct LightQuery {
    position: vec3<f32>,
    u_pick: f32,
    normal: vec3<f32>,
    hit_prim: u32,
    dir: vec3<f32>,
    distance: f32,
    u: vec2<f32>,
    _pad: vec2<u32>,
}

// Its answers: the sample's fields (`delta` 1 or 0), then the others.
struct LightAnswer {
    wi: vec3<f32>,
    distance: f32,
    radiance: vec3<f32>,
    pdf: f32,
    environment: vec3<f32>,
    environment_pdf: f32,
    emitter_pdf: f32,
    delta: u32,
    _pad: vec2<u32>,
}

@group(1) @binding(20) var<storage, read> light_queries: array<LightQuery>;
@group(1) @binding(21) var<storage, read_write> light_answers: array<LightAnswer>;

@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn probe_lights(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let id = spread_invocation(group, groups, local, vec3<u32>(WORKGROUP_INVOCATIONS, 1u, 1u));
    if id.x >= arrayLength(&light_queries) {
        return;
    }
    let q = light_queries[id.x];
    let s = sample_emitter(q.position, q.normal, q.u_pick, q.u);
    light_answers[id.x] = LightAnswer(s.wi, s.distance, s.radiance, s.pdf,
        environment_radiance(q.dir), environment_pdf(q.dir),
        emitter_pdf(q.position, q.hit_prim, q.dir, q.distance), u32(s.delta), vec2<u32>(0u));
}
