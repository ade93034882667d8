//! `lambert view` in the page: a model refined a few samples at a time.

use std::path::Path;

use lambert::gpu::Gpu;
use wasm_bindgen::prelude::*;

/// A model shown progressively (in progress: the camera's moves follow).
#[wasm_bindgen]
pub struct Viewer {
    _private: (),
}

impl Viewer {
    pub async fn open(_gpu: &Gpu, bytes: &[u8], path: &Path) -> lambert::Result<Viewer> {
        super::model::scene(bytes, path, None, None, None)?;
        Err(lambert::Error::Usage("the viewer is not built yet".into()))
    }
}
