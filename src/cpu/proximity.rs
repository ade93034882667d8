//! The CPU path's geometric queries (docs/ray-query.md): closest points,
//! winding numbers and every hit along rays, points and rays in parallel
//! chunks, in the scene's local frame (the engine, `render`, moves world
//! points and rays into it and the answers back).

use glam::Vec3;
use rayon::prelude::*;

use super::closest::{closest_point, query_margin};
use super::f32;
use super::precision::Scalar;
use super::prefetch::prefetch_rows;
use super::query::SharedOut;
use super::simd::{CpuKernel, check_runs, with_simd};
use super::winding::winding_number;
use crate::bvh::Sides;
use crate::layout::{ClosestPoint, ListedHit, NO_HIT, Ray};
use crate::scene::Scene;

/// Points per parallel task: enough to amortise the task, few enough to
/// balance two to a few dozen threads.
const CHUNK: usize = 1024;

/// The points' indices in Morton order over their bounding box (10 bits
/// an axis): queries taken in this order touch the same nodes and leaves
/// one after another, which keeps them in cache, and each closest-point
/// query starts from its predecessor's triangle (`closest_points`). The
/// answers do not depend on the order.
pub fn spatial_order(points: &[[f32; 3]]) -> Vec<u32> {
    let (lo, hi) = points
        .par_iter()
        .fold(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |(lo, hi), &p| (lo.min(Vec3::from(p)), hi.max(Vec3::from(p))),
        )
        .reduce(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let scale = Vec3::splat(1023.0) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    // Every other bit of a 10-bit number spread to every third.
    let spread = |x: u32| {
        let mut x = x & 0x3ff;
        x = (x | x << 16) & 0x0300_00ff;
        x = (x | x << 8) & 0x0300_f00f;
        x = (x | x << 4) & 0x030c_30c3;
        (x | x << 2) & 0x0924_9249
    };
    let mut keyed: Vec<(u32, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let c = ((Vec3::from(p) - lo) * scale).to_array().map(|c| c as u32);
            (
                spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2,
                i as u32,
            )
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// `f(points[i])` for every index i in `order` (a permutation of the
/// points' indices), in parallel chunks of `CHUNK` taken in order (with
/// state `init()` carried through a chunk), put back in index order. In
/// `order` the points lie far apart in memory: each is asked for
/// `AHEAD` queries before its own (8% of the dragon's closest-point
/// walk waited on the point's load without).
fn in_order<T, S>(
    points: &[[f32; 3]],
    order: &[u32],
    init: impl Fn() -> S + Sync,
    f: impl Fn(&mut S, Vec3) -> T + Sync,
) -> Vec<T>
where
    T: Send,
{
    const AHEAD: usize = 8;
    assert_eq!(order.len(), points.len());
    let mut out: Vec<T> = Vec::with_capacity(order.len());
    let shared = SharedOut::new_spare(&mut out);
    order.par_chunks(CHUNK).for_each(|chunk| {
        let mut state = init();
        for (k, &i) in chunk.iter().enumerate() {
            if let Some(&ahead) = chunk.get(k + AHEAD) {
                prefetch_rows(points.as_ptr().wrapping_add(ahead as usize), 1);
            }
            let i = i as usize;
            let value = f(&mut state, Vec3::from(points[i]));
            // SAFETY: `order` holds each index below its length once
            // (`spatial_order`), so each element is written once, by one
            // thread, within the capacity.
            unsafe { shared.at(i).write(value) };
        }
    });
    // SAFETY: every element was written above.
    unsafe { out.set_len(order.len()) };
    out
}

/// The nearest point of the scene's triangles to each point (local frame)
/// within `max_distance` (squared distance ≤ max_distance², in f32);
/// `ClosestPoint::NONE` where none is. The point comes back in the local
/// frame. Through this process's CPU kernel (`CpuKernel::active`).
pub fn closest_points(scene: &Scene, points: &[[f32; 3]], max_distance: f32) -> Vec<ClosestPoint> {
    closest_points_with(scene, points, max_distance, CpuKernel::active())
}

/// `closest_points` through `kernel`: the walk compiled for its vector
/// instructions, the same answers bit for bit (tests compare them with the
/// portable kernel's). Compiled for AVX-512, the dragon's closest points ran
/// 4–5% faster than in the portable code (docs/benchmarks.md).
///
/// # Panics
/// Where this CPU cannot run `kernel`.
pub fn closest_points_with(
    scene: &Scene,
    points: &[[f32; 3]],
    max_distance: f32,
    kernel: CpuKernel,
) -> Vec<ClosestPoint> {
    check_runs(kernel);
    let triangles = scene.triangles.len();
    let radius = scene.placement().radius as f32;
    let max_d2 = max_distance * max_distance;
    let order = spatial_order(points);
    let wide = <f32::Real as Scalar>::has_wide(kernel);
    in_order(
        points,
        &order,
        || (Vec::new(), NO_HIT),
        // SAFETY: `check_runs` checked the kernel.
        |(queue, previous), p| unsafe {
            with_simd(
                kernel,
                #[inline(always)]
                || {
                    let margin = query_margin(p.abs().max_element(), radius);
                    let hint = (*previous != NO_HIT).then(|| {
                        let t = &scene.triangles[*previous as usize];
                        (*previous, [t.v0, t.v1, t.v2].map(Vec3::from))
                    });
                    match closest_point(&scene.bvh, triangles, p, max_d2, margin, hint, queue, wide)
                    {
                        Some(n) => {
                            *previous = n.prim;
                            ClosestPoint {
                                point: n.point.to_array(),
                                prim: n.prim,
                                u: n.u,
                                v: n.v,
                                distance: n.d2.sqrt(),
                                _pad: 0,
                            }
                        }
                        None => ClosestPoint::NONE,
                    }
                },
            )
        },
    )
}

/// The generalized winding number of the scene's triangles at each point
/// (local frame), through the winding tree (built on the first call).
pub fn winding_numbers(scene: &Scene, points: &[[f32; 3]]) -> Vec<f32> {
    let tree = scene.bvh.winding_tree(scene.triangles.len());
    in_order(
        points,
        &spatial_order(points),
        || (),
        |_, p| winding_number(tree, &scene.triangles, p),
    )
}

/// Whether each point (local frame) is inside by its winding number's rule
/// (|w| ≥ 0.5), from the side of its closest point's surface it lies
/// (`bvh::Sides`; `closest`, the points' `closest_points` with no max
/// distance, gives each one's triangle): Err (why not) where the scene's
/// winding number is no integer (a mesh with a hole); None for a point
/// that lies within a few `query_margin`s of its closest point (where a
/// near tie between triangles could give the other side) or where the
/// sides decide nothing, for the winding number to decide.
pub fn solid_inside(
    scene: &Scene,
    points: &[[f32; 3]],
    closest: &[ClosestPoint],
) -> Result<Vec<Option<bool>>, String> {
    let sides = scene.bvh.sides(&scene.triangles)?;
    let radius = scene.placement().radius as f32;
    let near = |p: Vec3| f64::from(8.0 * query_margin(p.abs().max_element(), radius));
    // Each piece's winding number in front: at a point before one of its
    // triangles that has that triangle nearest, in front, and a winding
    // number within a quarter of an integer.
    // (The winding tree built here, not under `label_pieces`' parallel
    // calls, where the other threads would wait on its build.)
    let tree = scene.bvh.winding_tree(scene.triangles.len());
    sides.label_pieces(|samples| {
        samples.iter().find_map(|&t| {
            let p = Sides::in_front(&scene.triangles, t).as_vec3();
            let margin = query_margin(p.abs().max_element(), radius);
            let found = closest_point(
                &scene.bvh,
                scene.triangles.len(),
                p,
                f32::INFINITY,
                margin,
                None,
                &mut Vec::new(),
                false,
            )?;
            let ahead = sides.behind(&scene.triangles, found.prim, p.as_dvec3(), near(p));
            if found.prim != t || ahead.map(|(behind, _)| behind) != Some(false) {
                return None;
            }
            let w = winding_number(tree, &scene.triangles, p);
            ((w - w.round()).abs() < 0.25).then_some(w.round() as i32)
        })
    });
    // The points' triangles are far apart in memory, and `inside` reads
    // several rows of each in turn: the rows of the triangle AHEAD points
    // on asked for first, then, once those are in, the normals they name.
    const AHEAD: usize = 16;
    let prefetch = |i: usize, normals: bool| {
        if let Some(c) = closest.get(i) {
            for row in sides.rows(c.prim, normals) {
                prefetch_rows(row, 1);
            }
            if !normals {
                prefetch_rows(scene.triangles.as_ptr().wrapping_add(c.prim as usize), 1);
            }
        }
    };
    let mut inside = vec![None; points.len()];
    inside
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, rows)| {
            for (i, row) in (c * CHUNK..).zip(rows) {
                prefetch(i + AHEAD, false);
                prefetch(i + AHEAD / 2, true);
                let p = Vec3::from(points[i]);
                *row = sides.inside(&scene.triangles, closest[i].prim, p.as_dvec3(), near(p));
            }
        });
    Ok(inside)
}

/// How many triangles each ray (local frame) crosses in (tmin, tmax), an
/// edge or a vertex once.
pub fn count_intersections(scene: &Scene, rays: &[Ray]) -> Vec<u32> {
    let kernel = f32::Kernel::new(scene);
    let pad = box_pad(scene.placement().radius);
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
    let pad = box_pad(scene.placement().radius);
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
pub fn box_pad(scene_radius: f64) -> f32 {
    (1e-6 * scene_radius).max(f64::from(f32::MIN_POSITIVE)) as f32
}

/// One ray's hits in the order both paths report them: by t, then prim.
pub fn sort_hits(hits: &mut [ListedHit]) {
    hits.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
}
