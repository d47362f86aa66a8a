//! [`PackReader`]: opens a pack by reading header, manifest and directory only, validates them,
//! and reads single chunks on demand by byte range.

use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::attributes::{ProxyAttributes, attributes_header, decode_proxy_attributes};
use crate::bytes::{ByteReader, checksum};
use crate::directory::{ChunkEntry, ChunkKind, DIRECTORY_ROW_LEN, NO_BASE_VIEW};
use crate::environment::{decode_environment_image, environment_image_header};
use crate::error::{ChunkRef, PackError, Result, Section};
use crate::header::{HEADER_LEN, Header};
use crate::ktx::inspect_cube;
use crate::manifest::{MAX_MANIFEST_BYTES, Manifest};
use crate::material::validate_materials;
use crate::proxy::{
    AnimationTracks, ProxyMesh, decode_proxy_mesh, decode_tracks, proxy_header, tracks_header,
};
use crate::range_image::{
    DISTANCE_FORMATS, DistanceCube, NORMAL_FORMATS, NormalCube, OBJECT_ID_FORMATS, ObjectIdCube,
    RADIANCE_FORMATS, RadianceCube, RangeImage, decode_distance, decode_normal, decode_object_id,
    decode_radiance,
};
use crate::texture::{TextureImage, decode_texture, inspect_texture};
use crate::volume::{
    VolumeBlock, block_header, connectivity_header, decode_connectivity, decode_volume_block,
};
use crate::writer::{MAX_CHUNK_LENGTH, MAX_CHUNKS};
use plenoptic_sky::EquirectImage;

/// Positional reads from a shared source.
trait Source: Send + Sync {
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()>;
}

struct FileSource(#[cfg(unix)] File, #[cfg(not(unix))] Mutex<File>);

impl Source for FileSource {
    #[cfg(unix)]
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        std::os::unix::fs::FileExt::read_exact_at(&self.0, buf, offset)
    }
    #[cfg(not(unix))]
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        let mut f = self
            .0
            .lock()
            .map_err(|_| std::io::Error::other("poisoned"))?;
        f.seek(SeekFrom::Start(offset))?;
        f.read_exact(buf)
    }
}

struct StreamSource<R>(Mutex<R>);

impl<R: Read + Seek + Send> Source for StreamSource<R> {
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        let mut r = self
            .0
            .lock()
            .map_err(|_| std::io::Error::other("reader mutex poisoned"))?;
        r.seek(SeekFrom::Start(offset))?;
        r.read_exact(buf)
    }
}

/// A decoded chunk of any kind.
#[derive(Clone, Debug, PartialEq)]
pub enum Chunk {
    /// A radiance cube.
    Radiance(RadianceCube),
    /// A diffuse-lighting cube.
    Lighting(RadianceCube),
    /// A non-diffuse radiance cube.
    NonDiffuse(RadianceCube),
    /// A distance cube.
    Distance(DistanceCube),
    /// An object-id cube.
    ObjectId(ObjectIdCube),
    /// A normal cube.
    Normal(NormalCube),
    /// A temporal-volume block.
    Volume(VolumeBlock),
    /// Tetrahedra over a volume block.
    Connectivity {
        /// Samples in the block the indices refer to.
        sample_count: u32,
        /// Tetrahedra (indices in the block's stored order).
        tetrahedra: Vec<[u32; 4]>,
    },
    /// A proxy mesh.
    ProxyMesh(ProxyMesh),
    /// The animation tracks.
    Tracks(AnimationTracks),
    /// The environment's image.
    EnvironmentImage(EquirectImage),
    /// A material texture with its mip levels.
    Texture(TextureImage),
    /// A proxy mesh's UVs and tangents.
    ProxyAttributes(ProxyAttributes),
    /// A light group's diffuse-lighting cube.
    GroupLighting(RadianceCube),
    /// A light group's non-diffuse radiance cube.
    GroupNonDiffuse(RadianceCube),
    /// A light group's (lighting, non-diffuse) values of a volume block's samples, in the
    /// block's stored order.
    GroupVolume(Vec<[glam::Vec3; 2]>),
}

