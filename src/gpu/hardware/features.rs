//! What a device is opened with for ray queries: wgpu's experimental
//! feature and the token that accepts it (a file of its own, so that the
//! device context, which the rest of the hardware module reads, imports
//! nothing of it back).

/// The wgpu feature the hardware path needs: Vulkan's VK_KHR_ray_query
/// (docs/hardware-rays.md says where wgpu 30 offers it).
pub const RAY_QUERY: wgpu::Features = wgpu::Features::EXPERIMENTAL_RAY_QUERY;

/// The features to open `adapter`'s device with: `wanted`, and ray
/// queries where `ray_queries` asks for them, of those the adapter has;
/// and wgpu's token for experimental features, given only with them.
pub fn device_features(
    adapter: &wgpu::Adapter,
    wanted: wgpu::Features,
    ray_queries: bool,
) -> (wgpu::Features, wgpu::ExperimentalFeatures) {
    let wanted = match ray_queries {
        true => wanted | RAY_QUERY,
        false => wanted,
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
