// Stage: fetch. Reads of the scene's arrays from their words (split over
// two bindings where large), the BVH's nodes and leaf blocks and the
// triangles from those or from textures (BVH_TEXELS). CPU twin: src/cpu/fetch.rs (the CPU reads one
// array, so only the prefetch of what traversal visits next is there).

// The scene's arrays in `scene_words` (no CPU twin: the CPU reads its own
// arrays). Word w lies in the low binding, or in `scene_words_hi` after
// it where the words are split (WORDS_PER_BINDING in the low one; UNSPLIT
// where not, which compiles the `_hi` load out: lavapipe would run it,
// masked, all the same).
const UNSPLIT: u32 = 0xffffffffu;

fn word_at(w: u32) -> vec4<u32> {
    if WORDS_PER_BINDING == UNSPLIT || w < WORDS_PER_BINDING {
        return scene_words[w];
    }
    return scene_words_hi[w - WORDS_PER_BINDING];
}

fn float_word_at(w: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(word_at(w));
}

// Element i of an array of 32-bit values starting at word `base`.
fn scalar_at(base: u32, i: u32) -> u32 {
    return word_at(base + (i >> 2u))[i & 3u];
}

fn triangle_at(i: u32) -> Triangle {
    var a: vec4<u32>;
    var b: vec4<u32>;
    var c: vec4<u32>;
    if BVH_TEXELS {
        a = texel_at(triangle_texels, 3u * i);
        b = texel_at(triangle_texels, 3u * i + 1u);
        c = texel_at(triangle_texels, 3u * i + 2u);
    } else {
        let w = arrays.triangles + 3u * i;
        a = word_at(w);
        b = word_at(w + 1u);
        c = word_at(w + 2u);
    }
    return Triangle(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w,
        bitcast<vec3<f32>>(c.xyz), c.w);
}

fn triangle_normals_at(i: u32) -> TriangleNormals {
    let w = arrays.normals + 3u * i;
    return TriangleNormals(float_word_at(w), float_word_at(w + 1u), float_word_at(w + 2u));
}

fn triangle_tangents_at(i: u32) -> TriangleTangents {
    let w = arrays.tangents + 3u * i;
    return TriangleTangents(float_word_at(w), float_word_at(w + 1u), float_word_at(w + 2u));
}

fn triangle_attributes_at(i: u32) -> TriangleAttributes {
    let w = arrays.attributes + 5u * i;
    let uv01 = float_word_at(w + 3u);
    let uv2 = float_word_at(w + 4u);
    return TriangleAttributes(
        array<vec4<f32>, 3>(float_word_at(w), float_word_at(w + 1u), float_word_at(w + 2u)),
        array<vec2<f32>, 3>(uv01.xy, uv01.zw, uv2.xy), uv2.zw);
}

fn sphere_at(i: u32) -> Sphere {
    let w = arrays.spheres + 2u * i;
    let a = word_at(w);
    let b = word_at(w + 1u);
    return Sphere(bitcast<vec3<f32>>(a.xyz), bitcast<f32>(a.w), b.x, b.y, b.z, b.w);
}

fn material_entry(i: u32) -> Material {
    let w = arrays.materials + 5u * i;
    let emission = word_at(w + 1u);
    let c = word_at(w + 2u);
    let d = word_at(w + 3u);
    let e = word_at(w + 4u);
    return Material(float_word_at(w), bitcast<vec3<f32>>(emission.xyz), emission.w,
        bitcast<f32>(c.x), c.y, c.z, c.w, d.x, bitcast<f32>(d.y), bitcast<f32>(d.z), d.w, e.x,
        bitcast<f32>(e.y), e.zw);
}

fn light_at(i: u32) -> Light {
    let w = arrays.lights + 3u * i;
    let a = word_at(w);
    let b = word_at(w + 1u);
    let c = word_at(w + 2u);
    return Light(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w),
        bitcast<vec3<f32>>(c.xyz), bitcast<f32>(c.w));
}

fn emitter_at(i: u32) -> Emitter {
    let w = arrays.emitters + 2u * i;
    let a = word_at(w);
    let b = word_at(w + 1u);
    return Emitter(a.x, a.y, bitcast<f32>(a.z), bitcast<f32>(a.w), b.x, b.y, b.z, b.w);
}

// The environment map's pixel i (linear RGB × strength, row 0 straight up).
fn environment_at(i: u32) -> vec4<f32> {
    return float_word_at(arrays.environment + i);
}

// Its sampling distribution's value i (src/lighting/distribution.rs: the
// marginal CDF over its rows of cells, then each row's conditional CDF).
fn environment_cdf_at(i: u32) -> f32 {
    return bitcast<f32>(scalar_at(arrays.environment_cdf, i));
}

// Word i of the scene's textures (src/texture/store.rs).
fn texture_word(i: u32) -> u32 {
    return scalar_at(arrays.textures, i);
}

// Nodes are stored as five vec4 words and read as such: five
// loads rather than one per field. lavapipe runs a load whose address
// differs between invocations one invocation at a time, a loop per load
// instruction, so fewer, wider loads made traversal 12% faster there
// (docs/bvh.md).
fn unpack_node(w: array<vec4<u32>, 5>) -> CompressedNode {
    return CompressedNode(bitcast<vec3<f32>>(w[0].xyz), w[0].w, w[1].x, w[1].y, w[1].zw,
        array<vec2<u32>, 6>(w[2].xy, w[2].zw, w[3].xy, w[3].zw, w[4].xy, w[4].zw));
}

fn texel_at(texels: texture_storage_2d<rgba32uint, read>, t: u32) -> vec4<u32> {
    let row_mask = (1u << TEXEL_ROW_BITS) - 1u;
    return textureLoad(texels, vec2<u32>(t & row_mask, t >> TEXEL_ROW_BITS));
}

// Word k (0 to 4) of node i.
fn node_word(i: u32, k: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_node_texels, 5u * i + k);
    }
    return word_at(arrays.nodes + 5u * i + k);
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
    return float_word_at(arrays.blocks + 10u * i + 3u * k + a);
}

fn block_prims(i: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_block_texels, 10u * i + 9u);
    }
    return word_at(arrays.blocks + 10u * i + 9u);
}
