//! Structs shared by the host, the GPU shader (`shaders/layout.wgsl`) and the
//! CPU reference. Each (but `BvhNode`, the CPU kernel's alone) mirrors the
//! WGSL struct of the same name byte for byte
//! (vec3 fields take 16 bytes with the following scalar in their padding);
//! `tests/shaders.rs` checks sizes and offsets against naga's reflection.

use bytemuck::{Pod, Zeroable};

/// Primitive id of a miss.
pub const NO_HIT: u32 = u32::MAX;
/// Invocations per workgroup of every entry point (`WORKGROUP_INVOCATIONS`
/// in shaders/layout.wgsl, which sizes the traversal stacks in workgroup
/// memory by it; `cwbvh::short_stack` sizes the GPU's stack by it too).
pub const WORKGROUP_INVOCATIONS: u32 = 64;
/// `Light::kind` of a point light.
pub const LIGHT_POINT: u32 = 0;
/// `Light::kind` of a directional light.
pub const LIGHT_DIRECTIONAL: u32 = 1;
/// `Light::kind` of a spot light (glTF KHR_lights_punctual's, TOML
/// `kind = "spot"`): a point light limited to a cone.
pub const LIGHT_SPOT: u32 = 2;
/// `Material::kind`: Lambert, f = albedo/π (TOML albedo, OBJ without
/// specular terms, PLY, STL).
pub const MATERIAL_LAMBERT: u32 = 0;
/// `Material::kind`: glTF 2.0's metallic-roughness BRDF (its appendix B;
/// OBJ/MTL with Ks/Ns/Pr/Pm mapped to it, docs/rendering.md).
pub const MATERIAL_METALLIC_ROUGHNESS: u32 = 1;
/// `Triangle::flags` bit: interpolate `TriangleNormals` for shading.
pub const FLAG_SMOOTH: u32 = 1;
/// `Triangle::flags` bit: the triangle has `TriangleAttributes` (corner
/// colours and texture coordinates).
pub const FLAG_ATTRIBUTES: u32 = 2;
/// `Triangle::flags` bit: its material is alpha-masked, so traversal tests
/// its alpha at each hit (opaque triangles skip the test).
pub const FLAG_MASKED: u32 = 4;
/// `Material::alpha_mode`: opaque.
pub const ALPHA_OPAQUE: u32 = 0;
/// `Material::alpha_mode`: cut out where alpha < `alpha_cutoff` (glTF MASK,
/// and BLEND rendered as MASK at 0.5).
pub const ALPHA_MASK: u32 = 1;
/// A `Material` texture slot that holds no texture.
pub const NO_TEXTURE: u32 = u32::MAX;
/// The shader's "no hit yet" distance (WGSL has no infinity literal).
pub const FAR: f32 = f32::MAX;

/// Per-render uniform: camera basis, background, counts, current tile.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    pub eye: [f32; 3],
    pub width: u32,
    pub right: [f32; 3],
    pub height: u32,
    pub up: [f32; 3],
    /// tan(vfov/2)·W/H
    pub tan_half_x: f32,
    pub forward: [f32; 3],
    /// tan(vfov/2)
    pub tan_half_y: f32,
    pub background: [f32; 3],
    pub num_triangles: u32,
    pub ambient: [f32; 3],
    pub num_spheres: u32,
    pub tile_origin: [u32; 2],
    pub num_lights: u32,
    /// 1 to cast shadow rays, 0 not to.
    pub shadows: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the sample jitter.
    pub seed: u32,
    /// Columns of the stratified sample grid (a divisor of spp).
    pub strata_x: u32,
    /// The samples one dispatch adds to each pixel: [begin, end).
    pub sample_begin: u32,
    pub sample_end: u32,
    /// Trip count of the shader's `loops_completed` check: 2.
    pub canary_loops: u32,
    /// A camera ray's cone's spread angle: its width at distance t is
    /// t · cone_spread (`texture::cone_spread`).
    pub cone_spread: f32,
    /// Always 0: the guard the shader's `rounded` and `camera_ray` select
    /// on, a value no compiler can know; a uniform, so lavapipe reads it
    /// once, not lane by lane as a storage word (docs/accuracy.md).
    pub zero: u32,
    /// The current tile's width and height in pixels (at most gpu::TILE).
    pub tile_size: [u32; 2],
    /// Under the shader's PATH_TRACE, the most surfaces a path hits
    /// (`RenderSettings::max_depth`).
    pub max_depth: u32,
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub flags: u32,
    pub v2: [f32; 3],
    pub _pad: u32,
}

