//! Which adapter to use: the request, the adapters wgpu finds, and the
//! choice among them.

use crate::error::{Error, Result};

use super::bindings::unmet_limits;
use super::options::{
    GpuOptions, LLVMPIPE_THREADS_ENV, MAX_BUFFER_ENV, RAY_QUERY_GEOMETRY_ENV, SHADOW_DISPATCH_ENV,
};

/// Which adapter to use: `--adapter`, `--backend`, or wgpu's own
/// `WGPU_ADAPTER_NAME` and `WGPU_BACKEND` when those are unset, and the
/// options of what is opened. The library reads no environment variable:
/// the front ends pass theirs in (`with_environment`).
#[derive(Clone, Debug, Default)]
pub struct AdapterRequest {
    /// Case-insensitive substring of the adapter's name.
    pub name: Option<String>,
    /// vulkan, metal, dx12 or gl.
    pub backend: Option<String>,
    /// wgpu's `WGPU_BACKEND` as the front end found it: a comma-separated
    /// list, used when `backend` is unset.
    pub backend_list: Option<String>,
    pub options: GpuOptions,
    /// Open the device with ray queries where the adapter has them (wgpu's
    /// experimental EXPERIMENTAL_RAY_QUERY): what `--accel hardware` needs.
    /// Off, the device is what it was before the hardware path existed.
    pub ray_queries: bool,
}

impl AdapterRequest {
    /// This request completed from the environment as `var` reads it (the
    /// front ends pass `std::env::var`): `WGPU_ADAPTER_NAME` where no name
    /// is given, `WGPU_BACKEND`, and lambert's own GPU variables.
    pub fn with_environment(self, var: impl Fn(&str) -> Option<String>) -> AdapterRequest {
        AdapterRequest {
            name: self.name.or_else(|| var("WGPU_ADAPTER_NAME")),
            backend_list: var("WGPU_BACKEND"),
            options: GpuOptions {
                max_buffer_bytes: var(MAX_BUFFER_ENV),
                shadow_dispatch: var(SHADOW_DISPATCH_ENV),
                llvmpipe_threads: var(LLVMPIPE_THREADS_ENV),
                ray_query_geometry: var(RAY_QUERY_GEOMETRY_ENV),
            },
            ..self
        }
    }

    pub(super) fn name_filter(&self) -> Option<String> {
        self.name.as_ref().map(|n| n.to_lowercase())
    }

    /// True when the user named an adapter, which then may be a software one.
    pub fn names_adapter(&self) -> bool {
        self.name_filter().is_some()
    }

    /// The backends asked for, if any were: `--backend`, else wgpu's
    /// `WGPU_BACKEND` (a comma-separated list), each name checked alike.
    fn backends(&self) -> Result<Option<wgpu::Backends>> {
        let parse = |name: &str, source: &str| match name.trim().to_lowercase().as_str() {
            "vulkan" | "vk" => Ok(wgpu::Backends::VULKAN),
            "metal" | "mtl" => Ok(wgpu::Backends::METAL),
            "dx12" | "d3d12" => Ok(wgpu::Backends::DX12),
            "gl" | "gles" | "opengl" => Ok(wgpu::Backends::GL),
            other => Err(Error::Usage(format!(
                "unknown backend '{other}'{source}: use vulkan, metal, dx12 or gl"
            ))),
        };
        match self.backend.as_deref() {
            Some(name) => parse(name, "").map(Some),
            None => match &self.backend_list {
                Some(list) => list
                    .split(',')
                    .try_fold(wgpu::Backends::empty(), |all, name| {
                        Ok(all | parse(name, " in WGPU_BACKEND")?)
                    })
                    .map(Some),
                None => Ok(None),
            },
        }
    }

    /// Whether the adapter's name matches `--adapter`/`WGPU_ADAPTER_NAME`.
    pub fn matches(&self, info: &wgpu::AdapterInfo) -> bool {
        self.name_filter()
            .is_none_or(|f| info.name.to_lowercase().contains(&f))
    }

    /// What was asked for, in words, for "no adapter" messages.
    pub fn describe_request(&self) -> Result<String> {
        let mut parts = Vec::new();
        if let Some(name) = self.name_filter() {
            parts.push(format!("whose name contains '{name}'"));
        }
        if let Some(backends) = self.backends()? {
            let names: Vec<&str> = [
                (wgpu::Backends::VULKAN, "Vulkan"),
                (wgpu::Backends::METAL, "Metal"),
                (wgpu::Backends::DX12, "DX12"),
                (wgpu::Backends::GL, "GL"),
            ]
            .iter()
            .filter(|(b, _)| backends.contains(*b))
            .map(|(_, name)| *name)
            .collect();
            parts.push(format!("on {}", names.join(" or ")));
        }
        Ok(parts.join(" "))
    }

    /// The backends an instance for this request enables: those asked
    /// for, else Vulkan, Metal and DX12 (what a window's instance uses).
    pub fn instance_backends(&self) -> Result<wgpu::Backends> {
        Ok(self.backends()?.unwrap_or(wgpu::Backends::PRIMARY))
    }

