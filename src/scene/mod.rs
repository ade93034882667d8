//! The scene: the flattened geometry both render paths read, its
//! materials and lights, and where it sits (its offset). Read from a TOML
//! scene file (`file`, docs/scene-format.md) or a model file alone
//! (`model`).

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use glam::{DMat3, DVec3};
use serde::Deserialize;

use crate::bvh::{Bvh, MAX_PRIMITIVES};
use crate::camera::{Camera, View, default_up};
use crate::error::{Error, Result};
use crate::layout::{
    ALPHA_MASK, ALPHA_OPAQUE, FLAG_ATTRIBUTES, FLAG_MASKED, FLAG_SMOOTH, Hit, LIGHT_POINT,
    LIGHT_SPOT, Light, MATERIAL_METALLIC_ROUGHNESS, Material, NO_HIT, Ray, Sphere, Triangle,
    TriangleAttributes, TriangleNormals, TriangleTangents,
};
use crate::lighting::{EmitterTable, Environment};
use crate::limits::{MAX_COORDINATE, MAX_LOCAL_COORDINATE, checked_point, vector_text};
use crate::loading;
use crate::placement::{Placement, checked_local};

mod access;
mod file;
mod lighting;
mod model;
mod settings;

pub use lighting::{environment_option, environment_spec};
pub use settings::{DEFAULT_MAX_DEPTH, Integrator, RenderSettings};

/// A loaded, validated scene, flattened into the buffers the GPU receives:
/// geometry, materials, lights and its default view, read through its
/// methods (`access.rs`). What a render may change (size, spp, shadows,
/// ambient, accel, intersect) is a `RenderSettings`: the scene's own are
/// `default_settings()`, and the jobs render `with_settings`.
///
/// Primitive ids: triangles in file order across meshes in scene order
/// (polygons fan-triangulated), then spheres.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The view the scene's file asks for (its camera, spp and seed): the
    /// default of the front ends, which render any other view as well.
    pub(crate) view: View,
    /// Whether the file set `view.spp` (`render.spp`) rather than leaving
    /// it 1: the viewer refines to it only then.
    pub(crate) spp_given: bool,
    pub(crate) background: [f32; 3],
    pub(crate) ambient: [f32; 3],
    pub(crate) shadows: bool,
    pub(crate) triangles: Vec<Triangle>,
    /// One entry per triangle when any mesh is smooth, else empty.
    pub(crate) normals: Vec<TriangleNormals>,
    /// One entry per triangle when any mesh has vertex colours or texture
    /// coordinates, else empty.
    pub(crate) attributes: Vec<TriangleAttributes>,
    /// One entry per triangle when any material has a normal texture, else
    /// empty.
    pub(crate) tangents: Vec<TriangleTangents>,
    /// Triangles whose file gave them vertex colours (for `lambert info`).
    pub(crate) colored_triangles: usize,
    pub(crate) spheres: Vec<Sphere>,
    pub(crate) materials: Vec<Material>,
    pub(crate) lights: Vec<Light>,
    /// Every texture the materials use, as both paths read it.
    pub(crate) textures: crate::texture::TextureStore,
    /// Over all primitives; built by `load`/`from_toml`.
    pub(crate) bvh: Bvh,
    /// How rays find their hits; both paths follow it.
    pub(crate) accel: Accel,
    /// The ray/triangle test both paths use.
    pub(crate) intersect: Intersect,
    pub(crate) integrator: Integrator,
    /// Whether `lights` is the one default light a model with none of its
    /// own is given (`camera::default_light`), which the path integrator
    /// drops where the model has light of its own (`with_settings`).
    pub(crate) default_light: bool,
    /// The default light `with_settings` dropped for the path integrator,
    /// given back when the scene is set to `direct` again (the viewer's
    /// `p`, the Python package's `integrator=`).
    pub(crate) dropped_default_light: Vec<Light>,
    /// Under `Integrator::Path`, the most surfaces a path hits.
    pub(crate) max_depth: u32,
    /// What loading read but ignored or could not find (each names its
    /// file); the CLI prints them.
    pub(crate) warnings: Vec<String>,
    /// Every file loading read or looked for: the scene file, its models,
    /// their MTL files, glTF buffers and textures. No output may replace
    /// one (`check_output`).
    pub(crate) inputs: Vec<PathBuf>,
    /// World position (f64) of the origin of the f32 geometry, lights and
    /// camera the kernels see: the centre of a scene far from the origin,
    /// else zero (`placement::centring_offset`).
    pub(crate) offset: DVec3,
    /// Light from every direction at infinity (`lighting.rs`), shared by
    /// the scene's copies: a map may be large.
    pub(crate) environment: Option<Arc<Environment>>,
    /// The emitters' table, built on first use (`Scene::emitters`) and
    /// dropped by every edit of what it is built from.
    pub(crate) emitters: OnceLock<EmitterTable>,
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

