//! Queries beyond the first hit as a job (`lambert query`; docs/ray-query.md,
//! "Closest points, distances and crossings"): a point file or a ray file
//! in, one record per point, ray or crossing out, written atomically. Also
//! what the CLI and the Python package share of them: the sign of a signed
//! distance and the inside test, on a `Renderer`'s queries.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use web_time::Instant;

use super::{open, say};
use crate::error::{Error, Result};
use crate::gpu::AdapterRequest;
use crate::layout::{ClosestPoint, ListedHit, NO_HIT, Ray};
use crate::output::write_atomically;
use crate::placement::WorldPoint;
use crate::progress::ProgressSink;
use crate::rays;
use crate::render::{DeviceChoice, Renderer, with_fallback};
use crate::scene::Scene;

/// A point is inside where the triangles' generalized winding number about
/// it is at least this in magnitude: 1 inside a closed mesh facing out, −1
/// inside one facing in, 0 outside, and across a hole the boundary between
/// the two. The magnitude makes inside the same whichever way a closed
/// body faces, as ray parity (Open3D's, trimesh's) has it.
pub const INSIDE_WINDING: f32 = 0.5;

/// How a signed distance tells inside from outside.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sign {
    /// The generalized winding number, at least `INSIDE_WINDING` in
    /// magnitude inside: sensible on meshes with holes or
    /// self-intersections, and on closed meshes facing either way.
    #[default]
    Winding,
    /// An odd number of crossings along a ray from the point (as Open3D
    /// does): for watertight meshes.
    Parity,
}

impl Sign {
    pub const ALL: [Sign; 2] = [Sign::Winding, Sign::Parity];

    pub fn name(self) -> &'static str {
        match self {
            Sign::Winding => "winding",
            Sign::Parity => "parity",
        }
    }
}

/// Whether each point is inside the triangles, by `sign`.
pub fn inside<P: WorldPoint>(
    renderer: &mut Renderer,
    points: &[P],
    sign: Sign,
) -> Result<Vec<bool>> {
    match sign {
        Sign::Winding => winding_inside(renderer, points, None),
        Sign::Parity => renderer.parity_inside(points),
    }
}

/// Whether each point is inside by its winding number (|w| ≥
/// `INSIDE_WINDING`): where the scene bounds a solid
/// (`Renderer::bounds_solid`), taken from the points' closest points
/// (`closest`, or found here) and their pseudo-normals, the same answer
/// for the price of the closest point, with the winding number kept for
/// the points that leaves unsure (on or very near the surface).
fn winding_inside<P: WorldPoint>(
    renderer: &mut Renderer,
    points: &[P],
    closest: Option<Vec<ClosestPoint>>,
) -> Result<Vec<bool>> {
    let inside_by_winding = |w: f32| w.abs() >= INSIDE_WINDING;
    if renderer.bounds_solid().is_err() {
        return Ok(renderer
            .winding_numbers(points)?
            .into_iter()
            .map(inside_by_winding)
            .collect());
    }
    let closest = match closest {
        Some(c) => c,
        None => renderer.closest_points(points, f32::INFINITY)?,
    };
    let sides = renderer.solid_inside(points, &closest)?;
    let unsure: Vec<usize> = (0..points.len()).filter(|&i| sides[i].is_none()).collect();
    let mut inside: Vec<bool> = sides.into_iter().map(|s| s.unwrap_or(false)).collect();
    if !unsure.is_empty() {
        let near: Vec<P> = unsure.iter().map(|&i| points[i]).collect();
        for (&i, w) in unsure.iter().zip(renderer.winding_numbers(&near)?) {
            inside[i] = inside_by_winding(w);
        }
    }
    Ok(inside)
}

/// The distance from each point to the nearest triangle.
pub fn distances<P: WorldPoint>(renderer: &mut Renderer, points: &[P]) -> Result<Vec<f32>> {
    Ok(renderer
        .closest_points(points, f32::INFINITY)?
        .iter()
        .map(|c| c.distance)
        .collect())
}

