// Stage: data layout. Every override (the host's per-scene specialisation),
// the constants, the structs (each with a #[repr(C)] twin in src/layout.rs)
// and the bindings of both groups, which entry points share; the entry
// files (entry_*.wgsl) say which bindings each of them uses. The shader is
// these files composed in order (src/shader_source.rs); the CPU twin of
// each stage is the src/cpu/ file of the same name (docs/bvh.md).

// Specialisation: the host sets these per scene so that a variant carries no
// code for what its scene lacks. Defaults give the full shader.
override HAS_TRIANGLES: bool = true;
override HAS_SPHERES: bool = true;
override HAS_SHADOWS: bool = true;
override HAS_POINT_LIGHTS: bool = true;
override HAS_DIRECTIONAL_LIGHTS: bool = true;
override HAS_SPOT_LIGHTS: bool = true;
// Some material has a normal texture: the scene's words hold every
// triangle's tangent frames (`triangle_tangents_at`). False: their reads are compiled out.
override HAS_NORMAL_MAPS: bool = true;
// Some triangle is alpha-masked (FLAG_MASKED): traversal tests alpha at
// its hits. False: the test is compiled out.
override HAS_ALPHA_MASK: bool = true;
// Some material reads a texture. False: texture lookups are compiled out
// (lavapipe runs a branch's body masked even where no lane takes it, so
// an untextured render would pay for them: 1.9× on the dragon).
override HAS_TEXTURES: bool = true;
// Some triangle has corner colours or texture coordinates
// (FLAG_ATTRIBUTES). False: their interpolation is compiled out, likewise.
override HAS_ATTRIBUTES: bool = true;
// Some triangle has shading normals (FLAG_SMOOTH). False: their reads and
// interpolation are compiled out, likewise.
override HAS_SMOOTH: bool = true;
// Samples are path traced (Integrator::Path): `radiance` calls
// `path_radiance`. False: the direct integrator's `shade` alone.
override PATH_TRACE: bool = true;
// false: test every primitive (the reference that tests the BVH).
override USE_BVH: bool = true;
// Ray/triangle test: INTERSECT_SEED, INTERSECT_MOLLER_TRUMBORE or
// INTERSECT_WATERTIGHT.
override INTERSECT: u32 = 2u;
// Entry point `trace_rays`: stop at the first hit found rather than the
// closest.
override ANY_HIT: bool = false;
// The scene's arrays lie in one array of 16-byte words (`scene_words`,
// each array from its word in `arrays`); where they pass one storage
// binding, the first this many words in `scene_words`, the rest in
// `scene_words_hi`. Unsplit: all.
override WORDS_PER_BINDING: u32 = 0xffffffffu;
// Read the BVH's nodes and blocks, and the triangles, from
// `bvh_node_texels`, `bvh_block_texels` and `triangle_texels` rather than
// the storage buffers (gpu::BvhStorage: lavapipe fetches texels with
// vector gathers, storage words a lane at a time).
override BVH_TEXELS: bool = false;
// The `render` entry point's workgroup: gpu::RENDER_WORKGROUP, measured
// (docs/bvh.md).
override RENDER_WORKGROUP_X: u32 = 8u;
override RENDER_WORKGROUP_Y: u32 = 8u;
// Side of the square render tile (gpu::TILE): the row stride of the tile
// buffers (`out_prim`, `tile_sums`).
override TILE: u32 = 256u;
// Traversal stack entries per invocation in workgroup memory (gpu.rs):
// the scene's BVH depth − 1, the most `trace_compressed` can push (see
// MAX_DEPTH), up to cwbvh::SHORT_STACK_ENTRIES. A deeper tree sets
// STACK_SPILLS: the stack's oldest entries then move to `stack_spill`.
override STACK_ENTRIES: u32 = 8u;
override STACK_SPILLS: bool = false;
// lavapipe's compute threads (`Gpu::cpu_threads`; 1 on every
// other adapter): llvmpipe hands thread t the t-th contiguous 1/T of a
// dispatch's workgroups (Mesa's lp_cs_tpool), so the entry points take
// workgroups through `spread_workgroup`, which deals neighbouring blocks of
// work to different threads.
override CPU_THREADS: u32 = 1u;
// Invocations per workgroup of every entry point (RENDER_WORKGROUP_X ×
// RENDER_WORKGROUP_Y for `render`).
const WORKGROUP_INVOCATIONS: u32 = 64u;

