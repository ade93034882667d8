//! The viewer's render thread: it owns the renderer and the progressive
//! render of the current view, adds a sample per frame, and hands each
//! frame to the window (which never waits on it); the window's commands
//! (a new camera, shadows, another model, a screenshot) reach it between
//! frames.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use lambert::camera::{Camera, View};
use lambert::error::{Error, Result};
use lambert::gpu::Gpu;
use lambert::render::{Progressive, Renderer};
use lambert::scene::{Integrator, RenderSettings, Scene};

use lambert::camera::navigate::Reach;

/// What the window asks of the render thread.
pub enum Command {
    /// A drag, in pixels (`navigate::orbit`, `navigate::pan`).
    Orbit {
        dx: f64,
        dy: f64,
    },
    Pan {
        dx: f64,
        dy: f64,
    },
    /// Notches of the wheel, towards the scene positive.
    Dolly(f64),
    /// A fly key: w, a, s, d, e or q.
    Fly(char),
    /// The window's new size: the image's.
    Resize {
        width: u32,
        height: u32,
    },
    /// Frame the model (`F`).
    Frame,
    /// The file's camera (`R`: None), or its glTF camera 1 to 9.
    FileCamera(Option<usize>),
    /// Shadows on or off (`L`).
    ToggleShadows,
    /// The direct integrator or path tracing (`P`).
    ToggleIntegrator,
    /// Another scene or model file (dropped on the window).
    Load(PathBuf),
    /// Write the image so far (`S`).
    Screenshot(PathBuf),
    /// Print the camera as a `[camera]` table (`C`).
    PrintCamera,
}

/// What the render thread tells the window.
pub enum Report {
    Frame(Arc<Frame>),
    /// A line for the terminal (stderr: notes, unless --quiet).
    Say(String),
    /// A result for the terminal (stdout: the `[camera]` table).
    Print(String),
    /// Something that failed without ending the session (a screenshot
    /// not written): on stderr and in the window's title.
    Problem(String),
    /// `--frames N`: the last frame is in and the screenshot written.
    Finished,
    Failed(String),
}

/// One frame: the image so far as 8-bit sRGB (the PNG's bytes), and the
/// heads-up line's figures.
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA, 8-bit sRGB, row by row.
    pub rgba: Vec<u8>,
    pub samples: u32,
    pub spp: u32,
    pub frame_time: Duration,
    pub mrays_per_s: f64,
    pub triangles: usize,
}

/// The render thread's state.
pub struct Worker {
    /// The host's copy, for framing and for its camera as loaded (`R`).
    pub scene: Arc<Scene>,
    /// The file the scene came from (its glTF cameras, `1`–`9`).
    pub path: PathBuf,
    pub renderer: Renderer,
    /// Whether the renderer traces shadows (`l` toggles it).
    pub shadows: bool,
    /// The renderer's integrator (`p` toggles it).
    pub integrator: Integrator,
    /// Where the camera may go in this scene.
    pub reach: Reach,
    /// Set by the window to stop the frame in flight (it is quitting).
    pub cancel: Arc<AtomicBool>,
    /// The device the renderer renders on, when a GPU's: rebuilds stay on
    /// the device the window presents with.
    pub gpu: Option<Gpu>,
    pub progressive: Progressive,
    /// `--frames N`: write here once the N samples are in, then stop.
    pub frames_screenshot: Option<PathBuf>,
}

impl Worker {
    /// Runs until the window goes (`commands` closes); `report` returns
    /// false once the window is gone.
    pub fn run(mut self, commands: Receiver<Command>, report: impl Fn(Report) -> bool) {
        loop {
            if self.cancel.load(Ordering::Relaxed) {
                return;
            }
            let command = if self.progressive.is_finished() {
                match commands.recv() {
                    Ok(command) => Some(command),
                    Err(_) => return,
                }
            } else {
                match commands.try_recv() {
                    Ok(command) => Some(command),
                    Err(TryRecvError::Empty) => None,
                    Err(TryRecvError::Disconnected) => return,
                }
            };
            let step = match command {
                Some(command) => self.obey(command, &report),
                None => self.add_frame(&report),
            };
            if let Err(e) = step {
                report(Report::Failed(e.to_string()));
                return;
            }
        }
    }

