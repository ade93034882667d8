//! The window: it opens the device (one that can present to it), starts
//! the render thread, turns input into its commands and shows the frames
//! it sends. It never waits on a render.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Sender};
use std::thread::JoinHandle;

use lambert::camera::View;
use lambert::error::{Error, Result};
use lambert::gpu::{Gpu, Presenting};
use lambert::render::{Progressive, Renderer};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{
    DeviceEvent, DeviceId, ElementState, MouseButton, MouseScrollDelta, WindowEvent,
};
use winit::event_loop::{ActiveEventLoop, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::Settings;
use super::present::{CpuPresenter, GpuPresenter, Presenter};
use super::worker::{Command, Frame, Report, Worker};

/// The keys and the mouse, as `H` prints them (docs/viewer.md too).
pub const KEYS: &str = "\
lambert view: keys and mouse
  left drag          orbit about the look-at point
  right/middle drag  pan
  wheel              dolly (10% closer a notch)
  w a d e            fly forward, left, right, up
  s q                (with a mouse button held) fly back, down
  f                  frame the model
  r                  the camera the file was loaded with
  1 .. 9             the file's cameras (glTF)
  l                  shadows on/off
  p                  path tracing on/off (the direct integrator)
  s, Shift+S         save a screenshot (PNG of the image so far, full resolution)
  c                  print the camera as a [camera] table
  h                  this list
  Esc, q, Shift+Q    quit
  drop a file        load it";

/// What a drag does.
#[derive(Clone, Copy)]
enum Drag {
    Orbit,
    Pan,
}

pub struct App {
    settings: Option<Settings>,
    proxy: EventLoopProxy<Report>,
    window: Option<Arc<Window>>,
    presenter: Option<Presenter>,
    commands: Option<Sender<Command>>,
    worker: Option<JoinHandle<()>>,
    /// Set on quitting: the render thread drops the frame in flight.
    cancel: Arc<AtomicBool>,
    latest: Option<Arc<Frame>>,
    cursor: Option<PhysicalPosition<f64>>,
    drag: Option<Drag>,
    /// A wheel button's release (X11 buttons 4 to 7) came: winit reports
    /// it as a wheel event too, which is not a second notch.
    wheel_released: bool,
    /// What failed without ending the session, shown in the title until
    /// the next try.
    problem: Option<String>,
    /// The heads-up line's device.
    about: String,
    screenshot: Option<PathBuf>,
    quiet: bool,
    failure: Option<Error>,
}

impl App {
    pub fn new(settings: Settings, proxy: EventLoopProxy<Report>) -> App {
        App {
            screenshot: settings.screenshot.clone(),
            quiet: settings.quiet,
            settings: Some(settings),
            proxy,
            window: None,
            presenter: None,
            commands: None,
            worker: None,
            cancel: Arc::new(AtomicBool::new(false)),
            latest: None,
            cursor: None,
            drag: None,
            wheel_released: false,
            problem: None,
            about: String::new(),
            failure: None,
        }
    }

    /// How the run ended.
    pub fn outcome(self) -> Result<ExitCode> {
        match self.failure {
            Some(e) => Err(e),
            None => Ok(ExitCode::SUCCESS),
        }
    }

    /// Opens the window, the device and the render thread.
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let settings = self.settings.take().expect("started once");
        // Raw wheel buttons tell a click's release apart (`device_event`),
        // focused or not.
        event_loop.listen_device_events(winit::event_loop::DeviceEvents::Always);
        let camera = &settings.scene.view().camera;
        let attributes = Window::default_attributes()
            .with_title("lambert view")
            .with_inner_size(PhysicalSize::new(camera.width, camera.height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| Error::Usage(format!("lambert view: cannot open a window: {e}")))?,
        );
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: settings.request.instance_backends()?,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let say = |line: &str| {
            if !settings.quiet {
                eprintln!("{line}");
            }
        };
        // No surface where no backend runs (no Vulkan driver at all): the
        // render goes where `render`'s would, and the CPU shows it.
        let surface = instance.create_surface(Arc::clone(&window));
        let presenting = surface.as_ref().ok().map(|surface| Presenting {
            instance: &instance,
            surface,
        });
        let scene = Arc::new(settings.scene);
        let (renderer, note) = Renderer::open_presenting(
            Arc::clone(&scene),
            settings.device,
            &settings.request,
            presenting.as_ref(),
        )?;
        if let Some(note) = note {
            say(&note);
        }
        // The GPU that renders shows its frames; the CPU path's are shown
        // by any adapter that can present (lavapipe too), else by the CPU.
        let shown_by = match (renderer.gpu(), &presenting) {
            (Some(gpu), Some(_)) => Ok(gpu.clone()),
            (_, Some(p)) => Gpu::open_presenting(&settings.request, false, p),
            (_, None) => Err(Error::Gpu(format!(
                "no surface for the window: {}",
                surface
                    .as_ref()
                    .err()
                    .map(|e| e.to_string())
                    .unwrap_or_default()
            ))),
        };
        if renderer.is_cpu() {
            let shown = match &shown_by {
                Ok(gpu) => format!("shown through {}", gpu.describe()),
                Err(e) => format!("shown by the CPU ({e})"),
            };
            say(&format!(
                "rendering on the CPU path (slower, still progressive); {shown}"
            ));
        }
        let gpu = renderer.gpu().cloned();
        self.about = renderer.describe();
        self.presenter = Some(match (shown_by, surface) {
            (Ok(shown_by), Ok(surface)) => {
                Presenter::Gpu(Box::new(GpuPresenter::new(surface, shown_by, &window)?))
            }
            _ => Presenter::Cpu(CpuPresenter::new(&window)?),
        });
        let view = View {
            spp: settings.spp,
            ..scene.view().clone()
        };
        let worker = Worker {
            path: settings.path.clone(),
            reach: scene.reach(),
            shadows: scene.default_settings().shadows,
            integrator: scene.default_settings().integrator,
            scene,
            renderer,
            cancel: Arc::clone(&self.cancel),
            gpu,
            progressive: Progressive::new(view),
            frames_screenshot: settings
                .frames
                .then(|| settings.screenshot.clone())
                .flatten(),
        };
        let (sender, receiver) = mpsc::channel();
        let proxy = self.proxy.clone();
        self.worker = Some(
            std::thread::Builder::new()
                .name("lambert view render".into())
                .spawn(move || worker.run(receiver, |r| proxy.send_event(r).is_ok()))
                .map_err(|e| Error::Usage(format!("cannot start the render thread: {e}")))?,
        );
        self.commands = Some(sender);
        self.window = Some(window);
        Ok(())
    }

    fn send(&self, command: Command) {
        if let Some(commands) = &self.commands {
            // A render thread that is gone has reported why.
            let _ = commands.send(command);
        }
    }

    /// Ends the run: the render thread drops the frame in flight (at its
    /// next tile) and stops.
    fn quit(&mut self, event_loop: &ActiveEventLoop) {
        self.cancel.store(true, Ordering::Relaxed);
        self.commands = None;
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
        event_loop.exit();
    }

    fn fail(&mut self, error: Error, event_loop: &ActiveEventLoop) {
        self.failure.get_or_insert(error);
        self.quit(event_loop);
    }

    fn present(&mut self, event_loop: &ActiveEventLoop) {
        if let (Some(presenter), Some(frame)) = (&mut self.presenter, &self.latest)
            && let Err(e) = presenter.present(frame)
        {
            self.fail(e, event_loop);
        }
    }

    /// Where `S` writes: `--screenshot`, else the first free
    /// lambert-view-NNN.png here.
    fn screenshot_path(&self) -> PathBuf {
        if let Some(path) = &self.screenshot {
            return path.clone();
        }
        (1..)
            .map(|n| PathBuf::from(format!("lambert-view-{n:03}.png")))
            .find(|p| !p.exists())
            .expect("a free name")
    }

    fn key(&mut self, key: &Key, event_loop: &ActiveEventLoop) {
        let text = match key {
            Key::Named(NamedKey::Escape) => return self.quit(event_loop),
            Key::Character(text) => text.as_str(),
            _ => return,
        };
        let mut chars = text.chars();
        let (Some(c), None) = (chars.next(), chars.next()) else {
            return;
        };
        // `s` and `q` are both the screenshot and quit and WASD/QE's
        // back and down: they fly while a mouse button is held (as in
        // viewers that fly with the right button down), else save and quit.
        let flying = self.drag.is_some();
        match c {
            'Q' => self.quit(event_loop),
            'q' if !flying => self.quit(event_loop),
            'S' => self.screenshot(),
            's' if !flying => self.screenshot(),
            'w' | 'a' | 's' | 'd' | 'e' | 'q' => self.send(Command::Fly(c)),
            'f' | 'F' => self.send(Command::Frame),
            'r' | 'R' => self.send(Command::FileCamera(None)),
            '1'..='9' => self.send(Command::FileCamera(Some(c as usize - '1' as usize))),
            'l' | 'L' => self.send(Command::ToggleShadows),
            'p' | 'P' => self.send(Command::ToggleIntegrator),
            'c' | 'C' => self.send(Command::PrintCamera),
            'h' | 'H' => println!("{KEYS}"),
            _ => {}
        }
    }

    fn screenshot(&mut self) {
        self.problem = None;
        self.show_title();
        self.send(Command::Screenshot(self.screenshot_path()));
    }

    /// The heads-up line: the latest frame's figures, and a problem.
    fn show_title(&self) {
        let (Some(window), Some(frame)) = (&self.window, &self.latest) else {
            return;
        };
        let done = if frame.samples == frame.spp {
            ", done"
        } else {
            ""
        };
        let problem = self
            .problem
            .as_ref()
            .map_or(String::new(), |p| format!(" — error: {p}"));
        window.set_title(&format!(
            "lambert view — {}/{} spp{done} — {:.2} Mrays/s — {:.1} ms/frame — {} triangles — {} — H: keys{problem}",
            frame.samples,
            frame.spp,
            frame.mrays_per_s,
            frame.frame_time.as_secs_f64() * 1e3,
            frame.triangles,
            self.about
        ));
    }

    fn frame_arrived(&mut self, frame: Arc<Frame>) {
        self.latest = Some(frame);
        self.show_title();
        if let Some(window) = &self.window {
            window.request_redraw();
        }
    }
}

