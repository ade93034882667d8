//! White furnace tests of the path integrator: a sphere inside a uniform
//! environment of radiance L. A white Lambert sphere reflects all it
//! receives, so it renders L everywhere (it vanishes); a white rough metal
//! (GGX, roughness 1, metallic 1) renders less, by the energy its
//! single-scattering microfacet model loses (docs/rendering.md, "The
//! BSDF"), within the bounds that loss allows.

mod common;

use common::*;
use lambert::Scene;
use lambert::output::Rendered;

const L: f32 = 0.75;

fn furnace(material: &str) -> Scene {
    let camera = camera_on_z(4.0, 40.0, 32, 32);
    scene(&format!(
        r#"
{camera}
[render]
integrator = "path"
max_depth = 16
spp = 64

[environment]
color = [{L}, {L}, {L}]

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
albedo = [1.0, 1.0, 1.0]
{material}
"#
    ))
}

/// The mean of the pixels whose camera ray hit the sphere, and their
/// smallest and largest values; and the corner's, where every sample sees
/// the environment alone.
fn sphere_pixels(r: &Rendered) -> (f64, f32, f32, [f32; 3]) {
    let mut hit = Vec::new();
    for (rgb, &prim) in r.image.rgb.iter().zip(&r.prims) {
        if prim != lambert::layout::NO_HIT {
            hit.extend_from_slice(rgb);
        }
    }
    assert!(hit.len() > 300, "the sphere is on screen");
    let mean = hit.iter().map(|&v| v as f64).sum::<f64>() / hit.len() as f64;
    let lo = hit.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = hit.iter().copied().fold(0.0, f32::max);
    (mean, lo, hi, r.image.rgb[0])
}

#[test]
fn a_white_lambert_sphere_vanishes_in_a_white_furnace() {
    let scene = furnace("");
    for (device, image) in [("CPU", render_cpu(&scene)), ("GPU", render_gpu(&scene))] {
        let (mean, lo, hi, corner) = sphere_pixels(&image);
        println!("{device}: sphere mean {mean}, range {lo}..{hi}; corner {corner:?}");
        // The environment, seen directly, is L exactly.
        assert_eq!(corner, [L; 3], "{device}: the background is not L");
        // Every sample is L·(f·cos/pdf) weighted by MIS: exactly L for a
        // BSDF sample (weight 1) and, for an environment sample, L·2·cos
        // (uniform sphere pdf 1/4π against cos/π); their mix is L on
        // average, within noise at 64 spp.
        assert!(
            (mean - L as f64).abs() <= 0.01 * L as f64,
            "{device}: the sphere renders {mean}, not L = {L}"
        );
        assert!(
            lo > 0.8 * L && hi < 1.2 * L,
            "{device}: pixels from {lo} to {hi}"
        );
    }
}

#[test]
fn a_white_rough_metal_loses_what_its_microfacet_model_loses() {
    // Single scattering at α = 1 loses 6% (grazing) to 69% (head on) of
    // the light: the sphere's directional albedo E(μ) runs from 0.307 at
    // μ = 1 to 0.935 at grazing (tests/bsdf.rs), and no bounce brings it
    // back (a convex body).
    let scene = furnace("metallic = 1.0\nroughness = 1.0");
    let image = render_cpu(&scene);
    let (mean, lo, hi, _) = sphere_pixels(&image);
    let lambert = sphere_pixels(&render_cpu(&furnace(""))).0;
    println!("rough metal: sphere mean {mean} (L = {L}), range {lo}..{hi}; Lambert {lambert}");
    assert!(mean < 0.75 * lambert, "the metal lost too little: {mean}");
    assert!(mean > 0.30 * L as f64, "the metal lost too much: {mean}");
    assert!(hi <= 1.05 * L, "energy was gained: {hi}");
}
