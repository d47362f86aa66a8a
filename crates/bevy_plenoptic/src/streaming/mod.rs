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
//! [`IoTaskPool`] (not the async compute pool, where Bevy compiles pipelines:
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

pub mod schedule;

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use bevy::tasks::{IoTaskPool, Task, futures::check_ready};
use plenoptic_pack::{ChunkKind, PackReader, cube, ktx, range_image};
use plenoptic_recon::streamed::{CUBE_KINDS, StreamedCube, read_cube};

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::settings::{PlenopticEvent, PlenopticSettings, PlenopticSystems};
use schedule::{BlockRef, KeyRef, Lookahead, working_set};

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

/// The GPU-ready texel bytes of one key (tightly packed faces +X, −X, +Y, −Y, +Z, −Z).
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedKey {
    /// Face size in texels.
    pub face_size: u32,
    /// Radiance texels (the pack's format, RGB9E5 by default).
    pub radiance: Vec<u8>,
    /// Distance texels (R32F or R16F).
    pub distance: Vec<u8>,
    /// Object id texels (R32Uint or R16Uint).
    pub object_id: Vec<u8>,
    /// Normal texels, when the pack has them.
    pub normal: Option<Vec<u8>>,
    /// Diffuse-lighting texels (pack 2.0; the radiance formats).
    pub lighting: Option<Vec<u8>>,
    /// Non-diffuse radiance texels (pack 2.0; the radiance formats).
    pub non_diffuse: Option<Vec<u8>>,
    /// On the CPU backend, the key's cubes decoded for `plenoptic_recon` instead of the
    /// GPU's texel bytes above (which are then empty): what its reconstructor looks up
    /// ([`decode_cpu_key`]).
    pub cpu: Vec<(ChunkKind, StreamedCube)>,
}

impl DecodedKey {
    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.radiance.len()
            + self.distance.len()
            + self.object_id.len()
            + self.normal.as_ref().map_or(0, Vec::len)
            + self.lighting.as_ref().map_or(0, Vec::len)
            + self.non_diffuse.as_ref().map_or(0, Vec::len)) as u64
            + self.cpu.iter().map(|(_, c)| c.bytes()).sum::<u64>()
    }
}

/// Reads and decodes one key: its radiance, distance, object-id (and normal, lighting and
/// non-diffuse) cubes to
/// GPU-ready texel bytes. The error names the failing chunk.
pub fn decode_key(pack: &PackReader, (view, key): KeyRef) -> Result<DecodedKey, (String, String)> {
    let name = |kind: ChunkKind| format!("{kind:?} view {view} key {key}");
    type Read = Result<Option<(u32, Vec<u8>)>, (String, String)>;
    let read = |kind: ChunkKind| -> Read {
        let Some(i) = pack.find(kind, view, key) else {
            return Ok(None);
        };
        let fail = |e: plenoptic_pack::PackError| (name(kind), e.to_string());
        let bytes = pack.chunk_bytes(i).map_err(fail)?;
        let formats = match kind {
            ChunkKind::RadianceCube | ChunkKind::LightingCube | ChunkKind::NonDiffuseCube => {
                &range_image::RADIANCE_FORMATS[..]
            }
            ChunkKind::DistanceCube => &range_image::DISTANCE_FORMATS[..],
            ChunkKind::ObjectIdCube => &range_image::OBJECT_ID_FORMATS[..],
            _ => &range_image::NORMAL_FORMATS[..],
        };
        let (info, raw) = ktx::read_cube(&bytes, formats).map_err(fail)?;
        Ok(Some((info.face_size, raw)))
    };
    let required =
        |kind: ChunkKind| read(kind)?.ok_or_else(|| (name(kind), "not in the pack".to_string()));
    let (face_size, radiance) = required(ChunkKind::RadianceCube)?;
    let distance = required(ChunkKind::DistanceCube)?.1;
    let object_id = required(ChunkKind::ObjectIdCube)?.1;
    let normal = read(ChunkKind::NormalCube)?.map(|n| n.1);
    let lighting = read(ChunkKind::LightingCube)?.map(|n| n.1);
    let non_diffuse = read(ChunkKind::NonDiffuseCube)?.map(|n| n.1);
    Ok(DecodedKey {
        face_size,
        radiance,
        distance,
        object_id,
        normal,
        lighting,
        non_diffuse,
        cpu: Vec::new(),
    })
}