    fn obey(&mut self, command: Command, report: &impl Fn(Report) -> bool) -> Result<()> {
        use lambert::camera::navigate::{camera_toml, dolly, fly, frame, orbit, pan};
        let camera = self.progressive.view().camera.clone();
        let (width, height) = (camera.width, camera.height);
        let sized = |c: Camera| Camera { width, height, ..c };
        let reach = self.reach;
        match command {
            Command::Orbit { dx, dy } => self.restart(orbit(&camera, dx, dy, height, &reach)),
            Command::Pan { dx, dy } => self.restart(pan(&camera, dx, dy, height, &reach)),
            Command::Dolly(notches) => self.restart(dolly(&camera, notches, &reach)),
            Command::Fly(key) => {
                if let Some(moved) = fly(&camera, key, &reach) {
                    self.restart(moved);
                }
            }
            Command::Resize { width, height } => {
                if (width, height) != (camera.width, camera.height) {
                    self.restart(Camera {
                        width,
                        height,
                        ..camera
                    });
                }
            }
            Command::Frame => match self.scene.bvh().bounds() {
                Some(b) => {
                    let offset = self.scene.offset();
                    let bounds = (b.min.as_dvec3() + offset, b.max.as_dvec3() + offset);
                    // Spheres are never flat; triangles alone may be.
                    let scene = &self.scene;
                    let flat = scene.spheres().is_empty().then(|| {
                        lambert::camera::flat_normal(|| {
                            scene.triangles().iter().flat_map(|t| {
                                [t.v0, t.v1, t.v2].map(|v| glam::Vec3::from(v).as_dvec3())
                            })
                        })
                    });
                    self.restart(frame(bounds, flat.flatten(), width, height, &reach));
                }
                None => {
                    report(Report::Say("the scene has no geometry to frame".into()));
                }
            },
            Command::FileCamera(index) => match self.file_camera(index) {
                Ok(camera) => self.restart(sized(camera)),
                Err(e) => {
                    report(Report::Say(format!("{e}")));
                }
            },
            Command::ToggleShadows => {
                let on = !self.shadows;
                self.respecialise(|renderer| renderer.set_shadows(on))?;
                self.shadows = on;
                report(Report::Say(format!(
                    "shadows {}",
                    if on { "on" } else { "off" }
                )));
                self.restart(camera);
            }
            Command::ToggleIntegrator => {
                let integrator = match self.integrator {
                    Integrator::Direct => Integrator::Path,
                    Integrator::Path => Integrator::Direct,
                };
                let settings = RenderSettings {
                    integrator,
                    shadows: self.shadows,
                    ..self.scene.default_settings()
                };
                if self.scene.lights_change_with(integrator) {
                    // The default light goes (or comes back) as `lambert
                    // render --integrator` has it: another scene's lights,
                    // so a renderer takes the scene again.
                    let scene = Arc::new((*self.scene).clone().with_settings(&settings));
                    let renderer = self.renderer_for(&scene)?;
                    self.show(scene, renderer, camera);
                } else {
                    let max_depth = settings.max_depth;
                    self.respecialise(|renderer| renderer.set_integrator(integrator, max_depth))?;
                    self.restart(camera);
                }
                self.integrator = integrator;
                report(Report::Say(format!("integrator {}", integrator.name())));
            }
            Command::Load(path) => match Scene::load(&path) {
                Ok(scene) => {
                    for warning in scene.warnings() {
                        report(Report::Say(format!("warning: {warning}")));
                    }
                    let camera = sized(scene.view().camera.clone());
                    // Another scene: the one shown stays until this one
                    // is on the device, and where it does not go there.
                    let scene = Arc::new(scene);
                    match self.renderer_for(&scene) {
                        Ok(renderer) => {
                            self.shadows = scene.default_settings().shadows;
                            self.integrator = scene.default_settings().integrator;
                            self.show(scene, renderer, camera);
                            report(Report::Say(format!("loaded {}", path.display())));
                            self.path = path;
                        }
                        Err(e) => {
                            report(Report::Say(format!("error: {}: {e}", path.display())));
                        }
                    }
                }
                Err(e) => {
                    report(Report::Say(format!("error: {e}")));
                }
            },
            Command::Screenshot(path) => match self.progressive.image().save(&path) {
                Ok(()) => {
                    report(Report::Say(format!(
                        "wrote {} ({} spp)",
                        path.display(),
                        self.progressive.samples()
                    )));
                }
                // The session goes on: the next `s` may find room.
                Err(e) => {
                    report(Report::Problem(format!("screenshot not written: {e}")));
                }
            },
            Command::PrintCamera => {
                report(Report::Print(camera_toml(&camera)));
            }
        }
        Ok(())
    }

