// Stage: materials. What the path integrator's BSDF sees at a hit: its
// parameters (the base colour, which is the direct integrator's albedo;
// the kind; metalness and roughness, × the metallic-roughness texture's B
// and G) and the shading normal, tilted by the normal map. CPU twin:
// src/cpu/material.rs. The tangent frame's products are `rounded` each
// (no multiply-add fuses) and its normalisations `normalize3`'s, so the
// twins agree where the division and square root do (lavapipe's are
// IEEE's); the interpolated normal it starts from is `surface_at`'s.

struct SurfaceMaterial {
    bsdf: BsdfParams,
    // Unit; on the side the ray arrives from, as `Surface`'s normals are.
    shading_normal: vec3<f32>,
}

fn material_at(ray: Ray, hit: Hit, surface: Surface) -> SurfaceMaterial {
    if HAS_SPHERES && hit.prim >= params.num_triangles {
        let m = sphere_at(hit.prim - params.num_triangles).material;
        return SurfaceMaterial(BsdfParams(surface.albedo, material_entry(m).metallic,
            material_entry(m).roughness, material_entry(m).kind), surface.shading_normal);
    }
    let tri = triangle_at(hit.prim);
    var out = SurfaceMaterial(BsdfParams(surface.albedo, material_entry(tri.material).metallic,
        material_entry(tri.material).roughness, material_entry(tri.material).kind), surface.shading_normal);
    // Texture slots are filled only for meshes with texture coordinates.
    if !HAS_TEXTURES || (tri.flags & FLAG_ATTRIBUTES) == 0u {
        return out;
    }
    // The camera ray's cone where it hits, as `surface_at` takes it.
    let cone_width = hit.t * params.cone_spread;
    let metallic_roughness = material_entry(tri.material).metallic_roughness_texture;
    if metallic_roughness != NO_TEXTURE {
        let texel = texture_at(metallic_roughness, tri, hit.prim, hit.u, hit.v, ray.dir,
            cone_width);
        out.bsdf.metallic *= texel.b;
        out.bsdf.roughness *= texel.g;
    }
    let normal_texture = material_entry(tri.material).normal_texture;
    if HAS_NORMAL_MAPS && normal_texture != NO_TEXTURE {
        let texel = texture_at(normal_texture, tri, hit.prim, hit.u, hit.v, ray.dir, cone_width);
        out.shading_normal = normal_mapped(tri, hit, ray.dir, texel.rgb,
            material_entry(tri.material).normal_scale);
    }
    return out;
}

// a × b, each component `difference_of_products`'s.
fn cross_rounded(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(difference_of_products(a.y, b.z, a.z, b.y),
        difference_of_products(a.z, b.x, a.x, b.z), difference_of_products(a.x, b.y, a.y, b.x));
}

// The shading normal a normal map's `texel` gives at `hit` (glTF's
// convention: RGB in [0, 1] holds the tangent-space vector 2·texel − 1,
// X along the tangent, Y along the bitangent, Z along the normal; X and Y
// × `scale`). The frame: the interpolated normal n (`vertex_normal`), the
// interpolated tangent made orthogonal to it (Gram-Schmidt), and the
// bitangent w · n × t, w the interpolated sign. The result is turned to
// the ray's side when n is (as `surface_at` turns n), so the map tilts
// the back of a surface as it tilts the front. n where the frame
// degenerates (a tangent along n, or a zero vector).
fn normal_mapped(tri: Triangle, hit: Hit, dir: vec3<f32>, texel: vec3<f32>, scale: f32) -> vec3<f32> {
    let w = 1.0 - hit.u - hit.v;
    let outward = normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
    let n = vertex_normal(tri, hit.prim, w, hit.u, hit.v, outward);
    let side = select(1.0, -1.0, dot(n, dir) > 0.0);
    let frames = triangle_tangents_at(hit.prim);
    let interpolated = rounded4(rounded4(w * frames.t0)
        + rounded4(rounded4(hit.u * frames.t1) + rounded4(hit.v * frames.t2)));
    let tangent = rounded3(interpolated.xyz - rounded3(n * dot_rounded(n, interpolated.xyz)));
    if !(dot_rounded(tangent, tangent) > 0.0) {
        return side * n;
    }
    let t = normalize3(tangent);
    let b = select(1.0, -1.0, interpolated.w < 0.0) * cross_rounded(n, t);
    let m = vec3<f32>(scale * (2.0 * texel.x - 1.0), scale * (2.0 * texel.y - 1.0),
        2.0 * texel.z - 1.0);
    let mapped = rounded3(rounded3(rounded3(m.x * t) + rounded3(m.y * b)) + rounded3(m.z * n));
    if !(dot_rounded(mapped, mapped) > 0.0) {
        return side * n;
    }
    return side * normalize3(mapped);
}
