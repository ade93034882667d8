//! Our own transcendentals, the twin of shaders/math.wgsl, function by
//! function with the same names: sine and cosine, arccosine, arctangent
//! and a fifth power of plain arithmetic, each operation rounded on its own
//! in the shader's order (Rust neither fuses nor reassociates; the shader's
//! `rounded` stops its compiler doing so), so that the f32 twin computes
//! the GPU's bits. The f64 oracle, which matches no shader's bits, takes
//! the library's functions, exact to f64's precision, so that it measures
//! the approximations' error too. Accuracy in docs/rendering.md ("Math
//! approximations"), measured by tests/math.rs.
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it into
//! `cpu::f32` and `cpu::f64`, whose `Real` and `Vec3` it takes.

/// The stage's items, expanded into the module that invokes it (`kernel!`).
macro_rules! math {
    () => {
        // f64's constants rounded to f32 are the shader's literals.
        pub const PI: Real = std::f64::consts::PI as Real;
        pub const HALF_PI: Real = std::f64::consts::FRAC_PI_2 as Real;
        pub const TWO_PI: Real = std::f64::consts::TAU as Real;
        pub const INV_PI: Real = std::f64::consts::FRAC_1_PI as Real;
        // As the winding numbers always had it: 0.5/π in `Real`.
        pub const INV_TWO_PI: Real = 0.5 / PI;
        const TWO_OVER_PI: Real = std::f64::consts::FRAC_2_PI as Real;
        // π/2 in three parts (Cody and Waite): k times the first (8
        // significant bits) and the second (13) is exact for |k| < 2048.
        const PIO2_HI: Real = 1.5703125;
        const PIO2_MID: Real = 0.000_483_751_3;
        const PIO2_LO: Real = 7.54979e-8;

        /// Whether this is the f64 oracle, which takes the library's
        /// functions.
        const EXACT: bool = Real::MANTISSA_DIGITS > f32::MANTISSA_DIGITS;

        /// a·b + c in two roundings (the shader's is never fused either).
        #[inline(always)]
        pub fn mad(a: Real, b: Real, c: Real) -> Real {
            a * b + c
        }

        /// (sin x, cos x) for |x| ≤ 3216: x less the nearest multiple k of
        /// π/2, Cephes' sinf and cosf polynomials on [−π/4, π/4] (Moshier),
        /// and the pair rotated by k quarter turns.
        #[inline(always)]
        pub fn approx_sin_cos(x: Real) -> (Real, Real) {
            if EXACT {
                return x.sin_cos();
            }
            let k = (x * TWO_OVER_PI + 0.5).floor();
            let r = x - k * PIO2_HI - k * PIO2_MID - k * PIO2_LO;
            let z = r * r;
            let sin_poly = mad(mad(-0.000_195_152_96, z, 0.008_332_161), z, -0.166_666_55);
            let s = mad(r * z, sin_poly, r);
            let cos_poly = mad(mad(2.443_315_7e-5, z, -0.001_388_731_6), z, 0.041_666_646);
            let c = mad(z * z, cos_poly, -(0.5 * z)) + 1.0;
            let quarter = (k as i32) & 3;
            let (s, c) = if quarter & 1 != 0 { (c, -s) } else { (s, c) };
            if quarter & 2 != 0 { (-s, -c) } else { (s, c) }
        }

        #[inline(always)]
        pub fn approx_sin(x: Real) -> Real {
            approx_sin_cos(x).0
        }

        #[inline(always)]
        pub fn approx_cos(x: Real) -> Real {
            approx_sin_cos(x).1
        }

        /// asin(s) for s in [0, 1/2], z = s²: Cephes' asinf polynomial
        /// (Moshier).
        #[inline(always)]
        fn asin_half(s: Real, z: Real) -> Real {
            let p = mad(
                mad(
                    mad(mad(0.042_163_2, z, 0.024_181_312), z, 0.045_470_025),
                    z,
                    0.074_953_005,
                ),
                z,
                0.166_667_52,
            );
            mad(p * z, s, s)
        }

        /// acos(x) in [0, π], x clamped to [−1, 1] (a cosine from rounded
        /// vectors may pass 1): π/2 − asin x where |x| ≤ 1/2, else from
        /// acos |x| = 2·asin √((1 − |x|)/2), whose argument is at most 1/2.
        #[inline(always)]
        pub fn approx_acos(x: Real) -> Real {
            if EXACT {
                return x.clamp(-1.0, 1.0).acos();
            }
            let a = x.abs().min(1.0);
            if a <= 0.5 {
                let t = asin_half(a, a * a);
                return HALF_PI - if x < 0.0 { -t } else { t };
            }
            let z = 0.5 * (1.0 - a);
            let t = 2.0 * asin_half(z.sqrt(), z);
            if x < 0.0 { PI - t } else { t }
        }

        /// x⁵ by multiplication (Schlick's Fresnel).
        #[inline(always)]
        pub fn approx_pow5(x: Real) -> Real {
            let x2 = x * x;
            x2 * x2 * x
        }

        /// √x, 0 for x < 0 (a difference of squares rounded below 0).
        #[inline(always)]
        pub fn safe_sqrt(x: Real) -> Real {
            (if x < 0.0 { 0.0 } else { x }).sqrt()
        }

        /// v / |v|, as glam's `normalize` (v · (1/|v|)).
        #[inline(always)]
        pub fn normalize3(v: Vec3) -> Vec3 {
            v * (1.0 / dot3(v, v).sqrt())
        }

        /// atan(z) for z in [0, 1]: an odd polynomial of degree 15, fitted for
        /// relative error (below 3e-7 in f32): a far triangle's small solid
        /// angle keeps its relative precision, which stacked layers of
        /// triangles, all erring alike, multiply (the winding numbers').
        #[inline(always)]
        pub fn atan_unit(z: Real) -> Real {
            if EXACT {
                return z.atan();
            }
            let z2 = z * z;
            z * (0.999_999_94
                + z2 * (-0.333_320_95
                    + z2 * (0.199_713_74
                        + z2 * (-0.140_294_12
                            + z2 * (0.099_427_36
                                + z2 * (-0.059_904_337
                                    + z2 * (0.024_556_82 + z2 * -0.004_780_36)))))))
        }

        /// atan2(y, x) in (−π, π] from `atan_unit`; 0 where both are 0.
        #[inline(always)]
        pub fn approx_atan2(y: Real, x: Real) -> Real {
            let ax = x.abs();
            let ay = y.abs();
            let steep = ay > ax;
            let hi = if steep { ay } else { ax };
            let lo = if steep { ax } else { ay };
            if hi == 0.0 {
                return 0.0;
            }
            let mut r = atan_unit(lo / hi);
            if steep {
                r = HALF_PI - r;
            }
            if x < 0.0 {
                r = PI - r;
            }
            if y < 0.0 {
                r = -r;
            }
            r
        }
    };
}
pub(crate) use math;