/// Reads and decodes one key for the CPU backend: its cubes as `plenoptic_recon` looks them
/// up ([`plenoptic_recon::streamed`]), none of the GPU's texel bytes. The error names the
/// failing chunk.
pub fn decode_cpu_key(
    pack: &PackReader,
    (view, key): KeyRef,
) -> Result<DecodedKey, (String, String)> {
    let mut cpu = Vec::new();
    for kind in CUBE_KINDS {
        let name = || format!("{kind:?} view {view} key {key}");
        match read_cube(pack, kind, view, key) {
            Ok(Some(c)) => cpu.push((kind, c)),
            Ok(None)
                if matches!(
                    kind,
                    ChunkKind::RadianceCube | ChunkKind::DistanceCube | ChunkKind::ObjectIdCube
                ) =>
            {
                return Err((name(), "not in the pack".to_string()));
            }
            Ok(None) => {}
            Err(e) => return Err((name(), e.to_string())),
        }
    }
    let face_size = match cpu.first() {
        Some((_, StreamedCube::Colour(c))) => c.face_size,
        _ => 0,
    };
    Ok(DecodedKey {
        face_size,
        radiance: Vec::new(),
        distance: Vec::new(),
        object_id: Vec::new(),
        normal: None,
        lighting: None,
        non_diffuse: None,
        cpu,
    })
}

/// Bytes a key occupies once decoded for the CPU backend ([`decode_cpu_key`]), from the
/// directory and the pack's face size (known before reading): 12 per texel of a colour or
/// normal cube, 4 of a distance or id cube. Saturates (a hostile face size then exceeds any
/// budget and the key is never read).
pub fn cpu_key_bytes(pack: &PackReader, (view, key): KeyRef) -> u64 {
    let face = u64::from(pack.manifest().bake.cube_face_size);
    let texels = face.saturating_mul(face).saturating_mul(6);
    CUBE_KINDS
        .into_iter()
        .filter(|&k| pack.find(k, view, key).is_some())
        .map(|k| match k {
            ChunkKind::DistanceCube | ChunkKind::ObjectIdCube => texels.saturating_mul(4),
            _ => texels.saturating_mul(12),
        })
        .fold(0u64, u64::saturating_add)
}

/// Bytes a key will occupy once decoded, from the directory (known before reading).
pub fn key_bytes(pack: &PackReader, (view, key): KeyRef) -> u64 {
    CUBE_KINDS
        .into_iter()
        .filter_map(|k| pack.find(k, view, key))
        .map(|i| pack.entries()[i].uncompressed_length)
        .sum()
}

/// Face size of the direction bins of a [`BinnedVolume`] (`plenoptic_recon`'s
/// `VolumeIndex` bins the same way).
pub const VOLUME_BIN_FACE: u32 = 16;
/// Number of bin offsets of a [`BinnedVolume`]: one per bin and the end.
pub const VOLUME_BIN_OFFSETS: usize = 6 * (VOLUME_BIN_FACE * VOLUME_BIN_FACE) as usize + 1;
/// 32-bit words per sample of a [`BinnedVolume`].
pub const VOLUME_SAMPLE_WORDS: usize = 12;

/// A temporal-volume block ready for the GPU: its samples sorted by direction bin (a cube of
/// [`VOLUME_BIN_FACE`]² texels per face, bin = `cube::direction_to_texel`), each as
/// [`VOLUME_SAMPLE_WORDS`] words `(direction.xyz, radius, radiance.rgb, distance, t, object
/// id, lighting, non-diffuse)` (floats as their bits, the last two RGB9E5), and the offset of
/// each bin's first sample.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedVolume {
    /// Sample words, bin by bin.
    pub words: Vec<u32>,
    /// [`VOLUME_BIN_OFFSETS`] sample offsets: bin `b` holds samples `bins[b]..bins[b + 1]`.
    pub bins: Vec<u32>,
}

impl BinnedVolume {
    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        4 * (self.words.len() + self.bins.len()) as u64
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.words.len() / VOLUME_SAMPLE_WORDS
    }

    /// True if it has no samples.
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }
}

