// Stage: intersection. The ray/triangle tests (seed, Möller–Trumbore,
// watertight, and the watertight one on a leaf block's four lanes), the
// ray/sphere test with its error-free arithmetic, and the recording of the
// nearest hit. CPU twin: src/cpu/intersect.rs.

fn miss() -> Hit {
    return Hit(FAR, NO_HIT, 0.0, 0.0);
}

fn intersect_triangle(ray: Ray, shear: Shear, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    if INTERSECT == INTERSECT_SEED {
        return intersect_triangle_seed(ray, a, b, c);
    }
    if INTERSECT == INTERSECT_MOLLER_TRUMBORE {
        return intersect_triangle_moller_trumbore(ray, a, b, c);
    }
    return intersect_triangle_watertight(ray, shear, a, b, c);
}

fn no_triangle_hit() -> vec3<f32> {
    return vec3<f32>(FAR, 0.0, 0.0);
}

// The lecture's test: plane hit t = n·(a − o)/(n·d), then three edge tests
// that must all agree in sign. Returns (t, u, v); t = FAR on a miss.
fn intersect_triangle_seed(ray: Ray, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let n = cross(b - a, c - a);
    let n_dot_d = dot(n, ray.dir);
    if n_dot_d == 0.0 {
        return no_triangle_hit();
    }
    let t = dot(n, a - ray.origin) / n_dot_d;
    // Written so that a NaN t is a miss too.
    if !(t > ray.tmin && t < ray.tmax) {
        return no_triangle_hit();
    }
    let p = ray.origin + t * ray.dir;
    let e0 = dot(cross(b - a, p - a), n);
    let e1 = dot(cross(c - b, p - b), n);
    let e2 = dot(cross(a - c, p - c), n);
    let inside = (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
    if !inside {
        return no_triangle_hit();
    }
    // Edge values are twice the sub-triangle areas times |n|: barycentrics.
    let nn = dot(n, n);
    return vec3<f32>(t, e2 / nn, e0 / nn);
}

// Möller and Trumbore (1997), without the epsilon on the determinant so that
// it works at every scale: only an exactly parallel ray is rejected.
fn intersect_triangle_moller_trumbore(ray: Ray, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return no_triangle_hit();
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - a;
    let u = dot(s, p) * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return no_triangle_hit();
    }
    let q = cross(s, e1);
    let v = dot(ray.dir, q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return no_triangle_hit();
    }
    let t = dot(e2, q) * inv_det;
    if !(t > ray.tmin && t < ray.tmax) {
        return no_triangle_hit();
    }
    return vec3<f32>(t, u, v);
}

fn ray_shear(dir: vec3<f32>) -> Shear {
    let m = abs(dir);
    var kz = 2u;
    if m.x >= m.y && m.x >= m.z {
        kz = 0u;
    } else if m.y >= m.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    // Keep the winding: swapping x and y mirrors when d points down z.
    if dir[kz] < 0.0 {
        let k = kx;
        kx = ky;
        ky = k;
    }
    return Shear(vec3<u32>(kx, ky, kz), vec3<f32>(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]), 1.0);
}

// Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT
// 2013): vertices moved into a frame where the ray is the +z axis through
// the origin, so that an edge shared by two triangles gives both of them the
// same edge value, up to sign. A ray cannot pass between them.
// Edge values of exactly 0 count as inside for both (the paper recomputes
// them in f64, which GPUs may lack; a tie then hits both, never neither).
fn intersect_triangle_watertight(ray: Ray, shear: Shear, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    return watertight_test(ray, shear, a, b, c, false);
}