// The block of work (rays, pixels) of workgroup `group` of `groups`: on
// llvmpipe thread t runs workgroups t·C to t·C + C − 1 (C = groups /
// CPU_THREADS, the rest after them one by one), and as it is given them
// here it works on blocks t, t + T, t + 2T, …: every thread gets a
// share of each part of the image, where contiguous halves of it (the
// dragon and the sky above it) differ in work by up to 2× and the dispatch
// waits for the slower thread. A permutation of 0..groups; the identity
// where CPU_THREADS = 1.
fn spread_workgroup(group: u32, groups: u32) -> u32 {
    let chunk = groups / CPU_THREADS;
    if group >= chunk * CPU_THREADS {
        return group;
    }
    return (group % chunk) * CPU_THREADS + group / chunk;
}

// The global invocation id of a 2D (or 3D) dispatch with its workgroups
// spread as `spread_workgroup` spreads them (llvmpipe numbers a grid's
// workgroups x fastest, then y, then z).
fn spread_invocation(group: vec3<u32>, groups: vec3<u32>, local: vec3<u32>, size: vec3<u32>) -> vec3<u32> {
    let linear = (group.z * groups.y + group.y) * groups.x + group.x;
    let spread = spread_workgroup(linear, groups.x * groups.y * groups.z);
    let plane = groups.x * groups.y;
    let g = vec3<u32>(spread % groups.x, (spread % plane) / groups.x, spread / plane);
    return g * size + local;
}

const NO_HIT: u32 = 0xffffffffu;
// Texels a row of the BVH textures: 1 << TEXEL_ROW_BITS (gpu::TEXELS_PER_ROW).
const TEXEL_ROW_BITS: u32 = 12u;
// WGSL has no infinity literal; the largest finite f32 serves as "no hit
// yet", written exactly in hex: Tint (Chrome's WGSL compiler) rejects the
// decimal 3.40282347e38, a hair above it, which naga rounds down.
const FAR: f32 = 0x1.fffffep+127f;
const LIGHT_POINT: u32 = 0u;
const LIGHT_DIRECTIONAL: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;
const MATERIAL_LAMBERT: u32 = 0u;
const MATERIAL_METALLIC_ROUGHNESS: u32 = 1u;
const FLAG_SMOOTH: u32 = 1u;
const FLAG_ATTRIBUTES: u32 = 2u;
const FLAG_MASKED: u32 = 4u;
const ALPHA_OPAQUE: u32 = 0u;
const ALPHA_MASK: u32 = 1u;
const NO_TEXTURE: u32 = 0xffffffffu;
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
    // A camera ray's cone's spread angle: its width at distance t is
    // t · cone_spread (texture::cone_spread; docs/textures.md).
    cone_spread: f32,
    // Always 0: what `rounded` and `camera_ray` select on.
    zero: u32,
    // The tile's width and height in pixels (at most TILE).
    tile_size: vec2<u32>,
    // Under PATH_TRACE, the most surfaces a path hits.
    max_depth: u32,
    _pad: u32,
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

