//! Textures: the images a model names, decoded (PNG, JPEG), given mip
//! chains, and packed with the materials' uses of them into one array of
//! 32-bit words that both paths read (the GPU as one storage buffer, the
//! CPU twin, src/cpu/texture.rs, as a slice). docs/textures.md describes
//! the layout, the filtering and the level of detail.

mod decode;
mod lod;
mod model;
mod store;

pub use decode::{DecodedImage, MAX_IMAGE_BYTES, MAX_TEXTURE_SIDE, decode_image};
pub use lod::cone_spread;
pub use model::{ImageReport, MaterialSlots, add_model_textures, describe_images};
pub use store::{
    Encoding, LINEAR_ONE, SLOT_WORDS, SRGB_TABLE_WORDS, StoredImage, TextureLevel, TextureSlot,
    TextureStore, linear_from_srgb, mip_chain,
};
