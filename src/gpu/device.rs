//! An open device and queue: its limits, its error slot, and waiting on it.

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

use super::adapter::{AdapterRequest, Presenting, choose_adapter, describe, is_software};
use super::features::device_features;
use super::options::GpuOptions;
use super::signal::signal;

/// An open device and queue. A clone shares them (a viewer presents on
/// the device its renderer renders on).
#[derive(Clone)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// The adapter it was opened on (a window asks it what it can show).
    pub adapter: wgpu::Adapter,
    pub limits: wgpu::Limits,
    /// The request's options, for the renderers opened on this device.
    pub options: GpuOptions,
    errors: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// The threads llvmpipe splits a dispatch between (the shader's
    /// `CPU_THREADS`, which deals them neighbouring blocks of work in
    /// turn): Mesa's `LP_NUM_THREADS` or the CPUs it sees, at most its
    /// `LP_MAX_THREADS`; 1 on other adapters, which schedule workgroups
    /// themselves. A count that differs from llvmpipe's own still gives a
    /// permutation of the work, only a less even one.
    pub fn cpu_threads(&self) -> u32 {
        /// Mesa's LP_MAX_THREADS (gallium/drivers/llvmpipe/lp_limits.h).
        const LLVMPIPE_MAX_THREADS: u32 = 32;
        if !self.is_llvmpipe() {
            return 1;
        }
        let cpus = || std::thread::available_parallelism().map_or(1, |n| n.get() as u32);
        let threads = match &self.options.llvmpipe_threads {
            Some(v) => v.trim().parse().unwrap_or_else(|_| cpus()),
            None => cpus(),
        };
        threads.clamp(1, LLVMPIPE_MAX_THREADS)
    }

    /// Mesa's llvmpipe (lavapipe, or through GL).
    pub fn is_llvmpipe(&self) -> bool {
        super::adapter::is_llvmpipe(&self.info)
    }

    /// Opens the best adapter matching `request`: hardware before software,
    /// Vulkan/Metal/DX12 before GL. With `hardware_only`, software
    /// rasterisers such as lavapipe do not count.
    pub fn open(request: &AdapterRequest, hardware_only: bool) -> Result<Gpu> {
        Gpu::open_limited(request, hardware_only, request.options.max_buffer_bytes()?)
    }

    /// Opens `adapter`'s device (one the caller found: the browser's, which
    /// only `request_adapter` gives) with `options`, requesting the
    /// adapter's limits; the one asynchronous opening the blocking ones
    /// wait on.
    pub async fn open_adapter_async(adapter: wgpu::Adapter, options: &GpuOptions) -> Result<Gpu> {
        let request = AdapterRequest {
            options: options.clone(),
            ..AdapterRequest::default()
        };
        let max_buffer_bytes = options.max_buffer_bytes()?;
        Gpu::open_adapter(adapter, &request, max_buffer_bytes).await
    }

    /// `open`, requesting at most `max_buffer_bytes` per buffer and per
    /// storage binding (when given) instead of all the adapter offers: what
    /// a smaller GPU would do, for tests and for sharing a device.
    pub fn open_limited(
        request: &AdapterRequest,
        hardware_only: bool,
        max_buffer_bytes: Option<u64>,
    ) -> Result<Gpu> {
        pollster::block_on(Gpu::open_adapter(
            choose_adapter(request, hardware_only, None)?,
            request,
            max_buffer_bytes,
        ))
    }

    /// `open`, choosing among the adapters that can present to a window.
    pub fn open_presenting(
        request: &AdapterRequest,
        hardware_only: bool,
        presenting: &Presenting,
    ) -> Result<Gpu> {
        let adapter = choose_adapter(request, hardware_only, Some(presenting))?;
        let max_buffer_bytes = request.options.max_buffer_bytes()?;
        pollster::block_on(Gpu::open_adapter(adapter, request, max_buffer_bytes))
    }

    async fn open_adapter(
        adapter: wgpu::Adapter,
        request: &AdapterRequest,
        max_buffer_bytes: Option<u64>,
    ) -> Result<Gpu> {
        let info = adapter.get_info();
        let limits = requested_limits(&adapter, max_buffer_bytes);
        // GPU time of each dispatch, where the adapter can measure it; ray
        // queries where asked for and the adapter has them.
        let (required_features, experimental_features) =
            device_features(&adapter, request.ray_queries);
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("lambert"),
                required_features,
                required_limits: limits.clone(),
                experimental_features,
                ..Default::default()
            })
            .await
            .map_err(|e| Error::Gpu(format!("cannot open {}: {e}", describe(&info))))?;
        let errors = error_slot(&device, &info);
        Ok(Gpu {
            device,
            queue,
            info,
            adapter,
            limits,
            options: request.options.clone(),
            errors,
        })
    }

    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// A software rasteriser such as lavapipe.
    pub fn is_software(&self) -> bool {
        is_software(&self.info)
    }

    fn check_errors(&self) -> Result<()> {
        match self.errors.lock().unwrap().take() {
            Some(e) => Err(Error::Gpu(e)),
            None => Ok(()),
        }
    }

    /// Waits until the queue's work is done, and fails with the first
    /// error the device reported meanwhile. Natively `poll` blocks until
    /// then (and runs the callbacks); on the web it does nothing and the
    /// queue's callback comes when the browser's event loop turns.
    pub(super) async fn wait(&self) -> Result<()> {
        let (sender, done) = signal();
        self.queue.on_submitted_work_done(move || sender.send(()));
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        done.await;
        self.check_errors()
    }

    /// Largest storage binding, bytes.
    pub(super) fn binding_limit(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }
}

/// The adapter's real limits, not wgpu's conservative defaults (large
/// scenes need big storage bindings), capped at `max_buffer_bytes`.
fn requested_limits(adapter: &wgpu::Adapter, max_buffer_bytes: Option<u64>) -> wgpu::Limits {
    let mut limits = adapter.limits();
    if let Some(max) = max_buffer_bytes {
        limits.max_buffer_size = limits.max_buffer_size.min(max);
        limits.max_storage_buffer_binding_size = limits.max_storage_buffer_binding_size.min(max);
    }
    limits
}

/// Where the device's errors wait for the next `Gpu::wait`.
fn error_slot(device: &wgpu::Device, info: &wgpu::AdapterInfo) -> Arc<Mutex<Option<String>>> {
    // wgpu's default handler panics; keep the error and report it instead.
    let errors = Arc::new(Mutex::new(None));
    let slot = errors.clone();
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        slot.lock().unwrap().get_or_insert(e.to_string());
    }));
    // A lost device (a driver reset, a removed GPU, `destroy`) is an
    // error with the driver's reason at the next wait, not a hang.
    let slot = errors.clone();
    let name = describe(info);
    device.set_device_lost_callback(move |reason, message| {
        slot.lock()
            .unwrap_or_else(|e| e.into_inner())
            .get_or_insert(format!(
                "the device {name} was lost ({reason:?}): {message}"
            ));
    });
    errors
}
