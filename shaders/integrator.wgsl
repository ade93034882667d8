// Stage: the integrator. Which integrator a sample's radiance comes from
// (`radiance`: the direct one's `shade`, or `path_radiance`), and
// unidirectional path tracing with next-event estimation and multiple
// importance sampling (docs/rendering.md). CPU twin: src/cpu/integrator.rs.

// Mixed into a path's random-number seed so that its numbers are not the
// sample jitter's (`sample_position`).
const PATH_SEED: u32 = 0x68bc21ebu;
// Bounces after which Russian roulette may end a path (Mitsuba 3's
// rr_depth).
const ROULETTE_DEPTH: u32 = 5u;
// The largest chance Russian roulette lets a path go on (Mitsuba 3's).
const ROULETTE_CONTINUE: f32 = 0.95;
// A shadow ray towards a point on an area light stops this fraction of the
// way short of it, so that it cannot hit the light itself.
const SHADOW_SHORTENING: f32 = 1.0 / 4096.0;

fn path_seed(x: u32, y: u32, sample: u32, seed: u32) -> u32 {
    return pcg_hash(x ^ pcg_hash(y ^ pcg_hash(sample ^ pcg_hash(seed ^ PATH_SEED))));
}

fn next_random(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return unit_float(*state);
}

// Veach's power heuristic (β = 2).
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 == 0.0 {
        return 0.0;
    }
    return a2 / (a2 + b2);
}

// One sample's radiance along the camera ray `ray` that hit `hit`, by the
// integrator the pipeline is specialised for.
fn radiance(ray: Ray, hit: Hit, pixel: vec2<u32>, sample: u32) -> vec3<f32> {
    if PATH_TRACE {
        return path_radiance(ray, hit, path_seed(pixel.x, pixel.y, sample, params.seed));
    }
    return shade(ray, hit);
}

// What a ray that left the scene brings back (see the CPU twin).
fn escaped(ray: Ray, bsdf_pdf: f32) -> vec3<f32> {
    if !HAS_ENVIRONMENT {
        if bsdf_pdf == 0.0 {
            return params.background;
        }
        return vec3<f32>(0.0);
    }
    let light = environment_radiance(ray.dir);
    if bsdf_pdf == 0.0 {
        return light;
    }
    return light * power_heuristic(bsdf_pdf, environment_pdf(ray.dir));
}

// Direct light from one emitter drawn by power (see the CPU twin).
fn emitter_light(surface: Surface, origin: vec3<f32>, bsdf: BsdfParams, frame: mat3x3<f32>,
    wo: vec3<f32>, state: ptr<function, u32>) -> vec3<f32> {
    let u_pick = next_random(state);
    let u0 = next_random(state);
    let u = vec2<f32>(u0, next_random(state));
    let sample = sample_emitter(surface.position, surface.geometric_normal, u_pick, u);
    if !(sample.pdf > 0.0) || all(sample.radiance == vec3<f32>(0.0))
        || dot(sample.wi, surface.geometric_normal) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let wi = to_local(frame, sample.wi);
    let f = bsdf_eval(bsdf, wo, wi);
    if all(f == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    var tmax = FAR;
    if sample.distance < FAR {
        tmax = sample.distance * (1.0 - SHADOW_SHORTENING);
    }
    if params.shadows != 0u && trace_any(Ray(origin, 0.0, sample.wi, tmax)) {
        return vec3<f32>(0.0);
    }
    var weight = 1.0;
    if !sample.delta {
        weight = power_heuristic(sample.pdf, bsdf_pdf(bsdf, wo, wi));
    }
    return rounded3(f * sample.radiance * (weight / sample.pdf));
}

// Path tracing from the camera ray `ray` that hit `hit` (see the CPU twin).
fn path_radiance(camera_ray: Ray, camera_hit: Hit, seed: u32) -> vec3<f32> {
    var state = seed;
    var ray = camera_ray;
    var hit = camera_hit;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var bsdf_pdf_before = 0.0;
    var origin_before = ray.origin;
    var depth = 0u;
    loop {
        if hit.prim == NO_HIT {
            radiance += rounded3(throughput * escaped(ray, bsdf_pdf_before));
            break;
        }
        let surface = surface_at(ray, hit);
        if any(surface.emission != vec3<f32>(0.0)) {
            var weight = 1.0;
            if bsdf_pdf_before > 0.0 {
                let light_pdf = emitter_pdf(origin_before, hit.prim, ray.dir, hit.t);
                weight = power_heuristic(bsdf_pdf_before, light_pdf);
            }
            radiance += rounded3(throughput * surface.emission * weight);
        }
        depth += 1u;
        if depth > params.max_depth {
            break;
        }
        let material = material_at(ray, hit, surface);
        let frame = frame_from_normal(material.shading_normal);
        let wo = to_local(frame, -ray.dir);
        let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
        if HAS_EMITTERS {
            radiance += rounded3(throughput * emitter_light(surface, origin, material.bsdf, frame, wo, &state));
        }

        let u_lobe = next_random(&state);
        let u0 = next_random(&state);
        let u = vec2<f32>(u0, next_random(&state));
        let sample = bsdf_sample(material.bsdf, wo, u, u_lobe);
        if !sample.ok {
            break;
        }
        let wi = to_world(frame, sample.wi);
        if dot(wi, surface.geometric_normal) <= 0.0 {
            break;
        }
        throughput *= sample.weight;
        if depth >= ROULETTE_DEPTH {
            let go_on = min(max(max(throughput.x, throughput.y), throughput.z), ROULETTE_CONTINUE);
            if next_random(&state) >= go_on {
                break;
            }
            throughput /= go_on;
        }
        bsdf_pdf_before = sample.pdf;
        origin_before = surface.position;
        ray = Ray(origin, 0.0, wi, FAR);
        hit = trace_closest(ray);
    }
    return radiance;
}
