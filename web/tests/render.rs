//! The web crate in headless Chromium (wasm-bindgen-test, `.cargo/config.toml`'s
//! runner, web/webdriver.json's flags): a model made here rendered through
//! `Session::renderModel` on the browser's WebGPU adapter, checked against
//! the CPU twin of the same scene run in the same page, and a bad file's
//! error.
//!
//! CHROMEDRIVER=/usr/bin/chromedriver WASM_BINDGEN_TEST_TIMEOUT=300 \
//!     cargo test -p lambert-web --release --target wasm32-unknown-unknown
#![cfg(target_arch = "wasm32")]

use std::path::Path;

use js_sys::{Float32Array, Reflect};
use lambert::cpu::{self, Precision};
use lambert::progress::Progress;
use lambert_web::Session;
use wasm_bindgen::prelude::*;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// A triangle facing +z, in the middle of the framed camera's picture.
const TRIANGLE: &str = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";

fn field(object: &JsValue, key: &str) -> JsValue {
    Reflect::get(object, &key.into()).expect("a field of the result")
}

#[wasm_bindgen_test]
async fn a_triangle_renders_as_the_cpu_twin_renders_it() {
    let session = Session::open().await.map_err(JsValue::from).unwrap();
    assert!(!session.adapter().is_empty());
    let (width, height, spp) = (40, 30, 4);
    let result = session
        .render_model(
            TRIANGLE.as_bytes().to_vec(),
            "tri.obj".into(),
            Some(width),
            Some(height),
            Some(spp),
        )
        .await
        .map_err(JsValue::from)
        .unwrap();
    assert_eq!(field(&result, "width").as_f64(), Some(width as f64));
    assert_eq!(field(&result, "height").as_f64(), Some(height as f64));
    let pixels = Float32Array::from(field(&result, "pixels")).to_vec();
    assert_eq!(pixels.len(), (width * height * 3) as usize);
    let at = |x: u32, y: u32| {
        let i = 3 * (y * width + x) as usize;
        [pixels[i], pixels[i + 1], pixels[i + 2]]
    };
    // The lit triangle in the middle, the background (the CLI's: black)
    // in the corners.
    let centre = at(width / 2, height / 2);
    assert!(centre.iter().all(|&c| c > 0.1), "centre {centre:?}");
    for (x, y) in [
        (0, 0),
        (width - 1, 0),
        (0, height - 1),
        (width - 1, height - 1),
    ] {
        assert_eq!(at(x, y), [0.0; 3], "corner ({x}, {y})");
    }
    // The CPU twin of the same scene and view, in this page.
    let (scene, settings) = lambert_web::model::scene(
        TRIANGLE.as_bytes(),
        Path::new("tri.obj"),
        Some(width),
        Some(height),
        Some(spp),
    )
    .unwrap();
    let twin = cpu::render(&scene, &settings.view, Precision::F32, &Progress::hidden());
    let twin: Vec<f32> = twin.image.rgb.iter().flatten().copied().collect();
    let worst = pixels
        .iter()
        .zip(&twin)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    let bright = twin.iter().filter(|&&c| c > 0.1).count();
    assert!(bright > 100, "the twin's triangle covers {bright} channels");
    // Edge pixels may differ by a sample's hit (1/spp of the triangle's
    // colour); everywhere else by rounding.
    let differing = pixels
        .iter()
        .zip(&twin)
        .filter(|(a, b)| (*a - *b).abs() > 1e-3)
        .count();
    assert!(
        differing <= 3 * 2 * width as usize,
        "{differing} channels differ from the CPU twin by more than 1e-3 (worst {worst})"
    );
}

#[wasm_bindgen_test]
async fn a_bad_file_is_an_error_naming_it_not_a_panic() {
    let session = Session::open().await.map_err(JsValue::from).unwrap();
    let bad = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec();
    let error = session
        .render_model(bad, "broken.obj".into(), Some(8), Some(8), Some(1))
        .await
        .map(|_| ())
        .map_err(JsValue::from)
        .expect_err("a face naming vertex 9 of 3");
    let message = field(&error, "message").as_string().unwrap();
    assert!(message.contains("broken.obj"), "{message}");
    // The session still renders after the error.
    let fine = session
        .render_model(
            TRIANGLE.as_bytes().to_vec(),
            "tri.obj".into(),
            Some(8),
            Some(8),
            Some(1),
        )
        .await;
    assert!(fine.is_ok());
}
