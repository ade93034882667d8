//! Geometry far from the origin (docs/accuracy.md, "Far from the origin").
//! A scene keeps its geometry in f32 relative to its offset, an f64 point
//! (world = offset + local), and each ray's origin is brought near the
//! geometry in f64 before it becomes f32: the kernels then see small
//! numbers wherever the scene and its rays are.

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use crate::layout::{Hit, NO_HIT, Ray};
use crate::limits::{MAX_LOCAL_COORDINATE, vector_text};

/// A scene is centred on its bounds only when their centre is more than
/// this many times their diagonal from the origin: nearer, f32 already
/// holds the geometry to 1e-6 of its size, and the scene's numbers (so its
/// images, bit for bit) stay as they were.
pub const CENTRE_RATIO: f64 = 8.0;

/// A ray starting farther from the scene's local origin than this many
/// times the geometry's radius starts, in f32, where it enters the sphere
/// of twice that radius: f32 holds an origin to about 6e-8 of its
/// distance, which is then at most a few radii.
pub const FAR_RATIO: f64 = 8.0;

/// How finely an f32 ray origin must be held, relative to the larger of
/// the scene's size and the ray's distance from it, for a ray query's hits
/// to be as precise as its geometry: coarser, `ray_problem` warns.
pub const ORIGIN_PRECISION: f64 = 1e-5;

/// The bits of |c|: infinity's or more where c is not finite, and in the
/// order of the magnitudes, so that the largest of many values is one
/// integer maximum, which vectorises (as `near_within` takes it).
#[inline(always)]
pub fn magnitude_bits(c: f32) -> u32 {
    c.to_bits() & (u32::MAX >> 1)
}

/// The offset a geometry with world bounds `lo`..`hi` is kept relative to:
/// the centre of the bounds where it is far (CENTRE_RATIO), else zero.
pub fn centring_offset(lo: DVec3, hi: DVec3) -> DVec3 {
    let centre = 0.5 * (lo + hi);
    if centre.is_finite() && centre.length() > CENTRE_RATIO * (hi - lo).length() {
        centre
    } else {
        DVec3::ZERO
    }
}

/// Where a scene's geometry sits: what turns world rays into the scene's
/// local f32 rays, and local hits back.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Placement {
    /// World position of the scene's local origin.
    pub offset: DVec3,
    /// Radius, about the local origin, of a sphere holding all geometry.
    pub radius: f64,
}

/// A ray query's rays in the scene's local frame, and how far along its
/// ray each origin was moved (`Placement::localize`).
pub struct LocalRays<'a> {
    pub rays: Cow<'a, [Ray]>,
    /// Per ray; empty where no origin moved.
    pub shifts: Vec<f64>,
}

impl LocalRays<'_> {
    /// The hits of `rays` on the rays as given: each t plus its shift.
    pub fn to_world(&self, hits: &mut [Hit]) {
        if !self.shifts.is_empty() {
            hits.par_iter_mut()
                .zip(&self.shifts)
                .for_each(|(hit, &shift)| *hit = world_hit(*hit, shift));
        }
    }
}

/// A local hit on a ray whose origin was moved `shift` along it, on the
/// ray as given: t + shift, in f64 then rounded once. A t beyond f32's
/// range is a miss (`Placement::ray_problem` warns of it beforehand).
#[inline]
pub fn world_hit(hit: Hit, shift: f64) -> Hit {
    if hit.prim == NO_HIT || shift == 0.0 {
        return hit;
    }
    let t = (hit.t as f64 + shift) as f32;
    if t.is_finite() {
        Hit { t, ..hit }
    } else {
        Hit::MISS
    }
}

