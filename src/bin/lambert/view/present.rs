//! Showing a frame: its 8-bit sRGB bytes copied as they are into the
//! window's surface (a linear, non-sRGB format, so that no conversion
//! touches them: the screen shows the screenshot's very pixels), on the
//! device that renders.

use std::sync::Arc;

use lambert::error::{Error, Result};
use lambert::gpu::Gpu;
use winit::window::Window;

use super::worker::Frame;

pub struct Presenter {
    pub surface: wgpu::Surface<'static>,
    gpu: Gpu,
    config: wgpu::SurfaceConfiguration,
    /// Whether the surface's bytes are in BGRA order.
    bgra: bool,
}

impl Presenter {
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
        Ok(Presenter {
            surface,
            gpu,
            config,
            bgra: format == wgpu::TextureFormat::Bgra8Unorm,
        })
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.gpu.device, &self.config);
        }
    }

    /// Shows `frame`, at the window's top left (black where a frame of
    /// the size before a resize does not cover it). A window that cannot
    /// show it now (hidden, being resized) skips it: the next frame comes.
    pub fn present(&mut self, frame: &Frame) {
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
        let mut bytes = vec![0u8; width as usize * height as usize * 4];
        let columns = frame.width.min(width) as usize;
        for y in 0..frame.height.min(height) as usize {
            let from = &frame.rgba[y * frame.width as usize * 4..][..columns * 4];
            let to = &mut bytes[y * width as usize * 4..][..columns * 4];
            to.copy_from_slice(from);
            if self.bgra {
                to.chunks_mut(4).for_each(|p| p.swap(0, 2));
            }
        }
        self.gpu.queue.write_texture(
            texture.texture.as_image_copy(),
            &bytes,
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
