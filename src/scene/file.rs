//! The TOML scene format (docs/scene-format.md): its tables, and a scene
//! built from them.

use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use serde::Deserialize;

use super::lighting::EnvironmentEntry;
use super::{
    Accel, DEFAULT_MAX_DEPTH, Integrator, Intersect, Rgb, Scene, Transform, colour,
    directional_light, point, point_light, spot_light,
};
use crate::camera::{Camera, View, validate_camera};
use crate::error::{Error, Result};
use crate::layout::{MATERIAL_METALLIC_ROUGHNESS, Material, Sphere};
use crate::limits::{MAX_SPHERE_RADIUS, checked_point, validate_spp, vector_text};
use crate::loading::{self, NormalMode};
use crate::placement::centring_offset;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: Camera,
    #[serde(default)]
    render: RenderTable,
    #[serde(default)]
    mesh: Vec<MeshEntry>,
    #[serde(default)]
    sphere: Vec<SphereEntry>,
    #[serde(default)]
    point_light: Vec<PointLightEntry>,
    #[serde(default)]
    directional_light: Vec<DirectionalLightEntry>,
    #[serde(default)]
    spot_light: Vec<SpotLightEntry>,
    #[serde(default)]
    environment: Option<EnvironmentEntry>,
}

/// The `[render]` table.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderTable {
    pub background: Rgb,
    pub ambient: Rgb,
    pub shadows: bool,
    /// None where the file does not say (1).
    pub spp: Option<u32>,
    pub seed: u32,
    pub intersect: Intersect,
    pub integrator: Integrator,
    pub max_depth: u32,
    pub accel: Accel,
}

impl Default for RenderTable {
    fn default() -> Self {
        RenderTable {
            background: Rgb::Uniform(0.0),
            ambient: Rgb::Uniform(0.0),
            shadows: true,
            spp: None,
            seed: 0,
            intersect: Intersect::default(),
            integrator: Integrator::default(),
            max_depth: DEFAULT_MAX_DEPTH,
            accel: Accel::default(),
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
    /// Make every material of the file metallic-roughness (`Brdf`).
    #[serde(default)]
    metallic: Option<f64>,
    #[serde(default)]
    roughness: Option<f64>,
    /// Replaces every material's emission (radiance): an area light.
    #[serde(default)]
    emission: Option<Rgb>,
    #[serde(default)]
    normals: NormalMode,
    #[serde(default)]
    translate: Option<[f64; 3]>,
    #[serde(default)]
    scale: Option<Scale>,
    #[serde(default)]
    rotate_deg: Option<[f64; 3]>,
}

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
    #[serde(default)]
    metallic: Option<f64>,
    #[serde(default)]
    roughness: Option<f64>,
    #[serde(default)]
    emission: Option<Rgb>,
}

/// `metallic` and `roughness` of a `[[mesh]]` or `[[sphere]]`, checked
/// (each in [0, 1]; `field` names them in errors): either makes its
/// materials glTF's metallic-roughness BRDF (docs/scene-format.md).
#[derive(Clone, Copy, Debug)]
struct Brdf {
    metallic: Option<f32>,
    roughness: Option<f32>,
    /// `emission`, radiance in linear RGB: the materials' own, replaced.
    emission: Option<[f32; 3]>,
}

impl Brdf {
    fn checked(field: &str, metallic: Option<f64>, roughness: Option<f64>) -> Result<Brdf, String> {
        let factor = |key: &str, value: Option<f64>| match value {
            Some(v) if !(0.0..=1.0).contains(&v) => {
                Err(format!("{field}.{key} = {v} must be in [0, 1]"))
            }
            v => Ok(v.map(|v| v as f32)),
        };
        Ok(Brdf {
            metallic: factor("metallic", metallic)?,
            roughness: factor("roughness", roughness)?,
            emission: None,
        })
    }

    /// With `emission` (`field`'s), which every material then emits: an
    /// area light under the path integrator, seen alone under direct.
    fn with_emission(self, field: &str, emission: Option<Rgb>) -> Result<Brdf, String> {
        let emission = emission
            .map(|e| colour(&format!("{field}.emission"), e))
            .transpose()?;
        Ok(Brdf { emission, ..self })
    }

