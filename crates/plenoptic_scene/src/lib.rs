//! # plenoptic_scene
//!
//! The scene model of plenoptic (being written): see [`model`] and [`anim`].

pub mod anim;
pub mod model;

pub use anim::{Interpolation, Key, Track, TrsTrack};
pub use model::*;
