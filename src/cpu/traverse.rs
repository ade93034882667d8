//! Traversal, the twin of shaders/traverse.wgsl: the slab test of a
//! compressed node, the group stack, the compressed BVH's traversal (what the
//! GPU runs), the brute-force reference, and `trace`, `trace_closest`,
//! `trace_any`. Written once for both precisions: `kernel!` (kernel.rs)
//! expands it into `cpu::f32` and `cpu::f64`, whose `Real`, `Vec3` and `Vec4`
//! it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! traverse {
    () => {
        /// `hit` (of a ray `prepare_ray` scaled) with its distance along the ray as
        /// given; a miss stays at FAR.
        #[inline(always)]
        pub(crate) fn unscale(hit: Hit, shear: &Shear) -> Hit {
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

        /// Whether any component of `v` is a NaN.
        #[inline(always)]
        pub fn has_nan(v: Vec3) -> bool {
            v.is_nan()
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

        impl<'a> Kernel<'a> {
            /// The shader's `trace_compressed`: closest hit through the GPU's
            /// compressed nodes (`nodes`, the scene's BVH compressed), children in
            /// octant order, in the shader's while-while form (the blocks of the
            /// last node visited, then nodes until one enters blocks: the same order
            /// as one loop doing a node a pass), a node group (child_base and its
            /// masks) per stack entry; with `any_hit`, the first hit found.
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
                let (entered, mut leaf_blocks) =
                    intersect_compressed_node(&ray, &slabs, root, octant);
                let mut group = (root.child_base, entered);
                let mut block_base = root.block_base;
                loop {
                    while leaf_blocks != 0 {
                        let i = leaf_blocks.trailing_zeros();
                        leaf_blocks &= leaf_blocks - 1;
                        let block = &blocks[(block_base + i) as usize];
                        if self.record_block_hits::<ALL_FEATURES>(&mut ray, shear, &mut hit, block)
                            && any_hit
                        {
                            return hit;
                        }
                    }
                    // Nodes until one enters blocks (the shader's inner loop).
                    loop {
                        if group.1 & 0xff == 0 {
                            if sp == 0 {
                                return hit;
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
                        let (entered, next_blocks) =
                            intersect_compressed_node(&ray, &slabs, node, octant);
                        group = (node.child_base, entered);
                        leaf_blocks = next_blocks;
                        block_base = node.block_base;
                        if leaf_blocks != 0 {
                            break;
                        }
                    }
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
                // As the shader: a NaN ray misses at once rather than entering
                // every box of the tree on its way to missing.
                if has_nan(ray_in.origin) || has_nan(ray_in.dir) || ray_in.tmin.is_nan() {
                    return miss();
                }
                let (ray, shear) = prepare_ray(ray_in);
                let hit = match (self.scene.accel.traverses_bvh(), self.compressed) {
                    (true, Some(nodes)) => self.trace_compressed(nodes, ray, &shear, any_hit),
                    (true, None) => self.trace_bvh(ray, &shear, any_hit),
                    (false, _) => self.trace_brute_force(ray, &shear, any_hit),
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
        }

        /// What the slab test needs of a ray, computed once per ray (`ray_slabs`):
        /// per axis, the reciprocal direction (widened by the slack for exit
        /// distances), the offsets that make a plane's distance one multiply-add,
        /// and which of the two planes the ray meets first.
        #[derive(Clone, Copy, Debug)]
        pub struct Slabs {
            pub(crate) inv_dir: [Real; 3],
            pub(crate) inv_dir_far: [Real; 3],
            /// −origin·inv_dir (or ·inv_dir_far), moved down (near) or up (far) by
            /// more than the rounding of that product, of this sum and of an
            /// unfused multiply-add (WGSL's fma may be either): a plane's distance
            /// `plane·inv_dir + offset` then errs only by rounding relative to
            /// itself, which the slack covers for exit distances.
            pub(crate) near_offset: [Real; 3],
            pub(crate) far_offset: [Real; 3],
            /// Whether the ray runs toward −axis: its near plane is the maximum.
            pub(crate) flip: [bool; 3],
        }

        /// Direction components smaller than this count as this, with their sign,
        /// in the slab test (as in Embree): their reciprocals stay finite, so the
        /// offsets do (no ∞ − ∞), and a ray parallel to an axis has huge slab
        /// distances of the right signs, or one near 0 for a plane that holds its
        /// origin.
        pub(crate) const MIN_SLAB_DIR: Real = 1e-18;

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

        /// Where the ray enters and leaves four boxes, within (tmin, tmax), their
        /// planes given by row: `row(2a)` the minima along axis a, `row(2a + 1)`
        /// the maxima. Each plane's distance is one fused multiply-add; a NaN slab
        /// (from a NaN ray) is ignored as in the shader: `Scalar::greater_of`/`lesser_of`
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
                t_near = <Real as Scalar>::greater_of(near, t_near);
                t_far = <Real as Scalar>::lesser_of(far, t_far);
            }
            (t_near, t_far)
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
    };
}
pub(crate) use traverse;
