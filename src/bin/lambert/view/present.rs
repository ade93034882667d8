//! Showing a frame: its 8-bit sRGB bytes copied as they are into the
//! window's surface (a linear, non-sRGB format, so that no conversion
//! touches them: the screen shows the screenshot's very pixels), on the
//! device that renders; or, where no adapter can present to the window,
//! written by the CPU into the window's own buffer (softbuffer).

use std::num::NonZeroU32;
use std::sync::Arc;

use lambert::error::{Error, Result};
use lambert::gpu::Gpu;
use winit::window::Window;

use super::worker::Frame;

pub enum Presenter {
    /// Boxed: a surface's configuration is large.
    Gpu(Box<GpuPresenter>),
    Cpu(CpuPresenter),
}

impl Presenter {
    pub fn resize(&mut self, width: u32, height: u32) {
        match self {
            Presenter::Gpu(p) => p.resize(width, height),
            Presenter::Cpu(p) => (p.width, p.height) = (width, height),
        }
    }

    /// Shows `frame`, at the window's top left (black where a frame of
    /// the size before a resize does not cover it).
    pub fn present(&mut self, frame: &Frame) -> Result<()> {
        match self {
            Presenter::Gpu(p) => {
                p.present(frame);
                Ok(())
            }
            Presenter::Cpu(p) => p.present(frame),
        }
    }
}

/// `frame`'s pixels laid out in a `width` × `height` window, each a
/// `pixel` of its 8-bit sRGB R, G and B, black beyond the frame.
fn fit<T: Copy>(
    frame: &Frame,
    width: u32,
    height: u32,
    black: T,
    pixel: impl Fn(&[u8]) -> T,
) -> Vec<T> {
    let mut out = vec![black; width as usize * height as usize];
    let columns = frame.width.min(width) as usize;
    for y in 0..frame.height.min(height) as usize {
        let from = &frame.rgba[y * frame.width as usize * 4..][..columns * 4];
        let to = &mut out[y * width as usize..][..columns];
        for (to, from) in to.iter_mut().zip(from.chunks(4)) {
            *to = pixel(from);
        }
    }
    out
}

/// The CPU writing the window's pixels (X11's PutImage), where no
/// adapter can present.
pub struct CpuPresenter {
    surface: softbuffer::Surface<Arc<Window>, Arc<Window>>,
    width: u32,
    height: u32,
}

impl CpuPresenter {
    pub fn new(window: &Arc<Window>) -> Result<CpuPresenter> {
        let fail = |e: softbuffer::SoftBufferError| {
            Error::Usage(format!("showing frames without a GPU (softbuffer): {e}"))
        };
        let context = softbuffer::Context::new(Arc::clone(window)).map_err(fail)?;
        let surface = softbuffer::Surface::new(&context, Arc::clone(window)).map_err(fail)?;
        let size = window.inner_size();
        Ok(CpuPresenter {
            surface,
            width: size.width,
            height: size.height,
        })
    }

    fn present(&mut self, frame: &Frame) -> Result<()> {
        let fail = |e: softbuffer::SoftBufferError| Error::Usage(format!("showing a frame: {e}"));
        let (Some(width), Some(height)) =
            (NonZeroU32::new(self.width), NonZeroU32::new(self.height))
        else {
            return Ok(());
        };
        self.surface.resize(width, height).map_err(fail)?;
        let pixels = fit(frame, self.width, self.height, 0u32, |p| {
            (p[0] as u32) << 16 | (p[1] as u32) << 8 | p[2] as u32
        });
        let mut buffer = self.surface.buffer_mut().map_err(fail)?;
        buffer.copy_from_slice(&pixels);
        buffer.present().map_err(fail)
    }
}

pub struct GpuPresenter {
    surface: wgpu::Surface<'static>,
    gpu: Gpu,
    config: wgpu::SurfaceConfiguration,
    /// Whether the surface's bytes are in BGRA order.
    bgra: bool,
}

impl GpuPresenter {
    /// Configures `surface` (made by the instance `gpu`'s adapter came
    /// from) for `window` on `gpu`.
    pub fn new(surface: wgpu::Surface<'static>, gpu: Gpu, window: &Arc<Window>) -> Result<Self> {
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = [
            wgpu::TextureFormat::Bgra8Unorm,
            wgpu::TextureFormat::Rgba8Unorm,
        ]
        .into_iter()
        .find(|f| caps.formats.contains(f))
        .ok_or_else(|| {
            Error::Gpu(format!(
                "{}: the window offers none of Bgra8Unorm and Rgba8Unorm (it offers {:?})",
                gpu.describe(),
                caps.formats
            ))
        })?;
        if !caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
            return Err(Error::Gpu(format!(
                "{}: the window's surface cannot be copied to (usages {:?})",
                gpu.describe(),
                caps.usages
            )));
        }
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::COPY_DST,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &config);
        Ok(GpuPresenter {
            surface,
            gpu,
            config,
            bgra: format == wgpu::TextureFormat::Bgra8Unorm,
        })
    }

    fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.gpu.device, &self.config);
        }
    }

    /// A window that cannot show a frame now (hidden, being resized)
    /// skips it: the next frame comes.
    fn present(&mut self, frame: &Frame) {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return;
            }
            _ => return,
        };
        let (width, height) = (self.config.width, self.config.height);
        let order = if self.bgra { [2, 1, 0] } else { [0, 1, 2] };
        let pixels = fit(frame, width, height, [0u8, 0, 0, 255], |p| {
            [p[order[0]], p[order[1]], p[order[2]], 255]
        });
        self.gpu.queue.write_texture(
            texture.texture.as_image_copy(),
            bytemuck::cast_slice(&pixels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 4),
                rows_per_image: Some(height),
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([]);
        self.gpu.queue.present(texture);
    }
}
