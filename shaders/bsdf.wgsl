// STAND-IN (the lead's scratch, replaced by the BSDF engineer's at merge).
struct BsdfParams { base_color: vec3<f32>, metallic: f32, roughness: f32, kind: u32 }
struct BsdfSample { wi: vec3<f32>, weight: vec3<f32>, pdf: f32, ok: bool }
fn frame_from_normal(n: vec3<f32>) -> mat3x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat3x3<f32>(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y), n);
}
fn to_local(frame: mat3x3<f32>, v: vec3<f32>) -> vec3<f32> { return v * frame; }
fn to_world(frame: mat3x3<f32>, v: vec3<f32>) -> vec3<f32> { return frame * v; }
fn bsdf_eval(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if wo.z <= 0.0 || wi.z <= 0.0 { return vec3<f32>(0.0); }
    return p.base_color * (wi.z / 3.14159265358979);
}
fn bsdf_pdf(p: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 { return 0.0; }
    return wi.z / 3.14159265358979;
}
fn bsdf_sample(p: BsdfParams, wo: vec3<f32>, u: vec2<f32>, u_lobe: f32) -> BsdfSample {
    let r = sqrt(u.x);
    let phi = 2.0 * 3.14159265358979 * u.y;
    let wi = vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
    let pdf = wi.z / 3.14159265358979;
    return BsdfSample(wi, p.base_color, pdf, wo.z > 0.0 && pdf > 0.0);
}
