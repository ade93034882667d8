//! The scene: its TOML file format (see docs/scene-format.md), validation, and
//! the flattened geometry that both render paths read.

use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use serde::Deserialize;

use crate::bvh::{Bvh, MAX_PRIMITIVES};
use crate::error::{Error, Result};
use crate::layout::{
    FLAG_SMOOTH, LIGHT_DIRECTIONAL, LIGHT_POINT, Light, Material, Sphere, Triangle, TriangleNormals,
};
use crate::loading::{self, NormalMode};
use crate::placement::{centring_offset, checked_local};

/// World coordinates beyond this magnitude are rejected: f64 itself spaces
/// them 1/8 apart there. Geometry far from the origin is kept relative to
/// the scene's offset (`placement`), so precision does not set this limit.
pub const MAX_COORDINATE: f64 = 1e15;

/// Geometry, lights and the camera beyond this distance (per axis) from
/// the scene's offset are rejected: the f32 edge tests take fourth powers
/// of lengths and would overflow.
pub const MAX_LOCAL_COORDINATE: f64 = 1e9;

/// Largest sphere radius. The hit distance no longer errs with the radius
/// (`intersect_sphere` keeps |o − c|² − r² exact to a few ulps of itself:
/// five units off a sphere of this radius, t is right to 1e-7), but f32
/// holds points on a larger sphere's surface no closer than 1/16 unit.
pub const MAX_SPHERE_RADIUS: f64 = 1e6;
/// Largest image side, in pixels.
pub const MAX_SIDE: u32 = 65_536;
/// Largest image, in pixels (16K × 16K): 5 GiB of host buffers.
pub const MAX_PIXELS: u64 = 1 << 28;

// ---------------------------------------------------------------- file format

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: Camera,
    #[serde(default)]
    render: RenderSettings,
    #[serde(default)]
    mesh: Vec<MeshEntry>,
    #[serde(default)]
    sphere: Vec<SphereEntry>,
    #[serde(default)]
    point_light: Vec<PointLightEntry>,
    #[serde(default)]
    directional_light: Vec<DirectionalLightEntry>,
}

/// The `[camera]` table. Kept in f64 so the oracle can use it at full
/// precision; the f32 paths round it once.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub eye: [f64; 3],
    pub look_at: [f64; 3],
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub vfov: f64,
    pub width: u32,
    pub height: u32,
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

/// The `[render]` table.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSettings {
    pub background: Rgb,
    pub ambient: Rgb,
    pub shadows: bool,
    pub spp: u32,
    pub seed: u32,
    pub intersect: Intersect,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            background: Rgb::Uniform(0.0),
            ambient: Rgb::Uniform(0.0),
            shadows: true,
            spp: 1,
            seed: 0,
            intersect: Intersect::default(),
        }
    }
}

/// Most samples per pixel a render may ask for.
pub const MAX_SPP: u32 = 4096;

/// A colour given as one number (grey) or as `[r, g, b]`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(untagged, expecting = "a number or an array of 3 numbers")]
pub enum Rgb {
    Uniform(f64),
    PerChannel([f64; 3]),
}

impl Rgb {
    pub fn to_array(self) -> [f64; 3] {
        match self {
            Rgb::Uniform(v) => [v; 3],
            Rgb::PerChannel(v) => v,
        }
    }
}

/// `scale = s` or `scale = [sx, sy, sz]`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(untagged, expecting = "a number or an array of 3 numbers")]
enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    /// Any model format (`obj` is its older name).
    #[serde(alias = "obj")]
    file: PathBuf,
    /// Overrides every material of the file when given.
    #[serde(default)]
    albedo: Option<Rgb>,
    #[serde(default)]
    normals: NormalMode,
    #[serde(default)]
    translate: Option<[f64; 3]>,
    #[serde(default)]
    scale: Option<Scale>,
    #[serde(default)]
    rotate_deg: Option<[f64; 3]>,
}

/// A face's albedo when neither the scene nor its file gives one.
pub const DEFAULT_ALBEDO: [f32; 3] = [0.8; 3];

