//! glTF materials: base colour, emission and alpha, metalness and
//! roughness, the normal map, their textures (the images they name,
//! samplers, KHR_texture_transform) and which texture coordinate set a
//! primitive's material reads.

use std::path::Path;

use super::material_name;
use super::percent_decoded;
use crate::loading::material::{
    AlphaMode, Brdf, Filter, IDENTITY_UV_TRANSFORM, ImageSource, MaterialDesc, Sampler, TextureUse,
    Wrap,
};

/// glTF's BRDF with the spec's defaults (metallicFactor and
/// roughnessFactor 1): what a primitive without a material gets, as
/// three.js and the Khronos sample viewer give it.
pub(super) const DEFAULT_BRDF: Brdf = Brdf::MetallicRoughness {
    metallic: 1.0,
    roughness: 1.0,
};

/// A material as lambert renders it: baseColorFactor (negative components,
/// outside the spec's [0, 1] and negative radiance in the image, clamped to
/// 0 with a warning, as trimesh and Blender read such files; above 1 kept,
/// as a TOML or MTL albedo may be), its texture, emissiveFactor ×
/// KHR_materials_emissive_strength and its texture, alphaMode and
/// alphaCutoff (BLEND with a warning: it is rendered as MASK at 0.5);
/// metallicFactor and roughnessFactor (clamped to the spec's [0, 1]) and
/// metallicRoughnessTexture; normalTexture and its scale. occlusionTexture
/// is not read (docs/rendering.md, "Materials").
pub(super) fn material_desc(
    material: &gltf::Material,
    path: &Path,
    images: &mut Images,
    warnings: &mut Vec<String>,
) -> MaterialDesc {
    let name = material_name(material);
    let pbr = material.pbr_metallic_roughness();
    let factor = pbr.base_color_factor();
    if factor.iter().any(|c| *c < 0.0) {
        warnings.push(format!(
            "{}: material {name}: baseColorFactor {factor:?} has a negative component, clamped to 0",
            path.display(),
        ));
    }
    let strength = material.emissive_strength().unwrap_or(1.0);
    let alpha_mode = match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask,
        gltf::material::AlphaMode::Blend => {
            warnings.push(format!(
                "{}: material {name}: alphaMode BLEND is rendered as MASK with alphaCutoff 0.5 \
                 (lambert has no partial transparency)",
                path.display()
            ));
            AlphaMode::Blend
        }
    };
    let normal = material.normal_texture();
    MaterialDesc {
        base_color: factor.map(|c| c.max(0.0)),
        base_color_texture: pbr
            .base_color_texture()
            .and_then(|info| images.info_use(&info, warnings)),
        emissive: material.emissive_factor().map(|c| (c * strength).max(0.0)),
        emissive_texture: material
            .emissive_texture()
            .and_then(|info| images.info_use(&info, warnings)),
        alpha_mode,
        alpha_cutoff: material.alpha_cutoff().unwrap_or(0.5),
        alpha_texture: None,
        brdf: Brdf::MetallicRoughness {
            metallic: pbr.metallic_factor().clamp(0.0, 1.0),
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        },
        metallic_roughness_texture: pbr
            .metallic_roughness_texture()
            .and_then(|info| images.info_use(&info, warnings)),
        // The crate reads no KHR_texture_transform on a normalTexture.
        normal_texture: normal
            .as_ref()
            .and_then(|n| images.texture_use(&n.texture(), None, warnings)),
        normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
        name,
    }
}

/// Which TEXCOORD_n a primitive's material reads: its base colour
/// texture's set (KHR_texture_transform may name another), else that of
/// the first of its emissive, metallic-roughness and normal textures; a
/// material whose textures read two sets gets that one, with a warning
/// naming the other. None without textures. A texture whose
/// set the primitive lacks is a warning naming the material, the texture
/// and the set: the primitive reads it at (0, 0), as an OBJ face without
/// `vt` does.
pub(super) fn texture_coordinate_set(
    material: &gltf::Material,
    primitive: &gltf::Primitive,
    what: &str,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Option<u32> {
    let name = material_name(material);
    let mut set = |(set, whose): (u32, &str), slot: &str| {
        // One warning a material's texture, naming the first primitive.
        let said = format!(
            "{}: material {name}: its {slot} reads TEXCOORD_{set} ({whose})",
            path.display()
        );
        if primitive.get(&gltf::Semantic::TexCoords(set)).is_none()
            && !warnings.iter().any(|w| w.starts_with(&said))
        {
            warnings.push(format!(
                "{said}, which {what} (the first such) does not have; primitives without it \
                 read the texture at (0, 0)"
            ));
        }
        set
    };
    let info_set =
        |info: gltf::texture::Info| match info.texture_transform().and_then(|t| t.tex_coord()) {
            Some(set) => (set, "its KHR_texture_transform texCoord"),
            None => (info.tex_coord(), "texCoord"),
        };
    let pbr = material.pbr_metallic_roughness();
    let sets: Vec<(u32, &str)> = [
        (pbr.base_color_texture().map(info_set), "baseColorTexture"),
        (material.emissive_texture().map(info_set), "emissiveTexture"),
        (
            pbr.metallic_roughness_texture().map(info_set),
            "metallicRoughnessTexture",
        ),
        (
            material
                .normal_texture()
                .map(|n| (n.tex_coord(), "texCoord")),
            "normalTexture",
        ),
    ]
    .into_iter()
    .filter_map(|(texture, slot)| texture.map(|t| (set(t, slot), slot)))
    .collect();
    let &(first, first_slot) = sets.first()?;
    for &(other, slot) in &sets[1..] {
        if other != first {
            let warning = format!(
                "{}: material {name}: its {slot} reads TEXCOORD_{other}, its {first_slot} \
                 TEXCOORD_{first}; both read TEXCOORD_{first}",
                path.display(),
            );
            if !warnings.contains(&warning) {
                warnings.push(warning);
            }
        }
    }
    Some(first)
}

/// The file's images as materials use them: each read once, in the order
/// first used (`Mesh::images`).
pub(super) struct Images<'a> {
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    path: &'a Path,
    /// Per image of the file, its index in `sources` (None: not yet).
    ids: Vec<Option<Option<u32>>>,
    pub(super) sources: Vec<ImageSource>,
}

