//! MTL's specular terms as glTF's metallic-roughness BRDF, by Blender's
//! OBJ importer's rule (its obj_import_mtl.cc, the importer users compare
//! with), so that an OBJ renders in lambert's path tracer as it does in
//! Blender:
//!
//! - a material becomes metallic-roughness when it gives `Pr` or `Pm`
//!   (the PBR extension of MTL), or a `Ks` with a non-zero component; an
//!   MTL without them (or with `Ks 0 0 0`, no highlight) stays Lambert;
//! - roughness: `Pr` where given, else 1 − √(clamp(`Ns`, 0, 1000) / 1000)
//!   (Blender's map of the Phong exponent), else 1;
//! - metallic: `Pm` where given, else 0 (Blender takes `Ka`'s mean under
//!   `illum 3`; lambert reads neither, since exporters write `Ka 1 1 1`
//!   for materials that are not metal at all);
//! - `Ks`'s colour and magnitude are not modelled: glTF's dielectric
//!   reflects 4% at normal incidence (Blender's Principled specular 0.5).

use super::material::Brdf;

/// The specular statements one MTL material gave.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct MtlSpecular {
    pub ks: Option<[f32; 3]>,
    pub ns: Option<f32>,
    pub pr: Option<f32>,
    pub pm: Option<f32>,
}

impl MtlSpecular {
    /// The BRDF the rule above gives.
    pub fn brdf(&self) -> Brdf {
        let highlight = self.ks.is_some_and(|ks| ks.iter().any(|&c| c > 0.0));
        if !(highlight || self.pr.is_some() || self.pm.is_some()) {
            return Brdf::Lambert;
        }
        let from_exponent = |ns: f32| 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt();
        Brdf::MetallicRoughness {
            metallic: self.pm.unwrap_or(0.0),
            roughness: self
                .pr
                .unwrap_or_else(|| self.ns.map_or(1.0, from_exponent)),
        }
    }
}