    /// The camera the file was loaded with (`index` None: no reparse), or
    /// its glTF camera `index`.
    fn file_camera(&self, index: Option<usize>) -> Result<Camera> {
        let Some(index) = index else {
            return Ok(self.scene.view().camera.clone());
        };
        let is_gltf = lambert::loading::Format::of(&self.path).is_ok_and(|f| f.is_gltf());
        if !is_gltf {
            return Err(Error::Usage(format!(
                "{}: keys 1 to 9 choose a glTF file's cameras; this is no glTF file",
                self.path.display()
            )));
        }
        let mode = lambert::loading::NormalMode::Smooth;
        let cameras = lambert::loading::gltf::load_scene(&self.path, mode)?.cameras;
        let Some(name) = cameras.get(index).map(|c| c.name.clone()) else {
            return Err(Error::Usage(format!(
                "{} has {} perspective camera(s); there is no camera {}",
                self.path.display(),
                cameras.len(),
                index + 1
            )));
        };
        // Chosen by name as `--camera` does; an unnamed one only as the first.
        let name = match (name, index) {
            (Some(name), _) => Some(name),
            (None, 0) => None,
            (None, _) => {
                return Err(Error::Usage(format!(
                    "camera {} of {} has no name: only a first camera is chosen unnamed",
                    index + 1,
                    self.path.display()
                )));
            }
        };
        Ok(Scene::load_with_camera(&self.path, name.as_deref())?
            .view()
            .camera
            .clone())
    }

    /// A renderer of `scene` on the device the renderer was on (or the
    /// CPU path, sharing the host's copy).
    fn renderer_for(&self, scene: &Arc<Scene>) -> Result<Renderer> {
        Renderer::open_on(Arc::clone(scene), self.gpu.as_ref())
    }

    /// `scene`, rendered by `renderer`, seen from `camera`.
    fn show(&mut self, scene: Arc<Scene>, renderer: Renderer, camera: Camera) {
        self.renderer = renderer;
        self.reach = scene.reach();
        self.scene = scene;
        self.restart(camera);
    }

    /// Starts the view again from its first sample, from `camera`.
    /// Changes a setting the renderer is specialised on (`change`): on a
    /// GPU, its pipelines specialised again, the scene staying uploaded.
    /// The CPU path shares our scene: ours goes first, so that the
    /// renderer changes it in place (never two copies at once), and comes
    /// back changed.
    fn respecialise(&mut self, change: impl FnOnce(&mut Renderer) -> Result<()>) -> Result<()> {
        let empty = Arc::new(Scene::from_triangles(Vec::new()));
        let ours = std::mem::replace(&mut self.scene, empty);
        let kept = self.renderer.shared_scene().is_none().then_some(ours);
        let changed = change(&mut self.renderer);
        match (self.renderer.shared_scene(), kept) {
            (Some(scene), _) => self.scene = Arc::clone(scene),
            (None, Some(ours)) => self.scene = ours,
            (None, None) => {}
        }
        changed
    }

    fn restart(&mut self, camera: Camera) {
        let view = View {
            camera,
            ..self.progressive.view().clone()
        };
        self.progressive = Progressive::new(view);
    }

    /// Adds one sample per pixel and reports the frame; with `--frames`,
    /// writes the screenshot after the last. A frame cancelled (the window
    /// is quitting) reports nothing.
    fn add_frame(&mut self, report: &impl Fn(Report) -> bool) -> Result<()> {
        let start = Instant::now();
        if !self
            .renderer
            .add_samples_or_cancel(&mut self.progressive, 1, &self.cancel)?
        {
            return Ok(());
        }
        let frame_time = start.elapsed();
        let image = self.progressive.image();
        let view = self.progressive.view();
        let rays = view.camera.width as f64 * view.camera.height as f64;
        let frame = Frame {
            width: image.width,
            height: image.height,
            rgba: image.to_rgba8(),
            samples: self.progressive.samples(),
            spp: view.spp,
            frame_time,
            mrays_per_s: rays / frame_time.as_secs_f64().max(1e-9) / 1e6,
            triangles: self.scene.triangles().len(),
        };
        report(Report::Frame(Arc::new(frame)));
        if self.progressive.is_finished()
            && let Some(path) = self.frames_screenshot.take()
        {
            image.save(&path)?;
            report(Report::Say(format!("wrote {}", path.display())));
            report(Report::Finished);
        }
        Ok(())
    }
}
