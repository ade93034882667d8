//! Generalized winding numbers, the twin of shaders/winding.wgsl: the
//! solid angle of a triangle (Van Oosterom and Strackee), with an
//! arctangent of plain arithmetic (`solid_atan2`, so that both paths give
//! the same bits where a library's `atan2` would not), the far field of a
//! winding-tree node (its dipole, first order) and the walk of the tree
//! (`winding_number`), which sums in one fixed order on both paths, with
//! its rounding errors carried (`winding_sum`).
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it
//! into `cpu::f32` and `cpu::f64`, whose `Real` and vector types it takes;
//! its items here are the single-precision ones; the macro is in
//! stage.rs.

pub(super) mod stage;

pub use super::f32::{
    WINDING_BETA, WINDING_STACK, atan_unit, dipole_winding, solid_atan2, triangle_winding,
    winding_number, winding_sum,
};
