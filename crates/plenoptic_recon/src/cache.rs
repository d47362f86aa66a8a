//! The reconstructor's chunk cache: decoded chunks by (kind, base view, key), least recently
//! used evicted beyond `ReconSettings::cache_bytes`; a chunk that failed is cached as its
//! error so that it is reported, not re-read, every frame.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{ChunkKind, CubeImage, VolumeBlock};

/// A decoded chunk, or why it could not be read.
#[derive(Clone)]
pub(crate) enum Cached {
    Radiance(Arc<CubeImage<Vec3>>),
    Distance(Arc<CubeImage<f32>>),
    Ids(Arc<CubeImage<u32>>),
    Normal(Arc<CubeImage<Vec3>>),
    Volume(Arc<VolumeBlock>),
    Connectivity(Arc<Vec<[u32; 4]>>),
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
