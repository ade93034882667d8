//! `Packet::load` in 8-lane registers (AVX2): each lane the same IEEE
//! operations as the portable loops give its ray, so the same bits
//! (tests: `load_ymm_gives_the_portable_loads_bits` below, and
//! tests/cpu_packets.rs through the packets' hits). A packet's preparation
//! is a sixth of a camera ray's time through the dragon; LLVM left the
//! portable loops mostly scalar (docs/benchmarks.md).

use super::{PACKET, Packet, f32};
use crate::layout;
use std::arch::x86_64::*;

impl Packet {
    /// `load` for the query's rays as given (`f32::Ray::from_query` of
    /// each): the same packet, or false where `load` gives false.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub(super) unsafe fn load_ymm(&mut self, rays: &[layout::Ray; PACKET]) -> bool {
        const { assert!(PACKET == 8 && size_of::<layout::Ray>() == 32) };
        // SAFETY: the caller vouches for AVX2; every load and store is
        // unaligned, within its array.
        unsafe {
            // The eight rays' eight values, transposed: row k holds value k
            // of every ray (ox, oy, oz, tmin, dx, dy, dz, tmax).
            let row = |i: usize| rays[i].origin.as_ptr();
            let r = [
                _mm256_loadu_ps(row(0)),
                _mm256_loadu_ps(row(1)),
                _mm256_loadu_ps(row(2)),
                _mm256_loadu_ps(row(3)),
                _mm256_loadu_ps(row(4)),
                _mm256_loadu_ps(row(5)),
                _mm256_loadu_ps(row(6)),
                _mm256_loadu_ps(row(7)),
            ];
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpackhi_ps(r[0], r[1]);
            let t2 = _mm256_unpacklo_ps(r[2], r[3]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            let t4 = _mm256_unpacklo_ps(r[4], r[5]);
            let t5 = _mm256_unpackhi_ps(r[4], r[5]);
            let t6 = _mm256_unpacklo_ps(r[6], r[7]);
            let t7 = _mm256_unpackhi_ps(r[6], r[7]);
            let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
            let u1 = _mm256_shuffle_ps::<0xee>(t0, t2);
            let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
            let u3 = _mm256_shuffle_ps::<0xee>(t1, t3);
            let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
            let u5 = _mm256_shuffle_ps::<0xee>(t4, t6);
            let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
            let u7 = _mm256_shuffle_ps::<0xee>(t5, t7);
            let origin = [
                _mm256_permute2f128_ps::<0x20>(u0, u4),
                _mm256_permute2f128_ps::<0x20>(u1, u5),
                _mm256_permute2f128_ps::<0x20>(u2, u6),
            ];
            let tmin = _mm256_permute2f128_ps::<0x20>(u3, u7);
            let dir = [
                _mm256_permute2f128_ps::<0x31>(u0, u4),
                _mm256_permute2f128_ps::<0x31>(u1, u5),
                _mm256_permute2f128_ps::<0x31>(u2, u6),
            ];
            let tmax = _mm256_permute2f128_ps::<0x31>(u3, u7);

            let sign = _mm256_set1_ps(-0.0);
            let one = _mm256_set1_ps(1.0);
            // `direction_scale` of the largest component (maxps is `greater`).
            let m = _mm256_max_ps(_mm256_max_ps(abs(dir[0]), abs(dir[1])), abs(dir[2]));
            let exponent = _mm256_and_si256(
                _mm256_srli_epi32::<23>(_mm256_castps_si256(m)),
                _mm256_set1_epi32(0xff),
            );
            let scaled = _mm256_castsi256_ps(_mm256_and_si256(
                _mm256_cmpgt_epi32(exponent, _mm256_setzero_si256()),
                _mm256_cmpgt_epi32(_mm256_set1_epi32(254), exponent),
            ));
            let up = _mm256_blendv_ps(
                one,
                power(_mm256_sub_epi32(_mm256_set1_epi32(254), exponent)),
                scaled,
            );
            let down = _mm256_blendv_ps(one, power(exponent), scaled);
            let d = [
                _mm256_mul_ps(dir[0], up),
                _mm256_mul_ps(dir[1], up),
                _mm256_mul_ps(dir[2], up),
            ];
            let tmin = _mm256_mul_ps(tmin, down);
            // minps is `if tmax < FAR { tmax } else { FAR }`.
            let tmax = _mm256_min_ps(_mm256_mul_ps(tmax, down), _mm256_set1_ps(f32::FAR));

            // The slabs, axis by axis.
            let margin = _mm256_set1_ps(8.0 * f32::MACHINE_EPSILON);
            let min_dir = _mm256_set1_ps(f32::MIN_SLAB_DIR);
            let mut nan = _mm256_cmp_ps::<_CMP_UNORD_Q>(tmin, tmin);
            let mut flips = [0; 3];
            let mut slabs = [[_mm256_setzero_ps(); 4]; 3];
            for a in 0..3 {
                let c = d[a];
                let tiny = _mm256_cmp_ps::<_CMP_LT_OQ>(abs(c), min_dir);
                let clamped =
                    _mm256_blendv_ps(c, _mm256_or_ps(_mm256_and_ps(c, sign), min_dir), tiny);
                let inv = _mm256_div_ps(one, clamped);
                let inv_far = _mm256_mul_ps(inv, _mm256_set1_ps(f32::BOX_SLACK));
                let minus_origin = _mm256_xor_ps(origin[a], sign);
                let near = _mm256_mul_ps(minus_origin, inv);
                let far = _mm256_mul_ps(minus_origin, inv_far);
                let near_offset = _mm256_sub_ps(near, _mm256_mul_ps(abs(near), margin));
                let far_offset = _mm256_add_ps(far, _mm256_mul_ps(abs(far), margin));
                nan = _mm256_or_ps(nan, _mm256_cmp_ps::<_CMP_UNORD_Q>(near_offset, far_offset));
                flips[a] =
                    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(clamped, _mm256_setzero_ps()));
                _mm256_storeu_ps(self.inv_dir[a].as_mut_ptr(), inv);
                _mm256_storeu_ps(self.inv_dir_far[a].as_mut_ptr(), inv_far);
                _mm256_storeu_ps(self.near_offset[a].as_mut_ptr(), near_offset);
                _mm256_storeu_ps(self.far_offset[a].as_mut_ptr(), far_offset);
                slabs[a] = [inv, inv_far, near_offset, far_offset];
            }
            if _mm256_movemask_ps(nan) != 0 || flips.iter().any(|&f| f != 0 && f != 0xff) {
                return false;
            }
            _mm256_storeu_ps(self.tmin.as_mut_ptr(), tmin);
            _mm256_storeu_ps(self.tmax.as_mut_ptr(), tmax);

            // `ray_shear`: z the largest axis, x and y the next ones
            // round (swapped where z points down), d's components by the
            // lanes' axes picked with blends.
            let [x, y, z] = [abs(d[0]), abs(d[1]), abs(d[2])];
            let kz_x = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(x, y),
                _mm256_cmp_ps::<_CMP_GE_OQ>(x, z),
            );
            let kz_y = _mm256_andnot_ps(kz_x, _mm256_cmp_ps::<_CMP_GE_OQ>(y, z));
            let dz = pick(kz_x, kz_y, d[0], d[1], d[2]);
            let dx = pick(kz_x, kz_y, d[1], d[2], d[0]);
            let dy = pick(kz_x, kz_y, d[2], d[0], d[1]);
            let down_z = _mm256_cmp_ps::<_CMP_LT_OQ>(dz, _mm256_setzero_ps());
            let (dx, dy) = (
                _mm256_blendv_ps(dx, dy, down_z),
                _mm256_blendv_ps(dy, dx, down_z),
            );
            // Each ray's four-float groups by a transpose in registers:
            // values stored as rows and read back a ray at a time stalled
            // on store forwarding (LLVM merged the reads into wide loads
            // across several stores), a tenth of a missing ray's time.
            let shear_rows = transpose(
                _mm256_div_ps(dx, dz),
                _mm256_div_ps(dy, dz),
                _mm256_div_ps(one, dz),
                up,
            );
            let dir_rows = transpose(d[0], d[1], d[2], tmax);
            let origin_rows = transpose(origin[0], origin[1], origin[2], tmin);
            let (on_x, on_y, down_z) = (
                _mm256_movemask_ps(kz_x),
                _mm256_movemask_ps(kz_y),
                _mm256_movemask_ps(down_z),
            );
            for i in 0..PACKET {
                let kz = if on_x >> i & 1 != 0 {
                    0
                } else if on_y >> i & 1 != 0 {
                    1
                } else {
                    2
                };
                let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
                if down_z >> i & 1 != 0 {
                    std::mem::swap(&mut kx, &mut ky);
                }
                let [sx, sy, sz, t_scale] = four(shear_rows[i]);
                self.shears[i] = f32::Shear {
                    axes: [kx, ky, kz],
                    s: glam::Vec3::new(sx, sy, sz),
                    t_scale,
                };
                let [dx, dy, dz, tmax] = four(dir_rows[i]);
                let [ox, oy, oz, tmin] = four(origin_rows[i]);
                self.rays[i] = f32::Ray {
                    origin: glam::Vec3::new(ox, oy, oz),
                    tmin,
                    dir: glam::Vec3::new(dx, dy, dz),
                    tmax,
                };
            }
            self.flip = flips.map(|f| (f != 0) as usize);