impl<'a> Images<'a> {
    pub(super) fn new(
        document: &'a gltf::Document,
        buffers: &'a [gltf::buffer::Data],
        path: &'a Path,
    ) -> Images<'a> {
        let count = document.images().len();
        Images {
            document,
            buffers,
            path,
            ids: vec![None; count],
            sources: Vec::new(),
        }
    }

    /// `texture_use` of a texture reference with its KHR_texture_transform.
    fn info_use(
        &mut self,
        info: &gltf::texture::Info,
        warnings: &mut Vec<String>,
    ) -> Option<TextureUse> {
        self.texture_use(&info.texture(), info.texture_transform(), warnings)
    }

    /// A texture as lambert keeps it: its image (None, with a warning,
    /// where the image cannot be found), sampler and transform.
    fn texture_use(
        &mut self,
        texture: &gltf::Texture,
        transform: Option<gltf::texture::TextureTransform>,
        warnings: &mut Vec<String>,
    ) -> Option<TextureUse> {
        let image = texture.source();
        let id = match self.ids[image.index()] {
            Some(id) => id,
            None => {
                let id = match self.source(&image) {
                    Ok(source) => {
                        self.sources.push(source);
                        Some((self.sources.len() - 1) as u32)
                    }
                    Err(why) => {
                        warnings.push(format!(
                            "{}: image {}: {why}; the materials using it keep their factors",
                            self.path.display(),
                            image.index()
                        ));
                        None
                    }
                };
                self.ids[image.index()] = Some(id);
                id
            }
        }?;
        Some(TextureUse {
            image: id,
            sampler: sampler(&texture.sampler()),
            transform: transform.map_or(IDENTITY_UV_TRANSFORM, |t| {
                uv_transform(t.offset(), t.rotation(), t.scale())
            }),
        })
    }

    fn source(&self, image: &gltf::Image) -> std::result::Result<ImageSource, String> {
        let name = format!("{} image {}", self.path.display(), image.index());
        // `Image::source` unwraps what the crate's validation lets through:
        // a bufferView without a mimeType, or neither a bufferView nor a uri.
        let json = &self.document.as_json().images[image.index()];
        match (&json.buffer_view, &json.uri, &json.mime_type) {
            (Some(_), _, None) => return Err("it has a bufferView but no mimeType".to_string()),
            (None, None, _) => return Err("it has neither a bufferView nor a uri".to_string()),
            _ => {}
        }
        match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()].0;
                let bytes = view
                    .offset()
                    .checked_add(view.length())
                    .and_then(|end| buffer.get(view.offset()..end))
                    .ok_or_else(|| {
                        format!(
                            "its buffer view {} ends beyond its buffer ({} bytes)",
                            view.index(),
                            buffer.len()
                        )
                    })?;
                Ok(ImageSource::Embedded {
                    bytes: bytes.to_vec(),
                    name,
                })
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                let data = gltf::buffer::Data::from_source_and_blob(
                    gltf::buffer::Source::Uri(uri),
                    None,
                    &mut None,
                )
                .map_err(|e| format!("its data URI cannot be decoded: {e}"))?;
                Ok(ImageSource::Embedded {
                    bytes: data.0,
                    name,
                })
            }
            gltf::image::Source::Uri { uri, .. } => {
                let file = percent_decoded(uri)
                    .ok_or_else(|| format!("its uri {uri:?} is not percent-encoded UTF-8"))?;
                let file = self.path.parent().unwrap_or(Path::new(".")).join(file);
                if let Some(why) = crate::files::not_regular(&file) {
                    return Err(format!("{} is {why}", file.display()));
                }
                Ok(ImageSource::File(file))
            }
        }
    }
}

/// A glTF sampler as lambert's (no minFilter: mipmapped, as viewers do).
fn sampler(s: &gltf::texture::Sampler) -> Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let (minify, mipmaps) = match s.min_filter() {
        None => (Filter::Linear, true),
        Some(MinFilter::Nearest) => (Filter::Nearest, false),
        Some(MinFilter::Linear) => (Filter::Linear, false),
        Some(MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear) => {
            (Filter::Nearest, true)
        }
        Some(MinFilter::LinearMipmapNearest | MinFilter::LinearMipmapLinear) => {
            (Filter::Linear, true)
        }
    };
    Sampler {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        magnify: match s.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
        minify,
        mipmaps,
    }
}

/// KHR_texture_transform's T · R · S as a row-major 2×3 matrix (the
/// extension's rotation turns counter-clockwise in UV space).
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 3]; 2] {
    let (sin, cos) = rotation.sin_cos();
    [
        [cos * scale[0], sin * scale[1], offset[0]],
        [-sin * scale[0], cos * scale[1], offset[1]],
    ]
}
