//! PLY colours (`red green blue [alpha]` of vertices or faces) and texture
//! coordinates (`u v`, `s t`, `texture_u texture_v`, a face `texcoord`
//! list): which properties hold them, and their values.

use super::{Element, Scalar};
use crate::loading::srgb_to_linear;

/// The colour and texture coordinate properties a file has: their slots
/// among their element's properties, and each colour channel's type.
#[derive(Default)]
pub(super) struct Attributes {
    /// red, green, blue and (optionally) alpha of a vertex.
    pub(super) vertex_colors: Option<ColourSlots>,
    /// Of a face, used where the vertices have none.
    pub(super) face_colors: Option<ColourSlots>,
    /// `u v`, `s t` or `texture_u texture_v` of a vertex.
    pub(super) vertex_uvs: Option<[usize; 2]>,
    /// A face's `texcoord` list (u v per corner).
    pub(super) face_uvs: Option<usize>,
}

/// Slot and type of each colour channel (alpha optional).
pub(super) type ColourSlots = [Option<(usize, Scalar)>; 4];

/// The names of colour channels and texture coordinates lambert reads.
pub(super) const COLOUR_NAMES: [&str; 4] = ["red", "green", "blue", "alpha"];
const UV_NAMES: [[&str; 2]; 3] = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]];

impl Attributes {
    /// What `elements` hold; an error where a colour or texture coordinate
    /// property has a type lambert cannot read as one.
    pub(super) fn of(
        elements: &[Element],
        vertex: usize,
        face: Option<usize>,
    ) -> Result<Attributes, String> {
        let colours = |element: &Element| -> Result<Option<ColourSlots>, String> {
            let mut slots: ColourSlots = [None; 4];
            for (k, name) in COLOUR_NAMES.iter().enumerate() {
                if let Some(p) = element.property(name) {
                    let property = &element.properties[p];
                    if property.count.is_some()
                        || !matches!(
                            property.value,
                            Scalar::U8 | Scalar::U16 | Scalar::F32 | Scalar::F64
                        )
                    {
                        return Err(format!(
                            "{} property '{name}' is {}; colours are uchar, ushort, float or \
                             double",
                            element.name,
                            if property.count.is_some() {
                                "a list".to_string()
                            } else {
                                format!("{:?}", property.value).to_lowercase()
                            }
                        ));
                    }
                    slots[k] = Some((p, property.value));
                }
            }
            Ok(slots[..3].iter().all(Option::is_some).then_some(slots))
        };
        let vertex_element = &elements[vertex];
        let mut attributes = Attributes {
            vertex_colors: colours(vertex_element)?,
            ..Attributes::default()
        };
        for [u, v] in UV_NAMES {
            if let (Some(a), Some(b)) = (vertex_element.property(u), vertex_element.property(v)) {
                if [a, b]
                    .iter()
                    .any(|&p| vertex_element.properties[p].count.is_some())
                {
                    return Err(format!("vertex property '{u}' or '{v}' is a list"));
                }
                attributes.vertex_uvs = Some([a, b]);
                break;
            }
        }
        if let Some(f) = face {
            let element = &elements[f];
            attributes.face_colors = colours(element)?;
            if let Some(p) = element.property("texcoord") {
                if element.properties[p].count.is_none() {
                    return Err("face property 'texcoord' must be a list (u v per corner)".into());
                }
                attributes.face_uvs = Some(p);
            }
        }
        Ok(attributes)
    }
}

/// A colour read from its channels' values: integers sRGB-encoded (of
/// their type's range; alpha linear), floats linear; alpha 1 when absent.
pub(super) fn colour(slots: &ColourSlots, values: &[f64]) -> [f32; 4] {
    let mut c = [1.0f32; 4];
    for (k, slot) in slots.iter().enumerate() {
        let Some((p, kind)) = *slot else { continue };
        let x = values[p];
        c[k] = match kind {
            Scalar::U8 | Scalar::U16 => {
                let max = if kind == Scalar::U8 { 255.0 } else { 65535.0 };
                let encoded = (x / max) as f32;
                if k == 3 {
                    encoded
                } else {
                    srgb_to_linear(encoded)
                }
            }
            _ => x as f32,
        };
    }
    c
}