// The watertight test; with `owned_edges`, an edge value of exactly 0
// counts only for the triangle that owns_edge (every-hit queries, which
// must count a crossing once) rather than for both.
fn watertight_test(ray: Ray, shear: Shear, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, owned_edges: bool) -> vec3<f32> {
    let k = shear.axes;
    let oa = a - ray.origin;
    let ob = b - ray.origin;
    let oc = c - ray.origin;
    let ax = oa[k.x] - shear.s.x * oa[k.z];
    let ay = oa[k.y] - shear.s.y * oa[k.z];
    let bx = ob[k.x] - shear.s.x * ob[k.z];
    let by = ob[k.y] - shear.s.y * ob[k.z];
    let cx = oc[k.x] - shear.s.x * oc[k.z];
    let cy = oc[k.y] - shear.s.y * oc[k.z];
    // u: edge c → b, v: a → c, w: b → a.
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return no_triangle_hit();
    }
    let det = u + v + w;
    if det == 0.0 {
        return no_triangle_hit();
    }
    if owned_edges && ((u == 0.0 && !owns_edge(bx - cx, by - cy, det))
        || (v == 0.0 && !owns_edge(cx - ax, cy - ay, det))
        || (w == 0.0 && !owns_edge(ax - bx, ay - by, det))) {
        return no_triangle_hit();
    }
    let t_scaled = u * shear.s.z * oa[k.z] + v * shear.s.z * ob[k.z] + w * shear.s.z * oc[k.z];
    let t = t_scaled / det;
    if !(t > ray.tmin && t < ray.tmax) {
        return no_triangle_hit();
    }
    // u, v and w weigh a, b and c: the hit is (1 − u' − v')·a + u'·b + v'·c.
    return vec3<f32>(t, v / det, w / det);
}

// A leaf block's four lanes after intersect_triangle_block: t per lane (FAR
// where it misses), and what u and v are divided from, since only a
// recorded hit needs them.
struct BlockHits {
    t: vec4<f32>,
    v: vec4<f32>,
    w: vec4<f32>,
    det: vec4<f32>,
}

// (u, v) of lane `lane`, as intersect_triangle_watertight gives them.
fn block_uv(lanes: BlockHits, lane: u32) -> vec2<f32> {
    return vec2<f32>(lanes.v[lane] / lanes.det[lane], lanes.w[lane] / lanes.det[lane]);
}

// intersect_triangle_watertight on a block's four lanes at once, the same
// operations in the same order in each; t = FAR where a lane misses (a lane
// of zero vertices too, unless the device fuses multiply-adds:
// record_block_hits looks only at triangle lanes).
fn intersect_triangle_block(ray: Ray, shear: Shear, block: u32) -> BlockHits {
    let k = shear.axes;
    // Coordinate k.x, k.y or k.z of each vertex relative to the origin.
    let az = block_lanes(block, 0u, k.z) - vec4<f32>(ray.origin[k.z]);
    let bz = block_lanes(block, 1u, k.z) - vec4<f32>(ray.origin[k.z]);
    let cz = block_lanes(block, 2u, k.z) - vec4<f32>(ray.origin[k.z]);
    let ax = (block_lanes(block, 0u, k.x) - vec4<f32>(ray.origin[k.x])) - shear.s.x * az;
    let ay = (block_lanes(block, 0u, k.y) - vec4<f32>(ray.origin[k.y])) - shear.s.y * az;
    let bx = (block_lanes(block, 1u, k.x) - vec4<f32>(ray.origin[k.x])) - shear.s.x * bz;
    let by = (block_lanes(block, 1u, k.y) - vec4<f32>(ray.origin[k.y])) - shear.s.y * bz;
    let cx = (block_lanes(block, 2u, k.x) - vec4<f32>(ray.origin[k.x])) - shear.s.x * cz;
    let cy = (block_lanes(block, 2u, k.y) - vec4<f32>(ray.origin[k.y])) - shear.s.y * cz;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = vec4<f32>(0.0);
    let outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
    let det = u + v + w;
    let t = (u * shear.s.z * az + v * shear.s.z * bz + w * shear.s.z * cz) / det;
    let hit = !outside & (det != zero) & (t > vec4<f32>(ray.tmin)) & (t < vec4<f32>(ray.tmax));
    return BlockHits(select(vec4<f32>(FAR), t, hit), v, w, det);
}

// Nearest root of |o + t·d − c|² = r² inside (tmin, tmax); FAR on a miss.
// Uses the cancellation-free form of Ray Tracing Gems ch. 7, with c from
// `sphere_gap`.
fn intersect_sphere(ray: Ray, center: vec3<f32>, radius: f32) -> f32 {
    let oc = ray.origin - center;
    let a = dot(ray.dir, ray.dir);
    let b = dot(oc, ray.dir);
    let c = sphere_gap(ray.origin, center, radius);
    let f = oc - (b / a) * ray.dir;
    let discriminant = a * (radius * radius - dot(f, f));
    if discriminant < 0.0 {
        return FAR;
    }
    let q = -b - sign_nonzero(b) * sqrt(discriminant);
    let t0 = c / q;
    let t1 = q / a;
    let near = min(t0, t1);
    let far = max(t0, t1);
    if near > ray.tmin && near < ray.tmax {
        return near;
    }
    if far > ray.tmin && far < ray.tmax {
        return far;
    }
    return FAR;
}

