//! Accuracy probes shared by the stress suite and the benchmarks: closed
//! meshes, rays aimed exactly at their vertices and edges, and a leak count.

use glam::{DVec3, Vec3};

use crate::layout::{NO_HIT, Ray, Triangle};

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
    pub fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length_squared();
            if l > 1e-6 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

/// A closed icosphere of `radius` around the origin: shared vertices, faces
/// wound outwards; each subdivision splits every face in four.
pub fn icosphere(radius: f64, subdivisions: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    use std::collections::HashMap;
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| DVec3::from(*v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| {
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

/// Rays from the mesh's centre aimed exactly at every vertex, every edge
/// midpoint and three random points on every edge (all rounded to f32, as
/// a user would compute them). From inside a closed mesh, every one of
/// them must hit it.
pub fn edge_aimed_rays(vertices: &[Vec3], faces: &[[u32; 3]], rng: &mut Rng) -> Vec<Ray> {
    let centre = vertices.iter().map(|v| v.as_dvec3()).sum::<DVec3>() / vertices.len() as f64;
    let origin = centre.as_vec3();
    let mut targets: Vec<Vec3> = vertices.to_vec();
    for f in faces {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            // Each edge once: from its lower-numbered vertex.
            if a > b {
                continue;
            }
            let (a, b) = (vertices[a as usize], vertices[b as usize]);
            targets.push((a + b) * 0.5);
            for _ in 0..3 {
                targets.push(a.lerp(b, rng.unit() as f32));
            }
        }
    }
    targets
        .iter()
        .map(|&t| Ray {
            origin: origin.to_array(),
            tmin: 0.0,
            dir: (t - origin).to_array(),
            tmax: f32::INFINITY,
        })
        .collect()
}

/// The leak probe of the benchmarks: an icosphere of radius 10 (1280
/// faces) at the origin and moved to (1.5e5, 1.2e3, −2.2e5), as triangle
/// lists with their edge-aimed rays.
pub fn leak_probe() -> Vec<(Vec<Triangle>, Vec<Ray>)> {
    let (vertices, faces) = icosphere(10.0, 3);
    let mut rng = Rng(11);
    [DVec3::ZERO, DVec3::new(1.5e5, 1.2e3, -2.2e5)]
        .iter()
        .map(|&offset| {
            let v32: Vec<Vec3> = vertices.iter().map(|&v| (v + offset).as_vec3()).collect();
            let rays = edge_aimed_rays(&v32, &faces, &mut rng);
            (triangles(&v32, &faces), rays)
        })
        .collect()
}

/// The triangles `faces` make of `vertices`, with the default material.
pub fn triangles(vertices: &[Vec3], faces: &[[u32; 3]]) -> Vec<Triangle> {
    faces
        .iter()
        .map(|f| Triangle {
            v0: vertices[f[0] as usize].to_array(),
            v1: vertices[f[1] as usize].to_array(),
            v2: vertices[f[2] as usize].to_array(),
            ..Default::default()
        })
        .collect()
}

/// Rays of a probe that found nothing.
pub fn count_misses(hits: &[crate::layout::Hit]) -> usize {
    hits.iter().filter(|h| h.prim == NO_HIT).count()
}
