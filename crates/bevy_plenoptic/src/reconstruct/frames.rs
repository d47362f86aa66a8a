//! Per-view state the features share (`docs/architecture.md`, "The plugin's layers"): what a
//! camera's frame is drawn from this frame. The features that produce a frame write it (image
//! mode its [`ImageFrame`], the CPU backend its [`CpuFrameImage`], the geometry-assisted lookups
//! the camera's [`ViewDisplay`]); the features that show a frame (the proxies' materials, the
//! background, `lit/`) read it. No feature names another: they meet here.

use bevy::prelude::*;

/// The frame a camera's image-mode passes write (an `Rgba32Float` storage texture, resized
/// to the camera); every plenoptic camera on the GPU backend has one.
#[derive(Component, Debug, Clone)]
pub struct ImageFrame {
    /// The texture.
    pub image: Handle<Image>,
    /// Whether the passes write it this frame (image or volume mode with keys to warp), so
    /// that it is shown instead of the geometry-assisted lookups.
    pub active: bool,
}

/// The CPU backend's latest frame of a camera (linear radiance, screen space), once it has
/// one.
#[derive(Component, Debug, Clone)]
pub struct CpuFrameImage(pub Handle<Image>);

/// What a GPU camera shows this frame, for what is drawn behind or through its proxies.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ViewDisplay {
    /// First array layer of the heaviest lookup's key: the background's cube for packs
    /// without an environment.
    pub heaviest_layer: Option<u32>,
    /// Whether the image-mode frame is shown instead of the lookups.
    pub image_mode: bool,
}

/// A frame texture (an [`ImageFrame`] or a [`CpuFrameImage`]) was replaced or rewritten:
/// materials that bind it must prepare their bind group again (Bevy does not do this itself
/// for a material's handles).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameReplaced(pub AssetId<Image>);
