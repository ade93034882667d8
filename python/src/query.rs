//! A ray query's rays as the caller gave them, read a ray at a time, and
//! the frame they are traced in: float32 origins (and ray records) as
//! world rays (the library moves far ones into the scene's frame from
//! f32), float64 origins moved into the scene's frame in f64 before they
//! become f32 (`Placement::local_ray`), so a mesh far from the origin is
//! hit as precisely as one at it.

use std::mem::MaybeUninit;
use std::ops::Range;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use lambert::cpu::{Filled, pack_rays, prefetch_rows};
use lambert::layout::{Hit, NO_HIT, Ray};
use lambert::placement::{Placement, RayProblem, magnitude_bits, world_hit};
use lambert::{Error, rays};

use crate::arrays::{Bound1View, RowsView};

/// A query's rays as the caller gave them: records (still to be
/// checked), or arrays read a ray at a time.
#[derive(Clone, Copy)]
pub enum Query<'a> {
    Records(&'a [Ray]),
    Arrays {
        origins: RowsView<'a>,
        directions: RowsView<'a>,
        tmin: Bound1View<'a>,
        tmax: Bound1View<'a>,
        n: usize,
        /// The scene's placement where the origins are float64: each ray is
        /// then traced in the scene's frame (`local_ray`); None for float32
        /// origins, which f32 already holds as given.
        local: Option<Placement>,
    },
}

