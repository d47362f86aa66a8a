//! # bevy_plenoptic
//!
//! The Bevy plugin of plenoptic: it streams a radiance pack and reconstructs globally
//! illuminated frames for the camera's position and the current time (thesis chapters 6–7
//! and 8.2.3; `design.md`, "The runtime plugin").
//!
//! At this stage the crate holds the plugin skeleton: [`PlenopticPlugin`] registers the
//! settings resource and the public [`PlenopticSystems`] set that later passes (streaming,
//! geometry mask, reconstruction) run in. The rendering path itself is proven by the crate's
//! headless tests, which render on Mesa's software Vulkan driver and read the pixels back.

use bevy::prelude::*;

/// Adds plenoptic's resources and system sets to an app.
#[derive(Debug, Default)]
pub struct PlenopticPlugin;

impl Plugin for PlenopticPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<PlenopticSettings>().configure_sets(
            Update,
            (PlenopticSystems::Playback, PlenopticSystems::Streaming).chain(),
        );
    }
}

/// Global settings of the plugin.
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct PlenopticSettings {
    /// Upper bound, in bytes, on decoded pack data kept resident (CPU and GPU together).
    /// Larger budgets keep more base views and time keys around the camera and stall less.
    pub memory_budget_bytes: u64,
}

impl Default for PlenopticSettings {
    fn default() -> Self {
        Self {
            memory_budget_bytes: 256 * 1024 * 1024,
        }
    }
}

/// The system sets plenoptic runs in `Update`, in this order. Order your own systems
/// against them, e.g. set the playback time `.before(PlenopticSystems::Playback)`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlenopticSystems {
    /// Advances or applies the playback time of each plenoptic camera.
    Playback,
    /// Decides the working set and issues reads and decodes off the main thread.
    Streaming,
}
