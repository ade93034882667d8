// Stage: traversal in the GPU's ray-tracing units (`--accel hardware`,
// docs/hardware-rays.md): `trace` as a ray query against the scene's TLAS,
// which src/gpu/hardware.rs builds, in place of shaders/trace.wgsl's
// compute BVH; everything above (`trace_closest`, `trace_any`, shading,
// sampling, the integrator, the entry points) is the same source, in a
// module of its own (src/shader_source.rs, HARDWARE_SOURCE) that opens
// with shaders/hardware_layout.wgsl. No CPU twin of its own: its answers
// are those of shaders/trace.wgsl's twin (`trace` in src/cpu/traverse.rs),
// within the bounds docs/hardware-rays.md states.

// Whether every component of `v` is finite (by its bits, as `has_nan`).
fn is_finite3(v: vec3<f32>) -> bool {
    return all((bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u)) != vec3<u32>(0x7f800000u));
}

// Whether a ray query may take the prepared `ray`: Vulkan's rules for
// rayQueryInitialize (a finite origin and direction, 0 ≤ tmin ≤ tmax, no
// NaN; `prepare_ray` made tmax finite) and a direction that is not zero.
// Any other ray takes the compute BVH, which answers it as the CPU does.
fn hardware_takes(ray: Ray) -> bool {
    return is_finite3(ray.origin) && is_finite3(ray.dir) && any(ray.dir != vec3<f32>(0.0))
        && ray.tmin >= 0.0 && ray.tmin <= ray.tmax;
}

// The primitive id of a ray query's intersection.
fn hardware_prim(intersection: RayIntersection) -> u32 {
    let run = intersection.instance_custom_data + intersection.geometry_index;
    return hardware_runs[run] + intersection.primitive_index;
}

// The hit of triangle `prim`, found by the hardware at distance `t` and
// barycentrics `uv`: the exact test's (t, u, v) where it hits the
// triangle too (`--intersect`'s test, the compute path's: so a hit both
// find has the same bits), else the hardware's own.
fn refined_hit(ray: Ray, shear: Shear, prim: u32, t: f32, uv: vec2<f32>) -> Hit {
    let tri = triangle_at(prim);
    let exact = intersect_triangle(ray, shear, tri.v0, tri.v1, tri.v2);
    if exact.x < FAR {
        return Hit(exact.x, prim, exact.y, exact.z);
    }
    return Hit(t, prim, uv.x, uv.y);
}

// The hit of the prepared `ray` on primitive `prim`, whose box the
// hardware found, before `ray.tmax`: the compute path's own tests (the
// triangle's with its alpha mask, or the sphere's); a miss if none.
fn box_hit(ray: Ray, shear: Shear, prim: u32) -> Hit {
    if prim < params.num_triangles {
        let tri = triangle_at(prim);
        let tuv = intersect_triangle(ray, shear, tri.v0, tri.v1, tri.v2);
        if tuv.x < ray.tmax && !cut_out(prim, tuv.y, tuv.z) {
            return Hit(tuv.x, prim, tuv.y, tuv.z);
        }
        return miss();
    }
    let sphere = sphere_at(prim - params.num_triangles);
    let t = intersect_sphere(ray, sphere.center, sphere.radius);
    if t < ray.tmax {
        return Hit(t, prim, 0.0, 0.0);
    }
    return miss();
}