impl Placement {
    /// The ray from world `origin` along `dir` over (`tmin`, `tmax`), all in
    /// f64, as the local f32 ray the kernels trace, and the distance
    /// (in units of `dir`) its origin was moved along it: a local hit at t
    /// is at t + shift on the ray as given (`world_hit`). A ray that cannot
    /// reach the geometry comes back as one that hits nothing (tmin = tmax
    /// = 0). See `place`.
    #[inline]
    pub fn local_ray(&self, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> (Ray, f64) {
        match self.place(origin, dir, tmin, tmax) {
            Some((o, tmin, tmax, shift)) => (f32_ray(o, dir, tmin, tmax), shift),
            None => (f32_ray(DVec3::ZERO, dir, 0.0, 0.0), 0.0),
        }
    }

    /// `local_ray` in f64 (the oracle's): the local origin, tmin, tmax and
    /// the shift; None where the ray cannot reach the geometry. An origin
    /// within FAR_RATIO radii stays where it is (shift 0); one beyond moves
    /// to where the ray enters the sphere of twice the radius, which every
    /// hit lies beyond.
    #[inline]
    pub fn place(
        &self,
        origin: DVec3,
        dir: DVec3,
        tmin: f64,
        tmax: f64,
    ) -> Option<(DVec3, f64, f64, f64)> {
        let o = origin - self.offset;
        if self.is_near(o) {
            return Some((o, tmin, tmax, 0.0));
        }
        // The near root of |o + t·d|² = r² in the stable form (as
        // `intersect_sphere`): o is outside, so it is c/q with q > 0 where
        // the ray looks towards the sphere (b < 0).
        let r = 2.0 * self.radius;
        let (a, b) = (dir.length_squared(), o.dot(dir));
        let off_axis = o - (b / a) * dir;
        let discriminant = a * (r * r - off_axis.length_squared());
        if discriminant < 0.0 || b >= 0.0 {
            return None;
        }
        let entry = (o.length_squared() - r * r) / (-b + discriminant.sqrt());
        (entry < tmax).then(|| {
            (
                o + entry * dir,
                (tmin - entry).max(0.0),
                tmax - entry,
                entry,
            )
        })
    }

    /// `local_ray` where the origin stays where it is (shift 0: within
    /// FAR_RATIO radii), else None: the usual ray, without `place`'s
    /// search for where a far one enters.
    #[inline]
    pub fn near_ray(&self, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> Option<Ray> {
        let o = origin - self.offset;
        self.is_near(o).then(|| f32_ray(o, dir, tmin, tmax))
    }

    /// Whether an origin `o` (relative to the offset) stays where it is.
    #[inline]
    fn is_near(&self, o: DVec3) -> bool {
        o.length_squared() <= self.reach_squared()
    }

    /// The square of how far from the offset an origin stays where it is
    /// (`is_near`).
    pub fn reach_squared(&self) -> f64 {
        let reach = FAR_RATIO * self.radius;
        reach * reach
    }

    /// `local_ray` for every ray of a query given in world f32 (a ray
    /// file): the rays themselves, unchanged, where the scene is not
    /// centred and none starts far.
    pub fn localize<'a>(&self, rays: &'a [Ray]) -> LocalRays<'a> {
        if self.offset == DVec3::ZERO && !rays.par_iter().any(|r| self.is_far(r)) {
            return LocalRays {
                rays: Cow::Borrowed(rays),
                shifts: Vec::new(),
            };
        }
        let (local, shifts): (Vec<Ray>, Vec<f64>) = rays
            .par_iter()
            .map(|r| {
                let (o, d) = (world(r.origin), world(r.dir));
                self.local_ray(o, d, r.tmin as f64, r.tmax as f64)
            })
            .unzip();
        LocalRays {
            rays: Cow::Owned(local),
            shifts,
        }
    }

    /// `localize` for a chunk of rays, on this thread: None where every
    /// ray stays as it is (the usual case, which then costs no copy).
    /// Inlined, so that the usual case's one pass takes the caller's
    /// vector instructions (`with_simd`: 3% of the CLI's camera rays as a
    /// scalar call).
    #[inline(always)]
    pub fn localize_chunk(&self, rays: &[Ray]) -> Option<(Vec<Ray>, Vec<f64>)> {
        match self.all_near(rays) {
            true => None,
            false => self.localize_rays(rays),
        }
    }

    /// `localize_chunk` where the largest coordinate could not tell.
    #[inline(never)]
    fn localize_rays(&self, rays: &[Ray]) -> Option<(Vec<Ray>, Vec<f64>)> {
        if self.offset == DVec3::ZERO && !rays.iter().any(|r| self.is_far(r)) {
            return None;
        }
        Some(
            rays.iter()
                .map(|r| {
                    self.local_ray(world(r.origin), world(r.dir), r.tmin as f64, r.tmax as f64)
                })
                .unzip(),
        )
    }

    /// Whether every origin of `rays` is near (`is_near`), as their
    /// largest coordinate bounds them (`near_within`): one pass without a
    /// branch a ray, where the usual chunk is near, over each ray's eight
    /// values at once (the origins' taken after), which vectorises.
    /// False where that cannot tell (a far or non-finite origin).
    #[inline(always)]
    fn all_near(&self, rays: &[Ray]) -> bool {
        let lanes = rays.iter().fold([0u32; 8], |m, r| {
            let values: [f32; 8] = bytemuck::cast(*r);
            std::array::from_fn(|k| m[k].max(magnitude_bits(values[k])))
        });
        self.near_within(f32::from_bits(lanes[..3].iter().copied().fold(0, u32::max)))
    }

