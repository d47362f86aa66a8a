//! Streaming: keeps each camera's working set of cubes resident inside the memory budget.
//!
//! Every frame, per [`PlenopticCamera`]: the working set ([`schedule::working_set`]) is the
//! base views the reconstruction blends (the view-space weights,
//! [`plenoptic_recon::ReconSettings::view_weights`]) × the time keys bracketing t (in image mode the up to four keys
//! of its Bézier segment) ("needed"), plus the same around where
//! the camera and the playback will be [`PlenopticSettings::prefetch_seconds`] from now
//! ("prefetch"). Missing keys are read and decoded (checksum, zstd, KTX2 → GPU-ready texel
//! bytes; on the CPU backend, the cubes `plenoptic_recon` looks up, which its reconstructor
//! then takes from here instead of reading the pack, [`decode_cpu_key`]) on the
//! [`IoTaskPool`](bevy::tasks::IoTaskPool) (not the async compute pool, where Bevy compiles pipelines:
//! on a slow driver those compiles would queue the reads behind them); the main thread never
//! waits on I/O. A key's bytes
//! are reserved against the budget *before* its read starts, from the directory's
//! uncompressed lengths, so resident + in-flight bytes never exceed
//! [`PlenopticSettings::memory_budget_bytes`]; to make room the least recently used keys
//! outside the current working set are evicted. While a needed key is missing the frame is
//! reconstructed from what is resident (a *stall* is counted).
//!
//! The temporal-volume blocks of the needed base views around t (the GPU reconstruction's
//! fallback, and the source of the GPU volume mode's cubes) are streamed the same way, inside the same budget and LRU, when the pack has them:
//! decoded and binned by direction ([`BinnedVolume`]) off the main thread.
//!
//! Each resident key sits in a fixed-size slot (`slot` < budget / key bytes): the index of its
//! layer range in the cube-array textures the GPU reconstruction samples.
//!
//! - [`schedule`]: the working set; `decode.rs`: reading and decoding a key or volume block;
//!   `cache.rs`: the [`StreamCache`], its slots and eviction; `tasks.rs`: the reads on the
//!   task pool and their collection; `diagnostics.rs`: the diagnostics and
//!   [`StreamingStats`]; `mod.rs`: the plugin and the per-frame scheduling of every camera.

mod cache;
mod decode;
mod diagnostics;
pub mod schedule;
mod tasks;

