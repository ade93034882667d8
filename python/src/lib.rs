//! `lambert._lambert`: the extension module under the `lambert` Python
//! package (python/lambert/). Arrays cross without per-ray Python work:
//! rays are read from numpy views as they are traced (the CPU path, chunk
//! by chunk) or into one buffer (a GPU's upload): the one copy in; each
//! result column is a numpy array that owns the vector it was filled into
//! (the one copy out). Tracing and rendering run with the GIL released.

use std::mem::MaybeUninit;
use std::ops::Range;
use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use lambert::Error;
use lambert::cpu::{
    CpuKernel, Filled, QueryOptions, QueryRays, RayFrame, SharedOut, TracedChunk, prefetch_rows,
    trace_rays_each, with_simd,
};
use lambert::gpu::AdapterRequest;
use lambert::layout::{Hit, NO_HIT, Ray};
use lambert::render::{DeviceChoice, Renderer, Renderers};
use lambert::scene::{Intersect, Scene, hit_normal, prefetch_hit_triangles};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod arrays;
mod errors;
mod images;
mod query;
mod render;
use arrays::{Bound1, Rows};
use errors::Kind;
use query::{FirstBad, Gathered, Problems, Query};

/// The library's errors as the exceptions a Python user expects, with the
/// CLI's messages (advice, where the library leaves it to the front end,
/// in Python's terms).
fn to_py(e: Error) -> PyErr {
    let message = e.to_string();
    match &e {
        Error::Io { source, .. } => match source.kind() {
            std::io::ErrorKind::NotFound => errors::error(Kind::FileNotFound, message),
            std::io::ErrorKind::PermissionDenied => errors::error(Kind::Permission, message),
            _ => errors::error(Kind::Os, message),
        },
        Error::Gpu(_) | Error::GpuLimit(_) => errors::error(Kind::Runtime, message),
        // The library leaves the advice to the front end: Python's words.
        Error::LoopsCut(_) => {
            errors::error(Kind::Runtime, format!("{message}: use device=\"cpu\""))
        }
        Error::Scene { .. } | Error::Line { .. } | Error::Usage(_) => errors::value_error(message),
    }
}

/// Runs `work` without the GIL; a panic (a bug) becomes a RuntimeError
/// rather than tearing through the interpreter.
fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Error> + Send,
) -> PyResult<T> {
    py.detach(|| std::panic::catch_unwind(AssertUnwindSafe(work)))
        .map_err(|panic| {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            errors::error(
                Kind::Runtime,
                format!("internal error in lambert (please report): {what}"),
            )
        })?
        .map_err(to_py)
}

fn device_choice(device: &str) -> PyResult<DeviceChoice> {
    match device {
        "auto" => Ok(DeviceChoice::Auto),
        "gpu" => Ok(DeviceChoice::Gpu),
        "cpu" => Ok(DeviceChoice::Cpu),
        other => Err(crate::errors::value_error(format!(
            "device={other:?}: use \"auto\", \"gpu\" or \"cpu\""
        ))),
    }
}

fn intersect_choice(name: &str) -> PyResult<Intersect> {
    Intersect::ALL
        .into_iter()
        .find(|i| i.name() == name.replace('_', "-"))
        .ok_or_else(|| {
            crate::errors::value_error(format!(
                "intersect={name:?}: use \"watertight\", \"moller-trumbore\" or \"seed\""
            ))
        })
}

/// A vector of `n` elements that parallel chunks write, each once, before
/// it is read (no zero fill: a recycled heap block would be filled
/// by one thread first).
struct Column<T> {
    vec: Vec<T>,
    out: SharedOut<T>,
}

impl<T> Column<T> {
    fn new(n: usize) -> Column<T> {
        let mut vec = Vec::with_capacity(n);
        let out = SharedOut::new_spare(&mut vec);
        Column { vec, out }
    }