    /// Whether every world f32 origin with coordinates within ±`largest`
    /// is near, and needs no move (`localize_chunk`): the scene not being
    /// centred, and √3 times `largest` (NaN: false) within FAR_RATIO
    /// radii.
    pub fn near_within(&self, largest: f32) -> bool {
        let largest = largest as f64;
        // `is_near`'s sum, each square the largest's (rounding keeps the
        // order, so the bound holds as computed).
        let square = largest * largest;
        self.offset == DVec3::ZERO && square + square + square <= self.reach_squared()
    }

    /// Whether a world f32 ray's origin (the scene not being centred) is
    /// beyond FAR_RATIO radii.
    fn is_far(&self, r: &Ray) -> bool {
        !self.is_near(world(r.origin))
    }

    /// What limits the precision of a query ray from `origin` along `dir`
    /// (world, f64), if anything: an origin given in f32 (`in_f32`) more
    /// coarsely than ORIGIN_PRECISION of the larger of the scene's size
    /// and the ray's distance from it (a sensor a few units from a mesh
    /// placed at 1e8, where f32 spaces values 8 apart), or hits beyond
    /// f32's largest t (reported as misses).
    pub fn ray_problem(&self, origin: DVec3, dir: DVec3, in_f32: bool) -> Option<RayProblem> {
        let local = origin - self.offset;
        if in_f32 && let Some(coarse) = self.coarse_in_f32(origin, "origin", "hits") {
            return Some(RayProblem::CoarseOrigin(format!(
                "{coarse} (give origins in f64, as the Python package takes them)"
            )));
        }
        let last = (local.length() + 2.0 * self.radius) / dir.length();
        if last > f32::MAX as f64 && self.radius > 0.0 {
            return Some(RayProblem::BeyondT(format!(
                "the scene lies up to t = {last:.3e} along it, beyond f32's largest t \
                 ({:e}): a hit there is reported as a miss",
                f32::MAX
            )));
        }
        None
    }

    /// Whether no ray can have a `ray_problem` whose origin's coordinates
    /// are all within ±`origin_max` and whose direction has an axis at
    /// least `dir_min` long (a bound over a chunk of rays, so that a query
    /// checks ray by ray only the chunks it cannot clear at once). False
    /// where it cannot tell (NaN, a zero direction).
    pub fn rays_clear(&self, origin_max: f64, dir_min: f64, in_f32: bool) -> bool {
        // f32's spacing grows with the magnitude, and `coarse_in_f32`'s
        // scale is at least the scene's size.
        let magnitude = origin_max as f32;
        let spacing = (magnitude.next_up() - magnitude) as f64;
        let fine = !in_f32 || spacing <= ORIGIN_PRECISION * 2.0 * self.radius;
        // |origin − offset| ≤ √3·origin_max + |offset| and |dir| ≥ dir_min;
        // half f32's largest t leaves room for rounding.
        let last = (2.0 * origin_max + self.offset.length() + 2.0 * self.radius) / dir_min;
        fine && last <= f32::MAX as f64 / 2.0
    }

    /// Where a world position given in f32 is held more coarsely than
    /// ORIGIN_PRECISION of the larger of the scene's size and the
    /// position's distance from it: what it says of the `what` (a ray's
    /// origin, a query point) and of its `answers`.
    fn coarse_in_f32(&self, position: DVec3, what: &str, answers: &str) -> Option<String> {
        let magnitude = position.abs().max_element() as f32;
        let spacing = (magnitude.next_up() - magnitude) as f64;
        let scale = (2.0 * self.radius).max((position - self.offset).length());
        (spacing > ORIGIN_PRECISION * scale).then(|| {
            format!(
                "its {what} {} is given in f32, which spaces values {spacing} apart \
                 there, more than {ORIGIN_PRECISION:e} of the scene's size or distance \
                 ({scale:.3}): its {answers} are no more precise than its {what}",
                vector_text(position)
            )
        })
    }

    /// `ray_problem` over a query given in world f32: one warning per kind
    /// of problem, naming the first ray with it and how many have it.
    pub fn ray_warnings(&self, rays: &[Ray]) -> Vec<String> {
        self.warnings_for(rays.len(), true, |i| {
            (world(rays[i].origin), world(rays[i].dir))
        })
    }

    /// `ray_warnings` over `n` rays, ray i's world origin and direction
    /// being `ray(i)` (in f64), their origins given in f32 if `in_f32`.
    pub fn warnings_for(
        &self,
        n: usize,
        in_f32: bool,
        ray: impl Fn(usize) -> (DVec3, DVec3) + Sync,
    ) -> Vec<String> {
        grouped_warnings("ray", n, |i| {
            let (origin, dir) = ray(i);
            self.ray_problem(origin, dir, in_f32)
        })
    }

