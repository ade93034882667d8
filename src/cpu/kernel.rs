// The CPU twin of shaders/trace.wgsl, function by function with the same
// names. Included twice by src/cpu/mod.rs: once with `Real = f32` (the
// reference the GPU is diffed against) and once with `Real = f64` (the
// oracle). The including module defines `Real`, `Vec3`, `Vec4`,
// `greater_of` and `lesser_of` (the shader's NaN-ignoring selects), and
// `intersect_boxes_ymm` with `has_ymm_boxes` (`intersect_boxes` in one
// 8-lane register, and whether the CPU can run it), and `push_sorted_zmm`
// (the ordering of entered children in vector registers).

use crate::bvh::{MAX_DEPTH, STACK_SIZE};
use crate::layout::{
    BVH_WIDTH, BvhNode, CompressedNode, FLAG_SMOOTH, LEAF_BIT, LIGHT_POINT, META_LEAF, NO_HIT,
    PrimBlock, leaf_range,
};
use crate::scene::{Accel, Camera, Intersect, Scene};

/// Widens a box's exit distance so that rounding cannot cull a box the ray
/// grazes, as in the shader.
const BOX_SLACK: Real = 1.000001;

/// Unit roundoff (pbrt's MachineEpsilon), for error bounds.
const MACHINE_EPSILON: Real = Real::EPSILON * 0.5;

/// "No hit yet" distance, as in the shader.
pub const FAR: Real = Real::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub tmin: Real,
    pub dir: Vec3,
    pub tmax: Real,
}

impl Ray {
    /// A ray of a ray query, in this precision.
    pub fn from_query(ray: &crate::layout::Ray) -> Ray {
        Ray {
            origin: vec3(ray.origin),
            tmin: ray.tmin as Real,
            dir: vec3(ray.dir),
            tmax: ray.tmax as Real,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: Real,
    pub prim: u32,
    pub u: Real,
    pub v: Real,
}

impl Hit {
    /// A ray query's answer, in this precision.
    pub fn from_query(hit: &crate::layout::Hit) -> Hit {
        Hit {
            t: hit.t as Real,
            prim: hit.prim,
            u: hit.u as Real,
            v: hit.v as Real,
        }
    }
}

/// Precomputed per ray for the watertight test: axes permuted so that the
/// direction's largest component is z, and the shear onto +z.
#[derive(Clone, Copy, Debug)]
pub struct Shear {
    pub axes: [usize; 3],
    pub s: Vec3,
    /// The power of two `prepare_ray` scaled the direction by: a hit's
    /// distance along the scaled ray times this is its distance along the
    /// ray as given.
    pub t_scale: Real,
}

pub struct Surface {
    pub position: Vec3,
    /// How far `position` may be off the surface, per axis (self_hit_bound).
    pub error: Vec3,
    pub geometric_normal: Vec3,
    pub shading_normal: Vec3,
    pub albedo: Vec3,
}

/// A traversal's stack: node indices or leaf references, and the distances at
/// which the ray enters their boxes. Uninitialised: zeroing it would cost as
/// much as a node visit, and only entries below the traversal's `sp` are
/// ever read.
pub(crate) type TraversalStack = [std::mem::MaybeUninit<(u32, Real)>; STACK_SIZE];

#[inline(always)]
pub(crate) fn new_stack() -> TraversalStack {
    [std::mem::MaybeUninit::uninit(); STACK_SIZE]
}

/// One ray's traversal of the BVH in progress: the shader's `trace_bvh`
/// locals (but the stack), kept between `Kernel::visit` passes so that a
/// thread can advance several rays in turn (their memory loads then
/// overlap).
#[derive(Clone, Copy)]
pub(crate) struct Traversal {
    /// tmax shrinks to the closest hit so far.
    pub ray: Ray,
    pub hit: Hit,
    slabs: Slabs,
    shear: Shear,
    any_hit: bool,
    /// Entries on the stack.
    sp: usize,
    /// What the next pass visits: the root first.
    child: u32,
    /// The leaf block that holds `hit`'s primitive (the last block that
    /// recorded a hit), for its geometric normal while the block is hot.
    pub hit_block: u32,
}

impl Traversal {
    #[inline(always)]
    pub(crate) fn new(ray: Ray, shear: Shear, any_hit: bool) -> Traversal {
        Traversal {
            ray,
            hit: miss(),
            slabs: ray_slabs(&ray),
            shear,
            any_hit,
            sp: 0,
            child: 0,
            hit_block: NO_HIT,
        }
    }

    /// The hit found, its distance along the ray as given.
    #[inline(always)]
    #[allow(dead_code)] // the oracle traces through `Kernel::trace` alone
    pub(crate) fn answer(&self) -> Hit {
        unscale(self.hit, &self.shear)
    }
}

/// `hit` (of a ray `prepare_ray` scaled) with its distance along the ray as
/// given; a miss stays at FAR.
#[inline(always)]
fn unscale(hit: Hit, shear: &Shear) -> Hit {
    if hit.prim == NO_HIT {
        hit
    } else {
        Hit {
            t: hit.t * shear.t_scale,
            ..hit
        }
    }
}

/// Powers of two 2^k and 2^−k such that the largest of `m` (> 0)·2^k is in
/// [1, 2), from the exponent of `m` in single precision (as the shader's
/// frexp); 1 and 1 for 0 or a subnormal.
#[inline(always)]
fn direction_scale(m: Real) -> (Real, Real) {
    let exponent = ((m as f32).to_bits() >> 23) & 0xff;
    if exponent == 0 || exponent >= 254 {
        return (1.0, 1.0);
    }
    let up = f32::from_bits((254 - exponent) << 23);
    let down = f32::from_bits(exponent << 23);
    (up as Real, down as Real)
}

/// The ray as `trace` traces it (misses report FAR, so an infinite tmax must
/// not let them through), and its shear.
#[inline(always)]
pub fn prepare_ray(ray_in: Ray) -> (Ray, Shear) {
    let mut ray = ray_in;
    // The direction scaled by a power of two to a largest component in
    // [1, 2), and tmin, tmax by its inverse: exact, so every distance is
    // the same times that power; but the slab test's clamp of tiny
    // components (MIN_SLAB_DIR) then sees them relative to the largest,
    // so a ray of direction (0, 0, −1e-18) is not stopped by the clamped
    // x and y. The hit's distance is scaled back (`unscale`).
    let (up, down) = direction_scale(ray.dir.abs().max_element());
    ray.dir *= up;
    ray.tmin *= down;
    // As the shader's select: a NaN tmax becomes FAR.
    ray.tmax *= down;
    ray.tmax = if ray.tmax < FAR { ray.tmax } else { FAR };
    let mut shear = ray_shear(ray.dir);
    shear.t_scale = up;
    (ray, shear)
}

pub fn miss() -> Hit {
    Hit {
        t: FAR,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    }
}

fn vec3(v: [f32; 3]) -> Vec3 {
    Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
}

#[inline(always)]
fn vec4(v: [f32; 4]) -> Vec4 {
    Vec4::new(v[0] as Real, v[1] as Real, v[2] as Real, v[3] as Real)
}

fn vec3_f64(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0] as Real, v[1] as Real, v[2] as Real)
}