impl Query<'_> {
    pub fn len(&self) -> usize {
        match self {
            Query::Records(r) => r.len(),
            Query::Arrays { n, .. } => *n,
        }
    }

    /// Starts loading rays `rows` as given (`QueryRays::Fill`'s ahead):
    /// records, and packed origins and directions.
    #[inline]
    pub fn prefetch(&self, rows: Range<usize>) {
        match self {
            Query::Records(r) => {
                let first = rows.start.min(r.len());
                prefetch_rows(r[first..].as_ptr(), rows.len().min(r.len() - first));
            }
            Query::Arrays {
                origins,
                directions,
                ..
            } => {
                for view in [origins, directions] {
                    match view {
                        RowsView::PackedF32(a) => prefetch_packed(a, &rows),
                        RowsView::PackedF64(a) => prefetch_packed(a, &rows),
                        // Strided rows are rare; left to the CPU.
                        RowsView::F32(_) | RowsView::F64(_) => {}
                    }
                }
            }
        }
    }

    /// The placement its rays are moved into the scene's frame by, when
    /// they are traced as local rays (float64 origins).
    pub fn local(&self) -> Option<&Placement> {
        match self {
            Query::Arrays { local, .. } => local.as_ref(),
            Query::Records(_) => None,
        }
    }

    /// Ray `i` as given, in world f32 (what is checked and named in
    /// errors).
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        match self {
            Query::Records(r) => r[i],
            Query::Arrays {
                origins,
                directions,
                tmin,
                tmax,
                ..
            } => Ray {
                // The one place an origin row (read in f64) becomes f32.
                origin: origins.row_f64(i).map(|c| c as f32),
                tmin: tmin.at(i) as f32,
                dir: directions.row(i),
                tmax: tmax.at(i) as f32,
            },
        }
    }

    /// Ray `i` as given, in f64: origin, direction, tmin, tmax.
    fn ray_f64(&self, i: usize) -> (DVec3, DVec3, f64, f64) {
        match self {
            Query::Records(r) => {
                let widen = |v: [f32; 3]| DVec3::from(v.map(f64::from));
                let r = r[i];
                (widen(r.origin), widen(r.dir), r.tmin as f64, r.tmax as f64)
            }
            Query::Arrays {
                origins,
                directions,
                tmin,
                tmax,
                ..
            } => (
                DVec3::from(origins.row_f64(i)),
                DVec3::from(directions.row_f64(i)),
                tmin.at(i),
                tmax.at(i),
            ),
        }
    }

    /// Ray `i`'s hit `traced` (as the tracer returned it) on the ray as
    /// given: the hit, t rounded once to f32 (a miss beyond f32's t, as
    /// `world_hit` has it), and t in f64 (the local t plus the shift,
    /// unrounded: a location from it is as precise as the trace).
    #[inline]
    pub fn world_hit(&self, i: usize, traced: Hit) -> (Hit, f64) {
        match self.local() {
            Some(placement) if traced.prim != NO_HIT => {
                let shift = self.shift(placement, i);
                (world_hit(traced, shift), traced.t as f64 + shift)
            }
            _ => (traced, traced.t as f64),
        }
    }

    /// How far along ray `i` its origin moved into the scene's frame
    /// (`local_ray`'s shift, without the local ray).
    #[inline]
    fn shift(&self, placement: &Placement, i: usize) -> f64 {
        let (origin, dir, tmin, tmax) = self.ray_f64(i);
        placement
            .place(origin, dir, tmin, tmax)
            .map_or(0.0, |(.., shift)| shift)
    }

    /// How far along its ray each origin moved into the scene's frame
    /// (`local_ray`'s shift), ray by ray.
    pub fn shifts(&self, placement: &Placement) -> Vec<f64> {
        use rayon::prelude::*;
        (0..self.len())
            .into_par_iter()
            .map(|i| self.shift(placement, i))
            .collect()
    }

    /// Writes rays start.. into all of `out` as they are traced (world,
    /// or local where `local`), checking each as given and noting the
    /// chunk's precision problems in `problems`: per chunk, so the usual
    /// arrays (packed rows, scalar bounds) take a loop of their own, with
    /// no choice of layout per ray.
    #[inline(always)]
    pub fn fill(
        &self,
        start: usize,
        out: &mut [MaybeUninit<Ray>],
        first_bad: &FirstBad,
        problems: &Problems,
    ) -> Filled {
        if let Query::Records(r) = *self {
            let rays = &r[start..start + out.len()];
            for (slot, ray) in out.iter_mut().zip(rays) {
                slot.write(*ray);
            }
            self.check_records(start, rays, first_bad, problems);
            // Traced as given, in the world's frame.
            return Filled::AsGiven;
        }
        if let Query::Arrays {
            origins: RowsView::PackedF32(o),
            directions: RowsView::PackedF32(d),
            tmin: Bound1View::All(tmin),
            tmax: Bound1View::All(tmax),
            local: None,
            ..
        } = *self
        {
            let (tmin, tmax) = (tmin as f32, tmax as f32);
            let rows = start * 3..(start + out.len()) * 3;
            let (o, d) = (&o[rows.clone()], &d[rows]);
            // Over the flat rows, in loops that vectorise: the largest
            // magnitude's bits, which are infinity's or more where a
            // coordinate is not finite; so the origins' largest
            // coordinate (as `Placement::rays_clear` takes it) comes too.
            let largest = |a: &[f32]| a.iter().copied().map(magnitude_bits).fold(0, u32::max);
            let (origin_bits, dir_bits) = (largest(o), largest(d));
            let infinite = f32::INFINITY.to_bits();
            let mut valid = (origin_bits < infinite)
                & (dir_bits < infinite)
                & rays::bounds_are_valid(tmin, tmax);
            // The chunk's shortest longest direction axis (meaningful
            // where every value is finite: where the chunk is valid).
            let dir_min = pack_rays(o, d, tmin, tmax, out);
            valid &= rays::direction_lengths_are_valid(dir_min, f32::from_bits(dir_bits));
            if valid {
                let rows = start..start + out.len();
                let origin_max = f32::from_bits(origin_bits);
                problems.check(self, rows, origin_max as f64, dir_min as f64);
                // Traced as given, in the world's frame: moved by the
                // trace where some origin may be far.
                return match problems.placement.near_within(origin_max) {
                    true => Filled::Near,
                    false => Filled::AsGiven,
                };
            }
        }
        // float64 origins in packed rows with scalar bounds: the chunk at
        // once where every ray is valid and none moves, else the general
        // loop below, compiled for that layout.
        if let Query::Arrays {
            origins: RowsView::PackedF64(o),
            directions,
            tmin: Bound1View::All(tmin),
            tmax: Bound1View::All(tmax),
            local: Some(placement),
            ..
        } = *self
        {
            let rows = start * 3..(start + out.len()) * 3;
            let near = match directions {
                RowsView::PackedF64(d) => {
                    fill_near(&placement, &o[rows.clone()], &d[rows], tmin, tmax, out)
                }
                RowsView::PackedF32(d) => {
                    fill_near(&placement, &o[rows.clone()], &d[rows], tmin, tmax, out)
                }
                _ => None,
            };
            if let Some((origin_max, dir_min)) = near {
                problems.check(self, start..start + out.len(), origin_max, dir_min);
                return Filled::AsGiven;
            }
            match directions {
                RowsView::PackedF64(d) => {
                    return self.fill_from(start, out, first_bad, problems, |i| {
                        let row = |a: &[f64]| DVec3::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
                        (row(o), row(d), tmin, tmax)
                    });
                }
                RowsView::PackedF32(d) => {
                    return self.fill_from(start, out, first_bad, problems, |i| {
                        let dir = [d[3 * i], d[3 * i + 1], d[3 * i + 2]].map(f64::from);
                        let origin = DVec3::new(o[3 * i], o[3 * i + 1], o[3 * i + 2]);
                        (origin, DVec3::from(dir), tmin, tmax)
                    });
                }
                _ => {}
            }
        }
        self.fill_from(start, out, first_bad, problems, |i| self.ray_f64(i))
    }

    /// Checks records start.. (`rays`) as `fill` checks arrays: each ray's
    /// validity (`FirstBad`), and the chunk's precision problems.
    fn check_records(&self, start: usize, rays: &[Ray], first_bad: &FirstBad, problems: &Problems) {
        // As the packed float32 rows' loop: the largest magnitudes' bits
        // (infinity's or more where a value is not finite), the shortest
        // longest direction axis compared plainly, each ray's bounds; the
        // rays one by one only where the chunk fails.
        let (mut origin_bits, mut dir_bits, mut dir_min) = (0, 0, f32::INFINITY);
        let mut bounds = true;
        for ray in rays {
            origin_bits = ray
                .origin
                .map(magnitude_bits)
                .into_iter()
                .fold(origin_bits, u32::max);
            dir_bits = ray
                .dir
                .map(magnitude_bits)
                .into_iter()
                .fold(dir_bits, u32::max);
            let longest = longest_axis(ray.dir);
            dir_min = if longest < dir_min { longest } else { dir_min };
            bounds &= rays::bounds_are_valid(ray.tmin, ray.tmax);
        }
        let infinite = f32::INFINITY.to_bits();
        let valid = (origin_bits < infinite)
            & (dir_bits < infinite)
            & bounds
            & rays::direction_lengths_are_valid(dir_min, f32::from_bits(dir_bits));
        if !valid {
            for (i, ray) in (start..).zip(rays) {
                first_bad.check(ray, i);
            }
        }
        let origin_max = f32::from_bits(origin_bits) as f64;
        problems.check(self, start..start + rays.len(), origin_max, dir_min as f64);
    }

    /// `fill`'s loop, ray i being `ray(i)` as given in f64 (`ray_f64`).
    #[inline(always)]
    fn fill_from(
        &self,
        start: usize,
        out: &mut [MaybeUninit<Ray>],
        first_bad: &FirstBad,
        problems: &Problems,
        ray: impl Fn(usize) -> (DVec3, DVec3, f64, f64),
    ) -> Filled {
        let (mut origin_max, mut dir_min) = (0.0f64, f64::INFINITY);
        let mut moved = false;
        let len = out.len();
        for (i, slot) in (start..).zip(out) {
            let (origin, dir, tmin, tmax) = ray(i);
            // As given, in f32 (`ray`): what is checked.
            let world = Ray {
                origin: origin.as_vec3().to_array(),
                tmin: tmin as f32,
                dir: dir.as_vec3().to_array(),
                tmax: tmax as f32,
            };
            first_bad.check(&world, i);
            slot.write(match self.local() {
                Some(placement) => {
                    let (ray, shift) = placement.local_ray(origin, dir, tmin, tmax);
                    moved |= shift != 0.0;
                    ray
                }
                None => world,
            });
            origin_max = origin_max.max(origin.abs().max_element());
            dir_min = dir_min.min(dir.abs().max_element());
        }
        problems.check(self, start..start + len, origin_max, dir_min);
        match moved {
            true => Filled::Moved,
            false => Filled::AsGiven,
        }
    }

    /// The rays in one buffer (what a GPU uploads), checked: records as
    /// they are, arrays assembled into `buffer` in one parallel pass.
    pub fn gathered(
        &self,
        mut buffer: Vec<Ray>,
        problems: &Problems,
    ) -> Result<Gathered<'_>, Error> {
        use rayon::prelude::*;
        const CHUNK: usize = 4096;
        if let Query::Records(r) = *self {
            let first_bad = FirstBad::new();
            r.par_chunks(CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| self.check_records(c * CHUNK, chunk, &first_bad, problems));
            first_bad.result(self)?;
            return Ok(Gathered::Records(r));
        }
        let n = self.len();
        let first_bad = FirstBad::new();
        buffer.clear();
        buffer.reserve(n);
        buffer.spare_capacity_mut()[..n]
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                self.fill(c * CHUNK, chunk, &first_bad, problems);
            });
        // SAFETY: every one of the n slots was written above.
        unsafe { buffer.set_len(n) };
        first_bad.result(self)?;
        Ok(Gathered::Buffer(buffer))
    }
}