    /// Elements start..start + len, to write.
    ///
    /// # Safety
    /// The range within the `n` elements, written by one thread, and no
    /// other slice of it alive.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    unsafe fn rows(&self, start: usize, len: usize) -> &mut [MaybeUninit<T>] {
        unsafe { std::slice::from_raw_parts_mut(self.out.at(start).cast(), len) }
    }

    /// Writes `values` into the rows from `start` on.
    ///
    /// # Safety
    /// As `rows`, for as many rows as `values` has.
    #[inline]
    unsafe fn write(&self, start: usize, values: impl ExactSizeIterator<Item = T>) {
        let len = values.len();
        let rows = unsafe { self.rows(start, len) };
        for (row, value) in rows.iter_mut().zip(values) {
            row.write(value);
        }
    }

    /// Starts loading rows `rows` (a later chunk's: `QueryRays::Fill`'s
    /// ahead), so that writing them does not wait on memory.
    #[inline]
    fn prefetch(&self, rows: Range<usize>) {
        let first = rows.start.min(self.vec.capacity());
        // SAFETY: within the capacity; prefetching reads nothing.
        let at = unsafe { self.out.at(first) };
        prefetch_rows(at, rows.len().min(self.vec.capacity() - first));
    }

    /// # Safety
    /// Every one of the `n` elements was set.
    unsafe fn filled(mut self, n: usize) -> Vec<T> {
        unsafe { self.vec.set_len(n) };
        self.vec
    }
}

/// The t column as it is filled: float32, or float64 (`intersect`'s t64).
enum TColumn {
    F32(Column<f32>),
    F64(Column<f64>),
}

impl TColumn {
    fn new(n: usize, t64: bool) -> TColumn {
        if t64 {
            TColumn::F64(Column::new(n))
        } else {
            TColumn::F32(Column::new(n))
        }
    }

    /// Writes the t of `rows`' hits: each hit's own (float32), or its t
    /// in f64 (the local t plus the shift where the rays were moved).
    ///
    /// # Safety
    /// As `Column::write`.
    #[inline]
    unsafe fn write(&self, rows: &HitRows) {
        let start = rows.start;
        match (self, rows.world_t) {
            (TColumn::F32(c), _) => unsafe { c.write(start, rows.hits.iter().map(|h| h.t)) },
            (TColumn::F64(c), Some(t)) => unsafe { c.write(start, t.iter().copied()) },
            (TColumn::F64(c), None) => unsafe {
                c.write(start, rows.hits.iter().map(|h| h.t as f64))
            },
        }
    }

    fn prefetch(&self, rows: Range<usize>) {
        match self {
            TColumn::F32(c) => c.prefetch(rows),
            TColumn::F64(c) => c.prefetch(rows),
        }
    }

    /// # Safety
    /// As `Column::filled`.
    unsafe fn filled(self, n: usize) -> TValues {
        match self {
            TColumn::F32(c) => TValues::F32(unsafe { c.filled(n) }),
            TColumn::F64(c) => TValues::F64(unsafe { c.filled(n) }),
        }
    }
}

enum TValues {
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// A chunk of a query's hits in the world's frame, as the columns take
/// them.
struct HitRows<'a> {
    /// The index of its first ray.
    start: usize,
    hits: &'a [Hit],
    /// The hits' t in f64, where the rays were traced in the scene's frame
    /// (`Query::world_hit`); None: the hits' own.
    world_t: Option<&'a [f64]>,
    /// The hits' normals, if asked.
    normals: &'a [[f32; 3]],
}

/// The hit columns Python receives.
struct Columns {
    t: TValues,
    prim: Vec<i64>,
    u: Vec<f32>,
    v: Vec<f32>,
    normal: Vec<f32>,
}

/// Hands `hits` to `each` in parallel chunks, as `trace_rays_each` does
/// (with `normals`, each hit's normal too, its triangle fetched ahead).
fn each_chunk(
    scene: &Scene,
    rays: &[Ray],
    hits: &[Hit],
    normals: bool,
    moved: bool,
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    hits.par_chunks(CHUNK).enumerate().for_each(|(i, hits)| {
        let start = i * CHUNK;
        let mut chunk_normals = Vec::new();
        if normals {
            prefetch_hit_triangles(scene, hits);
            chunk_normals.extend(
                (start..)
                    .zip(hits)
                    .map(|(r, hit)| hit_normal(scene, &rays[r], hit)),
            );
        }
        each(&TracedChunk {
            start,
            hits,
            normals: &chunk_normals,
            moved,
        });
    });
}