// |o − c|² − r² with every rounding error kept and added back: near a
// large sphere the two squares cancel in most of their digits.
fn sphere_gap(origin: vec3<f32>, center: vec3<f32>, radius: f32) -> f32 {
    let x = two_sum(origin.x, -center.x);
    let y = two_sum(origin.y, -center.y);
    let z = two_sum(origin.z, -center.z);
    let xx = two_square(x.x);
    let yy = two_square(y.x);
    let zz = two_square(z.x);
    let rr = two_square(radius);
    let s1 = two_sum(xx.x, yy.x);
    let s2 = two_sum(s1.x, zz.x);
    let s3 = two_sum(s2.x, -rr.x);
    let cross = 2.0 * (x.x * x.y + y.x * y.y + z.x * z.y);
    return s3.x + (((s1.y + s2.y) + s3.y) + (((xx.y + yy.y) + zz.y) - rr.y) + cross);
}

// (a + b rounded, its rounding error): Knuth's TwoSum. The sum passes
// through `opaque_one`, or the driver's optimiser, the operations not being
// marked exact, folds (a + b) − a to b and the error to 0 (Mesa's does).
fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = (a + b) * opaque_one();
    let bb = s - a;
    return vec2<f32>(s, (a - (s - bb)) + (b - bb));
}

// (a² rounded, its rounding error): Dekker's, every product of halves
// exact, so the same bits whether or not a multiply-add is fused.
fn two_square(a: f32) -> vec2<f32> {
    let hi = high_half(a);
    let lo = a - hi;
    let p = a * a;
    return vec2<f32>(p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo);
}

// 1, from a number no compiler can know: only scenes with spheres call it.
fn opaque_one() -> f32 {
    return f32(min(params.num_spheres, 1u));
}

// `x` with the low 12 of its 23 stored mantissa bits cleared (a split by
// mask: no multiply for a fused multiply-add to spoil).
fn high_half(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) & 0xfffff000u);
}

