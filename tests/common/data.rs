//! Test inputs made in code (a deterministic generator, rays, binary
//! glTF) and an f64 reference (the winding number).

use glam::{DVec3, Vec3};
use lambert::layout::{Ray, Triangle};

/// A small deterministic generator (no dependency on a seed's crate).
pub struct Lcg(pub u64);

impl Lcg {
    fn step(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0
    }

    /// In [0, 1), from the step's top 24 bits.
    pub fn next(&mut self) -> f32 {
        ((self.step() >> 40) as f32) / ((1u64 << 24) as f32)
    }

    /// In [0, 1), from the step's top 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        ((self.step() >> 11) as f64) / ((1u64 << 53) as f64)
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }

    pub fn point(&mut self, lo: f32, hi: f32) -> [f32; 3] {
        [self.range(lo, hi), self.range(lo, hi), self.range(lo, hi)]
    }

    /// A point drawn in f64, rounded to f32.
    pub fn point_f64(&mut self, lo: f64, hi: f64) -> [f32; 3] {
        [0; 3].map(|_| (lo + (hi - lo) * self.next_f64()) as f32)
    }
}

/// A binary glTF of `json` (its one buffer: `bin`).
pub fn glb(mut json: serde_json::Value, bin: &[u8]) -> Vec<u8> {
    json["buffers"] = serde_json::json!([{"byteLength": bin.len()}]);
    let mut text = serde_json::to_vec(&json).unwrap();
    text.resize(text.len().div_ceil(4) * 4, b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().div_ceil(4) * 4, 0);
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// A glb whose scene is one node of mesh 0, using `extension`; `rest`
/// (an object) gives the other keys of its JSON: meshes, accessors...
pub fn one_mesh_glb(extension: &str, rest: serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": [extension],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
    });
    let serde_json::Value::Object(rest) = rest else {
        panic!("the rest of a glTF's JSON is an object")
    };
    json.as_object_mut().unwrap().extend(rest);
    glb(json, bin)
}

/// A ray from `origin` along `dir`, from t = 0 on.
pub fn ray(origin: [f32; 3], dir: [f32; 3]) -> Ray {
    Ray {
        origin,
        tmin: 0.0,
        dir,
        tmax: f32::INFINITY,
    }
}

/// A triangle with the default attributes.
pub fn tri(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> Triangle {
    Triangle {
        v0,
        v1,
        v2,
        ..Default::default()
    }
}

/// A vertex in f64.
pub fn d3(v: [f32; 3]) -> DVec3 {
    DVec3::from(v.map(f64::from))
}

/// The winding number in f64, every triangle's solid angle.
pub fn winding_f64(q: DVec3, triangles: &[Triangle]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (d3(t.v0) - q, d3(t.v1) - q, d3(t.v2) - q);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let det = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
            det.atan2(den) / (2.0 * std::f64::consts::PI)
        })
        .sum()
}

/// A closed, outward-facing latitude-longitude sphere of radius r about c.
pub fn sphere_mesh(c: [f32; 3], r: f32, rings: usize, segments: usize) -> Vec<Triangle> {
    let vertex = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * (j % segments) as f32 / segments as f32;
        if i == 0 {
            return [c[0], c[1], c[2] + r];
        }
        if i == rings {
            return [c[0], c[1], c[2] - r];
        }
        [
            c[0] + r * theta.sin() * phi.cos(),
            c[1] + r * theta.sin() * phi.sin(),
            c[2] + r * theta.cos(),
        ]
    };
    quad_grid(rings, segments, vertex)
}

/// The triangles of a rows × cols grid of quads, quad (i, j) having
/// corners `vertex(i, j)`, `vertex(i + 1, j)`, `vertex(i + 1, j + 1)` and
/// `vertex(i, j + 1)` (`vertex` wraps them where the grid closes), cut
/// along its first diagonal; a half with two corners the same (at a
/// sphere's poles) is left out.
pub fn quad_grid(
    rows: usize,
    cols: usize,
    vertex: impl Fn(usize, usize) -> [f32; 3],
) -> Vec<Triangle> {
    let mut out = Vec::new();
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i + 1, j + 1),
                vertex(i, j + 1),
            );
            for (x, y, z) in [(a, c, d), (a, b, c)] {
                if x != y && y != z && z != x {
                    out.push(tri(x, y, z));
                }
            }
        }
    }
    out
}

/// A uniform f32 in [0, 1).
pub fn unit(rng: &mut lambert::probe::Rng) -> f32 {
    rng.unit() as f32
}

/// `n` small random triangles in the cube of side 1 around the origin (a soup: overlapping, of
/// every orientation).
pub fn soup(seed: u64, n: usize) -> Vec<Triangle> {
    let mut rng = lambert::probe::Rng(seed);
    (0..n)
        .map(|_| {
            let p = Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5;
            let mut corner = || {
                let d = Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng)) - 0.5;
                (p + 0.05 * d).to_array()
            };
            let (v0, v1, v2) = (corner(), corner(), corner());
            tri(v0, v1, v2)
        })
        .collect()
}
