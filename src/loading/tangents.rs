//! Tangent frames for normal maps where a file gives none: MikkTSpace's
//! (the `bevy_mikktspace` crate, byte-identical to the reference C code),
//! which glTF's specification asks for and which Blender, Substance and
//! xNormal bake normal maps against, so that a baked map reads back as it
//! was baked. Per triangle corner: the tangent (xyz, towards increasing u)
//! and the bitangent's sign (w), glTF TANGENT's convention: bitangent =
//! w · normal × tangent, pointing up the image (towards decreasing v in
//! glTF's texture coordinates).

use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::DVec3;

/// What a corner gets where MikkTSpace finds no frame (a degenerate face
/// with no neighbour to borrow one from): +X, right-handed. Shading
/// orthogonalises it against the normal, or keeps the normal unperturbed
/// where it is parallel.
const NO_FRAME: [f32; 4] = [1.0, 0.0, 0.0, 1.0];

/// The faces as MikkTSpace reads them, and the frames it writes back.
struct Faces<'a> {
    positions: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    normals: Option<&'a [[DVec3; 3]]>,
    uvs: &'a [[[f32; 2]; 3]],
    tangents: Vec<[[f32; 4]; 3]>,
}

impl Faces<'_> {
    fn corner(&self, face: usize, vert: usize) -> DVec3 {
        self.positions[self.triangles[face][vert] as usize]
    }
}

impl Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.corner(face, vert).as_vec3().to_array()
    }

    /// The corner's shading normal, or the face's where the mesh is flat.
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let n = match self.normals {
            Some(normals) => normals[face][vert],
            None => (self.corner(face, 1) - self.corner(face, 0))
                .cross(self.corner(face, 2) - self.corner(face, 0)),
        };
        n.normalize_or_zero().as_vec3().to_array()
    }

    /// MikkTSpace's coordinates run up the image (OpenGL's and Blender's),
    /// glTF's down it: v flipped, so that the sign it gives is glTF's.
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let [u, v] = self.uvs[face][vert];
        [u, 1.0 - v]
    }

    fn set_tangent(&mut self, frame: Option<TangentSpace>, face: usize, vert: usize) {
        self.tangents[face][vert] = frame.map_or(NO_FRAME, |f| f.tangent_encoded());
    }
}

/// MikkTSpace tangents of `triangles` (indices into `positions`) with
/// their corners' shading normals (the face's where None) and texture
/// coordinates (glTF's convention), per triangle corner.
pub fn generate(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    normals: Option<&[[DVec3; 3]]>,
    uvs: &[[[f32; 2]; 3]],
) -> Vec<[[f32; 4]; 3]> {
    let mut faces = Faces {
        positions,
        triangles,
        normals,
        uvs,
        tangents: vec![[NO_FRAME; 3]; triangles.len()],
    };
    // Its error type has no variants (yet): it cannot fail. Were one added,
    // the corners it could not reach would keep NO_FRAME.
    let _ = generate_tangents(&mut faces);
    faces.tangents
}
