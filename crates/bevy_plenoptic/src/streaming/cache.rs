//! The stream cache: the resident and in-flight keys and temporal-volume blocks of every pack,
//! their fixed-size slots, and the least-recently-used eviction that keeps them inside the
//! memory budget (see the [module doc](super)).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use bevy::prelude::*;
use bevy::tasks::Task;
use plenoptic_pack::PackReader;

use super::diagnostics::{Residency, StreamingStats};
use super::schedule::{self, BlockRef, KeyRef};
use super::{BinnedVolume, DecodedKey};
use crate::asset::RadiancePack;

/// A resident key.
#[derive(Debug, Clone)]
pub struct Resident {
    /// Its texel bytes.
    pub data: Arc<DecodedKey>,
    /// Bytes reserved for it.
    pub bytes: u64,
    /// Frame it was last in a working set (LRU).
    pub last_used: u64,
    /// Its fixed-size slot (layer range in the cube-array textures).
    pub slot: u32,
}

/// A resident temporal-volume block.
#[derive(Debug, Clone)]
pub struct ResidentVolume {
    /// Its binned samples.
    pub data: Arc<BinnedVolume>,
    /// Bytes reserved for it.
    pub bytes: u64,
    /// Frame it was last in a working set (LRU).
    pub last_used: u64,
}

pub(super) type DecodeResult = (Result<DecodedKey, (String, String)>, Duration);
/// Reserved bytes, slot and the decode task of a key being read.
pub(super) type InFlight = (u64, u32, Task<DecodeResult>);
pub(super) type VolumeResult = (Result<BinnedVolume, (String, String)>, Duration);
/// (pack, view, key or bucket).
pub(super) type CacheKey = (AssetId<RadiancePack>, u32, u32);

/// What the cache streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Unit {
    Key(KeyRef),
    Volume(BlockRef),
}

/// A unit some camera's working set asks for this frame: its pack, the pack's reader, the
/// unit and whether it is needed now (else prefetched).
pub(super) type Wanted = (AssetId<RadiancePack>, Arc<PackReader>, Unit, bool);

/// Resident and in-flight keys and volume blocks of every pack, keyed by (pack, view, key)
/// and (pack, view, bucket).
#[derive(Resource, Default)]
pub struct StreamCache {
    /// Resident keys.
    pub resident: HashMap<CacheKey, Resident>,
    /// Resident temporal-volume blocks.
    pub volumes: HashMap<CacheKey, ResidentVolume>,
    pub(super) in_flight: HashMap<CacheKey, InFlight>,
    pub(super) volumes_in_flight: HashMap<CacheKey, (u64, Task<VolumeResult>)>,
    pub(super) failed: HashMap<(AssetId<RadiancePack>, Unit), String>,
    pub(super) frame: u64,
    pub(super) free_slots: Vec<u32>,
    next_slot: u32,
}

impl StreamCache {
    /// Resident plus reserved (in-flight) bytes.
    pub fn committed_bytes(&self) -> u64 {
        self.resident.values().map(|r| r.bytes).sum::<u64>()
            + self.in_flight.values().map(|f| f.0).sum::<u64>()
            + self.volumes.values().map(|r| r.bytes).sum::<u64>()
            + self.volumes_in_flight.values().map(|f| f.0).sum::<u64>()
    }

    /// The resident volume block `(view, bucket)` of `pack`.
    pub fn volume(&self, pack: AssetId<RadiancePack>, b: BlockRef) -> Option<&ResidentVolume> {
        self.volumes.get(&(pack, b.0, b.1))
    }

    /// Evicts the least recently used key or volume block outside `protected`; false when
    /// there is none.
    pub(super) fn evict_one(
        &mut self,
        protected: &[(AssetId<RadiancePack>, Unit)],
        stats: &mut StreamingStats,
    ) -> bool {
        let key = self
            .resident
            .iter()
            .filter(|(k, _)| !protected.contains(&(k.0, Unit::Key((k.1, k.2)))))
            .min_by_key(|(_, r)| r.last_used)
            .map(|(k, r)| (r.last_used, *k, false));
        let volume = self
            .volumes
            .iter()
            .filter(|(k, _)| !protected.contains(&(k.0, Unit::Volume((k.1, k.2)))))
            .min_by_key(|(_, r)| r.last_used)
            .map(|(k, r)| (r.last_used, *k, true));
        let victim = match (key, volume) {
            (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
            (a, b) => a.or(b),
        };
        let Some((_, k, is_volume)) = victim else {
            return false;
        };
        if is_volume {
            self.volumes.remove(&k);
        } else if let Some(r) = self.resident.remove(&k) {
            self.free_slots.push(r.slot);
        }
        stats.evictions += 1;
        true
    }

    /// The resident key `(view, key)` of `pack`.
    pub fn get(&self, pack: AssetId<RadiancePack>, k: KeyRef) -> Option<&Resident> {
        self.resident.get(&(pack, k.0, k.1))
    }

    pub(super) fn alloc_slot(&mut self) -> u32 {
        self.free_slots.pop().unwrap_or_else(|| {
            self.next_slot += 1;
            self.next_slot - 1
        })
    }

    /// Marks `unit` of `pack` used this frame if it is resident; whether it is.
    fn touch(&mut self, pack: AssetId<RadiancePack>, unit: Unit) -> bool {
        let frame = self.frame;
        let last_used = match unit {
            Unit::Key(k) => self
                .resident
                .get_mut(&(pack, k.0, k.1))
                .map(|r| &mut r.last_used),
            Unit::Volume(b) => self
                .volumes
                .get_mut(&(pack, b.0, b.1))
                .map(|r| &mut r.last_used),
        };
        let Some(last_used) = last_used else {
            return false;
        };
        *last_used = frame;
        true
    }

    /// Marks the resident units of `set` (of `pack`, read through `reader`) used this frame,
    /// counts the needed ones found resident and missing in `residency`, and appends every
    /// unit of `set` to `wanted`: the needed keys and volume blocks, then the prefetched
    /// ones. Returns whether every needed unit is resident.
    pub(super) fn touch_working_set(
        &mut self,
        pack: AssetId<RadiancePack>,
        reader: &Arc<PackReader>,
        set: &schedule::WorkingSet,
        residency: &mut Residency,
        wanted: &mut Vec<Wanted>,
    ) -> bool {
        let needed = set
            .needed
            .iter()
            .map(|&k| Unit::Key(k))
            .chain(set.volumes.iter().map(|&b| Unit::Volume(b)))
            .map(|unit| (unit, true));
        let prefetch = set
            .prefetch
            .iter()
            .map(|&k| Unit::Key(k))
            .chain(set.volume_prefetch.iter().map(|&b| Unit::Volume(b)))
            .map(|unit| (unit, false));
        let mut complete = true;
        for (unit, is_needed) in needed.chain(prefetch) {
            let resident = self.touch(pack, unit);
            if is_needed && resident {
                residency.hits += 1;
            } else if is_needed {
                residency.misses += 1;
                complete = false;
            }
            wanted.push((pack, reader.clone(), unit, is_needed));
        }
        complete
    }

    /// Whether `unit` of `pack` is resident or being read.
    pub(super) fn is_present(&self, pack: AssetId<RadiancePack>, unit: Unit) -> bool {
        match unit {
            Unit::Key((a, b)) => {
                self.resident.contains_key(&(pack, a, b))
                    || self.in_flight.contains_key(&(pack, a, b))
            }
            Unit::Volume((a, b)) => {
                self.volumes.contains_key(&(pack, a, b))
                    || self.volumes_in_flight.contains_key(&(pack, a, b))
            }
        }
    }
}