            // The packet's bounds: halving trees, lane r against lane
            // r + width, as `load` folds them.
            self.tmin_least = least(tmin);
            for (bounds, [inv, inv_far, near_offset, far_offset]) in
                self.bounds.iter_mut().zip(slabs)
            {
                *bounds = [
                    least(inv),
                    most(inv),
                    least(inv_far),
                    most(inv_far),
                    least(near_offset),
                    most(far_offset),
                ];
            }
            true
        }
    }
}

// Helpers as functions that are always inlined, not closures: a closure is
// compiled without the caller's vector features, and its intrinsics became
// calls (docs/benchmarks.md).

/// |v| lane by lane.
#[inline(always)]
unsafe fn abs(v: __m256) -> __m256 {
    // SAFETY: the caller vouches for AVX.
    unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), v) }
}

/// The float whose exponent field is `e` (mantissa zero).
#[inline(always)]
unsafe fn power(e: __m256i) -> __m256 {
    // SAFETY: the caller vouches for AVX2.
    unsafe { _mm256_castsi256_ps(_mm256_slli_epi32::<23>(e)) }
}

/// `on_x`, `on_y` or `on_z` by the lane's largest axis (`kz_x`, else
/// `kz_y`, else z).
#[inline(always)]
unsafe fn pick(kz_x: __m256, kz_y: __m256, on_x: __m256, on_y: __m256, on_z: __m256) -> __m256 {
    // SAFETY: the caller vouches for AVX.
    unsafe { _mm256_blendv_ps(_mm256_blendv_ps(on_z, on_y, kz_y), on_x, kz_x) }
}

