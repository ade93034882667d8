//! Fetch, the twin of shaders/fetch.wgsl. The CPU reads each of the scene's
//! arrays whole (no split over two bindings, no textures), so only the
//! prefetch of what traversal visits next is here. Written once for both
//! precisions: `kernel!` (kernel.rs) expands it into `cpu::f32` and
//! `cpu::f64`, whose `Real`, `Vec3` and `Vec4` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! fetch {
    () => {
        impl<'a> Kernel<'a> {
            /// With `PREFETCH`, asks the CPU to start loading what the traversal
            /// visits next, so that the load overlaps the other interleaved rays'
            /// work.
            #[inline(always)]
            pub(crate) fn prefetch<const PREFETCH: bool>(&self, child: u32) {
                if !PREFETCH {
                    return;
                }
                let bvh = &self.scene.bvh;
                if child & LEAF_BIT != 0 {
                    let (first, _) = leaf_range(child);
                    super::prefetch::prefetch(bvh.blocks.as_ptr().wrapping_add(first as usize));
                } else {
                    super::prefetch::prefetch(bvh.nodes.as_ptr().wrapping_add(child as usize));
                }
            }
        }
    };
}
pub(crate) use fetch;
