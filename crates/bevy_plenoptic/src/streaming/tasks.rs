//! The reads: each missing key or temporal-volume block is read and decoded
//! ([`super::decode`]) on the [`IoTaskPool`], its bytes reserved against the budget before
//! the read starts (evicting to fit), at most [`MAX_IN_FLIGHT`] at once; finished reads are
//! collected into the cache each frame, and failed chunks reported (see the
//! [module doc](super)).

use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::diagnostic::Diagnostics;
use bevy::prelude::*;
use bevy::tasks::{IoTaskPool, futures::check_ready};
use plenoptic_pack::PackReader;

use super::cache::{Unit, Wanted};
use super::diagnostics::DECODE_MS;
use super::{
    Resident, ResidentVolume, StreamCache, StreamingStats, cpu_key_bytes, decode_cpu_key,
    decode_key, decode_volume, key_bytes, volume_bytes,
};
use crate::asset::RadiancePack;
use crate::settings::PlenopticEvent;

/// Most reads in flight at once.
const MAX_IN_FLIGHT: usize = 8;

impl StreamCache {
    /// Starts reading and decoding `unit` of `pack` on the [`IoTaskPool`] with `bytes`
    /// reserved for it (a key also takes a slot); `cpu`: decode a key for `plenoptic_recon`.
    pub(super) fn spawn_read(
        &mut self,
        pack: AssetId<RadiancePack>,
        reader: Arc<PackReader>,
        unit: Unit,
        bytes: u64,
        cpu: bool,
    ) {
        let pool = IoTaskPool::get();
        match unit {
            Unit::Key(k) => {
                let slot = self.alloc_slot();
                let task = pool.spawn(async move {
                    let start = Instant::now();
                    let r = if cpu {
                        decode_cpu_key(&reader, k)
                    } else {
                        decode_key(&reader, k)
                    };
                    (r, start.elapsed())
                });
                self.in_flight.insert((pack, k.0, k.1), (bytes, slot, task));
            }
            Unit::Volume(v) => {
                let task = pool.spawn(async move {
                    let start = Instant::now();
                    let r = decode_volume(&reader, v);
                    (r, start.elapsed())
                });
                self.volumes_in_flight
                    .insert((pack, v.0, v.1), (bytes, task));
            }
        }
    }
}

/// Moves the reads that finished into the cache (or records their failure) and reports the
/// time they took.
pub(super) fn collect_finished(
    mut cache: ResMut<StreamCache>,
    mut stats: ResMut<StreamingStats>,
    mut events: MessageWriter<PlenopticEvent>,
    mut diagnostics: Diagnostics,
) {
    let frame = cache.frame;
    let done: Vec<_> = cache
        .in_flight
        .iter_mut()
        .filter_map(|(k, (_, _, task))| check_ready(task).map(|r| (*k, r)))
        .collect();
    let mut decode = Duration::ZERO;
    for (k, (result, time)) in done {
        let (bytes, slot, _) = cache.in_flight.remove(&k).expect("in flight");
        decode += time;
        match result {
            Ok(data) => {
                stats.decoded_keys += 1;
                stats.decoded_bytes += data.bytes();
                debug_assert!(data.bytes() <= bytes, "directory under-declared a key");
                cache.resident.insert(
                    k,
                    Resident {
                        data: Arc::new(data),
                        bytes,
                        last_used: frame,
                        slot,
                    },
                );
            }
            Err((chunk, reason)) => {
                warn!("plenoptic: chunk {chunk} failed: {reason}");
                cache.free_slots.push(slot);
                cache
                    .failed
                    .insert((k.0, Unit::Key((k.1, k.2))), reason.clone());
                events.write(PlenopticEvent::ChunkFailed { chunk, reason });
            }
        }
    }
    let done: Vec<_> = cache
        .volumes_in_flight
        .iter_mut()
        .filter_map(|(k, (_, task))| check_ready(task).map(|r| (*k, r)))
        .collect();
    for (k, (result, time)) in done {
        let (bytes, _) = cache.volumes_in_flight.remove(&k).expect("in flight");
        decode += time;
        match result {
            Ok(data) => {
                stats.decoded_bytes += data.bytes();
                debug_assert!(data.bytes() <= bytes, "directory under-declared a block");
                cache.volumes.insert(
                    k,
                    ResidentVolume {
                        data: Arc::new(data),
                        bytes,
                        last_used: frame,
                    },
                );
            }
            Err((chunk, reason)) => {
                warn!("plenoptic: chunk {chunk} failed: {reason}");
                cache
                    .failed
                    .insert((k.0, Unit::Volume((k.1, k.2))), reason.clone());
                events.write(PlenopticEvent::ChunkFailed { chunk, reason });
            }
        }
    }
    stats.decode_time += decode;
    diagnostics.add_measurement(&DECODE_MS, || decode.as_secs_f64() * 1e3);
}

/// Starts reads of the wanted units that are neither resident, in flight nor failed, needed
/// ones first (each group in the cameras' priority order), while fewer than
/// [`MAX_IN_FLIGHT`] are in flight. Each read's bytes are reserved first, evicting the least
/// recently used units outside every working set to fit the budget; a unit that cannot fit
/// is skipped.
pub(super) fn start_reads(
    cache: &mut StreamCache,
    stats: &mut StreamingStats,
    mut wanted: Vec<Wanted>,
    cpu: bool,
    budget: u64,
) {
    wanted.sort_by_key(|w| !w.3);
    let protected: Vec<_> = wanted.iter().map(|w| (w.0, w.2)).collect();
    for (id, reader, unit, _) in wanted {
        if cache.in_flight.len() + cache.volumes_in_flight.len() >= MAX_IN_FLIGHT {
            break;
        }
        if cache.is_present(id, unit) || cache.failed.contains_key(&(id, unit)) {
            continue;
        }
        let bytes = match unit {
            Unit::Key(k) if cpu => cpu_key_bytes(&reader, k),
            Unit::Key(k) => key_bytes(&reader, k),
            Unit::Volume(v) => volume_bytes(&reader, v).unwrap_or(u64::MAX),
        };
        if bytes > budget {
            continue;
        }
        while cache.committed_bytes() + bytes > budget && cache.evict_one(&protected, stats) {}
        if cache.committed_bytes() + bytes > budget {
            continue;
        }
        cache.spawn_read(id, reader, unit, bytes, cpu);
    }
}
