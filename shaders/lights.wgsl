// Stage: lights. The path integrator's light sampling (docs/rendering.md,
// "Lights" and "The environment"): an emitter picked from the emitters'
// table by power (an alias table), a point on it or a direction from it,
// and the pdfs that multiple importance sampling weighs by; the
// environment's radiance and its sampling. CPU twin: src/cpu/lights.rs,
// the same bits: every product that feeds a sum is `rounded`, every
// square root too (Mesa rewrites sqrt(x)·sqrt(x) as x), and a product
// that a constant multiplies is an `opaque_copy` (Mesa moves a constant
// factor into a product of products, which rounds otherwise).

// What `sample_emitter` gives: the direction to the light from the shaded
// point, how far the light is (FAR: at infinity), the radiance arriving
// along it, and its pdf (solid angle, times the pick's probability; the
// pick's probability alone for a punctual light, `delta`). pdf 0: no
// sample.
struct EmitterSample {
    wi: vec3<f32>,
    distance: f32,
    radiance: vec3<f32>,
    pdf: f32,
    delta: bool,
}

// The largest f32 below 1 (pbrt's OneMinusEpsilon).
const ONE_MINUS_EPSILON: f32 = 0.99999994f;
// 1/(2π²): a map's pdf in (u, v) to solid angle, with 1/sin θ (1/4π,
// the uniform sphere's pdf, is the winding stage's INV_FOUR_PI).
const INV_TWO_PI_SQUARED: f32 = 0.05066059f;

// The emission at (u, v) of triangle `prim`: its material's, times its
// emissive texture read as `texture_at` does (where the triangle has
// texture coordinates). Shading and light sampling both read it.
fn emission_at(tri: Triangle, prim: u32, u: f32, v: f32, dir: vec3<f32>, cone_width: f32) -> vec3<f32> {
    var emission = material_entry(tri.material).emission;
    let emissive_texture = material_entry(tri.material).emissive_texture;
    if HAS_TEXTURES && emissive_texture != NO_TEXTURE && (tri.flags & FLAG_ATTRIBUTES) != 0u {
        emission *= texture_at(emissive_texture, tri, prim, u, v, dir, cone_width).rgb;
    }
    return emission;
}

// The entry of the emitters' table that `u` picks (pbrt-v4's
// AliasTable::Sample): bin ⌊u·n⌋, kept where the rest of u·n is below its
// q, else its alias.
fn pick_emitter(u: f32) -> u32 {
    let n = lighting.num_emitters;
    let scaled = rounded(u * f32(n));
    let bin = min(u32(scaled), n - 1u);
    let rest = min(scaled - f32(bin), ONE_MINUS_EPSILON);
    return select(emitter_at(bin).alias_bin, bin, rest < emitter_at(bin).q);
}