/// Vertex normals of one triangle (w unused), for smooth shading.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriangleNormals {
    pub n0: [f32; 4],
    pub n1: [f32; 4],
    pub n2: [f32; 4],
}

/// Corner colours (linear RGBA, multiplying the base colour) and texture
/// coordinates (glTF's convention) of one triangle; only read for
/// triangles with FLAG_ATTRIBUTES. 80 bytes a triangle, stored only when
/// some mesh has colours or texture coordinates (as `TriangleNormals`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriangleAttributes {
    pub colors: [[f32; 4]; 3],
    pub uvs: [[f32; 2]; 3],
    pub _pad: [f32; 2],
}

impl Default for TriangleAttributes {
    /// White corners (the base colour unchanged), texture coordinates 0.
    fn default() -> TriangleAttributes {
        TriangleAttributes {
            colors: [[1.0; 4]; 3],
            uvs: [[0.0; 2]; 3],
            _pad: [0.0; 2],
        }
    }
}

/// Tangent frames of one triangle's corners, for normal maps: xyz the
/// tangent (the direction of increasing u), w the bitangent's sign (glTF
/// TANGENT's convention: bitangent = w · normal × tangent). Stored only when
/// some material has a normal texture (as `TriangleNormals`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriangleTangents {
    pub t0: [f32; 4],
    pub t1: [f32; 4],
    pub t2: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// How a surface looks (docs/scene-format.md, "How colour reaches a
/// pixel"; docs/rendering.md, "Materials"): base colour (RGB: the albedo;
/// A: its alpha), emission added to the radiance it sends back, alpha mode
/// and cut-off, the BRDF (`kind`) with its metallic and roughness factors,
/// and texture slots (`NO_TEXTURE` where none). 80 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Linear RGBA.
    pub base_color: [f32; 4],
    /// Linear RGB radiance.
    pub emission: [f32; 3],
    /// ALPHA_OPAQUE or ALPHA_MASK.
    pub alpha_mode: u32,
    pub alpha_cutoff: f32,
    pub base_color_texture: u32,
    pub emissive_texture: u32,
    pub alpha_texture: u32,
    /// MATERIAL_LAMBERT or MATERIAL_METALLIC_ROUGHNESS.
    pub kind: u32,
    /// Metalness factor, × the metallic-roughness texture's B.
    pub metallic: f32,
    /// Perceptual roughness (glTF's; the GGX α is its square), × the
    /// metallic-roughness texture's G.
    pub roughness: f32,
    /// glTF metallicRoughnessTexture (linear: G roughness, B metallic).
    pub metallic_roughness_texture: u32,
    /// glTF normalTexture (linear, tangent space), read with the
    /// triangle's `TriangleTangents`.
    pub normal_texture: u32,
    /// glTF normalTexture.scale: the map's X and Y are scaled by it.
    pub normal_scale: f32,
    pub _pad: [u32; 2],
}