/// The camera convention of docs/scene-format.md in this precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraBasis {
    pub eye: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    /// tan(vfov/2)·W/H
    pub tan_half_x: Real,
    /// tan(vfov/2)
    pub tan_half_y: Real,
    pub width: u32,
    pub height: u32,
}

impl CameraBasis {
    pub fn new(camera: &Camera) -> CameraBasis {
        let eye = vec3_f64(camera.eye);
        let forward = (vec3_f64(camera.look_at) - eye).normalize();
        let right = forward.cross(vec3_f64(camera.up)).normalize();
        let up = right.cross(forward);
        let tan_half_y = (camera.vfov.to_radians() * 0.5).tan() as Real;
        CameraBasis {
            eye,
            right,
            up,
            forward,
            tan_half_x: tan_half_y * camera.width as Real / camera.height as Real,
            tan_half_y,
            width: camera.width,
            height: camera.height,
        }
    }
}

/// A scene seen from one camera: what the shader's bindings hold.
pub struct Kernel<'a> {
    pub camera: CameraBasis,
    pub scene: &'a Scene,
    background: Vec3,
    ambient: Vec3,
    strata_x: u32,
    /// The ray/triangle test: the scene's, unless a query asks for another.
    pub intersect: Intersect,
    /// Whether node visits take `intersect_boxes_ymm` (the CPU has 8-lane
    /// vector registers and fused multiply-adds).
    ymm_boxes: bool,
    /// The GPU's compressed nodes of the scene's BVH: with them, `trace`
    /// traverses as the shader does (`trace_compressed`), the twin that
    /// GPU results are compared with.
    pub compressed: Option<&'a [CompressedNode]>,
    /// The GPU's short stack: entries `trace_compressed` keeps before the
    /// oldest spill (`cwbvh::short_stack`; `MAX_DEPTH`, none spill).
    pub stack_entries: usize,
}

/// The shader's traversal stack of node groups: entry `sp` in slot
/// `sp % entries` of the short stack (workgroup memory there), the entry
/// it displaces in `spill`, so the top `entries` are always short-stack
/// entries. Same steps as the shader's `push_group` and `pop_group`.
struct GroupStack {
    short: [(u32, u32); MAX_DEPTH],
    spill: [(u32, u32); MAX_DEPTH],
    entries: usize,
}

impl GroupStack {
    fn new(entries: usize) -> GroupStack {
        GroupStack {
            short: [(0, 0); MAX_DEPTH],
            spill: [(0, 0); MAX_DEPTH],
            entries: entries.clamp(1, MAX_DEPTH),
        }
    }

    /// Pushes `group` as entry `sp`.
    fn push_group(&mut self, sp: usize, group: (u32, u32)) {
        let slot = sp % self.entries;
        if sp >= self.entries {
            self.spill[sp - self.entries] = self.short[slot];
        }
        self.short[slot] = group;
    }

    /// Pops entry `sp` (the top).
    fn pop_group(&mut self, sp: usize) -> (u32, u32) {
        let slot = sp % self.entries;
        let group = self.short[slot];
        if sp >= self.entries {
            self.short[slot] = self.spill[sp - self.entries];
        }
        group
    }
}

/// What a light gives a point unless something blocks it (the shader's
/// `LightSample`, with `lit` as the `Some`).
pub struct LightSample {
    pub irradiance: Vec3,
    pub cos_theta: Real,
    pub shadow_ray: Ray,
}

/// The shader's `light_sample`: what `light` gives the point `surface`
/// (shadow rays leaving from `origin`), or `None` when nothing.
#[inline(always)]
pub fn light_sample(
    surface: &Surface,
    origin: Vec3,
    light: &crate::layout::Light,
) -> Option<LightSample> {
    let light_vector = vec3(light.vector);
    let (to_light, irradiance, shadow_ray) = if light.kind == LIGHT_POINT {
        let d = light_vector - surface.position;
        let distance_squared = d.dot(d);
        // A point light on the shaded point lies in its tangent plane:
        // cos θ = 0, no light (not 0/0). Close by, I/r² is held finite, so
        // that a black albedo gives 0, not 0·∞.
        if distance_squared == 0.0 {
            return None;
        }
        let s = light_vector - origin;
        let shadow_length = s.length();
        (
            d / distance_squared.sqrt(),
            (vec3(light.color) / distance_squared).min(Vec3::splat(FAR)),
            Ray {
                origin,
                tmin: 0.0,
                dir: s / shadow_length,
                tmax: shadow_length,
            },
        )
    } else {
        (
            light_vector,
            vec3(light.color),
            Ray {
                origin,
                tmin: 0.0,
                dir: light_vector,
                tmax: FAR,
            },
        )
    };
    let cos_theta = surface.shading_normal.dot(to_light);
    // No shadow ray for a light that cannot contribute (a NaN cos θ still
    // goes on, as it always has).
    if cos_theta <= 0.0 || irradiance == Vec3::ZERO {
        return None;
    }
    Some(LightSample {
        irradiance,
        cos_theta,
        shadow_ray,
    })
}

