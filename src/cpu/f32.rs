//! Single precision, as on the GPU: the kernel (`kernel!`, kernel.rs)
//! with `Real = f32`, and its `Scalar` (src/cpu/precision.rs): the
//! NaN-ignoring selects in SSE, and on x86 the vector variants of the slab
//! test and of the ordering of entered children. Nothing else is defined
//! here (tests/architecture_rules.rs checks it): the stages take what
//! differs by precision from the trait alone.

super::kernel::kernel!(f32);

impl Scalar for Real {
    /// In one instruction where SSE's maxps and minps give exactly the
    /// shader's select (their second operand unless the comparison
    /// holds).
    #[inline(always)]
    fn greater_of(a: Vec4, b: Vec4) -> Vec4 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86_64.
        return Vec4::from(unsafe { std::arch::x86_64::_mm_max_ps(a.into(), b.into()) });
        #[cfg(not(target_arch = "x86_64"))]
        return Vec4::select(a.cmpgt(b), a, b);
    }

    #[inline(always)]
    fn lesser_of(a: Vec4, b: Vec4) -> Vec4 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86_64.
        return Vec4::from(unsafe { std::arch::x86_64::_mm_min_ps(a.into(), b.into()) });
        #[cfg(not(target_arch = "x86_64"))]
        return Vec4::select(a.cmplt(b), a, b);
    }

    /// The low 12 of the 23 stored mantissa bits cleared: a 12-bit high
    /// half, and 12 bits of rest.
    #[inline(always)]
    fn high_half(x: Real) -> Real {
        Real::from_bits(x.to_bits() & 0xffff_f000)
    }

    #[cfg(target_arch = "x86_64")]
    type Wide = crate::cpu::lanes::Ymm;
    #[cfg(not(target_arch = "x86_64"))]
    type Wide = crate::cpu::lanes::Pair<Vec4>;

    fn has_wide(kernel: super::CpuKernel) -> bool {
        cfg!(not(target_arch = "x86_64")) || kernel.ymm_boxes()
    }

    #[inline(always)]
    unsafe fn wide_vertices(low: &PrimBlock, high: &PrimBlock) -> [[Self::Wide; 3]; 3] {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the caller vouches for the kernel, which has AVX.
        return std::array::from_fn(|i| {
            std::array::from_fn(|k| unsafe {
                crate::cpu::lanes::Ymm::join(&low.v[i][k], &high.v[i][k])
            })
        });
        #[cfg(not(target_arch = "x86_64"))]
        return std::array::from_fn(|i| {
            std::array::from_fn(|k| crate::cpu::lanes::Pair(vec4(low.v[i][k]), vec4(high.v[i][k])))
        });
    }

    fn has_ymm_boxes() -> bool {
        super::CpuKernel::active().ymm_boxes()
    }

    /// Each row of eight planes in one AVX register: maxps and minps are
    /// `greater_of` and `lesser_of`, so the same result in half the
    /// instructions of two 4-lane halves.
    ///
    /// Inlined into `with_simd`'s kernels, which every entry point of the
    /// CPU path runs in. (Compiled for its own features instead, it was 4%
    /// slower there; a caller outside them, as tests are, runs each
    /// intrinsic as a call: the same result, slowly.)
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn intersect_boxes_ymm(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
        use std::arch::x86_64::*;
        // SAFETY: the caller vouches for AVX and FMA; a node is 64-byte
        // aligned, so each 32-byte row is too.
        unsafe {
            let mut t_near = _mm256_set1_ps(ray.tmin);
            let mut t_far = _mm256_set1_ps(ray.tmax);
            for axis in 0..3 {
                let flip = slabs.flip[axis] as usize;
                let near_plane = _mm256_load_ps(node.bounds[2 * axis + flip].as_ptr());
                let far_plane = _mm256_load_ps(node.bounds[2 * axis + 1 - flip].as_ptr());
                let near = _mm256_fmadd_ps(
                    near_plane,
                    _mm256_set1_ps(slabs.inv_dir[axis]),
                    _mm256_set1_ps(slabs.near_offset[axis]),
                );
                let far = _mm256_fmadd_ps(
                    far_plane,
                    _mm256_set1_ps(slabs.inv_dir_far[axis]),
                    _mm256_set1_ps(slabs.far_offset[axis]),
                );
                t_near = _mm256_max_ps(near, t_near);
                t_far = _mm256_min_ps(far, t_far);
            }
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t_near, _mm256_set1_ps(ray.tmax)),
            );
            let mut t = [0.0; BVH_WIDTH];
            _mm256_storeu_ps(t.as_mut_ptr(), t_near);
            BoxHits {
                t,
                entered: _mm256_movemask_ps(inside) as u32,
            }
        }
    }

    fn has_vector_sort() -> bool {
        super::CpuKernel::active().vector_sort()
    }

    /// In vector registers and without the data-dependent branches of
    /// `visit` and `push_sorted`, which on incoherent rays mispredict about
    /// as often as not. Pushes the entered children farthest deepest, lower
    /// slots deeper among equal distances (exactly the order of `visit`:
    /// with two, the nearer, the second on a tie, is visited; with more,
    /// `push_sorted`'s), pops the nearest and returns it.
    ///
    /// Each child's depth on the stack is the number of entered children
    /// whose key (distance, then slot) is greater than its own, counted in
    /// one register of eight 64-bit keys against its seven rotations; one
    /// masked scatter then writes every entry at its depth.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn push_sorted_zmm(
        stack: &mut TraversalStack,
        sp: &mut usize,
        t: &[Real; BVH_WIDTH],
        children: &[u32; BVH_WIDTH],
        entered: u32,
    ) -> u32 {
        use std::arch::x86_64::*;
        type Entry = (u32, Real);
        // Where a stack entry's two halves are, as shifts within a 64-bit
        // lane (a tuple's layout is the compiler's choice).
        const CHILD_SHIFT: u64 = 8 * std::mem::offset_of!(Entry, 0) as u64;
        const T_SHIFT: u64 = 8 * std::mem::offset_of!(Entry, 1) as u64;
        const { assert!(std::mem::size_of::<Entry>() == 8) };
        let count = entered.count_ones() as usize;
        // The insertion's bounds checks, in one.
        assert!(*sp + count <= STACK_SIZE);
        let lanes = entered as __mmask8;
        // SAFETY: the caller vouches for AVX-512; the scatter writes entries
        // sp..sp + count, inside the stack (asserted).
        unsafe {
            let t_bits = _mm256_loadu_si256(t.as_ptr().cast());
            // Distances as unsigned integers in the same order: −0 made +0
            // (they compare equal), then all bits of a negative float
            // flipped, only the sign bit of a positive one.
            let canonical = _mm256_castps_si256(_mm256_add_ps(
                _mm256_castsi256_ps(t_bits),
                _mm256_setzero_ps(),
            ));
            let flip = _mm256_or_si256(
                _mm256_srai_epi32::<31>(canonical),
                _mm256_set1_epi32(i32::MIN),
            );
            let ordered = _mm256_xor_si256(canonical, flip);
            // Key: distance above, 7 − slot below (lower slots deeper on a
            // tie); 0 in lanes not entered, below every entered key.
            let keys = _mm512_maskz_or_epi64(
                lanes,
                _mm512_slli_epi64::<32>(_mm512_cvtepu32_epi64(ordered)),
                _mm512_set_epi64(0, 1, 2, 3, 4, 5, 6, 7),
            );
            let one = _mm512_set1_epi64(1);
            let mut depth = _mm512_setzero_si512();
            macro_rules! count_greater {
                ($($rotation:literal)*) => {$(
                    let rotated = _mm512_alignr_epi64::<$rotation>(keys, keys);
                    let greater = _mm512_cmpgt_epu64_mask(rotated, keys);
                    depth = _mm512_mask_add_epi64(depth, greater, depth, one);
                )*};
            }
            count_greater!(1 2 3 4 5 6 7);
            let entries = _mm512_or_si512(
                _mm512_sll_epi64(
                    _mm512_cvtepu32_epi64(_mm256_loadu_si256(children.as_ptr().cast())),
                    _mm_cvtsi64_si128(CHILD_SHIFT as i64),
                ),
                _mm512_sll_epi64(
                    _mm512_cvtepu32_epi64(t_bits),
                    _mm_cvtsi64_si128(T_SHIFT as i64),
                ),
            );
            _mm512_mask_i64scatter_epi64::<8>(
                stack.as_mut_ptr().add(*sp).cast(),
                lanes,
                depth,
                entries,
            );
            let nearest =
                _mm512_mask_cmpeq_epi64_mask(lanes, depth, _mm512_set1_epi64(count as i64 - 1));
            *sp += count - 1;
            children[nearest.trailing_zeros() as usize]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Real, Scalar, new_stack, push_sorted};
    use crate::layout::{BVH_WIDTH, LEAF_BIT};

    /// `push_sorted_zmm` pushes exactly what the insertion pushes, in the
    /// same order, and visits the same child, for every set of entered
    /// children (with one or two, the insertion does what `visit`'s own
    /// cases do: visit the one; push the farther, visit the nearer, the
    /// second on a tie), with ties, ±0, negative and huge distances, above
    /// entries already pushed.
    #[test]
    fn vector_child_ordering_equals_the_insertion() {
        if let Some(missing) = crate::cpu::CpuKernel::Avx512.missing() {
            // Straight to stderr: the harness would hide eprintln! of a
            // passing test.
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "skipped: push_sorted_zmm needs {missing}, which this CPU lacks"
            );
            return;
        }
        // Few distinct values, so that ties are common.
        let values = [-1.0, -0.0, 0.0, 0.5, 1.0, 2.5, 1e30, f32::MAX];
        let children: [u32; BVH_WIDTH] = std::array::from_fn(|slot| {
            if slot % 3 == 0 {
                LEAF_BIT | slot as u32
            } else {
                40 + slot as u32
            }
        });
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut checked = 0;
        for entered in 0..1u32 << BVH_WIDTH {
            if entered == 0 {
                continue;
            }
            for _ in 0..64 {
                let t: [f32; BVH_WIDTH] =
                    std::array::from_fn(|_| values[next() as usize % values.len()]);
                let below = (next() % 5) as usize;
                let (mut scalar, mut vector) = (new_stack(), new_stack());
                for i in 0..below {
                    scalar[i].write((i as u32, i as f32));
                    vector[i].write((i as u32, i as f32));
                }
                let (mut sp_scalar, mut sp_vector) = (below, below);
                let nearest = push_sorted(&mut scalar, &mut sp_scalar, &t, &children, entered);
                // SAFETY: the CPU has AVX-512.
                let nearest_vector = unsafe {
                    <Real as Scalar>::push_sorted_zmm(
                        &mut vector,
                        &mut sp_vector,
                        &t,
                        &children,
                        entered,
                    )
                };
                assert_eq!(
                    (nearest_vector, sp_vector),
                    (nearest, sp_scalar),
                    "{t:?} {entered:#b}"
                );
                // Every entry up to the popped one, bit for bit.
                for i in 0..=sp_scalar {
                    // SAFETY: written by both (pushed, or the popped nearest).
                    let (a, b) = unsafe { (scalar[i].assume_init(), vector[i].assume_init()) };
                    assert_eq!(
                        (a.0, a.1.to_bits()),
                        (b.0, b.1.to_bits()),
                        "entry {i}: {t:?} {entered:#b}"
                    );
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 255 * 64);
    }
}
