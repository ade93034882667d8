// lambert's ray tracing kernel: one invocation per pixel (entry point `render`)
// or per ray (entry point `trace_rays`).
//
// The CPU reference in src/cpu/kernel.rs mirrors this file function by
// function with the same names; change both together.

// Specialisation: the host sets these per scene so that a variant carries no
// code for what its scene lacks. Defaults give the full shader.
override HAS_TRIANGLES: bool = true;
override HAS_SPHERES: bool = true;
override HAS_SHADOWS: bool = true;
override HAS_POINT_LIGHTS: bool = true;
override HAS_DIRECTIONAL_LIGHTS: bool = true;
// false: test every primitive (the reference that tests the BVH).
override USE_BVH: bool = true;
// Ray/triangle test: INTERSECT_SEED, INTERSECT_MOLLER_TRUMBORE or
// INTERSECT_WATERTIGHT.
override INTERSECT: u32 = 2u;
// Entry point `trace_rays`: stop at the first hit found rather than the
// closest.
override ANY_HIT: bool = false;
// Arrays too large for one storage binding are split over two: the first
// this many elements in `triangles` (and `triangle_normals`), `bvh_nodes`
// or `bvh_blocks`, the rest in the `_hi` binding. Unsplit: all.
override TRIANGLES_PER_BINDING: u32 = 0xffffffffu;
override NODES_PER_BINDING: u32 = 0xffffffffu;
override BLOCKS_PER_BINDING: u32 = 0xffffffffu;
// Read the BVH's nodes and blocks from `bvh_node_texels` and
// `bvh_block_texels` rather than the storage buffers (gpu::BvhStorage:
// lavapipe fetches texels with vector gathers, storage words a lane at a
// time).
override BVH_TEXELS: bool = false;
// The `render` entry point's workgroup: gpu::RENDER_WORKGROUP, measured
// (docs/bvh.md).
override RENDER_WORKGROUP_X: u32 = 8u;
override RENDER_WORKGROUP_Y: u32 = 8u;
// Traversal stack entries per invocation in workgroup memory (gpu.rs):
// the scene's BVH depth − 1, the most `trace_compressed` can push (see
// MAX_DEPTH), up to cwbvh::SHORT_STACK_ENTRIES. A deeper tree sets
// STACK_SPILLS: the stack's oldest entries then move to `stack_spill`.
override STACK_ENTRIES: u32 = 8u;
override STACK_SPILLS: bool = false;
// Invocations per workgroup of every entry point (RENDER_WORKGROUP_X ×
// RENDER_WORKGROUP_Y for `render`).
const WORKGROUP_INVOCATIONS: u32 = 64u;

const NO_HIT: u32 = 0xffffffffu;
// Texels a row of the BVH textures: 1 << TEXEL_ROW_BITS (gpu::TEXELS_PER_ROW).
const TEXEL_ROW_BITS: u32 = 12u;
// WGSL has no infinity literal; the largest finite f32 serves as "no hit yet".
const FAR: f32 = 3.40282347e38;
const LIGHT_POINT: u32 = 0u;
const LIGHT_DIRECTIONAL: u32 = 1u;
const FLAG_SMOOTH: u32 = 1u;
const INTERSECT_SEED: u32 = 0u;
const INTERSECT_MOLLER_TRUMBORE: u32 = 1u;
const INTERSECT_WATERTIGHT: u32 = 2u;
// Unit roundoff of f32 (pbrt's MachineEpsilon), for error bounds.
const MACHINE_EPSILON: f32 = 5.96046448e-8;
// Wide levels at most: bvh::MAX_DEPTH. A traversal stack entry is a node
// group (a node and the entered children of it not visited yet), pushed
// when traversal descends below that node: one per level at most, so a
// tree of depth d needs d − 1 entries, and the tree is at most MAX_DEPTH
// levels deep (Bvh::from_binary checks): the short stack and its spill
// (STACK_ENTRIES, stack_spill) never overflow.
const MAX_DEPTH: u32 = 24u;
// CompressedNode meta bytes (src/layout.rs): 0 for an empty slot,
// META_INTERIOR | rank for an interior child, META_LEAF | (count − 1) << 4
// | offset for a leaf.
const META_INTERIOR: u32 = 0x08u;
const META_LEAF: u32 = 0x80u;
// Widens a box's exit distance so that rounding in the slab test cannot cull
// a box the ray grazes: pbrt-v4's 1 + 2·gamma(3), with room for a GPU's
// reciprocal being up to a few ULPs off (WGSL allows 2.5). The watertight
// triangle test relies on it: no box may drop a ray its triangles catch.
const BOX_SLACK: f32 = 1.000001;

