// STAND-IN (the lead's scratch, replaced by the materials engineer's at merge).
struct SurfaceMaterial { bsdf: BsdfParams, shading_normal: vec3<f32> }
fn material_at(ray: Ray, hit: Hit, surface: Surface) -> SurfaceMaterial {
    return SurfaceMaterial(BsdfParams(surface.albedo, 0.0, 1.0, 0u), surface.shading_normal);
}
