//! `Scene.render` and `Scene.camera_rays` with the CLI's choices (camera,
//! samples, light, integrator, environment, tiles), applied by the
//! library's `RenderOverrides` as the CLI applies its options, so that the
//! same choices give the same image; and lights added to a scene.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use lambert::Error;
use lambert::camera::Camera;
use lambert::gpu::AdapterRequest;
use lambert::jobs::{self, RenderOverrides, Sampling};
use lambert::output::Image;
use lambert::parts::Tile;
use lambert::progress::{ProgressBar, ProgressSink};
use lambert::render::{Renderer, Renderers};
use lambert::scene::{Integrator, RenderSettings, Scene, environment_spec};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::prelude::*;

use crate::errors::value_error;
use crate::{NativeScene, detached, device_choice};

/// A camera as Python gives it: eye, look_at, up, vfov (degrees).
type CameraView = ([f64; 3], [f64; 3], [f64; 3], f64);

/// A render's choices as the Python wrapper passes them (None: the scene's).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Choices {
    width: Option<u32>,
    height: Option<u32>,
    camera: Option<CameraView>,
    camera_name: Option<String>,
    spp: Option<u32>,
    seed: Option<u32>,
    ambient: Option<[f32; 3]>,
    shadows: Option<bool>,
    integrator: Option<String>,
    max_depth: Option<u32>,
    /// A file, or "r,g,b", with its strength and rotation (degrees).
    environment: Option<(String, f64, f64)>,
}

/// An argument's name in errors: the keyword's own.
fn keyword(name: &str) -> String {
    name.to_string()
}

impl Choices {
    /// The scene to render (a copy, where the environment changes it) and
    /// its settings, as the CLI's options make them.
    fn apply(&self, native: &NativeScene) -> Result<(Option<Scene>, RenderSettings), Error> {
        let scene = &native.scene;
        let mut settings = scene.default_settings();
        if let Some(name) = &self.camera_name {
            settings.view.camera = named_camera(native, name)?;
        }
        let integrator = match &self.integrator {
            None => None,
            Some(name) => Some(
                Integrator::ALL
                    .into_iter()
                    .find(|i| i.name() == name)
                    .ok_or_else(|| {
                        Error::Usage(format!("integrator={name:?}: use \"direct\" or \"path\""))
                    })?,
            ),
        };
        let environment = match &self.environment {
            None => None,
            Some((text, strength, rotation)) => Some(environment_spec(
                text,
                *strength,
                *rotation,
                [
                    "environment",
                    "environment_strength",
                    "environment_rotation",
                ],
            )?),
        };
        let overrides = RenderOverrides {
            width: self.width,
            height: self.height,
            camera: self.camera.map(|(eye, look_at, up, vfov)| Camera {
                eye,
                look_at,
                up,
                vfov,
                // The view's size is kept.
                width: 1,
                height: 1,
            }),
            spp: self.spp,
            seed: self.seed,
            ambient: self.ambient,
            shadows: self.shadows,
            integrator,
            max_depth: self.max_depth,
            environment,
            ..RenderOverrides::default()
        };
        overrides.apply_settings(scene, &mut settings, &keyword)?;
        let copy = match &overrides.environment {
            None => None,
            Some(spec) => {
                let mut copy = Scene::clone(&**scene);
                copy.set_environment(Some(spec))?;
                Some(copy)
            }
        };
        Ok((copy, settings))
    }
}

/// The glTF camera `name` of the file `native` was loaded from (read
/// again for it), as `lambert render --camera NAME` takes it.
fn named_camera(native: &NativeScene, name: &str) -> Result<Camera, Error> {
    let path = native.path.as_ref().ok_or_else(|| {
        Error::Usage(format!(
            "camera={name:?} names a glTF file's camera; this scene was made from arrays"
        ))
    })?;
    let is_toml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if is_toml {
        return Err(Error::Usage(format!(
            "camera={name:?} names a glTF file's camera; a TOML scene has one camera \
             (give a lambert.Camera instead)"
        )));
    }
    Ok(Scene::load_with_camera(path, Some(name))?
        .view()
        .camera
        .clone())
}

