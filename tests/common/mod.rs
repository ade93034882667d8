//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use lambert::Scene;
use lambert::cpu::{self, Precision};
use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
use lambert::layout::{Sphere, Triangle};
use lambert::output::Rendered;
use lambert::progress::Progress;

pub mod args;
mod bin;
pub mod cli;
pub mod data;
pub mod formats;
pub mod hardware;
pub mod lights;
pub mod paths;
pub mod pbr;
mod settings;
pub mod signals;
pub mod stress;
// Each test file uses some of these; unused ones are no warning.
#[allow(unused_imports)]
pub use bin::*;
#[allow(unused_imports)]
pub use settings::*;

pub fn asset(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(path)
}

pub fn load(name: &str) -> Scene {
    Scene::load(&asset(&format!("scenes/{name}.toml"))).expect("bundled scene loads")
}

/// A `side` × `side` PNG of one RGBA colour, encoded.
pub fn png_bytes(side: u32, rgba: [u8; 4]) -> Vec<u8> {
    let image = image::RgbaImage::from_pixel(side, side, image::Rgba(rgba));
    let mut bytes = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .unwrap();
    bytes
}

/// The initialiser of the WGSL constant `name` in `module`.
pub fn wgsl_constant<'m>(module: &'m naga::Module, name: &str) -> &'m naga::Expression {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("WGSL has no const {name}"));
    &module.global_expressions[c.init]
}

/// A `[camera]` table `distance` up the +Z axis looking at the origin.
pub fn camera_on_z(distance: f64, vfov: f64, width: u32, height: u32) -> String {
    format!(
        "[camera]\neye = [0.0, 0.0, {distance:?}]\nlook_at = [0.0, 0.0, 0.0]\n\
         vfov = {vfov:?}\nwidth = {width}\nheight = {height}\n"
    )
}

/// Parses scene text as if it sat in assets/scenes (so meshes/… resolves).
pub fn scene(toml: &str) -> Scene {
    Scene::from_toml(toml, &asset("scenes/inline.toml")).expect("test scene is valid")
}

/// The error loading a model file gives (a panic if it loads).
pub fn error_of(path: &Path) -> String {
    match lambert::loading::load_mesh(path, lambert::loading::NormalMode::Face) {
        Ok(m) => panic!(
            "{} loaded ({} triangles)",
            path.display(),
            m.triangles.len()
        ),
        Err(e) => e.to_string(),
    }
}

/// Opens a GPU adapter, software ones included. A GPU test never passes
/// for lack of one: it fails and says what to install.
pub fn open_gpu() -> Gpu {
    match Gpu::open(&AdapterRequest::default(), false) {
        Ok(gpu) => gpu,
        Err(e) => panic!(
            "GPU tests need a wgpu adapter and found none ({e}).\n\
             Install Mesa's lavapipe: sudo apt-get install mesa-vulkan-drivers"
        ),
    }
}

pub fn render_gpu(scene: &Scene) -> Rendered {
    let mut renderer = GpuRenderer::new(open_gpu(), scene).expect("scene uploads");
    renderer
        .render(scene.view(), &Progress::hidden())
        .expect("GPU render")
        .0
}

pub fn render_cpu(scene: &Scene) -> Rendered {
    cpu::render(scene, scene.view(), Precision::F32, &Progress::hidden())
}

pub fn render_oracle(scene: &Scene) -> Rendered {
    cpu::render(scene, scene.view(), Precision::F64, &Progress::hidden())
}

/// An image's values as bits, for bit-for-bit comparisons.
pub fn bits(r: &Rendered) -> Vec<u32> {
    r.image.rgb.iter().flatten().map(|c| c.to_bits()).collect()
}

pub fn assert_close(actual: [f32; 3], expected: [f64; 3], rel: f64, what: &str) {
    for c in 0..3 {
        let (a, e) = (actual[c] as f64, expected[c]);
        assert!(
            (a - e).abs() <= rel * e.abs().max(1e-6),
            "{what}: channel {c} is {a}, expected {e} (relative tolerance {rel})"
        );
    }
}