/// A scene resident in memory: its BVH built once, and uploaded once to
/// each device it is traced or rendered on.
#[pyclass(frozen, module = "lambert._lambert")]
struct NativeScene {
    scene: Arc<Scene>,
    /// The file it was loaded from, where a glTF camera is found by name.
    path: Option<PathBuf>,
    renderers: Mutex<Renderers>,
    /// The last GPU query's ray buffer, kept for the next (32 bytes a ray).
    scratch: Mutex<Vec<Ray>>,
}

impl NativeScene {
    fn new(scene: Scene) -> NativeScene {
        let scene = Arc::new(scene);
        NativeScene {
            // The GPU's environment variables, as the CLI reads them.
            renderers: Mutex::new(Renderers::new(
                Arc::clone(&scene),
                AdapterRequest::default().with_environment(|name| std::env::var(name).ok()),
            )),
            scratch: Mutex::new(Vec::new()),
            scene,
            path: None,
        }
    }

    /// Traces `query` on `device` (the GIL released by the caller),
    /// handing the hits (and with `normals` their normals) to `sink` chunk
    /// by chunk, then fails if a ray was invalid. The CPU path reads the
    /// rays as it traces them, without the renderers' lock, so threads
    /// trace at once; a GPU gets them in one buffer, and its queue is taken
    /// in turn. Hits come in the frame the rays were traced in (a local
    /// query's: `Query::world_hit` turns them back). Returns the fallback
    /// note, if any, and the query's precision warnings. `ahead(rows)`
    /// starts loading the rows the sink will write for rays `rows`
    /// (`QueryRays::Fill`'s ahead; their rays are loaded too).
    fn trace_into(
        &self,
        query: Query,
        options: QueryOptions,
        device: DeviceChoice,
        ahead: &(dyn Fn(Range<usize>) + Sync),
        sink: &(dyn Fn(&TracedChunk) + Sync),
    ) -> Result<(Option<String>, Vec<String>), Error> {
        let scene = &self.scene;
        let problems = Problems::new(&query, scene.placement());
        let (traced, note) = Renderers::run(&self.renderers, device, |renderer| {
            if !renderer.is_cpu() {
                return self
                    .trace_gathered(&query, options, renderer, &problems)
                    .map(Some);
            }
            // The CPU path traces the rays as it reads them.
            let first_bad = FirstBad::new();
            // In the kernel's vector instructions (the same IEEE
            // operations): the fill's loops then take 8 lanes. No wider
            // on Intel, whose core the packets' rays then leave slowed.
            let fill = |start: usize, out: &mut [MaybeUninit<Ray>]| -> Filled {
                // SAFETY: the options' kernel is one this CPU runs, and so
                // is any narrower.
                unsafe {
                    with_simd(
                        options.cpu_kernel.narrow_on_intel(),
                        #[inline(always)]
                        || query.fill(start, out, &first_bad, &problems),
                    )
                }
            };
            let ahead = |rows: Range<usize>| {
                query.prefetch(rows.clone());
                ahead(rows);
            };
            let rays = QueryRays::Fill(query.len(), &fill, &ahead);
            let frame = match query.local() {
                Some(_) => RayFrame::Local,
                None => RayFrame::World,
            };
            trace_rays_each(scene, rays, options, frame, sink);
            first_bad.result(&query)?;
            Ok(None)
        })?;
        if let Some((rays, hits)) = traced {
            // A local query's rays were traced as moved (`local_ray`).
            let moved = query.local().is_some();
            each_chunk(scene, &rays, &hits, options.normals, moved, sink);
            if let (Gathered::Buffer(b), Ok(mut home)) = (rays, self.scratch.try_lock()) {
                if home.capacity() < b.capacity() {
                    *home = b;
                }
            }
        }
        Ok((note, problems.warnings()))
    }

