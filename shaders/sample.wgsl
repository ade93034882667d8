// Stage: sampling. Camera rays, the stratified, hashed sample positions, a
// pixel's sums of samples and their mean, the tile pixel of an invocation,
// and the check on loops the driver cut short (which every entry point
// runs last). CPU twin: src/cpu/sample.rs (no twin for the tile and loop
// checks: the CPU has neither).

// Pinhole camera; `pixel` is a position in pixel units, row 0 at the top
// (pixel centres are at +0.5).
fn camera_ray(pixel: vec2<f32>) -> Ray {
    // Each operation rounded on its own, in the CPU twin's order, so both
    // paths shoot the same bits: a select on `guard`, which the compiler
    // cannot know (as `rounded`'s), stops it fusing or reordering.
    let guard = params.zero != 0u;
    let sx = select(select(2.0 * pixel.x / f32(params.width), 0.0, guard) - 1.0, 0.0, guard)
        * params.tan_half_x;
    let sy = select(1.0 - select(2.0 * pixel.y / f32(params.height), 0.0, guard), 0.0, guard)
        * params.tan_half_y;
    let zero = vec3<f32>(0.0);
    let v = select(select(params.forward + select(sx * params.right, zero, guard), zero, guard)
        + select(sy * params.up, zero, guard), zero, guard);
    let squares = select(v * v, zero, guard);
    let length_squared = select(select(squares.x + squares.y, 0.0, guard) + squares.z, 0.0, guard);
    let dir = select(v * select(1.0 / select(sqrt(length_squared), 0.0, guard), 0.0, guard), zero, guard);
    return Ray(params.eye, 0.0, dir, FAR);
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
        textureStore(loop_status, vec2<u32>(0u, 0u), vec4<u32>(1u));
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
    var result = SampleSums(sums, NO_HIT);
    for (var sample = params.sample_begin; sample < params.sample_end; sample++) {
        let ray = camera_ray(sample_position(pixel, sample));
        let hit = trace_closest(ray);
        if sample == params.sample_begin {
            result.prim = hit.prim;
        }
        result.sums = add_sample(result.sums, radiance(ray, hit, pixel, sample));
    }
    return result;
}

// `sums` with one more sample's colour (and its squared luminance).
fn add_sample(sums: vec4<f32>, color: vec3<f32>) -> vec4<f32> {
    let y = dot(color, LUMINANCE);
    return vec4<f32>(sums.xyz + color, sums.w + y * y);
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

// A render entry point's invocation (8×8 workgroups over the tile): its
// pixel (x, y in the image) and that pixel's place in the tile buffers,
// NO_HIT in z where it lies outside the tile; its traversal stack placed.
// The host dispatches
// T = CPU_THREADS layers (z) of every T-th column of workgroups, and
// llvmpipe, which hands each of its threads a contiguous share of a
// dispatch's workgroups, gives thread t layer t: the workgroups whose
// column and row add up to t modulo T (for T = 2, the squares of one
// colour of a chessboard), a share of each part of the image, as
// `spread_invocation` deals them, without its integer divisions by
// values known only at run time, which llvmpipe runs a lane at a time.
// Every T-th row alone left a thread a row more than the other on a
// small tile (4 rows of 7 against 3 at 64 spp).
fn tile_pixel(group: vec3<u32>, local: vec3<u32>, lane: u32) -> vec3<u32> {
    stack_base = lane * STACK_ENTRIES;
    let column = group.x * CPU_THREADS + (group.y + group.z) % CPU_THREADS;
    let id = vec2<u32>(column * RENDER_WORKGROUP_X + local.x, group.y * RENDER_WORKGROUP_Y + local.y);
    let inside = id.x < params.tile_size.x && id.y < params.tile_size.y;
    return vec3<u32>(params.tile_origin + id, select(NO_HIT, id.y * TILE + id.x, inside));
}

// A tile pixel's sums of the samples before `params.sample_begin`, kept
// in `tile_sums` between dispatches.
fn sums_so_far(slot: u32) -> vec4<f32> {
    if params.sample_begin > 0u {
        return tile_sums[slot];
    }
    return vec4<f32>(0.0);
}

// A tile pixel's samples so far: its primitive after its first sample,
// its mean after its last, else its sums for the next dispatch.
fn store_samples(slot: u32, result: SampleSums) {
    if params.sample_begin == 0u {
        out_prim[slot] = result.prim;
    }
    store_sums(slot, result.sums);
}

// A tile pixel's sums of samples so far: its mean after its last, else
// the sums for the next dispatch.
fn store_sums(slot: u32, sums: vec4<f32>) {
    tile_sums[slot] = select(sums, pixel_mean(sums), params.sample_end == params.spp);
}
