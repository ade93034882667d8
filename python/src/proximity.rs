//! The queries beyond the first hit (docs/python.md, "Closest points,
//! distances and crossings"): closest points, unsigned and signed
//! distances, winding numbers, inside tests, and every crossing along
//! rays, on numpy arrays of any layout, with the GIL released, on the
//! device asked (`Renderer`'s queries, both paths).

use std::borrow::Cow;

use lambert::Error;
use lambert::jobs::{self, Sign};
use lambert::layout::{ListedHit, NO_HIT, Ray};
use lambert::limits::checked_point;
use lambert::placement::LocalRays;
use lambert::render::{DeviceChoice, IntersectionList, Renderer, Renderers, with_fallback};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::arrays::{Bound1, Rows, RowsView};
use crate::query::{Problems, Query};
use crate::{NativeScene, detached, device_choice};

/// Query points as given (float32 widened exactly: float64 points stay f64
/// until the renderer moves them into the scene's frame), each checked
/// finite and within the coordinate limit, the first bad row named.
fn read_points(rows: RowsView<'_>, n: usize) -> Result<Vec<[f64; 3]>, Error> {
    let bad = (0..n)
        .into_par_iter()
        .position_first(|i| checked_point("", rows.row_f64(i)).is_err());
    if let Some(i) = bad {
        let problem = checked_point("", rows.row_f64(i)).expect_err("a bad row");
        return Err(Error::Usage(format!("points row {i}{problem}")));
    }
    Ok((0..n).into_par_iter().map(|i| rows.row_f64(i)).collect())
}

/// Runs `work` on the renderer for `device`, without the GIL: on the CPU
/// path on a renderer of its own sharing the scene, so that threads query
/// at once; a GPU's queue is taken in turn (auto takes the CPU path where
/// the work hits the GPU's limits). Returns the fallback note too.
fn on_device<T: Send>(
    native: &NativeScene,
    device: DeviceChoice,
    work: impl Fn(&mut Renderer) -> Result<T, Error>,
) -> Result<(T, Option<String>), Error> {
    if native.scene.triangles().is_empty() {
        return Err(Error::Usage(
            "the scene has no triangles: proximity and crossing queries are over triangles".into(),
        ));
    }
    let ((out, fell_back), note) = Renderers::run(&native.renderers, device, |renderer| {
        with_fallback(renderer, device, &native.scene, work)
    })?;
    Ok((out, note.or(fell_back)))
}

/// A points query: the points read (any layout), `work` run on them; a
/// RuntimeWarning where float32 points are too coarse for the scene's
/// precision (as `intersect` warns of float32 origins).
fn points_query<'py, T: Send>(
    py: Python<'py>,
    native: &NativeScene,
    points: &Bound<'py, PyAny>,
    device: &str,
    work: impl Fn(&mut Renderer, &[[f64; 3]]) -> Result<T, Error> + Send + Sync,
) -> PyResult<T> {
    let device = device_choice(device)?;
    let rows = Rows::extract("points", points)?;
    let (view, n) = (rows.view(), rows.len());
    let (out, notes) = detached(py, || {
        let points = read_points(view, n)?;
        let warnings = if view.is_f64() {
            Vec::new()
        } else {
            let placement = native.scene.placement();
            placement.point_warnings(n, |i| points[i].into())
        };
        let (out, note) = on_device(native, device, |renderer| work(renderer, &points))?;
        Ok((out, note.into_iter().chain(warnings)))
    })?;
    NativeScene::warn(py, notes)?;
    Ok(out)
}

/// Closest points within `max_distance`: point, prim_id (-1 beyond),
/// u, v, distance (inf beyond).
#[pyfunction]
pub fn closest_points<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    points: &Bound<'py, PyAny>,
    max_distance: f64,
    device: &str,
) -> PyResult<Bound<'py, PyDict>> {
    // The library checks max_distance (≥ 0, not NaN).
    let found = points_query(py, scene.get(), points, device, |renderer, points| {
        renderer.closest_points(points, max_distance as f32)
    })?;
    let n = found.len();
    let mut point = Vec::with_capacity(3 * n);
    let (mut prim, mut u, mut v, mut distance) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    // Beyond max_distance: ClosestPoint::NONE, whose distance is +inf.
    for c in &found {
        point.extend(c.point);
        prim.push(if c.prim == NO_HIT { -1 } else { c.prim as i64 });
        u.push(c.u);
        v.push(c.v);
        distance.push(c.distance);
    }
    let out = PyDict::new(py);
    let point = Array2::from_shape_vec((n, 3), point).expect("3 per point");
    out.set_item("point", point.into_pyarray(py))?;
    out.set_item("prim_id", prim.into_pyarray(py))?;
    out.set_item("u", u.into_pyarray(py))?;
    out.set_item("v", v.into_pyarray(py))?;
    out.set_item("distance", distance.into_pyarray(py))?;
    Ok(out)
}

/// A value per point: `what` is "distance" (unsigned), "winding_number"
/// or "signed_distance" (negative inside by `method`, "winding" or
/// "parity").
#[pyfunction]
pub fn point_values<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    points: &Bound<'py, PyAny>,
    what: &str,
    method: &str,
    device: &str,
) -> PyResult<Bound<'py, numpy::PyArray1<f32>>> {
    let sign = Sign::ALL
        .into_iter()
        .find(|s| s.name() == method)
        .ok_or_else(|| {
            crate::errors::value_error(format!("method={method:?}: use \"winding\" or \"parity\""))
        })?;
    let what = what.to_string();
    let values = points_query(
        py,
        scene.get(),
        points,
        device,
        |renderer, points| match what.as_str() {
            "distance" => jobs::distances(renderer, points),
            "winding_number" => renderer.winding_numbers(points),
            "signed_distance" => jobs::signed_distances(renderer, points, sign),
            other => Err(Error::Usage(format!("no point query {other:?}"))),
        },
    )?;
    Ok(values.into_pyarray(py))
}