impl Material {
    /// An opaque, untextured, non-emissive Lambert material of this albedo.
    pub fn from_albedo(albedo: [f32; 3]) -> Material {
        let [r, g, b] = albedo;
        Material {
            base_color: [r, g, b, 1.0],
            emission: [0.0; 3],
            alpha_mode: ALPHA_OPAQUE,
            alpha_cutoff: 0.5,
            base_color_texture: NO_TEXTURE,
            emissive_texture: NO_TEXTURE,
            alpha_texture: NO_TEXTURE,
            kind: MATERIAL_LAMBERT,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: NO_TEXTURE,
            normal_texture: NO_TEXTURE,
            normal_scale: 1.0,
            _pad: [0; 2],
        }
    }

    pub fn albedo(&self) -> [f32; 3] {
        let [r, g, b, _] = self.base_color;
        [r, g, b]
    }
}

impl Default for Material {
    fn default() -> Material {
        Material::from_albedo([0.0; 3])
    }
}

/// A light, in the lecture's units (docs/rendering.md, "Light units"): a
/// point light adds albedo · color · cos θ / r² to the colour, a
/// directional light albedo · color · cos θ. Point light: `vector` = position,
/// `color` = intensity. Directional light: `vector` = unit direction towards
/// the light, `color` = irradiance. Spot light: a point light times the
/// falloff of KHR_lights_punctual between its cones about `direction`.
/// 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    pub vector: [f32; 3],
    /// LIGHT_POINT, LIGHT_DIRECTIONAL or LIGHT_SPOT.
    pub kind: u32,
    pub color: [f32; 3],
    /// Spot: cos of the outer cone's half-angle (no light beyond it).
    pub cos_outer: f32,
    /// Spot: the unit direction it points along.
    pub direction: [f32; 3],
    /// Spot: cos of the inner cone's half-angle (full intensity within).
    pub cos_inner: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

/// A ray-query answer: the hit point is (1−u−v)·v0 + u·v1 + v·v2 of triangle
/// `prim` (u = v = 0 for spheres).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl Hit {
    /// What a ray that hits nothing reports.
    pub const MISS: Hit = Hit {
        t: f32::INFINITY,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    };
}

/// Children of a BVH node at most.
pub const BVH_WIDTH: usize = 8;

/// One 8-wide BVH node (256 bytes: four cache lines), as the CPU kernel
/// reads it (the GPU reads `CompressedNode`s made from these); docs/bvh.md
/// and `bvh` tell more. The eight children's boxes are stored one lane per
/// child: `bounds[2a]` holds their minima along axis a, `bounds[2a + 1]` their
/// maxima. `children[i]` is child i's reference: a node index, a leaf
/// (`LEAF_BIT` set, see `leaf_ref`) or `EMPTY_SLOT`. Bit i of `occupied` is
/// set when slot i holds a child: traversal enters only those, because a ray
/// with a NaN or infinite component can pass the slab test of an empty
/// slot's inverted box. `set_child` is how a child is added: it keeps
/// `occupied` in step with `children`.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub bounds: [[f32; BVH_WIDTH]; 6],
    pub children: [u32; BVH_WIDTH],
    pub occupied: u32,
    pub _pad: [u32; BVH_WIDTH - 1],
}

/// Up to four primitives of one BVH leaf (160 bytes), the four lanes of
/// one watertight triangle test: lane i is primitive `prims[i]` (`NO_HIT`
/// for an empty lane), and for a triangle, `v[k][a][i]` is coordinate a of
/// its vertex k. Sphere and empty lanes have zero vertices, and traversal
/// takes hits only from lanes whose id is a triangle's (with fused
/// multiply-adds a GPU can find a hit in a triangle of zero vertices).
/// Holding the vertices here, in leaf order, spares a leaf the
/// id → triangle load, and one 4-lane test costs little more than one
/// triangle. Aligned to 32 bytes, so a block spans whole cache-line halves.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PrimBlock {
    pub v: [[[f32; 4]; 3]; 3],
    pub prims: [u32; 4],
}