// Closest hit, or with `any_hit` the first hit found (the query ends at
// it). Opaque triangles are decided in the hardware; a candidate reaches
// the loop only where the hardware cannot decide it: a box (a sphere's, or
// a triangle's where the driver's own tests leak), tested as the compute
// path tests it, or an alpha-masked triangle (the only non-opaque
// triangles: confirmed unless `cut_out`).
//
// Box hits are kept here (`best`), not read back from the query: wgpu
// allows the committed intersection to be read only once the traversal
// is done, and naga 30 checks a generated hit's distance against the
// candidate's (for a box, undefined) rather than the committed one, so it
// drops some generated hits (docs/hardware-rays.md, "Bugs met"). A hit
// is still generated where all committed hits are generated ones (the
// triangles as boxes), so that the traversal skips what lies beyond it.
fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    if is_nan_ray(ray_in) {
        return miss();
    }
    let prepared = prepare_ray(ray_in);
    let ray = prepared.ray;
    let shear = prepared.shear;
    if !hardware_takes(ray) {
        // USE_BVH is set under --accel hardware (src/gpu/shader.rs).
        return unscale(trace_compressed(ray, shear, any_hit), shear);
    }
    var flags = RAY_FLAG_NONE;
    if any_hit {
        flags = RAY_FLAG_TERMINATE_ON_FIRST_HIT;
    }
    var query: ray_query;
    rayQueryInitialize(&query, scene_tlas, RayDesc(flags, 0xffu, ray.tmin, ray.tmax, ray.origin, ray.dir));
    var best = miss();
    while rayQueryProceed(&query) {
        let candidate = rayQueryGetCandidateIntersection(&query);
        let prim = hardware_prim(candidate);
        if candidate.kind == RAY_QUERY_INTERSECTION_AABB {
            var nearer = ray;
            nearer.tmax = min(ray.tmax, best.t);
            let hit = box_hit(nearer, shear, prim);
            if hit.prim != NO_HIT {
                best = hit;
                if HARDWARE_TRIANGLE_BOXES {
                    // Nearer than every committed hit: each is one of ours.
                    // A `let`: naga 30 does not emit an argument expression
                    // of this call before it (docs/hardware-rays.md).
                    let t = hit.t;
                    rayQueryGenerateIntersection(&query, t);
                }
                if any_hit {
                    rayQueryTerminate(&query);
                }
            }
        } else {
            let hit = refined_hit(ray, shear, prim, candidate.t, candidate.barycentrics);
            if !cut_out(prim, hit.u, hit.v) {
                rayQueryConfirmIntersection(&query);
            }
        }
    }
    let committed = rayQueryGetCommittedIntersection(&query);
    if committed.kind == RAY_QUERY_INTERSECTION_TRIANGLE {
        // The hardware's triangle, its (u, v) and t from the exact test.
        let prim = hardware_prim(committed);
        let hit = refined_hit(ray, shear, prim, committed.t, committed.barycentrics);
        if hit.t < best.t {
            best = hit;
        }
    }
    return unscale(best, shear);
}

// Every crossing of a ray (the count and list queries) through a ray
// query where the triangles are boxes: each box the hardware reports,
// opaque or not, tested by `crossing` (all_hits.wgsl's watertight test,
// an edge owned by one triangle), never committed, so that the traversal
// visits every box along the ray. Triangles the hardware tests itself
// reach the shader only where its own test hits them, and on an edge that
// need not be the triangle lambert's rule counts: there, and for rays a
// query may not take, the compute BVH's walk (`all_hits`).
fn every_hit(ray_in: Ray, index: u32, pad: f32, fill: bool, base: u32) -> u32 {
    let prepared = prepare_ray(ray_in);
    let ray = prepared.ray;
    let shear = prepared.shear;
    if !HARDWARE_TRIANGLE_BOXES || is_nan_ray(ray_in) || !hardware_takes(ray) {
        return all_hits(ray_in, index, pad, fill, base);
    }
    var query: ray_query;
    rayQueryInitialize(&query, scene_tlas, RayDesc(RAY_FLAG_FORCE_NO_OPAQUE, 0xffu, ray.tmin, ray.tmax, ray.origin, ray.dir));
    var count = 0u;
    while rayQueryProceed(&query) {
        let prim = hardware_prim(rayQueryGetCandidateIntersection(&query));
        if prim < params.num_triangles {
            let tri = triangle_at(prim);
            let h = crossing(ray, shear, tri.v0, tri.v1, tri.v2);
            if h.x < FAR {
                if fill {
                    listed_hits[base + count] = ListedHit(index, prim, h.x * shear.t_scale, h.y, h.z);
                }
                count += 1u;
            }
        }
    }
    return count;
}