/// Whether each point is inside: winding number ≥ 0.5.
#[pyfunction]
pub fn contains<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    points: &Bound<'py, PyAny>,
    device: &str,
) -> PyResult<Bound<'py, numpy::PyArray1<bool>>> {
    let inside = points_query(py, scene.get(), points, device, |renderer, points| {
        jobs::inside(renderer, points, Sign::Winding)
    })?;
    Ok(inside.into_pyarray(py))
}

/// A crossing query's rays, gathered (checked as given): world f32 rays,
/// or for float64 origins rays already in the scene's frame with their
/// shifts (`LocalRays`, as `intersect` traces them); `work` run on them.
#[allow(clippy::too_many_arguments)]
fn rays_query<'py, T: Send>(
    py: Python<'py>,
    native: &NativeScene,
    origins: &Bound<'py, PyAny>,
    directions: Option<&Bound<'py, PyAny>>,
    tmin: &Bound<'py, PyAny>,
    tmax: &Bound<'py, PyAny>,
    device: &str,
    work: impl Fn(&mut Renderer, Crossings) -> Result<T, Error> + Send + Sync,
) -> PyResult<T> {
    let device = device_choice(device)?;
    with_query!(native.scene, origins, directions, tmin, tmax, |query| {
        let (out, notes) = detached(py, || {
            let problems = Problems::new(&query, native.scene.placement());
            let rays = query.gathered(Vec::new(), &problems)?;
            let local = query.local().map(|placement| LocalRays {
                rays: Cow::Borrowed(&rays[..]),
                shifts: query.shifts(placement),
            });
            let crossings = match &local {
                Some(local) => Crossings::Local(local),
                None => Crossings::World(&rays),
            };
            let (out, note) = on_device(native, device, |renderer| work(renderer, crossings))?;
            Ok((out, (note, problems.warnings())))
        })?;
        NativeScene::warn(py, notes.0.into_iter().chain(notes.1))?;
        Ok(out)
    })
}

/// The rays of a crossing query as the renderer takes them.
#[derive(Clone, Copy)]
enum Crossings<'a> {
    /// World f32 rays (float32 origins, ray records).
    World(&'a [Ray]),
    /// Rays moved into the scene's frame in f64 (float64 origins).
    Local(&'a LocalRays<'a>),
}

impl Crossings<'_> {
    fn count(self, renderer: &mut Renderer) -> Result<Vec<u32>, Error> {
        match self {
            Crossings::World(rays) => renderer.count_intersections(rays),
            Crossings::Local(local) => renderer.count_local_intersections(local),
        }
    }

    fn list(self, renderer: &mut Renderer) -> Result<IntersectionList, Error> {
        match self {
            Crossings::World(rays) => renderer.list_intersections(rays),
            Crossings::Local(local) => renderer.list_local_intersections(local),
        }
    }
}

/// The crossings of each ray in (tmin, tmax): with `list`, every one
/// (a dict of columns, sorted by t per ray), else their count per ray.
#[pyfunction]
#[pyo3(signature = (scene, origins, directions, tmin, tmax, device, list))]
#[allow(clippy::too_many_arguments)]
pub fn crossings<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    origins: &Bound<'py, PyAny>,
    directions: Option<&Bound<'py, PyAny>>,
    tmin: &Bound<'py, PyAny>,
    tmax: &Bound<'py, PyAny>,
    device: &str,
    list: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let native = scene.get();
    if !list {
        let counts = rays_query(
            py,
            native,
            origins,
            directions,
            tmin,
            tmax,
            device,
            |renderer, rays| {
                // Open3D's dtype; no ray crosses 2³¹ triangles of a scene
                // that fits in memory.
                let counts = rays.count(renderer)?;
                Ok(counts.into_iter().map(|c| c as i32).collect::<Vec<i32>>())
            },
        )?;
        return Ok(counts.into_pyarray(py).into_any());
    }
    let IntersectionList { ray_splits, hits } = rays_query(
        py,
        native,
        origins,
        directions,
        tmin,
        tmax,
        device,
        |renderer, rays| rays.list(renderer),
    )?;
    let floats = |f: fn(&ListedHit) -> f32| hits.iter().map(f).collect::<Vec<f32>>();
    let ids = |f: fn(&ListedHit) -> u32| hits.iter().map(|h| f(h) as i64).collect::<Vec<i64>>();
    let out = PyDict::new(py);
    let splits: Vec<i64> = ray_splits.iter().map(|&s| s as i64).collect();
    out.set_item("ray_splits", splits.into_pyarray(py))?;
    out.set_item("ray_ids", ids(|h| h.ray).into_pyarray(py))?;
    out.set_item("t", floats(|h| h.t).into_pyarray(py))?;
    out.set_item("prim_id", ids(|h| h.prim).into_pyarray(py))?;
    out.set_item("u", floats(|h| h.u).into_pyarray(py))?;
    out.set_item("v", floats(|h| h.v).into_pyarray(py))?;
    Ok(out.into_any())
}

/// Registers the functions in the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(closest_points, m)?)?;
    m.add_function(wrap_pyfunction!(point_values, m)?)?;
    m.add_function(wrap_pyfunction!(contains, m)?)?;
    m.add_function(wrap_pyfunction!(crossings, m)?)?;
    Ok(())
}