/// Reads, decodes and bins one temporal-volume block. The error names the chunk.
pub fn decode_volume(
    pack: &PackReader,
    (view, bucket): BlockRef,
) -> Result<BinnedVolume, (String, String)> {
    let block = pack.volume_block(view, bucket).map_err(|e| {
        (
            format!("VolumeBlock view {view} bucket {bucket}"),
            e.to_string(),
        )
    })?;
    let bin: Vec<usize> = block
        .samples
        .iter()
        .map(|s| cube::direction_to_texel(VOLUME_BIN_FACE, s.direction))
        .collect();
    let mut bins = vec![0u32; VOLUME_BIN_OFFSETS];
    for &b in &bin {
        bins[b + 1] += 1;
    }
    for i in 0..VOLUME_BIN_OFFSETS - 1 {
        bins[i + 1] += bins[i];
    }
    let mut fill = bins.clone();
    let mut words = vec![0u32; block.samples.len() * VOLUME_SAMPLE_WORDS];
    for (s, &b) in block.samples.iter().zip(&bin) {
        let o = fill[b] as usize * VOLUME_SAMPLE_WORDS;
        fill[b] += 1;
        let f = [
            s.direction.x,
            s.direction.y,
            s.direction.z,
            s.radius,
            s.radiance.x,
            s.radiance.y,
            s.radiance.z,
            s.distance,
            s.t,
        ];
        for (w, x) in words[o..o + 9].iter_mut().zip(f) {
            *w = x.to_bits();
        }
        words[o + 9] = s.object_id;
        words[o + 10] = cube::rgb9e5_pack(s.lighting);
        words[o + 11] = cube::rgb9e5_pack(s.non_diffuse);
    }
    Ok(BinnedVolume { words, bins })
}

/// Bytes a volume block will occupy once binned, from the directory (known before reading):
/// its samples at 48 bytes (against [`plenoptic_pack::volume::SAMPLE_BYTES`] stored) plus the
/// bin offsets.
pub fn volume_bytes(pack: &PackReader, (view, bucket): BlockRef) -> Option<u64> {
    let i = pack.find(ChunkKind::VolumeBlock, view, bucket)?;
    let samples =
        pack.entries()[i].uncompressed_length / plenoptic_pack::volume::SAMPLE_BYTES as u64;
    Some(samples * 4 * VOLUME_SAMPLE_WORDS as u64 + 4 * VOLUME_BIN_OFFSETS as u64)
}

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

type DecodeResult = (Result<DecodedKey, (String, String)>, Duration);
/// Reserved bytes, slot and the decode task of a key being read.
type InFlight = (u64, u32, Task<DecodeResult>);
type VolumeResult = (Result<BinnedVolume, (String, String)>, Duration);
/// (pack, view, key or bucket).
type CacheKey = (AssetId<RadiancePack>, u32, u32);

/// What the cache streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Unit {
    Key(KeyRef),
    Volume(BlockRef),
}

/// Resident and in-flight keys and volume blocks of every pack, keyed by (pack, view, key)
/// and (pack, view, bucket).
#[derive(Resource, Default)]
pub struct StreamCache {
    /// Resident keys.
    pub resident: HashMap<CacheKey, Resident>,
    /// Resident temporal-volume blocks.
    pub volumes: HashMap<CacheKey, ResidentVolume>,
    in_flight: HashMap<CacheKey, InFlight>,
    volumes_in_flight: HashMap<CacheKey, (u64, Task<VolumeResult>)>,
    failed: HashMap<(AssetId<RadiancePack>, Unit), String>,
    frame: u64,
    free_slots: Vec<u32>,
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
    fn evict_one(
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

    fn alloc_slot(&mut self) -> u32 {
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
    fn touch_working_set(
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
    fn is_present(&self, pack: AssetId<RadiancePack>, unit: Unit) -> bool {
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

    /// Starts reading and decoding `unit` of `pack` on the [`IoTaskPool`] with `bytes`
    /// reserved for it (a key also takes a slot); `cpu`: decode a key for `plenoptic_recon`.
    fn spawn_read(
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

fn collect_finished(
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

/// Most reads in flight at once.
const MAX_IN_FLIGHT: usize = 8;

/// A unit some camera's working set asks for this frame: its pack, the pack's reader, the
/// unit and whether it is needed now (else prefetched).
type Wanted = (AssetId<RadiancePack>, Arc<PackReader>, Unit, bool);

/// Needed keys and volume blocks found resident and missing this frame, over every camera.
#[derive(Debug, Default)]
struct Residency {
    hits: u64,
    misses: u64,
    /// Whether some camera missed a needed unit.
    stalled: bool,
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

/// Starts reads of the wanted units that are neither resident, in flight nor failed, needed
/// ones first (each group in the cameras' priority order), while fewer than
/// [`MAX_IN_FLIGHT`] are in flight. Each read's bytes are reserved first, evicting the least
/// recently used units outside every working set to fit the budget; a unit that cannot fit
/// is skipped.
fn start_reads(
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

/// Adds this frame's residency to the cumulative stats and the diagnostics.
fn report_residency(
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
