// Stage: shading. The surface at a hit, the offset shadow-ray origin, the
// lights (point, directional, spot), shadows, and Lambert's sum. CPU twin:
// src/cpu/shade.rs.

fn face_forward(n: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot(n, dir) > 0.0);
}

fn gamma(n: f32) -> f32 {
    return n * MACHINE_EPSILON / (1.0 - n * MACHINE_EPSILON);
}

// How far a point computed on a primitive whose coordinates reach `extent`
// (per axis) may lie off it, plus how far a ray starting there must be from
// it for the intersection test's own rounding (of differences of such
// coordinates) to see it as clear: both are a few ULPs of the largest
// coordinate. pbrt-v4 bounds the first alone (gamma(7)·Σ|bᵢ·vᵢ|) because its
// tests carry a conservative t bound; ours do not, so the bound is
// isotropic and 32 ULPs wide. See docs/accuracy.md.
fn self_hit_bound(extent: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(gamma(32.0) * max(max(extent.x, extent.y), extent.z));
}

// The unit shading normal at barycentrics (w, u, v) of triangle `prim`
// before it is turned towards the ray: its corners' normals interpolated
// (FLAG_SMOOTH), else (or where they cancel) `outward`, the face's.
fn vertex_normal(tri: Triangle, prim: u32, w: f32, u: f32, v: f32, outward: vec3<f32>) -> vec3<f32> {
    if HAS_SMOOTH && (tri.flags & FLAG_SMOOTH) != 0u {
        let ns = triangle_normals_at(prim);
        let interpolated = w * ns.n0.xyz + u * ns.n1.xyz + v * ns.n2.xyz;
        if dot(interpolated, interpolated) > 0.0 {
            return normalize(interpolated);
        }
    }
    return outward;
}

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    // The sphere's half below is compiled out where the scene has none (it
    // would run masked on lavapipe even where no lane hit a sphere).
    if !HAS_SPHERES || hit.prim < params.num_triangles {
        let tri = triangle_at(hit.prim);
        let w = 1.0 - hit.u - hit.v;
        // From barycentrics, not o + t·d: the point lies closer to the plane.
        let position = w * tri.v0 + hit.u * tri.v1 + hit.v * tri.v2;
        let error = self_hit_bound(max(max(abs(tri.v0), abs(tri.v1)), abs(tri.v2)));
        let outward = normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
        let geometric = face_forward(outward, ray.dir);
        let shading = face_forward(vertex_normal(tri, hit.prim, w, hit.u, hit.v, outward), ray.dir);
        // The camera ray's cone where it hits (docs/textures.md).
        let cone_width = hit.t * params.cone_spread;
        let base = base_color_at(tri, hit.prim, hit.u, hit.v, ray.dir, cone_width);
        let emission = emission_at(tri, hit.prim, hit.u, hit.v, ray.dir, cone_width);
        return Surface(position, error, geometric, shading, base.rgb, emission);
    }
    let sphere = sphere_at(hit.prim - params.num_triangles);
    // Relative to the centre first: o − c is exact when both are near each
    // other, so far from the origin the normal keeps its precision.
    let outward = normalize((ray.origin - sphere.center) + hit.t * ray.dir);
    // Re-projected onto the sphere to undo the rounding of t.
    let position = sphere.center + sphere.radius * outward;
    let error = self_hit_bound(abs(sphere.center) + sphere.radius);
    let normal = face_forward(outward, ray.dir);
    let material = material_entry(sphere.material);
    return Surface(position, error, normal, normal, material.base_color.rgb, material.emission);
}

// The next f32 away from zero in the direction of `towards` (+1 or −1).
fn next_float(x: f32, towards: f32) -> f32 {
    // −0 and +0 step alike.
    let y = select(x, 0.0, x == 0.0);
    let bits = bitcast<u32>(y);
    let away_from_zero = (y >= 0.0) == (towards > 0.0);
    if y == 0.0 {
        return select(-bitcast<f32>(1u), bitcast<f32>(1u), towards > 0.0);
    }
    return bitcast<f32>(select(bits - 1u, bits + 1u, away_from_zero));
}