/// A direction's longest axis in magnitude, compared plainly (its values
/// finite where it counts: a chunk with one that is not fails anyway).
#[inline(always)]
fn longest_axis(d: [f32; 3]) -> f32 {
    let [x, y, z] = d.map(f32::abs);
    let longest = if x > y { x } else { y };
    if longest > z { longest } else { z }
}

/// Starts loading the packed rows (three values a ray) of rays `rows`.
#[inline]
fn prefetch_packed<T>(all: &[T], rows: &Range<usize>) {
    let first = (rows.start * 3).min(all.len());
    prefetch_rows(
        all[first..].as_ptr(),
        (rows.len() * 3).min(all.len() - first),
    );
}

/// Writes the local rays of packed float64 `origins` and `directions`
/// (float64 or float32 rows) over (`tmin`, `tmax`) into `out`, where the
/// chunk's rays are all valid (as `FirstBad` checks them in f32) and none
/// moves (`Placement::near_ray`): the usual query, at once. Returns the
/// origins' largest coordinate and the directions' shortest longest axis
/// (`Problems::check`'s), or None where some ray needs the general loop.
#[inline(always)]
fn fill_near<D: Copy + Into<f64>>(
    placement: &Placement,
    origins: &[f64],
    directions: &[D],
    tmin: f64,
    tmax: f64,
    out: &mut [MaybeUninit<Ray>],
) -> Option<(f64, f64)> {
    // Magnitudes compared as their bits (the same order for finite
    // values; infinity's or more where one is not finite), in loops
    // without a branch a ray, which vectorise.
    let magnitude = |v: f64| v.to_bits() & (u64::MAX >> 1);
    let origin_max = f64::from_bits(origins.iter().fold(0, |m, &c| m.max(magnitude(c))));
    let (offset, reach) = (placement.offset.to_array(), placement.reach_squared());
    let (mut near, mut dir_min, mut dir_max) = (true, u64::MAX, 0u64);
    for (slot, (o, d)) in out
        .iter_mut()
        .zip(origins.chunks_exact(3).zip(directions.chunks_exact(3)))
    {
        // `Placement::near_ray`'s ray, where the origin is near
        // (`Placement::is_near`'s sum).
        let local = [o[0] - offset[0], o[1] - offset[1], o[2] - offset[2]];
        near &= local[0] * local[0] + local[1] * local[1] + local[2] * local[2] <= reach;
        let dir: [f64; 3] = [d[0].into(), d[1].into(), d[2].into()];
        slot.write(Ray {
            origin: local.map(|v| v as f32),
            tmin: tmin as f32,
            dir: dir.map(|v| v as f32),
            tmax: tmax as f32,
        });
        let longest = magnitude(dir[0])
            .max(magnitude(dir[1]))
            .max(magnitude(dir[2]));
        dir_min = dir_min.min(longest);
        dir_max = dir_max.max(longest);
    }
    let (dir_min, dir_max) = (f64::from_bits(dir_min), f64::from_bits(dir_max));
    // In f32 too (a bound on each; the general loop decides the rest).
    // The longest axes in f32, as `FirstBad` checks each ray: rounding
    // keeps their order, and one beyond f32 becomes infinite and fails.
    let valid = near
        && dir_max <= f64::MAX
        && origin_max <= f32::MAX as f64
        && rays::bounds_are_valid(tmin as f32, tmax as f32)
        && rays::direction_lengths_are_valid(dir_min as f32, dir_max as f32);
    valid.then_some((origin_max, dir_min))
}