/// Tells a Python callable `progress(done, total, unit)` how far a pass
/// has got; the first exception it raises is kept for after the render.
struct PySink {
    callback: Py<PyAny>,
    failure: Arc<Mutex<Option<PyErr>>>,
}

struct PyBar {
    callback: Py<PyAny>,
    failure: Arc<Mutex<Option<PyErr>>>,
    done: AtomicU64,
    total: u64,
    unit: String,
}

impl ProgressSink for PySink {
    fn start(&self, total: u64, unit: &str) -> Box<dyn ProgressBar> {
        let bar = PyBar {
            callback: Python::attach(|py| self.callback.clone_ref(py)),
            failure: Arc::clone(&self.failure),
            done: AtomicU64::new(0),
            total,
            unit: unit.to_string(),
        };
        bar.tell(0);
        Box::new(bar)
    }
}

impl PyBar {
    /// Adds `units` to what is done and tells the callable the new total.
    fn tell(&self, units: u64) {
        let mut failure = self.failure.lock().unwrap_or_else(|e| e.into_inner());
        // Counted under the lock, so that the totals reach the callable in
        // the order they grow, one call at a time, whichever thread ends
        // its rows first.
        let done = self.done.fetch_add(units, Ordering::Relaxed) + units;
        if failure.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = self
                .callback
                .call1(py, (done, self.total, self.unit.as_str()))
            {
                *failure = Some(e);
            }
        });
    }
}

impl ProgressBar for PyBar {
    fn inc(&self, units: u64) {
        self.tell(units);
    }

    fn finish(&self) {}
}

/// A linear-RGB image as an (H, W, 3) float32 array.
pub fn image_array<'py>(py: Python<'py>, image: Image) -> Bound<'py, PyArray3<f32>> {
    let (w, h) = (image.width as usize, image.height as usize);
    let flat: Vec<f32> = image.rgb.into_iter().flatten().collect();
    Array3::from_shape_vec((h, w, 3), flat)
        .expect("3 per pixel")
        .into_pyarray(py)
}

/// What a part of a render records: its tile (index, count), its rows
/// (start, end), the image's height, and the settings' hash.
pub type PartInfo = ((u32, u32), (u32, u32), u32, String);

/// A render with `choices`, `sampling` (fixed, a time budget in seconds,
/// or adaptive to a target error with at most max_spp samples), on
/// `device`, telling `progress`; with `tile`, only that part's rows, and
/// what `lambert.merge` needs to join it.
#[pyfunction]
#[pyo3(signature = (scene, choices, time_budget, target_error, max_spp, device, progress, tile))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    choices: Choices,
    time_budget: Option<f64>,
    target_error: Option<f64>,
    max_spp: u32,
    device: &str,
    progress: Option<Py<PyAny>>,
    tile: Option<(u32, u32)>,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Option<PartInfo>)> {
    let native = scene.get();
    let device = device_choice(device)?;
    let sampling = match (time_budget, target_error) {
        (Some(budget), _) => Sampling::Budget(budget),
        (None, Some(target_error)) => Sampling::Adaptive {
            target_error,
            max_spp,
        },
        (None, None) => Sampling::Fixed,
    };
    let failure = Arc::new(Mutex::new(None));
    let sink = progress.map(|callback| PySink {
        callback,
        failure: Arc::clone(&failure),
    });
    let sink = sink.as_ref().map(|s| s as &dyn ProgressSink);
    let (image, part, note) = detached(py, || {
        let (copy, settings) = choices.apply(native)?;
        let request = AdapterRequest::default().with_environment(|name| std::env::var(name).ok());
        if let Some((index, count)) = tile {
            let tile = Tile { index, count };
            if count == 0 || index >= count {
                return Err(Error::Usage(format!(
                    "tile=({index}, {count}): expected (k, n) with 0 ≤ k < n"
                )));
            }
            // As `lambert render --tile`: a renderer of its own.
            let scene = copy.unwrap_or_else(|| Scene::clone(&*native.scene));
            let band = jobs::render_band(scene, &settings, tile, device, &request, sink)?;
            let info = (
                (index, count),
                (band.rows.start, band.rows.end),
                band.height,
                band.hash,
            );
            return Ok((band.image, Some(info), None));
        }
        let base = native.scene.default_settings();
        let same_light = copy.is_none()
            && settings.ambient == base.ambient
            && settings.shadows == base.shadows
            && settings.accel == base.accel
            && settings.intersect == base.intersect;
        if same_light {
            // Another view, integrator or sample count: the scene, and a
            // GPU's buffers, stay the ones uploaded.
            native
                .renderers
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .set_integrator(settings.integrator, settings.max_depth)?;
            let (sampled, note) = Renderers::run(&native.renderers, device, |renderer| {
                jobs::render_view(renderer, &settings.view, sampling, sink)
            })?;
            return Ok((sampled.rendered.image, None, note));
        }
        // Other light: the scene with it, opened as the CLI opens one.
        let scene = copy.unwrap_or_else(|| Scene::clone(&*native.scene));
        let scene = Arc::new(scene.with_settings(&settings));
        let (mut renderer, note) = Renderer::open(scene, device, &request)?;
        let sampled = jobs::render_view(&mut renderer, &settings.view, sampling, sink)?;
        Ok((sampled.rendered.image, None, note))
    })?;
    NativeScene::warn(py, note)?;
    if let Some(e) = failure.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(e);
    }
    Ok((image_array(py, image), part))
}

