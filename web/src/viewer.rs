//! `lambert view` in the page: a model refined a few samples at a time,
//! its camera moved by the library's `camera::navigate` (the native
//! viewer's moves), every move restarting the samples.

use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use lambert::camera::navigate::{INTERACTIVE_SPP, Reach, dolly, orbit, pan};
use lambert::camera::{Camera, View};
use lambert::gpu::Gpu;
use lambert::limits::validate_resolution;
use lambert::output::Image;
use lambert::render::{Progressive, Renderer};
use wasm_bindgen::prelude::*;

/// A model shown progressively (`Session.openModel`).
#[wasm_bindgen]
pub struct Viewer {
    /// The renderer and the samples so far; taken out while a batch is
    /// on the device, so that the camera may move meanwhile.
    engine: RefCell<Option<(Renderer, Progressive)>>,
    /// The camera to render next (its size the picture's), and the one
    /// the model came with (`resetCamera`).
    camera: RefCell<Camera>,
    home: Camera,
    reach: Reach,
    /// The mean of the samples so far, and their count.
    shown: RefCell<(Image, u32)>,
    warnings: Vec<String>,
}

impl Viewer {
    /// The model of `bytes` (`path` names it) on `gpu`, at its file's
    /// camera or the framed one, `lambert view`'s samples per pixel.
    pub async fn open(gpu: &Gpu, bytes: &[u8], path: &Path) -> lambert::Result<Viewer> {
        let (scene, settings) =
            super::model::scene(bytes, path, None, None, Some(INTERACTIVE_SPP))?;
        let camera = settings.view.camera.clone();
        let reach = scene.reach();
        let warnings = scene.warnings().to_vec();
        let renderer = Renderer::open_on_gpu(Arc::new(scene), gpu).await?;
        let progressive = Progressive::new(settings.view);
        let shown = (progressive.image(), 0);
        Ok(Viewer {
            engine: RefCell::new(Some((renderer, progressive))),
            camera: RefCell::new(camera.clone()),
            home: camera,
            reach,
            shown: RefCell::new(shown),
            warnings,
        })
    }

    /// Moves the camera by `change` of the camera (and the picture's
    /// height, which sets a drag's scale); the next batch starts over.
    fn move_camera(&self, change: impl FnOnce(&Camera, u32, &Reach) -> Camera) {
        let mut camera = self.camera.borrow_mut();
        *camera = change(&camera, camera.height, &self.reach);
    }
}

#[wasm_bindgen]
impl Viewer {
    /// Renders at `width` × `height` from now on (the camera's aspect
    /// follows, as the native window's does).
    pub fn resize(&self, width: u32, height: u32) -> Result<(), JsError> {
        validate_resolution(width, height).map_err(|e| JsError::new(&e))?;
        let mut camera = self.camera.borrow_mut();
        camera.width = width;
        camera.height = height;
        Ok(())
    }

    /// A drag with the left button: orbits about the look-at point.
    pub fn orbit(&self, dx: f64, dy: f64) {
        self.move_camera(|c, height, reach| orbit(c, dx, dy, height, reach));
    }

    /// A drag with the right or middle button: the point under the cursor
    /// follows it.
    pub fn pan(&self, dx: f64, dy: f64) {
        self.move_camera(|c, height, reach| pan(c, dx, dy, height, reach));
    }

    /// Wheel notches towards the scene (negative: away), 10% each.
    pub fn dolly(&self, steps: f64) {
        self.move_camera(|c, _, reach| dolly(c, steps, reach));
    }

    /// Back to the file's camera or the framed one, at the current size.
    #[wasm_bindgen(js_name = resetCamera)]
    pub fn reset_camera(&self) {
        self.move_camera(|c, _, _| Camera {
            width: c.width,
            height: c.height,
            ..self.home.clone()
        });
    }

    /// Adds `n` samples per pixel (fewer once all of `lambert view`'s are
    /// in) and returns the samples per pixel so far; a camera moved or
    /// resized since the last batch starts the image over. Rejects while
    /// another batch is still running.
    #[wasm_bindgen(js_name = addSamples)]
    pub async fn add_samples(&self, n: u32) -> Result<u32, JsError> {
        let taken = self.engine.borrow_mut().take();
        let (mut renderer, mut progressive) =
            taken.ok_or_else(|| JsError::new("addSamples: the last batch is still running"))?;
        let camera = self.camera.borrow().clone();
        if progressive.view().camera != camera {
            progressive = Progressive::new(View {
                camera,
                ..progressive.view().clone()
            });
        }
        let added = renderer
            .add_samples_async(&mut progressive, n, &AtomicBool::new(false))
            .await;
        let samples = progressive.samples();
        *self.shown.borrow_mut() = (progressive.image(), samples);
        *self.engine.borrow_mut() = Some((renderer, progressive));
        added.map_err(super::js_error)?;
        Ok(samples)
    }

    /// The image so far as 8-bit sRGB RGBA, rows from the top: a canvas's
    /// ImageData.
    pub fn rgba(&self) -> Vec<u8> {
        self.shown.borrow().0.to_rgba8()
    }

    /// The image so far as the PNG `lambert render` writes.
    pub fn png(&self) -> Result<Vec<u8>, JsError> {
        self.shown.borrow().0.to_png().map_err(super::js_error)
    }

    /// Samples per pixel in the image so far.
    pub fn spp(&self) -> u32 {
        self.shown.borrow().1
    }

    /// Rays a sample of a pixel counts in Mrays/s: its camera ray, as
    /// `lambert view` counts them.
    #[wasm_bindgen(js_name = raysPerSample)]
    pub fn rays_per_sample(&self) -> f64 {
        1.0
    }

    /// The picture's size (the image so far may be of the last).
    pub fn width(&self) -> u32 {
        self.camera.borrow().width
    }

    pub fn height(&self) -> u32 {
        self.camera.borrow().height
    }

    /// What loading skipped (an OBJ's MTL file that cannot be read here,
    /// an image that does not decode), each naming its file.
    pub fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
}
