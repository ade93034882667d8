// Stage: textures. Sampling the scene's texture store (`texture_word`: one
// array of words in the scene's words: the sRGB table, mip levels, texels, texture slots;
// src/texture/store.rs) and the level of detail from a ray cone. CPU
// twin: src/cpu/texture.rs. Bit-identical to it: every float result that
// another operation reads passes through `rounded`, so no compiler can
// fuse a multiply into an add or reassociate a sum (lavapipe does both;
// WGSL allows it); texel positions and filter weights are integers; the
// level of detail is read from float bits, not `log2` (docs/textures.md).

const WRAP_MIRRORED: u32 = 1u;
const WRAP_CLAMP: u32 = 2u;
// Linear 1.0 in the store's fixed point (texture::LINEAR_ONE).
const LINEAR_ONE: u32 = 32768u;

// A texture coordinate brought into one period of its wrap mode: [0, 1]
// (repeat, clamp) or [0, 2] (mirrored repeat). NaN and infinities read 0.
fn wrap_coordinate(u: f32, mode: u32) -> f32 {
    let x = select(0.0, u, abs(u) <= 1e30);
    if mode == WRAP_CLAMP {
        return clamp(x, 0.0, 1.0);
    }
    if mode == WRAP_MIRRORED {
        return rounded(x - 2.0 * floor(x * 0.5));
    }
    return rounded(x - floor(x));
}

// A texel index (possibly outside the image) as the wrap mode reads it.
fn wrap_texel(i: i32, size: i32, mode: u32) -> i32 {
    if mode == WRAP_CLAMP {
        return clamp(i, 0, size - 1);
    }
    if mode == WRAP_MIRRORED {
        let period = 2 * size;
        let k = ((i % period) + period) % period;
        return select(k, period - 1 - k, k >= size);
    }
    return ((i % size) + size) % size;
}

// A wrapped coordinate in texels from the first texel's centre, in 1/256
// steps: texel i's centre, (i + 0.5)/size, gives 256·i exactly.
fn texel_position(u: f32, size: u32) -> i32 {
    return i32(floor(u * f32(size * 256u))) - 128;
}

// Texel (x, y) of the level whose entry starts at word `level`, as linear
// RGBA in 1/LINEAR_ONE (RGB through the table at word `table`: the sRGB
// table for colour, the linear one for data; A linear).
fn texel_linear(level: u32, x: i32, y: i32, table: u32) -> vec4<u32> {
    let word = texture_word(texture_word(level) + u32(y) * texture_word(level + 1u) + u32(x));
    return vec4<u32>(texture_word(table + (word & 255u)), texture_word(table + ((word >> 8u) & 255u)),
        texture_word(table + ((word >> 16u) & 255u)), ((word >> 24u) * LINEAR_ONE + 127u) / 255u);
}

// One level's filtered value at the wrapped `uv`, weighted in 1/65536 (so
// that 1.0 is LINEAR_ONE · 65536 = 2^31): nearest or bilinear.
fn level_sum(level: u32, uv: vec2<f32>, wrap_u: u32, wrap_v: u32, bilinear: bool,
        table: u32) -> vec4<u32> {
    let width = i32(texture_word(level + 1u));
    let height = i32(texture_word(level + 2u));
    let px = texel_position(uv.x, u32(width));
    let py = texel_position(uv.y, u32(height));
    if !bilinear {
        let x = wrap_texel((px + 128) >> 8u, width, wrap_u);
        let y = wrap_texel((py + 128) >> 8u, height, wrap_v);
        return texel_linear(level, x, y, table) * 65536u;
    }
    let x0 = wrap_texel(px >> 8u, width, wrap_u);
    let x1 = wrap_texel((px >> 8u) + 1, width, wrap_u);
    let y0 = wrap_texel(py >> 8u, height, wrap_v);
    let y1 = wrap_texel((py >> 8u) + 1, height, wrap_v);
    let fx = u32(px & 255);
    let fy = u32(py & 255);
    return texel_linear(level, x0, y0, table) * ((256u - fx) * (256u - fy))
        + texel_linear(level, x1, y0, table) * (fx * (256u - fy))
        + texel_linear(level, x0, y1, table) * ((256u - fx) * fy)
        + texel_linear(level, x1, y1, table) * (fx * fy);
}

// `x` as rounded here: a select on a value the compiler cannot know (the
// uniform's `zero`, always 0) hides how `x` was made, so no multiply
// behind it is fused into an add after it and no sum is reassociated
// across it. A uniform, not a storage word: lavapipe loads a storage word
// lane by lane, which cost its camera rays 6% (docs/accuracy.md).
fn rounded(x: f32) -> f32 {
    return select(x, 0.0, params.zero != 0u);
}

// `rounded` for vectors (no twin: Rust needs neither).
fn rounded3(x: vec3<f32>) -> vec3<f32> {
    return select(x, vec3<f32>(0.0), params.zero != 0u);
}

fn rounded4(x: vec4<f32>) -> vec4<f32> {
    return select(x, vec4<f32>(0.0), params.zero != 0u);
}

// The slot's UV transform: uv' = M · (u, v, 1).
fn transform_uv(slot: u32, uv: vec2<f32>) -> vec2<f32> {
    let m = array<f32, 6>(bitcast<f32>(texture_word(slot)), bitcast<f32>(texture_word(slot + 1u)),
        bitcast<f32>(texture_word(slot + 2u)), bitcast<f32>(texture_word(slot + 3u)),
        bitcast<f32>(texture_word(slot + 4u)), bitcast<f32>(texture_word(slot + 5u)));
    return vec2<f32>(rounded(rounded(rounded(m[0] * uv.x) + rounded(m[1] * uv.y)) + m[2]),
        rounded(rounded(rounded(m[3] * uv.x) + rounded(m[4] * uv.y)) + m[5]));
}