/// The distance to the nearest triangle, negative inside (by `sign`); a
/// point on the surface inside is -0.0.
pub fn signed_distances<P: WorldPoint>(
    renderer: &mut Renderer,
    points: &[P],
    sign: Sign,
) -> Result<Vec<f32>> {
    let closest = renderer.closest_points(points, f32::INFINITY)?;
    let distance: Vec<f32> = closest.iter().map(|c| c.distance).collect();
    let inside = match sign {
        Sign::Winding => winding_inside(renderer, points, Some(closest))?,
        Sign::Parity => renderer.parity_inside(points)?,
    };
    Ok(distance
        .into_iter()
        .zip(inside)
        .map(|(d, inside)| if inside { -d } else { d })
        .collect())
}

/// What `lambert query` computes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QueryKind {
    /// Of a point file.
    Points(PointQuery),
    /// Of a ray file.
    Rays(RayQuery),
}

/// A query of points, and its records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointQuery {
    /// The closest point within a max distance: a `ClosestPoint` record
    /// (32 bytes) per point.
    Closest { max_distance: f32 },
    /// The unsigned distance: an f32 per point.
    Distance,
    /// The distance, negative inside: an f32 per point.
    SignedDistance(Sign),
    /// Inside or not: a byte (1 or 0) per point.
    Inside(Sign),
}

/// A query of rays, and its records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayQuery {
    /// How many times each ray crosses the triangles: a u32 per ray.
    Count,
    /// Every crossing, by ray and then t: a `ListedHit` record (20 bytes)
    /// per crossing.
    List,
}

/// One query to run and write.
pub struct QueryJob<'a> {
    pub kind: QueryKind,
    /// The point file, or the ray file.
    pub input: &'a Path,
    pub output: &'a Path,
    pub device: DeviceChoice,
    pub adapter: &'a AdapterRequest,
}

/// What `run_query` did.
#[derive(Debug, serde::Serialize)]
pub struct QueryReport {
    pub output: PathBuf,
    /// `Renderer::describe` of the device it ran on.
    pub device: String,
    /// Points or rays read.
    pub queries: usize,
    /// Records written.
    pub records: usize,
    /// Points within the max distance, points inside, or crossings.
    pub found: usize,
    pub read_seconds: f64,
    pub query_seconds: f64,
    pub write_seconds: f64,
}

/// A query's records as bytes, how many, and how many found something.
struct Records {
    bytes: Vec<u8>,
    count: usize,
    found: usize,
}

type Work = Box<dyn Fn(&mut Renderer) -> Result<Records>>;

