//! lambert in a browser: what the page (web/static/) calls through
//! wasm-bindgen. A `Session` holds the browser's WebGPU device; it renders
//! a model file's bytes as `lambert render NAME --width W --height H --spp
//! N` would (`renderModel`), or opens it in a `Viewer` that refines it a
//! few samples at a time as `lambert view` does. Everything here awaits
//! the library's asynchronous GPU host: a browser runs the device's
//! callbacks only between its tasks, so nothing may block (docs/web.md).
//!
//! Against the native CPU path (`lambert render --device cpu`) a render
//! here cannot be bit for bit the same (the browser's WGSL compiler and its
//! adapter round differently): web/tests/render.rs compares it with the CPU
//! twin run in the same page, and allows edge pixels to differ by a
//! sample's hit and the rest by 1e-3.

pub mod model;
mod viewer;

use std::path::Path;

use js_sys::{Float32Array, Object, Reflect};
use lambert::gpu::{Gpu, GpuOptions};
use wasm_bindgen::prelude::*;

pub use viewer::Viewer;

/// The browser's WebGPU device, opened once for every render and viewer.
#[wasm_bindgen]
pub struct Session {
    gpu: Gpu,
    /// Whether the browser gave its fallback (software) adapter.
    fallback: bool,
}

#[wasm_bindgen]
impl Session {
    /// Opens the browser's default WebGPU adapter or, where it has none,
    /// its fallback adapter (SwiftShader in Chromium: never refused), with
    /// the adapter's own limits (larger storage bindings than WebGPU's
    /// default 128 MiB, and the wavefronts' 10 storage buffers a stage
    /// where it allows them). Rejects with a message
    /// naming what is missing where the browser has no WebGPU at all.
    pub async fn open() -> Result<Session, JsError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let options = |force_fallback_adapter| wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter,
            compatible_surface: None,
            apply_limit_buckets: false,
        };
        let (adapter, fallback) = match instance.request_adapter(&options(false)).await {
            Ok(adapter) => (adapter, false),
            Err(first) => match instance.request_adapter(&options(true)).await {
                Ok(adapter) => (adapter, true),
                Err(e) => {
                    return Err(JsError::new(&format!(
                        "this browser offers no WebGPU adapter (navigator.gpu.requestAdapter: \
                         {first}; its fallback adapter: {e}); lambert renders through WebGPU"
                    )));
                }
            },
        };
        let gpu = Gpu::open_adapter_async(adapter, &GpuOptions::default())
            .await
            .map_err(js_error)?;
        Ok(Session { gpu, fallback })
    }

    /// The adapter in words: its name, its backend, and "fallback" when
    /// it is the browser's fallback adapter.
    pub fn adapter(&self) -> String {
        match self.fallback {
            true => format!("{}, fallback", self.gpu.describe()),
            false => self.gpu.describe(),
        }
    }

    /// Renders a model file (`name` tells its format: .glb, .gltf with its
    /// buffers and images embedded, .obj, .ply, .stl) as `lambert render
    /// NAME --width W --height H --spp N` does: `{width, height, pixels}`,
    /// `pixels` linear RGB, 3 floats a pixel, rows from the top. Rejects
    /// with lambert's message on a file it cannot read.
    #[wasm_bindgen(js_name = renderModel)]
    pub async fn render_model(
        &self,
        bytes: Vec<u8>,
        name: String,
        width: Option<u32>,
        height: Option<u32>,
        spp: Option<u32>,
    ) -> Result<JsValue, JsError> {
        let image = model::render(&self.gpu, &bytes, Path::new(&name), width, height, spp)
            .await
            .map_err(js_error)?;
        let pixels: Vec<f32> = image.rgb.iter().flatten().copied().collect();
        let result = Object::new();
        for (key, value) in [
            ("width", JsValue::from(image.width)),
            ("height", JsValue::from(image.height)),
            ("pixels", Float32Array::from(pixels.as_slice()).into()),
        ] {
            Reflect::set(&result, &key.into(), &value).map_err(|_| JsError::new("Reflect.set"))?;
        }
        Ok(result.into())
    }

    /// Opens a model file in a `Viewer` at the file's camera (or the
    /// framed one) and its size, `lambert view`'s default.
    #[wasm_bindgen(js_name = openModel)]
    pub async fn open_model(&self, bytes: Vec<u8>, name: String) -> Result<Viewer, JsError> {
        Viewer::open(&self.gpu, &bytes, Path::new(&name))
            .await
            .map_err(js_error)
    }
}

/// A library error as the JS Error it rejects with: lambert's message.
fn js_error(e: lambert::Error) -> JsError {
    JsError::new(&e.to_string())
}
