//! Cubes streamed by the runtime that embeds the reconstructor (docs/architecture.md, "The
//! runtime plugin"): a [`KeySource`] set on a [`crate::Reconstructor`] answers for every
//! cube chunk (radiance, lighting, non-diffuse, distance, object id, normal), so the
//! reconstructor reads none from the pack and looks up only the keys the source holds, as a
//! GPU renderer looks up only the keys its streaming has resident. A key the source lacks is
//! not an error: its lookups are skipped (the frame's fallbacks fill in), as on the GPU.
//! Temporal-volume blocks are still read by the reconstructor's own chunk cache.

use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{ChunkKind, CubeImage, PackReader};

/// One decoded cube chunk of a key, as a [`KeySource`] hands it over.
#[derive(Clone, Debug, PartialEq)]
pub enum StreamedCube {
    /// A colour cube: radiance, lighting or non-diffuse radiance.
    Colour(Arc<CubeImage<Vec3>>),
    /// The distance cube.
    Distance(Arc<CubeImage<f32>>),
    /// The object-id cube.
    Ids(Arc<CubeImage<u32>>),
    /// The normal cube.
    Normal(Arc<CubeImage<Vec3>>),
}

/// Where a reconstructor gets its cube chunks when a runtime streams them (see the module
/// doc).
pub trait KeySource: Send + Sync {
    /// The cube of `kind` of (base view `view`, time key `key`), if it is resident.
    fn cube(&self, kind: ChunkKind, view: u32, key: u32) -> Option<StreamedCube>;
}

/// Whether chunks of `kind` are cubes a [`KeySource`] answers for.
pub(crate) fn is_cube(kind: ChunkKind) -> bool {
    CUBE_KINDS.contains(&kind)
}

/// Reads and decodes the cube of `kind` of (view, key) from `pack`, as a [`KeySource`] hands
/// it over: `Ok(None)` when the pack has no such chunk (or `kind` is not a cube).
pub fn read_cube(
    pack: &PackReader,
    kind: ChunkKind,
    view: u32,
    key: u32,
) -> plenoptic_pack::Result<Option<StreamedCube>> {
    if !is_cube(kind) || pack.find(kind, view, key).is_none() {
        return Ok(None);
    }
    Ok(Some(match kind {
        ChunkKind::RadianceCube => StreamedCube::Colour(Arc::new(pack.radiance(view, key)?)),
        ChunkKind::LightingCube => StreamedCube::Colour(Arc::new(pack.lighting(view, key)?)),
        ChunkKind::NonDiffuseCube => StreamedCube::Colour(Arc::new(pack.non_diffuse(view, key)?)),
        ChunkKind::DistanceCube => StreamedCube::Distance(Arc::new(pack.distance(view, key)?)),
        ChunkKind::ObjectIdCube => StreamedCube::Ids(Arc::new(pack.object_id(view, key)?)),
        _ => StreamedCube::Normal(Arc::new(pack.normal(view, key)?)),
    }))
}

/// Every cube chunk kind, in the order a key's cubes are read.
pub const CUBE_KINDS: [ChunkKind; 6] = [
    ChunkKind::RadianceCube,
    ChunkKind::DistanceCube,
    ChunkKind::ObjectIdCube,
    ChunkKind::NormalCube,
    ChunkKind::LightingCube,
    ChunkKind::NonDiffuseCube,
];

impl StreamedCube {
    /// Bytes it holds in memory.
    pub fn bytes(&self) -> u64 {
        (match self {
            StreamedCube::Colour(c) | StreamedCube::Normal(c) => c.texels.len() * 12,
            StreamedCube::Distance(c) => c.texels.len() * 4,
            StreamedCube::Ids(c) => c.texels.len() * 4,
        }) as u64
    }
}
