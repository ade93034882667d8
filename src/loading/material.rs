//! How a model file says its surfaces look, as every loader hands it on:
//! materials (base colour, alpha, emission, the BRDF with its metallic and
//! roughness factors, and the textures that scale them or perturb the
//! normal) and the images those textures read (docs/rendering.md,
//! "Materials"). Loaders fill these; the
//! `texture` module decodes the images; the scene flattens both for the
//! CPU and GPU paths.
//!
//! One convention for every format: texture coordinates are glTF's, (0, 0)
//! the image's top-left corner, so OBJ and PLY loaders store (u, 1 − v).

use std::path::PathBuf;

/// Where an image's bytes are.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// A file named by the model (OBJ `map_Kd`, glTF `uri`, PLY
    /// `comment TextureFile`), resolved against the model's folder.
    File(PathBuf),
    /// Bytes the model carries (a GLB buffer view, a data URI); `name` says
    /// where they came from in messages ("Duck.glb image 0").
    Embedded { bytes: Vec<u8>, name: String },
}

/// What a texture coordinate outside [0, 1] reads (glTF sampler wrapS/T).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    #[default]
    Linear,
}

/// How a texture is sampled: a glTF sampler; OBJ and PLY get the default
/// (repeat, bilinear, mipmapped), but for MTL `-clamp on` (clamp to edge).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    pub magnify: Filter,
    pub minify: Filter,
    /// Whether minified lookups read the mip chain (glTF minFilter
    /// *_MIPMAP_*, or none given).
    pub mipmaps: bool,
}

impl Default for Sampler {
    fn default() -> Sampler {
        Sampler {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            magnify: Filter::Linear,
            minify: Filter::Linear,
            mipmaps: true,
        }
    }
}

/// A material's use of an image. The texture coordinates are the ones the
/// mesh stores per corner (a loader keeps the set the base colour texture
/// names, glTF `texCoord`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureUse {
    /// Index into `Mesh::images`.
    pub image: u32,
    pub sampler: Sampler,
    /// `KHR_texture_transform` (and OBJ `-o`/`-s`) as a row-major 2×3
    /// matrix: uv' = M · (u, v, 1). Identity when the file gives none.
    pub transform: [[f32; 3]; 2],
}

pub const IDENTITY_UV_TRANSFORM: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// glTF `alphaMode`; OBJ `d < 1` or `map_d` is `Blend`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AlphaMode {
    #[default]
    Opaque,
    /// Cut out where alpha < `alpha_cutoff`.
    Mask,
    /// Rendered as `Mask` at 0.5, with a warning that says so.
    Blend,
}

/// The BRDF a file asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Brdf {
    /// f = albedo/π: OBJ without specular terms, PLY, STL.
    #[default]
    Lambert,
    /// glTF 2.0's (its appendix B): metalness and perceptual roughness
    /// factors, each in [0, 1].
    MetallicRoughness { metallic: f32, roughness: f32 },
}

/// One material as its file defines it, colours linear.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// Linear RGBA factor (glTF baseColorFactor, MTL `Kd` and `d`).
    pub base_color: [f32; 4],
    pub base_color_texture: Option<TextureUse>,
    /// Linear RGB radiance added at the surface (glTF emissiveFactor ×
    /// KHR_materials_emissive_strength, MTL `Ke`).
    pub emissive: [f32; 3],
    pub emissive_texture: Option<TextureUse>,
    pub alpha_mode: AlphaMode,
    pub alpha_cutoff: f32,
    /// An image whose own alpha (MTL `map_d`) scales the alpha, apart from
    /// the base colour texture's (glTF has none: its alpha is the base
    /// colour texture's).
    pub alpha_texture: Option<TextureUse>,
    pub brdf: Brdf,
    /// glTF metallicRoughnessTexture: data, not colour; its B scales the
    /// metalness, its G the roughness.
    pub metallic_roughness_texture: Option<TextureUse>,
    /// glTF normalTexture: tangent-space normals (data), X and Y scaled
    /// by `normal_scale`.
    pub normal_texture: Option<TextureUse>,
    pub normal_scale: f32,
    /// The file's name for it, for messages (else its index).
    pub name: String,
}

impl Default for MaterialDesc {
    fn default() -> MaterialDesc {
        MaterialDesc {
            base_color: [1.0; 4],
            base_color_texture: None,
            emissive: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            alpha_texture: None,
            brdf: Brdf::Lambert,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            name: String::new(),
        }
    }
}
