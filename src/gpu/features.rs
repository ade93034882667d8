//! The features a device is opened with: timestamp queries, and the ray
//! queries of `--accel hardware` (wgpu's experimental feature and the
//! token that accepts it), the one place besides `hardware` that names
//! them: the device context opens with them and the hardware module
//! checks for them, and neither imports the other for it.

/// The wgpu feature the hardware path needs: Vulkan's VK_KHR_ray_query
/// (docs/hardware-rays.md says where wgpu 30 offers it).
pub(super) const RAY_QUERY: wgpu::Features = wgpu::Features::EXPERIMENTAL_RAY_QUERY;

/// The features to open `adapter`'s device with, of those it has: GPU
/// time of each dispatch, and ray queries where `ray_queries` asks for
/// them; and wgpu's token for experimental features, given only with them.
pub(super) fn device_features(
    adapter: &wgpu::Adapter,
    ray_queries: bool,
) -> (wgpu::Features, wgpu::ExperimentalFeatures) {
    let wanted = match ray_queries {
        true => wgpu::Features::TIMESTAMP_QUERY | RAY_QUERY,
        false => wgpu::Features::TIMESTAMP_QUERY,
    };
    let features = adapter.features() & wanted;
    let experimental = if features.contains(RAY_QUERY) {
        // SAFETY: wgpu's token that the caller accepts its experimental
        // features' bugs. Only the hardware module and its shader use them,
        // and tests/hardware_rays.rs checks their answers against the CPU
        // path (docs/hardware-rays.md lists the bugs met).
        unsafe { wgpu::ExperimentalFeatures::enabled() }
    } else {
        wgpu::ExperimentalFeatures::disabled()
    };
    (features, experimental)
}