// Layouts: each struct here has a #[repr(C)] twin in src/layout.rs, checked
// against naga's reflection of this file by tests/shaders.rs.
struct Params {
    eye: vec3<f32>,
    width: u32,
    right: vec3<f32>,
    height: u32,
    up: vec3<f32>,
    tan_half_x: f32,
    forward: vec3<f32>,
    tan_half_y: f32,
    background: vec3<f32>,
    num_triangles: u32,
    ambient: vec3<f32>,
    num_spheres: u32,
    tile_origin: vec2<u32>,
    num_lights: u32,
    shadows: u32,
    // Samples per pixel and the seed of their jitter.
    spp: u32,
    seed: u32,
    // Columns of the spp-sample stratified grid (a divisor of spp).
    strata_x: u32,
    // The samples this dispatch adds to each pixel's sums: [begin, end).
    sample_begin: u32,
    sample_end: u32,
    // How often `loops_completed`'s loop must run (2).
    canary_loops: u32,
    _pad0: u32,
    _pad1: u32,
}

struct Triangle {
    v0: vec3<f32>,
    material: u32,
    v1: vec3<f32>,
    flags: u32,
    v2: vec3<f32>,
    _pad: u32,
}

// Per-vertex shading normals; only read for triangles with FLAG_SMOOTH.
struct TriangleNormals {
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct Material {
    albedo: vec3<f32>,
    _pad: u32,
}

// Point light: `vector` is its position and `color` its intensity I
// (irradiance I / r² at distance r). Directional light: `vector` is the unit
// direction towards the light and `color` its irradiance.
struct Light {
    vector: vec3<f32>,
    kind: u32,
    color: vec3<f32>,
    _pad: u32,
}

struct Ray {
    origin: vec3<f32>,
    tmin: f32,
    dir: vec3<f32>,
    tmax: f32,
}

// Hit point = (1-u-v)·v0 + u·v1 + v·v2 for triangles; u = v = 0 for spheres.
struct Hit {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
}

// One node of the compressed 8-wide BVH (80 bytes, src/layout.rs and
// src/cwbvh.rs): child boxes quantised outwards to a byte per plane on a
// grid of origin + q·2^(e − 127) per axis (e in byte a of exponents), whose
// every point is an f32, so dequantising with fma is exact. Slots are in
// octant order (ray_octant). child_meta: a byte per slot (slots 0–3 in child_meta.x,
// low byte first): 0 empty, META_INTERIOR | rank for node child_base +
// rank, META_LEAF | (count − 1) << 4 | offset for the leaf of count blocks
// from block_base + offset. q[2a]: the slots' minima along axis a, q[2a +
// 1] their maxima, bytes as in child_meta.
struct CompressedNode {
    origin: vec3<f32>,
    exponents: u32,
    child_base: u32,
    block_base: u32,
    child_meta: vec2<u32>,
    q: array<vec2<u32>, 6>,
}

// Up to four primitives of a BVH leaf (src/layout.rs PrimBlock): lane i is
// primitive prims[i] (NO_HIT: empty), and for a triangle v[k][a][i] is
// coordinate a of its vertex k; other lanes have zero vertices, and
// record_block_hits ignores what the 4-lane test says of them.
struct PrimBlock {
    v: array<array<vec4<f32>, 3>, 3>,
    prims: vec4<u32>,
}

// Precomputed per ray for the watertight test: the axes permuted so that
// the direction's largest component is z (kx, ky, kz), and the shear that
// maps the direction onto +z.
struct Shear {
    axes: vec3<u32>,
    s: vec3<f32>,
    // The power of two `trace` scaled the direction by (see the CPU twin's
    // prepare_ray): hit distances are scaled back by it.
    t_scale: f32,
}

struct Surface {
    position: vec3<f32>,
    // How far `position` may be off the surface, per axis: see self_hit_bound.
    error: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    albedo: vec3<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> triangle_normals: array<TriangleNormals>;
@group(0) @binding(3) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> lights: array<Light>;
@group(0) @binding(6) var<storage, read> bvh_nodes: array<array<vec4<u32>, 5>>; // CompressedNode
@group(0) @binding(7) var<storage, read> bvh_blocks: array<PrimBlock>;
@group(0) @binding(8) var<storage, read> triangles_hi: array<Triangle>;
@group(0) @binding(9) var<storage, read> triangle_normals_hi: array<TriangleNormals>;
@group(0) @binding(10) var<storage, read> bvh_nodes_hi: array<array<vec4<u32>, 5>>; // CompressedNode
@group(0) @binding(11) var<storage, read> bvh_blocks_hi: array<PrimBlock>;
// Set to 1 by an invocation whose loops the driver cut short (see
// `loops_completed`); the host then splits the work finer or fails.
@group(0) @binding(12) var<storage, read_write> loop_status: array<atomic<u32>>;
// With BVH_TEXELS: node i's words at texels 5i to 5i + 4, block i's at 10i
// to 10i + 9 (v[k][a] at 10i + 3k + a, prims at 10i + 9), texel t at
// (t mod row, t / row).
@group(0) @binding(13) var bvh_node_texels: texture_2d<u32>;
@group(0) @binding(14) var bvh_block_texels: texture_2d<u32>;
// Group 1 holds what one entry point reads and writes: an image tile for
// `render`, a batch of rays for `trace_rays`.
@group(1) @binding(0) var out_color: texture_storage_2d<rgba32float, write>;
@group(1) @binding(1) var out_prim: texture_storage_2d<r32uint, write>;
@group(1) @binding(2) var<storage, read> rays: array<Ray>;
@group(1) @binding(3) var<storage, read_write> hits: array<Hit>;
// `render_pixel_list`: pixels to (re)sample, and their mean colours with the
// variance of the mean (in w).
@group(1) @binding(4) var<storage, read> pixel_list: array<vec2<u32>>;
@group(1) @binding(5) var<storage, read_write> pixel_results: array<vec4<f32>>;
// `render`: each tile pixel's running sums (colour, squared luminance)
// between the dispatches that add its samples in turn.
@group(1) @binding(6) var<storage, read_write> tile_sums: array<vec4<f32>>;
// Shadow rays in a dispatch of their own (`render_primary`,
// `render_shadows`, `render_shade`; gpu::ShadowDispatch): each tile
// pixel's hit, the shadow rays to trace (compacted), how many, and each
// pixel's blocked lights (bit i for light i).
struct ShadowQuery {
    slot: u32,
    light: u32,
    _pad: vec2<u32>,
    ray: Ray,
}
@group(1) @binding(7) var<storage, read_write> split_hits: array<Hit>;
@group(1) @binding(8) var<storage, read_write> shadow_queue: array<ShadowQuery>;
@group(1) @binding(9) var<storage, read_write> shadow_count: array<atomic<u32>, 1>;
@group(1) @binding(10) var<storage, read_write> shadow_blocked: array<atomic<u32>>;
// `shade` takes its shadows from `shade_blocked` rather than tracing them.
override SHADOWS_FROM_QUEUE: bool = false;
// `render_shade`'s pixel's word of shadow_blocked (at most
// gpu::MAX_LIGHTS_APART lights).
var<private> shade_blocked: u32;

// Storage access across the split (no CPU twin: the CPU reads one array).
fn triangle_at(i: u32) -> Triangle {
    if i < TRIANGLES_PER_BINDING {
        return triangles[i];
    }
    return triangles_hi[i - TRIANGLES_PER_BINDING];
}

fn triangle_normals_at(i: u32) -> TriangleNormals {
    if i < TRIANGLES_PER_BINDING {
        return triangle_normals[i];
    }
    return triangle_normals_hi[i - TRIANGLES_PER_BINDING];
}

// Nodes are stored as five vec4 words (`bvh_nodes`) and read as such: five
// loads rather than one per field. lavapipe runs a load whose address
// differs between invocations one invocation at a time, a loop per load
// instruction, so fewer, wider loads made traversal 12% faster there
// (docs/bvh.md).
fn unpack_node(w: array<vec4<u32>, 5>) -> CompressedNode {
    return CompressedNode(bitcast<vec3<f32>>(w[0].xyz), w[0].w, w[1].x, w[1].y, w[1].zw,
        array<vec2<u32>, 6>(w[2].xy, w[2].zw, w[3].xy, w[3].zw, w[4].xy, w[4].zw));
}

fn texel_at(texels: texture_2d<u32>, t: u32) -> vec4<u32> {
    let row_mask = (1u << TEXEL_ROW_BITS) - 1u;
    return textureLoad(texels, vec2<u32>(t & row_mask, t >> TEXEL_ROW_BITS), 0);
}

// Word k (0 to 4) of node i.
fn node_word(i: u32, k: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_node_texels, 5u * i + k);
    }
    if i < NODES_PER_BINDING {
        return bvh_nodes[i][k];
    }
    return bvh_nodes_hi[i - NODES_PER_BINDING][k];
}

