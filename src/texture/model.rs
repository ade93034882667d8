//! A model's textures into a scene's store: each image its materials use
//! decoded once (and stored once per encoding its uses read it in: colour
//! or data), and each material's uses of them as slots. An image that
//! does not decode is a warning naming the model, the image and the
//! materials that use it, which keep their factors.

use std::path::Path;

use super::decode::{DecodedImage, decode_image};
use super::store::{Encoding, TextureStore};
use crate::layout::NO_TEXTURE;
use crate::loading::material::{ImageSource, MaterialDesc, TextureUse};

/// A material's texture slots (words in the store, or `NO_TEXTURE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialSlots {
    pub base_color: u32,
    pub emissive: u32,
    pub alpha: u32,
    pub metallic_roughness: u32,
    pub normal: u32,
}

/// One image of a model as `lambert info` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageReport {
    /// The file's name, or where embedded bytes came from.
    pub name: String,
    /// (width, height, format), or why it did not decode.
    pub decoded: Result<(u32, u32, &'static str), String>,
    /// The materials that use it (in any slot).
    pub materials: Vec<usize>,
}

fn image_name(source: &ImageSource) -> String {
    match source {
        ImageSource::File(path) => path.display().to_string(),
        ImageSource::Embedded { name, .. } => name.clone(),
    }
}

/// A material's texture slots with the encoding each reads its image in:
/// base colour, emissive, alpha, metallic-roughness, normal (the order of
/// `MaterialSlots`).
fn slots(desc: &MaterialDesc) -> [(&Option<TextureUse>, Encoding); 5] {
    [
        (&desc.base_color_texture, Encoding::Srgb),
        (&desc.emissive_texture, Encoding::Srgb),
        // Alpha is linear in either encoding.
        (&desc.alpha_texture, Encoding::Srgb),
        (&desc.metallic_roughness_texture, Encoding::Linear),
        (&desc.normal_texture, Encoding::Linear),
    ]
}

/// The uses of each material: (material, texture, encoding).
fn uses(materials: &[MaterialDesc]) -> impl Iterator<Item = (usize, &TextureUse, Encoding)> {
    materials.iter().enumerate().flat_map(|(m, desc)| {
        slots(desc)
            .into_iter()
            .filter_map(move |(t, encoding)| t.as_ref().map(|t| (m, t, encoding)))
    })
}

/// Per image of `images`, the materials that use it.
fn users(images: &[ImageSource], materials: &[MaterialDesc]) -> Vec<Vec<usize>> {
    let mut users = vec![Vec::new(); images.len()];
    for (m, texture, _) in uses(materials) {
        if let Some(list) = users.get_mut(texture.image as usize)
            && list.last() != Some(&m)
        {
            list.push(m);
        }
    }
    users
}

/// Decodes the images `materials` use, adds them and the materials' uses
/// of them to `store`, and returns each material's slots; warnings name
/// `model`.
pub fn add_model_textures(
    store: &mut TextureStore,
    model: &Path,
    images: &[ImageSource],
    materials: &[MaterialDesc],
    warnings: &mut Vec<String>,
) -> Vec<MaterialSlots> {
    let users = users(images, materials);
    // Per image, whether some use reads it as colour, as data.
    let mut encodings = vec![[false; 2]; images.len()];
    for (_, texture, encoding) in uses(materials) {
        if let Some(e) = encodings.get_mut(texture.image as usize) {
            e[(encoding == Encoding::Linear) as usize] = true;
        }
    }
    // Per image, its index in the store as colour and as data.
    let mut stored: Vec<[Option<u32>; 2]> = Vec::with_capacity(images.len());
    for ((source, users), needed) in images.iter().zip(&users).zip(&encodings) {
        if users.is_empty() {
            stored.push([None; 2]);
            continue;
        }
        stored.push(match decode_image(source) {
            Ok(image) => {
                let mut add = |i: usize, encoding| {
                    needed[i].then(|| store.add_encoded_image(&image, image_name(source), encoding))
                };
                [add(0, Encoding::Srgb), add(1, Encoding::Linear)]
            }
            Err(why) => {
                warnings.push(format!(
                    "{}: {why}; material{} {} keep{} {} colour without it",
                    model.display(),
                    if users.len() == 1 { "" } else { "s" },
                    list(users, materials),
                    if users.len() == 1 { "s" } else { "" },
                    if users.len() == 1 { "its" } else { "their" },
                ));
                [None; 2]
            }
        });
    }
    let mut slot = |m: usize, (texture, encoding): (&Option<TextureUse>, Encoding)| {
        let Some(texture) = texture else {
            return NO_TEXTURE;
        };
        match stored.get(texture.image as usize) {
            Some(images) => match images[(encoding == Encoding::Linear) as usize] {
                Some(image) => store.slot(image, texture),
                None => NO_TEXTURE,
            },
            None => {
                warnings.push(format!(
                    "{}: material {} names image {}, and the model has {}; it keeps its colour \
                     without it",
                    model.display(),
                    name(m, materials),
                    texture.image,
                    images.len()
                ));
                NO_TEXTURE
            }
        }
    };
    materials
        .iter()
        .enumerate()
        .map(|(m, desc)| {
            let [base_color, emissive, alpha, metallic_roughness, normal] =
                slots(desc).map(|s| slot(m, s));
            MaterialSlots {
                base_color,
                emissive,
                alpha,
                metallic_roughness,
                normal,
            }
        })
        .collect()
}

/// A material as messages name it: its file's name, else its index.
fn name(m: usize, materials: &[MaterialDesc]) -> String {
    match materials[m].name.as_str() {
        "" => m.to_string(),
        name => format!("'{name}'"),
    }
}

fn list(items: &[usize], materials: &[MaterialDesc]) -> String {
    items
        .iter()
        .map(|&m| name(m, materials))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Every image of a model: its size and format (decoded to find them) or
/// why it does not decode, and the materials that use it.
pub fn describe_images(images: &[ImageSource], materials: &[MaterialDesc]) -> Vec<ImageReport> {
    images
        .iter()
        .zip(users(images, materials))
        .map(|(source, materials)| ImageReport {
            name: image_name(source),
            decoded: decode_image(source).map(|i: DecodedImage| (i.width, i.height, i.format)),
            materials,
        })
        .collect()
}