    /// `query`'s rays gathered into one buffer and traced on `renderer`
    /// (a GPU's: one upload), in the scene's frame where they are f64.
    fn trace_gathered<'q>(
        &self,
        query: &'q Query<'_>,
        options: QueryOptions,
        renderer: &mut Renderer,
        problems: &Problems,
    ) -> Result<(Gathered<'q>, Vec<Hit>), Error> {
        // The scene's buffer from an earlier query, if no other thread
        // holds it: its pages are mapped already (fresh ones cost a
        // fault each).
        let buffer = self
            .scratch
            .try_lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        let rays = query.gathered(buffer, problems)?;
        let hits = match query.local() {
            Some(_) => renderer.trace_local(&rays, options.any_hit, options.intersect)?,
            None => renderer.trace(&rays, options.any_hit, options.intersect)?,
        };
        Ok((rays, hits))
    }

    /// Traces `query` on `device` without the GIL into the columns that
    /// `make` makes for its n rays: `write` fills a chunk's rows from its
    /// hits in the world's frame (`Query::world_hit`, with their t in f64)
    /// and, with `options.normals`, their normals, each row once and from
    /// one thread; `ahead` starts loading rows a later chunk writes
    /// (`trace_into`'s). Warns of the trace's notes and returns what
    /// `finish` makes of the columns once every row is written.
    #[allow(clippy::too_many_arguments)]
    fn trace_rows<C: Sync, R: Send>(
        &self,
        py: Python<'_>,
        query: Query,
        options: QueryOptions,
        device: DeviceChoice,
        make: impl FnOnce(usize) -> C + Send,
        ahead: impl Fn(&C, Range<usize>) + Sync,
        write: impl Fn(&C, &HitRows) + Sync,
        finish: impl FnOnce(C, usize) -> R + Send,
    ) -> PyResult<R> {
        let (out, notes) = detached(py, || {
            let n = query.len();
            let columns = make(n);
            let ahead = |rows| ahead(&columns, rows);
            let notes = self.trace_into(query, options, device, &ahead, &|chunk| {
                let start = chunk.start;
                match chunk.moved {
                    // Traced as given: the hits are the world's, with no
                    // move back to make (decided once a chunk, not a row).
                    false => write(
                        &columns,
                        &HitRows {
                            start,
                            hits: chunk.hits,
                            world_t: None,
                            normals: chunk.normals,
                        },
                    ),
                    // As `intersect` reports them (a hit beyond f32's t is
                    // a miss, as warned).
                    true => {
                        let (hits, world_t): (Vec<Hit>, Vec<f64>) = (start..)
                            .zip(chunk.hits)
                            .map(|(i, hit)| query.world_hit(i, *hit))
                            .unzip();
                        write(
                            &columns,
                            &HitRows {
                                start,
                                hits: &hits,
                                world_t: Some(&world_t),
                                normals: chunk.normals,
                            },
                        )
                    }
                }
            })?;
            Ok((finish(columns, n), notes))
        })?;
        NativeScene::warn(py, notes.0.into_iter().chain(notes.1))?;
        Ok(out)
    }

    /// `trace`'s closest hits, as a dict of columns.
    fn closest_hits<'py>(
        &self,
        py: Python<'py>,
        query: Query,
        options: QueryOptions,
        device: DeviceChoice,
        t64: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let columns = self.trace_rows(
            py,
            query,
            options,
            device,
            |n| {
                let t = TColumn::new(n, t64);
                let prim = Column::<i64>::new(n);
                let (u, v) = (Column::<f32>::new(n), Column::<f32>::new(n));
                (t, prim, u, v, Column::<[f32; 3]>::new(n))
            },
            |(t, prim, u, v, normal), rows| {
                t.prefetch(rows.clone());
                prim.prefetch(rows.clone());
                u.prefetch(rows.clone());
                v.prefetch(rows.clone());
                normal.prefetch(rows);
            },
            // SAFETY: `trace_rows` writes each chunk's rows once, from one
            // thread, within the n rows.
            |(t, prim, u, v, normal), rows| unsafe {
                let (start, hits) = (rows.start, rows.hits);
                t.write(rows);
                let id = |h: &Hit| if h.prim == NO_HIT { -1 } else { h.prim as i64 };
                prim.write(start, hits.iter().map(id));
                u.write(start, hits.iter().map(|h| h.u));
                v.write(start, hits.iter().map(|h| h.v));
                match rows.normals.len() {
                    // No normals asked: zeros.
                    0 => normal.write(start, hits.iter().map(|_| [0.0; 3])),
                    _ => normal.write(start, rows.normals.iter().copied()),
                }
            },
            // SAFETY: the trace handed over every ray's hit and normal.
            |(t, prim, u, v, normal), n| unsafe {
                Columns {
                    t: t.filled(n),
                    prim: prim.filled(n),
                    u: u.filled(n),
                    v: v.filled(n),
                    normal: normal.filled(n).into_flattened(),
                }
            },
        )?;
        let Columns {
            t,
            prim,
            u,
            v,
            normal,
        } = columns;
        let n = prim.len();
        let normal = Array2::from_shape_vec((n, 3), normal).expect("3 per hit");
        let out = PyDict::new(py);
        match t {
            TValues::F32(t) => out.set_item("t", t.into_pyarray(py))?,
            TValues::F64(t) => out.set_item("t", t.into_pyarray(py))?,
        }
        out.set_item("prim_id", prim.into_pyarray(py))?;
        out.set_item("u", u.into_pyarray(py))?;
        out.set_item("v", v.into_pyarray(py))?;
        out.set_item("normal", normal.into_pyarray(py))?;
        Ok(out)
    }

    fn warn(py: Python<'_>, notes: impl IntoIterator<Item = String>) -> PyResult<()> {
        for note in notes {
            let warning = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
            PyErr::warn(
                py,
                &warning,
                &std::ffi::CString::new(note).unwrap_or_default(),
                2,
            )?;
        }
        Ok(())
    }
}

