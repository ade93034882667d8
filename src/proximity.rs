//! Geometric queries on a `Renderer` (docs/ray-query.md): closest points,
//! winding numbers and the inside tests built on them, and every hit
//! along rays, on either device. Here, what both paths share: the checks
//! of the points and rays, and their move into the scene's local frame
//! (world points and rays in, world answers out, as `trace`): points, f32
//! or f64, are moved in f64; rays given in f64 are moved by the caller
//! (`Placement::local_ray`, as `trace`'s) and passed as `LocalRays`.

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use crate::cpu;
use crate::error::{Error, Result};
use crate::layout::{ClosestPoint, NO_HIT, Ray};
use crate::limits::{MAX_LOCAL_COORDINATE, vector_text};
use crate::placement::{LocalRays, Placement, WorldPoint, world_hit};
use crate::render::{IntersectionList, Renderer};

/// The direction of `parity_inside`'s rays: Open3D's (RaycastingScene's
/// ComputeOccupancy and ComputeSignedDistance cast (1, 1, 1)).
pub const PARITY_DIRECTION: [f32; 3] = [1.0, 1.0, 1.0];

impl Renderer {
    fn placement_and_spheres(&self) -> (Placement, u32) {
        match self {
            Renderer::Gpu(r) => (r.placement, r.sphere_count()),
            Renderer::Cpu(scene) => (scene.placement(), scene.spheres.len() as u32),
        }
    }

    /// Queries are over triangles: a scene with spheres is refused.
    fn triangles_only(&self, query: &str) -> Result<Placement> {
        let (placement, spheres) = self.placement_and_spheres();
        if spheres > 0 {
            return Err(Error::Usage(format!(
                "{query} are over triangles, and this scene has {spheres} sphere(s): \
                 give spheres as meshes for this query"
            )));
        }
        Ok(placement)
    }

    /// The nearest point of the scene's triangles to each world point
    /// within `max_distance` (≥ 0; +inf for no limit): the point (world),
    /// the triangle, its (u, v) as `trace` gives them and the distance;
    /// `ClosestPoint::NONE` where no triangle is that near. Where several
    /// triangles are equally near (an edge or a vertex they share), the
    /// lowest id.
    pub fn closest_points<P: WorldPoint>(
        &mut self,
        points: &[P],
        max_distance: f32,
    ) -> Result<Vec<ClosestPoint>> {
        let placement = self.triangles_only("closest points")?;
        if max_distance.is_nan() || max_distance < 0.0 {
            return Err(Error::Usage(format!(
                "max_distance = {max_distance}: it must be 0 or more (+inf for no limit)"
            )));
        }
        let local = local_points(&placement, points)?;
        let mut answers = match self {
            Renderer::Gpu(r) => in_spatial_order(&local, |local| {
                // The CPU's cull margins, so that both cull alike.
                let radius = placement.radius as f32;
                let margins: Vec<f32> = local
                    .par_iter()
                    .map(|p| {
                        cpu::closest::query_margin(glam::Vec3::from(*p).abs().max_element(), radius)
                    })
                    .collect();
                r.closest_points(local, &margins, max_distance)
            })?,
            Renderer::Cpu(scene) => cpu::closest_points(scene, &local, max_distance),
        };
        if placement.offset != DVec3::ZERO {
            answers.par_iter_mut().for_each(|a| {
                if a.prim != NO_HIT {
                    a.point = (DVec3::from(a.point.map(f64::from)) + placement.offset)
                        .as_vec3()
                        .to_array();
                }
            });
        }
        Ok(answers)
    }

    /// The generalized winding number of the scene's triangles at each
    /// world point (Jacobson et al. 2013, through Barill et al.'s tree):
    /// 1 inside a closed, outward-facing mesh (−1 facing in), 0 outside,
    /// fractions near holes. Inside is |w| ≥ 0.5 (`jobs::inside`).
    pub fn winding_numbers<P: WorldPoint>(&mut self, points: &[P]) -> Result<Vec<f32>> {
        let placement = self.triangles_only("winding numbers")?;
        let local = local_points(&placement, points)?;
        match self {
            Renderer::Gpu(r) => in_spatial_order(&local, |local| r.winding_numbers(local)),
            Renderer::Cpu(scene) => Ok(cpu::winding_numbers(scene, &local)),
        }
    }