impl PrimBlock {
    /// The block of `prims` (one to four ids), with the vertices of those
    /// that are triangles.
    pub fn new(prims: &[u32], triangles: &[Triangle]) -> PrimBlock {
        assert!(
            (1..=4).contains(&prims.len()),
            "a block of {} primitives",
            prims.len()
        );
        let mut block = PrimBlock {
            prims: [NO_HIT; 4],
            ..PrimBlock::default()
        };
        for (lane, &prim) in prims.iter().enumerate() {
            block.prims[lane] = prim;
            if let Some(t) = triangles.get(prim as usize) {
                for (k, vertex) in [t.v0, t.v1, t.v2].iter().enumerate() {
                    for (a, &x) in vertex.iter().enumerate() {
                        block.v[k][a][lane] = x;
                    }
                }
            }
        }
        block
    }
}

/// Marks a child reference as a leaf.
pub const LEAF_BIT: u32 = 0x8000_0000;
/// A leaf reference holds its block count − 1 from this bit up (3 bits)...
pub const LEAF_COUNT_SHIFT: u32 = 28;
/// ...and the index of its first block in the bits below.
pub const LEAF_FIRST_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// A child slot with no child; its box is inverted, so that no finite ray
/// enters it, and its `occupied` bit clear, so that traversal never does.
pub const EMPTY_SLOT: u32 = u32::MAX;

/// The reference to a leaf of `count` (1 to 8) blocks from block `first`.
pub fn leaf_ref(first: u32, count: u32) -> u32 {
    assert!(
        (1..=8).contains(&count) && first <= LEAF_FIRST_MASK,
        "no leaf reference holds {count} blocks from {first}"
    );
    LEAF_BIT | (count - 1) << LEAF_COUNT_SHIFT | first
}

/// (first, count) of a leaf reference.
pub fn leaf_range(child: u32) -> (u32, u32) {
    (
        child & LEAF_FIRST_MASK,
        ((child & !LEAF_BIT) >> LEAF_COUNT_SHIFT) + 1,
    )
}

impl BvhNode {
    /// No children: every slot empty, every box inverted.
    pub const EMPTY: BvhNode = BvhNode {
        bounds: [
            [FAR; BVH_WIDTH],
            [-FAR; BVH_WIDTH],
            [FAR; BVH_WIDTH],
            [-FAR; BVH_WIDTH],
            [FAR; BVH_WIDTH],
            [-FAR; BVH_WIDTH],
        ],
        children: [EMPTY_SLOT; BVH_WIDTH],
        occupied: 0,
        _pad: [0; BVH_WIDTH - 1],
    };

    /// Child `slot`'s box as (min, max).
    pub fn child_bounds(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        let b = &self.bounds;
        (
            [b[0][slot], b[2][slot], b[4][slot]],
            [b[1][slot], b[3][slot], b[5][slot]],
        )
    }

    /// Puts child `reference` with box (min, max) in `slot`.
    pub fn set_child(&mut self, slot: usize, reference: u32, min: [f32; 3], max: [f32; 3]) {
        for axis in 0..3 {
            self.bounds[2 * axis][slot] = min[axis];
            self.bounds[2 * axis + 1][slot] = max[axis];
        }
        assert_ne!(
            reference, EMPTY_SLOT,
            "slot {slot}: EMPTY_SLOT is not a child"
        );
        self.children[slot] = reference;
        self.occupied |= 1 << slot;
    }
}

