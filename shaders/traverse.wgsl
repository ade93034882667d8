// Stage: traversal. The slab test of a compressed node's eight children,
// the traversal stack (workgroup memory, spilling when the tree is deep),
// the compressed BVH's traversal and the brute-force reference, a ray's
// preparation for them (`prepare_ray`, `unscale`), and `trace_closest`,
// `trace_any` over `trace` (shaders/trace.wgsl, or hardware_trace.wgsl).
// CPU twin: src/cpu/traverse.rs.

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
// sorting); with `any_hit`, the first hit found. Aila and Laine's
// while-while form: the outer loop tests the leaf blocks the last node
// visit entered, then the inner loop visits nodes until one enters blocks
// (or none is left). Each invocation still tests a node's blocks before it
// visits the next node, so its order, and its hit, is the CPU twin's, bit
// for bit. Why two loops: lavapipe runs invocations in the lanes of a SIMD
// register and runs every branch and loop body at least once for all of
// them, masked, so in one loop each pass paid for a block test whether any
// lane had a block or not; here a block test runs once a leaf is found, and
// the node visits between leaves run back to back (docs/bvh.md: 1.3x).
// A node group (child_base; entered interior children in visit order, and
// the interior slots in bits 8–15) names the next nodes without reading
// their parent again: slot s is node child_base + the interior slots below
// s. The stack holds groups, pushed when traversal descends below a node:
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
        var done = false;
        loop {
            if (group.y & 0xffu) == 0u {
                if sp == 0u {
                    done = true;
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
            if blocks != 0u {
                break;
            }
        }
        if done {
            break;
        }
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

// Whether any of `v` is a NaN: by its bits, which no compiler's float
// rules can fold away.
fn has_nan(v: vec3<f32>) -> bool {
    return any((bitcast<vec3<u32>>(v) & vec3<u32>(0x7fffffffu)) > vec3<u32>(0x7f800000u));
}

// A ray as the traversal takes it (the CPU twin's prepare_ray returns the
// pair): its direction scaled by a power of two, exactly, so that tiny
// directions' clamped components stay negligible (see the twin), tmin and
// tmax by the inverse; its shear, whose t_scale takes a hit's distance
// back (`unscale`).
struct PreparedRay {
    ray: Ray,
    shear: Shear,
}

fn prepare_ray(ray_in: Ray) -> PreparedRay {
    var ray = ray_in;
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
    return PreparedRay(ray, shear);
}

// A hit of a prepared ray, its distance back in the ray's own units.
fn unscale(hit_in: Hit, shear: Shear) -> Hit {
    var hit = hit_in;
    if hit.prim != NO_HIT {
        hit.t *= shear.t_scale;
    }
    return hit;
}

// Whether a ray has a NaN in its origin, direction or tmin: it hits
// nothing (every distance test fails), but its slab test enters every box
// (a NaN comparison is false, so the slab is ignored), so `trace` returns
// a miss at once: walking the whole tree took an H200 0.39 s for one ray.
fn is_nan_ray(ray: Ray) -> bool {
    return has_nan(ray.origin) || has_nan(ray.dir) || has_nan(vec3<f32>(ray.tmin));
}

// `trace` itself, which the functions below and the ray-query entry point
// call, is shaders/trace.wgsl's (the compute traversal above) or, under
// `--accel hardware`, shaders/hardware_trace.wgsl's (a ray query).

fn trace_closest(ray: Ray) -> Hit {
    return trace(ray, false);
}

// Any hit in (tmin, tmax): stops at the first blocker.
fn trace_any(ray: Ray) -> bool {
    return trace(ray, true).prim != NO_HIT;
}
