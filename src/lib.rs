//! # plenoptic
//!
//! An embeddable streaming walk-through runtime. A scene author bakes an animated glTF scene
//! offline into a *radiance pack*; a Bevy app adds [`bevy_plenoptic::PlenopticPlugin`] and gets
//! globally illuminated frames for any camera position inside the baked view space at any
//! time of the animation.
//!
//! This facade re-exports the workspace crates:
//!
//! | crate | holds |
//! |---|---|
//! | [`pack`] | the radiance pack file format |
//! | [`scene`] | the scene model, glTF import, animation, bake recipes |
//! | [`trace`] | BVHs, cameras, id-images, the multi-stage and reference renderers |
//! | [`recon`] | the runtime core of reconstruction (CPU), shared with the plugin |
//! | [`eval`] | offline evaluation: render / compare tools, metrics, frame files, plots |
//! | [`bake`] | the baker and the `plenoptic` command |
//! | [`bevy`] | the Bevy plugin |

#[cfg(feature = "bevy")]
pub use bevy_plenoptic as bevy;
pub use plenoptic_bake as bake;
pub use plenoptic_eval as eval;
pub use plenoptic_pack as pack;
pub use plenoptic_recon as recon;
pub use plenoptic_scene as scene;
pub use plenoptic_trace as trace;
