//! glTF files for the materials and lights tests (issue 46), made in
//! code: a GLB builder (views, accessors, embedded PNGs) and the quads
//! they put under a material or a light.

use serde_json::{Value, json};

use super::data::glb;

/// A GLB under construction: its binary chunk, buffer views and accessors.
#[derive(Default)]
pub struct Glb {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Glb {
    /// A buffer view of `bytes`, on a 4-byte boundary as the spec asks.
    fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().div_ceil(4) * 4, 0);
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend(bytes);
        self.views.len() - 1
    }

    /// An accessor of f32 `values`, `kind` ("SCALAR", "VEC2", …) each, with
    /// the min and max the spec asks of POSITION.
    pub fn floats(&mut self, values: &[f32], kind: &str) -> usize {
        let width = match kind {
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
        let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let column = |c: usize| values.iter().skip(c).step_by(width).copied();
        let min: Vec<f32> = (0..width)
            .map(|c| column(c).fold(f32::INFINITY, f32::min))
            .collect();
        let max: Vec<f32> = (0..width)
            .map(|c| column(c).fold(f32::NEG_INFINITY, f32::max))
            .collect();
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5126,
            "count": values.len() / width, "type": kind, "min": min, "max": max}));
        self.accessors.len() - 1
    }

    /// An accessor of u16 triangle indices.
    pub fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5123,
            "count": indices.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// An embedded 4×4 PNG of one RGBA colour, as a glTF image entry.
    pub fn png(&mut self, rgba: [u8; 4]) -> Value {
        let bytes = super::png_bytes(4, rgba);
        json!({"bufferView": self.view(&bytes), "mimeType": "image/png"})
    }

    /// The file: `json` (scenes, nodes, meshes, materials…) with the views
    /// and accessors made.
    pub fn finish(self, mut json: Value) -> Vec<u8> {
        json["asset"] = json!({"version": "2.0"});
        json["bufferViews"] = self.views.into();
        json["accessors"] = self.accessors.into();
        glb(json, &self.bin)
    }
}

/// glTF texture coordinates of a quad's corners (bottom left, bottom
/// right, top right, top left) laid out as an image on it: u along +x, v
/// down the image (−y).
pub const UPRIGHT_UVS: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];

/// The quad (−1, −1, 0) … (1, 1, 0) facing +z (triangles (0, 1, 2) and
/// (0, 2, 3)), NORMAL +z, texture coordinates `uvs` at its corners and
/// TANGENT `tangent` at each where given: a primitive of material 0.
pub fn quad_primitive(glb: &mut Glb, uvs: [[f32; 2]; 4], tangent: Option<[f32; 4]>) -> Value {
    let corners = [-1., -1., 0., 1., -1., 0., 1., 1., 0., -1., 1., 0.];
    let mut attributes = json!({
        "POSITION": glb.floats(&corners, "VEC3"),
        "NORMAL": glb.floats(&[0., 0., 1.].repeat(4), "VEC3"),
        "TEXCOORD_0": glb.floats(&uvs.concat(), "VEC2"),
    });
    if let Some(t) = tangent {
        attributes["TANGENT"] = glb.floats(&t.repeat(4), "VEC4").into();
    }
    json!({"attributes": attributes, "indices": glb.indices(&[0, 1, 2, 0, 2, 3]), "material": 0})
}

/// A GLB of one node holding `primitive`, with `material` and `images`
/// (texture i reads image i).
pub fn one_primitive_glb(
    glb: Glb,
    primitive: Value,
    material: Value,
    images: Vec<Value>,
    extensions: &[&str],
) -> Vec<u8> {
    let textures: Vec<Value> = (0..images.len()).map(|i| json!({"source": i})).collect();
    glb.finish(json!({
        "extensionsUsed": extensions,
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [primitive]}],
        "materials": [material],
        "textures": textures,
        "images": images,
    }))
}