/// The camera's rays through pixel centres, row-major from the top, as
/// `lambert camera-rays` writes them for the same choices.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn camera_rays<'py>(
    py: Python<'py>,
    scene: &Bound<'py, NativeScene>,
    choices: Choices,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>)> {
    let native = scene.get();
    let (origins, directions) = detached(py, || {
        let (copy, settings) = choices.apply(native)?;
        let scene = copy.as_ref().unwrap_or(&native.scene);
        let rays = lambert::rays::camera_rays_for(scene, &settings.view.camera);
        let origins: Vec<f32> = rays.iter().flat_map(|r| r.origin).collect();
        let directions: Vec<f32> = rays.iter().flat_map(|r| r.dir).collect();
        Ok((origins, directions))
    })?;
    let n = origins.len() / 3;
    let rows = |v: Vec<f32>| Array2::from_shape_vec((n, 3), v).expect("3 per ray");
    Ok((
        rows(origins).into_pyarray(py),
        rows(directions).into_pyarray(py),
    ))
}

/// `scene` with one more light, as the TOML format's tables give one:
/// kind "point" (position, intensity), "directional" (direction,
/// irradiance) or "spot" (position, direction, intensity, [inner, outer]
/// degrees). A model file's default light and ambient go.
#[pyfunction]
#[pyo3(signature = (scene, kind, position, direction, color, angles))]
fn with_light(
    py: Python<'_>,
    scene: &Bound<'_, NativeScene>,
    kind: &str,
    position: Option<[f64; 3]>,
    direction: Option<[f64; 3]>,
    color: [f64; 3],
    angles: Option<[f64; 2]>,
) -> PyResult<NativeScene> {
    let native = scene.get();
    let mut copy = Scene::clone(&*native.scene);
    let missing = |what: &str| value_error(format!("a {kind} light needs its {what}"));
    match kind {
        "point" => {
            let position = position.ok_or_else(|| missing("position"))?;
            detached(py, || copy.add_point_light("light", position, color))?;
        }
        "directional" => {
            let direction = direction.ok_or_else(|| missing("direction"))?;
            detached(py, || copy.add_directional_light("light", direction, color))?;
        }
        "spot" => {
            let position = position.ok_or_else(|| missing("position"))?;
            let direction = direction.ok_or_else(|| missing("direction"))?;
            let angles = angles.ok_or_else(|| missing("cone angles"))?;
            detached(py, || {
                copy.add_spot_light("light", position, direction, color, angles)
            })?;
        }
        other => {
            return Err(value_error(format!(
                "kind={other:?}: use \"point\", \"directional\" or \"spot\""
            )));
        }
    }
    Ok(NativeScene {
        path: native.path.clone(),
        ..NativeScene::new(copy)
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(camera_rays, m)?)?;
    m.add_function(wrap_pyfunction!(with_light, m)?)?;
    m.add("MAX_SPP", lambert::limits::MAX_SPP)?;
    Ok(())
}
