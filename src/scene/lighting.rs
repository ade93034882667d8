//! A scene's lights as the path integrator reads them: its environment
//! (the TOML `[environment]` table, or `--environment`), and its emitters'
//! table, built on first use from the geometry, materials, lights and
//! environment and forgotten whenever one of them is edited.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;

use super::{Rgb, Scene, colour};
use crate::error::{Error, Result};
use crate::lighting::{
    EmitterTable, Environment, EnvironmentSource, EnvironmentSpec, SceneLights, emitter_table,
};

/// The `[environment]` table: `color` or `image` (relative to the scene
/// file), `strength`, `rotation_deg`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EnvironmentEntry {
    #[serde(default)]
    color: Option<Rgb>,
    #[serde(default)]
    image: Option<PathBuf>,
    #[serde(default = "one")]
    strength: f64,
    #[serde(default)]
    rotation_deg: f64,
}

fn one() -> f64 {
    1.0
}

impl EnvironmentEntry {
    /// The spec the table gives, an image's path taken relative to `base`
    /// (the scene file's folder).
    pub(super) fn spec(&self, base: &Path) -> Result<EnvironmentSpec, String> {
        let source = match (&self.color, &self.image) {
            (Some(c), None) => EnvironmentSource::Color(colour("environment.color", *c)?),
            (None, Some(image)) => EnvironmentSource::Image(base.join(image)),
            (Some(_), Some(_)) => {
                return Err("[environment] gives both color and image; give one".into());
            }
            (None, None) => {
                return Err("[environment] needs color = [r, g, b] or image = \"file\"".into());
            }
        };
        EnvironmentSpec::new(source, self.strength, self.rotation_deg, |key| {
            format!("environment.{key}")
        })
    }
}

impl Scene {
    /// The emitters' table (built on first use; docs/rendering.md,
    /// "Lights").
    pub fn emitters(&self) -> &EmitterTable {
        self.emitters.get_or_init(|| {
            let radius = self.bvh.bounds().map_or(0.0, |b| {
                0.5 * (b.max.as_dvec3() - b.min.as_dvec3()).length()
            });
            emitter_table(&SceneLights {
                triangles: &self.triangles,
                materials: &self.materials,
                textures: &self.textures,
                lights: &self.lights,
                environment: self.environment.as_deref(),
                radius,
            })
        })
    }

    /// The environment, where the scene has one.
    pub fn environment(&self) -> Option<&Environment> {
        self.environment.as_deref()
    }

    /// Lights the scene with `spec`'s environment (none: with none),
    /// replacing its own: its map is read now, and becomes one of the
    /// scene's inputs, which no output may replace.
    pub fn set_environment(&mut self, spec: Option<&EnvironmentSpec>) -> Result<()> {
        let environment = spec.map(Environment::load).transpose()?;
        if let Some(file) = environment.as_ref().and_then(Environment::file) {
            self.inputs.push(file.to_path_buf());
        }
        self.environment = environment.map(Arc::new);
        self.forget_emitters();
        Ok(())
    }

    /// What the direct integrator leaves out of this scene, in words for a
    /// warning: its environment, which only the path integrator samples
    /// (a miss shows `render.background` under `direct`).
    pub fn ignored_by_direct(&self) -> Option<String> {
        self.environment().map(|e| {
            format!(
                "{} lights only the path integrator; the direct integrator ignores it",
                e.spec.describe()
            )
        })
    }

    /// Drops the emitters' table after an edit it depends on.
    pub(super) fn forget_emitters(&mut self) {
        self.emitters = Default::default();
    }
}

/// `--environment`'s spec: `R,G,B` (or one value, grey) is a colour,
/// anything else a file, read from where the command runs.
pub fn environment_option(text: &str, strength: f64, rotation_deg: f64) -> Result<EnvironmentSpec> {
    let values: Option<Vec<f64>> = text.split(',').map(|v| v.trim().parse().ok()).collect();
    let source = match values.as_deref() {
        Some(&[v]) => EnvironmentSource::Color([v as f32; 3]),
        Some(&[r, g, b]) => EnvironmentSource::Color([r as f32, g as f32, b as f32]),
        _ => EnvironmentSource::Image(PathBuf::from(text)),
    };
    EnvironmentSpec::new(source, strength, rotation_deg, |key| {
        match key {
            "strength" => "--environment-strength",
            "rotation_deg" => "--environment-rotation",
            _ => "--environment",
        }
        .to_string()
    })
    .map_err(Error::Usage)
}
