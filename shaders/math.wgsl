// Stage: math. Sine and cosine, arccosine, arctangent and a fifth power of
// plain arithmetic, so that the shader and its CPU twin (src/cpu/math.rs)
// compute the same bits: WGSL leaves its builtins' precision to the
// driver, and Rust's come from the platform's library. Every product that
// feeds a sum is `rounded` (shaders/texture.wgsl) so that no compiler fuses
// or reorders it; +, −, ×, / and sqrt are IEEE on lavapipe. Accuracy,
// measured by tests/math.rs, in docs/rendering.md ("Math approximations").

// The twin's f32 constants, bit for bit: suffixed literals, written as
// Rust prints them (the shortest that reads back as the same f32).
const PI: f32 = 3.1415927f;
const HALF_PI: f32 = 1.5707964f;
const TWO_PI: f32 = 6.2831855f;
const INV_PI: f32 = 0.31830987f;
const INV_TWO_PI: f32 = 0.15915494f;
const TWO_OVER_PI: f32 = 0.63661975f;

// π/2 in three parts (Cody and Waite): the first of 8 significant bits and
// the second of 13, so that k times each is exact for |k| < 2048 (|x| up
// to 3216) and x − k·PIO2_HI is exact (Sterbenz).
const PIO2_HI: f32 = 1.5703125f;
const PIO2_MID: f32 = 0.0004837513f;
const PIO2_LO: f32 = 7.54979e-8f;

// a·b + c in two roundings, never fused into one.
fn mad(a: f32, b: f32, c: f32) -> f32 {
    return rounded(a * b) + c;
}

// (sin x, cos x) for |x| ≤ 3216: x less the nearest multiple k of π/2,
// then Cephes' sinf and cosf polynomials on [−π/4, π/4] (Moshier), and the
// pair rotated by k quarter turns.
fn approx_sin_cos(x: f32) -> vec2<f32> {
    let k = floor(rounded(x * TWO_OVER_PI) + 0.5);
    let r = rounded(rounded(x - rounded(k * PIO2_HI)) - rounded(k * PIO2_MID))
        - rounded(k * PIO2_LO);
    let z = r * r;
    let sin_poly = mad(mad(-0.00019515296f, z, 0.008332161f), z, -0.16666655f);
    let s = mad(r * z, sin_poly, r);
    let cos_poly = mad(mad(2.4433157e-5f, z, -0.0013887316f), z, 0.041666646f);
    let c = mad(z * z, cos_poly, -rounded(0.5 * z)) + 1.0;
    let quarter = u32(i32(k)) & 3u;
    var sc = select(vec2<f32>(s, c), vec2<f32>(c, -s), (quarter & 1u) != 0u);
    if (quarter & 2u) != 0u {
        sc = -sc;
    }
    return sc;
}

fn approx_sin(x: f32) -> f32 {
    return approx_sin_cos(x).x;
}

fn approx_cos(x: f32) -> f32 {
    return approx_sin_cos(x).y;
}

// asin(s) for s in [0, 1/2]: Cephes' asinf polynomial (Moshier).
fn asin_half(s: f32, z: f32) -> f32 {
    let p = mad(mad(mad(mad(0.0421632f, z, 0.024181312f), z, 0.045470025f), z, 0.074953005f),
        z, 0.16666752f);
    return mad(p * z, s, s);
}

// acos(x) in [0, π], x clamped to [−1, 1] (a cosine from rounded vectors
// may pass 1): π/2 − asin x where |x| ≤ 1/2, else from
// acos |x| = 2·asin √((1 − |x|)/2), whose argument is at most 1/2.
fn approx_acos(x: f32) -> f32 {
    let a = min(abs(x), 1.0);
    if a <= 0.5 {
        let t = asin_half(a, a * a);
        return HALF_PI - select(t, -t, x < 0.0);
    }
    let z = 0.5 * (1.0 - a);
    let t = 2.0 * asin_half(sqrt(z), z);
    return select(t, PI - t, x < 0.0);
}

// x⁵ by multiplication (Schlick's Fresnel).
fn approx_pow5(x: f32) -> f32 {
    let x2 = x * x;
    return x2 * x2 * x;
}

// √x, 0 for x < 0 (a difference of squares rounded below 0), `rounded` so
// that a division by it stays a division (no reciprocal square root).
fn safe_sqrt(x: f32) -> f32 {
    return rounded(sqrt(select(x, 0.0, x < 0.0)));
}

// v / |v|, as glam's `normalize` (v · (1/|v|)).
fn normalize3(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / rounded(sqrt(dot3(v, v))));
}

// atan(z) for z in [0, 1]: an odd polynomial of degree 15, fitted for
// relative error (below 3e-7): a far triangle's small solid angle keeps its
// relative precision (the winding numbers' arctangent).
fn atan_unit(z: f32) -> f32 {
    let z2 = z * z;
    let p = mad(mad(mad(mad(mad(mad(mad(-0.00478036f, z2, 0.02455682f), z2, -0.059904337f), z2,
        0.09942736f), z2, -0.14029412f), z2, 0.19971374f), z2, -0.33332095f), z2, 0.99999994f);
    return z * p;
}

// atan2(y, x) in (−π, π] from `atan_unit`; 0 where both are 0.
fn approx_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let steep = ay > ax;
    let hi = select(ax, ay, steep);
    let lo = select(ay, ax, steep);
    if hi == 0.0 {
        return 0.0;
    }
    var r = atan_unit(lo / hi);
    if steep {
        r = HALF_PI - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        r = -r;
    }
    return r;
}
