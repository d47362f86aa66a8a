//! # plenoptic_pack
//!
//! The *radiance pack*: the one file a bake produces and the runtime streams. This crate is the
//! file format of `docs/architecture.md` § "The pack" and nothing else: no engine, no renderer. The byte
//! layout, quantization, error bounds and limits are specified in `docs/pack-format.md`.
//!
//! What it stores comes from Nimeroff's thesis (1997): the *range images* of chapter 6 (per base
//! view and time key, cubes of radiance, distance, object id and normal; [`range_image`]) and
//! the *temporal volumes* of chapter 7 (per base view, (direction, t) samples bucketed by time,
//! with their optional (x, y, t) tetrahedral complex; [`volume`]), plus proxy geometry and
//! animation tracks for the geometry-assisted reconstruction ([`proxy`]).
//!
//! From version 1.2 a pack also carries each object's glTF material ([`material`]), its
//! textures as mipmapped KTX2 files ([`texture`]) and the proxies' UVs and tangents
//! ([`attributes`]) for the geometry-assisted reconstruction (docs/architecture.md, "Pack v2").
//!
//! Layers, bottom-up: byte I/O → [`header`] → [`manifest`] → [`directory`] → [`cube`]
//! addressing and quantizers → [`ktx`] (KTX2 files) → [`range_image`], [`texture`] →
//! [`volume`] → [`proxy`], [`attributes`], [`material`] → [`writer`] → [`reader`].
//!
//! A pack is untrusted input: every count and length is checked against the file and the caps
//! before anything is allocated, every section and chunk is checksummed (xxh3-64), and a bad pack
//! gives a [`PackError`] naming the chunk, never a panic.
//!
//! ```
//! use plenoptic_pack::*;
//! # fn main() -> Result<()> {
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("room.pack");
//!
//! // Write: chunks stream to disk, the manifest and directory go at the end.
//! let mut image = RangeImage::new(4);
//! image.radiance = CubeImage::from_fn(4, |_, dir| dir.abs());
//! let mut writer = PackWriter::create(&path)?;
//! writer.add_range_image(0, 0, &image, CubeFormats::default())?;
//! let mut manifest = Manifest::new(TimeRange { start: 0.0, end: 1.0 }, 0.25);
//! manifest.base_views.push(BaseView { id: 0, position: glam::Vec3::ZERO, time_keys: vec![0.0] });
//! writer.finish(&manifest)?;
//!
//! // Read: open reads header, manifest and directory; chunks are read on demand.
//! let pack = PackReader::open(&path)?;
//! assert_eq!(pack.manifest(), &manifest);
//! let distance = pack.distance(0, 0)?;
//! assert_eq!(distance.texels, image.distance.texels);
//! let radiance = pack.radiance(0, 0)?;
//! assert!((radiance.texels[0] - image.radiance.texels[0]).abs().max_element() < 1e-2);
//! # Ok(())
//! # }
//! ```

pub mod attributes;
mod bytes;
pub mod cube;
pub mod directory;
pub mod environment;
mod error;
pub mod groups;
pub mod header;
pub mod ktx;
pub mod manifest;
pub mod material;
pub mod proxy;
pub mod range_image;
pub mod reader;
pub mod texture;
pub mod volume;
pub mod writer;

/// The glam this crate's types use (the workspace's one glam).
pub use glam;
/// The environment model whose parameters the pack stores.
pub use plenoptic_sky;

pub use attributes::{ProxyAttributes, decode_proxy_attributes, encode_proxy_attributes};
pub use cube::{direction_to_face_uv, face_uv_to_direction};
pub use directory::{ChunkEntry, ChunkKind, NO_BASE_VIEW};
pub use environment::{
    DirectSun, EnvironmentEntry, EnvironmentSource, decode_environment_image,
    encode_environment_image,
};
pub use error::{ChunkRef, PackError, Result, Section};
pub use groups::{DEFAULT_GROUP, GroupWeights, LayerBlend, LightGroupsEntry, MAX_LIGHT_GROUPS};
pub use header::{HEADER_LEN, Header, MAGIC, OLDEST_MAJOR, VERSION_MAJOR, VERSION_MINOR};
pub use manifest::{
    Aabb, BakeSettings, BakeStatistics, BaseView, Light, LightKind, LightPlacement,
    MAX_RUNTIME_LAMPS, Manifest, Motion, ObjectEntry, TimeRange, Units, ViewSpace, lamps_placed,
};
pub use material::{
    AlphaMode, MaterialEntry, TextureBinding, TextureEntry, UvTransform, WrapMode,
    validate_materials,
};
pub use proxy::{AnimationTracks, Interpolation, ObjectTracks, ProxyMesh, Track};
pub use range_image::{
    CubeFormats, CubeImage, DistanceCube, DistanceFormat, NormalCube, NormalFormat, ObjectIdCube,
    ObjectIdFormat, RadianceCube, RadianceFormat, RangeImage, decode_distance, decode_normal,
    decode_object_id, decode_radiance, encode_distance, encode_normal, encode_object_id,
    encode_radiance,
};
pub use reader::{Chunk, PackReader, is_outdated};
pub use texture::{
    ColourSpace, MAX_TEXTURE_SIDE, TextureImage, TextureLevel, decode_texture, encode_texture,
    mip_count, mip_size,
};
pub use volume::{
    EncodedVolumeBlock, VolumeBlock, VolumeSample, decode_connectivity, decode_volume_block,
    encode_connectivity, encode_volume_block,
};
pub use writer::PackWriter;

/// xxh3-64, the checksum of every section and chunk.
pub fn checksum(bytes: &[u8]) -> u64 {
    bytes::checksum(bytes)
}

/// Compile-time check that the reader can be shared between threads.
const _: fn() = || {
    fn shared<T: Send + Sync>() {}
    shared::<PackReader>();
};
