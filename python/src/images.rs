//! Images out of Python: written as the CLI writes them (atomically,
//! never over a scene's input), encoded to 8-bit sRGB or PNG bytes (what
//! a notebook shows), and the parts of a tiled render joined as `lambert
//! merge` joins them.

use std::path::PathBuf;

use lambert::output::{Image, encode_png_rgb8};
use lambert::parts::{Part, Tile, assemble, read_part, write_part};
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::value_error;
use crate::render::{PartInfo, image_array};
use crate::{NativeScene, detached};

/// An (H, W, 3) float32 array as an image; `name` names it in errors.
fn image_of(name: &str, array: &PyReadonlyArray3<'_, f32>) -> PyResult<Image> {
    let shape = array.shape().to_vec();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(value_error(format!(
            "{name} has shape {shape:?}; it must be (H, W, 3) with H, W ≥ 1"
        )));
    }
    let (height, width) = (u32::try_from(shape[0]), u32::try_from(shape[1]));
    let (Ok(height), Ok(width)) = (height, width) else {
        return Err(value_error(format!(
            "{name} of shape {shape:?} is too large"
        )));
    };
    let rgb: Vec<[f32; 3]> = array
        .as_array()
        .rows()
        .into_iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Image { width, height, rgb })
}

/// Writes a linear-RGB (H, W, 3) float32 image as .png (8-bit sRGB), .exr
/// or .pfm, atomically, as the CLI does; never over a file `scene` was
/// read from. With `part` (a tile of a render), an EXR part file that
/// `lambert merge` reads, as `lambert render --tile` writes it.
#[pyfunction]
#[pyo3(signature = (path, image, scene=None, part=None))]
fn write_image(
    py: Python<'_>,
    path: PathBuf,
    image: PyReadonlyArray3<'_, f32>,
    scene: Option<&Bound<'_, NativeScene>>,
    part: Option<PartInfo>,
) -> PyResult<()> {
    let image = image_of("image", &image)?;
    let scene = scene.map(|s| &s.get().scene);
    detached(py, || {
        if let Some(scene) = scene {
            scene.check_output(&path)?;
        }
        lambert::output::prepare_output(&path)?;
        match part {
            None => image.save(&path),
            Some(((index, count), (start, end), height, hash)) => write_part(
                &path,
                &image,
                Tile { index, count },
                height,
                start..end,
                &hash,
            ),
        }
    })
}

/// The 8-bit sRGB encoding of a linear image, (H, W, 3) uint8: the PNG's
/// pixels.
#[pyfunction]
fn to_srgb<'py>(
    py: Python<'py>,
    image: PyReadonlyArray3<'_, f32>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let image = image_of("image", &image)?;
    let (w, h) = (image.width as usize, image.height as usize);
    let bytes = py.detach(|| image.to_srgb8());
    Ok(Array3::from_shape_vec((h, w, 3), bytes)
        .expect("3 per pixel")
        .into_pyarray(py))
}

/// The image as a PNG file's bytes (8-bit sRGB), as `write_image` writes
/// a .png.
#[pyfunction]
fn png_bytes<'py>(
    py: Python<'py>,
    image: PyReadonlyArray3<'_, f32>,
) -> PyResult<Bound<'py, PyBytes>> {
    let image = image_of("image", &image)?;
    let png = detached(py, || {
        encode_png_rgb8(image.width, image.height, &image.to_srgb8())
    })?;
    Ok(PyBytes::new(py, &png))
}

/// One of `merge`'s parts: a part file's path, or a tile rendered in
/// Python with what its render recorded.
#[derive(FromPyObject)]
enum PartArg<'py> {
    Tile((PyReadonlyArray3<'py, f32>, PartInfo)),
    File(PathBuf),
}

/// The image the parts of one render make (`lambert merge`'s checks: all
/// of one render, each once).
#[pyfunction]
fn merge<'py>(py: Python<'py>, parts: Vec<PartArg<'py>>) -> PyResult<Bound<'py, PyArray3<f32>>> {
    // The arrays are read with the GIL held, the files without it.
    enum Given {
        File(PathBuf),
        Tile(PathBuf, Image, Tile, u32, String),
    }
    let mut given = Vec::with_capacity(parts.len());
    for (i, part) in parts.into_iter().enumerate() {
        given.push(match part {
            PartArg::Tile((band, ((index, count), _, height, hash))) => {
                let name = format!("parts[{i}]");
                let band = image_of(&name, &band)?;
                Given::Tile(name.into(), band, Tile { index, count }, height, hash)
            }
            PartArg::File(path) => Given::File(path),
        });
    }
    let image = detached(py, || {
        let parts = given
            .into_iter()
            .map(|p| match p {
                Given::File(path) => read_part(&path),
                Given::Tile(name, band, tile, height, hash) => {
                    Part::new(name, band, tile, height, hash)
                }
            })
            .collect::<Result<Vec<Part>, _>>()?;
        assemble(&parts)
    })?;
    Ok(image_array(py, image))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(write_image, m)?)?;
    m.add_function(wrap_pyfunction!(to_srgb, m)?)?;
    m.add_function(wrap_pyfunction!(png_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    Ok(())
}