/// `--accel` (`render.accel`): the BVH, testing every primitive (the
/// reference that tests the BVH), or the GPU's ray-tracing units
/// (docs/hardware-rays.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Accel {
    #[default]
    Bvh,
    BruteForce,
    /// Ray queries against acceleration structures the GPU's driver builds
    /// (wgpu's experimental ray queries). The CPU path, and on the GPU the
    /// queries and rays they cannot take, traverse the BVH.
    Hardware,
}

impl Accel {
    /// Whether the BVH is traversed: under `Bvh`, and under `Hardware`
    /// wherever ray queries are not used.
    pub fn traverses_bvh(self) -> bool {
        self != Accel::BruteForce
    }
}

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

/// A face's albedo when neither the scene nor its file gives one.
pub const DEFAULT_ALBEDO: [f32; 3] = [0.8; 3];

/// A model with no light of its own, rendered alone: ambient light, so
/// that no face is black.
pub const DEFAULT_AMBIENT: f32 = 0.1;

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
        loading::Format::of(path).map_err(|_| {
            Error::Usage(format!(
                "{}: not a scene (.toml) or a model file ({})",
                path.display(),
                loading::SUPPORTED
            ))
        })?;
        Scene::from_model(path, camera)
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
            view: View {
                camera: Camera {
                    eye: [0.0, 0.0, 1.0],
                    look_at: [0.0; 3],
                    up: default_up(),
                    vfov: 60.0,
                    width: 1,
                    height: 1,
                },
                spp: 1,
                seed: 0,
            },
            spp_given: false,
            background: [0.0; 3],
            ambient: [0.0; 3],
            shadows: false,
            triangles: Vec::new(),
            normals: Vec::new(),
            attributes: Vec::new(),
            tangents: Vec::new(),
            colored_triangles: 0,
            spheres: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            textures: Default::default(),
            bvh: Bvh::default(),
            accel: Accel::default(),
            intersect: Intersect::default(),
            integrator: Integrator::default(),
            default_light: false,
            dropped_default_light: Vec::new(),
            max_depth: DEFAULT_MAX_DEPTH,
            warnings: Vec::new(),
            inputs: Vec::new(),
            offset: DVec3::ZERO,
            environment: None,
            emitters: OnceLock::new(),
        }
    }

    fn add_material(&mut self, albedo: [f32; 3]) -> u32 {
        self.push_material(Material::from_albedo(albedo))
    }

    fn push_material(&mut self, material: Material) -> u32 {
        self.materials.push(material);
        (self.materials.len() - 1) as u32
    }

    /// Whether some material is alpha-masked (the shader's HAS_ALPHA_MASK:
    /// without one, traversal skips the alpha test altogether).
    pub fn has_alpha_mask(&self) -> bool {
        self.materials.iter().any(|m| m.alpha_mode == ALPHA_MASK)
    }

    /// Whether some material reads a texture (the shader's HAS_TEXTURES:
    /// without one, its texture lookups are compiled out).
    pub fn has_textures(&self) -> bool {
        self.materials.iter().any(|m| {
            [
                m.base_color_texture,
                m.emissive_texture,
                m.alpha_texture,
                m.metallic_roughness_texture,
                m.normal_texture,
            ]
            .iter()
            .any(|&slot| slot != crate::layout::NO_TEXTURE)
        })
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
        self.inputs.append(&mut mesh.files);
        self.inputs
            .extend(mesh.images.iter().filter_map(|image| match image {
                loading::ImageSource::File(file) => Some(file.clone()),
                loading::ImageSource::Embedded { .. } => None,
            }));
        let uniform = match albedo {
            Some(a) => Some(a),
            None if mesh.face_materials.is_empty() => Some(DEFAULT_ALBEDO),
            None => None,
        };
        let (material, file_materials, fallback) = match uniform {
            Some(a) => (self.add_material(a), Vec::new(), 0),
            None => {
                // Textures only where the mesh has texture coordinates to
                // read them with (a loader warns of a texture without).
                let slots = if mesh.uvs.is_some() {
                    crate::texture::add_model_textures(
                        &mut self.textures,
                        path,
                        &mesh.images,
                        &mesh.materials,
                        &mut self.warnings,
                    )
                } else {
                    Vec::new()
                };
                let ids: Vec<u32> = mesh
                    .materials
                    .iter()
                    .enumerate()
                    .map(|(i, m)| {
                        let mut material = material_of(m);
                        if let Some(s) = slots.get(i) {
                            material.base_color_texture = s.base_color;
                            material.emissive_texture = s.emissive;
                            material.alpha_texture = s.alpha;
                            material.metallic_roughness_texture = s.metallic_roughness;
                            material.normal_texture = s.normal;
                        }
                        self.push_material(material)
                    })
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
        // Tangent frames where a material reads a normal map with the
        // mesh's texture coordinates (kept unless `albedo` replaces the
        // file's materials): the file's, else MikkTSpace's.
        let normal_mapped = albedo.is_none()
            && mesh.uvs.is_some()
            && mesh.materials.iter().any(|m| m.normal_texture.is_some());
        let tangents = normal_mapped.then(|| match mesh.tangents.take() {
            Some(given) => given,
            None => loading::tangents::generate(
                &mesh.positions,
                &mesh.triangles,
                mesh.normals.as_deref(),
                mesh.uvs.as_deref().unwrap_or_default(),
            ),
        });
        if tangents.is_some() && self.tangents.len() < self.triangles.len() {
            self.tangents
                .resize(self.triangles.len(), TriangleTangents::default());
        }
        let smooth = mesh.normals.is_some();
        if smooth && self.normals.len() < self.triangles.len() {
            self.normals
                .resize(self.triangles.len(), TriangleNormals::default());
        }
        // A scene's `albedo` replaces the file's colours, its vertex
        // colours too.
        let (colors, uvs) = if albedo.is_some() {
            (None, None)
        } else {
            (mesh.colors.as_deref(), mesh.uvs.as_deref())
        };
        let attributed = colors.is_some() || uvs.is_some();
        if colors.is_some() {
            self.colored_triangles += mesh.triangles.len();
        }
        if attributed && self.attributes.len() < self.triangles.len() {
            self.attributes
                .resize(self.triangles.len(), TriangleAttributes::default());
        }
        // A mirroring transform (negative determinant) would turn every
        // face inside out; two corners swapped keep them facing out, as a
        // glTF node's mirror does.
        let mirrored = transform.linear.determinant() < 0.0;
        self.triangles.reserve(mesh.triangles.len());
        for (i, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = if mirrored {
                [tri[0], tri[2], tri[1]]
            } else {
                *tri
            };
            let material = face_material(i);
            let masked = self.materials[material as usize].alpha_mode == ALPHA_MASK;
            let flags = [
                (smooth, FLAG_SMOOTH),
                (attributed, FLAG_ATTRIBUTES),
                (masked, FLAG_MASKED),
            ]
            .iter()
            .filter(|(on, _)| *on)
            .fold(0, |flags, (_, flag)| flags | flag);
            self.triangles.push(Triangle {
                v0: to_f32(a)?,
                material,
                v1: to_f32(b)?,
                flags,
                v2: to_f32(c)?,
                _pad: 0,
            });
            let swap = |[x, y, z]: [[f32; 4]; 3]| if mirrored { [x, z, y] } else { [x, y, z] };
            if attributed {
                let mut entry = TriangleAttributes::default();
                if let Some(colors) = colors {
                    entry.colors = swap(colors[i]);
                }
                if let Some(uvs) = uvs {
                    let [p, q, r] = uvs[i];
                    entry.uvs = if mirrored { [p, r, q] } else { [p, q, r] };
                }
                self.attributes.push(entry);
            } else if !self.attributes.is_empty() {
                self.attributes.push(TriangleAttributes::default());
            }
            if let Some(normals) = &mesh.normals {
                let [na, nb, nc] = normals[i];
                let corners = if mirrored { [na, nc, nb] } else { [na, nb, nc] };
                let n = corners.map(|n| {
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
            if let Some(tangents) = &tangents {
                let [ta, tb, tc] = tangents[i];
                let corners = if mirrored { [ta, tc, tb] } else { [ta, tb, tc] };
                let [t0, t1, t2] = corners.map(|t| transform.tangent(t));
                self.tangents.push(TriangleTangents { t0, t1, t2 });
            } else if !self.tangents.is_empty() {
                self.tangents.push(TriangleTangents::default());
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

    /// Rebuilds the BVH after the geometry changed.
    pub fn rebuild_bvh(&mut self) {
        self.bvh = Bvh::build(&self.triangles, &self.spheres);
        self.forget_emitters();
    }

    pub fn primitive_count(&self) -> usize {
        self.triangles.len() + self.spheres.len()
    }
}

/// The kernels' material of a file's: BLEND is rendered as MASK at 0.5
/// (the loader warns); texture slots are filled by `add_mesh`.
fn material_of(desc: &loading::MaterialDesc) -> Material {
    let [r, g, b, a] = desc.base_color;
    let mut material = Material::from_albedo([r, g, b]);
    material.base_color[3] = a;
    material.emission = desc.emissive;
    if let loading::Brdf::MetallicRoughness {
        metallic,
        roughness,
    } = desc.brdf
    {
        (material.kind, material.metallic, material.roughness) =
            (MATERIAL_METALLIC_ROUGHNESS, metallic, roughness);
    }
    material.normal_scale = desc.normal_scale;
    (material.alpha_mode, material.alpha_cutoff) = match desc.alpha_mode {
        loading::AlphaMode::Opaque => (ALPHA_OPAQUE, desc.alpha_cutoff),
        loading::AlphaMode::Mask => (ALPHA_MASK, desc.alpha_cutoff),
        loading::AlphaMode::Blend => (ALPHA_MASK, 0.5),
    };
    material
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

    /// A tangent (xyz) and bitangent sign (w): the direction mapped as a
    /// surface's vectors are, the sign flipped by a mirroring transform
    /// (which turns the frame's handedness: bitangent = w · normal ×
    /// tangent holds after it only so).
    fn tangent(&self, t: [f32; 4]) -> [f32; 4] {
        let d =
            (self.linear * DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)).normalize_or_zero();
        let w = if self.linear.determinant() < 0.0 {
            -t[3]
        } else {
            t[3]
        };
        [d.x as f32, d.y as f32, d.z as f32, w]
    }
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
        ..Light::default()
    })
}

/// A spot light: `point_light`'s, pointing along `direction`, at full
/// intensity within `inner_deg` of its axis, falling off smoothly to none
/// at `outer_deg` (KHR_lights_punctual's cone half-angles: 0 ≤ inner ≤
/// outer ≤ 90, outer > 0).
fn spot_light(
    field: &str,
    position: [f64; 3],
    direction: DVec3,
    intensity: Rgb,
    [inner_deg, outer_deg]: [f64; 2],
    offset: DVec3,
) -> Result<Light, String> {
    let mut light = point_light(field, position, intensity, offset)?;
    let direction = checked_direction(field, direction)?;
    if !(0.0 <= inner_deg && inner_deg <= outer_deg && outer_deg <= 90.0 && outer_deg > 0.0) {
        return Err(format!(
            "{field}: the cone angles (inner {inner_deg}°, outer {outer_deg}°) must satisfy \
             0 ≤ inner ≤ outer ≤ 90 with outer > 0"
        ));
    }
    light.kind = LIGHT_SPOT;
    light.direction = direction.normalize().as_vec3().to_array();
    light.cos_inner = inner_deg.to_radians().cos() as f32;
    light.cos_outer = outer_deg.to_radians().cos() as f32;
    Ok(light)
}

/// A light's `direction`: finite and non-zero (`field` names it).
fn checked_direction(field: &str, direction: DVec3) -> Result<DVec3, String> {
    if !direction.is_finite() || direction.length_squared() == 0.0 {
        return Err(format!(
            "{field}.direction = {} must be a finite, non-zero vector",
            vector_text(direction)
        ));
    }
    Ok(direction)
}

/// A directional light travelling along `direction` (finite, non-zero)
/// with `irradiance`; the shader takes the way to the light.
fn directional_light(field: &str, direction: DVec3, irradiance: Rgb) -> Result<Light, String> {
    let direction = checked_direction(field, direction)?;
    let irradiance = colour(&format!("{field}.irradiance"), irradiance)?;
    Ok(crate::camera::directional_light(direction, irradiance))
}

/// A world position: finite and within MAX_COORDINATE, kept relative to
/// the scene's `offset` (within MAX_LOCAL_COORDINATE of it) and rounded to
/// f32 from there.
fn point(field: &str, v: [f64; 3], offset: DVec3) -> Result<[f32; 3], String> {
    let local = checked_local(field, DVec3::from(checked_point(field, v)?), offset)?;
    Ok(local.as_vec3().to_array())
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

impl Scene {
    /// `camera` relative to the scene's offset (in f64): what the kernels'
    /// camera basis is built from.
    pub fn local_camera(&self, camera: &Camera) -> Camera {
        camera.relative_to(self.offset)
    }

    /// The default view's eye and look_at within MAX_LOCAL_COORDINATE of
    /// the offset, as the geometry is, and a camera still in f32 there.
    pub(crate) fn check_camera_placement(&self) -> Result<(), String> {
        self.check_camera(&self.view.camera)
    }

    /// `camera` (any view of the scene) within MAX_LOCAL_COORDINATE of
    /// the offset, and still a camera in f32 there.
    pub fn check_camera(&self, camera: &Camera) -> Result<(), String> {
        for (name, world) in [("eye", camera.eye), ("look_at", camera.look_at)] {
            checked_local(&format!("camera.{name}"), DVec3::from(world), self.offset)?;
        }
        crate::camera::validate_camera_f32(camera, self.offset)
    }

    /// An error where writing `output` would replace a file the scene was
    /// read from (its scene file, a model, an MTL file, a buffer, a
    /// texture; links included), naming that file.
    pub fn check_output(&self, output: &Path) -> Result<()> {
        let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        crate::output::refuse_input(output, &inputs)
    }

    /// Its offset, and the radius of its geometry about it (from the
    /// BVH's bounds).
    pub fn placement(&self) -> Placement {
        let radius = self.bvh.bounds().map_or(0.0, |b| {
            b.min.as_dvec3().abs().max(b.max.as_dvec3().abs()).length()
        });
        Placement {
            offset: self.offset,
            radius,
        }
    }
}

/// The unnormalised geometric normal at `hit` of `ray`: (v1 − v0) × (v2 − v0)
/// of the triangle hit (Embree's Ng), the centre-to-hit vector of a sphere
/// (length: its radius), zero on a miss.
#[inline]
pub fn hit_normal(scene: &Scene, ray: &Ray, hit: &Hit) -> [f32; 3] {
    use glam::Vec3;
    let prim = hit.prim as usize;
    let triangles = &scene.triangles;
    if hit.prim == NO_HIT {
        [0.0; 3]
    } else if prim < triangles.len() {
        let t = &triangles[prim];
        let v0 = Vec3::from(t.v0);
        (Vec3::from(t.v1) - v0)
            .cross(Vec3::from(t.v2) - v0)
            .to_array()
    } else {
        let sphere = &scene.spheres[prim - triangles.len()];
        // `ray` is in world coordinates, the sphere relative to the offset.
        let origin = (Vec3::from(ray.origin).as_dvec3() - scene.offset).as_vec3();
        let point = origin + hit.t * Vec3::from(ray.dir);
        (point - Vec3::from(sphere.center)).to_array()
    }
}

/// Asks the CPU to fetch the triangles `hits` name before `hit_normal`
/// reads them: the kernel reads its own copy of the triangles (the BVH's
/// blocks), so these are cold, and one at a time each is a trip to memory
/// (incoherent rays through the dragon: 40–70 ms a million hits; fetched
/// together, their latencies overlap).
#[inline]
pub fn prefetch_hit_triangles(scene: &Scene, hits: &[Hit]) {
    #[cfg(target_arch = "x86_64")]
    for hit in hits {
        if let Some(t) = scene.triangles.get(hit.prim as usize) {
            // SAFETY: a prefetch is a hint; it cannot fault.
            unsafe {
                use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
                _mm_prefetch::<_MM_HINT_T0>((t as *const crate::layout::Triangle).cast());
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (scene, hits);
}
