// Stage: the integrator. Which integrator a sample's radiance comes from
// (`radiance`: the direct one's `shade`, or `path_radiance`), and
// unidirectional path tracing with next-event estimation and multiple
// importance sampling, a vertex at a time (`path_vertex`, which the
// megakernel's `path_radiance` loops over and the wavefront's `path_shade`
// runs once a pass; docs/rendering.md). CPU twin: src/cpu/integrator.rs.

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

// A path between its vertices (see the CPU twin): the ray it goes on
// along (from `origin` with tmin 0 and tmax FAR), what it carries, what it
// has gathered, its random numbers, and what the ray was drawn by.
struct PathState {
    ray: Ray,
    throughput: vec3<f32>,
    radiance: vec3<f32>,
    state: u32,
    bsdf_pdf_before: f32,
    origin_before: vec3<f32>,
    depth: u32,
}

// What a path's vertex asks of the tracer (see the CPU twin): the shadow
// ray of its light sample and what that light adds unless it is blocked
// (`lit`), and whether the path goes on along `PathState.ray`.
struct PathStep {
    shadow: Ray,
    term: vec3<f32>,
    lit: bool,
    goes_on: bool,
}

// A path that starts along the camera ray `ray` (see the CPU twin).
fn path_start(ray: Ray, seed: u32) -> PathState {
    return PathState(ray, vec3<f32>(1.0), vec3<f32>(0.0), seed, 0.0, ray.origin, 0u);
}

// Direct light from one emitter drawn by power, but for its shadow ray
// (see the CPU twin).
fn emitter_light(surface: Surface, origin: vec3<f32>, bsdf: BsdfParams, frame: mat3x3<f32>,
    wo: vec3<f32>, state: ptr<function, u32>) -> PathStep {
    var step = PathStep(Ray(origin, 0.0, vec3<f32>(0.0), FAR), vec3<f32>(0.0), false, false);
    let u_pick = next_random(state);
    let u0 = next_random(state);
    let u = vec2<f32>(u0, next_random(state));
    let sample = sample_emitter(surface.position, surface.geometric_normal, u_pick, u);
    if !(sample.pdf > 0.0) || all(sample.radiance == vec3<f32>(0.0))
        || dot(sample.wi, surface.geometric_normal) <= 0.0 {
        return step;
    }
    let wi = to_local(frame, sample.wi);
    let f = bsdf_eval(bsdf, wo, wi);
    if all(f == vec3<f32>(0.0)) {
        return step;
    }
    var tmax = FAR;
    if sample.distance < FAR {
        tmax = sample.distance * (1.0 - SHADOW_SHORTENING);
    }
    var weight = 1.0;
    if !sample.delta {
        weight = power_heuristic(sample.pdf, bsdf_pdf(bsdf, wo, wi));
    }
    step.shadow = Ray(origin, 0.0, sample.wi, tmax);
    step.term = rounded3(f * sample.radiance * (weight / sample.pdf));
    step.lit = true;
    return step;
}

// One vertex of a path, where its ray hit `hit` (see the CPU twin).
fn path_vertex(path: ptr<function, PathState>, hit: Hit) -> PathStep {
    var step = PathStep((*path).ray, vec3<f32>(0.0), false, false);
    let ray = (*path).ray;
    if hit.prim == NO_HIT {
        (*path).radiance += rounded3((*path).throughput * escaped(ray, (*path).bsdf_pdf_before));
        return step;
    }
    let surface = surface_at(ray, hit);
    if any(surface.emission != vec3<f32>(0.0)) {
        var weight = 1.0;
        if (*path).bsdf_pdf_before > 0.0 {
            let light_pdf = emitter_pdf((*path).origin_before, hit.prim, ray.dir, hit.t);
            weight = power_heuristic((*path).bsdf_pdf_before, light_pdf);
        }
        (*path).radiance += rounded3((*path).throughput * surface.emission * weight);
    }
    (*path).depth += 1u;
    if (*path).depth > params.max_depth {
        return step;
    }
    let material = material_at(ray, hit, surface);
    let frame = frame_from_normal(material.shading_normal);
    let wo = to_local(frame, -ray.dir);
    let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
    // The random state copied in and out: a pointer argument names a whole
    // variable in WGSL (without unrestricted_pointer_parameters).
    if HAS_EMITTERS {
        var state = (*path).state;
        step = emitter_light(surface, origin, material.bsdf, frame, wo, &state);
        (*path).state = state;
        step.term = rounded3((*path).throughput * step.term);
    }

    var state = (*path).state;
    let u_lobe = next_random(&state);
    let u0 = next_random(&state);
    let u = vec2<f32>(u0, next_random(&state));
    (*path).state = state;
    let sample = bsdf_sample(material.bsdf, wo, u, u_lobe);
    if !sample.ok {
        return step;
    }
    let wi = to_world(frame, sample.wi);
    if dot(wi, surface.geometric_normal) <= 0.0 {
        return step;
    }
    (*path).throughput *= sample.weight;
    if (*path).depth >= ROULETTE_DEPTH {
        let t = (*path).throughput;
        let go_on = min(max(max(t.x, t.y), t.z), ROULETTE_CONTINUE);
        var state = (*path).state;
        let u_roulette = next_random(&state);
        (*path).state = state;
        if u_roulette >= go_on {
            return step;
        }
        (*path).throughput /= go_on;
    }
    (*path).bsdf_pdf_before = sample.pdf;
    (*path).origin_before = surface.position;
    (*path).ray = Ray(origin, 0.0, wi, FAR);
    step.goes_on = true;
    return step;
}

// Whether a vertex's light sample `step` reaches it: its shadow ray not
// blocked, or the render without shadows.
fn light_reaches(step: PathStep) -> bool {
    return step.lit && (params.shadows == 0u || !trace_any(step.shadow));
}

// Path tracing from the camera ray `ray` that hit `hit`, every vertex in
// this invocation (the megakernel; see the CPU twin).
fn path_radiance(camera_ray: Ray, camera_hit: Hit, seed: u32) -> vec3<f32> {
    var path = path_start(camera_ray, seed);
    var hit = camera_hit;
    loop {
        let step = path_vertex(&path, hit);
        if light_reaches(step) {
            path.radiance += step.term;
        }
        if !step.goes_on {
            break;
        }
        hit = trace_closest(path.ray);
    }
    return path.radiance;
}