use bevy::diagnostic::{Diagnostic, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use plenoptic_pack::ChunkKind;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::settings::{PlenopticSettings, PlenopticSystems};
use cache::Wanted;
pub use cache::{Resident, ResidentVolume, StreamCache};
pub use decode::{
    BinnedVolume, DecodedKey, VOLUME_BIN_FACE, VOLUME_BIN_OFFSETS, VOLUME_SAMPLE_WORDS,
    cpu_key_bytes, decode_cpu_key, decode_key, decode_volume, key_bytes, volume_bytes,
};
pub use diagnostics::{DECODE_MS, HITS, MISSES, RESIDENT_BYTES, STALLS, StreamingStats};
use diagnostics::{Residency, report_residency};
use schedule::{BlockRef, Lookahead, working_set};
use tasks::{collect_finished, start_reads};

/// Adds the streaming scheduler and its diagnostics.
#[derive(Debug, Default)]
pub struct PlenopticStreamingPlugin;

impl Plugin for PlenopticStreamingPlugin {
    fn build(&self, app: &mut App) {
        for path in [RESIDENT_BYTES, HITS, MISSES, STALLS, DECODE_MS] {
            app.register_diagnostic(Diagnostic::new(path));
        }
        // The camera layer does not know streaming: its state is required from here.
        app.register_required_components::<PlenopticCamera, StreamState>();
        app.init_resource::<StreamCache>()
            .init_resource::<StreamingStats>()
            .add_systems(
                Update,
                (collect_finished, schedule_reads)
                    .chain()
                    .in_set(PlenopticSystems::Streaming),
            );
    }
}

/// Per-camera streaming state (required by [`PlenopticCamera`]).
#[derive(Component, Debug, Clone, Default)]
pub struct StreamState {
    /// Position last frame (for the velocity estimate).
    pub last_position: Option<Vec3>,
    /// This frame's working set.
    pub working_set: schedule::WorkingSet,
    /// Whether every needed key and volume block was resident this frame.
    pub complete: bool,
}

#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn schedule_reads(
    mut cache: ResMut<StreamCache>,
    mut stats: ResMut<StreamingStats>,
    settings: Res<PlenopticSettings>,
    backend: Option<Res<crate::settings::ResolvedBackend>>,
    packs: Res<Assets<RadiancePack>>,
    time: Res<Time>,
    mut cameras: Query<(&PlenopticCamera, &mut StreamState, &GlobalTransform)>,
    mut diagnostics: Diagnostics,
) {
    // The CPU backend's keys are decoded for plenoptic_recon, in the same budget.
    let cpu = backend.is_some_and(|b| b.0 == crate::settings::Backend::Cpu);
    cache.frame += 1;
    let budget = settings.memory_budget_bytes;
    let mut residency = Residency::default();
    let mut wanted: Vec<Wanted> = Vec::new();
    for (cam, mut state, transform) in &mut cameras {
        let Some(pack) = packs.get(&cam.pack) else {
            continue;
        };
        let set = camera_working_set(
            cam,
            &mut state,
            transform.translation(),
            time.delta_secs(),
            pack,
            &settings,
        );
        let complete = cache.touch_working_set(
            cam.pack.id(),
            &pack.reader,
            &set,
            &mut residency,
            &mut wanted,
        );
        residency.stalled |= !complete;
        state.complete = complete;
        state.working_set = set;
    }
    start_reads(&mut cache, &mut stats, wanted, cpu, budget);
    report_residency(&cache, &mut stats, &mut diagnostics, &residency, budget);
}

/// This frame's working set of camera `cam` at `position` (its velocity estimated from
/// `state`'s last position and the frame time `dt`): the bracketing keys, in image mode
/// every key of the Bézier segments, and only the volume blocks the pack has.
fn camera_working_set(
    cam: &PlenopticCamera,
    state: &mut StreamState,
    position: Vec3,
    dt: f32,
    pack: &RadiancePack,
    settings: &PlenopticSettings,
) -> schedule::WorkingSet {
    let velocity = match state.last_position {
        Some(p) if dt > 0.0 => (position - p) / dt,
        _ => Vec3::ZERO,
    };
    state.last_position = Some(position);
    let speed = match cam.playback {
        crate::camera::Playback::Clock { speed, .. } => speed,
        crate::camera::Playback::Manual => 0.0,
    };
    let mut set = working_set(
        pack.reader.manifest(),
        &pack.usable_views,
        position,
        velocity,
        cam.time,
        speed,
        Lookahead {
            settings: &cam.settings,
            seconds: settings.prefetch_seconds,
        },
    );
    if cam.mode == crate::camera::ReconMode::Image {
        need_bezier_keys(&mut set, pack, cam.time);
    }
    // Volume blocks are optional: only those the pack has.
    let has = |b: &BlockRef| pack.reader.find(ChunkKind::VolumeBlock, b.0, b.1).is_some();
    set.volumes.retain(has);
    set.volume_prefetch.retain(has);
    set
}

/// Image mode blends each view's keys with Bézier weights over up to four keys
/// (`plenoptic_recon::temporal::bezier_weights`), not just the bracketing two: those at
/// `time` become needed (and leave the prefetch list).
fn need_bezier_keys(set: &mut schedule::WorkingSet, pack: &RadiancePack, time: f32) {
    let m = pack.reader.manifest();
    let mut views: Vec<u32> = set.needed.iter().map(|k| k.0).collect();
    views.dedup();
    for v in views {
        let times = &m.base_views[v as usize].time_keys;
        for (k, _) in plenoptic_recon::temporal::bezier_weights(times, time) {
            let key = (v, k as u32);
            if !set.needed.contains(&key) {
                set.needed.push(key);
            }
            set.prefetch.retain(|p| *p != key);
        }
    }
}