/// A query's rays in one buffer.
pub enum Gathered<'a> {
    Records(&'a [Ray]),
    Buffer(Vec<Ray>),
}

impl std::ops::Deref for Gathered<'_> {
    type Target = [Ray];
    fn deref(&self) -> &[Ray] {
        match self {
            Gathered::Records(r) => r,
            Gathered::Buffer(b) => b,
        }
    }
}

/// Where the first invalid ray of a query was seen, by index (rays are
/// checked as they are read, by whichever thread reads them).
pub struct FirstBad(AtomicUsize);

impl FirstBad {
    pub fn new() -> FirstBad {
        FirstBad(AtomicUsize::new(usize::MAX))
    }

    #[inline]
    fn check(&self, ray: &Ray, i: usize) {
        if !rays::ray_is_valid(ray) {
            self.0.fetch_min(i, Ordering::Relaxed);
        }
    }

    /// The query's error, if a ray was invalid.
    pub fn result(&self, query: &Query) -> Result<(), Error> {
        match self.0.load(Ordering::Relaxed) {
            usize::MAX => Ok(()),
            i => Err(Error::Usage(rays::bad_ray(&query.ray(i), i).to_string())),
        }
    }
}

/// The precision problems of a query's rays (`Placement::ray_problem`),
/// noted as `Query::fill` reads them: a chunk that
/// `Placement::rays_clear` clears at once is not checked ray by ray (a
/// second pass over every ray after the trace cost half the kernel's time
/// on the dragon's camera rays).
pub struct Problems {
    placement: Placement,
    in_f32: bool,
    found: Mutex<Vec<(usize, RayProblem)>>,
}

