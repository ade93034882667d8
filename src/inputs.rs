//! Every file format a user can feed lambert, each parsed from bytes as its
//! loader parses it: the one list that the fuzz harness (`fuzz/`) and its
//! regression tests (`tests/reliability.rs`) both drive, so that neither
//! keeps its own copy of which parser reads what.

use std::path::Path;

use crate::error::Result;
use crate::loading::material::ImageSource;
use crate::loading::{self, Mesh, NormalMode};

/// A user-facing input format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// A scene file (`Scene::from_toml`).
    Toml,
    Obj,
    Mtl,
    /// PLY, ascii or binary (a `.ply.gz` is gunzipped first by flate2).
    Ply,
    /// glTF JSON or GLB.
    Gltf,
    /// STL, binary or ASCII.
    Stl,
    /// A ray file of `lambert trace`.
    Rays,
    /// A point file of `lambert query`.
    Points,
    /// An EXR part file of `lambert merge`.
    Part,
    /// An environment map, Radiance HDR or OpenEXR (`[environment]`,
    /// `--environment`).
    Environment,
}

impl Input {
    pub const ALL: [Input; 10] = [
        Input::Toml,
        Input::Obj,
        Input::Mtl,
        Input::Ply,
        Input::Gltf,
        Input::Stl,
        Input::Rays,
        Input::Points,
        Input::Part,
        Input::Environment,
    ];

    /// The file extension of an input of this kind.
    pub fn extension(self) -> &'static str {
        match self {
            Input::Part => "exr",
            Input::Environment => "hdr",
            other => other.name(),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Input::Toml => "toml",
            Input::Obj => "obj",
            Input::Mtl => "mtl",
            Input::Ply => "ply",
            Input::Gltf => "gltf",
            Input::Stl => "stl",
            Input::Rays => "rays",
            Input::Points => "points",
            Input::Part => "part",
            Input::Environment => "environment",
        }
    }

    pub fn from_name(name: &str) -> Option<Input> {
        Input::ALL.into_iter().find(|i| i.name() == name)
    }

    /// Parses `bytes` as this format; `path` names the file in errors and
    /// anchors the files it refers to (meshes, MTL files, glTF buffers).
    /// Model formats are parsed with both normal modes, whose code differs.
    pub fn parse(self, bytes: &[u8], path: &Path) -> Result<()> {
        let modes = [NormalMode::Face, NormalMode::Smooth];
        match self {
            Input::Toml => crate::Scene::from_toml(&String::from_utf8_lossy(bytes), path).map(drop),
            Input::Obj | Input::Ply | Input::Gltf | Input::Stl => modes
                .into_iter()
                .try_for_each(|m| self.mesh(bytes, path, m).map(drop)),
            Input::Mtl => loading::obj::parse_mtl(
                &String::from_utf8_lossy(bytes),
                path,
                &mut Default::default(),
            ),
            Input::Rays => crate::rays::parse_rays(bytes, path).map(drop),
            Input::Points => crate::rays::parse_points(bytes, path).map(drop),
            Input::Part => crate::parts::parse_part(bytes, path).map(drop),
            Input::Environment => {
                crate::lighting::EnvironmentMap::parse(bytes, path, 1.0).map(drop)
            }
        }
    }

    /// A model input (OBJ, PLY, glTF, STL) as a scene of its triangles alone
    /// (`Scene::from_arrays`, its BVH built), for the fuzz harness to
    /// validate the tree; None for other formats and models without
    /// triangles.
    pub fn model_scene(self, bytes: &[u8], path: &Path) -> Result<Option<crate::Scene>> {
        let Some(mesh) = self.mesh(bytes, path, NormalMode::Face)? else {
            return Ok(None);
        };
        if mesh.triangles.is_empty() {
            return Ok(None);
        }
        // The images the model carries, decoded as a scene would (files it
        // names are left unread: the harness reads only its input).
        let carried: Vec<ImageSource> = mesh
            .images
            .iter()
            .map(|source| match source {
                ImageSource::File(path) => ImageSource::Embedded {
                    bytes: Vec::new(),
                    name: path.display().to_string(),
                },
                embedded => embedded.clone(),
            })
            .collect();
        let mut textures = crate::texture::TextureStore::default();
        let mut warnings = Vec::new();
        crate::texture::add_model_textures(
            &mut textures,
            path,
            &carried,
            &mesh.materials,
            &mut warnings,
        );
        let vertices: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        let faces: Vec<[i64; 3]> = mesh.triangles.iter().map(|t| t.map(i64::from)).collect();
        crate::Scene::from_arrays(&vertices, &faces, None).map(Some)
    }

    /// The mesh of a model input; None for other formats.
    fn mesh(self, bytes: &[u8], path: &Path, mode: NormalMode) -> Result<Option<Mesh>> {
        Ok(Some(match self {
            Input::Obj => loading::parse_obj(&String::from_utf8_lossy(bytes), path, mode)?,
            Input::Ply => loading::ply::parse_ply(bytes, path, mode)?,
            Input::Gltf => loading::gltf::parse_scene(bytes, path, mode)?.mesh,
            Input::Stl => loading::stl::parse_stl(bytes, path, mode)?,
            _ => return Ok(None),
        }))
    }
}
