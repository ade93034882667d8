//! What a render changes of a scene's own settings: the command line's
//! options and the Python package's keywords, applied by one rule, so
//! that both render the same image from the same choices.

use crate::camera::{Camera, validate_camera};
use crate::error::{Error, Result};
use crate::lighting::EnvironmentSpec;
use crate::limits::{validate_max_depth, validate_spp};
use crate::scene::{Accel, Integrator, Intersect, RenderSettings, Scene};

/// Settings over a scene's own; None keeps the scene's.
#[derive(Clone, Debug, Default)]
pub struct RenderOverrides {
    /// The image size; one side alone keeps the camera's aspect ratio.
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Another camera (its eye, look_at, up and vfov; its size is the
    /// view's, after `width` and `height`).
    pub camera: Option<Camera>,
    pub spp: Option<u32>,
    pub seed: Option<u32>,
    pub accel: Option<Accel>,
    pub intersect: Option<Intersect>,
    pub ambient: Option<[f32; 3]>,
    pub shadows: Option<bool>,
    pub integrator: Option<Integrator>,
    pub max_depth: Option<u32>,
    /// Replaces the scene's environment (scene content, read here).
    pub environment: Option<EnvironmentSpec>,
}

impl RenderOverrides {
    /// Applies the overrides to `scene` and its `settings`; `name` gives
    /// the caller's name of an option in errors (`--spp`, `spp`).
    pub fn apply(
        &self,
        scene: &mut Scene,
        settings: &mut RenderSettings,
        name: &dyn Fn(&str) -> String,
    ) -> Result<()> {
        self.apply_settings(scene, settings, name)?;
        if let Some(spec) = &self.environment {
            scene.set_environment(Some(spec))?;
        }
        Ok(())
    }

    /// `apply`'s changes to `settings`, all but the environment's (which
    /// changes the scene).
    pub fn apply_settings(
        &self,
        scene: &Scene,
        settings: &mut RenderSettings,
        name: &dyn Fn(&str) -> String,
    ) -> Result<()> {
        if let Some(accel) = self.accel {
            settings.accel = accel;
        }
        if let Some(intersect) = self.intersect {
            settings.intersect = intersect;
        }
        if let Some(spp) = self.spp {
            // validate_spp's message starts with the option's name.
            validate_spp(spp).map_err(|e| Error::Usage(name(&e)))?;
            settings.view.spp = spp;
        }
        if let Some(seed) = self.seed {
            settings.view.seed = seed;
        }
        if let Some(camera) = &self.camera {
            let (width, height) = (settings.view.camera.width, settings.view.camera.height);
            let camera = Camera {
                width,
                height,
                ..camera.clone()
            };
            validate_camera(&camera)
                .and_then(|()| scene.check_camera(&camera))
                .map_err(|e| Error::Usage(format!("{}: {e}", name("camera"))))?;
            settings.view.camera = camera;
        }
        settings.view.camera = settings
            .view
            .camera
            .resized(self.width, self.height)
            .map_err(|e| Error::Usage(format!("{}/{}: {e}", name("width"), name("height"))))?;
        if let Some(ambient) = self.ambient {
            settings.ambient = ambient;
        }
        if let Some(shadows) = self.shadows {
            settings.shadows = shadows;
        }
        if let Some(integrator) = self.integrator {
            settings.integrator = integrator;
        }
        if let Some(max_depth) = self.max_depth {
            validate_max_depth(max_depth).map_err(|e| Error::Usage(name(&e)))?;
            settings.max_depth = max_depth;
        }
        Ok(())
    }
}