fn bvh_node_at(i: u32) -> CompressedNode {
    return unpack_node(array<vec4<u32>, 5>(node_word(i, 0u), node_word(i, 1u), node_word(i, 2u), node_word(i, 3u), node_word(i, 4u)));
}

// Block i's lanes of coordinate a of vertex k, and its primitives: read
// where they lie, not as a copy of the block, which dynamic indexing by
// the ray's axes would put in slow local memory.
fn block_lanes(i: u32, k: u32, a: u32) -> vec4<f32> {
    if BVH_TEXELS {
        return bitcast<vec4<f32>>(texel_at(bvh_block_texels, 10u * i + 3u * k + a));
    }
    if i < BLOCKS_PER_BINDING {
        return bvh_blocks[i].v[k][a];
    }
    return bvh_blocks_hi[i - BLOCKS_PER_BINDING].v[k][a];
}

fn block_prims(i: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_block_texels, 10u * i + 9u);
    }
    if i < BLOCKS_PER_BINDING {
        return bvh_blocks[i].prims;
    }
    return bvh_blocks_hi[i - BLOCKS_PER_BINDING].prims;
}

fn miss() -> Hit {
    return Hit(FAR, NO_HIT, 0.0, 0.0);
}

// Pinhole camera; `pixel` is a position in pixel units, row 0 at the top
// (pixel centres are at +0.5).
fn camera_ray(pixel: vec2<f32>) -> Ray {
    let sx = (2.0 * pixel.x / f32(params.width) - 1.0) * params.tan_half_x;
    let sy = (1.0 - 2.0 * pixel.y / f32(params.height)) * params.tan_half_y;
    let dir = normalize(params.forward + sx * params.right + sy * params.up);
    return Ray(params.eye, 0.0, dir, FAR);
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
        let sphere = spheres[prim - params.num_triangles];
        return vec3<f32>(intersect_sphere(ray, sphere.center, sphere.radius), 0.0, 0.0);
    }
    return no_triangle_hit();
}