    /// Whether Vulkan is among the backends asked for (lavapipe can help).
    pub fn wants_vulkan(&self) -> Result<bool> {
        Ok(self
            .backends()?
            .is_none_or(|b| b.contains(wgpu::Backends::VULKAN)))
    }
}

/// Every adapter wgpu finds for the requested backends. Unless a backend is
/// named, GL is only tried when Vulkan, Metal and DX12 offer nothing: its
/// headless start-up is slow and noisy.
pub fn enumerate_adapters(request: &AdapterRequest) -> Result<Vec<wgpu::Adapter>> {
    let find = |backends| {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        pollster::block_on(instance.enumerate_adapters(backends))
    };
    match request.backends()? {
        Some(backends) => Ok(find(backends)),
        None => {
            let primary = find(wgpu::Backends::PRIMARY);
            Ok(if primary.is_empty() {
                find(wgpu::Backends::SECONDARY)
            } else {
                primary
            })
        }
    }
}

/// A window to present to (the viewer's): the instance its surface was
/// made by, whose adapters alone can present to it.
pub struct Presenting<'a> {
    pub instance: &'a wgpu::Instance,
    pub surface: &'a wgpu::Surface<'a>,
}

/// The adapters to choose from: all that `request` finds, or, for a
/// window, those of its instance that can present to its surface.
fn candidates(
    request: &AdapterRequest,
    presenting: Option<&Presenting>,
) -> Result<Vec<wgpu::Adapter>> {
    let Some(p) = presenting else {
        return enumerate_adapters(request);
    };
    let all = pollster::block_on(p.instance.enumerate_adapters(request.instance_backends()?));
    Ok(all
        .into_iter()
        .filter(|a| a.is_surface_supported(p.surface))
        .collect())
}

/// The best adapter matching `request` (and able to present to the
/// window, if one is given): hardware before software, Vulkan/Metal/DX12
/// before GL. With `hardware_only`, software rasterisers such as lavapipe
/// do not count.
pub(super) fn choose_adapter(
    request: &AdapterRequest,
    hardware_only: bool,
    presenting: Option<&Presenting>,
) -> Result<wgpu::Adapter> {
    let adapters = candidates(request, presenting)?;
    let filter = request.name_filter();
    let rank = |info: &wgpu::AdapterInfo| {
        let kind = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        (kind, info.backend == wgpu::Backend::Gl)
    };
    let chosen = adapters
        .iter()
        .filter(|a| {
            let info = a.get_info();
            filter
                .as_ref()
                .is_none_or(|f| info.name.to_lowercase().contains(f))
                && !(hardware_only && is_software(&info))
                && cannot_run(a).is_none()
        })
        .min_by_key(|a| rank(&a.get_info()));
    let Some(adapter) = chosen else {
        let mut unfit = false;
        let available: Vec<String> = adapters
            .iter()
            .map(|a| match cannot_run(a) {
                Some(why) => {
                    unfit = true;
                    format!("{} (cannot run lambert: {why})", describe(&a.get_info()))
                }
                None => describe(&a.get_info()),
            })
            .collect();
        let wanted = match (&filter, hardware_only) {
            (Some(f), _) => format!("no adapter whose name contains '{f}'"),
            (None, true) => "no hardware GPU adapter".to_string(),
            (None, false) => "no GPU adapter".to_string(),
        };
        let wanted = match presenting {
            Some(_) => format!("{wanted} that can present to the window"),
            None => wanted,
        };
        let available = if available.is_empty() {
            "none (install Mesa's lavapipe: apt-get install mesa-vulkan-drivers)".to_string()
        } else {
            available.join(", ")
        };
        let advice = if unfit {
            "; use another backend (vulkan, metal or dx12) or --device cpu"
        } else {
            ""
        };
        return Err(Error::Gpu(format!(
            "{wanted}; adapters available: {available}{advice}"
        )));
    };
    Ok(adapter.clone())
}

/// Why `adapter` cannot run lambert's kernel, if it cannot: its limits
/// (`unmet_limits`), or wgpu's GL backend: the kernel fits GL's 16 storage
/// buffers, but Mesa's GL refuses the GLSL naga writes of it ("is is not
/// allowed on function parameter"), so GL is refused before it is tried.
pub fn cannot_run(adapter: &wgpu::Adapter) -> Option<String> {
    if adapter.get_info().backend == wgpu::Backend::Gl {
        return Some("wgpu's GL backend does not compile lambert's kernel".to_string());
    }
    unmet_limits(&adapter.limits())
}

pub(super) fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

pub(super) fn is_software(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
}

/// Mesa's llvmpipe, as lavapipe (Vulkan) or through GL: it cuts loops short
/// after 65535 iterations an invocation group (the shader's
/// `loops_completed`).
pub(super) fn is_llvmpipe(info: &wgpu::AdapterInfo) -> bool {
    info.name.to_lowercase().contains("llvmpipe") || info.driver.to_lowercase().contains("llvmpipe")
}
