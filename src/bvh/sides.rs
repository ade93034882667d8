//! Which side of a closed mesh a point lies, from its closest point: the
//! angle-weighted pseudo-normal of the face, edge or vertex that point lies
//! on (Bærentzen and Aanæs, "Signed Distance Computation Using the Angle
//! Weighted Pseudonormal", 2005) says whether the point is in front of the
//! surface there or behind it. On a closed mesh (every edge run as often
//! one way as the other) the winding number is an integer off the surface
//! and steps by one across it, so w(p) = w in front of that surface + 1
//! behind it: the winding number's inside test (|w| ≥ 0.5) for the price of
//! the closest point, which a signed distance computes anyway. What is in
//! front of each triangle is the same over a piece of the surface that no
//! other triangle crosses (a connected run of such triangles across edges
//! shared by two): one winding number a piece, taken once
//! (`Sides::label_pieces`, by the CPU path). Triangles that cross others,
//! edges and vertices where more than two triangles meet, triangles of
//! zero area and points very near the surface decide nothing: the
//! winding number does, there. A mesh with a hole (an edge run more often
//! one way) has a winding number that is no integer: it keeps winding
//! numbers everywhere. Built once per mesh (`Bvh::sides`).

use std::sync::OnceLock;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::overlap;
use crate::layout::Triangle;

/// No vertex, edge or piece.
const NONE: u32 = u32::MAX;

/// The pseudo-normal decides no side where the vector from the closest
/// point makes less than this cosine with it (a fold of nearly 180°, or a
/// vector the rounding of its ends could turn): the winding number does.
const MIN_COSINE: f64 = 1e-3;

/// Triangles of a piece whose fronts are sampled for its winding number,
/// at most (`Sides::samples`).
const SAMPLES: usize = 4;

/// What the sides of a closed mesh's points need.
#[derive(Clone, Debug)]
pub struct Sides {
    /// Per triangle, its corners' vertices (welded by position); `NONE` for
    /// a triangle of zero area, which bounds nothing and is left out.
    corners: Vec<[u32; 3]>,
    /// Per triangle, its edges (edge k from corner k to corner k + 1).
    edges: Vec<[u32; 3]>,
    /// Per vertex, the sum of its triangles' unit normals weighted by their
    /// angles there; zero where it decides nothing (a vertex where separate
    /// fans meet, or on an edge of more than two triangles, or of a
    /// triangle that crosses another).
    /// (f32: the direction to well within `MIN_COSINE`, in half the
    /// memory.)
    vertex_normals: Vec<Vec3>,
    /// Per edge, the sum of its two triangles' unit normals; zero where it
    /// decides nothing (more than two triangles, or one that crosses).
    edge_normals: Vec<Vec3>,
    /// Per triangle, its piece; `NONE` for one that crosses another or has
    /// zero area.
    piece: Vec<u32>,
    /// Per piece, up to `SAMPLES` of its largest triangles.
    samples: Vec<Vec<u32>>,
    /// Per piece, the winding number in front of its triangles, once taken
    /// (`label_pieces`); None where it could not be.
    labels: OnceLock<Vec<Option<i32>>>,
}

/// What part of a triangle a point is nearest: Ericson's regions.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Feature {
    Face,
    /// From corner k to corner k + 1.
    Edge(usize),
    Vertex(usize),
}

fn corners(t: &Triangle) -> [DVec3; 3] {
    [t.v0, t.v1, t.v2].map(|v| DVec3::from(v.map(f64::from)))
}

fn unit_normal(v: [DVec3; 3]) -> DVec3 {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero()
}