// Tests `prim`; if it is hit nearer than ray.tmax, makes it the hit and
// shortens the ray. Returns whether it did.
fn record_hit(ray: ptr<function, Ray>, shear: Shear, hit: ptr<function, Hit>, prim: u32) -> bool {
    let tuv = intersect_primitive(*ray, shear, prim);
    if tuv.x < (*ray).tmax {
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
                (*ray).tmax = lanes.t[lane];
                let uv = block_uv(lanes, lane);
                *hit = Hit(lanes.t[lane], prims[lane], uv.x, uv.y);
                recorded = true;
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

// What the slab test needs of a ray, computed once per ray (ray_slabs): per
// axis, the reciprocal direction (widened by the slack for exit distances),
// the offsets that make a plane's distance one multiply-add, and which of the
// two planes the ray meets first.
struct Slabs {
    inv_dir: vec3<f32>,
    inv_dir_far: vec3<f32>,
    // −origin·inv_dir (or ·inv_dir_far), moved down (near) or up (far) by
    // more than the rounding of that product, of this sum and of an unfused
    // multiply-add (WGSL's fma may be either): a plane's distance
    // fma(plane, inv_dir, offset) then errs only by rounding relative to
    // itself, which the slack covers for exit distances.
    near_offset: vec3<f32>,
    far_offset: vec3<f32>,
    // Whether the ray runs toward −axis: its near plane is the maximum.
    flip: vec3<bool>,
}

// Direction components smaller than this count as this, with their sign, in
// the slab test (as in Embree): their reciprocals stay finite, so the offsets
// do (no ∞ − ∞), and a ray parallel to an axis has huge slab distances of the
// right signs, or one near 0 for a plane that holds its origin.
const MIN_SLAB_DIR: f32 = 1e-18;

fn ray_slabs(ray: Ray) -> Slabs {
    // The sign bit, not a comparison, so that −0 counts as negative.
    let sign_bits = bitcast<vec3<u32>>(ray.dir) & vec3<u32>(0x80000000u);
    let tiny = bitcast<vec3<f32>>(vec3<u32>(bitcast<u32>(MIN_SLAB_DIR)) | sign_bits);
    let dir = select(ray.dir, tiny, abs(ray.dir) < vec3<f32>(MIN_SLAB_DIR));
    let inv_dir = 1.0 / dir;
    let inv_dir_far = inv_dir * BOX_SLACK;
    let near = -ray.origin * inv_dir;
    let far = -ray.origin * inv_dir_far;
    let margin = 8.0 * MACHINE_EPSILON;
    return Slabs(
        inv_dir,
        inv_dir_far,
        near - abs(near) * margin,
        far + abs(far) * margin,
        dir < vec3<f32>(0.0),
    );
}

// The four bytes of a word, low first: four slots of a row of eight.
fn slot_bytes(word: u32) -> vec4<u32> {
    return (vec4<u32>(word) >> vec4<u32>(0u, 8u, 16u, 24u)) & vec4<u32>(0xffu);
}

// Bit a set when the ray runs toward −a. A node's slots taken in the order
// b ^ octant (b = 0, 1, …) come nearest first: slot s holds the child
// lying most toward the corner on the +a side where bit a of s is set.
fn ray_octant(slabs: Slabs) -> u32 {
    return select(0u, 1u, slabs.flip.x) | select(0u, 2u, slabs.flip.y) | select(0u, 4u, slabs.flip.z);
}

// Which children of `node` the ray enters within (tmin, tmax): x, its
// interior children as bits in visit order (bit b for slot b ^ octant),
// and in bits 8–15 which slots hold interior children at all; y, the blocks of its leaves as bits from block_base (bit i for block
// block_base + i). The planes are dequantised exactly, then each distance
// is one multiply-add, as for an exact box. Written with select on a
// comparison rather than WGSL's min/max, whose result for a NaN operand is
// unspecified: a NaN comparison is false on every device, so a NaN slab
// (from a NaN ray) is ignored the same way everywhere. Two 4-lane halves.
fn intersect_compressed_node(ray: Ray, slabs: Slabs, node: CompressedNode, octant: u32) -> vec2<u32> {
    let exponents = (vec3<u32>(node.exponents) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu);
    let scale = bitcast<vec3<f32>>(exponents << vec3<u32>(23u));
    var interior = 0u;
    var blocks = 0u;
    for (var half = 0u; half < 2u; half++) {
        var t_near = vec4<f32>(ray.tmin);
        var t_far = vec4<f32>(ray.tmax);
        for (var axis = 0u; axis < 3u; axis++) {
            let flip = slabs.flip[axis];
            let minima = node.q[2u * axis][half];
            let maxima = node.q[2u * axis + 1u][half];
            let grid_scale = vec4<f32>(scale[axis]);
            let grid_origin = vec4<f32>(node.origin[axis]);
            let near_plane = fma(vec4<f32>(slot_bytes(select(minima, maxima, flip))), grid_scale, grid_origin);
            let far_plane = fma(vec4<f32>(slot_bytes(select(maxima, minima, flip))), grid_scale, grid_origin);
            let near = fma(near_plane, vec4<f32>(slabs.inv_dir[axis]), vec4<f32>(slabs.near_offset[axis]));
            let far = fma(far_plane, vec4<f32>(slabs.inv_dir_far[axis]), vec4<f32>(slabs.far_offset[axis]));
            t_near = select(t_near, near, near > t_near);
            t_far = select(t_far, far, far < t_far);
        }
        let m = slot_bytes(node.child_meta[half]);
        let inside = (t_near <= t_far) & (t_near < vec4<f32>(ray.tmax)) & (m != vec4<u32>(0u));
        let leaf = (m & vec4<u32>(META_LEAF)) != vec4<u32>(0u);
        let order = (vec4<u32>(0u, 1u, 2u, 3u) + vec4<u32>(4u * half)) ^ vec4<u32>(octant);
        let slots = vec4<u32>(0u, 1u, 2u, 3u) + vec4<u32>(4u * half);
        let is_interior = (m != vec4<u32>(0u)) & !leaf;
        // Entered interior children in visit order (bits 0–7), and every
        // interior slot (bits 8–15), whose count below a slot is its rank.
        let child_bits = select(vec4<u32>(0u), vec4<u32>(1u) << order, inside & !leaf)
            | select(vec4<u32>(0u), vec4<u32>(1u) << (slots + vec4<u32>(8u)), is_interior);
        let count = ((m >> vec4<u32>(4u)) & vec4<u32>(7u)) + vec4<u32>(1u);
        let block_bits = ((vec4<u32>(1u) << count) - vec4<u32>(1u)) << (m & vec4<u32>(0xfu));
        let leaf_bits = select(vec4<u32>(0u), block_bits, inside & leaf);
        interior |= child_bits.x | child_bits.y | child_bits.z | child_bits.w;
        blocks |= leaf_bits.x | leaf_bits.y | leaf_bits.z | leaf_bits.w;
    }
    return vec2<u32>(interior, blocks);
}

// Each invocation's traversal stack: STACK_ENTRIES entries from
// `stack_base` (set by the entry point) in workgroup memory. Measured on
// lavapipe against a private array of MAX_DEPTH entries, which WGSL
// zero-initialises for every ray: 7–12% faster (docs/bvh.md). Not
// zero-initialised (the pipelines ask not to): only pushed entries are read.
var<workgroup> traversal_stack: array<vec2<u32>, WORKGROUP_INVOCATIONS * STACK_ENTRIES>;
var<private> stack_base: u32;
// Where the short stack's oldest entries go when it is full (STACK_SPILLS
// only: otherwise never read, and compiled out with its branches). Entry
// sp lives in slot sp % STACK_ENTRIES; pushing entry sp ≥ STACK_ENTRIES
// moves entry sp − STACK_ENTRIES from that slot to stack_spill, and
// popping entry sp brings it back, so the top STACK_ENTRIES entries are
// always in workgroup memory.
var<private> stack_spill: array<vec2<u32>, MAX_DEPTH>;

// Pushes `group` as stack entry `sp`.
fn push_group(sp: u32, group: vec2<u32>) {
    var slot = sp;
    if STACK_SPILLS {
        slot = sp % STACK_ENTRIES;
        if sp >= STACK_ENTRIES {
            stack_spill[sp - STACK_ENTRIES] = traversal_stack[stack_base + slot];
        }
    }
    traversal_stack[stack_base + slot] = group;
}

// Pops stack entry `sp` (the top).
fn pop_group(sp: u32) -> vec2<u32> {
    var slot = sp;
    if STACK_SPILLS {
        slot = sp % STACK_ENTRIES;
    }
    let group = traversal_stack[stack_base + slot];
    if STACK_SPILLS && sp >= STACK_ENTRIES {
        traversal_stack[stack_base + slot] = stack_spill[sp - STACK_ENTRIES];
    }
    return group;
}

// Closest hit through the compressed BVH, children in octant order (no
// sorting); with `any_hit`, the first hit found. Each pass of the loop
// tests the leaf blocks the last node visit entered, then visits one node:
// on a GPU running invocations in lockstep (lavapipe's SIMD lanes too) an
// invocation that has blocks to test and one that has a node to visit then
// do both in the same pass, rather than one waiting on the other. A node
// group (child_base; entered interior children in visit order, and the
// interior slots in bits 8–15) names the next nodes without reading their
// parent again: slot s is node child_base + the interior slots below s.
// The stack holds groups, pushed when traversal descends below a node:
// one per level at most.
fn trace_compressed(ray_in: Ray, shear: Shear, any_hit: bool) -> Hit {
    var ray = ray_in;
    var hit = miss();
    let slabs = ray_slabs(ray);
    let octant = ray_octant(slabs);
    var sp = 0u;
    let root = bvh_node_at(0u);
    let entered = intersect_compressed_node(ray, slabs, root, octant);
    var group = vec2<u32>(root.child_base, entered.x);
    var blocks = entered.y;
    var block_base = root.block_base;
    loop {
        while blocks != 0u {
            let i = firstTrailingBit(blocks);
            blocks &= blocks - 1u;
            if record_block_hits(&ray, shear, &hit, block_base + i) && any_hit {
                return hit;
            }
        }
        if (group.y & 0xffu) == 0u {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            group = pop_group(sp);
        }
        let next_bit = firstTrailingBit(group.y & 0xffu);
        let slot = next_bit ^ octant;
        group.y &= ~(1u << next_bit);
        if (group.y & 0xffu) != 0u {
            push_group(sp, group);
            sp += 1u;
        }
        let below = (group.y >> 8u) & ((1u << slot) - 1u);
        let next = bvh_node_at(group.x + countOneBits(below));
        let hits = intersect_compressed_node(ray, slabs, next, octant);
        group = vec2<u32>(next.child_base, hits.x);
        blocks = hits.y;
        block_base = next.block_base;
    }
    return hit;
}

// Every primitive in turn: the reference the BVH is tested against.
fn trace_brute_force(ray_in: Ray, shear: Shear, any_hit: bool) -> Hit {
    var ray = ray_in;
    var hit = miss();
    for (var prim = 0u; prim < params.num_triangles + params.num_spheres; prim++) {
        if record_hit(&ray, shear, &hit, prim) && any_hit {
            return hit;
        }
    }
    return hit;
}

// Powers of two 2^k and 2^-k such that m (> 0)·2^k is in [1, 2); 1 and 1
// for 0 or a subnormal (the CPU twin's direction_scale).
fn direction_scale(m: f32) -> vec2<f32> {
    let exponent = (bitcast<u32>(m) >> 23u) & 0xffu;
    if exponent == 0u || exponent >= 254u {
        return vec2<f32>(1.0);
    }
    return vec2<f32>(bitcast<f32>((254u - exponent) << 23u), bitcast<f32>(exponent << 23u));
}

fn trace(ray_in: Ray, any_hit: bool) -> Hit {
    var ray = ray_in;
    // The direction scaled by a power of two, exactly (see the CPU twin's
    // prepare_ray): tiny directions' clamped components stay negligible.
    let m = abs(ray.dir);
    let scale = direction_scale(max(max(m.x, m.y), m.z));
    ray.dir *= scale.x;
    ray.tmin *= scale.y;
    ray.tmax *= scale.y;
    // Misses report FAR, so an infinite tmax must not let them through. A
    // comparison, not min (unspecified for NaN): a NaN tmax becomes FAR, as
    // on the CPU.
    ray.tmax = select(FAR, ray.tmax, ray.tmax < FAR);
    var shear = ray_shear(ray.dir);
    shear.t_scale = scale.x;
    var hit: Hit;
    if USE_BVH {
        hit = trace_compressed(ray, shear, any_hit);
    } else {
        hit = trace_brute_force(ray, shear, any_hit);
    }
    if hit.prim != NO_HIT {
        hit.t *= shear.t_scale;
    }
    return hit;
}

fn trace_closest(ray: Ray) -> Hit {
    return trace(ray, false);
}

// Any hit in (tmin, tmax): stops at the first blocker.
fn trace_any(ray: Ray) -> bool {
    return trace(ray, true).prim != NO_HIT;
}

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

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    if hit.prim < params.num_triangles {
        let tri = triangle_at(hit.prim);
        let w = 1.0 - hit.u - hit.v;
        // From barycentrics, not o + t·d: the point lies closer to the plane.
        let position = w * tri.v0 + hit.u * tri.v1 + hit.v * tri.v2;
        let error = self_hit_bound(max(max(abs(tri.v0), abs(tri.v1)), abs(tri.v2)));
        let geometric = face_forward(normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0)), ray.dir);
        var shading = geometric;
        if (tri.flags & FLAG_SMOOTH) != 0u {
            let ns = triangle_normals_at(hit.prim);
            let interpolated = w * ns.n0.xyz + hit.u * ns.n1.xyz + hit.v * ns.n2.xyz;
            if dot(interpolated, interpolated) > 0.0 {
                shading = face_forward(normalize(interpolated), ray.dir);
            }
        }
        return Surface(position, error, geometric, shading, materials[tri.material].albedo);
    }
    let sphere = spheres[hit.prim - params.num_triangles];
    // Relative to the centre first: o − c is exact when both are near each
    // other, so far from the origin the normal keeps its precision.
    let outward = normalize((ray.origin - sphere.center) + hit.t * ray.dir);
    // Re-projected onto the sphere to undo the rounding of t.
    let position = sphere.center + sphere.radius * outward;
    let error = self_hit_bound(abs(sphere.center) + sphere.radius);
    let normal = face_forward(outward, ray.dir);
    return Surface(position, error, normal, normal, materials[sphere.material].albedo);
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
    if HAS_POINT_LIGHTS && (!HAS_DIRECTIONAL_LIGHTS || light.kind == LIGHT_POINT) {
        let d = light.vector - surface.position;
        let distance_squared = dot(d, d);
        // A light on the shaded point: no light (see the CPU twin).
        if distance_squared == 0.0 {
            return out;
        }
        to_light = d / sqrt(distance_squared);
        out.irradiance = min(light.color / distance_squared, vec3<f32>(FAR));
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

fn shadowed(ray: Ray, light: u32) -> bool {
    if SHADOWS_FROM_QUEUE {
        return ((shade_blocked >> light) & 1u) != 0u;
    }
    return trace_any(ray);
}

// Lambert: ambient·k + Σ k·E·max(0, n·l)·visible, linear RGB.
fn shade(ray: Ray, hit: Hit) -> vec3<f32> {
    if hit.prim == NO_HIT {
        return params.background;
    }
    let surface = surface_at(ray, hit);
    var color = params.ambient * surface.albedo;
    let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
    for (var i = 0u; i < params.num_lights; i++) {
        let sample = light_sample(surface, origin, lights[i]);
        if !sample.lit {
            continue;
        }
        if HAS_SHADOWS && params.shadows != 0u && shadowed(sample.shadow_ray, i) {
            continue;
        }
        color += surface.albedo * sample.irradiance * sample.cos_theta;
    }
    return color;
}

// PCG hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT
// 2020): integer only, so the CPU path draws the very same numbers.
fn pcg_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A uniform number in [0, 1) from the top 24 bits: exact in f32.
fn unit_float(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Position of sample `sample` in `pixel`: the centre when spp = 1, else a
// jittered point in its cell of a strata_x × (spp / strata_x) grid.
fn sample_position(pixel: vec2<u32>, sample: u32) -> vec2<f32> {
    let corner = vec2<f32>(pixel);
    if params.spp == 1u {
        return corner + 0.5;
    }
    let h = pcg_hash(pixel.x ^ pcg_hash(pixel.y ^ pcg_hash(sample ^ pcg_hash(params.seed))));
    let jitter = vec2<f32>(unit_float(h), unit_float(pcg_hash(h)));
    let strata_y = params.spp / params.strata_x;
    let cell = vec2<f32>(vec2<u32>(sample % params.strata_x, sample / params.strata_x));
    return corner + (cell + jitter) / vec2<f32>(f32(params.strata_x), f32(strata_y));
}

const LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

// Mesa's llvmpipe (lavapipe, and its GL driver) ends every loop after its
// first iteration once an invocation group has run 65535 loop iterations in
// all (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS), silently: high-spp pixels
// then lost their later samples' hits. A loop that must run
// `params.canary_loops` (2) times, run last, tells whether that happened;
// the host keeps each dispatch's samples under the budget and redoes the
// work in smaller parts when it did. Other drivers never trip it.
fn loops_completed() -> bool {
    var runs = 0u;
    for (var i = 0u; i < params.canary_loops; i++) {
        runs += 1u;
    }
    return runs == params.canary_loops;
}

fn report_cut_loops() {
    if !loops_completed() {
        atomicOr(&loop_status[0], 1u);
    }
}

// Samples `params.sample_begin` to `params.sample_end` of `pixel`, added in
// turn to `sums` (colour, squared luminance): samples split over several
// dispatches sum exactly as in one loop. `prim` is what the first of them
// hit.
struct SampleSums {
    sums: vec4<f32>,
    prim: u32,
}

fn add_samples(pixel: vec2<u32>, sums: vec4<f32>) -> SampleSums {
    var sum = sums.xyz;
    var sum_squares = sums.w;
    var first_prim = NO_HIT;
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let ray = camera_ray(sample_position(pixel, sample));
        let hit = trace_closest(ray);
        if sample == params.sample_begin {
            first_prim = hit.prim;
        }
        let color = shade(ray, hit);
        sum += color;
        let y = dot(color, LUMINANCE);
        sum_squares += y * y;
    }
    return SampleSums(vec4<f32>(sum, sum_squares), first_prim);
}

// A pixel's box-filtered mean and the variance of its mean luminance (the
// square of its standard error, from the spread of its samples; 0 at 1
// sample: adaptive sampling refines where it is large), from the sums of
// all `params.spp` samples.
fn pixel_mean(sums: vec4<f32>) -> vec4<f32> {
    let n = f32(params.spp);
    let mean = sums.xyz / n;
    let y = dot(mean, LUMINANCE);
    var variance = 0.0;
    if params.spp > 1u {
        variance = max(0.0, sums.w - n * y * y) / ((n - 1.0) * n);
    }
    return vec4<f32>(mean, variance);
}

// The tile pixel of a render invocation, or none.
fn tile_slot(id: vec3<u32>) -> u32 {
    let size = textureDimensions(out_color);
    let pixel = params.tile_origin + id.xy;
    if id.x >= size.x || id.y >= size.y || pixel.x >= params.width || pixel.y >= params.height {
        return NO_HIT;
    }
    return id.y * size.x + id.x;
}

@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    let pixel = params.tile_origin + id.xy;
    var sums = vec4<f32>(0.0);
    if params.sample_begin > 0u {
        sums = tile_sums[slot];
    }
    let result = add_samples(pixel, sums);
    if params.sample_begin == 0u {
        textureStore(out_prim, id.xy, vec4<u32>(result.prim, 0u, 0u, 0u));
    }
    if params.sample_end == params.spp {
        textureStore(out_color, id.xy, pixel_mean(result.sums));
    } else {
        tile_sums[slot] = result.sums;
    }
    report_cut_loops();
}