impl ApplicationHandler<Report> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.settings.is_some()
            && let Err(e) = self.start(event_loop)
        {
            self.fail(e, event_loop);
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, report: Report) {
        match report {
            Report::Frame(frame) => self.frame_arrived(frame),
            Report::Say(line) => {
                if !self.quiet {
                    eprintln!("{line}");
                }
            }
            Report::Print(text) => print!("{text}"),
            // An error: shown even with --quiet.
            Report::Problem(text) => {
                eprintln!("error: {text}");
                self.problem = Some(text);
                self.show_title();
            }
            Report::Finished => {
                self.present(event_loop);
                self.quit(event_loop);
            }
            Report::Failed(e) => self.fail(Error::Usage(e), event_loop),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            // Destroyed: by the window manager, with no close request.
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.quit(event_loop),
            WindowEvent::RedrawRequested => self.present(event_loop),
            WindowEvent::Resized(size) => {
                if let Some(presenter) = &mut self.presenter {
                    presenter.resize(size.width, size.height);
                }
                if size.width > 0 && size.height > 0 {
                    self.send(Command::Resize {
                        width: size.width,
                        height: size.height,
                    });
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(&event.logical_key, event_loop);
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = match (state, button) {
                    (ElementState::Pressed, MouseButton::Left) => Some(Drag::Orbit),
                    (ElementState::Pressed, MouseButton::Right | MouseButton::Middle) => {
                        Some(Drag::Pan)
                    }
                    _ => None,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (Some(drag), Some(last)) = (self.drag, self.cursor) {
                    let (dx, dy) = (position.x - last.x, position.y - last.y);
                    self.send(match drag {
                        Drag::Orbit => Command::Orbit { dx, dy },
                        Drag::Pan => Command::Pan { dx, dy },
                    });
                }
                self.cursor = Some(position);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                if std::mem::take(&mut self.wheel_released)
                    && matches!(delta, MouseScrollDelta::LineDelta(..))
                {
                    return;
                }
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 50.0,
                };
                self.send(Command::Dolly(notches));
            }
            WindowEvent::DroppedFile(path) => self.send(Command::Load(path)),
            _ => {}
        }
    }

    /// X11's wheel is buttons 4 to 7, and winit 0.30 makes a wheel event
    /// of both a button's press and its release: its raw release (which
    /// comes just before) marks the next wheel event as that echo. Wheels
    /// that scroll by valuators instead send no raw button at all.
    fn device_event(&mut self, _: &ActiveEventLoop, _: DeviceId, event: DeviceEvent) {
        if let DeviceEvent::Button {
            button: 4..=7,
            state,
        } = event
        {
            self.wheel_released = state == ElementState::Released;
        }
    }
}