/// The uncompressed length a chunk's own header declares (validating that header).
pub(crate) fn declared_uncompressed_length(kind: ChunkKind, bytes: &[u8]) -> Result<u64> {
    Ok(match kind {
        ChunkKind::RadianceCube
        | ChunkKind::LightingCube
        | ChunkKind::NonDiffuseCube
        | ChunkKind::GroupLighting(_)
        | ChunkKind::GroupNonDiffuse(_) => {
            inspect_cube(bytes, &RADIANCE_FORMATS)?.uncompressed_length
        }
        ChunkKind::GroupVolume(_) => crate::groups::group_volume_header(bytes)?.1,
        ChunkKind::DistanceCube => inspect_cube(bytes, &DISTANCE_FORMATS)?.uncompressed_length,
        ChunkKind::ObjectIdCube => inspect_cube(bytes, &OBJECT_ID_FORMATS)?.uncompressed_length,
        ChunkKind::NormalCube => inspect_cube(bytes, &NORMAL_FORMATS)?.uncompressed_length,
        ChunkKind::VolumeBlock => block_header(bytes)?.3,
        ChunkKind::VolumeConnectivity => connectivity_header(bytes)?.2,
        ChunkKind::ProxyMesh => proxy_header(bytes)?.4,
        ChunkKind::AnimationTracks => tracks_header(bytes)?.1,
        ChunkKind::EnvironmentImage => environment_image_header(bytes)?.2,
        ChunkKind::MaterialTexture => inspect_texture(bytes)?.uncompressed_length,
        ChunkKind::ProxyAttributes => attributes_header(bytes)?.3,
        ChunkKind::Unknown(_) => {
            return Err(PackError::input(
                "unknown chunk kinds must be added with add_raw_chunk",
            ));
        }
    })
}

/// Random-access reader of a pack. `Send + Sync`: chunks may be read from many threads at once
/// (files use positional reads; other sources a mutex around seek + read).
pub struct PackReader {
    source: Box<dyn Source>,
    path: PathBuf,
    file_length: u64,
    header: Header,
    manifest: Manifest,
    entries: Vec<ChunkEntry>,
    index: HashMap<(ChunkKind, u32, u32), usize>,
}

impl std::fmt::Debug for PackReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PackReader")
            .field("path", &self.path)
            .field("file_length", &self.file_length)
            .field("header", &self.header)
            .field("chunks", &self.entries.len())
            .finish()
    }
}

