//! A model's textures into a scene's store: each image its materials use
//! decoded once, and each material's uses of them as slots. An image that
//! does not decode is a warning naming the model, the image and the
//! materials that use it, which keep their factors.

use std::path::Path;

use super::decode::{DecodedImage, decode_image};
use super::store::TextureStore;
use crate::layout::NO_TEXTURE;
use crate::loading::material::{ImageSource, MaterialDesc, TextureUse};

/// A material's texture slots (words in the store, or `NO_TEXTURE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialSlots {
    pub base_color: u32,
    pub emissive: u32,
    pub alpha: u32,
}

/// One image of a model as `lambert info` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageReport {
    /// The file's name, or where embedded bytes came from.
    pub name: String,
    /// (width, height, format), or why it did not decode.
    pub decoded: Result<(u32, u32, &'static str), String>,
    /// The materials that use it (base colour, emissive or alpha).
    pub materials: Vec<usize>,
}

fn image_name(source: &ImageSource) -> String {
    match source {
        ImageSource::File(path) => path.display().to_string(),
        ImageSource::Embedded { name, .. } => name.clone(),
    }
}

/// The uses of each material: (material, base colour or emissive).
fn uses(materials: &[MaterialDesc]) -> impl Iterator<Item = (usize, &TextureUse)> {
    materials.iter().enumerate().flat_map(|(m, desc)| {
        [
            &desc.base_color_texture,
            &desc.emissive_texture,
            &desc.alpha_texture,
        ]
        .into_iter()
        .flatten()
        .map(move |t| (m, t))
    })
}

/// Per image of `images`, the materials that use it.
fn users(images: &[ImageSource], materials: &[MaterialDesc]) -> Vec<Vec<usize>> {
    let mut users = vec![Vec::new(); images.len()];
    for (m, texture) in uses(materials) {
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
    let mut stored: Vec<Option<u32>> = Vec::with_capacity(images.len());
    for (source, users) in images.iter().zip(&users) {
        if users.is_empty() {
            stored.push(None);
            continue;
        }
        stored.push(match decode_image(source) {
            Ok(image) => Some(store.add_image(&image, image_name(source))),
            Err(why) => {
                warnings.push(format!(
                    "{}: {why}; material{} {} keep{} {} colour without it",
                    model.display(),
                    if users.len() == 1 { "" } else { "s" },
                    list(users, materials),
                    if users.len() == 1 { "s" } else { "" },
                    if users.len() == 1 { "its" } else { "their" },
                ));
                None
            }
        });
    }
    let mut slot = |m: usize, texture: &Option<TextureUse>| {
        let Some(texture) = texture else {
            return NO_TEXTURE;
        };
        match stored.get(texture.image as usize) {
            Some(Some(image)) => store.slot(*image, texture),
            Some(None) => NO_TEXTURE,
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
        .map(|(m, desc)| MaterialSlots {
            base_color: slot(m, &desc.base_color_texture),
            emissive: slot(m, &desc.emissive_texture),
            alpha: slot(m, &desc.alpha_texture),
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