// One ray of a `lambert trace` batch. Misses leave t = FAR, prim = NO_HIT.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn trace_rays(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    if id.x >= arrayLength(&rays) {
        return;
    }
    hits[id.x] = trace(rays[id.x], ANY_HIT);
    report_cut_loops();
}

// Adaptive sampling's later passes: `params.spp` more samples (seeded by
// `params.seed`) for each listed pixel, in parts as `render` adds them.
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_pixel_list(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    if id.x >= arrayLength(&pixel_list) {
        return;
    }
    var sums = vec4<f32>(0.0);
    if params.sample_begin > 0u {
        sums = pixel_results[id.x];
    }
    let result = add_samples(pixel_list[id.x], sums);
    if params.sample_end == params.spp {
        pixel_results[id.x] = pixel_mean(result.sums);
    } else {
        pixel_results[id.x] = result.sums;
    }
    report_cut_loops();
}

// Shadow rays apart, pass 1: the pixel's primary hit (its one sample),
// and its shadow rays queued.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_primary(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    stack_base = lane * STACK_ENTRIES;
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin));
    let hit = trace_closest(ray);
    split_hits[slot] = hit;
    if hit.prim != NO_HIT && HAS_SHADOWS && params.shadows != 0u {
        let surface = surface_at(ray, hit);
        let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
        atomicStore(&shadow_blocked[slot], 0u);
        for (var i = 0u; i < params.num_lights; i++) {
            let sample = light_sample(surface, origin, lights[i]);
            if sample.lit {
                let q = atomicAdd(&shadow_count[0], 1u);
                shadow_queue[q] = ShadowQuery(slot, i, vec2<u32>(0u), sample.shadow_ray);
            }
        }
    }
    report_cut_loops();
}

