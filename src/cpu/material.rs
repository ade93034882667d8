//! STAND-IN (the lead's scratch, replaced by the materials engineer's at merge).
macro_rules! material {
    () => {
        pub struct SurfaceMaterial { pub bsdf: BsdfParams, pub shading_normal: Vec3 }
        impl<'a> Kernel<'a> {
            pub fn material_at(&self, _ray: &Ray, _hit: &Hit, surface: &Surface) -> SurfaceMaterial {
                SurfaceMaterial { bsdf: BsdfParams { base_color: surface.albedo, metallic: 0.0, roughness: 1.0, kind: 0 }, shading_normal: surface.shading_normal }
            }
        }
    };
}
pub(crate) use material;