/// Parses a query's arguments: either `records` (an (N, 8) float32 view of
/// RAY_DTYPE records) or origins, directions, tmin and tmax, and runs
/// `$body` with `$query` the `Query` (on `$scene`): float64 origins are
/// traced in the scene's frame.
macro_rules! with_query {
    ($scene:expr, $origins:expr, $directions:expr, $tmin:expr, $tmax:expr, |$query:ident| $body:expr) => {{
        match $directions {
            None => {
                let records: PyReadonlyArray2<f32> = $origins.extract()?;
                if records.shape()[1] != 8 {
                    return Err(crate::errors::value_error(
                        "ray records must be (N, 8) float32",
                    ));
                }
                let flat = records
                    .as_slice()
                    .ok()
                    .filter(|_| records.is_c_contiguous());
                let flat = flat.ok_or_else(|| {
                    crate::errors::value_error(
                        "ray records must be a contiguous lambert.RAY_DTYPE array",
                    )
                })?;
                let $query = Query::Records(bytemuck::cast_slice(flat));
                $body
            }
            Some(directions) => {
                let origins = Rows::extract("origins", $origins)?;
                let directions = Rows::extract("directions", directions)?;
                let n = origins.len();
                if directions.len() != n {
                    return Err(crate::errors::value_error(format!(
                        "{n} origins but {} directions",
                        directions.len()
                    )));
                }
                let tmin = Bound1::extract("tmin", $tmin, n)?;
                let tmax = Bound1::extract("tmax", $tmax, n)?;
                let origins = origins.view();
                let $query = Query::Arrays {
                    origins,
                    directions: directions.view(),
                    tmin: tmin.view(),
                    tmax: tmax.view(),
                    n,
                    // float64 origins stay f64 until they are in the
                    // scene's frame (docs/python.md, "Far from the origin").
                    local: origins.is_f64().then(|| $scene.placement()),
                };
                $body
            }
        }
    }};
}

// After `with_query!`, which it uses.
mod proximity;

#[pymethods]
impl NativeScene {
    #[staticmethod]
    #[pyo3(signature = (vertices, faces, albedo=None))]
    fn from_arrays(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        albedo: Option<[f64; 3]>,
    ) -> PyResult<NativeScene> {
        if vertices.shape()[1] != 3 || faces.shape()[1] != 3 {
            return Err(crate::errors::value_error(format!(
                "vertices {:?} and faces {:?} must both be (N, 3)",
                vertices.shape(),
                faces.shape()
            )));
        }
        if faces.shape()[0] == 0 {
            // As a model file with no triangles is refused.
            return Err(crate::errors::value_error(format!(
                "faces is empty: no triangles ({} points)",
                vertices.shape()[0]
            )));
        }
        let (v, f) = (arrays::rows3(&vertices), arrays::rows3(&faces));
        let scene = detached(py, || Scene::from_arrays(&v, &f, albedo))?;
        Ok(NativeScene::new(scene))
    }