/// One node of the GPU's compressed 8-wide BVH (80 bytes; `cwbvh` builds
/// it from the wide tree, docs/bvh.md has the measurements). Child boxes are
/// quantised to 8 bits per plane on a grid of `origin + q·2^(e − 127)` per
/// axis, rounded outwards, so a child's box only grows; the grid is chosen
/// so that every plane it can hold is an f32 exactly (no rounding when the
/// shader dequantises it). `exponents` holds e for x, y and z in bytes 0 to
/// 2. Slots are ordered by octant: slot s holds the child lying most toward
/// the corner whose axis a is on the positive side when bit a of s is set,
/// so a ray visits children nearest first by taking slots in the order
/// `b ^ octant` for b = 0..8 (`ray_octant`). `child_meta` has a byte per slot
/// (slots 0–3 in `child_meta[0]`, low byte first): 0 for an empty slot,
/// `META_INTERIOR | rank` for interior child `child_base + rank` (rank: the
/// interior slots below it; siblings are consecutive, in slot order), and for a
/// leaf `META_LEAF | (count − 1) << 4 | offset`, blocks `block_base +
/// offset ..` (count of them). `q[2a]` holds the slots' quantised minima
/// along axis a, `q[2a + 1]` their maxima, a byte per slot as in `child_meta`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CompressedNode {
    pub origin: [f32; 3],
    pub exponents: u32,
    pub child_base: u32,
    pub block_base: u32,
    pub child_meta: [u32; 2],
    pub q: [[u32; 2]; 6],
}

/// Point q of a `CompressedNode` grid, as the shader computes it: exact on
/// the grids `cwbvh` chooses.
pub fn grid_point(q: u32, scale: f32, origin: f32) -> f32 {
    (q as f32).mul_add(scale, origin)
}

/// `CompressedNode::child_meta` byte of an interior child (its rank below).
pub const META_INTERIOR: u32 = 0x08;
/// `CompressedNode::child_meta` byte of a leaf (count − 1 and offset below).
pub const META_LEAF: u32 = 0x80;

impl CompressedNode {
    /// Slot `slot`'s byte of a row of eight (`child_meta` or a row of `q`).
    pub fn byte(row: [u32; 2], slot: usize) -> u32 {
        row[slot / 4] >> (8 * (slot % 4)) & 0xff
    }

    /// The scale 2^(e − 127) of axis `axis`'s grid.
    pub fn scale(&self, axis: usize) -> f32 {
        f32::from_bits((self.exponents >> (8 * axis) & 0xff) << 23)
    }

    /// Child `slot`'s box as the shader dequantises it: (min, max).
    pub fn child_bounds(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        let plane = |row: usize, axis: usize| {
            grid_point(
                CompressedNode::byte(self.q[row], slot),
                self.scale(axis),
                self.origin[axis],
            )
        };
        (
            std::array::from_fn(|a| plane(2 * a, a)),
            std::array::from_fn(|a| plane(2 * a + 1, a)),
        )
    }
}

/// A closest-point query's answer for one point (docs/ray-query.md,
/// "Closest points"): the nearest point of triangle `prim`, which is
/// (1−u−v)·v0 + u·v1 + v·v2 as `Hit`'s u and v are, and its distance.
/// Beyond the query's max distance, or in an empty scene, `prim` is
/// `NO_HIT`, `distance` +inf, and the point and u, v are 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ClosestPoint {
    pub point: [f32; 3],
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub distance: f32,
    pub _pad: u32,
}

impl ClosestPoint {
    /// What a point with no triangle within the max distance reports.
    pub const NONE: ClosestPoint = ClosestPoint {
        point: [0.0; 3],
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
        distance: f32::INFINITY,
        _pad: 0,
    };
}

/// One crossing of an all-hits query: ray `ray` crosses triangle `prim` at
/// t (in units of the ray's direction), at (u, v) as `Hit` gives them.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ListedHit {
    pub ray: u32,
    pub prim: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// One node of the winding tree (`bvh::WindingTree`, fast winding numbers
/// after Barill et al. 2018): the dipole of every triangle below it (the
/// sum of their area vectors, half the edge cross products, and their
/// area-weighted centre), the radius about that centre of a ball holding
/// them, its interior children `first_child ..` (`child_count` of them)
/// and the triangles of its leaves, `first_prim ..` (`prim_count`) in
/// `WindingTree::prims`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WindingNode {
    pub centre: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub first_child: u32,
    pub child_count: u32,
    pub first_prim: u32,
    pub prim_count: u32,
    pub _pad: u32,
}

