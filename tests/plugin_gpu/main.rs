//! The plugin's GPU tests on packs built through the tracer, in one test binary: each binary
//! links all of Bevy, and CI's disk and link time pay for every one (one binary instead of
//! three). They live in the facade package, not in bevy_plenoptic, so that the plugin needs
//! the tracer not even as a dev-dependency.
//!
//! - [`scene_render`]: the baked scene on screen, composited with Bevy meshes, streamed in
//!   a budget; GPU against CPU in every mode.
//! - [`pack_asset`]: the `RadiancePack` asset and its failures.
//! - [`sky`]: the sky, its ground and the glazing on the GPU.
//! - [`lit`]: the app's own meshes lit by the pack's radiance around the camera.
//! - [`own_scene`]: the tour's glb loaded by Bevy's glTF loader, lit by the pack.
//! - [`many_cameras`]: several plenoptic cameras in one app (two modes and times, a stereo
//!   pair, a runtime sun per camera), each equal to its CPU frame.
//! - [`per_view`]: a camera's lookups live in its view buffer; its materials are not
//!   rewritten from frame to frame.
//! - [`counters`]: the shaders' cost counters count what the frame did and change nothing.

#[path = "../../crates/bevy_plenoptic/tests/gpu/common/mod.rs"]
mod common;
/// The reconstruction crate's test pack builder (analytic scenes written with `PackWriter`),
/// shared so that the GPU is tested on the very packs the CPU reconstruction is.
#[path = "../../crates/plenoptic_recon/tests/common/mod.rs"]
mod pack;

mod counters;
mod harness;
mod light_groups;
mod lit;
mod many_cameras;
mod own_scene;
mod pack_asset;
mod per_view;
mod scene_render;
mod sky;