// A triangle emitter's entry in the table (triangles come first, by
// primitive id), or NO_HIT where `prim` emits nothing.
fn triangle_emitter(prim: u32) -> u32 {
    var lo = 0u;
    var hi = lighting.num_triangle_emitters;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitter_at(mid).index < prim {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < lighting.num_triangle_emitters && emitter_at(lo).index == prim {
        return lo;
    }
    return NO_HIT;
}

// The solid-angle pdf of a point sampled uniformly on the triangle whose
// edges' cross product is `n`, seen at `distance` along unit `wi`:
// r²/(A·|cos θ|) = 2r²/|n·wi|; 0 edge-on.
fn triangle_solid_angle_pdf(n: vec3<f32>, wi: vec3<f32>, distance: f32) -> f32 {
    let cos_area = abs(dot_rounded(n, wi));
    if cos_area == 0.0 {
        return 0.0;
    }
    return rounded(rounded(2.0 * rounded(distance * distance)) / cos_area);
}

// A point on triangle `prim`, uniform by area (pbrt-v4's
// SampleUniformTriangle), as seen from `position`; pdf in solid angle.
fn sample_triangle(position: vec3<f32>, prim: u32, u: vec2<f32>) -> EmitterSample {
    var out: EmitterSample;
    out.pdf = 0.0;
    out.delta = false;
    var b0: f32;
    var b1: f32;
    if u.x < u.y {
        b0 = rounded(0.5 * u.x);
        b1 = u.y - b0;
    } else {
        b1 = rounded(0.5 * u.y);
        b0 = u.x - b1;
    }
    // As a hit's (u, v): the weights of v1 and v2.
    let hu = b1;
    let hv = rounded(rounded(1.0 - b0) - b1);
    let tri = triangle_at(prim);
    let w = rounded(rounded(1.0 - hu) - hv);
    let p = rounded3(rounded3(rounded3(w * tri.v0) + rounded3(hu * tri.v1)) + rounded3(hv * tri.v2));
    let d = p - position;
    let distance_squared = dot_rounded(d, d);
    if distance_squared == 0.0 {
        return out;
    }
    out.distance = rounded(sqrt(distance_squared));
    out.wi = d / out.distance;
    let n = cross_rounded(tri.v1 - tri.v0, tri.v2 - tri.v0);
    out.pdf = triangle_solid_angle_pdf(n, out.wi, out.distance);
    // A cut-out point of an alpha-masked triangle is no surface: no light.
    if cut_out(prim, hu, hv) {
        out.radiance = vec3<f32>(0.0);
    } else {
        out.radiance = emission_at(tri, prim, hu, hv, out.wi, 0.0);
    }
    return out;
}

// A punctual light's light at `position`: π·color/r² from a point or spot
// light (a spot's times its falloff), π·color from a directional one (the
// lecture convention's `color` as a BRDF of albedo/π sees it).
fn sample_light(position: vec3<f32>, light: Light) -> EmitterSample {
    var out: EmitterSample;
    out.delta = true;
    out.pdf = 1.0;
    let emitted = rounded3(PI * light.color);
    if light.kind == LIGHT_DIRECTIONAL {
        out.wi = light.vector;
        out.distance = FAR;
        out.radiance = emitted;
        return out;
    }
    let d = light.vector - position;
    let distance_squared = dot_rounded(d, d);
    if distance_squared == 0.0 {
        out.pdf = 0.0;
        return out;
    }
    out.distance = rounded(sqrt(distance_squared));
    out.wi = d / out.distance;
    out.radiance = min(rounded3(emitted / distance_squared), vec3<f32>(FAR));
    if HAS_SPOT_LIGHTS && light.kind == LIGHT_SPOT {
        out.radiance *= rounded(spot_falloff(light, out.wi));
    }
    return out;
}

// A light for the point `position` whose (shading) normal is `normal`:
// an emitter picked by power with `u_pick`, then a point or direction on
// it with `u`. No sample (pdf 0) where the scene has no emitter or the
// light lies below the point's horizon (it would light nothing).
fn sample_emitter(position: vec3<f32>, normal: vec3<f32>, u_pick: f32, u: vec2<f32>) -> EmitterSample {
    var out: EmitterSample;
    out.pdf = 0.0;
    out.delta = false;
    if !HAS_EMITTERS || lighting.num_emitters == 0u {
        return out;
    }
    let entry = pick_emitter(u_pick);
    let kind = emitter_at(entry).kind;
    let pmf = emitter_at(entry).pmf;
    if kind == EMITTER_TRIANGLE {
        out = sample_triangle(position, emitter_at(entry).index, u);
    } else if kind == EMITTER_LIGHT {
        out = sample_light(position, light_at(emitter_at(entry).index));
    } else {
        out = sample_environment(u);
    }
    out.pdf = rounded(out.pdf * pmf);
    if !(dot_rounded(out.wi, normal) > 0.0) {
        out.pdf = 0.0;
    }
    return out;
}

// The pdf `sample_emitter` would have given the direction `wi` from
// `position` to the point of triangle `hit_prim` at `distance`: how a ray
// the BSDF sampled weighs the emission it hit. 0 for a primitive that is
// no emitter. (`position` is not read: area sampling needs only the
// distance.)
fn emitter_pdf(position: vec3<f32>, hit_prim: u32, wi: vec3<f32>, distance: f32) -> f32 {
    if !HAS_EMITTERS || hit_prim >= params.num_triangles {
        return 0.0;
    }
    let entry = triangle_emitter(hit_prim);
    if entry == NO_HIT {
        return 0.0;
    }
    let tri = triangle_at(hit_prim);
    let n = cross_rounded(tri.v1 - tri.v0, tri.v2 - tri.v0);
    return rounded(triangle_solid_angle_pdf(n, wi, distance) * emitter_at(entry).pmf);
}

// A world direction in the map's frame: turned by −rotation about +Y.
fn environment_local(dir: vec3<f32>) -> vec3<f32> {
    let c = lighting.rotation_cos;
    let s = lighting.rotation_sin;
    return vec3<f32>(rounded(rounded(c * dir.x) - rounded(s * dir.z)), dir.y,
        rounded(rounded(s * dir.x) + rounded(c * dir.z)));
}

// A direction in the map's frame in the world: turned by +rotation.
fn environment_world(d: vec3<f32>) -> vec3<f32> {
    let c = lighting.rotation_cos;
    let s = lighting.rotation_sin;
    return vec3<f32>(rounded(rounded(c * d.x) + rounded(s * d.z)), d.y,
        rounded(rounded(c * d.z) - rounded(s * d.x)));
}

// Mitsuba 3's (u, v) of a direction in the map's frame: u = atan2(x, −z)/2π
// wrapped into [0, 1), v = acos(y)/π.
fn environment_uv(d: vec3<f32>) -> vec2<f32> {
    let u = rounded(approx_atan2(d.x, -d.z) * INV_TWO_PI);
    return vec2<f32>(u - floor(u), rounded(approx_acos(d.y) * INV_PI));
}

fn environment_texel(x: u32, y: u32) -> vec3<f32> {
    return environment_at(y * lighting.environment_width + x).xyz;
}

// The map at (u, v), bilinear as Mitsuba reads it: columns texel-centred
// and periodic (x = u·W − ½), rows corner-aligned (y = v·(H − 1)).
fn environment_lookup(uv: vec2<f32>) -> vec3<f32> {
    let width = lighting.environment_width;
    let height = lighting.environment_height;
    let x = rounded(uv.x * f32(width)) - 0.5;
    let y = rounded(clamp(uv.y, 0.0, 1.0) * f32(height - 1u));
    let x0 = floor(x);
    let y0 = min(floor(y), f32(height - 2u));
    let fx = x - x0;
    let fy = y - y0;
    // x0 ≥ −1: the column left of the first is the last.
    let c0 = u32(i32(x0) + i32(width)) % width;
    let c1 = (c0 + 1u) % width;
    let r0 = u32(y0);
    let top = rounded3(rounded3((1.0 - fx) * environment_texel(c0, r0))
        + rounded3(fx * environment_texel(c1, r0)));
    let bottom = rounded3(rounded3((1.0 - fx) * environment_texel(c0, r0 + 1u))
        + rounded3(fx * environment_texel(c1, r0 + 1u)));
    return rounded3(rounded3((1.0 - fy) * top) + rounded3(fy * bottom));
}

// The radiance arriving from the environment along world direction `dir`
// (towards the sky): its map's, its constant colour where it has none, 0
// where the scene has no environment.
fn environment_radiance(dir: vec3<f32>) -> vec3<f32> {
    if !HAS_ENVIRONMENT {
        return vec3<f32>(0.0);
    }
    if (lighting.flags & LIGHTING_ENVIRONMENT_IMAGE) == 0u {
        return lighting.environment_color;
    }
    return environment_lookup(environment_uv(environment_local(dir)));
}

// pbrt-v4's FindInterval over the `size` entries of `environment_cdf`
// from `start`: the last i (at most size − 2) with cdf[i] ≤ u.
fn find_interval(start: u32, size: u32, u: f32) -> u32 {
    var first = 1u;
    var remaining = size - 2u;
    while remaining > 0u {
        let half = remaining >> 1u;
        let middle = first + half;
        if environment_cdf_at(start + middle) <= u {
            first = middle + 1u;
            remaining -= half + 1u;
        } else {
            remaining = half;
        }
    }
    return clamp(first, 1u, size - 1u) - 1u;
}

// The map's cells: its rows of cells (the bands between its rows of
// texels), its columns, and where row `row`'s conditional CDF starts.
fn conditional_start(rows: u32, columns: u32, row: u32) -> u32 {
    return rows + 1u + row * (columns + 1u);
}

// A direction drawn from the environment, with the radiance along it and
// its pdf in solid angle (0: none): a map's cells by luminance times solid
// angle, then uniformly within the cell in (u, v); a constant colour
// uniformly over the sphere.
fn sample_environment(u: vec2<f32>) -> EmitterSample {
    var out: EmitterSample;
    out.distance = FAR;
    out.delta = false;
    out.pdf = 0.0;
    if (lighting.flags & LIGHTING_ENVIRONMENT_IMAGE) == 0u {
        let z = rounded(1.0 - rounded(2.0 * u.x));
        let r = safe_sqrt(rounded(1.0 - rounded(z * z)));
        let sc = approx_sin_cos(rounded(TWO_PI * u.y));
        out.wi = vec3<f32>(rounded(r * sc.y), rounded(r * sc.x), z);
        out.radiance = lighting.environment_color;
        out.pdf = INV_FOUR_PI;
        return out;
    }
    let columns = lighting.environment_width;
    let rows = lighting.environment_height - 1u;
    let row = find_interval(0u, rows + 1u, u.y);
    let m0 = environment_cdf_at(row);
    let dm = rounded(environment_cdf_at(row + 1u) - m0);
    let start = conditional_start(rows, columns, row);
    let column = find_interval(start, columns + 1u, u.x);
    let c0 = environment_cdf_at(start + column);
    let dc = rounded(environment_cdf_at(start + column + 1u) - c0);
    if !(dm > 0.0 && dc > 0.0) {
        return out;
    }
    let t = rounded(rounded(f32(row) + rounded(rounded(u.y - m0) / dm)) / f32(rows));
    let s = rounded(rounded(f32(column) + rounded(rounded(u.x - c0) / dc)) / f32(columns));
    // Cell j starts at texel j's centre.
    var map_u = s + rounded(0.5 / f32(columns));
    if map_u >= 1.0 {
        map_u -= 1.0;
    }
    let theta = approx_sin_cos(rounded(PI * t));
    let phi = approx_sin_cos(rounded(TWO_PI * map_u));
    if !(theta.x > 0.0) {
        return out;
    }
    let d = vec3<f32>(rounded(phi.x * theta.x), theta.y, -rounded(phi.y * theta.x));
    out.wi = environment_world(d);
    out.radiance = environment_lookup(vec2<f32>(map_u, t));
    let pdf_uv = rounded(rounded(dm * f32(rows)) * rounded(dc * f32(columns)));
    out.pdf = rounded(rounded(opaque_copy(pdf_uv) * INV_TWO_PI_SQUARED) / theta.x);
    return out;
}

// The pdf `sample_emitter` would have given world direction `dir` by way
// of the environment: how a ray the BSDF sampled weighs the environment it
// reached. 0 where the scene has none.
fn environment_pdf(dir: vec3<f32>) -> f32 {
    if !HAS_ENVIRONMENT {
        return 0.0;
    }
    let pmf = lighting.environment_pmf;
    if (lighting.flags & LIGHTING_ENVIRONMENT_IMAGE) == 0u {
        return rounded(INV_FOUR_PI * pmf);
    }
    let d = environment_local(dir);
    let uv = environment_uv(d);
    let columns = lighting.environment_width;
    let rows = lighting.environment_height - 1u;
    var s = uv.x - rounded(0.5 / f32(columns));
    if s < 0.0 {
        s += 1.0;
    }
    let column = min(u32(rounded(s * f32(columns))), columns - 1u);
    let row = min(u32(rounded(uv.y * f32(rows))), rows - 1u);
    let start = conditional_start(rows, columns, row);
    let dm = rounded(environment_cdf_at(row + 1u) - environment_cdf_at(row));
    let dc = rounded(environment_cdf_at(start + column + 1u) - environment_cdf_at(start + column));
    let sin_theta = safe_sqrt(rounded(rounded(d.x * d.x) + rounded(d.z * d.z)));
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let pdf_uv = rounded(rounded(dm * f32(rows)) * rounded(dc * f32(columns)));
    return rounded(rounded(rounded(opaque_copy(pdf_uv) * INV_TWO_PI_SQUARED) / sin_theta) * pmf);
}
