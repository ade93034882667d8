//! Rays assembled from packed float32 rows (origins and directions, three
//! values a ray: the Python binding's arrays) as the CPU path traces them:
//! the portable loop, and an SSE variant that writes each ray in two
//! stores rather than eight (the portable loop's stores stalled on the
//! store queue: a sixth of the binding's fill).

use std::mem::MaybeUninit;

use crate::layout::Ray;

/// Writes ray i (origin `origins[3i..3i + 3]`, direction
/// `directions[3i..3i + 3]`, over (`tmin`, `tmax`)) into `out[i]`, for
/// every ray of `out` (the rows hold at least as many), and returns the
/// shortest of the directions' longest axes in magnitude: what
/// `rays::direction_lengths_are_valid` takes. Where some direction has a
/// NaN, that value is meaningless (the caller has found the NaN already).
#[inline(always)]
pub fn pack_rays(
    origins: &[f32],
    directions: &[f32],
    tmin: f32,
    tmax: f32,
    out: &mut [MaybeUninit<Ray>],
) -> f32 {
    assert!(origins.len() >= 3 * out.len() && directions.len() >= 3 * out.len());
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: the rows hold every ray of `out` (checked above); SSE
        // is x86-64's baseline.
        unsafe { pack_rays_sse(origins, directions, tmin, tmax, out) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    pack_rays_portable(origins, directions, tmin, tmax, out)
}

/// `pack_rays`' portable original.
#[inline(always)]
pub fn pack_rays_portable(
    origins: &[f32],
    directions: &[f32],
    tmin: f32,
    tmax: f32,
    out: &mut [MaybeUninit<Ray>],
) -> f32 {
    let mut shortest = f32::INFINITY;
    for (slot, (o, d)) in out
        .iter_mut()
        .zip(origins.chunks_exact(3).zip(directions.chunks_exact(3)))
    {
        slot.write(Ray {
            origin: [o[0], o[1], o[2]],
            tmin,
            dir: [d[0], d[1], d[2]],
            tmax,
        });
        let [x, y, z] = [d[0], d[1], d[2]].map(f32::abs);
        let longest = if x > y { x } else { y };
        let longest = if longest > z { longest } else { z };
        shortest = if longest < shortest {
            longest
        } else {
            shortest
        };
    }
    shortest
}

/// `pack_rays` in SSE registers: each row loaded as four values (the
/// fourth, the next row's, replaced by tmin or tmax), each ray stored as
/// two. The last ray, whose fourth value may lie past the rows, is the
/// portable loop's.
///
/// # Safety
/// `origins` and `directions` hold at least `3 * out.len()` values.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn pack_rays_sse(
    origins: &[f32],
    directions: &[f32],
    tmin: f32,
    tmax: f32,
    out: &mut [MaybeUninit<Ray>],
) -> f32 {
    use std::arch::x86_64::*;
    let Some(last) = out.len().checked_sub(1) else {
        return f32::INFINITY;
    };
    // SAFETY: SSE2 is x86-64's baseline; row i's four values at 3i..3i + 4
    // lie within the rows for i < last (3i + 4 <= 3 * out.len()); each
    // slot is 32 bytes (`Ray`: origin, tmin, dir, tmax).
    unsafe {
        let xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
        let fourth = |v: f32| _mm_setr_ps(0.0, 0.0, 0.0, v);
        let (tmin4, tmax4) = (fourth(tmin), fourth(tmax));
        let magnitude = _mm_castsi128_ps(_mm_set1_epi32(i32::MAX));
        let mut shortest = _mm_set1_ps(f32::INFINITY);
        let (o, d) = (origins.as_ptr(), directions.as_ptr());
        let slots = out.as_mut_ptr().cast::<f32>();
        for i in 0..last {
            let origin = _mm_and_ps(_mm_loadu_ps(o.add(3 * i)), xyz);
            let dir = _mm_and_ps(_mm_loadu_ps(d.add(3 * i)), xyz);
            _mm_storeu_ps(slots.add(8 * i), _mm_or_ps(origin, tmin4));
            _mm_storeu_ps(slots.add(8 * i + 4), _mm_or_ps(dir, tmax4));
            // |x|, |y|, |z|, 0: the longest in every lane after two
            // rotations (finite values: any order gives the same).
            let a = _mm_and_ps(dir, magnitude);
            let b = _mm_max_ps(a, _mm_shuffle_ps::<0b11_00_10_01>(a, a));
            let longest = _mm_max_ps(b, _mm_shuffle_ps::<0b11_01_00_10>(a, a));
            shortest = _mm_min_ps(shortest, longest);
        }
        let tail = pack_rays_portable(
            &origins[3 * last..],
            &directions[3 * last..],
            tmin,
            tmax,
            &mut out[last..],
        );
        _mm_cvtss_f32(shortest).min(tail)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packed(
        f: impl Fn(&[f32], &[f32], f32, f32, &mut [MaybeUninit<Ray>]) -> f32,
        o: &[f32],
        d: &[f32],
        n: usize,
    ) -> (Vec<[u32; 8]>, u32) {
        let mut out = vec![MaybeUninit::<Ray>::uninit(); n];
        let shortest = f(o, d, -0.0, f32::INFINITY, &mut out);
        let rays = out
            .iter()
            // SAFETY: `pack_rays` writes every slot.
            .map(|r| bytemuck::cast(unsafe { r.assume_init() }))
            .collect();
        (rays, shortest.to_bits())
    }

    /// Every length (the last ray alone, and none), with signed zeros,
    /// subnormals and the largest values: the same bits as the portable
    /// loop, and the shortest longest axis computed plainly.
    #[test]
    fn pack_rays_gives_the_portable_rays() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let special = [0.0, -0.0, 1e-40, -1e-40, f32::MAX, -f32::MAX, 1.0];
            match state % 8 {
                k @ 0..=6 => special[k as usize],
                _ => f32::from_bits((state >> 32) as u32 & 0xbf7f_ffff),
            }
        };
        for n in [0, 1, 2, 3, 7, 8, 9, 64, 257] {
            let o: Vec<f32> = (0..3 * n).map(|_| next()).collect();
            let d: Vec<f32> = (0..3 * n).map(|_| next()).collect();
            let portable = packed(pack_rays_portable, &o, &d, n);
            assert_eq!(packed(pack_rays, &o, &d, n), portable, "{n} rays");
            let plain = d
                .chunks_exact(3)
                .map(|d| d[0].abs().max(d[1].abs()).max(d[2].abs()))
                .fold(f32::INFINITY, f32::min);
            assert_eq!(portable.1, plain.to_bits(), "{n} rays");
        }
    }
}
