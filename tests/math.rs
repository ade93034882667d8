//! The shader's own transcendentals (shaders/math.wgsl, twin src/cpu/math.rs):
//! their accuracy in f32 against the library's in f64, the f64 oracle's
//! being the library's, and the shader's constants being the twin's bits.
//! The GPU computing the twin's bits is tests/bsdf_gpu.rs's.

mod common;

use lambert::cpu::{f32 as single, f64 as double};
use lambert::probe::Rng;

/// The largest |approx(x) − exact(x)| over `inputs`, with the x where it is.
fn max_error(
    inputs: impl Iterator<Item = f32>,
    approx: impl Fn(f32) -> f32,
    exact: impl Fn(f64) -> f64,
) -> (f64, f32) {
    inputs
        .map(|x| ((approx(x) as f64 - exact(x as f64)).abs(), x))
        .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
}

/// `n` points evenly over [a, b], both ends included.
fn grid(a: f32, b: f32, n: u32) -> impl Iterator<Item = f32> {
    (0..=n).map(move |i| (a as f64 + (b - a) as f64 * i as f64 / n as f64) as f32)
}

/// sin and cos in f32 are within 1.2e-7 of the exact (two units in the
/// last place below 1; measured 7.7e-8) over a dense grid of [−2π, 2π] and
/// random angles to 3216, and no quarter turn is mislabelled.
#[test]
fn sin_cos_are_within_two_ulps_of_one() {
    let mut rng = Rng(1);
    let random: Vec<f32> = (0..1_000_000)
        .map(|_| ((rng.unit() * 2.0 - 1.0) * 3216.0) as f32)
        .collect();
    for (name, inputs) in [
        ("[−2π, 2π]", grid(-6.3, 6.3, 4_000_000).collect::<Vec<_>>()),
        ("|x| ≤ 3216", random),
    ] {
        let (sin_error, sin_at) = max_error(inputs.iter().copied(), single::approx_sin, f64::sin);
        let (cos_error, cos_at) = max_error(inputs.iter().copied(), single::approx_cos, f64::cos);
        println!("{name}: sin {sin_error:.2e} at {sin_at}, cos {cos_error:.2e} at {cos_at}");
        assert!(sin_error < 1.2e-7, "sin {name}: {sin_error:e} at {sin_at}");
        assert!(cos_error < 1.2e-7, "cos {name}: {cos_error:e} at {cos_at}");
    }
    assert_eq!(single::approx_sin_cos(0.0), (0.0, 1.0));
    // sin² + cos² = 1 within rounding: no quadrant is mislabelled.
    for x in grid(-20.0, 20.0, 100_000) {
        let (s, c) = single::approx_sin_cos(x);
        assert!((s * s + c * c - 1.0).abs() < 5e-7, "{x}: {s}, {c}");
    }
}

/// acos in f32 is within 3.6e-7 of the exact (1.5 units in the last place
/// of π; measured 3.0e-7, where π − 2·asin rounds) over a dense grid of [−1, 1]
/// and the last few thousand floats below 1 (where √(1 − x) steepens),
/// and clamps inputs beyond ±1.
#[test]
fn acos_is_within_one_and_a_half_ulps_of_pi() {
    let near_one = (0..100_000u32).map(|i| f32::from_bits(1.0f32.to_bits() - i));
    let inputs: Vec<f32> = grid(-1.0, 1.0, 4_000_000)
        .chain(near_one.clone())
        .chain(near_one.map(|x| -x))
        .collect();
    let (error, at) = max_error(inputs.into_iter(), single::approx_acos, f64::acos);
    println!("acos: {error:.2e} at {at}");
    assert!(error < 3.6e-7, "acos: {error:e} at {at}");
    assert_eq!(single::approx_acos(1.0), 0.0);
    assert_eq!(single::approx_acos(-1.0), std::f32::consts::PI);
    assert_eq!(single::approx_acos(1.0 + 1e-6), 0.0);
    assert_eq!(single::approx_acos(-1.5), std::f32::consts::PI);
}

/// atan2 in f32 is within 3.6e-7 of the exact (1.5 units in the last
/// place of π; measured 3.4e-7) over directions all round
/// the circle at many lengths, and gives 0 at the origin and the exact
/// values on the axes.
#[test]
fn atan2_is_within_one_and_a_half_ulps_of_pi() {
    let mut rng = Rng(2);
    let mut worst = (0.0f64, (0.0f32, 0.0f32));
    for _ in 0..2_000_000 {
        let angle = (rng.unit() * 2.0 - 1.0) * std::f64::consts::PI;
        let length = 10f64.powf(rng.unit() * 8.0 - 4.0);
        let (y, x) = ((length * angle.sin()) as f32, (length * angle.cos()) as f32);
        let error = (single::approx_atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs();
        if error > worst.0 {
            worst = (error, (y, x));
        }
    }
    println!("atan2: {:.2e} at {:?}", worst.0, worst.1);
    assert!(worst.0 < 3.6e-7, "atan2: {:e} at {:?}", worst.0, worst.1);
    let pi = std::f32::consts::PI;
    assert_eq!(single::approx_atan2(0.0, 0.0), 0.0);
    assert_eq!(single::approx_atan2(0.0, 1.0), 0.0);
    assert_eq!(single::approx_atan2(1.0, 0.0), pi / 2.0);
    assert_eq!(single::approx_atan2(-1.0, 0.0), -pi / 2.0);
    assert_eq!(single::approx_atan2(0.0, -1.0), pi);
}

/// x⁵ by multiplication is within 3 roundings of the exact on [0, 1];
/// √ of a negative rounding is 0.
#[test]
fn pow5_and_safe_sqrt() {
    for x in grid(0.0, 1.0, 1_000_000) {
        let exact = (x as f64).powi(5);
        let error = (single::approx_pow5(x) as f64 - exact).abs();
        assert!(error <= 3.0 * f32::EPSILON as f64 * exact, "{x}");
    }
    assert_eq!(single::safe_sqrt(-1e-9), 0.0);
    assert_eq!(single::safe_sqrt(4.0), 2.0);
}

/// The f64 oracle's functions are the library's, exact to f64's precision.
#[test]
fn the_oracle_takes_the_library() {
    let mut rng = Rng(3);
    for _ in 0..100_000 {
        let x = (rng.unit() * 2.0 - 1.0) * 100.0;
        assert_eq!(double::approx_sin_cos(x), x.sin_cos());
        let c = rng.unit() * 2.0 - 1.0;
        assert_eq!(double::approx_acos(c), c.acos());
        assert!((double::approx_atan2(x, c) - x.atan2(c)).abs() <= 4e-16 * x.atan2(c).abs());
    }
}

/// The shader's constants are the twin's f32s, bit for bit.
#[test]
fn shader_constants_are_the_twins() {
    let source = lambert::shader_source::SOURCE;
    let module = naga::front::wgsl::parse_str(source).unwrap();
    let constant = |name: &str| -> f32 {
        match *common::wgsl_constant(&module, name) {
            naga::Expression::Literal(naga::Literal::F32(v)) => v,
            ref e => panic!("{name} is {e:?}"),
        }
    };
    for (name, value) in [
        ("PI", single::PI),
        ("HALF_PI", single::HALF_PI),
        ("TWO_PI", single::TWO_PI),
        ("INV_PI", single::INV_PI),
        ("INV_TWO_PI", single::INV_TWO_PI),
    ] {
        assert_eq!(constant(name).to_bits(), value.to_bits(), "{name}");
    }
}
