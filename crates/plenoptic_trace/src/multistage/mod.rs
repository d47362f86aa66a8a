//! Multi-stage rendering (Nimeroff 1997, chapter 5, figure 5.1): indirect diffuse light comes
//! from a precomputed, view-independent [`AmbientField`]; direct light and specular light are
//! ray traced per sample by the [`MultiStageRenderer`].

mod ambient;
mod renderer;

pub use ambient::{AmbientField, AmbientSettings, FieldLayout};
pub use renderer::{MultiStageRenderer, MultiStageSettings};
