// STAND-IN (the lead's scratch, replaced by the lights engineer's at merge).
struct EmitterSample { wi: vec3<f32>, distance: f32, radiance: vec3<f32>, pdf: f32, delta: bool }
fn sample_emitter(position: vec3<f32>, normal: vec3<f32>, u_pick: f32, u: vec2<f32>) -> EmitterSample {
    return EmitterSample(vec3<f32>(0.0, 0.0, 1.0), FAR, vec3<f32>(0.0), 0.0, false);
}
fn emitter_pdf(position: vec3<f32>, hit_prim: u32, wi: vec3<f32>, distance: f32) -> f32 { return 0.0; }
fn environment_radiance(dir: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0); }
fn environment_pdf(dir: vec3<f32>) -> f32 { return 0.0; }