fn default_albedo() -> Rgb {
    Rgb::Uniform(0.8)
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereEntry {
    center: [f64; 3],
    radius: f64,
    #[serde(default = "default_albedo")]
    albedo: Rgb,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightEntry {
    position: [f64; 3],
    intensity: Rgb,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionalLightEntry {
    direction: [f64; 3],
    irradiance: Rgb,
}

// ---------------------------------------------------------------- loaded scene

/// A loaded, validated scene, flattened into the buffers the GPU receives.
///
/// Primitive ids: triangles in file order across meshes in scene order
/// (polygons fan-triangulated), then spheres.
#[derive(Clone, Debug)]
pub struct Scene {
    pub camera: Camera,
    pub background: [f32; 3],
    pub ambient: [f32; 3],
    pub shadows: bool,
    pub triangles: Vec<Triangle>,
    /// One entry per triangle when any mesh is smooth, else empty.
    pub normals: Vec<TriangleNormals>,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// Over all primitives; built by `load`/`from_toml`.
    pub bvh: Bvh,
    /// How rays find their hits; both paths follow it.
    pub accel: Accel,
    /// The ray/triangle test both paths use.
    pub intersect: Intersect,
    /// Samples per pixel (1: the pixel centre).
    pub spp: u32,
    /// Seed of the sample jitter.
    pub seed: u32,
    /// What loading read but ignored or could not find (each names its
    /// file); the CLI prints them.
    pub warnings: Vec<String>,
    /// World position (f64) of the origin of the f32 geometry, lights and
    /// camera the kernels see: the centre of a scene far from the origin,
    /// else zero (`placement::centring_offset`).
    pub offset: DVec3,
}

/// `--intersect`: the ray/triangle test. See docs/accuracy.md for what each
/// costs and how far each can be trusted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Intersect {
    /// The lecture's plane intersection and three edge tests.
    Seed,
    /// Möller–Trumbore.
    MollerTrumbore,
    /// Woop, Benthin and Wald (JCGT 2013): no ray passes between triangles
    /// that share an edge.
    #[default]
    Watertight,
}

impl Intersect {
    pub const ALL: [Intersect; 3] = [
        Intersect::Seed,
        Intersect::MollerTrumbore,
        Intersect::Watertight,
    ];

    /// The shader's INTERSECT override value.
    pub fn shader_value(self) -> u32 {
        match self {
            Intersect::Seed => 0,
            Intersect::MollerTrumbore => 1,
            Intersect::Watertight => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Intersect::Seed => "seed",
            Intersect::MollerTrumbore => "moller-trumbore",
            Intersect::Watertight => "watertight",
        }
    }
}

/// `--accel`: the BVH, or testing every primitive (the reference that tests
/// the BVH).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Accel {
    #[default]
    Bvh,
    BruteForce,
}

impl Scene {
    /// Loads a scene file (mesh paths are relative to its folder), or a
    /// model file alone as a whole scene (`from_model`).
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_with_camera(path, None)
    }

    /// `load`, with a glTF file's camera chosen by name.
    pub fn load_with_camera(path: &Path, camera: Option<&str>) -> Result<Scene> {
        let is_toml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if is_toml {
            if camera.is_some() {
                return Err(Error::Usage(
                    "--camera picks a glTF file's camera; a TOML scene has one camera".into(),
                ));
            }
            let text = crate::files::read_text_capped(path, crate::files::MAX_TEXT_BYTES)?;
            return Scene::from_toml(&text, path);
        }
        let format = loading::Format::of(path).map_err(|_| {
            Error::Usage(format!(
                "{}: not a scene (.toml) or a model file ({})",
                path.display(),
                loading::SUPPORTED
            ))
        })?;
        Scene::from_model(path, format, camera)
    }

    /// A model file alone as a scene: its geometry and materials; a glTF
    /// file's first perspective camera (or `camera`, by name) and its
    /// lights. With no camera, one is framed on the model; with no light,
    /// the default light (docs/scene-format.md). The file's own normals
    /// shade smoothly where it gives them at every corner.
    pub fn from_model(path: &Path, format: loading::Format, camera: Option<&str>) -> Result<Scene> {
        let mut scene = Scene::model_bare();
        let (mut mesh, cameras, lights) = if format.is_gltf() {
            let g = loading::gltf::load_scene(path, NormalMode::Smooth)?;
            (g.mesh, g.cameras, g.lights)
        } else {
            (
                loading::load_mesh(path, NormalMode::Smooth)?,
                Vec::new(),
                Vec::new(),
            )
        };
        if !mesh.file_normals {
            mesh.normals = None;
        }
        let bounds = mesh_bounds(&mesh);
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
        scene.camera = match chosen {
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
            None => frame_camera(&bounds),
        };
        validate_camera(&scene.camera)
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
                    Rgb::PerChannel(*intensity),
                    scene.offset,
                ),
                loading::gltf::GltfLight::Directional {
                    direction,
                    irradiance,
                } => directional_light(&field, *direction, Rgb::PerChannel(*irradiance)),
            };
            scene.lights.push(light.map_err(|m| Error::scene(path, m))?);
        }
        // A file's lights are the scene's lights: the default light and
        // ambient belong only to a model with no light of its own.
        if scene.lights.is_empty() {
            scene.lights.push(default_light(&scene.camera));
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
        scene.camera = frame_camera(&bounds);
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
        scene.lights.push(default_light(&scene.camera));
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

    /// Parses scene text; `path` names it in errors and anchors relative paths.
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| Error::scene(path, e.to_string().trim_end()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let fail = |message: String| Error::scene(path, message);

        validate_camera(&file.camera).map_err(fail)?;
        let background = colour("render.background", file.render.background).map_err(fail)?;
        let ambient = colour("render.ambient", file.render.ambient).map_err(fail)?;
        validate_spp(file.render.spp).map_err(|e| fail(format!("render.{e}")))?;

        let mut scene = Scene {
            camera: file.camera,
            background,
            ambient,
            shadows: file.render.shadows,
            intersect: file.render.intersect,
            spp: file.render.spp,
            seed: file.render.seed,
            ..Scene::bare()
        };

        // Every mesh is read before any is placed: the offset depends on
        // the bounds of them all.
        let mut meshes = Vec::with_capacity(file.mesh.len());
        let mut bounds = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for (i, entry) in file.mesh.iter().enumerate() {
            let field = format!("mesh[{i}]");
            let albedo = entry
                .albedo
                .map(|a| colour(&format!("{field}.albedo"), a))
                .transpose()
                .map_err(fail)?;
            let transform = mesh_transform(&field, entry).map_err(fail)?;
            let model = base.join(&entry.file);
            let mesh = loading::load_mesh(&model, entry.normals)?;
            for &p in &mesh.positions {
                let q = transform.point(p);
                bounds = (bounds.0.min(q), bounds.1.max(q));
            }
            let what = format!("{field} ({})", entry.file.display());
            meshes.push((what, mesh, transform, albedo));
        }
        for entry in &file.sphere {
            let (center, radius) = (DVec3::from(entry.center), entry.radius.abs());
            bounds = (bounds.0.min(center - radius), bounds.1.max(center + radius));
        }
        scene.offset = centring_offset(bounds.0, bounds.1);
        for (what, mesh, transform, albedo) in meshes {
            scene.add_mesh(path, &what, mesh, &transform, albedo)?;
        }
        for (i, entry) in file.sphere.iter().enumerate() {
            let field = format!("sphere[{i}]");
            let center =
                point(&format!("{field}.center"), entry.center, scene.offset).map_err(fail)?;
            if !(entry.radius.is_finite()
                && entry.radius > 0.0
                && entry.radius <= MAX_SPHERE_RADIUS)
            {
                return Err(fail(format!(
                    "{field}.radius = {} must be positive and at most {MAX_SPHERE_RADIUS:e} \
                     (f32 places a larger sphere's surface points more than 1/16 unit apart; \
                     model a ground plane with triangles)",
                    entry.radius
                )));
            }
            let albedo = colour(&format!("{field}.albedo"), entry.albedo).map_err(fail)?;
            let material = scene.add_material(albedo);
            scene.spheres.push(Sphere {
                center,
                radius: entry.radius as f32,
                material,
                _pad0: 0,
                _pad1: 0,
                _pad2: 0,
            });
        }
        for (i, entry) in file.point_light.iter().enumerate() {
            let field = format!("point_light[{i}]");
            let light =
                point_light(&field, entry.position, entry.intensity, scene.offset).map_err(fail)?;
            scene.lights.push(light);
        }
        for (i, entry) in file.directional_light.iter().enumerate() {
            let field = format!("directional_light[{i}]");
            let direction = DVec3::from(entry.direction);
            let light = directional_light(&field, direction, entry.irradiance).map_err(fail)?;
            scene.lights.push(light);
        }
        if scene.triangles.is_empty() && scene.spheres.is_empty() {
            return Err(fail(
                "the scene is empty: it needs a [[mesh]] with faces or a [[sphere]]".into(),
            ));
        }
        scene.check_camera_placement().map_err(fail)?;
        scene.check_primitive_count(path)?;
        scene.rebuild_bvh();
        Ok(scene)
    }

    /// A scene of bare triangles (one grey material), for probes.
    pub fn from_triangles(triangles: Vec<Triangle>) -> Scene {
        let mut scene = Scene::bare();
        let material = scene.add_material([0.8; 3]);
        scene.triangles = triangles
            .into_iter()
            .map(|t| Triangle { material, ..t })
            .collect();
        scene.rebuild_bvh();
        scene
    }

    /// No geometry, no lights, and a camera that nothing uses yet.
    fn bare() -> Scene {
        Scene {
            camera: Camera {
                eye: [0.0, 0.0, 1.0],
                look_at: [0.0; 3],
                up: default_up(),
                vfov: 60.0,
                width: 1,
                height: 1,
            },
            background: [0.0; 3],
            ambient: [0.0; 3],
            shadows: false,
            triangles: Vec::new(),
            normals: Vec::new(),
            spheres: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            bvh: Bvh::default(),
            accel: Accel::default(),
            intersect: Intersect::default(),
            spp: 1,
            seed: 0,
            warnings: Vec::new(),
            offset: DVec3::ZERO,
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

    fn add_material(&mut self, albedo: [f32; 3]) -> u32 {
        self.materials.push(Material { albedo, _pad: 0 });
        (self.materials.len() - 1) as u32
    }

    /// Adds `mesh` (called `what` in errors about the file at `path`),
    /// every face with `albedo` when given, else with its file's material
    /// (DEFAULT_ALBEDO where it has none).
    fn add_mesh(
        &mut self,
        path: &Path,
        what: &str,
        mut mesh: loading::Mesh,
        transform: &Transform,
        albedo: Option<[f32; 3]>,
    ) -> Result<()> {
        self.warnings.append(&mut mesh.warnings);
        let uniform = match albedo {
            Some(a) => Some(a),
            None if mesh.face_materials.is_empty() => Some(DEFAULT_ALBEDO),
            None => None,
        };
        let (material, file_materials, fallback) = match uniform {
            Some(a) => (self.add_material(a), Vec::new(), 0),
            None => {
                let ids: Vec<u32> = mesh
                    .materials
                    .iter()
                    .map(|&a| self.add_material(a))
                    .collect();
                let fallback = if mesh.face_materials.iter().any(Option::is_none) {
                    self.add_material(DEFAULT_ALBEDO)
                } else {
                    0
                };
                (0, ids, fallback)
            }
        };
        let face_material = |i: usize| match mesh.face_materials.get(i) {
            _ if file_materials.is_empty() => material,
            Some(Some(m)) => file_materials[*m as usize],
            _ => fallback,
        };
        let offset = self.offset;
        let to_f32 = |v: u32| -> Result<[f32; 3]> {
            let p = mesh.positions[v as usize];
            let q = transform.point(p);
            let local = q - offset;
            if !q.is_finite() || q.abs().max_element() > MAX_COORDINATE {
                return Err(Error::scene(
                    path,
                    format!(
                        "{what}: vertex {} at {} is transformed to {}, beyond the supported magnitude {MAX_COORDINATE:e}",
                        v + 1,
                        vector_text(p),
                        vector_text(q)
                    ),
                ));
            }
            if local.abs().max_element() > MAX_LOCAL_COORDINATE {
                return Err(Error::scene(
                    path,
                    format!(
                        "{what}: vertex {} at {} is transformed to {}, {} from the scene's centre {}: \
                         the scene may span at most {MAX_LOCAL_COORDINATE:e} from its centre on each axis",
                        v + 1,
                        vector_text(p),
                        vector_text(q),
                        vector_text(local),
                        vector_text(offset)
                    ),
                ));
            }
            // Rounded once, from f64, relative to the offset.
            Ok(local.as_vec3().to_array())
        };
        let smooth = mesh.normals.is_some();
        if smooth && self.normals.len() < self.triangles.len() {
            self.normals
                .resize(self.triangles.len(), TriangleNormals::default());
        }
        self.triangles.reserve(mesh.triangles.len());
        for (i, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = *tri;
            self.triangles.push(Triangle {
                v0: to_f32(a)?,
                material: face_material(i),
                v1: to_f32(b)?,
                flags: if smooth { FLAG_SMOOTH } else { 0 },
                v2: to_f32(c)?,
                _pad: 0,
            });
            if let Some(normals) = &mesh.normals {
                let n = normals[i].map(|n| {
                    let m = transform.normal(n);
                    [m.x as f32, m.y as f32, m.z as f32, 0.0]
                });
                self.normals.push(TriangleNormals {
                    n0: n[0],
                    n1: n[1],
                    n2: n[2],
                });
            } else if !self.normals.is_empty() {
                self.normals.push(TriangleNormals::default());
            }
        }
        self.check_primitive_count(path)
    }

    /// The BVH addresses at most `MAX_PRIMITIVES` primitives.
    fn check_primitive_count(&self, path: &Path) -> Result<()> {
        if self.primitive_count() > MAX_PRIMITIVES {
            return Err(Error::scene(
                path,
                format!(
                    "the scene has {} primitives; lambert supports at most {MAX_PRIMITIVES}",
                    self.primitive_count()
                ),
            ));
        }
        Ok(())
    }

    /// Drops the triangles, their normals, the spheres and the BVH: what a
    /// render on a GPU, which has its own copy once the scene is uploaded,
    /// no longer needs on the host (materials, lights and the camera stay).
    pub fn release_geometry(&mut self) {
        self.triangles = Vec::new();
        self.normals = Vec::new();
        self.spheres = Vec::new();
        self.bvh = Bvh::default();
    }

    /// Rebuilds the BVH after the geometry changed.
    pub fn rebuild_bvh(&mut self) {
        self.bvh = Bvh::build(&self.triangles, &self.spheres);
    }

    pub fn primitive_count(&self) -> usize {
        self.triangles.len() + self.spheres.len()
    }
}

/// Object-to-world transform of a mesh: scale, then rotate about X, Y, Z (in
/// that order, fixed axes), then translate.
struct Transform {
    linear: DMat3,
    normal: DMat3,
    translate: DVec3,
}

impl Transform {
    const IDENTITY: Transform = Transform {
        linear: DMat3::IDENTITY,
        normal: DMat3::IDENTITY,
        translate: DVec3::ZERO,
    };

    fn point(&self, p: DVec3) -> DVec3 {
        self.linear * p + self.translate
    }

    fn normal(&self, n: DVec3) -> DVec3 {
        (self.normal * n).normalize_or_zero()
    }
}

fn mesh_transform(field: &str, entry: &MeshEntry) -> Result<Transform, String> {
    let scale = match entry.scale {
        None => DVec3::ONE,
        Some(Scale::Uniform(s)) => DVec3::splat(s),
        Some(Scale::PerAxis(s)) => DVec3::from(s),
    };
    if !scale.is_finite() || scale.abs().min_element() == 0.0 {
        return Err(format!(
            "{field}.scale = {} must be finite and non-zero on every axis",
            vector_text(scale)
        ));
    }
    let rotate = DVec3::from(entry.rotate_deg.unwrap_or([0.0; 3]));
    if !rotate.is_finite() {
        return Err(format!(
            "{field}.rotate_deg = {} must be finite",
            vector_text(rotate)
        ));
    }
    let translate = entry.translate.unwrap_or([0.0; 3]);
    let translate = DVec3::from(checked_point(&format!("{field}.translate"), translate)?);
    let rotation = DMat3::from_rotation_z(rotate.z.to_radians())
        * DMat3::from_rotation_y(rotate.y.to_radians())
        * DMat3::from_rotation_x(rotate.x.to_radians());
    let linear = rotation * DMat3::from_diagonal(scale);
    Ok(Transform {
        linear,
        normal: linear.inverse().transpose(),
        translate,
    })
}

/// Smallest sine of the angle between camera.up and the view direction:
/// closer, the camera's right vector (f × up) is mostly rounding. Any up
/// that passes gives the same camera as its part perpendicular to f.
pub const MIN_UP_SINE: f64 = 1e-6;

pub fn validate_camera(camera: &Camera) -> Result<(), String> {
    for (name, v) in [
        ("eye", camera.eye),
        ("look_at", camera.look_at),
        ("up", camera.up),
    ] {
        checked_point(&format!("camera.{name}"), v)?;
    }
    let eye = DVec3::from(camera.eye);
    let forward = DVec3::from(camera.look_at) - eye;
    if forward.length_squared() == 0.0 {
        return Err("camera.eye and camera.look_at are the same point".into());
    }
    let up = DVec3::from(camera.up);
    if up.length_squared() == 0.0 {
        return Err("camera.up is the zero vector".into());
    }
    let sine = forward.normalize().cross(up.normalize()).length();
    if sine < MIN_UP_SINE {
        return Err(format!(
            "camera.up = {} is parallel to the view direction (look_at − eye): the angle between them must be at least {MIN_UP_SINE:e} rad",
            vector_text(DVec3::from(camera.up))
        ));
    }
    if !(camera.vfov > 0.0 && camera.vfov < 180.0) {
        return Err(format!(
            "camera.vfov = {} must be in (0, 180) degrees",
            camera.vfov
        ));
    }
    validate_resolution(camera.width, camera.height).map_err(|e| format!("camera: {e}"))
}

/// A model rendered alone: its resolution unless its camera's aspect ratio
/// or --width/--height say otherwise.
pub const DEFAULT_WIDTH: u32 = 1024;
pub const DEFAULT_HEIGHT: u32 = 768;
/// A model with no light of its own, rendered alone: ambient light, so
/// that no face is black.
pub const DEFAULT_AMBIENT: f32 = 0.1;
/// Field of view of the camera framed on a model with none.
pub const FRAMED_VFOV_DEG: f64 = 40.0;

fn mesh_bounds(mesh: &loading::Mesh) -> (DVec3, DVec3) {
    mesh.positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// The camera framed on a model with none: looking at the centre of its
/// bounding box from the front-right and above (along (1, 0.75, 2) from
/// it, +Y up), at the distance where the box's bounding sphere just fits
/// the narrower field of view, with a 5% margin.
pub fn frame_camera(&(lo, hi): &(DVec3, DVec3)) -> Camera {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let aspect = DEFAULT_WIDTH as f64 / DEFAULT_HEIGHT as f64;
    let half_v = (FRAMED_VFOV_DEG / 2.0).to_radians();
    let half_h = (half_v.tan() * aspect).atan();
    let distance = 1.05 * radius / half_v.min(half_h).sin();
    let eye = centre + distance * DVec3::new(1.0, 0.75, 2.0).normalize();
    Camera {
        eye: eye.to_array(),
        look_at: centre.to_array(),
        up: default_up(),
        vfov: FRAMED_VFOV_DEG,
        width: DEFAULT_WIDTH,
        height: DEFAULT_HEIGHT,
    }
}

/// The light of a model with none: directional, irradiance 1, shining
/// from behind the camera's right shoulder (from the camera, 30% to its
/// right and 50% up), so that what the camera sees is lit.
pub fn default_light(camera: &Camera) -> Light {
    let basis = crate::cpu::f64::CameraBasis::new(camera);
    let travel = basis.forward - 0.3 * basis.right - 0.5 * basis.up;
    directional_light("the default light", travel, Rgb::Uniform(1.0))
        .expect("a valid camera's basis is orthonormal")
}

/// A point light at world `position` of `intensity` (candela), kept
/// relative to the scene's `offset`; `field` names it in errors.
fn point_light(
    field: &str,
    position: [f64; 3],
    intensity: Rgb,
    offset: DVec3,
) -> Result<Light, String> {
    Ok(Light {
        vector: point(&format!("{field}.position"), position, offset)?,
        kind: LIGHT_POINT,
        color: colour(&format!("{field}.intensity"), intensity)?,
        _pad: 0,
    })
}

/// A directional light travelling along `direction` (finite, non-zero)
/// with `irradiance`; the shader takes the way to the light.
fn directional_light(field: &str, direction: DVec3, irradiance: Rgb) -> Result<Light, String> {
    if !direction.is_finite() || direction.length_squared() == 0.0 {
        return Err(format!(
            "{field}.direction = {} must be a finite, non-zero vector",
            vector_text(direction)
        ));
    }
    Ok(Light {
        vector: (-direction.normalize()).as_vec3().to_array(),
        kind: LIGHT_DIRECTIONAL,
        color: colour(&format!("{field}.irradiance"), irradiance)?,
        _pad: 0,
    })
}

/// A vector as a user writes it: [x, y, z].
pub fn vector_text(v: DVec3) -> String {
    let number = |x: f64| {
        if x != 0.0 && !(1e-4..1e7).contains(&x.abs()) {
            format!("{x:e}")
        } else {
            format!("{x}")
        }
    };
    format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z))
}

/// Columns of the stratified sample grid: the largest divisor of `spp` not
/// above its square root, so that the grid is as square as `spp` allows and
/// every cell holds one sample.
pub fn strata_columns(spp: u32) -> u32 {
    (1..=spp.isqrt().max(1))
        .rev()
        .find(|d| spp.is_multiple_of(*d))
        .unwrap_or(1)
}

/// Checks a sample count.
pub fn validate_spp(spp: u32) -> Result<(), String> {
    if spp == 0 || spp > MAX_SPP {
        return Err(format!("spp = {spp} must be between 1 and {MAX_SPP}"));
    }
    Ok(())
}

/// Checks an image size against what memory and tiling can serve.
pub fn validate_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("resolution {width}×{height} has a zero side"));
    }
    if width > MAX_SIDE || height > MAX_SIDE || width as u64 * height as u64 > MAX_PIXELS {
        return Err(format!(
            "resolution {width}×{height} is beyond the supported maximum \
             ({MAX_SIDE} per side, {MAX_PIXELS} pixels in all)"
        ));
    }
    Ok(())
}