/// Runs `job` on `scene` and writes its records.
pub fn run_query(
    scene: Scene,
    job: &QueryJob,
    sink: Option<&dyn ProgressSink>,
) -> Result<QueryReport> {
    if scene.triangles.is_empty() {
        return Err(Error::Usage(
            "the scene has no triangles: proximity and crossing queries are over triangles".into(),
        ));
    }
    let start = Instant::now();
    let placement = scene.placement();
    // Where the file's f32 numbers limit the answers, said before the work
    // (docs/ray-query.md).
    let (queries, work, warnings): (usize, Work, _) = match job.kind {
        QueryKind::Points(query) => {
            let points = rays::read_points(job.input)?;
            let warnings = placement.point_warnings(points.len(), |i| points[i].world());
            (
                points.len(),
                Box::new(move |r| point_records(r, query, &points)),
                warnings,
            )
        }
        QueryKind::Rays(query) => {
            let rays = rays::read_rays(job.input)?;
            let warnings = placement.ray_warnings(&rays);
            (
                rays.len(),
                Box::new(move |r| ray_records(r, query, &rays)),
                warnings,
            )
        }
    };
    let read_seconds = start.elapsed().as_secs_f64();
    for warning in warnings {
        say(sink, &format!("warning: {warning}"));
    }
    // Held until the queries are done: a GPU renderer builds the winding
    // tree (inside tests, signed distances) from the host's scene.
    let scene = Arc::new(scene);
    let (mut renderer, _) = open(Arc::clone(&scene), job.device, job.adapter, sink)?;
    // Under --accel hardware, what walks the compute BVH all the same.
    let walks_bvh = match job.kind {
        QueryKind::Points(_) => Some("closest points, distances, winding numbers and inside tests"),
        QueryKind::Rays(_) if !renderer.ray_queries().is_some_and(|s| s.serves_crossings()) => {
            Some("crossing counts and lists")
        }
        QueryKind::Rays(_) => None,
    };
    if let Some(note) = walks_bvh.and_then(|what| renderer.bvh_note(what)) {
        say(sink, &note);
    }
    if let QueryKind::Points(
        PointQuery::SignedDistance(Sign::Winding) | PointQuery::Inside(Sign::Winding),
    ) = job.kind
    {
        // Which way the signs were taken (docs/ray-query.md).
        say(
            sink,
            &match renderer.bounds_solid() {
                Ok((pieces, apart)) => format!(
                    "inside from the side of each point's closest point (the mesh is closed: \
                     {pieces} piece(s), {apart} triangle(s) crossing another or of zero area \
                     left to winding numbers), and winding numbers on and near the surface"
                ),
                Err(why) => format!("inside from winding numbers: {why}"),
            },
        );
    }
    let start = Instant::now();
    let (records, fell_back) = with_fallback(&mut renderer, job.device, &scene, work)?;
    if let Some(note) = &fell_back {
        say(sink, note);
    }
    let device = match fell_back {
        Some(_) => Renderer::Cpu(Arc::clone(&scene)).describe(),
        None => renderer.describe(),
    };
    drop(scene);
    let query_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    write_atomically(job.output, &records.bytes)?;
    Ok(QueryReport {
        output: job.output.to_path_buf(),
        device,
        queries,
        records: records.count,
        found: records.found,
        read_seconds,
        query_seconds,
        write_seconds: start.elapsed().as_secs_f64(),
    })
}

fn point_records(renderer: &mut Renderer, query: PointQuery, p: &[[f32; 3]]) -> Result<Records> {
    let floats = |v: Vec<f32>, found: usize| Records {
        bytes: bytemuck::cast_slice(&v).to_vec(),
        count: v.len(),
        found,
    };
    Ok(match query {
        PointQuery::Closest { max_distance } => {
            // The reserved word written as the format says: 0.
            let found: Vec<ClosestPoint> = renderer
                .closest_points(p, max_distance)?
                .into_iter()
                .map(|c| ClosestPoint { _pad: 0, ..c })
                .collect();
            Records {
                bytes: bytemuck::cast_slice(&found).to_vec(),
                count: found.len(),
                found: found.iter().filter(|c| c.prim != NO_HIT).count(),
            }
        }
        PointQuery::Distance => floats(distances(renderer, p)?, p.len()),
        PointQuery::SignedDistance(sign) => {
            let d = signed_distances(renderer, p, sign)?;
            let inside = d.iter().filter(|d| d.is_sign_negative()).count();
            floats(d, inside)
        }
        PointQuery::Inside(sign) => {
            let bytes: Vec<u8> = inside(renderer, p, sign)?
                .into_iter()
                .map(u8::from)
                .collect();
            let found = bytes.iter().filter(|&&b| b == 1).count();
            Records {
                count: bytes.len(),
                bytes,
                found,
            }
        }
    })
}

fn ray_records(renderer: &mut Renderer, query: RayQuery, rays: &[Ray]) -> Result<Records> {
    Ok(match query {
        RayQuery::Count => {
            let counts = renderer.count_intersections(rays)?;
            Records {
                bytes: bytemuck::cast_slice(&counts).to_vec(),
                count: counts.len(),
                found: counts.iter().map(|&c| c as usize).sum(),
            }
        }
        RayQuery::List => {
            let hits: Vec<ListedHit> = renderer.list_intersections(rays)?.hits;
            Records {
                bytes: bytemuck::cast_slice(&hits).to_vec(),
                count: hits.len(),
                found: hits.len(),
            }
        }
    })
}