/// The point of triangle `v` nearest `p`, and the feature it lies on
/// (Ericson, Real-Time Collision Detection, 5.1.5; in f64).
fn nearest_feature(p: DVec3, v: [DVec3; 3]) -> (Feature, DVec3) {
    let [a, b, c] = v;
    let (ab, ac) = (b - a, c - a);
    let ap = p - a;
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (Feature::Vertex(0), a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (Feature::Vertex(1), b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (Feature::Edge(0), a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (Feature::Vertex(2), c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (Feature::Edge(2), a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (Feature::Edge(1), b + (c - b) * w);
    }
    let sum = va + vb + vc;
    (Feature::Face, a + ab * (vb / sum) + ac * (vc / sum))
}

/// Union–find's root of `i`, halving paths on the way.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

fn join(parent: &mut [u32], a: u32, b: u32) {
    let (a, b) = (root(parent, a), root(parent, b));
    parent[a.max(b) as usize] = a.min(b);
}

/// The welded vertex of each corner (3 a triangle; −0 as +0), and how
/// many vertices.
fn weld(triangles: &[Triangle]) -> (Vec<u32>, usize) {
    let mut keyed: Vec<([u32; 3], u32)> = (0..3 * triangles.len())
        .into_par_iter()
        .map(|c| {
            let t = &triangles[c / 3];
            let v = [t.v0, t.v1, t.v2][c % 3];
            (v.map(|x| (x + 0.0).to_bits()), c as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    let mut vertex_of = vec![0u32; keyed.len()];
    let mut count = 0;
    for (i, &(key, c)) in keyed.iter().enumerate() {
        if i == 0 || key != keyed[i - 1].0 {
            count += 1;
        }
        vertex_of[c as usize] = count - 1;
    }
    (vertex_of, count as usize)
}

impl Sides {
    /// The sides of `triangles` (the primitives of `bvh` below their
    /// count), or why their winding number is no integer off the surface:
    /// the first edge run more often one way than the other (a hole).
    pub fn build(bvh: &super::Bvh, triangles: &[Triangle]) -> Result<Sides, String> {
        let n = triangles.len();
        let (vertex_of, vertex_count) = weld(triangles);
        let corners: Vec<[u32; 3]> = (0..n)
            .into_par_iter()
            .map(|t| {
                let c = [0, 1, 2].map(|k| vertex_of[3 * t + k]);
                let v = self::corners(&triangles[t]);
                let flat = (v[1] - v[0]).cross(v[2] - v[0]) == DVec3::ZERO;
                if flat || c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
                    [NONE; 3]
                } else {
                    c
                }
            })
            .collect();
        drop(vertex_of);
        // Edges: the corners that run each (low, high) pair of vertices.
        let mut runs: Vec<(u64, u32)> = corners
            .par_iter()
            .enumerate()
            .filter(|(_, c)| c[0] != NONE)
            .flat_map_iter(|(t, c)| {
                (0..3).map(move |k| {
                    let (a, b) = (c[k], c[(k + 1) % 3]);
                    (
                        (a.min(b) as u64) << 32 | a.max(b) as u64,
                        (3 * t + k) as u32,
                    )
                })
            })
            .collect();
        runs.par_sort_unstable();
        let forward = |c: u32| {
            let (t, k) = (c as usize / 3, c as usize % 3);
            corners[t][k] < corners[t][(k + 1) % 3]
        };
        // A hole first: it leaves the winding number no integer, and the
        // crossing test need not be paid.
        for run in runs.chunk_by(|a, b| a.0 == b.0) {
            let ahead = run.iter().filter(|r| forward(r.1)).count();
            if 2 * ahead != run.len() {
                let c = run[0].1 as usize;
                let v = self::corners(&triangles[c / 3]);
                return Err(format!(
                    "the edge {:?} – {:?} of triangle {} is run {} time(s) one way and {} the \
                     other (the mesh has a hole there)",
                    v[c % 3].to_array(),
                    v[(c + 1) % 3].to_array(),
                    c / 3,
                    ahead,
                    run.len() - ahead
                ));
            }
        }
        let crossing = overlap::crossing(bvh, triangles, &corners);
        let mut crosses = vec![false; n];
        for &t in &crossing {
            crosses[t as usize] = true;
        }
        let mut edges = vec![[NONE; 3]; n];
        let mut edge_normals = Vec::with_capacity(runs.len() / 2);
        // Vertices that decide nothing, triangles joined into pieces, and
        // each vertex's corners into fans, across edges that decide.
        let mut unsure = vec![false; vertex_count];
        let mut pieces: Vec<u32> = (0..n as u32).collect();
        let mut fans: Vec<u32> = (0..3 * n as u32).collect();
        let next = |c: u32| c - c % 3 + (c % 3 + 1) % 3;
        for run in runs.chunk_by(|a, b| a.0 == b.0) {
            let (c1, c2) = (run[0].1, run[1].1);
            let decides = run.len() == 2 && !crosses[c1 as usize / 3] && !crosses[c2 as usize / 3];
            if !decides {
                unsure[(run[0].0 >> 32) as usize] = true;
                unsure[run[0].0 as u32 as usize] = true;
                continue;
            }
            let id = edge_normals.len() as u32;
            edges[c1 as usize / 3][c1 as usize % 3] = id;
            edges[c2 as usize / 3][c2 as usize % 3] = id;
            edge_normals.push(
                (unit_normal(self::corners(&triangles[c1 as usize / 3]))
                    + unit_normal(self::corners(&triangles[c2 as usize / 3])))
                .as_vec3(),
            );
            // c1 runs a → b, c2 runs b → a.
            join(&mut fans, c1, next(c2));
            join(&mut fans, next(c1), c2);
            join(&mut pieces, c1 / 3, c2 / 3);
        }
        drop(runs);
        // Vertex normals, where the vertex is one fan of deciding triangles.
        let mut fan_of = vec![NONE; vertex_count];
        let mut vertex_normals = vec![DVec3::ZERO; vertex_count];
        for (t, c) in corners.iter().enumerate() {
            if c[0] == NONE {
                continue;
            }
            let v = self::corners(&triangles[t]);
            let normal = unit_normal(v);
            for k in 0..3 {
                let vertex = c[k] as usize;
                let fan = root(&mut fans, (3 * t + k) as u32);
                if crosses[t] || (fan_of[vertex] != NONE && fan_of[vertex] != fan) {
                    unsure[vertex] = true;
                }
                fan_of[vertex] = fan;
                let angle = (v[(k + 1) % 3] - v[k]).angle_between(v[(k + 2) % 3] - v[k]);
                vertex_normals[vertex] += angle * normal;
            }
        }
        for (normal, &unsure) in vertex_normals.iter_mut().zip(&unsure) {
            if unsure {
                *normal = DVec3::ZERO;
            }
        }
        drop((fans, fan_of, unsure));
        // Pieces, numbered in order of their first triangle; each one's
        // largest triangles sampled.
        let mut piece = vec![NONE; n];
        let mut samples: Vec<Vec<(f64, u32)>> = Vec::new();
        let mut number = vec![NONE; n];
        for t in 0..n {
            if corners[t][0] == NONE || crosses[t] {
                continue;
            }
            let r = root(&mut pieces, t as u32) as usize;
            if number[r] == NONE {
                number[r] = samples.len() as u32;
                samples.push(Vec::new());
            }
            piece[t] = number[r];
            let v = self::corners(&triangles[t]);
            let area = (v[1] - v[0]).cross(v[2] - v[0]).length();
            let largest = &mut samples[number[r] as usize];
            largest.push((area, t as u32));
            if largest.len() > SAMPLES {
                largest.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
                largest.truncate(SAMPLES);
            }
        }
        Ok(Sides {
            corners,
            edges,
            vertex_normals: vertex_normals.iter().map(|n| n.as_vec3()).collect(),
            edge_normals,
            piece,
            samples: samples
                .into_iter()
                .map(|s| s.into_iter().map(|(_, t)| t).collect())
                .collect(),
            labels: OnceLock::new(),
        })
    }

    /// How many pieces, and how many triangles lie in none (they cross
    /// another or have zero area).
    pub fn counts(&self) -> (usize, usize) {
        let outside = self.piece.iter().filter(|&&p| p == NONE).count();
        (self.samples.len(), outside)
    }

    /// Per piece, the winding number in front of its triangles, taken on
    /// the first call: `label(samples)` is given a piece's sampled
    /// triangles and returns its winding number, or None where it cannot
    /// be sure of it (the CPU path's, `cpu::solid_inside`).
    pub fn label_pieces(&self, label: impl Fn(&[u32]) -> Option<i32> + Sync) -> &[Option<i32>] {
        self.labels
            .get_or_init(|| self.samples.par_iter().map(|s| label(s)).collect())
    }

    /// A point in front of triangle `t`'s centre, a tenth of its size
    /// (√(2 · area)) away along its normal: where the winding number is
    /// the one in front of `t`'s piece if `t` is the triangle nearest it
    /// and it is in front of `t` (`behind`), nothing lying between.
    pub fn in_front(triangles: &[Triangle], t: u32) -> DVec3 {
        let v = corners(&triangles[t as usize]);
        let cross = (v[1] - v[0]).cross(v[2] - v[0]);
        (v[0] + v[1] + v[2]) / 3.0 + cross.normalize_or_zero() * (0.1 * cross.length().sqrt())
    }

    /// Where `behind` reads for triangle `prim`: its piece, corners and
    /// edges, then (`normals`, which reads the corners and edges, so
    /// best called once those are in cache) its vertices' and edges'
    /// normals; for a caller to prefetch (a point's triangle is far in
    /// memory from the last point's, and each of these loads would
    /// otherwise wait on it in turn).
    pub fn rows(&self, prim: u32, normals: bool) -> [*const u8; 6] {
        fn at<T>(v: &[T], i: u32) -> *const u8 {
            v.as_ptr().wrapping_add(i as usize).cast()
        }
        match (normals, self.corners.get(prim as usize)) {
            (true, Some(&c)) => {
                let e = self.edges[prim as usize];
                let vertex = |k: usize| at(&self.vertex_normals, c[k]);
                let edge = |k: usize| at(&self.edge_normals, e[k]);
                [vertex(0), vertex(1), vertex(2), edge(0), edge(1), edge(2)]
            }
            _ => {
                let rows = [
                    at(&self.piece, prim),
                    at(&self.corners, prim),
                    at(&self.edges, prim),
                ];
                [rows[0], rows[1], rows[2], rows[0], rows[1], rows[2]]
            }
        }
    }

    /// Whether point `p` is behind the surface at its closest point on
    /// triangle `prim` (all in the frame of `triangles`, the sides'), and
    /// that triangle's piece: None where that does not decide (a triangle
    /// in no piece, p nearer it than `min_distance`, a feature that decides
    /// nothing, or a vector from the nearest point nearly across its
    /// pseudo-normal).
    pub fn behind(
        &self,
        triangles: &[Triangle],
        prim: u32,
        p: DVec3,
        min_distance: f64,
    ) -> Option<(bool, u32)> {
        let piece = *self.piece.get(prim as usize)?;
        if piece == NONE {
            return None;
        }
        let c = &self.corners[prim as usize];
        let v = corners(&triangles[prim as usize]);
        let (feature, q) = nearest_feature(p, v);
        let normal = match feature {
            Feature::Face => unit_normal(v),
            Feature::Edge(k) => match self.edges[prim as usize][k] {
                NONE => DVec3::ZERO,
                e => self.edge_normals[e as usize].as_dvec3(),
            },
            Feature::Vertex(k) => self.vertex_normals[c[k] as usize].as_dvec3(),
        };
        let away = p - q;
        let (distance, length) = (away.length(), normal.length());
        // A zero (or NaN) length decides nothing.
        if distance < min_distance || distance * length <= 0.0 || length.is_nan() {
            return None;
        }
        let cosine = away.dot(normal) / (distance * length);
        (cosine.abs() >= MIN_COSINE).then_some((cosine < 0.0, piece))
    }

    /// Whether point `p` is inside by the winding number's rule: behind
    /// its closest point's surface (`behind`) in a piece whose winding
    /// number in front is known (`label_pieces`'s). None where either is
    /// not known.
    pub fn inside(
        &self,
        triangles: &[Triangle],
        prim: u32,
        p: DVec3,
        min_distance: f64,
    ) -> Option<bool> {
        let (behind, piece) = self.behind(triangles, prim, p, min_distance)?;
        let front = (*self.labels.get()?.get(piece as usize)?)?;
        Some((front + i32::from(behind)) != 0)
    }
}