impl Camera {
    /// This camera at another image size: with only one of width and
    /// height given, the other keeps the aspect ratio.
    pub fn resized(&self, width: Option<u32>, height: Option<u32>) -> Result<Camera, String> {
        let (w, h) = (self.width as f64, self.height as f64);
        let (width, height) = match (width, height) {
            (None, None) => return Ok(self.clone()),
            (Some(width), Some(height)) => (width, height),
            (Some(width), None) => (width, ((width as f64 * h / w).round() as u32).max(1)),
            (None, Some(height)) => (((height as f64 * w / h).round() as u32).max(1), height),
        };
        validate_resolution(width, height)?;
        Ok(Camera {
            width,
            height,
            ..self.clone()
        })
    }
}

/// A world position: finite and within MAX_COORDINATE, kept relative to
/// the scene's `offset` (within MAX_LOCAL_COORDINATE of it) and rounded to
/// f32 from there.
fn point(field: &str, v: [f64; 3], offset: DVec3) -> Result<[f32; 3], String> {
    let local = checked_local(field, DVec3::from(checked_point(field, v)?), offset)?;
    Ok(local.as_vec3().to_array())
}

fn checked_point(field: &str, v: [f64; 3]) -> Result<[f64; 3], String> {
    if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE) {
        Ok(v)
    } else {
        Err(format!(
            "{field} = {v:?} must be finite with magnitude at most {MAX_COORDINATE:e}"
        ))
    }
}

fn colour(field: &str, rgb: Rgb) -> Result<[f32; 3], String> {
    let v = rgb.to_array();
    if v.iter()
        .all(|c| c.is_finite() && *c >= 0.0 && *c <= f32::MAX as f64)
    {
        Ok(v.map(|c| c as f32))
    } else {
        Err(format!("{field} = {v:?} must be finite and non-negative"))
    }
}