// Pass 2: the queued shadow rays, side by side (as many invocations as
// the tile has pixels, each taking every so many: at most as many shadow
// rays as a `render` invocation traces).
@compute @workgroup_size(WORKGROUP_INVOCATIONS)
fn render_shadows(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    stack_base = lane * STACK_ENTRIES;
    let count = atomicLoad(&shadow_count[0]);
    let stride = groups.x * WORKGROUP_INVOCATIONS;
    for (var i = id.x; i < count; i += stride) {
        let q = shadow_queue[i];
        if trace_any(q.ray) {
            atomicOr(&shadow_blocked[q.slot], 1u << q.light);
        }
    }
    report_cut_loops();
}

// Pass 3: shading from the hit and the shadows found (renders of one
// sample per pixel: gpu::GpuRenderer::shadows_apart), written as `render`
// writes its one sample.
@compute @workgroup_size(RENDER_WORKGROUP_X, RENDER_WORKGROUP_Y)
fn render_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = tile_slot(id);
    if slot == NO_HIT {
        return;
    }
    shade_blocked = atomicLoad(&shadow_blocked[slot]);
    let ray = camera_ray(sample_position(params.tile_origin + id.xy, params.sample_begin));
    let hit = split_hits[slot];
    let color = shade(ray, hit);
    let y = dot(color, LUMINANCE);
    textureStore(out_prim, id.xy, vec4<u32>(hit.prim, 0u, 0u, 0u));
    textureStore(out_color, id.xy, pixel_mean(vec4<f32>(color, y * y)));
}