/// Rows a, b, c and d of eight lanes as eight groups of four, lane i's
/// (a, b, c, d) in group i.
#[inline(always)]
unsafe fn transpose(a: __m256, b: __m256, c: __m256, d: __m256) -> [__m128; PACKET] {
    // SAFETY: the caller vouches for AVX.
    unsafe {
        let (ab_low, ab_high) = (_mm256_unpacklo_ps(a, b), _mm256_unpackhi_ps(a, b));
        let (cd_low, cd_high) = (_mm256_unpacklo_ps(c, d), _mm256_unpackhi_ps(c, d));
        // Lanes (0, 4), (1, 5), (2, 6) and (3, 7), one per 128-bit half.
        let pairs = [
            _mm256_shuffle_ps::<0x44>(ab_low, cd_low),
            _mm256_shuffle_ps::<0xee>(ab_low, cd_low),
            _mm256_shuffle_ps::<0x44>(ab_high, cd_high),
            _mm256_shuffle_ps::<0xee>(ab_high, cd_high),
        ];
        [
            _mm256_castps256_ps128(pairs[0]),
            _mm256_castps256_ps128(pairs[1]),
            _mm256_castps256_ps128(pairs[2]),
            _mm256_castps256_ps128(pairs[3]),
            _mm256_extractf128_ps::<1>(pairs[0]),
            _mm256_extractf128_ps::<1>(pairs[1]),
            _mm256_extractf128_ps::<1>(pairs[2]),
            _mm256_extractf128_ps::<1>(pairs[3]),
        ]
    }
}

/// A group's four values.
#[inline(always)]
unsafe fn four(v: __m128) -> [f32::Real; 4] {
    let mut out = [0.0; 4];
    // SAFETY: the caller vouches for SSE; four values, written unaligned.
    unsafe { _mm_storeu_ps(out.as_mut_ptr(), v) };
    out
}