/// Fails showing `text` unless it holds each of `parts`.
pub fn assert_contains_all(text: &str, parts: &[&str]) {
    assert!(parts.iter().all(|p| text.contains(p)), "{text}");
}

/// Traces a ray query on the GPU (any adapter, lavapipe included).
pub fn trace_gpu(
    scene: &Scene,
    rays: &[lambert::layout::Ray],
    any_hit: bool,
) -> Vec<lambert::layout::Hit> {
    let mut renderer = GpuRenderer::new(open_gpu(), scene).expect("scene uploads");
    renderer
        .trace_rays(rays, any_hit, scene.default_settings().intersect)
        .expect("GPU trace")
}

pub fn trace_cpu(
    scene: &Scene,
    rays: &[lambert::layout::Ray],
    any_hit: bool,
) -> Vec<lambert::layout::Hit> {
    cpu::trace_rays(scene, rays, any_hit)
}

/// A scene of the given primitives, camera and lights irrelevant.
pub fn scene_of(triangles: Vec<Triangle>, spheres: Vec<Sphere>) -> Scene {
    let mut s = scene(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
    );
    let material = s.spheres()[0].material;
    *s.triangles_mut() = triangles
        .into_iter()
        .map(|t| Triangle { material, ..t })
        .collect();
    *s.spheres_mut() = spheres
        .into_iter()
        .map(|sp| Sphere { material, ..sp })
        .collect();
    s.rebuild_bvh();
    s
}

/// What a signal at `delay_ms` into a run that writes `whole` bytes to an
/// output holding "previous" may leave: the run's whole output if it
/// finished (or if the signal came after its rename, before its exit), else
/// "previous", never a part. Returns whether the previous output was kept.
pub fn previous_or_whole(success: bool, bytes: &[u8], whole: usize, delay_ms: u64) -> bool {
    if bytes == b"previous" {
        assert!(
            !success,
            "after {delay_ms} ms: a finished run left the previous output"
        );
        return true;
    }
    assert_eq!(bytes.len(), whole, "after {delay_ms} ms: a partial output");
    false
}

/// The seed CI's property tests draw their cases from.
pub const PROPTEST_SEED: u64 = 0x1a3b_e27;

/// The configuration of every property test (docs/reliability.md): by
/// default `cases` cases drawn from PROPTEST_SEED, so that every run (CI's
/// included) tries the same cases; proptest's PROPTEST_CASES and
/// PROPTEST_RNG_SEED override the count and the seed. On demand,
/// LAMBERT_PROPTEST_CASES=N runs N cases from a random seed. A failure is
/// kept in tests/proptest-regressions/`name`.txt, which is committed and
/// replayed first on every run after.
pub fn proptest_config(cases: u32, name: &str) -> proptest::test_runner::Config {
    use proptest::test_runner::{Config, FileFailurePersistence, RngAlgorithm, RngSeed};
    // Reads proptest's own variables.
    let base = Config::default();
    let random = std::env::var("LAMBERT_PROPTEST_CASES").ok().map(|v| {
        v.parse::<u32>()
            .unwrap_or_else(|_| panic!("LAMBERT_PROPTEST_CASES = {v:?} is not a count"))
    });
    let cases = match random {
        Some(n) => n,
        None if std::env::var_os("PROPTEST_CASES").is_some() => base.cases,
        None => cases,
    };
    let rng_seed = match (base.rng_seed, random) {
        (RngSeed::Fixed(seed), _) => RngSeed::Fixed(seed),
        (RngSeed::Random, Some(_)) => RngSeed::Random,
        (RngSeed::Random, None) => RngSeed::Fixed(PROPTEST_SEED),
    };
    let path = format!(
        "{}/tests/proptest-regressions/{name}.txt",
        env!("CARGO_MANIFEST_DIR")
    );
    Config {
        cases,
        rng_seed,
        rng_algorithm: RngAlgorithm::ChaCha,
        // proptest wants the path for the life of the process.
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(Box::leak(
            path.into_boxed_str(),
        )))),
        ..base
    }
}
