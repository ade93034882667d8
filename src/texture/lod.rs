//! The camera's side of the ray cones that choose a texture's level of
//! detail (docs/textures.md); the triangle's side is `texture_lod` in the
//! shader and its twin.

/// The spread angle of a camera ray's cone: the angle of one pixel,
/// 2·tan(vfov/2)/height, divided by √spp, as each of spp stratified
/// samples covers 1/spp of the pixel (so more samples read finer levels
/// and converge to the box-filtered image of the full texture). Computed
/// once on the host: both paths read the same value.
pub fn cone_spread(tan_half_y: f32, height: u32, spp: u32) -> f32 {
    (2.0 * tan_half_y as f64 / height.max(1) as f64 / (spp.max(1) as f64).sqrt()) as f32
}
