//! The [`RadiancePack`] asset and its loader.
//!
//! Loading a `.pack` reads only the file's header, manifest and directory (plus the small
//! proxy meshes and animation tracks the geometry mask needs); cube chunks stay on disk and
//! are read on demand by the streaming scheduler ([`crate::streaming`]).
//!
//! Design choice (see `docs/architecture.md`, "The runtime plugin"): the loader resolves the asset path
//! to a file under the asset root and opens a [`PackReader`] on that file, so later chunk
//! reads are positional reads of exactly their byte range (random access, many threads at
//! once). Where the asset does not come from the file system (an embedded or remote source),
//! the loader falls back to reading the whole file into memory once and serving chunks from
//! there.

mod loader;

use std::sync::Arc;

use bevy::prelude::*;
use plenoptic_pack::PackReader;
use plenoptic_recon::ObjectMotion;

pub use loader::{RadiancePackLoader, RadiancePackLoaderError};

/// An opened radiance pack: header, manifest and directory in memory, chunks on disk.
#[derive(Asset, TypePath, Clone)]
pub struct RadiancePack {
    /// The random-access reader (cheap to clone; shared with streaming tasks).
    pub reader: Arc<PackReader>,
    /// The proxy mesh of every object that has one, as a Bevy mesh (object space where the
    /// object is animated, world space otherwise), with the pack object id.
    pub proxies: Vec<ProxyObject>,
    /// Chunks that could not be read while loading (a proxy mesh or the tracks), with the
    /// reason. Reported once as [`crate::PlenopticEvent::ChunkFailed`].
    pub failed: Vec<(String, String)>,
    /// The pack's file, when it was opened from the file system (the CPU backend opens its own
    /// reader on it).
    pub file: Option<std::path::PathBuf>,
    /// Per base view: whether the directory has a radiance cube of it at some time key. Views
    /// without one get no view-space weight, as in `plenoptic_recon`.
    pub usable_views: Vec<bool>,
    /// The environment behind the proxies (sky, image, colour) and the sun's track; none when
    /// the pack has none or it could not be read (then in [`RadiancePack::failed`]).
    pub environment: plenoptic_recon::background::PackEnvironment,
    /// The pack's material textures by index (pack 1.2+), mipmapped as stored; `None` for
    /// one that could not be read (then in [`RadiancePack::failed`]).
    pub textures: Vec<Option<Handle<Image>>>,
    /// The proxies as reflected rays are cast against them on the GPU (the words of a
    /// storage buffer, `reconstruct::rays`).
    pub rays: Arc<plenoptic_recon::flat_rays::FlatRays>,
}

/// Per base view of `pack`: whether the directory has a radiance cube of it at some time key
/// ([`RadiancePack::usable_views`]).
pub fn usable_views(pack: &plenoptic_pack::PackReader) -> Vec<bool> {
    pack.manifest()
        .base_views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            (0..v.time_keys.len()).any(|k| {
                pack.find(plenoptic_pack::ChunkKind::RadianceCube, i as u32, k as u32)
                    .is_some()
            })
        })
        .collect()
}

impl std::fmt::Debug for RadiancePack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RadiancePack")
            .field("reader", &self.reader)
            .field("proxies", &self.proxies.len())
            .field("failed", &self.failed)
            .finish()
    }
}

/// One object of the pack with proxy geometry.
#[derive(Clone, Debug)]
pub struct ProxyObject {
    /// The pack object id (1-based; 0 means "no object" in id cubes).
    pub id: u32,
    /// The object's name in the manifest.
    pub name: String,
    /// Its proxy mesh, a labeled sub-asset `proxy{id}` of the pack.
    pub mesh: Handle<Mesh>,
    /// Its animation track (None: static, placed by the identity).
    pub track: Option<ObjectMotion>,
}

impl ProxyObject {
    /// The object-to-world transform at time `t` (same convention as
    /// `plenoptic_recon::proxy::ProxyGeometry::transform`: identity without a track, a
    /// missing channel keeps the identity).
    pub fn transform_at(&self, t: f32) -> Transform {
        match &self.track {
            None => Transform::IDENTITY,
            Some(track) => {
                let (translation, rotation, scale) = track.sample(t);
                Transform {
                    translation,
                    rotation,
                    scale,
                }
            }
        }
    }
}

impl RadiancePack {
    /// The proxy object with pack id `id`.
    pub fn proxy(&self, id: u32) -> Option<&ProxyObject> {
        self.proxies.iter().find(|p| p.id == id)
    }

    /// The coverage of object `id` when it is see-through glazing (the pack's
    /// [`plenoptic_pack::ObjectEntry::coverage`], clamped to [0.001, 1]); `None` when opaque.
    pub fn coverage(&self, id: u32) -> Option<f32> {
        let object = self.reader.manifest().objects.iter().find(|o| o.id == id)?;
        object.coverage.map(|c| c.clamp(1e-3, 1.0))
    }
}
