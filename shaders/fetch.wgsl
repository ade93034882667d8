// Stage: fetch. Reads of the scene's arrays across the split into two
// bindings, and of the BVH's nodes and leaf blocks from storage buffers or
// textures (BVH_TEXELS). CPU twin: src/cpu/fetch.rs (the CPU reads one
// array, so only the prefetch of what traversal visits next is there).

// Storage access across the split (no CPU twin: the CPU reads one array).
// Which binding element i lies in: the low one, or the `_hi` one after it
// where the array is split (`..._PER_BINDING` elements in the low one;
// UNSPLIT where not, which compiles the `_hi` load out: lavapipe would run
// it, masked, all the same).
const UNSPLIT: u32 = 0xffffffffu;

fn triangle_at(i: u32) -> Triangle {
    if BVH_TEXELS {
        let a = texel_at(triangle_texels, 3u * i);
        let b = texel_at(triangle_texels, 3u * i + 1u);
        let c = texel_at(triangle_texels, 3u * i + 2u);
        return Triangle(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w,
            bitcast<vec3<f32>>(c.xyz), c.w);
    }
    if TRIANGLES_PER_BINDING == UNSPLIT || i < TRIANGLES_PER_BINDING {
        return triangles[i];
    }
    return triangles_hi[i - TRIANGLES_PER_BINDING];
}

fn triangle_normals_at(i: u32) -> TriangleNormals {
    if NORMALS_PER_BINDING == UNSPLIT || i < NORMALS_PER_BINDING {
        return triangle_normals[i];
    }
    return triangle_normals_hi[i - NORMALS_PER_BINDING];
}

fn triangle_attributes_at(i: u32) -> TriangleAttributes {
    if ATTRIBUTES_PER_BINDING == UNSPLIT || i < ATTRIBUTES_PER_BINDING {
        return triangle_attributes[i];
    }
    return triangle_attributes_hi[i - ATTRIBUTES_PER_BINDING];
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

fn texel_at(texels: texture_storage_2d<rgba32uint, read>, t: u32) -> vec4<u32> {
    let row_mask = (1u << TEXEL_ROW_BITS) - 1u;
    return textureLoad(texels, vec2<u32>(t & row_mask, t >> TEXEL_ROW_BITS));
}

// Word k (0 to 4) of node i.
fn node_word(i: u32, k: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_node_texels, 5u * i + k);
    }
    if NODES_PER_BINDING == UNSPLIT || i < NODES_PER_BINDING {
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
    if BLOCKS_PER_BINDING == UNSPLIT || i < BLOCKS_PER_BINDING {
        return bvh_blocks[i].v[k][a];
    }
    return bvh_blocks_hi[i - BLOCKS_PER_BINDING].v[k][a];
}

fn block_prims(i: u32) -> vec4<u32> {
    if BVH_TEXELS {
        return texel_at(bvh_block_texels, 10u * i + 9u);
    }
    if BLOCKS_PER_BINDING == UNSPLIT || i < BLOCKS_PER_BINDING {
        return bvh_blocks[i].prims;
    }
    return bvh_blocks_hi[i - BLOCKS_PER_BINDING].prims;
}
