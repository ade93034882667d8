//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use lambert::Scene;
use lambert::layout::{Sphere, Triangle};
use lambert::cpu::{self, Precision};
use lambert::gpu::{AdapterRequest, Gpu, GpuRenderer};
use lambert::output::Rendered;
use lambert::progress::Progress;

pub fn asset(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(path)
}

pub fn load(name: &str) -> Scene {
    Scene::load(&asset(&format!("scenes/{name}.toml"))).expect("bundled scene loads")
}

/// Parses scene text as if it sat in assets/scenes (so meshes/… resolves).
pub fn scene(toml: &str) -> Scene {
    Scene::from_toml(toml, &asset("scenes/inline.toml")).expect("test scene is valid")
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
    renderer.render(&Progress::hidden()).expect("GPU render").0
}

pub fn render_cpu(scene: &Scene) -> Rendered {
    cpu::render(scene, Precision::F32, &Progress::hidden())
}

pub fn render_oracle(scene: &Scene) -> Rendered {
    cpu::render(scene, Precision::F64, &Progress::hidden())
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

/// Traces a ray query on the GPU (any adapter, lavapipe included).
pub fn trace_gpu(scene: &Scene, rays: &[lambert::layout::Ray], any_hit: bool) -> Vec<lambert::layout::Hit> {
    let mut renderer = GpuRenderer::new(open_gpu(), scene).expect("scene uploads");
    renderer.trace_rays(rays, any_hit).expect("GPU trace")
}

pub fn trace_cpu(scene: &Scene, rays: &[lambert::layout::Ray], any_hit: bool) -> Vec<lambert::layout::Hit> {
    cpu::trace_rays(scene, rays, any_hit)
}

/// SplitMix64: reproducible random numbers without another dependency.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// A uniformly distributed unit vector.
    pub fn direction(&mut self) -> glam::DVec3 {
        loop {
            let v = glam::DVec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l = v.length_squared();
            if l > 1e-6 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

/// A closed icosphere of `radius` around the origin: shared vertices, faces
/// wound outwards; each subdivision splits every face in four.
pub fn icosphere(radius: f64, subdivisions: u32) -> (Vec<glam::DVec3>, Vec<[u32; 3]>) {
    use std::collections::HashMap;
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<glam::DVec3> = [
        [-1.0, t, 0.0], [1.0, t, 0.0], [-1.0, -t, 0.0], [1.0, -t, 0.0],
        [0.0, -1.0, t], [0.0, 1.0, t], [0.0, -1.0, -t], [0.0, 1.0, -t],
        [t, 0.0, -1.0], [t, 0.0, 1.0], [-t, 0.0, -1.0], [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| glam::DVec3::from(*v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<glam::DVec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push(((vertices[a as usize] + vertices[b as usize]) * 0.5).normalize());
                (vertices.len() - 1) as u32
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut vertices);
                let bc = midpoint(b, c, &mut vertices);
                let ca = midpoint(c, a, &mut vertices);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (vertices.into_iter().map(|v| v * radius).collect(), faces)
}

/// A scene of the given primitives, camera and lights irrelevant.
pub fn scene_of(triangles: Vec<Triangle>, spheres: Vec<Sphere>) -> Scene {
    let mut s = scene(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
    );
    let material = s.spheres[0].material;
    s.triangles = triangles
        .into_iter()
        .map(|t| Triangle { material, ..t })
        .collect();
    s.spheres = spheres
        .into_iter()
        .map(|sp| Sphere { material, ..sp })
        .collect();
    s.rebuild_bvh();
    s
}
