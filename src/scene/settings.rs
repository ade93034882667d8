//! What a render may set apart from the scene it renders: its view (size,
//! camera, spp, seed), shadows, ambient light, the acceleration and the
//! ray/triangle test. A scene file's `[camera]` and `[render]` tables are
//! the scene's defaults (`Scene::default_settings`); the front ends
//! override fields of a copy and hand it to the jobs.

use super::{Accel, Intersect, Scene};
use crate::camera::View;

/// A render's settings (see the module's comment).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The camera (image size included), spp and seed.
    pub view: View,
    pub shadows: bool,
    pub ambient: [f32; 3],
    /// How rays find their hits; both paths follow it.
    pub accel: Accel,
    /// The ray/triangle test both paths use.
    pub intersect: Intersect,
}

impl Scene {
    /// The settings the scene's file asks for (a model's: its framed
    /// camera, shadows, the default ambient where it has no light).
    pub fn default_settings(&self) -> RenderSettings {
        RenderSettings {
            view: self.view.clone(),
            shadows: self.shadows,
            ambient: self.ambient,
            accel: self.accel,
            intersect: self.intersect,
        }
    }

    /// The scene as `settings` render it, its default view theirs: what
    /// the jobs open a renderer on (the backends read the settings with
    /// the geometry, and a GPU specialises its pipelines on them).
    pub fn with_settings(mut self, settings: &RenderSettings) -> Scene {
        self.view = settings.view.clone();
        self.shadows = settings.shadows;
        self.ambient = settings.ambient;
        self.accel = settings.accel;
        self.intersect = settings.intersect;
        self
    }
}