/// `Emitter::kind` of an emissive triangle (`index`: its primitive id).
pub const EMITTER_TRIANGLE: u32 = 0;
/// `Emitter::kind` of a punctual light (`index`: its place in the lights).
pub const EMITTER_LIGHT: u32 = 1;
/// `Emitter::kind` of the environment (`index` 0).
pub const EMITTER_ENVIRONMENT: u32 = 2;
/// `Lighting::flags` bit: the environment is an image (binding
/// `environment`), not the constant `environment_color`.
pub const LIGHTING_ENVIRONMENT_IMAGE: u32 = 1;

/// One entry of the emitters' table (docs/rendering.md, "Lights"): an
/// emitter, the probability `pmf` that `sample_emitter` picks it (its share
/// of the scene's power), and its bin of the alias table the pick reads
/// (pbrt-v4's `AliasTable`: bin i keeps i with probability `q`, else
/// gives `alias_bin`). Triangles come first, ordered by primitive id, so that
/// `emitter_pdf` finds a hit triangle's entry by binary search.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Emitter {
    /// `EMITTER_TRIANGLE`, `EMITTER_LIGHT` or `EMITTER_ENVIRONMENT`.
    pub kind: u32,
    pub index: u32,
    pub pmf: f32,
    pub q: f32,
    pub alias_bin: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The lighting uniform (group 0, binding 23): the emitters' table's
/// counts and the environment's parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Lighting {
    /// The constant environment's radiance × strength (no image: flags).
    pub environment_color: [f32; 3],
    pub num_emitters: u32,
    /// The map's columns and rows (rows ≥ 2: one row is stored twice).
    pub environment_width: u32,
    pub environment_height: u32,
    /// cos and sin of `rotation_deg` (the map turned about +Y).
    pub rotation_cos: f32,
    pub rotation_sin: f32,
    /// Entries of the table that are triangles (its first ones).
    pub num_triangle_emitters: u32,
    /// The environment's entry's pmf (0 where there is none).
    pub environment_pmf: f32,
    /// The emitters' summed power, which the pmfs are shares of.
    pub total_power: f32,
    /// `LIGHTING_ENVIRONMENT_IMAGE`.
    pub flags: u32,
}

/// One query of `probe_lights` (shaders/entry_lights.wgsl), the lights
/// stage's functions run on the GPU for tests to compare with the CPU twin.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightQuery {
    pub position: [f32; 3],
    pub u_pick: f32,
    pub normal: [f32; 3],
    pub hit_prim: u32,
    pub dir: [f32; 3],
    pub distance: f32,
    pub u: [f32; 2],
    pub _pad: [u32; 2],
}

/// `probe_lights`' answer to a `LightQuery`: `sample_emitter`'s sample
/// (`delta` 1 or 0), `environment_radiance` and `environment_pdf` of
/// `dir`, and `emitter_pdf`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightAnswer {
    pub wi: [f32; 3],
    pub distance: f32,
    pub radiance: [f32; 3],
    pub pdf: f32,
    pub environment: [f32; 3],
    pub environment_pdf: f32,
    pub emitter_pdf: f32,
    pub delta: u32,
    pub _pad: [u32; 2],
}

/// Where each of the scene's arrays starts in the shader's `scene_words`
/// (group 0, binding 2; src/gpu/upload.rs), in 16-byte words: every
/// read-only array in one storage buffer, so that a pass binds few (WebGPU
/// in browsers allows 8 or 10 a stage).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SceneArrays {
    pub triangles: u32,
    pub normals: u32,
    pub attributes: u32,
    pub tangents: u32,
    pub nodes: u32,
    pub blocks: u32,
    pub spheres: u32,
    pub materials: u32,
    pub lights: u32,
    pub textures: u32,
    pub emitters: u32,
    pub environment: u32,
    pub environment_cdf: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}