    #[staticmethod]
    #[pyo3(signature = (path, camera=None))]
    fn load(py: Python<'_>, path: PathBuf, camera: Option<&str>) -> PyResult<NativeScene> {
        let scene = detached(py, || Scene::load_with_camera(&path, camera))?;
        for warning in scene.warnings() {
            NativeScene::warn(py, Some(warning.clone()))?;
        }
        Ok(NativeScene {
            path: Some(path),
            ..NativeScene::new(scene)
        })
    }

    /// A ray query: the closest hits, as columns t, prim_id (-1 for a
    /// miss), u, v and normal (with `t64`, t in float64: the trimesh
    /// drop-in's, whose locations from it are as precise as the trace where
    /// the f32 t would round a long ray's); with `any_hit`, whether
    /// anything lies on each ray within (tmin, tmax), a bool a ray.
    #[pyo3(signature = (origins, directions, tmin, tmax, device, intersect, any_hit, t64))]
    #[allow(clippy::too_many_arguments)]
    fn trace<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: Option<&Bound<'py, PyAny>>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
        device: &str,
        intersect: &str,
        any_hit: bool,
        t64: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (device, intersect) = (device_choice(device)?, intersect_choice(intersect)?);
        let options = QueryOptions {
            any_hit,
            intersect,
            cpu_kernel: CpuKernel::active(),
            normals: !any_hit,
        };
        with_query!(self.scene, origins, directions, tmin, tmax, |query| {
            if any_hit {
                let hit = self.trace_rows(
                    py,
                    query,
                    options,
                    device,
                    Column::<bool>::new,
                    Column::prefetch,
                    // SAFETY: `trace_rows` writes each chunk's rows once,
                    // from one thread, within the n rows.
                    |hit, rows| unsafe {
                        hit.write(rows.start, rows.hits.iter().map(|h| h.prim != NO_HIT))
                    },
                    // SAFETY: every row is written.
                    |hit, n| unsafe { hit.filled(n) },
                )?;
                Ok(hit.into_pyarray(py).into_any())
            } else {
                self.closest_hits(py, query, options, device, t64)
                    .map(Bound::into_any)
            }
        })
    }

    /// What `device` resolves to for this scene ("GPU: …" or "CPU …").
    #[pyo3(signature = (device="auto"))]
    fn device_name(&self, py: Python<'_>, device: &str) -> PyResult<String> {
        let device = device_choice(device)?;
        let (name, note) = detached(py, || {
            let mut renderers = self.renderers.lock().unwrap_or_else(|e| e.into_inner());
            let (renderer, note) = renderers.get(device)?;
            Ok((renderer.describe(), note))
        })?;
        NativeScene::warn(py, note)?;
        Ok(name)
    }

    #[getter]
    fn triangle_count(&self) -> usize {
        self.scene.triangles().len()
    }

    #[getter]
    fn sphere_count(&self) -> usize {
        self.scene.spheres().len()
    }

    /// (min, max) corners of the scene's bounding box, or None if empty.
    #[getter]
    fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        self.scene
            .bvh()
            .bounds()
            .map(|b| (b.min.to_array(), b.max.to_array()))
    }

    /// The scene's camera: eye, look_at, up, vfov (degrees), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.scene.view().camera;
        let out = PyDict::new(py);
        out.set_item("eye", c.eye)?;
        out.set_item("look_at", c.look_at)?;
        out.set_item("up", c.up)?;
        out.set_item("vfov", c.vfov)?;
        out.set_item("width", c.width)?;
        out.set_item("height", c.height)?;
        Ok(out)
    }

    #[getter]
    fn spp(&self) -> u32 {
        self.scene.view().spp
    }
}

#[pymodule]
fn _lambert(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The CPU kernel the user asks for, as the CLI reads it.
    CpuKernel::select(std::env::var(lambert::cpu::CPU_KERNEL_ENV).ok().as_deref());
    m.add_class::<NativeScene>()?;
    images::register(m)?;
    proximity::register(m)?;
    render::register(m)?;
    Ok(())
}
