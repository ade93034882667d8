//! Materials, the twin of shaders/material.wgsl: what the path
//! integrator's BSDF sees at a hit (its parameters, metalness and roughness
//! × the metallic-roughness texture) and the normal-mapped shading normal.
//! Written once for both precisions: `kernel!` (kernel.rs) expands it into
//! `cpu::f32` and `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! material {
    () => {
        /// The shader's `SurfaceMaterial`.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct SurfaceMaterial {
            pub bsdf: BsdfParams,
            /// Unit; on the side the ray arrives from, as `Surface`'s normals.
            pub shading_normal: Vec3,
        }

        /// a × b, each component `difference_of_products`'s.
        #[inline(always)]
        pub fn cross_rounded(a: Vec3, b: Vec3) -> Vec3 {
            Vec3::new(
                difference_of_products(a.y, b.z, a.z, b.y),
                difference_of_products(a.z, b.x, a.x, b.z),
                difference_of_products(a.x, b.y, a.y, b.x),
            )
        }

        impl<'a> Kernel<'a> {
            /// The shader's `material_at`: the BSDF's parameters and the shading
            /// normal at `hit`, whose surface `surface_at` gave.
            pub fn material_at(&self, ray: &Ray, hit: &Hit, surface: &Surface) -> SurfaceMaterial {
                let scene = self.scene;
                let num_triangles = scene.triangles.len() as u32;
                let params = |m: u32| {
                    let material = &scene.materials[m as usize];
                    BsdfParams {
                        base_color: surface.albedo,
                        metallic: material.metallic as Real,
                        roughness: material.roughness as Real,
                        kind: material.kind,
                    }
                };
                if hit.prim >= num_triangles {
                    let sphere = &scene.spheres[(hit.prim - num_triangles) as usize];
                    return SurfaceMaterial {
                        bsdf: params(sphere.material),
                        shading_normal: surface.shading_normal,
                    };
                }
                let tri = &scene.triangles[hit.prim as usize];
                let mut out = SurfaceMaterial {
                    bsdf: params(tri.material),
                    shading_normal: surface.shading_normal,
                };
                // Texture slots are filled only for meshes with texture
                // coordinates.
                if tri.flags & FLAG_ATTRIBUTES == 0 {
                    return out;
                }
                let material = &scene.materials[tri.material as usize];
                let cone_width = hit.t * self.cone_spread as Real;
                let texture =
                    |slot| self.texture_at(slot, tri, hit.prim, hit.u, hit.v, ray.dir, cone_width);
                if material.metallic_roughness_texture != NO_TEXTURE {
                    let texel = texture(material.metallic_roughness_texture);
                    out.bsdf.metallic *= texel.z;
                    out.bsdf.roughness *= texel.y;
                }
                if material.normal_texture != NO_TEXTURE {
                    let texel = texture(material.normal_texture).truncate();
                    out.shading_normal =
                        self.normal_mapped(tri, hit, ray.dir, texel, material.normal_scale as Real);
                }
                out
            }

            /// The shader's `normal_mapped` (its comment tells the frame): the
            /// shading normal a normal map's `texel` gives at `hit`.
            pub fn normal_mapped(
                &self,
                tri: &crate::layout::Triangle,
                hit: &Hit,
                dir: Vec3,
                texel: Vec3,
                scale: Real,
            ) -> Vec3 {
                let w = 1.0 - hit.u - hit.v;
                let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
                let outward = (v1 - v0).cross(v2 - v0).normalize();
                let n = self.vertex_normal(tri, hit.prim, w, hit.u, hit.v, outward);
                let side: Real = if n.dot(dir) > 0.0 { -1.0 } else { 1.0 };
                let frames = &self.scene.tangents[hit.prim as usize];
                let interpolated =
                    w * vec4(frames.t0) + (hit.u * vec4(frames.t1) + hit.v * vec4(frames.t2));
                let along = interpolated.truncate();
                let tangent = along - n * dot_rounded(n, along);
                // A zero or NaN vector has no direction (the shader's `!(x > 0)`).
                let degenerate = |v: Vec3| {
                    let squared = dot_rounded(v, v);
                    squared.is_nan() || squared <= 0.0
                };
                if degenerate(tangent) {
                    return side * n;
                }
                let t = normalize3(tangent);
                let sign: Real = if interpolated.w < 0.0 { -1.0 } else { 1.0 };
                let b = sign * cross_rounded(n, t);
                let m = Vec3::new(
                    scale * (2.0 * texel.x - 1.0),
                    scale * (2.0 * texel.y - 1.0),
                    2.0 * texel.z - 1.0,
                );
                let mapped = (m.x * t + m.y * b) + m.z * n;
                if degenerate(mapped) {
                    return side * n;
                }
                side * normalize3(mapped)
            }
        }
    };
}
pub(crate) use material;
