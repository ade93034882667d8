//! A model file alone, or a mesh given as arrays, as a whole scene: the
//! framed camera and the default light where the model has none.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{
    DEFAULT_AMBIENT, Rgb, Scene, Transform, colour, directional_light, point_light, spot_light,
};
use crate::bvh::MAX_PRIMITIVES;
use crate::camera::{
    Camera, DEFAULT_HEIGHT, DEFAULT_WIDTH, default_light, flat_normal, frame_camera,
    validate_camera,
};
use crate::error::{Error, Result};
use crate::limits::{MAX_SIDE, checked_point};
use crate::loading::{self, NormalMode};
use crate::placement::{centring_offset, checked_local};

impl Scene {
    /// A model file alone as a scene: its geometry and materials; a glTF
    /// file's first perspective camera (or `camera`, by name) and its
    /// lights. With no camera, one is framed on the model; with no light,
    /// the default light (docs/scene-format.md). The file's own normals
    /// shade smoothly where it gives them at every corner.
    pub fn from_model(path: &Path, camera: Option<&str>) -> Result<Scene> {
        let bytes = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
        let mut model = loading::parse_model(&bytes, path, NormalMode::Smooth)?;
        model.mesh.files.insert(0, path.to_path_buf());
        Scene::from_parsed_model(path, model, camera)
    }

    /// `from_model` of a file's bytes (the web's dropped file); `path` names
    /// it in errors and tells its format. A file it refers to that cannot
    /// be read (an OBJ's MTL, an image) is a warning, as for a file on disk
    /// that is missing; a glTF file's external buffers, an error.
    pub fn from_model_bytes(bytes: &[u8], path: &Path, camera: Option<&str>) -> Result<Scene> {
        let model = loading::parse_model(bytes, path, NormalMode::Smooth)?;
        Scene::from_parsed_model(path, model, camera)
    }