    /// Whether the winding number's inside test can be taken from closest
    /// points' sides (`solid_inside`): Ok where the CPU path's scene is
    /// closed (`bvh::Sides`, built on the first call: how many pieces its
    /// surface has, and how many triangles lie in none), else why not.
    pub fn bounds_solid(&self) -> std::result::Result<(usize, usize), String> {
        // A scene with spheres: refused as the winding numbers refuse it.
        self.triangles_only("inside tests")
            .map_err(|e| e.to_string())?;
        match self {
            Renderer::Gpu(_) => Err("the GPU path takes winding numbers".into()),
            Renderer::Cpu(scene) => scene
                .bvh
                .sides(&scene.triangles)
                .map(|sides| sides.counts())
                .map_err(|why| format!("the mesh is not closed: {why}")),
        }
    }

    /// Whether each world point is inside by the winding number's rule,
    /// from `closest`, its closest point (`closest_points` with no max
    /// distance), where the scene is closed (`bounds_solid`; an error
    /// where not): None for the points the sides leave unsure
    /// (`cpu::solid_inside`), for `winding_numbers` to decide.
    pub fn solid_inside<P: WorldPoint>(
        &mut self,
        points: &[P],
        closest: &[ClosestPoint],
    ) -> Result<Vec<Option<bool>>> {
        let placement = self.triangles_only("inside tests")?;
        let local = local_points(&placement, points)?;
        match self {
            Renderer::Cpu(scene) if closest.len() == points.len() => {
                cpu::solid_inside(scene, &local, closest).map_err(Error::Usage)
            }
            _ => Err(Error::Usage(format!(
                "inside tests from closest points: {}",
                self.bounds_solid()
                    .err()
                    .unwrap_or_else(|| "one closest point a point is needed".into())
            ))),
        }
    }

    /// Whether each world point is inside by parity: an odd number of
    /// crossings along a ray from it in direction `PARITY_DIRECTION`, as
    /// Open3D counts (for watertight meshes; `winding_numbers` for others).
    pub fn parity_inside<P: WorldPoint>(&mut self, points: &[P]) -> Result<Vec<bool>> {
        check_points(points)?;
        let placement = self.triangles_only("intersection counts")?;
        let dir = DVec3::from(PARITY_DIRECTION.map(f64::from));
        // Each ray starts from its point in f64 (`local_ray`, as a ray
        // given in f64): a counted crossing needs no shift back.
        let rays = points
            .par_iter()
            .map(|p| placement.local_ray(p.world(), dir, 0.0, f64::INFINITY).0)
            .collect();
        Ok(self
            .count_local_intersections(&LocalRays {
                rays: Cow::Owned(rays),
                shifts: Vec::new(),
            })?
            .into_iter()
            .map(|n| n % 2 == 1)
            .collect())
    }

    /// How many triangles each world ray crosses in (tmin, tmax), an edge
    /// or a vertex crossed once.
    pub fn count_intersections(&mut self, rays: &[Ray]) -> Result<Vec<u32>> {
        let placement = self.triangles_only("intersection counts")?;
        check_rays(rays)?;
        self.count_local_intersections(&placement.localize(rays))
    }

    /// `count_intersections` of rays already in the scene's local frame
    /// (`Placement::local_ray` of rays given in f64, checked as given).
    pub fn count_local_intersections(&mut self, local: &LocalRays) -> Result<Vec<u32>> {
        let placement = self.triangles_only("intersection counts")?;
        match self {
            Renderer::Gpu(r) => r.count_intersections(&local.rays, cpu::box_pad(placement.radius)),
            Renderer::Cpu(scene) => Ok(cpu::count_intersections(scene, &local.rays)),
        }
    }

