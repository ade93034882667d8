//! Where a packet's order of a node's children leaves a ray's own: the
//! any-hit packets' exactness check (`trace_packet`), and its variant in
//! 8-lane registers. The portable loop stayed scalar, a tenth of an
//! any-hit packet's instructions (callgrind, docs/benchmarks.md).

use super::{PACKET, f32};
use crate::layout::BVH_WIDTH;

/// A node's entered children in the packet's order: each child's slot,
/// with the rays that enter it above bit 8, and the bound it was ordered
/// by.
pub(super) type Order = [(u32, f32::Real)];

/// Where each ray enters each entered slot.
pub(super) type Entries = [std::mem::MaybeUninit<[f32::Real; PACKET]>; BVH_WIDTH];

/// For each of a node's entered children in the packet's `order`, the
/// rays that the packet takes into it before a sibling they enter first
/// alone: `Kernel::visit` visits a ray's children by its own entry
/// distance, the higher slot first on a tie. Before its first hit a ray
/// enters the same boxes in any order, so one that meets its first hit
/// where no child on its path was entered early meets its leaves with
/// hits in its own order: its first hit in the packet is its first alone.
#[inline(always)]
pub(super) fn out_of_order(order: &Order, entries: &Entries) -> [u32; BVH_WIDTH] {
    // The first, by each ray's own order, of the children after the one
    // at hand in the packet's.
    let mut first_t = [f32::Real::INFINITY; PACKET];
    let mut first_slot = [0u32; PACKET];
    let mut early = [0; BVH_WIDTH];
    for (k, &(key, _)) in order.iter().enumerate().rev() {
        let (slot, entered) = (key & 0xff, key >> 8);
        // SAFETY: written for every entered slot.
        let t = unsafe { entries[slot as usize].assume_init_ref() };
        // Without branches, so that the lanes vectorise.
        for r in 0..PACKET {
            let enters = entered >> r & 1 != 0;
            // A later child the ray alone takes first.
            let later_first = (first_t[r] < t[r]) | ((first_t[r] == t[r]) & (first_slot[r] > slot));
            early[k] |= ((enters & later_first) as u32) << r;
            let first = enters & !later_first;
            first_t[r] = if first { t[r] } else { first_t[r] };
            first_slot[r] = if first { slot } else { first_slot[r] };
        }
    }
    early
}

/// `out_of_order` with the packet's rays in one register (AVX2): the same
/// comparisons, lane by lane.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn out_of_order_ymm(order: &Order, entries: &Entries) -> [u32; BVH_WIDTH] {
    use std::arch::x86_64::*;
    const { assert!(PACKET == 8) };
    // SAFETY: the caller vouches for AVX2; the rows are read unaligned.
    unsafe {
        let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let mut first_t = _mm256_set1_ps(f32::Real::INFINITY);
        let mut first_slot = _mm256_setzero_si256();
        let mut early = [0; BVH_WIDTH];
        for (k, &(key, _)) in order.iter().enumerate().rev() {
            let (slot, entered) = (key & 0xff, key >> 8);
            // SAFETY: written for every entered slot.
            let t = _mm256_loadu_ps(entries[slot as usize].assume_init_ref().as_ptr());
            let enters = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                _mm256_and_si256(_mm256_set1_epi32(entered as i32), lane_bits),
                lane_bits,
            ));
            let slot = _mm256_set1_epi32(slot as i32);
            let later_first = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(first_t, t),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_EQ_OQ>(first_t, t),
                    _mm256_castsi256_ps(_mm256_cmpgt_epi32(first_slot, slot)),
                ),
            );
            early[k] = _mm256_movemask_ps(_mm256_and_ps(enters, later_first)) as u32;
            let first = _mm256_andnot_ps(later_first, enters);
            first_t = _mm256_blendv_ps(first_t, t, first);
            first_slot = _mm256_castps_si256(_mm256_blendv_ps(
                _mm256_castsi256_ps(first_slot),
                _mm256_castsi256_ps(slot),
                first,
            ));
        }
        early
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_order_ymm_gives_the_portable_masks() {
        #[cfg(target_arch = "x86_64")]
        {
            if !is_x86_feature_detected!("avx2") {
                eprintln!("skipped: no AVX2");
                return;
            }
            // Few distinct distances, so that ties are common; both zeros.
            let values = [-1.0, -0.0, 0.0, 0.5, 2.0, 1e-30, f32::FAR];
            let mut state = 0x9e37_79b9_u32;
            let mut next = || {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                state
            };
            let mut early_seen = 0;
            for _ in 0..20_000 {
                let n = 2 + next() as usize % (BVH_WIDTH - 1);
                let mut slots: Vec<u32> = (0..BVH_WIDTH as u32).collect();
                for i in (1..slots.len()).rev() {
                    slots.swap(i, next() as usize % (i + 1));
                }
                let mut entries: Entries = [std::mem::MaybeUninit::uninit(); BVH_WIDTH];
                let mut order = Vec::new();
                for &slot in &slots[..n] {
                    let t = std::array::from_fn(|_| values[next() as usize % values.len()]);
                    entries[slot as usize].write(t);
                    order.push((slot | (next() & 0xff) << 8, 0.0));
                }
                let portable = out_of_order(&order, &entries);
                // SAFETY: checked for AVX2 above.
                let vector = unsafe { out_of_order_ymm(&order, &entries) };
                assert_eq!(vector, portable, "{order:?}");
                early_seen += portable.iter().filter(|&&e| e != 0).count();
            }
            assert!(early_seen > 1000, "{early_seen} children entered early");
        }
    }
}
