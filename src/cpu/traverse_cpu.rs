//! The CPU's own traversal, with no GPU stage: the uncompressed BVH's nodes
//! (`intersect_boxes`), one node visit per pass (`visit`) so that a thread
//! can interleave rays, and the ordering of entered children. Written once
//! for both precisions: `kernel!` (kernel.rs) expands it into `cpu::f32` and
//! `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! traverse_cpu {
    () => {
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

            /// The traversal of `node`'s subtree alone, not the root's: where a
            /// packet's any-hit ray left the packet's order (packet.rs).
            #[inline(always)]
            #[allow(dead_code)] // the f32 packets' alone
            pub(crate) fn below(mut self, node: u32) -> Traversal {
                self.child = node;
                self
            }

            /// The hit found, its distance along the ray as given.
            #[inline(always)]
            #[allow(dead_code)] // the oracle traces through `Kernel::trace` alone
            pub(crate) fn answer(&self) -> Hit {
                unscale(self.hit, &self.shear)
            }
        }

        impl<'a> Kernel<'a> {
            /// Closest hit through the BVH, nearest child first; with `any_hit`, the
            /// first hit found. A ray that misses every box of the root stops there.
            /// The shader's loop, one `visit` per pass.
            #[inline(always)]
            pub fn trace_bvh(&self, ray: Ray, shear: &Shear, any_hit: bool) -> Hit {
                let mut traversal = Traversal::new(ray, *shear, any_hit);
                let mut stack = new_stack();
                // SAFETY: every pass gets this traversal's own stack.
                while unsafe {
                    self.visit::<false, false, ALL_FEATURES>(&mut traversal, &mut stack)
                } {}
                traversal.hit
            }

            /// One pass of `trace_bvh`'s loop: visits the traversal's current node or
            /// leaf and picks the next (with `PREFETCH`, and starts loading it).
            /// With `VECTOR_SORT`, entered children are ordered by `Scalar::push_sorted_zmm`,
            /// without the branches (on how many, and on their order) that
            /// mispredict on rays of random directions. Returns false when the
            /// traversal is done (its `hit` is then the answer). `FEATURES`:
            /// `Kernel::record_block_hits`', which must include the kernel's
            /// `features()` (a variant without a scene's feature misses it).
            ///
            /// # Safety
            /// `stack` must be the one that every earlier pass of this traversal
            /// used: it reads the entries they pushed. With `VECTOR_SORT`, the CPU
            /// must have AVX-512 (`Scalar::has_vector_sort`).
            #[inline(always)]
            pub(crate) unsafe fn visit<
                const PREFETCH: bool,
                const VECTOR_SORT: bool,
                const FEATURES: u8,
            >(
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
                    for (b, block) in
                        (first..).zip(&bvh.blocks[first as usize..(first + count) as usize])
                    {
                        if self.record_block_hits::<FEATURES>(ray, shear, hit, block) {
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
                        unsafe { <Real as Scalar>::intersect_boxes_ymm(ray, slabs, node) }
                    } else {
                        intersect_boxes(ray, slabs, node)
                    };
                    let mut entered = boxes.entered & node.occupied;
                    if VECTOR_SORT && entered != 0 {
                        // However many children: no branch on their count either.
                        // SAFETY: the caller vouches for AVX-512.
                        *child = unsafe {
                            <Real as Scalar>::push_sorted_zmm(
                                stack,
                                sp,
                                &boxes.t,
                                &node.children,
                                entered,
                            )
                        };
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
        }

        /// `visit`'s ordering of three or more entered children (`entered`), as the
        /// shader's `trace_bvh` does it: pushes them farthest deepest, lower slots
        /// deeper among equal distances, then pops the nearest and returns it.
        /// `Scalar::push_sorted_zmm` gives the same order in vector registers, for any
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

        /// A node's child boxes after `intersect_boxes`.
        #[derive(Clone, Copy, Debug)]
        pub struct BoxHits {
            /// Where the ray enters each box (meaningful for entered ones only).
            pub t: [Real; BVH_WIDTH],
            /// Bit i set: the ray enters box i within (tmin, tmax).
            pub entered: u32,
        }

        /// Which of the node's eight child boxes the ray enters within (tmin, tmax),
        /// and where (an empty slot's inverted box is never entered unless the ray
        /// has a NaN or infinite component: traversal masks empty slots). Each
        /// plane's distance is one fused multiply-add. A NaN slab (from a NaN ray)
        /// is ignored as in the shader: `Scalar::greater_of`/`lesser_of` keep the running
        /// bound when the comparison fails. Two 4-lane halves, as in the shader;
        /// `Scalar::intersect_boxes_ymm` (x86 with AVX2) does the same in one register.
        #[inline(always)]
        pub fn intersect_boxes(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
            let mut t = [0.0; BVH_WIDTH];
            let mut entered = 0;
            for half in 0..2 {
                let row =
                    |r: usize| vec4(node.bounds[r][4 * half..4 * half + 4].try_into().unwrap());
                let (t_near, t_far) = slab_interval(ray, slabs, row);
                // Two comparisons side by side rather than one on a select of
                // t_near: this is the critical path of a node visit.
                let inside = t_near.cmple(t_far) & t_near.cmplt(Vec4::splat(ray.tmax));
                entered |= inside.bitmask() << (4 * half);
                t[4 * half..4 * half + 4].copy_from_slice(&t_near.to_array());
            }
            BoxHits { t, entered }
        }
    };
}
pub(crate) use traverse_cpu;