    /// Every crossing of each world ray in (tmin, tmax), sorted by t (then
    /// triangle) per ray: ray i's are `hits[ray_splits[i]..ray_splits[i +
    /// 1]]`.
    pub fn list_intersections(&mut self, rays: &[Ray]) -> Result<IntersectionList> {
        let placement = self.triangles_only("intersection lists")?;
        check_rays(rays)?;
        self.list_local_intersections(&placement.localize(rays))
    }

    /// `list_intersections` of rays already in the scene's local frame
    /// (`Placement::local_ray`, checked as given), each t on the ray as
    /// given (plus its shift, in f64).
    pub fn list_local_intersections(&mut self, local: &LocalRays) -> Result<IntersectionList> {
        let placement = self.triangles_only("intersection lists")?;
        let (ray_splits, mut hits) = match self {
            Renderer::Gpu(r) => {
                let (splits, mut hits) =
                    r.list_intersections(&local.rays, cpu::box_pad(placement.radius))?;
                // In the order the device found them: sorted as the CPU's.
                let mut rest = hits.as_mut_slice();
                for w in splits.windows(2) {
                    let (ray, after) = rest.split_at_mut((w[1] - w[0]) as usize);
                    cpu::sort_hits(ray);
                    rest = after;
                }
                (splits, hits)
            }
            Renderer::Cpu(scene) => cpu::list_intersections(scene, &local.rays),
        };
        if !local.shifts.is_empty() {
            hits.par_iter_mut().for_each(|h| {
                h.t = world_hit(
                    crate::layout::Hit {
                        t: h.t,
                        prim: h.prim,
                        u: h.u,
                        v: h.v,
                    },
                    local.shifts[h.ray as usize],
                )
                .t
            });
        }
        Ok(IntersectionList { ray_splits, hits })
    }
}

/// `query` of the points taken in Morton order (`cpu::spatial_order`:
/// neighbouring invocations then walk the same nodes, which keeps them in
/// the device's caches), its answers put back in the points' order.
fn in_spatial_order<T: Copy + Send + Sync>(
    points: &[[f32; 3]],
    query: impl FnOnce(&[[f32; 3]]) -> Result<Vec<T>>,
) -> Result<Vec<T>> {
    let order = cpu::spatial_order(points);
    let sorted: Vec<[f32; 3]> = order.par_iter().map(|&i| points[i as usize]).collect();
    let answers = query(&sorted)?;
    let mut out = answers.clone();
    for (&i, &a) in order.iter().zip(&answers) {
        out[i as usize] = a;
    }
    Ok(out)
}

/// Every point finite, or an error naming the first that is not.
fn check_points<P: WorldPoint>(points: &[P]) -> Result<()> {
    match points.par_iter().position_first(|p| !p.world().is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::Usage(format!(
            "point {i}: {:?} is not finite (NaN or infinite)",
            points[i]
        ))),
    }
}

/// The rays as `trace` takes them, or an error naming the first bad one.
fn check_rays(rays: &[Ray]) -> Result<()> {
    crate::rays::validate_rays(rays).map_err(|bad| Error::Usage(bad.to_string()))
}

/// The world points in the scene's local frame (in f64, then rounded
/// once), or an error naming the first that is not finite or lies so far
/// from the scene that f32 squares of its distance would overflow.
fn local_points<P: WorldPoint>(placement: &Placement, points: &[P]) -> Result<Vec<[f32; 3]>> {
    check_points(points)?;
    let local = |p: &P| p.world() - placement.offset;
    if let Some(i) = points
        .par_iter()
        .position_first(|p| local(p).abs().max_element() > MAX_LOCAL_COORDINATE)
    {
        return Err(Error::Usage(format!(
            "point {i}: {} is more than {MAX_LOCAL_COORDINATE:e} from the scene's centre {} \
             along an axis: its distance cannot be given in f32",
            vector_text(points[i].world()),
            vector_text(placement.offset)
        )));
    }
    Ok(points
        .par_iter()
        .map(|p| local(p).as_vec3().to_array())
        .collect())
}