    /// The warnings of the problems a query's rays were found to have, in
    /// order of the ray (as `warnings_for` words them).
    pub fn ray_problem_warnings(&self, problems: Vec<(usize, RayProblem)>) -> Vec<String> {
        grouped("ray", problems)
    }

    /// The warning of a point query given in world f32 (a point file,
    /// float32 arrays), if any: where f32 holds points more coarsely than
    /// the scene's precision (a point near a mesh placed at 1e8, where f32
    /// spaces values 8 apart), naming the first such point and how many
    /// are; point i being `point(i)` (widened exactly to f64).
    pub fn point_warnings(&self, n: usize, point: impl Fn(usize) -> DVec3 + Sync) -> Vec<String> {
        grouped_warnings("point", n, |i| {
            self.coarse_in_f32(point(i), "position", "answers")
                .map(|coarse| {
                    RayProblem::CoarseOrigin(format!(
                        "{coarse} (give points in f64, as the Python package takes them)"
                    ))
                })
        })
    }
}

/// `problem` over items 0..n (`what`s: rays or points): one warning per
/// kind of problem, naming the first item with it and how many have it.
fn grouped_warnings(
    what: &str,
    n: usize,
    problem: impl Fn(usize) -> Option<RayProblem> + Sync,
) -> Vec<String> {
    let problems: Vec<(usize, RayProblem)> = (0..n)
        .into_par_iter()
        .filter_map(|i| problem(i).map(|p| (i, p)))
        .collect();
    grouped(what, problems)
}

/// One warning per kind of `problems` (in order of the item), naming the
/// first item with it and how many have it.
fn grouped(what: &str, problems: Vec<(usize, RayProblem)>) -> Vec<String> {
    let mut first: Vec<(usize, RayProblem, usize)> = Vec::new();
    for (i, problem) in problems {
        let kind = std::mem::discriminant(&problem);
        match first
            .iter_mut()
            .find(|f| std::mem::discriminant(&f.1) == kind)
        {
            Some(f) => f.2 += 1,
            None => first.push((i, problem, 1)),
        }
    }
    first
        .into_iter()
        .map(|(i, problem, count)| match count {
            1 => format!("{what} {i}: {}", problem.text()),
            _ => format!(
                "{what} {i} (and {} more like it): {}",
                count - 1,
                problem.text()
            ),
        })
        .collect()
}

/// What `Placement::ray_problem` found, and its message.
#[derive(Clone, Debug, PartialEq)]
pub enum RayProblem {
    /// The f32 origin is coarser than the geometry's precision.
    CoarseOrigin(String),
    /// Hits would lie beyond f32's largest t.
    BeyondT(String),
}

impl RayProblem {
    pub fn text(&self) -> &str {
        match self {
            RayProblem::CoarseOrigin(text) | RayProblem::BeyondT(text) => text,
        }
    }
}

/// A world point as a query gives it: f32 (a point file, float32 arrays)
/// or f64 (float64 arrays), taken exactly into f64 to be moved into the
/// scene's frame, so that f64 points keep their precision far from the
/// origin.
pub trait WorldPoint: Copy + Send + Sync + std::fmt::Debug {
    fn world(self) -> DVec3;
}

impl WorldPoint for [f32; 3] {
    fn world(self) -> DVec3 {
        world(self)
    }
}

impl WorldPoint for [f64; 3] {
    fn world(self) -> DVec3 {
        DVec3::from(self)
    }
}

fn world(v: [f32; 3]) -> DVec3 {
    DVec3::from(v.map(f64::from))
}

#[inline]
fn f32_ray(origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> Ray {
    Ray {
        origin: origin.as_vec3().to_array(),
        tmin: tmin as f32,
        dir: dir.as_vec3().to_array(),
        tmax: tmax as f32,
    }
}

/// `world` − `offset`, unless beyond MAX_LOCAL_COORDINATE on an axis.
pub(crate) fn checked_local(field: &str, world: DVec3, offset: DVec3) -> Result<DVec3, String> {
    let local = world - offset;
    if local.abs().max_element() > MAX_LOCAL_COORDINATE {
        return Err(format!(
            "{field} = {} is {} from the scene's centre {}: at most \
             {MAX_LOCAL_COORDINATE:e} on each axis is supported",
            vector_text(world),
            vector_text(local),
            vector_text(offset)
        ));
    }
    Ok(local)
}
