//! The path integrator converges to the truth: the Cornell box lit by its
//! ceiling light alone (assets/scenes/cornell_area.toml), against a
//! reference of our own (the f64 twin at many samples, another seed), its
//! error falling as 1/√spp (tests/path.rs has the GPU against its twin).

mod common;

use common::*;
use lambert::Scene;
use lambert::camera::View;
use lambert::cpu::{self, Precision};
use lambert::diff::{Tolerance, compare};
use lambert::output::Rendered;
use lambert::progress::Progress;

/// The box at `side`², its light and bounces as the file asks.
fn small_box(side: u32) -> Scene {
    let mut scene = load("cornell_area");
    let mut view = scene.view().clone();
    view.camera = view.camera.resized(Some(side), Some(side)).unwrap();
    scene.view_mut().clone_from(&view);
    scene
}

fn render(scene: &Scene, spp: u32, seed: u32, precision: Precision) -> Rendered {
    let view = View {
        spp,
        seed,
        ..scene.view().clone()
    };
    cpu::render(scene, &view, precision, &Progress::hidden())
}

#[test]
fn the_cornell_box_converges_as_one_over_root_spp() {
    let scene = small_box(24);
    let reference = render(&scene, 2048, 7, Precision::F64);
    let tolerance = Tolerance::default();
    let rmse = |spp| {
        compare(
            &render(&scene, spp, 1, Precision::F32),
            &reference,
            &tolerance,
        )
        .unwrap()
        .rmse
    };
    let errors: Vec<f64> = [4, 16, 64].into_iter().map(rmse).collect();
    println!("RMSE at 4, 16, 64 spp against the f64 reference at 2048: {errors:?}");
    // Four times the samples, at least half the error: 1/√spp, or faster
    // at these few samples, where the stratified camera samples' share of
    // the error (the edges) falls as fast as 1/spp.
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!(
            (1.7..=4.0).contains(&ratio),
            "4× the samples cut the error by {ratio:.2}, not 2 to 4: {errors:?}"
        );
    }
    // The light arrives: the box is neither black nor blown out.
    let mean = reference
        .image
        .rgb
        .iter()
        .flatten()
        .map(|&v| v as f64)
        .sum::<f64>()
        / (3 * reference.image.rgb.len()) as f64;
    assert!((0.05..2.0).contains(&mean), "mean radiance {mean}");
}