impl Problems {
    pub fn new(query: &Query, placement: Placement) -> Problems {
        Problems {
            placement,
            in_f32: query.local().is_none(),
            found: Mutex::new(Vec::new()),
        }
    }

    /// Notes the problems of `query`'s rays `rows`, whose origins'
    /// coordinates are within ±`origin_max` and whose directions' longest
    /// axes are at least `dir_min`.
    fn check(&self, query: &Query, rows: Range<usize>, origin_max: f64, dir_min: f64) {
        let placement = &self.placement;
        if placement.rays_clear(origin_max, dir_min, self.in_f32) {
            return;
        }
        let found: Vec<(usize, RayProblem)> = rows
            .filter_map(|i| {
                let (origin, dir, ..) = query.ray_f64(i);
                placement
                    .ray_problem(origin, dir, self.in_f32)
                    .map(|p| (i, p))
            })
            .collect();
        if !found.is_empty() {
            self.found
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .extend(found);
        }
    }

    /// Where f32 limits the query's hits: one warning per kind, naming the
    /// first ray and counting the rest.
    pub fn warnings(self) -> Vec<String> {
        let mut found = self
            .found
            .into_inner()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        found.sort_unstable_by_key(|&(i, _)| i);
        // A ray may be read twice (the kernel samples some alone to judge
        // the query's coherence); a ray has at most one problem.
        found.dedup_by_key(|&mut (i, _)| i);
        self.placement.ray_problem_warnings(found)
    }
}
