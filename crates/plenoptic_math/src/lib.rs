//! # plenoptic_math
//!
//! The formulas that both the path tracer (`plenoptic_trace`) and the runtime reconstruction
//! (`plenoptic_recon`) evaluate, written once so that the baked and the reconstructed
//! images agree by construction. It depends on glam only, so that the runtime does not
//! depend on the tracer.
//!
//! - [`optics`]: the glTF metallic-roughness model's scalar terms: the exact dielectric
//!   Fresnel, Schlick's Fresnel for metals, the GGX distribution and Smith masking.
//! - [`camera`]: the orientation of a camera looking from an eye at a target.
//!
//! The functions are small and sit in the per-pixel loops of both renderers: each is
//! `#[inline]`, so that it inlines across the crate boundary.

pub mod camera;
pub mod optics;

pub use camera::look_at_rotation;
