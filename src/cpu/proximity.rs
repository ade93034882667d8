//! The CPU path's geometric queries (docs/ray-query.md): closest points,
//! winding numbers and every hit along rays, points and rays in parallel
//! chunks, in the scene's local frame (the engine, `render`, moves world
//! points and rays into it and the answers back).

use glam::Vec3;
use rayon::prelude::*;

use super::closest::{closest_point, query_margin};
use super::f32;
use super::winding::winding_number;
use crate::layout::{ClosestPoint, ListedHit, Ray};
use crate::scene::Scene;

/// Points per parallel task: enough to amortise the task, few enough to
/// balance two to a few dozen threads.
const CHUNK: usize = 1024;

/// The nearest point of the scene's triangles to each point (local frame)
/// within `max_distance` (squared distance ≤ max_distance², in f32);
/// `ClosestPoint::NONE` where none is. The point comes back in the local
/// frame.
pub fn closest_points(scene: &Scene, points: &[[f32; 3]], max_distance: f32) -> Vec<ClosestPoint> {
    let triangles = scene.triangles.len();
    let radius = scene.placement().radius as f32;
    let max_d2 = max_distance * max_distance;
    points
        .par_iter()
        .with_min_len(CHUNK)
        .map_init(Vec::new, |queue, &p| {
            let p = Vec3::from(p);
            let margin = query_margin(p.abs().max_element(), radius);
            match closest_point(&scene.bvh, triangles, p, max_d2, margin, queue) {
                Some(n) => ClosestPoint {
                    point: n.point.to_array(),
                    prim: n.prim,
                    u: n.u,
                    v: n.v,
                    distance: n.d2.sqrt(),
                    _pad: 0,
                },
                None => ClosestPoint::NONE,
            }
        })
        .collect()
}

/// The generalized winding number of the scene's triangles at each point
/// (local frame), through the winding tree (built on the first call).
pub fn winding_numbers(scene: &Scene, points: &[[f32; 3]]) -> Vec<f32> {
    let tree = scene.bvh.winding_tree(scene.triangles.len());
    points
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&q| winding_number(tree, &scene.triangles, Vec3::from(q)))
        .collect()
}

/// How many triangles each ray (local frame) crosses in (tmin, tmax), an
/// edge or a vertex once.
pub fn count_intersections(scene: &Scene, rays: &[Ray]) -> Vec<u32> {
    let kernel = f32::Kernel::new(scene);
    let pad = box_pad(scene);
    rays.par_iter()
        .with_min_len(CHUNK / 4)
        .map(|ray| {
            let mut count = 0;
            kernel.all_hits(f32::Ray::from_query(ray), pad, |_| count += 1);
            count
        })
        .collect()
}

/// Every crossing of each ray (local frame): the offsets of each ray's
/// hits (N + 1) and the hits, each ray's sorted by (t, prim).
pub fn list_intersections(scene: &Scene, rays: &[Ray]) -> (Vec<u64>, Vec<ListedHit>) {
    let kernel = f32::Kernel::new(scene);
    let pad = box_pad(scene);
    let per_ray: Vec<Vec<ListedHit>> = rays
        .par_iter()
        .enumerate()
        .with_min_len(CHUNK / 4)
        .map(|(i, ray)| {
            let mut hits = Vec::new();
            kernel.all_hits(f32::Ray::from_query(ray), pad, |h: f32::Hit| {
                hits.push(ListedHit {
                    ray: i as u32,
                    prim: h.prim,
                    t: h.t,
                    u: h.u,
                    v: h.v,
                })
            });
            sort_hits(&mut hits);
            hits
        })
        .collect();
    let mut splits = Vec::with_capacity(rays.len() + 1);
    splits.push(0u64);
    for hits in &per_ray {
        splits.push(splits.last().unwrap() + hits.len() as u64);
    }
    (splits, per_ray.concat())
}

/// How much the all-hits traversal grows each box (`enters_padded_box`):
/// a millionth of the scene's radius, far more than the rounding of a
/// plane's distance and far less than any box.
pub fn box_pad(scene: &Scene) -> f32 {
    (1e-6 * scene.placement().radius).max(f64::from(f32::MIN_POSITIVE)) as f32
}

/// One ray's hits in the order both paths report them: by t, then prim.
pub fn sort_hits(hits: &mut [ListedHit]) {
    hits.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
}