fn sign_nonzero(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

// (t, u, v) of primitive `prim` (triangles first, then spheres).
fn intersect_primitive(ray: Ray, shear: Shear, prim: u32) -> vec3<f32> {
    if HAS_TRIANGLES && prim < params.num_triangles {
        let tri = triangle_at(prim);
        return intersect_triangle(ray, shear, tri.v0, tri.v1, tri.v2);
    }
    if HAS_SPHERES && prim >= params.num_triangles {
        let sphere = sphere_at(prim - params.num_triangles);
        return vec3<f32>(intersect_sphere(ray, sphere.center, sphere.radius), 0.0, 0.0);
    }
    return no_triangle_hit();
}

// The texture in `slot` at (u, v) of triangle `prim` (which has
// FLAG_ATTRIBUTES: slots are only filled for meshes with texture
// coordinates), at the level of detail of a ray cone `cone_width` wide
// there along `dir`; a cone of width 0 reads the base level (the any-hit
// test's alpha).
fn texture_at(slot: u32, tri: Triangle, prim: u32, u: f32, v: f32, dir: vec3<f32>, cone_width: f32) -> vec4<f32> {
    let a = triangle_attributes_at(prim);
    let uv = interpolate_uv(a.uvs[0], a.uvs[1], a.uvs[2], u, v);
    var lod = 0;
    if cone_width > 0.0 {
        lod = texture_lod(slot, tri.v0, tri.v1, tri.v2, a.uvs[0], a.uvs[1], a.uvs[2], dir, cone_width);
    }
    return sample_texture(slot, uv, lod);
}

// The base colour at (u, v) of triangle `prim`: its material's, times its
// corners' colours interpolated (FLAG_ATTRIBUTES), times its base colour
// texture (RGBA) and its alpha texture's alpha, read as `texture_at` does.
// Alpha and shading both read it.
fn base_color_at(tri: Triangle, prim: u32, u: f32, v: f32, dir: vec3<f32>, cone_width: f32) -> vec4<f32> {
    var color = material_entry(tri.material).base_color;
    if HAS_ATTRIBUTES && (tri.flags & FLAG_ATTRIBUTES) != 0u {
        let a = triangle_attributes_at(prim);
        // Each product and sum rounded on its own (`rounded`), as the
        // CPU's: lavapipe neither fuses an explicit `fma` reliably nor
        // keeps a sum's order unless told (docs/textures.md).
        let w = rounded(rounded(1.0 - u) - v);
        color *= rounded4(rounded4(w * a.colors[0])
            + rounded4(rounded4(u * a.colors[1]) + rounded4(v * a.colors[2])));
        let base_color_texture = material_entry(tri.material).base_color_texture;
        if HAS_TEXTURES && base_color_texture != NO_TEXTURE {
            color *= texture_at(base_color_texture, tri, prim, u, v, dir, cone_width);
        }
        let alpha_texture = material_entry(tri.material).alpha_texture;
        if HAS_TEXTURES && alpha_texture != NO_TEXTURE {
            color.a *= texture_at(alpha_texture, tri, prim, u, v, dir, cone_width).a;
        }
    }
    return color;
}

// Whether a hit at (u, v) of primitive `prim` falls in an alpha-masked
// triangle's cut-out (alpha below its material's cut-off): the any-hit
// test, made where a hit would be recorded, so a cut-out costs no extra
// traversal; opaque triangles (no FLAG_MASKED) pay one flag test, and
// scenes without masks nothing (HAS_ALPHA_MASK).
fn cut_out(prim: u32, u: f32, v: f32) -> bool {
    if !HAS_ALPHA_MASK || prim >= params.num_triangles {
        return false;
    }
    let tri = triangle_at(prim);
    if (tri.flags & FLAG_MASKED) == 0u {
        return false;
    }
    return base_color_at(tri, prim, u, v, vec3<f32>(0.0), 0.0).a < material_entry(tri.material).alpha_cutoff;
}

// Tests `prim`; if it is hit nearer than ray.tmax, makes it the hit and
// shortens the ray. Returns whether it did.
fn record_hit(ray: ptr<function, Ray>, shear: Shear, hit: ptr<function, Hit>, prim: u32) -> bool {
    let tuv = intersect_primitive(*ray, shear, prim);
    if tuv.x < (*ray).tmax && !cut_out(prim, tuv.y, tuv.z) {
        (*ray).tmax = tuv.x;
        *hit = Hit(tuv.x, prim, tuv.y, tuv.z);
        return true;
    }
    return false;
}

// Tests a leaf block's primitives: its triangles in one 4-lane watertight
// test, then (in lane order) its spheres, and its triangles too under
// another triangle test. Each hit nearer than ray.tmax becomes the hit and
// shortens the ray; returns whether there was one.
fn record_block_hits(
    ray: ptr<function, Ray>,
    shear: Shear,
    hit: ptr<function, Hit>,
    block: u32,
) -> bool {
    let watertight = INTERSECT == INTERSECT_WATERTIGHT;
    let prims = block_prims(block);
    var recorded = false;
    if watertight && HAS_TRIANGLES {
        let lanes = intersect_triangle_block(*ray, shear, block);
        for (var lane = 0u; lane < 4u; lane++) {
            // Only triangle lanes (the id test also drops empty ones): a
            // GPU that fuses multiply-adds can see a hit in a lane of zero
            // vertices.
            if lanes.t[lane] < (*ray).tmax && prims[lane] < params.num_triangles {
                let uv = block_uv(lanes, lane);
                if !cut_out(prims[lane], uv.x, uv.y) {
                    (*ray).tmax = lanes.t[lane];
                    *hit = Hit(lanes.t[lane], prims[lane], uv.x, uv.y);
                    recorded = true;
                }
            }
        }
    }
    if !watertight || HAS_SPHERES {
        for (var lane = 0u; lane < 4u; lane++) {
            let prim = prims[lane];
            if prim != NO_HIT && !(watertight && prim < params.num_triangles) {
                recorded = record_hit(ray, shear, hit, prim) || recorded;
            }
        }
    }
    return recorded;
}
