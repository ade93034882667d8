//! A ray query's rays as the caller gave them, read a ray at a time, and
//! the frame they are traced in: float32 origins (and ray records) as
//! world rays (the library moves far ones into the scene's frame from
//! f32), float64 origins moved into the scene's frame in f64 before they
//! become f32 (`Placement::local_ray`), so a mesh far from the origin is
//! hit as precisely as one at it.

use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use lambert::layout::{Hit, NO_HIT, Ray};
use lambert::placement::{Placement, world_hit};
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

    /// Ray `i` in the scene's frame, and how far along it its origin moved.
    #[inline]
    fn local_ray(&self, placement: &Placement, i: usize) -> (Ray, f64) {
        let (origin, dir, tmin, tmax) = self.ray_f64(i);
        placement.local_ray(origin, dir, tmin, tmax)
    }

    /// Ray `i`'s hit `traced` (as the tracer returned it) on the ray as
    /// given: the hit, t rounded once to f32 (a miss beyond f32's t, as
    /// `world_hit` has it), and t in f64 (the local t plus the shift,
    /// unrounded: a location from it is as precise as the trace).
    #[inline]
    pub fn world_hit(&self, i: usize, traced: Hit) -> (Hit, f64) {
        match self.local() {
            Some(placement) if traced.prim != NO_HIT => {
                let shift = self.local_ray(placement, i).1;
                (world_hit(traced, shift), traced.t as f64 + shift)
            }
            _ => (traced, traced.t as f64),
        }
    }

    /// How far along its ray each origin moved into the scene's frame
    /// (`local_ray`'s shift), ray by ray.
    pub fn shifts(&self, placement: &Placement) -> Vec<f64> {
        use rayon::prelude::*;
        (0..self.len())
            .into_par_iter()
            .map(|i| self.local_ray(placement, i).1)
            .collect()
    }

    /// Where f32 limits the query's hits (`Placement::ray_problem`): one
    /// warning per kind, naming the first ray and counting the rest.
    pub fn warnings(&self, placement: &Placement) -> Vec<String> {
        let in_f32 = self.local().is_none();
        placement.warnings_for(self.len(), in_f32, |i| {
            let (origin, dir, ..) = self.ray_f64(i);
            (origin, dir)
        })
    }

    /// Writes rays start.. into all of `out` as they are traced (world,
    /// or local where `local`), checking each as given: per chunk, so the
    /// usual arrays (packed float32 rows, scalar bounds) take a loop of
    /// their own, with no choice per ray.
    #[inline]
    pub fn fill(&self, start: usize, out: &mut [MaybeUninit<Ray>], first_bad: &FirstBad) {
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
            let (o, d) = (o[rows.clone()].chunks_exact(3), d[rows].chunks_exact(3));
            let mut valid = true;
            for (slot, (o, d)) in out.iter_mut().zip(o.zip(d)) {
                valid &= rays::ray_is_valid(slot.write(Ray {
                    origin: [o[0], o[1], o[2]],
                    tmin,
                    dir: [d[0], d[1], d[2]],
                    tmax,
                }));
            }
            if valid {
                return;
            }
        }
        for (i, slot) in (start..).zip(out) {
            let ray = self.ray(i);
            first_bad.check(&ray, i);
            slot.write(match self.local() {
                Some(placement) => self.local_ray(placement, i).0,
                None => ray,
            });
        }
    }

    /// The rays in one buffer (what a GPU uploads), checked: records as
    /// they are, arrays assembled into `buffer` in one parallel pass.
    pub fn gathered(&self, mut buffer: Vec<Ray>) -> Result<Gathered<'_>, Error> {
        use rayon::prelude::*;
        const CHUNK: usize = 4096;
        if let Query::Records(r) = self {
            rays::validate_rays(r).map_err(|bad| Error::Usage(bad.to_string()))?;
            return Ok(Gathered::Records(r));
        }
        let n = self.len();
        let first_bad = FirstBad::new();
        buffer.clear();
        buffer.reserve(n);
        buffer.spare_capacity_mut()[..n]
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| self.fill(c * CHUNK, chunk, &first_bad));
        // SAFETY: every one of the n slots was written above.
        unsafe { buffer.set_len(n) };
        first_bad.result(self)?;
        Ok(Gathered::Buffer(buffer))
    }
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
