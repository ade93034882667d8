//! What a render may set apart from the scene it renders: its view (size,
//! camera, spp, seed), shadows, ambient light, the acceleration, the
//! ray/triangle test and the integrator. A scene file's `[camera]` and `[render]` tables are
//! the scene's defaults (`Scene::default_settings`); the front ends
//! override fields of a copy and hand it to the jobs.

use serde::{Deserialize, Serialize};

use super::{Accel, Intersect, Scene};
use crate::camera::View;

/// `--integrator`: how light reaches the camera (docs/rendering.md). The
/// default everywhere, model files included, is `Direct`: today's pictures
/// and speed stay what they were, and `Path` is asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// The lecture's: ambient·k + Σ k·I·(n·l) over the point, directional
    /// and spot lights, with shadow rays; emission is seen, lighting
    /// nothing.
    #[default]
    Direct,
    /// Unidirectional path tracing: next-event estimation with multiple
    /// importance sampling (power heuristic), physically based materials,
    /// emissive triangles as area lights and the environment.
    Path,
}

impl Integrator {
    pub const ALL: [Integrator; 2] = [Integrator::Direct, Integrator::Path];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::Direct => "direct",
            Integrator::Path => "path",
        }
    }
}

/// Bounces a path takes at most unless `--max-depth` says otherwise: the
/// camera ray's hit and 7 more (pbrt-v4's and Mitsuba 3's scenes commonly
/// use 5 to 8).
pub const DEFAULT_MAX_DEPTH: u32 = 8;

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
    pub integrator: Integrator,
    /// Under `Integrator::Path`: the most surfaces a path hits (1: direct
    /// light alone).
    pub max_depth: u32,
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
            integrator: self.integrator,
            max_depth: self.max_depth,
        }
    }

    /// Whether the path integrator, which this scene is set to, drops its
    /// default light: a model lit by its own emissive surfaces or by an
    /// environment is lit by them alone (the default light and ambient
    /// are for a model with no light at all, which `direct` shows).
    pub fn default_light_goes(&self) -> bool {
        self.integrator == Integrator::Path
            && self.default_light
            && (self.environment().is_some()
                || self
                    .emitters()
                    .entries
                    .iter()
                    .any(|e| e.kind == crate::layout::EMITTER_TRIANGLE))
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
        self.integrator = settings.integrator;
        self.max_depth = settings.max_depth;
        if self.default_light_goes() {
            self.lights.clear();
            self.default_light = false;
            self.forget_emitters();
        }
        self
    }
}
