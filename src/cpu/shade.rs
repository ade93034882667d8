//! Shading, the twin of shaders/shade.wgsl: the surface at a hit, the offset
//! shadow-ray origin, the lights, shadows and Lambert's sum. Written once for
//! both precisions: `kernel!` (kernel.rs) expands it into `cpu::f32` and
//! `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! shade {
    () => {
        /// What a light gives a point unless something blocks it (the shader's
        /// `LightSample`, with `lit` as the `Some`).
        pub struct LightSample {
            pub irradiance: Vec3,
            pub cos_theta: Real,
            pub shadow_ray: Ray,
        }

        /// The shader's `light_term`: what a light adds to the colour of
        /// `surface` where its shadow ray is not blocked.
        #[inline(always)]
        pub fn light_term(surface: &Surface, sample: &LightSample) -> Vec3 {
            surface.albedo * sample.irradiance * sample.cos_theta
        }

        /// The shader's `light_sample`: what `light` gives the point `surface`
        /// (shadow rays leaving from `origin`), or `None` when nothing.
        #[inline(always)]
        pub fn light_sample(
            surface: &Surface,
            origin: Vec3,
            light: &crate::layout::Light,
        ) -> Option<LightSample> {
            let light_vector = vec3(light.vector);
            let (to_light, irradiance, shadow_ray) = if light.kind != LIGHT_DIRECTIONAL {
                let d = light_vector - surface.position;
                let distance_squared = d.dot(d);
                // A point light on the shaded point lies in its tangent plane:
                // cos θ = 0, no light (not 0/0). Close by, I/r² is held finite, so
                // that a black albedo gives 0, not 0·∞.
                if distance_squared == 0.0 {
                    return None;
                }
                let s = light_vector - origin;
                let shadow_length = s.length();
                let to_light = d / distance_squared.sqrt();
                let mut irradiance = (vec3(light.color) / distance_squared).min(Vec3::splat(FAR));
                if light.kind == LIGHT_SPOT {
                    irradiance *= spot_falloff(light, to_light);
                }
                (
                    to_light,
                    irradiance,
                    Ray {
                        origin,
                        tmin: 0.0,
                        dir: s / shadow_length,
                        tmax: shadow_length,
                    },
                )
            } else {
                (
                    light_vector,
                    vec3(light.color),
                    Ray {
                        origin,
                        tmin: 0.0,
                        dir: light_vector,
                        tmax: FAR,
                    },
                )
            };
            let cos_theta = surface.shading_normal.dot(to_light);
            // No shadow ray for a light that cannot contribute (a NaN cos θ still
            // goes on, as it always has).
            if cos_theta <= 0.0 || irradiance == Vec3::ZERO {
                return None;
            }
            Some(LightSample {
                irradiance,
                cos_theta,
                shadow_ray,
            })
        }

        /// The shader's `spot_falloff`: KHR_lights_punctual's smooth falloff
        /// of a spot light towards unit `to_light`, t² for t the angle's cosine
        /// taken from the outer cone's (0) to the inner cone's (1), clamped.
        /// Written as a difference over a difference, not the spec's
        /// `cd · scale + offset`, so that no multiply-add can fuse on the GPU.
        #[inline(always)]
        pub fn spot_falloff(light: &crate::layout::Light, to_light: Vec3) -> Real {
            let cos_angle = -dot_rounded(vec3(light.direction), to_light);
            let (cos_inner, cos_outer) = (light.cos_inner as Real, light.cos_outer as Real);
            let t = ((cos_angle - cos_outer) / (cos_inner - cos_outer).max(1e-3)).clamp(0.0, 1.0);
            t * t
        }

        /// The shader's `dot_rounded`: a · b in its order (Rust fuses nothing).
        #[inline(always)]
        pub fn dot_rounded(a: Vec3, b: Vec3) -> Real {
            (a.x * b.x + a.y * b.y) + a.z * b.z
        }

        impl<'a> Kernel<'a> {
            /// The unit shading normal at barycentrics (w, u, v) of triangle
            /// `prim` before it is turned towards the ray: its corners' normals
            /// interpolated (FLAG_SMOOTH), else (or where they cancel) `outward`.
            #[inline(always)]
            pub fn vertex_normal(
                &self,
                tri: &crate::layout::Triangle,
                prim: u32,
                w: Real,
                u: Real,
                v: Real,
                outward: Vec3,
            ) -> Vec3 {
                if tri.flags & FLAG_SMOOTH != 0 {
                    let ns = &self.scene.normals[prim as usize];
                    let corner = |n: [f32; 4]| Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real);
                    let interpolated = w * corner(ns.n0) + u * corner(ns.n1) + v * corner(ns.n2);
                    if interpolated.dot(interpolated) > 0.0 {
                        return interpolated.normalize();
                    }
                }
                outward
            }

            pub fn surface_at(&self, ray: &Ray, hit: &Hit) -> Surface {
                let scene = self.scene;
                let num_triangles = scene.triangles.len() as u32;
                if hit.prim < num_triangles {
                    let tri = &scene.triangles[hit.prim as usize];
                    let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
                    let w = 1.0 - hit.u - hit.v;
                    let position = w * v0 + hit.u * v1 + hit.v * v2;
                    let error = self_hit_bound(v0.abs().max(v1.abs()).max(v2.abs()));
                    let outward = (v1 - v0).cross(v2 - v0).normalize();
                    let geometric = face_forward(outward, ray.dir);
                    // The camera ray's cone where it hits (docs/textures.md).
                    let cone_width = hit.t * self.cone_spread as Real;
                    let emission =
                        self.emission_at(tri, hit.prim, hit.u, hit.v, ray.dir, cone_width);
                    let shading = face_forward(
                        self.vertex_normal(tri, hit.prim, w, hit.u, hit.v, outward),
                        ray.dir,
                    );
                    return Surface {
                        position,
                        error,
                        geometric_normal: geometric,
                        shading_normal: shading,
                        albedo: self
                            .base_color_at(tri, hit.prim, hit.u, hit.v, ray.dir, cone_width)
                            .truncate(),
                        emission,
                    };
                }
                let sphere = &scene.spheres[(hit.prim - num_triangles) as usize];
                let material = &scene.materials[sphere.material as usize];
                let center = vec3(sphere.center);
                let outward = ((ray.origin - center) + hit.t * ray.dir).normalize();
                let position = center + (sphere.radius as Real) * outward;
                let error = self_hit_bound(center.abs() + sphere.radius as Real);
                let normal = face_forward(outward, ray.dir);
                Surface {
                    position,
                    error,
                    geometric_normal: normal,
                    shading_normal: normal,
                    albedo: vec4(material.base_color).truncate(),
                    emission: vec3(material.emission),
                }
            }

            /// Lambert: ambient·k + Σ k·E·max(0, n·l)·visible + emission, linear RGB.
            #[inline(always)]
            pub fn shade(&self, ray: &Ray, hit: &Hit) -> Vec3 {
                if hit.prim == NO_HIT {
                    return self.background;
                }
                let surface = self.surface_at(ray, hit);
                let mut color = self.ambient * surface.albedo;
                let origin =
                    offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
                for light in &self.scene.lights {
                    let Some(sample) = light_sample(&surface, origin, light) else {
                        continue;
                    };
                    if self.scene.shadows && self.trace_any(sample.shadow_ray) {
                        continue;
                    }
                    color += light_term(&surface, &sample);
                }
                // Emission: the surface's own light, seen by the camera; it lights
                // nothing else (no light is sampled from it).
                color + surface.emission
            }
        }

        fn face_forward(n: Vec3, dir: Vec3) -> Vec3 {
            if n.dot(dir) > 0.0 { -n } else { n }
        }

        fn gamma(n: Real) -> Real {
            n * MACHINE_EPSILON / (1.0 - n * MACHINE_EPSILON)
        }

        /// How far a point on a primitive whose coordinates reach `extent` may be
        /// off it, with the margin our intersection tests need to see a ray leaving
        /// it as clear: 32 ULPs of the largest coordinate (see the shader).
        fn self_hit_bound(extent: Vec3) -> Vec3 {
            Vec3::splat(gamma(32.0) * extent.max_element())
        }

        /// The next float away from `x` in the direction of `towards`'s sign.
        fn next_float(x: Real, towards: Real) -> Real {
            if towards > 0.0 {
                x.next_up()
            } else {
                x.next_down()
            }
        }

        /// pbrt-v4's OffsetRayOrigin: move p off its surface along n by the
        /// projection of its error bound onto n, then one ULP further per axis.
        pub fn offset_ray_origin(p: Vec3, error: Vec3, n: Vec3) -> Vec3 {
            let d = n.abs().dot(error);
            let offset = d * n;
            let mut po = p + offset;
            for axis in 0..3 {
                if offset[axis] != 0.0 {
                    po[axis] = next_float(po[axis], offset[axis]);
                }
            }
            po
        }
    };
}
pub(crate) use shade;