// A fixed-point sum (1.0 = 2^31) as floats: the high and low halves are
// exact, their sum rounds once, the scale is a power of two.
fn fixed_to_float(sum: vec4<u32>) -> vec4<f32> {
    let high = vec4<f32>(sum >> vec4<u32>(16u));
    let low = vec4<f32>(sum & vec4<u32>(65535u));
    return (high * 65536.0 + low) * (1.0 / 2147483648.0);
}

// The texture of the slot starting at word `slot` at `uv` (glTF's
// convention, before the slot's transform), at level of detail `lod` in
// 1/256 levels (≤ 0: magnified), as linear RGBA.
fn sample_texture(slot: u32, uv: vec2<f32>, lod: i32) -> vec4<f32> {
    let flags = texture_word(slot + 8u);
    let levels = texture_word(slot + 7u);
    let table = texture_word(slot + 9u);
    let count = (flags >> 8u) & 255u;
    let wrap_u = flags & 3u;
    let wrap_v = (flags >> 2u) & 3u;
    let t = transform_uv(slot, uv);
    let w = vec2<f32>(wrap_coordinate(t.x, wrap_u), wrap_coordinate(t.y, wrap_v));
    if lod <= 0 {
        return fixed_to_float(level_sum(levels, w, wrap_u, wrap_v, (flags & 16u) != 0u, table));
    }
    let bilinear = (flags & 32u) != 0u;
    if (flags & 64u) == 0u {
        return fixed_to_float(level_sum(levels, w, wrap_u, wrap_v, bilinear, table));
    }
    let level = u32(lod >> 8u);
    if level + 1u >= count {
        return fixed_to_float(level_sum(levels + 4u * (count - 1u), w, wrap_u, wrap_v, bilinear,
            table));
    }
    let f = u32(lod & 255);
    let finer = level_sum(levels + 4u * level, w, wrap_u, wrap_v, bilinear, table);
    let coarser = level_sum(levels + 4u * (level + 1u), w, wrap_u, wrap_v, bilinear, table);
    return fixed_to_float((finer >> vec4<u32>(8u)) * (256u - f) + (coarser >> vec4<u32>(8u)) * f);
}

// log2 |x| read from the float's bits (exponent, and the mantissa as a
// straight line between powers of two: within 0.09 of log2), in 1/4096.
fn log2_fixed(x: f32) -> i32 {
    return i32(bitcast<u32>(abs(x)) >> 11u) - (127 << 12u);
}

// The texture coordinate at barycentrics (b1, b2) of a triangle whose
// corners have `uv0`, `uv1`, `uv2`.
fn interpolate_uv(uv0: vec2<f32>, uv1: vec2<f32>, uv2: vec2<f32>, b1: f32, b2: f32) -> vec2<f32> {
    let e1 = vec2<f32>(rounded(uv1.x - uv0.x), rounded(uv1.y - uv0.y));
    let e2 = vec2<f32>(rounded(uv2.x - uv0.x), rounded(uv2.y - uv0.y));
    return vec2<f32>(rounded(uv0.x + rounded(rounded(b1 * e1.x) + rounded(b2 * e2.x))),
        rounded(uv0.y + rounded(rounded(b1 * e1.y) + rounded(b2 * e2.y))));
}

// a·b − c·d, each product and the difference rounded on its own.
fn difference_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    return rounded(rounded(a * b) - rounded(c * d));
}

// Ray-cone level of detail (Ray Tracing Gems ch. 20) in 1/256 levels:
// λ = ½ log2(texel area / world area) + log2(cone width) − log2 |cos θ|,
// with both areas from the same triangle (corners `p0..p2`, `uv0..uv2`)
// and the cone `cone_width` wide where it meets it along unit `dir`. With
// N = (p1 − p0) × (p2 − p0): world area = |N|/2, |cos θ| = |N·d|/|N|, so
// 4λ = log2((uv area · texel area)² · N·N · width⁴ / (N·d)⁴): no division,
// no square root, no log2.
fn texture_lod(slot: u32, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, uv0: vec2<f32>,
        uv1: vec2<f32>, uv2: vec2<f32>, dir: vec3<f32>, cone_width: f32) -> i32 {
    let e1 = vec3<f32>(rounded(p1.x - p0.x), rounded(p1.y - p0.y), rounded(p1.z - p0.z));
    let e2 = vec3<f32>(rounded(p2.x - p0.x), rounded(p2.y - p0.y), rounded(p2.z - p0.z));
    let n = vec3<f32>(difference_of_products(e1.y, e2.z, e1.z, e2.y),
        difference_of_products(e1.z, e2.x, e1.x, e2.z),
        difference_of_products(e1.x, e2.y, e1.y, e2.x));
    let nn = rounded(rounded(rounded(n.x * n.x) + rounded(n.y * n.y)) + rounded(n.z * n.z));
    let nd = rounded(rounded(rounded(n.x * dir.x) + rounded(n.y * dir.y)) + rounded(n.z * dir.z));
    let a = vec2<f32>(rounded(uv1.x - uv0.x), rounded(uv1.y - uv0.y));
    let b = vec2<f32>(rounded(uv2.x - uv0.x), rounded(uv2.y - uv0.y));
    let uv_area = difference_of_products(a.x, b.y, a.y, b.x);
    let texel_area = bitcast<f32>(texture_word(slot + 6u));
    let four_lambda = 2 * log2_fixed(uv_area) + 2 * log2_fixed(texel_area) + log2_fixed(nn)
        + 4 * log2_fixed(cone_width) - 4 * log2_fixed(nd);
    return four_lambda >> 6u;
}
