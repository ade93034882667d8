//! Generalized winding numbers, the twin of shaders/winding.wgsl: the
//! solid angle of a triangle (Van Oosterom and Strackee), with an
//! arctangent of plain arithmetic (`approx_atan2`, src/cpu/math.rs, so
//! that both paths give the same bits where a library's `atan2` would
//! not), the far field of a winding-tree node (its dipole, first order)
//! and the walk of the tree (`winding_number`), which sums in one fixed
//! order on both paths, with its rounding errors carried (`winding_sum`).
//!
//! Written once for both precisions: `kernel!` (kernel.rs) expands it
//! into `cpu::f32` and `cpu::f64`, whose `Real` and vector types it takes;
//! its items here are the single-precision ones; the macro is in
//! stage.rs.

pub(super) mod stage;

pub use super::f32::{
    WINDING_BETA, WINDING_STACK, dipole_winding, triangle_winding, triangle_winding4,
    winding_number, winding_sum,
};