    fn from_parsed_model(
        path: &Path,
        model: loading::gltf::GltfScene,
        camera: Option<&str>,
    ) -> Result<Scene> {
        let mut scene = Scene::model_bare();
        let loading::gltf::GltfScene {
            mut mesh,
            cameras,
            lights,
        } = model;
        if !mesh.file_normals {
            mesh.normals = None;
        }
        let bounds = mesh_bounds(&mesh);
        let flat = flat_normal(|| mesh.positions.iter().copied());
        scene.offset = centring_offset(bounds.0, bounds.1);
        scene.add_mesh(path, "the model", mesh, &Transform::IDENTITY, None)?;
        let chosen = match camera {
            Some(name) => Some(
                cameras
                    .iter()
                    .find(|c| c.name.as_deref() == Some(name))
                    .ok_or_else(|| {
                        let names: Vec<String> = cameras
                            .iter()
                            .map(|c| format!("'{}'", c.name.as_deref().unwrap_or("")))
                            .collect();
                        Error::scene(
                            path,
                            format!(
                                "no perspective camera named '{name}' (the file has {})",
                                if names.is_empty() {
                                    "none".to_string()
                                } else {
                                    names.join(", ")
                                }
                            ),
                        )
                    })?,
            ),
            None => cameras.first(),
        };
        scene.view.camera = match chosen {
            Some(c) => {
                let width = DEFAULT_WIDTH;
                let aspect = c.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0);
                let height = aspect.map_or(DEFAULT_HEIGHT, |a| {
                    ((width as f64 / a).round() as u32).clamp(1, MAX_SIDE)
                });
                Camera {
                    eye: c.eye.to_array(),
                    look_at: (c.eye + c.forward).to_array(),
                    up: c.up.to_array(),
                    vfov: c.yfov_deg,
                    width,
                    height,
                }
            }
            None => frame_camera(&bounds, flat),
        };
        validate_camera(&scene.view.camera)
            .and_then(|()| scene.check_camera_placement())
            .map_err(|e| Error::scene(path, format!("its camera: {e}")))?;
        for (i, light) in lights.iter().enumerate() {
            let field = format!("light {i} (KHR_lights_punctual, placed by its node)");
            let light = match light {
                loading::gltf::GltfLight::Point {
                    position,
                    intensity,
                } => point_light(
                    &field,
                    position.to_array(),
                    lecture_units(*intensity),
                    scene.offset,
                ),
                loading::gltf::GltfLight::Spot {
                    position,
                    direction,
                    intensity,
                    inner_cone_angle,
                    outer_cone_angle,
                } => spot_light(
                    &field,
                    position.to_array(),
                    *direction,
                    lecture_units(*intensity),
                    // The spec's bound π/2, in f32, is a hair above 90°.
                    [inner_cone_angle, outer_cone_angle].map(|a| a.to_degrees().min(90.0)),
                    scene.offset,
                ),
                loading::gltf::GltfLight::Directional {
                    direction,
                    irradiance,
                } => directional_light(&field, *direction, lecture_units(*irradiance)),
            };
            scene.lights.push(light.map_err(|m| Error::scene(path, m))?);
        }
        // A file's lights are the scene's lights: the default light and
        // ambient belong only to a model with no light of its own.
        if scene.lights.is_empty() {
            scene.lights.push(default_light(&scene.view.camera));
            scene.default_light = true;
        } else {
            scene.ambient = [0.0; 3];
        }
        scene.check_primitive_count(path)?;
        scene.rebuild_bvh();
        Ok(scene)
    }

    /// A mesh given as arrays (the Python package's `Scene.from_arrays`):
    /// triangle i is `faces[i]`, so primitive ids are face rows; every face
    /// with `albedo` (else the default); the framed camera and the default
    /// light of a model file alone. Errors name the row at fault.
    pub fn from_arrays(
        vertices: &[[f64; 3]],
        faces: &[[i64; 3]],
        albedo: Option<[f64; 3]>,
    ) -> Result<Scene> {
        let positions: Vec<DVec3> = vertices
            .iter()
            .enumerate()
            .map(|(row, &v)| {
                checked_point(&format!("vertices row {row}"), v)
                    .map(DVec3::from)
                    .map_err(Error::Usage)
            })
            .collect::<Result<_>>()?;
        let count = positions.len() as i64;
        let triangles: Vec<[u32; 3]> = faces
            .iter()
            .enumerate()
            .map(|(row, face)| match face.iter().find(|&&i| !(0..count).contains(&i)) {
                Some(i) => Err(Error::Usage(format!(
                    "faces row {row} = {face:?}: index {i} is out of range (there are {count} vertices, indexed from 0)"
                ))),
                None => Ok(face.map(|i| i as u32)),
            })
            .collect::<Result<_>>()?;
        if triangles.len() > MAX_PRIMITIVES {
            return Err(Error::Usage(format!(
                "{} faces; lambert supports at most {MAX_PRIMITIVES}",
                triangles.len()
            )));
        }
        let albedo = albedo
            .map(|a| colour("albedo", Rgb::PerChannel(a)).map_err(Error::Usage))
            .transpose()?;
        let mesh = loading::Mesh {
            positions,
            triangles,
            ..loading::Mesh::default()
        };
        let mut scene = Scene::model_bare();
        let bounds = mesh_bounds(&mesh);
        scene.view.camera = frame_camera(&bounds, flat_normal(|| mesh.positions.iter().copied()));
        scene.offset = centring_offset(bounds.0, bounds.1);
        for (row, &p) in mesh.positions.iter().enumerate() {
            checked_local(&format!("vertices row {row}"), p, scene.offset).map_err(Error::Usage)?;
        }
        scene.add_mesh(
            Path::new("arrays"),
            "the mesh",
            mesh,
            &Transform::IDENTITY,
            albedo,
        )?;
        scene.lights.push(default_light(&scene.view.camera));
        scene.default_light = true;
        scene.rebuild_bvh();
        Ok(scene)
    }

    /// `bare`, lit as a model file alone is: shadows and the default ambient.
    fn model_bare() -> Scene {
        Scene {
            shadows: true,
            ambient: [DEFAULT_AMBIENT; 3],
            ..Scene::bare()
        }
    }

    /// A scene of OBJ meshes alone, in the given order, for ray queries
    /// (`lambert trace --obj`): no lights, and a camera that nothing uses.
    pub fn from_objs(paths: &[PathBuf]) -> Result<Scene> {
        let mut scene = Scene::bare();
        let meshes = paths
            .iter()
            .map(|path| loading::load_mesh(path, NormalMode::Face))
            .collect::<Result<Vec<_>>>()?;
        let bounds = meshes.iter().map(mesh_bounds).fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        );
        scene.offset = centring_offset(bounds.0, bounds.1);
        for (path, mesh) in paths.iter().zip(meshes) {
            scene.add_mesh(path, "the mesh", mesh, &Transform::IDENTITY, None)?;
        }
        if scene.triangles.is_empty() {
            return Err(Error::Usage(format!(
                "{}: no faces to trace against",
                paths
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        scene.rebuild_bvh();
        Ok(scene)
    }
}

/// KHR_lights_punctual's photometric units (candela, lux) in the lecture's
/// that `Light::color` holds (docs/rendering.md, "Light units"): I candela
/// light a white surface, whose glTF BRDF's diffuse lobe is albedo/π, to
/// radiance I·cos θ/(π r²), which the lecture's albedo · color · cos θ / r²
/// gives for color = I/π (and lux likewise). Without the ÷ π a glTF file's
/// lights were π times too bright.
fn lecture_units(photometric: [f64; 3]) -> Rgb {
    Rgb::PerChannel(photometric.map(|c| c / std::f64::consts::PI))
}

fn mesh_bounds(mesh: &loading::Mesh) -> (DVec3, DVec3) {
    mesh.positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}
