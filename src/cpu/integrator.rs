//! The path integrator, the twin of shaders/integrator.wgsl: which integrator a
//! sample's radiance comes from (`radiance`), and unidirectional path
//! tracing with next-event estimation and multiple importance sampling
//! (`path_radiance`; docs/rendering.md). Written once for both precisions:
//! `kernel!` (kernel.rs) expands it into `cpu::f32` and `cpu::f64`, whose
//! `Real`, `Vec2`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! integrator {
    () => {
        /// Mixed into a path's random-number seed so that its numbers are
        /// not the sample jitter's (`sample_position`).
        const PATH_SEED: u32 = 0x68bc_21eb;

        /// Bounces after which Russian roulette may end a path (Mitsuba 3's
        /// `rr_depth`).
        const ROULETTE_DEPTH: u32 = 5;

        /// The largest chance that Russian roulette lets a path go on: even
        /// a path that loses no energy ends with 5% (Mitsuba 3's 0.95), so
        /// that no path in a closed white box runs to `max_depth`.
        const ROULETTE_CONTINUE: Real = 0.95;

        /// A shadow ray towards a point on an area light stops this
        /// fraction of the way short of it, so that it cannot hit the light
        /// itself (the point's own error is far smaller).
        const SHADOW_SHORTENING: Real = 1.0 / 4096.0;

        /// The first random-number state of a sample's path.
        pub fn path_seed(x: u32, y: u32, sample: u32, seed: u32) -> u32 {
            pcg_hash(x ^ pcg_hash(y ^ pcg_hash(sample ^ pcg_hash(seed ^ PATH_SEED))))
        }

        /// The next uniform number in [0, 1) of a path, its state advanced.
        pub fn next_random(state: &mut u32) -> Real {
            *state = pcg_hash(*state);
            unit_float(*state)
        }

        /// Veach's power heuristic (β = 2) for a sample drawn with pdf `a`
        /// where another strategy had pdf `b`.
        pub fn power_heuristic(a: Real, b: Real) -> Real {
            let a2 = a * a;
            let b2 = b * b;
            if a2 + b2 == 0.0 {
                return 0.0;
            }
            a2 / (a2 + b2)
        }

        impl<'a> Kernel<'a> {
            /// One sample's radiance along the camera ray `ray` that hit
            /// `hit`, by the scene's integrator.
            #[inline(always)]
            pub fn radiance(&self, ray: &Ray, hit: &Hit, x: u32, y: u32, sample: u32) -> Vec3 {
                if self.path {
                    return self.path_radiance(ray, hit, path_seed(x, y, sample, self.seed));
                }
                self.shade(ray, hit)
            }

            /// What a ray that left the scene brings back: the environment
            /// (weighted against light sampling, which may have drawn its
            /// direction, unless `bsdf_pdf` is 0: a camera ray), or, for a
            /// camera ray where the scene has no environment, the
            /// background (which lights nothing).
            pub fn escaped(&self, ray: &Ray, bsdf_pdf: Real) -> Vec3 {
                if !self.has_environment() {
                    if bsdf_pdf == 0.0 {
                        return self.background;
                    }
                    return Vec3::ZERO;
                }
                let radiance = self.environment_radiance(ray.dir);
                if bsdf_pdf == 0.0 {
                    return radiance;
                }
                radiance * power_heuristic(bsdf_pdf, self.environment_pdf(ray.dir))
            }

            /// Direct light at a path's vertex from one emitter drawn by
            /// power (an emissive triangle, a point, spot or directional
            /// light, the environment), its shadow ray traced where the
            /// render has shadows; an emitter with area weighted against
            /// BSDF sampling (a punctual light, which BSDF sampling never
            /// finds, is not).
            fn emitter_light(
                &self,
                surface: &Surface,
                origin: Vec3,
                bsdf: BsdfParams,
                frame: Frame,
                wo: Vec3,
                state: &mut u32,
            ) -> Vec3 {
                let u_pick = next_random(state);
                let u = Vec2::new(next_random(state), next_random(state));
                let sample =
                    self.sample_emitter(surface.position, surface.geometric_normal, u_pick, u);
                if !(sample.pdf > 0.0)
                    || sample.radiance == Vec3::ZERO
                    || sample.wi.dot(surface.geometric_normal) <= 0.0
                {
                    return Vec3::ZERO;
                }
                let wi = to_local(frame, sample.wi);
                let f = bsdf_eval(bsdf, wo, wi);
                if f == Vec3::ZERO {
                    return Vec3::ZERO;
                }
                let tmax = if sample.distance >= FAR {
                    FAR
                } else {
                    sample.distance * (1.0 - SHADOW_SHORTENING)
                };
                if self.scene.shadows
                    && self.trace_any(Ray {
                        origin,
                        tmin: 0.0,
                        dir: sample.wi,
                        tmax,
                    })
                {
                    return Vec3::ZERO;
                }
                let weight = if sample.delta {
                    1.0
                } else {
                    power_heuristic(sample.pdf, bsdf_pdf(bsdf, wo, wi))
                };
                f * sample.radiance * (weight / sample.pdf)
            }

            /// Path tracing from the camera ray `ray` that hit `hit`:
            /// emission where a path hits it, direct light at each vertex
            /// (one emitter drawn by power, with multiple importance
            /// sampling against the BSDF's own direction), the next direction drawn from the BSDF, Russian
            /// roulette after `ROULETTE_DEPTH` bounces; at most
            /// `max_depth` surfaces (pbrt-v4's `maxdepth`; Mitsuba 3's
            /// `max_depth` is one more). Random numbers from `state`.
            pub fn path_radiance(&self, ray: &Ray, hit: &Hit, state: u32) -> Vec3 {
                let mut state = state;
                let mut ray = *ray;
                let mut hit = *hit;
                let mut radiance = Vec3::ZERO;
                let mut throughput = Vec3::ONE;
                // The pdf of the BSDF sample the ray was drawn by (0: the
                // camera's), and where it left.
                let mut bsdf_pdf_before: Real = 0.0;
                let mut origin_before = ray.origin;
                let mut depth = 0u32;
                loop {
                    if hit.prim == NO_HIT {
                        radiance += throughput * self.escaped(&ray, bsdf_pdf_before);
                        break;
                    }
                    let surface = self.surface_at(&ray, &hit);
                    if surface.emission != Vec3::ZERO {
                        let mut weight = 1.0;
                        if bsdf_pdf_before > 0.0 {
                            let light_pdf =
                                self.emitter_pdf(origin_before, hit.prim, ray.dir, hit.t);
                            weight = power_heuristic(bsdf_pdf_before, light_pdf);
                        }
                        radiance += throughput * surface.emission * weight;
                    }
                    depth += 1;
                    if depth > self.max_depth {
                        break;
                    }
                    let material = self.material_at(&ray, &hit, &surface);
                    let frame = frame_from_normal(material.shading_normal);
                    let wo = to_local(frame, -ray.dir);
                    let origin = offset_ray_origin(
                        surface.position,
                        surface.error,
                        surface.geometric_normal,
                    );
                    if self.has_emitters() {
                        radiance += throughput
                            * self.emitter_light(
                                &surface,
                                origin,
                                material.bsdf,
                                frame,
                                wo,
                                &mut state,
                            );
                    }

                    let u_lobe = next_random(&mut state);
                    let u = Vec2::new(next_random(&mut state), next_random(&mut state));
                    let sample = bsdf_sample(material.bsdf, wo, u, u_lobe);
                    if !sample.ok {
                        break;
                    }
                    let wi = to_world(frame, sample.wi);
                    // Below the geometric surface (a shading normal's
                    // artefact): the path would leak through it.
                    if wi.dot(surface.geometric_normal) <= 0.0 {
                        break;
                    }
                    throughput *= sample.weight;
                    if depth >= ROULETTE_DEPTH {
                        let go_on = throughput.max_element().min(ROULETTE_CONTINUE);
                        if next_random(&mut state) >= go_on {
                            break;
                        }
                        throughput /= go_on;
                    }
                    bsdf_pdf_before = sample.pdf;
                    origin_before = surface.position;
                    ray = Ray {
                        origin,
                        tmin: 0.0,
                        dir: wi,
                        tmax: FAR,
                    };
                    hit = self.trace_closest(ray);
                }
                radiance
            }
        }
    };
}
pub(crate) use integrator;