// pbrt-v4's OffsetRayOrigin: move p off its surface along n by the
// projection of its error bound onto n, then one more ULP per axis so that
// the rounding of the sum cannot bring it back. A ray leaving towards n's
// side then cannot hit the surface it starts on, at any scale.
fn offset_ray_origin(p: vec3<f32>, error: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let d = dot(abs(n), error);
    let offset = d * n;
    var po = p + offset;
    for (var axis = 0; axis < 3; axis++) {
        if offset[axis] != 0.0 {
            po[axis] = next_float(po[axis], sign(offset[axis]));
        }
    }
    return po;
}

// a · b with each product and sum `rounded`, in the CPU twin's order.
fn dot_rounded(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return rounded(rounded(rounded(a.x * b.x) + rounded(a.y * b.y)) + rounded(a.z * b.z));
}

// KHR_lights_punctual's smooth falloff of a spot light towards unit
// `to_light`: t² for t the angle's cosine taken from the outer cone's (0) to
// the inner cone's (1), clamped. A difference over a difference, not the
// spec's `cd · scale + offset`, and the dot product's terms rounded each,
// so that no multiply-add fuses: the CPU twin's bits.
fn spot_falloff(light: Light, to_light: vec3<f32>) -> f32 {
    let cos_angle = -dot_rounded(light.direction, to_light);
    let t = clamp(rounded(cos_angle - light.cos_outer)
        / max(light.cos_inner - light.cos_outer, 1e-3), 0.0, 1.0);
    return t * t;
}

// What light `light` gives a point (`surface`, shadow rays leaving from
// `origin`) unless something blocks it; `lit` false when nothing.
struct LightSample {
    irradiance: vec3<f32>,
    cos_theta: f32,
    shadow_ray: Ray,
    lit: bool,
}

fn light_sample(surface: Surface, origin: vec3<f32>, light: Light) -> LightSample {
    var out: LightSample;
    out.lit = false;
    var to_light: vec3<f32>;
    // Specialisation drops the branch of a light kind the scene lacks.
    if (HAS_POINT_LIGHTS || HAS_SPOT_LIGHTS)
        && (!HAS_DIRECTIONAL_LIGHTS || light.kind != LIGHT_DIRECTIONAL) {
        let d = light.vector - surface.position;
        let distance_squared = dot(d, d);
        // A light on the shaded point: no light (see the CPU twin).
        if distance_squared == 0.0 {
            return out;
        }
        to_light = d / sqrt(distance_squared);
        out.irradiance = min(light.color / distance_squared, vec3<f32>(FAR));
        if HAS_SPOT_LIGHTS && light.kind == LIGHT_SPOT {
            out.irradiance *= spot_falloff(light, to_light);
        }
        let s = light.vector - origin;
        let shadow_length = length(s);
        out.shadow_ray = Ray(origin, 0.0, s / shadow_length, shadow_length);
    } else {
        to_light = light.vector;
        out.irradiance = light.color;
        out.shadow_ray = Ray(origin, 0.0, to_light, FAR);
    }
    out.cos_theta = dot(surface.shading_normal, to_light);
    // Early out: no shadow ray for a light that cannot contribute (a NaN
    // cos θ still goes on, as on the CPU).
    out.lit = !(out.cos_theta <= 0.0 || all(out.irradiance == vec3<f32>(0.0)));
    return out;
}

// What a light adds to the colour where its shadow ray is not blocked:
// rounded as one value, so that the wavefront, which adds it in a later
// pass, sums the very bits `shade` sums (no multiply fused into the add).
fn light_term(surface: Surface, sample: LightSample) -> vec3<f32> {
    return rounded3(surface.albedo * sample.irradiance * sample.cos_theta);
}

// Lambert: ambient·k + Σ k·E·max(0, n·l)·visible + emission, linear RGB.
fn shade(ray: Ray, hit: Hit) -> vec3<f32> {
    if hit.prim == NO_HIT {
        return params.background;
    }
    let surface = surface_at(ray, hit);
    // Each addend rounded on its own, as the wavefront keeps them.
    var color = rounded3(params.ambient * surface.albedo);
    let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
    for (var i = 0u; i < params.num_lights; i++) {
        let sample = light_sample(surface, origin, light_at(i));
        if !sample.lit {
            continue;
        }
        if HAS_SHADOWS && params.shadows != 0u && trace_any(sample.shadow_ray) {
            continue;
        }
        color += light_term(surface, sample);
    }
    // Emission: the surface's own light, seen by the camera; it lights
    // nothing else (no light is sampled from it).
    return color + rounded3(surface.emission);
}