// Per-corner tangents (xyz) and bitangent signs (w) for normal maps; only
// read where the triangle's material has a normal texture.
struct TriangleTangents {
    t0: vec4<f32>,
    t1: vec4<f32>,
    t2: vec4<f32>,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Corner colours (linear RGBA) and texture coordinates of a triangle; only
// read for triangles with FLAG_ATTRIBUTES.
struct TriangleAttributes {
    colors: array<vec4<f32>, 3>,
    uvs: array<vec2<f32>, 3>,
    _pad: vec2<f32>,
}

// Base colour (linear RGBA), emission (linear RGB), alpha mode
// (ALPHA_OPAQUE, ALPHA_MASK) and cut-off, texture slots (NO_TEXTURE: none),
// the BRDF (MATERIAL_LAMBERT, MATERIAL_METALLIC_ROUGHNESS) with its
// metallic and perceptual roughness factors (× the metallic-roughness
// texture's B and G), the normal texture and its scale.
struct Material {
    base_color: vec4<f32>,
    emission: vec3<f32>,
    alpha_mode: u32,
    alpha_cutoff: f32,
    base_color_texture: u32,
    emissive_texture: u32,
    alpha_texture: u32,
    kind: u32,
    metallic: f32,
    roughness: f32,
    metallic_roughness_texture: u32,
    normal_texture: u32,
    normal_scale: f32,
    _pad: vec2<u32>,
}

// Point light: `vector` is its position and `color` its intensity I
// (irradiance I / r² at distance r). Directional light: `vector` is the unit
// direction towards the light and `color` its irradiance. Spot light: a
// point light times the falloff between its cones (cos_inner, cos_outer)
// about `direction`, the unit direction it points along.
struct Light {
    vector: vec3<f32>,
    kind: u32,
    color: vec3<f32>,
    cos_outer: f32,
    direction: vec3<f32>,
    cos_inner: f32,
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
    emission: vec3<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
// Every read-only array of the scene in one binding (two where large), so
// that a pass binds few storage buffers: WebGPU's browsers allow 8 or 10 a
// stage (docs/web.md). Read through shaders/fetch.wgsl's `*_at`.
@group(0) @binding(1) var<storage, read> scene_words: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> scene_words_hi: array<vec4<u32>>;
// Where each array starts in them, in words.
struct SceneArrays {
    triangles: u32,
    normals: u32,
    attributes: u32,
    tangents: u32,
    nodes: u32,
    blocks: u32,
    spheres: u32,
    materials: u32,
    lights: u32,
    textures: u32,
    emitters: u32,
    environment: u32,
    environment_cdf: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}
@group(0) @binding(2) var<uniform> arrays: SceneArrays;
// Set to 1 by an invocation whose loops the driver cut short (see
// `loops_completed`); the host then splits the work finer or fails. A
// one-texel storage texture, not a buffer, for the storage-buffer count
// that browsers allow (every writer stores the same 1).
@group(0) @binding(12) var loop_status: texture_storage_2d<r32uint, write>;
// With BVH_TEXELS: node i's words at texels 5i to 5i + 4, block i's at 10i
// to 10i + 9 (v[k][a] at 10i + 3k + a, prims at 10i + 9), texel t at
// (t mod row, t / row). Read-only storage textures, not sampled ones:
// lavapipe's load from a sampled texture clamps and looks up a mip level
// for each lane (row strides and offsets gathered lane by lane), an image
// load has one level; 1.4x faster traversal there (docs/bvh.md).
@group(0) @binding(13) var bvh_node_texels: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(14) var bvh_block_texels: texture_storage_2d<rgba32uint, read>;
// With BVH_TEXELS, the triangles too (the hits' surfaces, read once a hit
// in shading): triangle i's words at texels 3i to 3i + 2.
@group(0) @binding(18) var triangle_texels: texture_storage_2d<rgba32uint, read>;
// Group 1 holds what one entry point reads and writes: an image tile for
// `render`, a batch of rays for `trace_rays`.
// A render tile's pixels' first primitives, pixel (x, y) at y · TILE + x.
// Storage buffers, not storage textures (as were this and the means):
// lavapipe stores a texel's channels a loop over the lanes each, a
// buffer's vec4 in one.
@group(1) @binding(1) var<storage, read_write> out_prim: array<u32>;
@group(1) @binding(2) var<storage, read> rays: array<Ray>;
@group(1) @binding(3) var<storage, read_write> hits: array<Hit>;
// `render_pixel_list` (and the wavefront's `render_list_primary`, whose
// results are bound at `tile_sums`): pixels to (re)sample, and their mean
// colours with the variance of the mean (in w).
@group(1) @binding(4) var<storage, read> pixel_list: array<vec2<u32>>;
@group(1) @binding(5) var<storage, read_write> pixel_results: array<vec4<f32>>;
// A render tile's pixels (as `out_prim`): their running sums (colour,
// squared luminance) between the dispatches that add their samples in
// turn, their means (colour, variance of the mean luminance) after the
// last. One buffer for both: a pixel's store then is one, where lavapipe
// would run both of two, a loop over the lanes each.
@group(1) @binding(6) var<storage, read_write> tile_sums: array<vec4<f32>>;
// Shadow rays in a dispatch of their own (`render_primary`,
// `render_shadows`, `render_resolve`; gpu::ShadowDispatch): the kept
// shading of the listed pixels' samples (a dispatch's samples of the nth
// from n · samples), the shadow rays to trace (compacted, each camera
// ray's together and in light order), and how many. Read and written as
// whole vec4 words (shaders/entry_shadows.wgsl): lavapipe moves each
// member of a struct, as each load or store, a lane at a time, a loop
// each.
struct WaveShading {
    // The background on a miss; else the ambient term, to which the
    // terms of the lights whose shadow rays are not blocked are added.
    color: vec3<f32>,
    // The camera ray's first shadow ray in `shadow_queue`.
    first: u32,
    // Added last, as `shade` adds it.
    emission: vec3<f32>,
    // How many shadow rays it queued.
    count: u32,
}
struct ShadowQuery {
    // A Ray's words: origin and tmin, direction and tmax.
    origin_tmin: vec4<f32>,
    dir_tmax: vec4<f32>,
    // What the light adds (`light_term`) unless the ray is blocked.
    term: vec3<f32>,
    // 1 once `render_shadows` found the ray blocked.
    blocked: u32,
}
@group(1) @binding(7) var<storage, read_write> wave_shading: array<array<vec4<u32>, 2>>; // WaveShading
@group(1) @binding(8) var<storage, read_write> shadow_queue: array<array<vec4<u32>, 3>>; // ShadowQuery
// How many: [0] shadow rays queued, [1] pixels to resolve.
@group(1) @binding(9) var<storage, read_write> wave_counts: array<atomic<u32>, 2>;
// The indirect dispatches (workgroups x, y, z: one a WORKGROUP_INVOCATIONS
// queued items) of `render_shadows` (0 to 2) and `render_resolve` (3 to
// 5), apart from the counts, which those passes read: a dispatch may not
// bind its indirect buffer.
@group(1) @binding(10) var<storage, read_write> wave_workgroups: array<atomic<u32>, 6>;
// The pixels whose shading `render_resolve` finishes: each one's place in
// `tile_sums`, and the first sample it resolves.
@group(1) @binding(19) var<storage, read_write> resolve_pixels: array<vec2<u32>>;

// The path wavefront (shaders/entry_paths.wgsl): each path of a dispatch
// between its vertices, as `PathState` and the hit its ray found.
struct PathRecord {
    origin: vec3<f32>,
    state: u32,
    dir: vec3<f32>,
    bsdf_pdf_before: f32,
    throughput: vec3<f32>,
    depth: u32,
    radiance: vec3<f32>,
    hit_t: f32,
    origin_before: vec3<f32>,
    hit_prim: u32,
    hit_uv: vec2<f32>,
}
@group(1) @binding(24) var<storage, read_write> path_records: array<PathRecord>;
// The live paths a pass takes and those that go on: two halves, which
// swap from bounce to bounce (`path_counts[4]`: the live one).
@group(1) @binding(25) var<storage, read_write> path_queues: array<u32>;
// How many: [0] paths appended to the other half of `path_queues`, [1]
// shadow rays appended to `shadow_queue`, [2] and [3] those that the
// passes after `path_advance` take (the appends then start again from 0);
// [4] which half of `path_queues` is live.
@group(1) @binding(27) var<storage, read_write> path_counts: array<atomic<u32>, 5>;
// The indirect dispatches (workgroups x, y, z) of the passes over the live
// paths (0 to 2) and over the shadow rays (3 to 5): written only by
// `path_advance`, which is dispatched directly.
@group(1) @binding(28) var<storage, read_write> path_workgroups: array<u32, 6>;

// Lighting (the path integrator's; shaders/lights.wgsl reads it): the
// emitters' table and the environment. Whether the scene has an
// environment (a colour or a map) and any emitter at all: without, their
// lookups are compiled out.
override HAS_ENVIRONMENT: bool = true;
override HAS_EMITTERS: bool = true;
const EMITTER_TRIANGLE: u32 = 0u;
const EMITTER_LIGHT: u32 = 1u;
const EMITTER_ENVIRONMENT: u32 = 2u;
const LIGHTING_ENVIRONMENT_IMAGE: u32 = 1u;

// One entry of the emitters' table: the emitter (a triangle by primitive
// id, a light by index, the environment), the probability of picking it,
// and its bin of the alias table (keep it with probability q, else take
// `alias_bin`). Triangles first, by primitive id.
struct Emitter {
    kind: u32,
    index: u32,
    pmf: f32,
    q: f32,
    alias_bin: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Counts of the table, and the environment: its constant colour (no
// image), its map's size, its rotation about +Y, its entry's pmf.
struct Lighting {
    environment_color: vec3<f32>,
    num_emitters: u32,
    environment_width: u32,
    environment_height: u32,
    rotation_cos: f32,
    rotation_sin: f32,
    num_triangle_emitters: u32,
    environment_pmf: f32,
    total_power: f32,
    flags: u32,
}
@group(0) @binding(23) var<uniform> lighting: Lighting;
