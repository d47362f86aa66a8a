//! The streaming diagnostics: the paths of the per-frame measurements, the cumulative
//! counters ([`StreamingStats`]), and this frame's residency added to both.

use std::time::Duration;

use bevy::diagnostic::{DiagnosticPath, Diagnostics};
use bevy::prelude::*;

use super::StreamCache;

/// Bytes of decoded cube data resident (and reserved for reads in flight).
pub const RESIDENT_BYTES: DiagnosticPath = DiagnosticPath::const_new("plenoptic/resident_bytes");
/// Needed keys and volume blocks found resident this frame.
pub const HITS: DiagnosticPath = DiagnosticPath::const_new("plenoptic/hits");
/// Needed keys and volume blocks not resident this frame.
pub const MISSES: DiagnosticPath = DiagnosticPath::const_new("plenoptic/misses");
/// 1 for a frame in which some needed key or volume block was not resident, else 0.
pub const STALLS: DiagnosticPath = DiagnosticPath::const_new("plenoptic/stalls");
/// Milliseconds spent reading and decoding the keys that finished this frame.
pub const DECODE_MS: DiagnosticPath = DiagnosticPath::const_new("plenoptic/decode_ms");

/// Cumulative streaming counters (the diagnostics carry the per-frame values).
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct StreamingStats {
    /// Resident + reserved bytes now.
    pub resident_bytes: u64,
    /// Highest `resident_bytes` seen.
    pub peak_resident_bytes: u64,
    /// Needed keys and volume blocks found resident.
    pub hits: u64,
    /// Needed keys and volume blocks not resident.
    pub misses: u64,
    /// Frames with a needed key missing.
    pub stalls: u64,
    /// Keys decoded.
    pub decoded_keys: u64,
    /// Bytes decoded.
    pub decoded_bytes: u64,
    /// Time spent decoding (summed over worker threads).
    pub decode_time: Duration,
    /// Keys evicted.
    pub evictions: u64,
}

/// Needed keys and volume blocks found resident and missing this frame, over every camera.
#[derive(Debug, Default)]
pub(super) struct Residency {
    pub(super) hits: u64,
    pub(super) misses: u64,
    /// Whether some camera missed a needed unit.
    pub(super) stalled: bool,
}

/// Adds this frame's residency to the cumulative stats and the diagnostics.
pub(super) fn report_residency(
    cache: &StreamCache,
    stats: &mut StreamingStats,
    diagnostics: &mut Diagnostics,
    residency: &Residency,
    budget: u64,
) {
    let committed = cache.committed_bytes();
    debug_assert!(committed <= budget, "budget exceeded");
    stats.resident_bytes = committed;
    stats.peak_resident_bytes = stats.peak_resident_bytes.max(committed);
    stats.hits += residency.hits;
    stats.misses += residency.misses;
    stats.stalls += residency.stalled as u64;
    let (hits, misses, stalled) = (residency.hits, residency.misses, residency.stalled);
    diagnostics.add_measurement(&RESIDENT_BYTES, || committed as f64);
    diagnostics.add_measurement(&HITS, || hits as f64);
    diagnostics.add_measurement(&MISSES, || misses as f64);
    diagnostics.add_measurement(&STALLS, || stalled as u8 as f64);
}