    /// Applies the factors given to `materials`; one not given keeps the
    /// material's (a Lambert material's: metallic 0, roughness 1).
    fn apply(self, materials: &mut [Material]) {
        if let Some(emission) = self.emission {
            for material in materials.iter_mut() {
                material.emission = emission;
            }
        }
        if self.metallic.is_none() && self.roughness.is_none() {
            return;
        }
        for material in materials {
            material.kind = MATERIAL_METALLIC_ROUGHNESS;
            material.metallic = self.metallic.unwrap_or(material.metallic);
            material.roughness = self.roughness.unwrap_or(material.roughness);
        }
    }
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

/// `[[spot_light]]`: a point light limited to a cone (KHR_lights_punctual's
/// spot light, its falloff and defaults: inner 0°, outer 45°).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpotLightEntry {
    position: [f64; 3],
    /// The way it points.
    direction: [f64; 3],
    /// On its axis, as a point light's.
    intensity: Rgb,
    /// Half-angle of the cone of full intensity, degrees.
    #[serde(default)]
    inner_angle_deg: f64,
    /// Half-angle of the cone beyond which it gives no light, degrees.
    #[serde(default = "default_outer_angle")]
    outer_angle_deg: f64,
}

fn default_outer_angle() -> f64 {
    45.0
}

impl Scene {
    /// Parses scene text; `path` names it in errors and anchors relative paths.
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| Error::scene(path, e.to_string().trim_end()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let fail = |message: String| Error::scene(path, message);

        validate_camera(&file.camera).map_err(fail)?;
        let background = colour("render.background", file.render.background).map_err(fail)?;
        let ambient = colour("render.ambient", file.render.ambient).map_err(fail)?;
        let spp = file.render.spp.unwrap_or(1);
        validate_spp(spp).map_err(|e| fail(format!("render.{e}")))?;
        crate::limits::validate_max_depth(file.render.max_depth)
            .map_err(|e| fail(format!("render.{e}")))?;
        let environment = file
            .environment
            .as_ref()
            .map(|e| e.spec(base))
            .transpose()
            .map_err(fail)?;

        let mut scene = Scene {
            view: View {
                camera: file.camera,
                spp,
                seed: file.render.seed,
            },
            background,
            ambient,
            shadows: file.render.shadows,
            spp_given: file.render.spp.is_some(),
            intersect: file.render.intersect,
            integrator: file.render.integrator,
            max_depth: file.render.max_depth,
            accel: file.render.accel,
            inputs: vec![path.to_path_buf()],
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
            let brdf = Brdf::checked(&field, entry.metallic, entry.roughness)
                .and_then(|b| b.with_emission(&field, entry.emission))
                .map_err(fail)?;
            let model = base.join(&entry.file);
            let mesh = loading::load_mesh(&model, entry.normals)?;
            for &p in &mesh.positions {
                let q = transform.point(p);
                bounds = (bounds.0.min(q), bounds.1.max(q));
            }
            let what = format!("{field} ({})", entry.file.display());
            meshes.push((what, mesh, transform, albedo, brdf));
        }
        for entry in &file.sphere {
            let (center, radius) = (DVec3::from(entry.center), entry.radius.abs());
            bounds = (bounds.0.min(center - radius), bounds.1.max(center + radius));
        }
        scene.offset = centring_offset(bounds.0, bounds.1);
        for (what, mesh, transform, albedo, brdf) in meshes {
            let first = scene.materials.len();
            scene.add_mesh(path, &what, mesh, &transform, albedo)?;
            brdf.apply(&mut scene.materials[first..]);
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
            Brdf::checked(&field, entry.metallic, entry.roughness)
                .and_then(|b| b.with_emission(&field, entry.emission))
                .map_err(fail)?
                .apply(&mut scene.materials[material as usize..]);
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
        for (i, entry) in file.spot_light.iter().enumerate() {
            let light = spot_light(
                &format!("spot_light[{i}]"),
                entry.position,
                DVec3::from(entry.direction),
                entry.intensity,
                [entry.inner_angle_deg, entry.outer_angle_deg],
                scene.offset,
            )
            .map_err(fail)?;
            scene.lights.push(light);
        }
        if scene.triangles.is_empty() && scene.spheres.is_empty() {
            return Err(fail(
                "the scene is empty: it needs a [[mesh]] with faces or a [[sphere]]".into(),
            ));
        }
        scene.check_camera_placement().map_err(fail)?;
        scene.check_primitive_count(path)?;
        scene.set_environment(environment.as_ref())?;
        scene.rebuild_bvh();
        Ok(scene)
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
