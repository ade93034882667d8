//! How a ray query keeps memory loads in flight: how many rays a thread
//! traces in turn, and whether to prefetch, from the BVH's size and the
//! rays' coherence (query.rs's `coherent` judges it).

/// Starts loading the cache lines of the `T` at `p` (which may be out of
/// bounds: a prefetch never faults).
#[inline(always)]
pub(super) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    for line in (0..std::mem::size_of::<T>()).step_by(64) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: prefetching is a hint; it reads nothing.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>().wrapping_add(line)) };
    }
    // Stable Rust has a prefetch intrinsic on x86 only.
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Starts loading the cache lines of the `count` values from `first` on
/// (rows a thread will most likely read or write next, so that their
/// trips to memory overlap the work before). The pointer is never read
/// through, so it may point at memory another thread writes, or past the
/// end.
#[inline]
pub fn prefetch_rows<T>(first: *const T, count: usize) {
    let start = first.cast::<u8>();
    for line in (0..count * std::mem::size_of::<T>()).step_by(64) {
        prefetch(start.wrapping_add(line));
    }
}

/// Rays one thread traces together through the BVH, a node visit each in
/// turn, so that one ray's cache misses overlap the others' work. Each ray
/// takes exactly the path it takes alone. Two (docs/benchmarks.md): through
/// the dragon, incoherent rays gain 60% and camera rays 1–2% over one;
/// camera rays through a model that stays in cache lose 17%.
pub(super) const INTERLEAVED_RAYS: usize = 2;

/// Incoherent rays through a BVH larger than a core's cache wait on memory
/// at nearly every node. Eight in turn, each asking for its next node or
/// leaf as soon as it knows it (`Kernel::visit` with `PREFETCH`), keep
/// many loads in flight: the dragon's 1M random rays trace 1.3× faster
/// with prefetching (four rays either way) and about 1.13× faster again
/// with eight rays instead of four (twelve: +1–2%, noise). Coherent rays, or a
/// BVH that stays in cache, lose to the book-keeping: 3–4% for the
/// prefetches alone on the dragon's camera rays, 8% for both on
/// dragon_res4's random rays (docs/benchmarks.md).
pub(super) const INTERLEAVED_INCOHERENT_RAYS: usize = 8;

/// BVH nodes and blocks above this size count as larger than a core's cache
/// (L2 is 1–2 MiB a core on current x86 servers). Random rays with eight in
/// turn and prefetching, against two without (both ordering children in
/// vector registers): stanford_bunny's 3.8 MiB BVH gains 7–14%,
/// dragon_res3's 2.7 MiB loses up to 14%. Before that ordering:
/// dragon_res4's 0.6 MiB lost 8%, dragon_res2's 11 MiB gained 6–13%, the
/// dragon's 47 MiB 44%.
pub const LARGE_BVH_BYTES: usize = 3 << 20;
