//! The reconstructor's chunk cache: decoded chunks by (kind, base view, key), least recently
//! used evicted beyond `ReconSettings::cache_bytes`; a chunk that failed is cached as its
//! error so that it is reported, not re-read, every frame.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{ChunkKind, CubeImage, VolumeBlock};

use crate::Reconstructor;
use crate::streamed::StreamedCube;

/// A decoded chunk, or why it could not be read.
#[derive(Clone)]
pub(crate) enum Cached {
    Radiance(Arc<CubeImage<Vec3>>),
    Distance(Arc<CubeImage<f32>>),
    Ids(Arc<CubeImage<u32>>),
    Normal(Arc<CubeImage<Vec3>>),
    Volume(Arc<VolumeBlock>),
    Connectivity(Arc<Vec<[u32; 4]>>),
    /// A light group's (lighting, non-diffuse) values of a volume block's samples.
    GroupVolume(Arc<Vec<[Vec3; 2]>>),
    Failed(String),
    /// A cube the reconstructor's [`crate::KeySource`] does not hold (not an error).
    Absent,
}

impl Cached {
    /// Bytes the chunk holds in memory (what the cache budget counts).
    pub(crate) fn bytes(&self) -> usize {
        match self {
            Cached::Radiance(c) => c.texels.len() * 12,
            Cached::Distance(c) => c.texels.len() * 4,
            Cached::Ids(c) => c.texels.len() * 4,
            Cached::Normal(c) => c.texels.len() * 12,
            Cached::Volume(b) => b.samples.len() * 64,
            Cached::Connectivity(t) => t.len() * 16,
            Cached::GroupVolume(v) => v.len() * 24,
            Cached::Failed(s) => s.len(),
            Cached::Absent => 0,
        }
    }
}

#[derive(Default)]
/// Decoded chunks with the tick of their last use, and the bytes they hold.
pub(crate) struct Cache {
    pub(crate) map: HashMap<(ChunkKind, u32, u32), (Cached, u64)>,
    pub(crate) tick: u64,
    pub(crate) bytes: usize,
}

impl Reconstructor {
    /// The chunk of (kind, view, key) as the reconstruction uses it: lighting, non-diffuse
    /// cubes and volume blocks blended at the light groups' weights when they are not the
    /// pack's own ([`crate::relight`]), every other chunk as stored.
    pub(crate) fn cached(&self, kind: ChunkKind, view: u32, key: u32) -> Cached {
        if crate::relight::blended(kind) && !self.relight.blend.is_identity() {
            return self.relit(kind, view, key);
        }
        self.cached_stored(kind, view, key)
    }

    /// The chunk of (kind, view, key) as stored: from the key source for a cube it answers
    /// for, else from the pack through the cache.
    pub(crate) fn cached_stored(&self, kind: ChunkKind, view: u32, key: u32) -> Cached {
        if crate::streamed::is_cube(kind) {
            let source = self
                .source
                .read()
                .unwrap_or_else(|e| e.into_inner())
                .clone();
            if let Some(source) = source {
                return match source.cube(kind, view, key) {
                    Some(StreamedCube::Colour(c)) => Cached::Radiance(c),
                    Some(StreamedCube::Distance(c)) => Cached::Distance(c),
                    Some(StreamedCube::Ids(c)) => Cached::Ids(c),
                    Some(StreamedCube::Normal(c)) => Cached::Normal(c),
                    None => Cached::Absent,
                };
            }
        }
        {
            let mut c = self.cache.lock().unwrap_or_else(|e| e.into_inner());
            c.tick += 1;
            let tick = c.tick;
            if let Some(entry) = c.map.get_mut(&(kind, view, key)) {
                entry.1 = tick;
                return entry.0.clone();
            }
        }
        let what = |e: plenoptic_pack::PackError| Cached::Failed(e.to_string());
        self.chunks_read
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let value = match kind {
            ChunkKind::RadianceCube => self
                .pack
                .radiance(view, key)
                .map(|c| Cached::Radiance(Arc::new(c))),
            ChunkKind::LightingCube => self
                .pack
                .lighting(view, key)
                .map(|c| Cached::Radiance(Arc::new(c))),
            ChunkKind::NonDiffuseCube => self
                .pack
                .non_diffuse(view, key)
                .map(|c| Cached::Radiance(Arc::new(c))),
            ChunkKind::DistanceCube => self
                .pack
                .distance(view, key)
                .map(|c| Cached::Distance(Arc::new(c))),
            ChunkKind::ObjectIdCube => self
                .pack
                .object_id(view, key)
                .map(|c| Cached::Ids(Arc::new(c))),
            ChunkKind::NormalCube => self
                .pack
                .normal(view, key)
                .map(|c| Cached::Normal(Arc::new(c))),
            ChunkKind::VolumeConnectivity => self
                .pack
                .connectivity(view, key)
                .map(|t| Cached::Connectivity(Arc::new(t))),
            ChunkKind::GroupLighting(g) => self
                .pack
                .group_lighting(view, key, g)
                .map(|c| Cached::Radiance(Arc::new(c))),
            ChunkKind::GroupNonDiffuse(g) => self
                .pack
                .group_non_diffuse(view, key, g)
                .map(|c| Cached::Radiance(Arc::new(c))),
            ChunkKind::GroupVolume(g) => self
                .pack
                .group_volume(view, key, g)
                .map(|v| Cached::GroupVolume(Arc::new(v))),
            _ => self
                .pack
                .volume_block(view, key)
                .map(|b| Cached::Volume(Arc::new(b))),
        }
        .unwrap_or_else(what);
        let mut c = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        c.tick += 1;
        let tick = c.tick;
        c.bytes += value.bytes();
        c.map.insert((kind, view, key), (value.clone(), tick));
        while c.bytes > self.settings.cache_bytes && c.map.len() > 1 {
            let Some((&k, _)) = c.map.iter().min_by_key(|(_, v)| v.1) else {
                break;
            };
            if let Some((v, _)) = c.map.remove(&k) {
                c.bytes = c.bytes.saturating_sub(v.bytes());
            }
        }
        value
    }
}