impl<'a> Kernel<'a> {
    pub fn new(scene: &'a Scene) -> Kernel<'a> {
        Kernel::new_for(scene, has_ymm_boxes())
    }

    /// `new`, with node visits through `intersect_boxes_ymm` or not: the
    /// SIMD kernels' tests compare each against the portable one.
    pub fn new_for(scene: &'a Scene, ymm_boxes: bool) -> Kernel<'a> {
        Kernel {
            camera: CameraBasis::new(&scene.local_camera(&scene.camera)),
            scene,
            background: vec3(scene.background),
            ambient: vec3(scene.ambient),
            strata_x: crate::scene::strata_columns(scene.spp),
            intersect: scene.intersect,
            ymm_boxes,
            compressed: None,
            stack_entries: MAX_DEPTH,
        }
    }

    /// Pinhole camera; `pixel` in pixel units, row 0 at the top.
    pub fn camera_ray(&self, pixel_x: Real, pixel_y: Real) -> Ray {
        let c = &self.camera;
        let sx = (2.0 * pixel_x / c.width as Real - 1.0) * c.tan_half_x;
        let sy = (1.0 - 2.0 * pixel_y / c.height as Real) * c.tan_half_y;
        let dir = (c.forward + sx * c.right + sy * c.up).normalize();
        Ray {
            origin: c.eye,
            tmin: 0.0,
            dir,
            tmax: FAR,
        }
    }

    /// The scene's ray/triangle test.
    #[inline(always)]
    pub fn intersect_triangle(
        &self,
        ray: &Ray,
        shear: &Shear,
        a: Vec3,
        b: Vec3,
        c: Vec3,
    ) -> (Real, Real, Real) {
        match self.intersect {
            Intersect::Seed => intersect_triangle_seed(ray, a, b, c),
            Intersect::MollerTrumbore => intersect_triangle_moller_trumbore(ray, a, b, c),
            Intersect::Watertight => intersect_triangle_watertight(ray, shear, a, b, c),
        }
    }

    /// (t, u, v) of primitive `prim` (triangles first, then spheres).
    #[inline(always)]
    pub fn intersect_primitive(&self, ray: &Ray, shear: &Shear, prim: u32) -> (Real, Real, Real) {
        let triangles = &self.scene.triangles;
        if (prim as usize) < triangles.len() {
            let tri = &triangles[prim as usize];
            return self.intersect_triangle(ray, shear, vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
        }
        let sphere = &self.scene.spheres[prim as usize - triangles.len()];
        (intersect_sphere(ray, vec3(sphere.center), sphere.radius as Real), 0.0, 0.0)
    }

    /// Tests `prim`; if it is hit nearer than ray.tmax, makes it the hit and
    /// shortens the ray. Returns whether it did.
    #[inline(always)]
    pub fn record_hit(&self, ray: &mut Ray, shear: &Shear, hit: &mut Hit, prim: u32) -> bool {
        let (t, u, v) = self.intersect_primitive(ray, shear, prim);
        if t < ray.tmax {
            ray.tmax = t;
            *hit = Hit { t, prim, u, v };
            return true;
        }
        false
    }

    /// Tests a leaf block's primitives: its triangles in one 4-lane
    /// watertight test, then (in lane order) its spheres, and its triangles
    /// too under another triangle test. Each hit nearer than ray.tmax
    /// becomes the hit and shortens the ray; returns whether there was one.
    #[inline(always)]
    pub fn record_block_hits(
        &self,
        ray: &mut Ray,
        shear: &Shear,
        hit: &mut Hit,
        block: &PrimBlock,
    ) -> bool {
        let scene = self.scene;
        let watertight = self.intersect == Intersect::Watertight;
        let mut recorded = false;
        let num_triangles = scene.triangles.len() as u32;
        if watertight && num_triangles > 0 {
            let lanes = intersect_triangle_block(ray, shear, block);
            for (lane, &t) in lanes.t.to_array().iter().enumerate() {
                // Only triangle lanes (the id test also drops empty ones): a
                // GPU that fuses multiply-adds can see a hit in a lane of
                // zero vertices.
                if t < ray.tmax && block.prims[lane] < num_triangles {
                    ray.tmax = t;
                    let (u, v) = lanes.uv(lane);
                    *hit = Hit {
                        t,
                        prim: block.prims[lane],
                        u,
                        v,
                    };
                    recorded = true;
                }
            }
        }
        if !watertight || !scene.spheres.is_empty() {
            for &prim in &block.prims {
                if prim != NO_HIT && !(watertight && prim < num_triangles) {
                    recorded |= self.record_hit(ray, shear, hit, prim);
                }
            }
        }
        recorded
    }

    /// Closest hit through the BVH, nearest child first; with `any_hit`, the
    /// first hit found. A ray that misses every box of the root stops there.
    /// The shader's loop, one `visit` per pass.
    #[inline(always)]
    pub fn trace_bvh(&self, ray: Ray, shear: &Shear, any_hit: bool) -> Hit {
        let mut traversal = Traversal::new(ray, *shear, any_hit);
        let mut stack = new_stack();
        // SAFETY: every pass gets this traversal's own stack.
        while unsafe { self.visit::<false, false>(&mut traversal, &mut stack) } {}
        traversal.hit
    }

    /// The shader's `trace_compressed`: closest hit through the GPU's
    /// compressed nodes (`nodes`, the scene's BVH compressed), children in
    /// octant order, each pass the blocks of the last node visited and then
    /// one node, a node group (child_base and its masks) per stack entry;
    /// with `any_hit`, the first hit found.
    pub fn trace_compressed(
        &self,
        nodes: &[CompressedNode],
        ray_in: Ray,
        shear: &Shear,
        any_hit: bool,
    ) -> Hit {
        let mut ray = ray_in;
        let mut hit = miss();
        let Some(root) = nodes.first() else {
            return hit;
        };
        let blocks = &self.scene.bvh.blocks;
        let slabs = ray_slabs(&ray);
        let octant = ray_octant(&slabs);
        let mut stack = GroupStack::new(self.stack_entries);
        let mut sp = 0;
        let (entered, mut leaf_blocks) = intersect_compressed_node(&ray, &slabs, root, octant);
        let mut group = (root.child_base, entered);
        let mut block_base = root.block_base;
        loop {
            while leaf_blocks != 0 {
                let i = leaf_blocks.trailing_zeros();
                leaf_blocks &= leaf_blocks - 1;
                let block = &blocks[(block_base + i) as usize];
                if self.record_block_hits(&mut ray, shear, &mut hit, block) && any_hit {
                    return hit;
                }
            }
            if group.1 & 0xff == 0 {
                if sp == 0 {
                    break;
                }
                sp -= 1;
                group = stack.pop_group(sp);
            }
            let next_bit = (group.1 & 0xff).trailing_zeros();
            let slot = next_bit ^ octant;
            group.1 &= !(1 << next_bit);
            if group.1 & 0xff != 0 {
                stack.push_group(sp, group);
                sp += 1;
            }
            let below = (group.1 >> 8) & ((1 << slot) - 1);
            let node = &nodes[(group.0 + below.count_ones()) as usize];
            let (entered, next_blocks) = intersect_compressed_node(&ray, &slabs, node, octant);
            group = (node.child_base, entered);
            leaf_blocks = next_blocks;
            block_base = node.block_base;
        }
        hit
    }

    /// One pass of `trace_bvh`'s loop: visits the traversal's current node or
    /// leaf and picks the next (with `PREFETCH`, and starts loading it).
    /// With `VECTOR_SORT`, entered children are ordered by `push_sorted_zmm`,
    /// without the branches (on how many, and on their order) that
    /// mispredict on rays of random directions. Returns false when the
    /// traversal is done (its `hit` is then the answer).
    ///
    /// # Safety
    /// `stack` must be the one that every earlier pass of this traversal
    /// used: it reads the entries they pushed. With `VECTOR_SORT`, the CPU
    /// must have AVX-512 (`has_vector_sort`).
    #[inline(always)]
    pub(crate) unsafe fn visit<const PREFETCH: bool, const VECTOR_SORT: bool>(
        &self,
        traversal: &mut Traversal,
        stack: &mut TraversalStack,
    ) -> bool {
        let bvh = &self.scene.bvh;
        let Traversal {
            ray,
            hit,
            slabs,
            shear,
            any_hit,
            sp,
            child,
            hit_block,
        } = traversal;
        if *child & LEAF_BIT != 0 {
            let (first, count) = leaf_range(*child);
            for (b, block) in (first..).zip(&bvh.blocks[first as usize..(first + count) as usize]) {
                if self.record_block_hits(ray, shear, hit, block) {
                    *hit_block = b;
                    if *any_hit {
                        return false;
                    }
                }
            }
        } else {
            let node = &bvh.nodes[*child as usize];
            let boxes = if self.ymm_boxes {
                // SAFETY: `ymm_boxes` says the CPU has what it needs.
                unsafe { intersect_boxes_ymm(ray, slabs, node) }
            } else {
                intersect_boxes(ray, slabs, node)
            };
            let mut entered = boxes.entered & node.occupied;
            if VECTOR_SORT && entered != 0 {
                // However many children: no branch on their count either.
                // SAFETY: the caller vouches for AVX-512.
                *child = unsafe { push_sorted_zmm(stack, sp, &boxes.t, &node.children, entered) };
                self.prefetch::<PREFETCH>(*child);
                return true;
            }
            if entered != 0 {
                // The lowest entered slot.
                let first = entered.trailing_zeros() as usize;
                entered &= entered - 1;
                if entered == 0 {
                    // One child entered: visit it, nothing to push.
                    *child = node.children[first];
                    self.prefetch::<PREFETCH>(*child);
                    return true;
                }
                let t = boxes.t;
                let second = entered.trailing_zeros() as usize;
                entered &= entered - 1;
                if entered == 0 {
                    // Two: push the farther, visit the nearer (the second on
                    // a tie, as the sort below orders them), with no round
                    // trip through the stack.
                    let (near, far) = if t[first] < t[second] {
                        (first, second)
                    } else {
                        (second, first)
                    };
                    stack[*sp].write((node.children[far], t[far]));
                    *sp += 1;
                    *child = node.children[near];
                    self.prefetch::<PREFETCH>(*child);
                    return true;
                }
                // More: push them sorted, farthest deepest, then visit the
                // nearest at once.
                let all = boxes.entered & node.occupied;
                *child = push_sorted(stack, sp, &t, &node.children, all);
                self.prefetch::<PREFETCH>(*child);
                return true;
            }
        }
        // Then the nearest pushed entry that a hit found since has not put
        // out of reach.
        while *sp > 0 {
            *sp -= 1;
            // SAFETY: entries below `sp` are written.
            let (next, t_next) = unsafe { stack[*sp].assume_init() };
            if t_next < ray.tmax {
                *child = next;
                self.prefetch::<PREFETCH>(*child);
                return true;
            }
        }
        false
    }

    /// With `PREFETCH`, asks the CPU to start loading what the traversal
    /// visits next, so that the load overlaps the other interleaved rays'
    /// work.
    #[inline(always)]
    fn prefetch<const PREFETCH: bool>(&self, child: u32) {
        if !PREFETCH {
            return;
        }
        let bvh = &self.scene.bvh;
        if child & LEAF_BIT != 0 {
            let (first, _) = leaf_range(child);
            super::prefetch(bvh.blocks.as_ptr().wrapping_add(first as usize));
        } else {
            super::prefetch(bvh.nodes.as_ptr().wrapping_add(child as usize));
        }
    }

    /// Every primitive in turn: the reference the BVH is tested against.
    #[inline(always)]
    pub fn trace_brute_force(&self, ray_in: Ray, shear: &Shear, any_hit: bool) -> Hit {
        let mut ray = ray_in;
        let mut hit = miss();
        for prim in 0..self.scene.primitive_count() as u32 {
            if self.record_hit(&mut ray, shear, &mut hit, prim) && any_hit {
                return hit;
            }
        }
        hit
    }

    #[inline(always)]
    pub fn trace(&self, ray_in: Ray, any_hit: bool) -> Hit {
        let (ray, shear) = prepare_ray(ray_in);
        let hit = match (self.scene.accel, self.compressed) {
            (Accel::Bvh, Some(nodes)) => self.trace_compressed(nodes, ray, &shear, any_hit),
            (Accel::Bvh, None) => self.trace_bvh(ray, &shear, any_hit),
            (Accel::BruteForce, _) => self.trace_brute_force(ray, &shear, any_hit),
        };
        unscale(hit, &shear)
    }

    /// Inlined, as `trace` is, so that inside `cpu::with_simd` (where
    /// rendering calls it) the traversal runs with the vector instructions.
    #[inline(always)]
    pub fn trace_closest(&self, ray: Ray) -> Hit {
        self.trace(ray, false)
    }

    /// Any hit in (tmin, tmax): stops at the first blocker.
    #[inline(always)]
    pub fn trace_any(&self, ray: Ray) -> bool {
        self.trace(ray, true).prim != NO_HIT
    }

    pub fn surface_at(&self, ray: &Ray, hit: &Hit) -> Surface {
        let scene = self.scene;
        let num_triangles = scene.triangles.len() as u32;
        if hit.prim < num_triangles {
            let tri = &scene.triangles[hit.prim as usize];
            let (v0, v1, v2) = (vec3(tri.v0), vec3(tri.v1), vec3(tri.v2));
            let w = 1.0 - hit.u - hit.v;
            let position = w * v0 + hit.u * v1 + hit.v * v2;
            let error = self_hit_bound(v0.abs().max(v1.abs()).max(v2.abs()));
            let geometric = face_forward((v1 - v0).cross(v2 - v0).normalize(), ray.dir);
            let mut shading = geometric;
            if tri.flags & FLAG_SMOOTH != 0 {
                let ns = &scene.normals[hit.prim as usize];
                let corner = |n: [f32; 4]| Vec3::new(n[0] as Real, n[1] as Real, n[2] as Real);
                let interpolated =
                    w * corner(ns.n0) + hit.u * corner(ns.n1) + hit.v * corner(ns.n2);
                if interpolated.dot(interpolated) > 0.0 {
                    shading = face_forward(interpolated.normalize(), ray.dir);
                }
            }
            return Surface {
                position,
                error,
                geometric_normal: geometric,
                shading_normal: shading,
                albedo: vec3(scene.materials[tri.material as usize].albedo),
            };
        }
        let sphere = &scene.spheres[(hit.prim - num_triangles) as usize];
        let center = vec3(sphere.center);
        let outward = ((ray.origin - center) + hit.t * ray.dir).normalize();
        let position = center + (sphere.radius as Real) * outward;
        let error = self_hit_bound(center.abs() + sphere.radius as Real);
        let normal = face_forward(outward, ray.dir);
        Surface {
            position,
            error,
            geometric_normal: normal,
            shading_normal: normal,
            albedo: vec3(scene.materials[sphere.material as usize].albedo),
        }
    }

    /// Lambert: ambient·k + Σ k·E·max(0, n·l)·visible, linear RGB.
    #[inline(always)]
    pub fn shade(&self, ray: &Ray, hit: &Hit) -> Vec3 {
        if hit.prim == NO_HIT {
            return self.background;
        }
        let surface = self.surface_at(ray, hit);
        let mut color = self.ambient * surface.albedo;
        let origin = offset_ray_origin(surface.position, surface.error, surface.geometric_normal);
        for light in &self.scene.lights {
            let Some(sample) = light_sample(&surface, origin, light) else {
                continue;
            };
            if self.scene.shadows && self.trace_any(sample.shadow_ray) {
                continue;
            }
            color += surface.albedo * sample.irradiance * sample.cos_theta;
        }
        color
    }

    /// Position of sample `sample` in pixel (x, y): the centre when spp = 1,
    /// else a jittered point in its cell of the stratified grid.
    pub fn sample_position(&self, x: u32, y: u32, sample: u32) -> (Real, Real) {
        let scene = self.scene;
        if scene.spp == 1 {
            return (x as Real + 0.5, y as Real + 0.5);
        }
        let h = pcg_hash(x ^ pcg_hash(y ^ pcg_hash(sample ^ pcg_hash(scene.seed))));
        let (jx, jy) = (unit_float(h), unit_float(pcg_hash(h)));
        let strata_y = scene.spp / self.strata_x;
        let (cx, cy) = ((sample % self.strata_x) as Real, (sample / self.strata_x) as Real);
        (
            x as Real + (cx + jx) / self.strata_x as Real,
            y as Real + (cy + jy) / strata_y as Real,
        )
    }

    /// One pixel: the box-filtered mean of its samples, the primitive its
    /// first sample hit, and the variance of its mean luminance.
    #[inline(always)]
    pub fn render_pixel(&self, x: u32, y: u32) -> (Vec3, u32, Real) {
        let (sums, prim) = self.add_samples(x, y, 0..self.scene.spp, (Vec3::ZERO, 0.0));
        let (mean, variance) = self.pixel_mean(sums);
        (mean, prim, variance)
    }

    /// `samples` of the pixel added in turn to `sums` (colour, squared
    /// luminance), and what the first of them hit.
    pub fn add_samples(
        &self,
        x: u32,
        y: u32,
        samples: std::ops::Range<u32>,
        sums: (Vec3, Real),
    ) -> ((Vec3, Real), u32) {
        let luminance = Vec3::new(0.2126, 0.7152, 0.0722);
        let (mut sum, mut sum_squares) = sums;
        let mut first_prim = NO_HIT;
        let first = samples.start;
        for sample in samples {
            let (px, py) = self.sample_position(x, y, sample);
            let ray = self.camera_ray(px, py);
            let hit = self.trace_closest(ray);
            if sample == first {
                first_prim = hit.prim;
            }
            let color = self.shade(&ray, &hit);
            sum += color;
            let l = color.dot(luminance);
            sum_squares += l * l;
        }
        ((sum, sum_squares), first_prim)
    }

    /// The pixel's mean and the variance of its mean luminance, from the
    /// sums of all the scene's samples.
    pub fn pixel_mean(&self, (sum, sum_squares): (Vec3, Real)) -> (Vec3, Real) {
        let luminance = Vec3::new(0.2126, 0.7152, 0.0722);
        let spp = self.scene.spp;
        let n = spp as Real;
        let mean = sum / n;
        let l = mean.dot(luminance);
        let variance = if spp > 1 {
            (sum_squares - n * l * l).max(0.0) / ((n - 1.0) * n)
        } else {
            0.0
        };
        (mean, variance)
    }
}

/// `visit`'s ordering of three or more entered children (`entered`), as the
/// shader's `trace_bvh` does it: pushes them farthest deepest, lower slots
/// deeper among equal distances, then pops the nearest and returns it.
/// `push_sorted_zmm` gives the same order in vector registers, for any
/// number of children.
#[inline(always)]
pub(crate) fn push_sorted(
    stack: &mut TraversalStack,
    sp: &mut usize,
    t: &[Real; BVH_WIDTH],
    children: &[u32; BVH_WIDTH],
    mut entered: u32,
) -> u32 {
    let base = *sp;
    while entered != 0 {
        let slot = entered.trailing_zeros() as usize;
        entered &= entered - 1;
        let mut j = *sp;
        // SAFETY: entries below `sp` are written.
        while j > base && unsafe { stack[j - 1].assume_init().1 } < t[slot] {
            stack[j] = stack[j - 1];
            j -= 1;
        }
        stack[j].write((children[slot], t[slot]));
        *sp += 1;
    }
    *sp -= 1;
    // SAFETY: just written.
    unsafe { stack[*sp].assume_init().0 }
}

/// The lecture's test: plane hit t = n·(a − o)/(n·d), then three edge tests
/// that must all agree in sign. Returns (t, u, v); t = FAR on a miss.
pub fn intersect_triangle_seed(ray: &Ray, a: Vec3, b: Vec3, c: Vec3) -> (Real, Real, Real) {
    let n = (b - a).cross(c - a);
    let n_dot_d = n.dot(ray.dir);
    if n_dot_d == 0.0 {
        return NO_TRIANGLE_HIT;
    }
    let t = n.dot(a - ray.origin) / n_dot_d;
    if !(t > ray.tmin && t < ray.tmax) {
        return NO_TRIANGLE_HIT;
    }
    let p = ray.origin + t * ray.dir;
    let e0 = (b - a).cross(p - a).dot(n);
    let e1 = (c - b).cross(p - b).dot(n);
    let e2 = (a - c).cross(p - c).dot(n);
    let inside =
        (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
    if !inside {
        return NO_TRIANGLE_HIT;
    }
    let nn = n.dot(n);
    (t, e2 / nn, e0 / nn)
}

const NO_TRIANGLE_HIT: (Real, Real, Real) = (FAR, 0.0, 0.0);

/// Möller–Trumbore, with no epsilon on the determinant.
pub fn intersect_triangle_moller_trumbore(
    ray: &Ray,
    a: Vec3,
    b: Vec3,
    c: Vec3,
) -> (Real, Real, Real) {
    let e1 = b - a;
    let e2 = c - a;
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return NO_TRIANGLE_HIT;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - a;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return NO_TRIANGLE_HIT;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return NO_TRIANGLE_HIT;
    }
    let t = e2.dot(q) * inv_det;
    if !(t > ray.tmin && t < ray.tmax) {
        return NO_TRIANGLE_HIT;
    }
    (t, u, v)
}

#[inline(always)]
pub fn ray_shear(dir: Vec3) -> Shear {
    let m = dir.abs();
    let kz = if m.x >= m.y && m.x >= m.z {
        0
    } else if m.y >= m.z {
        1
    } else {
        2
    };
    let mut kx = (kz + 1) % 3;
    let mut ky = (kx + 1) % 3;
    // An array, not glam's Index: its match per access is a branch that
    // mispredicts on rays of random directions.
    let d = dir.to_array();
    if d[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    Shear {
        axes: [kx, ky, kz],
        s: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        t_scale: 1.0,
    }
}

/// Woop, Benthin and Wald (JCGT 2013), as in the shader: edge values of
/// exactly 0 count as inside.
#[inline(always)]
pub fn intersect_triangle_watertight(
    ray: &Ray,
    shear: &Shear,
    a: Vec3,
    b: Vec3,
    c: Vec3,
) -> (Real, Real, Real) {
    let [kx, ky, kz] = shear.axes;
    // Arrays, not glam's Index (a match per access): this is the hot loop.
    let oa = (a - ray.origin).to_array();
    let ob = (b - ray.origin).to_array();
    let oc = (c - ray.origin).to_array();
    let ax = oa[kx] - shear.s.x * oa[kz];
    let ay = oa[ky] - shear.s.y * oa[kz];
    let bx = ob[kx] - shear.s.x * ob[kz];
    let by = ob[ky] - shear.s.y * ob[kz];
    let cx = oc[kx] - shear.s.x * oc[kz];
    let cy = oc[ky] - shear.s.y * oc[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return NO_TRIANGLE_HIT;
    }
    let det = u + v + w;
    if det == 0.0 {
        return NO_TRIANGLE_HIT;
    }
    let t_scaled = u * shear.s.z * oa[kz] + v * shear.s.z * ob[kz] + w * shear.s.z * oc[kz];
    let t = t_scaled / det;
    if !(t > ray.tmin && t < ray.tmax) {
        return NO_TRIANGLE_HIT;
    }
    (t, v / det, w / det)
}

/// A leaf block's four lanes after `intersect_triangle_block`: t per lane
/// (FAR where it misses), and what u and v are divided from, since only a
/// recorded hit needs them.
#[derive(Clone, Copy, Debug)]
pub struct BlockHits {
    pub t: Vec4,
    v: Vec4,
    w: Vec4,
    det: Vec4,
}

impl BlockHits {
    /// (u, v) of lane `lane`, as `intersect_triangle_watertight` gives them.
    #[inline(always)]
    pub fn uv(&self, lane: usize) -> (Real, Real) {
        let det = self.det.to_array()[lane];
        (self.v.to_array()[lane] / det, self.w.to_array()[lane] / det)
    }
}

/// `intersect_triangle_watertight` on a block's four lanes at once, the
/// same operations in the same order in each: t per lane, FAR where a lane
/// misses (unfused arithmetic, as here, always misses a lane of zero
/// vertices; `record_block_hits` looks only at triangle lanes).
#[inline(always)]
pub fn intersect_triangle_block(ray: &Ray, shear: &Shear, block: &PrimBlock) -> BlockHits {
    let [kx, ky, kz] = shear.axes;
    let origin = ray.origin.to_array();
    // Coordinate a of vertex k relative to the origin.
    let rel = |k: usize, a: usize| vec4(block.v[k][a]) - Vec4::splat(origin[a]);
    let (sx, sy, sz) = (
        Vec4::splat(shear.s.x),
        Vec4::splat(shear.s.y),
        Vec4::splat(shear.s.z),
    );
    let (az, bz, cz) = (rel(0, kz), rel(1, kz), rel(2, kz));
    let ax = rel(0, kx) - sx * az;
    let ay = rel(0, ky) - sy * az;
    let bx = rel(1, kx) - sx * bz;
    let by = rel(1, ky) - sy * bz;
    let cx = rel(2, kx) - sx * cz;
    let cy = rel(2, ky) - sy * cz;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = Vec4::ZERO;
    let outside = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero))
        & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
    let det = u + v + w;
    let t = (u * sz * az + v * sz * bz + w * sz * cz) / det;
    let hit = !outside
        & det.cmpne(zero)
        & t.cmpgt(Vec4::splat(ray.tmin))
        & t.cmplt(Vec4::splat(ray.tmax));
    BlockHits {
        t: Vec4::select(hit, t, Vec4::splat(FAR)),
        v,
        w,
        det,
    }
}

/// Nearest root of |o + t·d − c|² = r² inside (tmin, tmax); FAR on a miss.
/// The stable form of Ray Tracing Gems ch. 7: the discriminant from the
/// ray's distance to the centre (|f|², not b² − ac), the near root as c/q,
/// and c itself exactly enough (`sphere_gap`) that a ray five units from a
/// sphere of radius 1e6 gets t to 1e-5.
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: Real) -> Real {
    let oc = ray.origin - center;
    let a = ray.dir.dot(ray.dir);
    let b = oc.dot(ray.dir);
    let c = sphere_gap(ray.origin, center, radius);
    let f = oc - (b / a) * ray.dir;
    let discriminant = a * (radius * radius - f.dot(f));
    if discriminant < 0.0 {
        return FAR;
    }
    let q = -b - sign_nonzero(b) * discriminant.sqrt();
    let t0 = c / q;
    let t1 = q / a;
    let near = t0.min(t1);
    let far = t0.max(t1);
    if near > ray.tmin && near < ray.tmax {
        return near;
    }
    if far > ray.tmin && far < ray.tmax {
        return far;
    }
    FAR
}

/// What the slab test needs of a ray, computed once per ray (`ray_slabs`):
/// per axis, the reciprocal direction (widened by the slack for exit
/// distances), the offsets that make a plane's distance one multiply-add,
/// and which of the two planes the ray meets first.
#[derive(Clone, Copy, Debug)]
pub struct Slabs {
    inv_dir: [Real; 3],
    inv_dir_far: [Real; 3],
    /// −origin·inv_dir (or ·inv_dir_far), moved down (near) or up (far) by
    /// more than the rounding of that product, of this sum and of an
    /// unfused multiply-add (WGSL's fma may be either): a plane's distance
    /// `plane·inv_dir + offset` then errs only by rounding relative to
    /// itself, which the slack covers for exit distances.
    near_offset: [Real; 3],
    far_offset: [Real; 3],
    /// Whether the ray runs toward −axis: its near plane is the maximum.
    flip: [bool; 3],
}

/// Direction components smaller than this count as this, with their sign,
/// in the slab test (as in Embree): their reciprocals stay finite, so the
/// offsets do (no ∞ − ∞), and a ray parallel to an axis has huge slab
/// distances of the right signs, or one near 0 for a plane that holds its
/// origin.
const MIN_SLAB_DIR: Real = 1e-18;

/// The ray's `Slabs`, as in the shader.
#[inline(always)]
pub fn ray_slabs(ray: &Ray) -> Slabs {
    let dir = ray.dir.to_array().map(|d| {
        if d.abs() < MIN_SLAB_DIR {
            MIN_SLAB_DIR.copysign(d)
        } else {
            d
        }
    });
    let inv_dir = Vec3::from_array(dir).recip();
    let inv_dir_far = inv_dir * BOX_SLACK;
    let near = -ray.origin * inv_dir;
    let far = -ray.origin * inv_dir_far;
    let margin = 8.0 * MACHINE_EPSILON;
    Slabs {
        inv_dir: inv_dir.to_array(),
        inv_dir_far: inv_dir_far.to_array(),
        near_offset: (near - near.abs() * margin).to_array(),
        far_offset: (far + far.abs() * margin).to_array(),
        flip: dir.map(|d| d < 0.0),
    }
}

/// A node's child boxes after `intersect_boxes`.
#[derive(Clone, Copy, Debug)]
pub struct BoxHits {
    /// Where the ray enters each box (meaningful for entered ones only).
    pub t: [Real; BVH_WIDTH],
    /// Bit i set: the ray enters box i within (tmin, tmax).
    pub entered: u32,
}

/// Where the ray enters and leaves four boxes, within (tmin, tmax), their
/// planes given by row: `row(2a)` the minima along axis a, `row(2a + 1)`
/// the maxima. Each plane's distance is one fused multiply-add; a NaN slab
/// (from a NaN ray) is ignored as in the shader: `greater_of`/`lesser_of`
/// keep the running bound when the comparison fails.
#[inline(always)]
fn slab_interval(ray: &Ray, slabs: &Slabs, row: impl Fn(usize) -> Vec4) -> (Vec4, Vec4) {
    let mut t_near = Vec4::splat(ray.tmin);
    let mut t_far = Vec4::splat(ray.tmax);
    for axis in 0..3 {
        let flip = slabs.flip[axis] as usize;
        let near = row(2 * axis + flip).mul_add(
            Vec4::splat(slabs.inv_dir[axis]),
            Vec4::splat(slabs.near_offset[axis]),
        );
        let far = row(2 * axis + 1 - flip).mul_add(
            Vec4::splat(slabs.inv_dir_far[axis]),
            Vec4::splat(slabs.far_offset[axis]),
        );
        t_near = greater_of(near, t_near);
        t_far = lesser_of(far, t_far);
    }
    (t_near, t_far)
}

/// Which of the node's eight child boxes the ray enters within (tmin, tmax),
/// and where (an empty slot's inverted box is never entered unless the ray
/// has a NaN or infinite component: traversal masks empty slots). Each
/// plane's distance is one fused multiply-add. A NaN slab (from a NaN ray)
/// is ignored as in the shader: `greater_of`/`lesser_of` keep the running
/// bound when the comparison fails. Two 4-lane halves, as in the shader;
/// `intersect_boxes_ymm` (x86 with AVX2) does the same in one register.
#[inline(always)]
pub fn intersect_boxes(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
    let mut t = [0.0; BVH_WIDTH];
    let mut entered = 0;
    for half in 0..2 {
        let row = |r: usize| vec4(node.bounds[r][4 * half..4 * half + 4].try_into().unwrap());
        let (t_near, t_far) = slab_interval(ray, slabs, row);
        // Two comparisons side by side rather than one on a select of
        // t_near: this is the critical path of a node visit.
        let inside = t_near.cmple(t_far) & t_near.cmplt(Vec4::splat(ray.tmax));
        entered |= inside.bitmask() << (4 * half);
        t[4 * half..4 * half + 4].copy_from_slice(&t_near.to_array());
    }
    BoxHits { t, entered }
}

/// Bit a set when the ray runs toward −a, as in the shader: a compressed
/// node's slots taken in the order b ^ octant (b = 0, 1, …) come nearest
/// first.
#[inline(always)]
pub fn ray_octant(slabs: &Slabs) -> u32 {
    slabs.flip[0] as u32 | (slabs.flip[1] as u32) << 1 | (slabs.flip[2] as u32) << 2
}

/// The four bytes of a word, low first, as numbers.
fn slot_bytes(word: u32) -> Vec4 {
    Vec4::from_array(std::array::from_fn(|i| (word >> (8 * i) & 0xff) as Real))
}

/// Which children of a compressed node the ray enters within (tmin, tmax),
/// as in the shader: its interior children as bits in visit order (bit b
/// for slot b ^ octant) with every interior slot in bits 8–15, and the blocks of its leaves as bits from
/// `block_base`. The planes are dequantised (exactly), then
/// `intersect_boxes`'s slab test.
pub fn intersect_compressed_node(
    ray: &Ray,
    slabs: &Slabs,
    node: &CompressedNode,
    octant: u32,
) -> (u32, u32) {
    let (mut interior, mut blocks) = (0, 0);
    for half in 0..2 {
        // Row r's planes, dequantised (exactly): axis r / 2.
        let plane = |r: usize| {
            let (scale, origin) = (node.scale(r / 2) as Real, node.origin[r / 2] as Real);
            slot_bytes(node.q[r][half]).mul_add(Vec4::splat(scale), Vec4::splat(origin))
        };
        let (t_near, t_far) = slab_interval(ray, slabs, plane);
        let inside = t_near.cmple(t_far) & t_near.cmplt(Vec4::splat(ray.tmax));
        for lane in 0..4 {
            let slot = 4 * half + lane;
            let m = CompressedNode::byte(node.child_meta, slot);
            // Every interior slot, entered or not, in bits 8–15: a slot's
            // rank among its siblings is the count below it.
            if m != 0 && m & META_LEAF == 0 {
                interior |= 1 << (slot + 8);
            }
            if inside.bitmask() >> lane & 1 == 0 || m == 0 {
                continue;
            }
            if m & META_LEAF == 0 {
                interior |= 1 << (slot as u32 ^ octant);
            } else {
                blocks |= ((1 << ((m >> 4 & 7) + 1)) - 1) << (m & 0xf);
            }
        }
    }
    (interior, blocks)
}

/// |o − c|² − r², to a few units in the last place of the result rather
/// than of |o − c|²: near a large sphere the two squares agree in most of
/// their digits (radius 1e6, five units off: 1e12 against a gap of 1e7),
/// so each difference, square and sum keeps its rounding error
/// (`two_sum`, `two_square`), and the errors are added back at the end.
fn sphere_gap(origin: Vec3, center: Vec3, radius: Real) -> Real {
    let (x, ex) = two_sum(origin.x, -center.x);
    let (y, ey) = two_sum(origin.y, -center.y);
    let (z, ez) = two_sum(origin.z, -center.z);
    let (xx, exx) = two_square(x);
    let (yy, eyy) = two_square(y);
    let (zz, ezz) = two_square(z);
    let (rr, err) = two_square(radius);
    let (s1, e1) = two_sum(xx, yy);
    let (s2, e2) = two_sum(s1, zz);
    let (s3, e3) = two_sum(s2, -rr);
    // (x + ex)² = x² + 2·x·ex + ex²; ex² is below every other error here.
    let cross = 2.0 * (x * ex + y * ey + z * ez);
    s3 + (((e1 + e2) + e3) + (((exx + eyy) + ezz) - err) + cross)
}

/// a + b as the rounded sum and its rounding error (Knuth's TwoSum: exact
/// without branches, whichever is larger). The shader's takes the sum
/// through `opaque_one` (1), lest a GPU compiler fold the error to 0.
fn two_sum(a: Real, b: Real) -> (Real, Real) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// a² as the rounded square and its rounding error (Dekker): each product
/// of halves is exact, so a fused multiply-add, which WGSL may or may not
/// use, gives the same bits.
fn two_square(a: Real) -> (Real, Real) {
    let hi = high_half(a);
    let lo = a - hi;
    let p = a * a;
    (p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo)
}

fn sign_nonzero(x: Real) -> Real {
    if x < 0.0 { -1.0 } else { 1.0 }
}

fn face_forward(n: Vec3, dir: Vec3) -> Vec3 {
    if n.dot(dir) > 0.0 { -n } else { n }
}

fn gamma(n: Real) -> Real {
    n * MACHINE_EPSILON / (1.0 - n * MACHINE_EPSILON)
}

/// How far a point on a primitive whose coordinates reach `extent` may be
/// off it, with the margin our intersection tests need to see a ray leaving
/// it as clear: 32 ULPs of the largest coordinate (see the shader).
fn self_hit_bound(extent: Vec3) -> Vec3 {
    Vec3::splat(gamma(32.0) * extent.max_element())
}

/// The next float away from `x` in the direction of `towards`'s sign.
fn next_float(x: Real, towards: Real) -> Real {
    if towards > 0.0 { x.next_up() } else { x.next_down() }
}

/// pbrt-v4's OffsetRayOrigin: move p off its surface along n by the
/// projection of its error bound onto n, then one ULP further per axis.
pub fn offset_ray_origin(p: Vec3, error: Vec3, n: Vec3) -> Vec3 {
    let d = n.abs().dot(error);
    let offset = d * n;
    let mut po = p + offset;
    for axis in 0..3 {
        if offset[axis] != 0.0 {
            po[axis] = next_float(po[axis], offset[axis]);
        }
    }
    po
}

/// PCG hash (Jarzynski and Olano, JCGT 2020), as in the shader.
pub fn pcg_hash(x: u32) -> u32 {
    let state = x.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// A uniform number in [0, 1) from the top 24 bits of `h`.
fn unit_float(h: u32) -> Real {
    (h >> 8) as Real * (1.0 / 16777216.0)
}
