//! The plugin's settings and the names every layer shares: the global
//! [`PlenopticSettings`], the [`Backend`] and the one in use ([`ResolvedBackend`]), the system
//! sets apps and features order against ([`PlenopticSystems`]) and the events the plugin sends
//! ([`PlenopticEvent`]). The lowest layer (`docs/architecture.md`, "The plugin's layers"):
//! it imports nothing of the plugin.

use bevy::prelude::*;

/// Global settings of the plugin.
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct PlenopticSettings {
    /// Upper bound, in bytes, on decoded pack data kept resident (including reads in flight).
    /// Larger budgets keep more base views and time keys around the camera and stall less.
    pub memory_budget_bytes: u64,
    /// How far ahead, in seconds, to prefetch along the camera's velocity and the playback
    /// direction. Longer hides more latency but spends budget on data that may not be used.
    pub prefetch_seconds: f32,
    /// Where frames are reconstructed. Read when a pack's proxy geometry is first shown.
    pub backend: Backend,
    /// The first render layer given to plenoptic cameras: each camera draws its own proxy
    /// geometry on a layer of its own, with a shadow-only layer above it, the lowest free pair
    /// from here up ([`crate::camera::layers`]). Choose it above the layers the app uses itself.
    pub first_render_layer: usize,
    /// Light the app's own meshes with the pack: each plenoptic camera without an
    /// environment light of its own gets one made from the pack's radiance around it at its
    /// time ([`crate::lit`]).
    pub environment_light: bool,
    /// Count what the GPU reconstruction's shaders do per pixel (lookups, loads, samples,
    /// steps, fallbacks) into each camera's [`crate::reconstruct::counters::CostReport`].
    /// A diagnostic: the shaders are compiled with the counting in, and each frame's counts
    /// are read back. Read when a camera's proxies get their materials.
    pub cost_counters: bool,
    /// Fill the holes of the geometry-assisted reconstruction with a compute pass over the
    /// opaque pass's output ([`crate::reconstruct::geometry::screen_fill`]) on every camera
    /// that can take it (on Vulkan or GL, HDR or not), instead of in the fragment shader,
    /// which reconstructs each ring pixel again. The same frame, for a fraction of the loads;
    /// off only to compare the two.
    pub screen_fill: bool,
    /// On cameras with the screen fill, make the opaque pixels' lookups in a compute pass
    /// over the fragments' records ([`crate::reconstruct::geometry::lookup_kernel`]) instead
    /// of in the fragment shader. The same frame; with [`ReconSettings::sparse_lighting`] a
    /// material's lighting is looked up at a quarter of the pixels, as on the CPU. Off by
    /// default: on lavapipe it takes longer (`docs/results/measurements.md`, "The plugin's
    /// work per pixel"); whether a GPU's fragment occupancy repays that is for its timings to
    /// say.
    ///
    /// [`ReconSettings::sparse_lighting`]: plenoptic_recon::ReconSettings::sparse_lighting
    pub lookup_kernel: bool,
}

/// Where frames are reconstructed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// The WGSL material on the proxy meshes (per-fragment lookups; cost scales with the
    /// covered pixels × base views × 2 keys, more where the volume fallback or the hole fill
    /// runs). Image mode runs as compute passes ([`crate::reconstruct::image`]: splats of the
    /// weighted views' cube texels, view blend, background fill) shown through the proxies
    /// and the background. Volume mode ([`crate::reconstruct::image::volume`]) interpolates each
    /// weighted view's cube at t from its resident temporal-volume blocks on the CPU (off
    /// the main thread, when the time or views change) and warps those cubes with the same
    /// passes. Every camera in image or volume mode has its own passes and frame; until its
    /// volume cubes exist a volume-mode camera is shown geometry-assisted.
    Gpu,
    /// `plenoptic_recon`'s CPU reconstructor on a worker thread, its frame shown through the
    /// proxy meshes (screen-space texture; depth still from the rasterised proxies). Far
    /// slower; a frame lags the camera while it is computed. The reference to compare with.
    Cpu,
    /// The GPU unless the device lacks what it needs (then the CPU, with a warning).
    #[default]
    Auto,
}

impl Default for PlenopticSettings {
    fn default() -> Self {
        Self {
            memory_budget_bytes: 256 * 1024 * 1024,
            prefetch_seconds: 0.5,
            backend: Backend::Auto,
            first_render_layer: 16,
            environment_light: true,
            cost_counters: false,
            screen_fill: true,
            lookup_kernel: false,
        }
    }
}

/// The system sets plenoptic runs in `Update`, in this order. Order your own systems
/// against them, e.g. set the playback time `.before(PlenopticSystems::Playback)`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlenopticSystems {
    /// Advances or applies the playback time of each plenoptic camera and places the proxy
    /// geometry.
    Playback,
    /// Decides the working set and issues reads and decodes off the main thread.
    Streaming,
}

/// Something that went wrong while streaming; the app keeps running.
#[derive(Message, Debug, Clone, PartialEq)]
pub enum PlenopticEvent {
    /// A chunk could not be read or decoded (checksum mismatch, truncated file, bad KTX2).
    ChunkFailed {
        /// The chunk (kind, base view, key).
        chunk: String,
        /// Why.
        reason: String,
    },
}

/// Whether the device supports the GPU reconstruction (decided in `Plugin::finish`).
#[derive(Resource, Debug, Clone, Copy)]
pub struct GpuSupport(pub bool);

/// The backend in use: [`PlenopticSettings::backend`] with `Auto` resolved.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ResolvedBackend(pub Backend);

pub(crate) fn resolve_backend(
    settings: Res<PlenopticSettings>,
    support: Option<Res<GpuSupport>>,
    mut resolved: ResMut<ResolvedBackend>,
) {
    let gpu = support.is_some_and(|s| s.0);
    let b = match settings.backend {
        Backend::Auto if gpu => Backend::Gpu,
        Backend::Auto => Backend::Cpu,
        b => b,
    };
    if resolved.0 != b {
        resolved.0 = b;
    }
}