/// `load`'s `fold` with `lesser` (minps): lane r against lane r + width.
#[inline(always)]
unsafe fn least(v: __m256) -> f32::Real {
    // SAFETY: the caller vouches for AVX.
    unsafe {
        let v4 = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let v2 = _mm_min_ps(v4, _mm_movehl_ps(v4, v4));
        _mm_cvtss_f32(_mm_min_ps(v2, _mm_shuffle_ps::<0x55>(v2, v2)))
    }
}

/// `load`'s `fold` with `greater` (maxps).
#[inline(always)]
unsafe fn most(v: __m256) -> f32::Real {
    // SAFETY: the caller vouches for AVX.
    unsafe {
        let v4 = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let v2 = _mm_max_ps(v4, _mm_movehl_ps(v4, v4));
        _mm_cvtss_f32(_mm_max_ps(v2, _mm_shuffle_ps::<0x55>(v2, v2)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field `load` writes, as bits.
    fn bits(p: &Packet) -> Vec<u32> {
        let mut out = Vec::new();
        for (ray, shear) in p.rays.iter().zip(&p.shears) {
            out.extend(
                [ray.origin, ray.dir, shear.s]
                    .iter()
                    .flat_map(|v| v.to_array())
                    .map(f32::Real::to_bits),
            );
            out.extend([ray.tmin, ray.tmax, shear.t_scale].map(f32::Real::to_bits));
            out.extend(shear.axes.map(|a| a as u32));
        }
        for a in 0..3 {
            for v in [
                &p.inv_dir[a],
                &p.inv_dir_far[a],
                &p.near_offset[a],
                &p.far_offset[a],
            ] {
                out.extend(v.map(f32::Real::to_bits));
            }
            out.extend(p.bounds[a].map(f32::Real::to_bits));
        }
        out.extend(p.tmin.map(f32::Real::to_bits));
        out.extend(p.tmax.map(f32::Real::to_bits));
        out.push(p.tmin_least.to_bits());
        out.extend(p.flip.map(|f| f as u32));
        out
    }

    #[test]
    fn load_ymm_gives_the_portable_loads_bits() {
        if !(is_x86_feature_detected!("avx2")) {
            eprintln!("skipped: no AVX2");
            return;
        }
        // Values that reach every branch: tiny components (clamped), zero
        // and negative zero, subnormal and huge directions (no scaling),
        // infinite and NaN bounds, ties between axes, both signs.
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -3.0,
            1e-20,
            -1e-20,
            1e-40,
            3e38,
            -3e38,
            7.25,
            -0.001,
            f32::Real::INFINITY,
            f32::Real::NAN,
            2.0,
            -2.0,
            123456.7,
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (mut loaded, mut refused) = (0, 0);
        for round in 0..20_000 {
            let base: [f32::Real; 8] =
                std::array::from_fn(|_| values[next() as usize % values.len()]);
            let rays: [layout::Ray; PACKET] = std::array::from_fn(|_| {
                let mut v = base;
                // Most packets share an octant, as camera rays do: small
                // changes of one ray's values, and sometimes a new value.
                for x in v.iter_mut() {
                    match next() % 8 {
                        0 => *x = values[next() as usize % values.len()],
                        1 => *x *= 1.0 + (next() % 1000) as f32::Real * 1e-4,
                        _ => {}
                    }
                }
                if round % 3 == 0 {
                    v[3] = 0.0;
                    v[7] = f32::Real::INFINITY;
                }
                layout::Ray {
                    origin: [v[0], v[1], v[2]],
                    tmin: v[3],
                    dir: [v[4], v[5], v[6]],
                    tmax: v[7],
                }
            });
            let (mut portable, mut wide) = (Packet::new(), Packet::new());
            let local = rays.map(|r| f32::Ray::from_query(&r));
            let ok = portable.load(&local);
            // SAFETY: AVX2 was checked above.
            assert_eq!(
                ok,
                unsafe { wide.load_ymm(&rays) },
                "round {round}: {rays:?}"
            );
            if ok {
                assert_eq!(bits(&portable), bits(&wide), "round {round}: {rays:?}");
                loaded += 1;
            } else {
                refused += 1;
            }
        }
        assert!(
            loaded > 1000 && refused > 1000,
            "{loaded} loaded, {refused} refused"
        );
    }
}
