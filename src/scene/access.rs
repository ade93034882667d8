//! What the library's users read of a scene (its fields are the crate's:
//! the backends read them directly), and the few edits they make: its
//! default view, and geometry built by hand (probes, tests), after which
//! `rebuild_bvh`.

use std::path::PathBuf;

use glam::DVec3;

use super::Scene;
use crate::bvh::Bvh;
use crate::camera::View;
use crate::camera::navigate::Reach;
use crate::layout::{
    Light, Material, Sphere, Triangle, TriangleAttributes, TriangleNormals, TriangleTangents,
};
use crate::texture::TextureStore;

impl Scene {
    /// The view the scene's file asks for (its camera, spp and seed): the
    /// front ends' default, which they override in a `RenderSettings`.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The default view, to change (a scene framed or resized by its
    /// maker, not a render's setting: those are `RenderSettings`).
    pub fn view_mut(&mut self) -> &mut View {
        &mut self.view
    }

    /// Whether the file set `render.spp` rather than leaving it 1: the
    /// viewer refines to it only then.
    pub fn spp_given(&self) -> bool {
        self.spp_given
    }

    pub fn background(&self) -> [f32; 3] {
        self.background
    }

    /// The ambient light the scene renders with (`RenderSettings::ambient`).
    pub fn ambient(&self) -> [f32; 3] {
        self.ambient
    }

    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// One entry per triangle when any mesh is smooth, else empty.
    pub fn normals(&self) -> &[TriangleNormals] {
        &self.normals
    }

    /// One entry per triangle when any mesh has vertex colours or texture
    /// coordinates, else empty.
    pub fn attributes(&self) -> &[TriangleAttributes] {
        &self.attributes
    }

    /// One entry per triangle when any material has a normal texture, else
    /// empty.
    pub fn tangents(&self) -> &[TriangleTangents] {
        &self.tangents
    }

    /// Triangles whose file gave them vertex colours (for `lambert info`).
    pub fn colored_triangles(&self) -> usize {
        self.colored_triangles
    }

    pub fn spheres(&self) -> &[Sphere] {
        &self.spheres
    }

    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Every texture the materials use, as both paths read it.
    pub fn textures(&self) -> &TextureStore {
        &self.textures
    }

    /// Over all primitives (`rebuild_bvh` after the geometry changes).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Puts in another tree over the same primitives (the benchmarks'
    /// builders), returning the one it replaces.
    pub fn replace_bvh(&mut self, bvh: Bvh) -> Bvh {
        std::mem::replace(&mut self.bvh, bvh)
    }

    /// Where a viewer's camera may go in this scene: about its offset, as
    /// far as its geometry's size (the view's distance where it has none).
    pub fn reach(&self) -> Reach {
        let camera = &self.view.camera;
        let size = self.bvh.bounds().map_or_else(
            || (DVec3::from(camera.eye) - DVec3::from(camera.look_at)).length(),
            |b| (b.max - b.min).as_dvec3().length(),
        );
        Reach::new(self.offset, size)
    }

    /// What loading read but ignored or could not find (each names its
    /// file); the front ends print them.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Every file loading read or looked for (`check_output` refuses them
    /// as outputs).
    pub fn inputs(&self) -> &[PathBuf] {
        &self.inputs
    }

    /// World position (f64) of the origin of the f32 geometry, lights and
    /// camera the kernels see.
    pub fn offset(&self) -> DVec3 {
        self.offset
    }

    /// Adds `triangles` (flat shaded, with no vertex attributes: their
    /// entries in `normals` and `attributes`, where those are kept, are
    /// zero); `rebuild_bvh` after.
    pub fn add_triangles(&mut self, triangles: impl IntoIterator<Item = Triangle>) {
        self.forget_emitters();
        self.triangles.extend(triangles);
        let n = self.triangles.len();
        if !self.normals.is_empty() {
            self.normals.resize(n, TriangleNormals::default());
        }
        if !self.attributes.is_empty() {
            self.attributes.resize(n, TriangleAttributes::default());
        }
        if !self.tangents.is_empty() {
            self.tangents.resize(n, TriangleTangents::default());
        }
    }

    /// The triangles, to edit by hand; `rebuild_bvh` after.
    pub fn triangles_mut(&mut self) -> &mut Vec<Triangle> {
        self.forget_emitters();
        &mut self.triangles
    }

    /// The spheres, to edit by hand; `rebuild_bvh` after.
    pub fn spheres_mut(&mut self) -> &mut Vec<Sphere> {
        self.forget_emitters();
        &mut self.spheres
    }

    /// The lights, to edit or add to: they are the scene's own from then
    /// on, which no integrator drops or gives back (`with_settings`).
    pub fn lights_mut(&mut self) -> &mut Vec<Light> {
        self.forget_emitters();
        self.default_light = false;
        self.dropped_default_light.clear();
        &mut self.lights
    }

    /// The materials, to edit by hand (a texture given to one, say).
    pub fn materials_mut(&mut self) -> &mut Vec<Material> {
        self.forget_emitters();
        &mut self.materials
    }

    /// The textures, to replace by hand, with `attributes_mut` for the
    /// texture coordinates that read them.
    pub fn textures_mut(&mut self) -> &mut TextureStore {
        self.forget_emitters();
        &mut self.textures
    }

    /// The per-triangle attributes (one per triangle, or none), to edit by
    /// hand.
    pub fn attributes_mut(&mut self) -> &mut Vec<TriangleAttributes> {
        &mut self.attributes
    }
}