impl PackReader {
    /// Opens the pack at `path`, reading and validating header, manifest and directory.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let file = File::open(&path).map_err(|e| PackError::io(&path, e))?;
        let len = file.metadata().map_err(|e| PackError::io(&path, e))?.len();
        #[cfg(unix)]
        let source = FileSource(file);
        #[cfg(not(unix))]
        let source = FileSource(Mutex::new(file));
        Self::from_source(Box::new(source), len, path)
    }

    /// Opens a pack from any seekable source (a `Cursor<Vec<u8>>`, a network range reader...).
    pub fn from_reader<R: Read + Seek + Send + 'static>(mut reader: R) -> Result<Self> {
        let len = reader
            .seek(SeekFrom::End(0))
            .map_err(|e| PackError::io("", e))?;
        Self::from_source(
            Box::new(StreamSource(Mutex::new(reader))),
            len,
            PathBuf::new(),
        )
    }

    /// The path the pack was opened from (empty for other sources).
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn read_at(&self, offset: u64, len: u64) -> Result<Vec<u8>> {
        read_range(&*self.source, &self.path, self.file_length, offset, len)
    }

    fn from_source(source: Box<dyn Source>, file_length: u64, path: PathBuf) -> Result<Self> {
        let mut head = [0u8; HEADER_LEN as usize];
        if file_length < HEADER_LEN {
            return Err(PackError::Truncated {
                expected: HEADER_LEN,
                actual: file_length,
            });
        }
        source
            .read_exact_at(&mut head, 0)
            .map_err(|e| PackError::io(&path, e))?;
        let header = Header::parse(&head)?;
        if header.file_length > file_length {
            return Err(PackError::Truncated {
                expected: header.file_length,
                actual: file_length,
            });
        }
        if header.file_length < file_length {
            return Err(PackError::TrailingData {
                expected: header.file_length,
                actual: file_length,
            });
        }
        // Sections: manifest then directory, both after the header and inside the file.
        if header.manifest_length > MAX_MANIFEST_BYTES {
            return Err(PackError::CountTooLarge {
                what: "manifest bytes",
                count: header.manifest_length,
                max: MAX_MANIFEST_BYTES,
            });
        }
        let max_rows = (file_length / DIRECTORY_ROW_LEN).min(MAX_CHUNKS);
        if header.directory_count > max_rows {
            return Err(PackError::CountTooLarge {
                what: "directory rows",
                count: header.directory_count,
                max: max_rows,
            });
        }
        let manifest_range = (header.manifest_offset, header.manifest_length);
        let directory_range = (
            header.directory_offset,
            header.directory_count * DIRECTORY_ROW_LEN,
        );
        for (section, (off, len)) in [
            (Section::Manifest, manifest_range),
            (Section::Directory, directory_range),
        ] {
            let inside =
                off >= HEADER_LEN && off.checked_add(len).is_some_and(|e| e <= file_length);
            if !inside || overlaps(manifest_range, directory_range) {
                return Err(PackError::SectionOutOfBounds {
                    section,
                    offset: off,
                    length: len,
                });
            }
        }
        let read = |(off, len): (u64, u64)| read_range(&*source, &path, file_length, off, len);
        let manifest_bytes = read(manifest_range)?;
        let actual = checksum(&manifest_bytes);
        if actual != header.manifest_checksum {
            return Err(PackError::SectionChecksumMismatch {
                section: Section::Manifest,
                expected: header.manifest_checksum,
                actual,
            });
        }
        let directory_bytes = read(directory_range)?;
        let actual = checksum(&directory_bytes);
        if actual != header.directory_checksum {
            return Err(PackError::SectionChecksumMismatch {
                section: Section::Directory,
                expected: header.directory_checksum,
                actual,
            });
        }
        let manifest = Manifest::from_json(&manifest_bytes)?;
        if let Some(env) = &manifest.environment {
            env.validate()
                .map_err(|reason| PackError::InvalidEnvironment {
                    path: path.clone(),
                    reason,
                })?;
        }

        let mut r = ByteReader::new(&directory_bytes, |reason| PackError::InvalidManifest {
            reason,
        });
        let mut entries = Vec::with_capacity(header.directory_count as usize);
        for i in 0..header.directory_count as usize {
            entries.push(ChunkEntry::read(&mut r, i)?);
        }
        let index = validate_entries(
            &entries,
            &manifest,
            file_length,
            manifest_range,
            directory_range,
        )?;
        crate::groups::validate_chunks(&entries, &index, manifest.light_groups.as_ref())?;
        let has_texture_chunk =
            |i: u32| index.contains_key(&(ChunkKind::MaterialTexture, NO_BASE_VIEW, i));
        validate_materials(&manifest, Some(&has_texture_chunk)).map_err(|reason| {
            PackError::InvalidMaterial {
                path: path.clone(),
                reason,
            }
        })?;
        Ok(PackReader {
            source,
            path,
            file_length,
            header,
            manifest,
            entries,
            index,
        })
    }

    /// Whether the non-diffuse radiance (cubes of kind 13, volume samples) leaves out the
    /// surfaces' emission, which the runtime then takes from each object's material at the
    /// pixel's UV (pack 4.0; `docs/pack-format.md`). Before 4.0 the emission is in it.
    pub fn runtime_emission(&self) -> bool {
        self.header().version_major >= crate::header::RUNTIME_EMISSION_MAJOR
    }

    /// Whether the lighting (cubes of kind 12, volume samples) leaves out the direct diffuse
    /// light of the pack's lamps, which the runtime then adds per pixel (pack 5.0,
    /// [`Manifest::lamps_at_runtime`]; `docs/pack-format.md`). Before 5.0 the lamps' light is
    /// in it whatever the manifest says.
    pub fn lamps_at_runtime(&self) -> bool {
        self.header().version_major >= crate::header::RUNTIME_LAMPS_MAJOR
            && self.manifest().lamps_at_runtime
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The directory rows.
    pub fn entries(&self) -> &[ChunkEntry] {
        &self.entries
    }

    /// Length of the pack in bytes.
    pub fn file_length(&self) -> u64 {
        self.file_length
    }

    /// The directory index of the chunk at `(kind, base_view, key)`, if there is one.
    pub fn find(&self, kind: ChunkKind, base_view: u32, key: u32) -> Option<usize> {
        self.index.get(&(kind, base_view, key)).copied()
    }

    fn entry(&self, index: usize) -> Result<(ChunkEntry, ChunkRef)> {
        let e = *self.entries.get(index).ok_or(PackError::NoSuchChunk {
            index,
            count: self.entries.len(),
        })?;
        Ok((e, e.chunk_ref(index)))
    }

    /// Reads chunk `index`'s stored bytes (exactly its byte range) and verifies the checksum.
    pub fn chunk_bytes(&self, index: usize) -> Result<Vec<u8>> {
        let (e, chunk) = self.entry(index)?;
        let bytes = self.read_at(e.offset, e.length)?;
        let actual = checksum(&bytes);
        if actual != e.checksum {
            return Err(PackError::ChecksumMismatch {
                chunk,
                expected: e.checksum,
                actual,
            });
        }
        Ok(bytes)
    }

    /// Reads, verifies and decodes chunk `index`.
    pub fn chunk(&self, index: usize) -> Result<Chunk> {
        let (e, chunk) = self.entry(index)?;
        let bytes = self.chunk_bytes(index)?;
        let declared = declared_uncompressed_length(e.kind, &bytes).map_err(|err| match err {
            PackError::InvalidInput { .. } => PackError::UnknownChunkKind { chunk },
            other => other.in_chunk(chunk),
        })?;
        if declared != e.uncompressed_length {
            return Err(PackError::UncompressedLengthMismatch {
                chunk,
                expected: e.uncompressed_length,
                actual: declared,
            });
        }
        let decoded = match e.kind {
            ChunkKind::RadianceCube => decode_radiance(&bytes).map(Chunk::Radiance),
            ChunkKind::LightingCube => decode_radiance(&bytes).map(Chunk::Lighting),
            ChunkKind::NonDiffuseCube => decode_radiance(&bytes).map(Chunk::NonDiffuse),
            ChunkKind::DistanceCube => decode_distance(&bytes).map(Chunk::Distance),
            ChunkKind::ObjectIdCube => decode_object_id(&bytes).map(Chunk::ObjectId),
            ChunkKind::NormalCube => decode_normal(&bytes).map(Chunk::Normal),
            ChunkKind::VolumeBlock => decode_volume_block(&bytes).map(Chunk::Volume),
            ChunkKind::VolumeConnectivity => {
                decode_connectivity(&bytes).map(|(sample_count, tetrahedra)| Chunk::Connectivity {
                    sample_count,
                    tetrahedra,
                })
            }
            ChunkKind::ProxyMesh => decode_proxy_mesh(&bytes).map(Chunk::ProxyMesh),
            ChunkKind::AnimationTracks => decode_tracks(&bytes).map(Chunk::Tracks),
            ChunkKind::EnvironmentImage => {
                decode_environment_image(&bytes).map(Chunk::EnvironmentImage)
            }
            ChunkKind::MaterialTexture => decode_texture(&bytes).map(Chunk::Texture),
            ChunkKind::ProxyAttributes => {
                decode_proxy_attributes(&bytes).map(Chunk::ProxyAttributes)
            }
            ChunkKind::GroupLighting(_) => decode_radiance(&bytes).map(Chunk::GroupLighting),
            ChunkKind::GroupNonDiffuse(_) => decode_radiance(&bytes).map(Chunk::GroupNonDiffuse),
            ChunkKind::GroupVolume(_) => {
                crate::groups::decode_group_volume(&bytes).map(Chunk::GroupVolume)
            }
            ChunkKind::Unknown(_) => return Err(PackError::UnknownChunkKind { chunk }),
        };
        decoded.map_err(|err| err.in_chunk(chunk))
    }

    pub(crate) fn get(&self, kind: ChunkKind, base_view: u32, key: u32) -> Result<Chunk> {
        let i = self
            .find(kind, base_view, key)
            .ok_or(PackError::ChunkNotFound {
                kind,
                base_view,
                key,
            })?;
        self.chunk(i)
    }

    /// The radiance cube of `base_view` at time key `key`.
    pub fn radiance(&self, base_view: u32, key: u32) -> Result<RadianceCube> {
        match self.get(ChunkKind::RadianceCube, base_view, key)? {
            Chunk::Radiance(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The diffuse-lighting cube of `base_view` at time key `key`.
    pub fn lighting(&self, base_view: u32, key: u32) -> Result<RadianceCube> {
        match self.get(ChunkKind::LightingCube, base_view, key)? {
            Chunk::Lighting(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The non-diffuse radiance cube of `base_view` at time key `key`.
    pub fn non_diffuse(&self, base_view: u32, key: u32) -> Result<RadianceCube> {
        match self.get(ChunkKind::NonDiffuseCube, base_view, key)? {
            Chunk::NonDiffuse(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The distance cube of `base_view` at time key `key`.
    pub fn distance(&self, base_view: u32, key: u32) -> Result<DistanceCube> {
        match self.get(ChunkKind::DistanceCube, base_view, key)? {
            Chunk::Distance(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The object-id cube of `base_view` at time key `key`.
    pub fn object_id(&self, base_view: u32, key: u32) -> Result<ObjectIdCube> {
        match self.get(ChunkKind::ObjectIdCube, base_view, key)? {
            Chunk::ObjectId(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The normal cube of `base_view` at time key `key`.
    pub fn normal(&self, base_view: u32, key: u32) -> Result<NormalCube> {
        match self.get(ChunkKind::NormalCube, base_view, key)? {
            Chunk::Normal(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// All six cubes of `base_view` at time key `key`.
    pub fn range_image(&self, base_view: u32, key: u32) -> Result<RangeImage> {
        Ok(RangeImage {
            radiance: self.radiance(base_view, key)?,
            lighting: self.lighting(base_view, key)?,
            non_diffuse: self.non_diffuse(base_view, key)?,
            distance: self.distance(base_view, key)?,
            object_id: self.object_id(base_view, key)?,
            normal: self.normal(base_view, key)?,
        })
    }

    /// The volume block of `base_view` in time bucket `bucket`.
    pub fn volume_block(&self, base_view: u32, bucket: u32) -> Result<VolumeBlock> {
        match self.get(ChunkKind::VolumeBlock, base_view, bucket)? {
            Chunk::Volume(b) => Ok(b),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The tetrahedra of `base_view`'s block in `bucket`, if the pack has them.
    pub fn connectivity(&self, base_view: u32, bucket: u32) -> Result<Vec<[u32; 4]>> {
        match self.get(ChunkKind::VolumeConnectivity, base_view, bucket)? {
            Chunk::Connectivity { tetrahedra, .. } => Ok(tetrahedra),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The proxy mesh of object `object_id`.
    pub fn proxy_mesh(&self, object_id: u32) -> Result<ProxyMesh> {
        match self.get(ChunkKind::ProxyMesh, NO_BASE_VIEW, object_id)? {
            Chunk::ProxyMesh(m) => Ok(m),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The animation tracks.
    pub fn tracks(&self) -> Result<AnimationTracks> {
        match self.get(ChunkKind::AnimationTracks, NO_BASE_VIEW, 0)? {
            Chunk::Tracks(t) => Ok(t),
            _ => unreachable!("decoded by kind"),
        }
    }
}

fn read_range(
    source: &dyn Source,
    path: &Path,
    file_length: u64,
    offset: u64,
    len: u64,
) -> Result<Vec<u8>> {
    let end = offset.checked_add(len).filter(|&e| e <= file_length);
    if end.is_none() || len > MAX_CHUNK_LENGTH {
        return Err(PackError::Truncated {
            expected: offset.saturating_add(len),
            actual: file_length,
        });
    }
    let mut buf = vec![0u8; len as usize];
    source.read_exact_at(&mut buf, offset).map_err(|e| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            PackError::Truncated {
                expected: offset + len,
                actual: file_length,
            }
        } else {
            PackError::io(path, e)
        }
    })?;
    Ok(buf)
}

fn overlaps(a: (u64, u64), b: (u64, u64)) -> bool {
    a.1 > 0 && b.1 > 0 && a.0 < b.0.saturating_add(b.1) && b.0 < a.0.saturating_add(a.1)
}

fn validate_entries(
    entries: &[ChunkEntry],
    manifest: &Manifest,
    file_length: u64,
    manifest_range: (u64, u64),
    directory_range: (u64, u64),
) -> Result<HashMap<(ChunkKind, u32, u32), usize>> {
    let mut index = HashMap::with_capacity(entries.len());
    for (i, e) in entries.iter().enumerate() {
        let chunk = e.chunk_ref(i);
        let inside = e.offset >= HEADER_LEN
            && e.offset
                .checked_add(e.length)
                .is_some_and(|end| end <= file_length)
            && e.length <= MAX_CHUNK_LENGTH;
        let range = (e.offset, e.length);
        if !inside || overlaps(range, manifest_range) || overlaps(range, directory_range) {
            return Err(PackError::ChunkOutOfBounds {
                chunk,
                offset: e.offset,
                length: e.length,
                limit: file_length,
            });
        }
        if e.base_view != NO_BASE_VIEW && e.base_view as usize >= manifest.base_views.len() {
            return Err(PackError::UnknownBaseView {
                chunk,
                base_view: e.base_view,
                count: manifest.base_views.len(),
            });
        }
        if let Some(prev) = index.insert((e.kind, e.base_view, e.key), i) {
            return Err(PackError::DuplicateChunk {
                a: entries[prev].chunk_ref(prev),
                b: chunk,
            });
        }
    }
    let mut order: Vec<usize> = (0..entries.len())
        .filter(|&i| entries[i].length > 0)
        .collect();
    order.sort_unstable_by_key(|&i| entries[i].offset);
    for w in order.windows(2) {
        let (a, b) = (&entries[w[0]], &entries[w[1]]);
        if a.offset + a.length > b.offset {
            return Err(PackError::OverlappingChunks {
                a: a.chunk_ref(w[0]),
                b: b.chunk_ref(w[1]),
            });
        }
    }
    Ok(index)
}

/// Whether the pack at `path` is of an older format than this crate writes: one it refuses
/// (version 1, [`PackError::NeedsRebake`]) or one it reads but a bake would improve (version
/// 2 keeps the sun's direct light in its lighting; 4.x keeps its lamps' direct light in the
/// lighting, at the cube's resolution). A newer minor is not outdated. A file that cannot be opened for another reason is not outdated (opening it
/// reports that).
pub fn is_outdated(path: impl AsRef<Path>) -> bool {
    match PackReader::open(path) {
        Ok(r) => {
            let h = r.header();
            h.version_major < crate::VERSION_MAJOR
        }
        Err(e) => matches!(e, PackError::NeedsRebake { .. }),
    }
}
