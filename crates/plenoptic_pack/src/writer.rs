//! [`PackWriter`]: streams chunks to a temporary file next to the target, then writes the
//! manifest and directory at the end, the header at offset 0, fsyncs and renames atomically.

use std::collections::{HashMap, HashSet};
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use crate::attributes::{ProxyAttributes, encode_proxy_attributes};
use crate::bytes::checksum;
use crate::directory::{ChunkEntry, ChunkKind, DIRECTORY_ROW_LEN, NO_BASE_VIEW};
use crate::error::{PackError, Result};
use crate::header::{HEADER_LEN, Header, VERSION_MAJOR, VERSION_MINOR};
use crate::manifest::Manifest;
use crate::material::{TextureEntry, validate_materials};
use crate::proxy::{AnimationTracks, ProxyMesh, encode_proxy_mesh, encode_tracks};
use crate::range_image::{
    CubeFormats, RangeImage, encode_distance, encode_normal, encode_object_id, encode_radiance,
};
use crate::reader::declared_uncompressed_length;
use crate::texture::{TextureImage, encode_texture};
use crate::volume::{VolumeSample, encode_connectivity, encode_volume_block};

/// Most chunks one pack may hold.
pub const MAX_CHUNKS: u64 = 1 << 22;
/// Largest single chunk, stored bytes.
pub const MAX_CHUNK_LENGTH: u64 = 1 << 31;

/// Writes a pack. Chunks go to disk as they are added; only their directory rows stay in
/// memory. Nothing appears at the target path until [`PackWriter::finish`] succeeds; dropping
/// the writer (or an error, or a crash) leaves any existing file at the path untouched and
/// removes the temporary file (a crash may leave a `.tmp*` file, never a file at the path).
pub struct PackWriter {
    path: PathBuf,
    tmp: NamedTempFile,
    offset: u64,
    entries: Vec<ChunkEntry>,
    addresses: HashSet<(ChunkKind, u32, u32)>,
    /// Vertex count of each proxy mesh added, by object id (for its attributes).
    proxy_vertices: HashMap<u32, u32>,
    /// What each texture added with [`PackWriter::add_texture`] is, by index (checked against
    /// the manifest's table at the end).
    textures: HashMap<u32, TextureEntry>,
}

impl std::fmt::Debug for PackWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PackWriter")
            .field("path", &self.path)
            .field("temporary", &self.tmp.path())
            .field("chunks", &self.entries.len())
            .field("offset", &self.offset)
            .finish()
    }
}

impl PackWriter {
    /// Starts a pack that will be committed to `path`; the temporary file lives in the same
    /// directory so that the final rename is atomic.
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut tmp = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .suffix(".partial")
            .tempfile_in(&dir)
            .map_err(|e| PackError::io(&dir, e))?;
        // A zeroed header: the partial file never carries the magic.
        tmp.as_file_mut()
            .write_all(&[0u8; HEADER_LEN as usize])
            .map_err(|e| PackError::io(&path, e))?;
        Ok(PackWriter {
            path,
            tmp,
            offset: HEADER_LEN,
            entries: Vec::new(),
            addresses: HashSet::new(),
            proxy_vertices: HashMap::new(),
            textures: HashMap::new(),
        })
    }

    /// Bytes the writer holds in memory: its directory rows, address set, proxy vertex counts
    /// and texture sizes. Does not grow with chunk payloads.
    pub fn buffered_bytes(&self) -> usize {
        self.entries.capacity() * std::mem::size_of::<ChunkEntry>()
            + self.addresses.capacity() * std::mem::size_of::<(ChunkKind, u32, u32)>()
            + self.proxy_vertices.capacity() * std::mem::size_of::<(u32, u32)>()
            + self.textures.capacity() * std::mem::size_of::<(u32, TextureEntry)>()
    }

    /// Rows written so far.
    pub fn entries(&self) -> &[ChunkEntry] {
        &self.entries
    }

    /// Bytes written to the temporary file so far.
    pub fn bytes_written(&self) -> u64 {
        self.offset
    }

    /// Adds an encoded chunk of a known kind. Its own header is checked and its uncompressed
    /// length taken from it. Returns the chunk's directory index.
    pub fn add_chunk(
        &mut self,
        kind: ChunkKind,
        base_view: u32,
        key: u32,
        bytes: &[u8],
    ) -> Result<usize> {
        let probe = ChunkEntry {
            kind,
            base_view,
            key,
            offset: 0,
            length: bytes.len() as u64,
            uncompressed_length: 0,
            checksum: 0,
        };
        let uncompressed = declared_uncompressed_length(kind, bytes)
            .map_err(|e| e.in_chunk(probe.chunk_ref(self.entries.len())))?;
        self.add_raw_chunk(kind, base_view, key, bytes, uncompressed, None)
    }

    /// Adds chunk bytes as they are, without looking inside (for merging shards, resuming, and
    /// kinds this version does not know). When `expected_checksum` is given (e.g. copied from
    /// another pack's directory) the bytes must match it.
    pub fn add_raw_chunk(
        &mut self,
        kind: ChunkKind,
        base_view: u32,
        key: u32,
        bytes: &[u8],
        uncompressed_length: u64,
        expected_checksum: Option<u64>,
    ) -> Result<usize> {
        let sum = checksum(bytes);
        let entry = ChunkEntry {
            kind,
            base_view,
            key,
            offset: self.offset,
            length: bytes.len() as u64,
            uncompressed_length,
            checksum: sum,
        };
        let chunk = entry.chunk_ref(self.entries.len());
        if let Some(expected) = expected_checksum.filter(|&e| e != sum) {
            return Err(PackError::ChecksumMismatch {
                chunk,
                expected,
                actual: sum,
            });
        }
        if self.entries.len() as u64 >= MAX_CHUNKS {
            return Err(PackError::CountTooLarge {
                what: "chunks",
                count: MAX_CHUNKS + 1,
                max: MAX_CHUNKS,
            });
        }
        if entry.length > MAX_CHUNK_LENGTH {
            return Err(PackError::CountTooLarge {
                what: "chunk bytes",
                count: entry.length,
                max: MAX_CHUNK_LENGTH,
            });
        }
        if !self.addresses.insert((kind, base_view, key)) {
            let a = self
                .entries
                .iter()
                .position(|e| (e.kind, e.base_view, e.key) == (kind, base_view, key))
                .unwrap_or(0);
            return Err(PackError::DuplicateChunk {
                a: self.entries[a].chunk_ref(a),
                b: chunk,
            });
        }
        self.tmp
            .as_file_mut()
            .write_all(bytes)
            .map_err(|e| PackError::io(self.tmp.path(), e))?;
        self.offset += entry.length;
        self.entries.push(entry);
        Ok(self.entries.len() - 1)
    }

    /// Encodes and adds the six cubes of a range image under `(base_view, time_key)` (lighting
    /// and the non-diffuse part in the radiance format).
    pub fn add_range_image(
        &mut self,
        base_view: u32,
        time_key: u32,
        image: &RangeImage,
        formats: CubeFormats,
    ) -> Result<()> {
        let r = encode_radiance(&image.radiance, formats.radiance)?;
        self.add_chunk(ChunkKind::RadianceCube, base_view, time_key, &r)?;
        let l = encode_radiance(&image.lighting, formats.radiance)?;
        self.add_chunk(ChunkKind::LightingCube, base_view, time_key, &l)?;
        let s = encode_radiance(&image.non_diffuse, formats.radiance)?;
        self.add_chunk(ChunkKind::NonDiffuseCube, base_view, time_key, &s)?;
        let d = encode_distance(&image.distance, formats.distance)?;
        self.add_chunk(ChunkKind::DistanceCube, base_view, time_key, &d)?;
        let o = encode_object_id(&image.object_id, formats.object_id)?;
        self.add_chunk(ChunkKind::ObjectIdCube, base_view, time_key, &o)?;
        let n = encode_normal(&image.normal, formats.normal)?;
        self.add_chunk(ChunkKind::NormalCube, base_view, time_key, &n)?;
        Ok(())
    }

    /// Encodes and adds a volume block; if `tetrahedra` (over *input* sample indices) are
    /// given, they are remapped to the stored order and added as the block's connectivity.
    /// Returns the stored order (`order[i]` = input index of stored sample `i`).
    pub fn add_volume_block(
        &mut self,
        base_view: u32,
        bucket: u32,
        span: (f32, f32),
        samples: &[VolumeSample],
        tetrahedra: Option<&[[u32; 4]]>,
    ) -> Result<Vec<u32>> {
        let enc = encode_volume_block(span.0, span.1, samples)?;
        self.add_raw_chunk(
            ChunkKind::VolumeBlock,
            base_view,
            bucket,
            &enc.bytes,
            enc.uncompressed_length,
            None,
        )?;
        if let Some(tets) = tetrahedra {
            let remapped = crate::volume::remap_tetrahedra(tets, &enc.order)?;
            let (bytes, len) = encode_connectivity(samples.len() as u32, &remapped)?;
            self.add_raw_chunk(
                ChunkKind::VolumeConnectivity,
                base_view,
                bucket,
                &bytes,
                len,
                None,
            )?;
        }
        Ok(enc.order)
    }

    /// Encodes and adds an object's proxy mesh (key: its object id).
    pub fn add_proxy_mesh(&mut self, mesh: &ProxyMesh) -> Result<usize> {
        let (bytes, len) = encode_proxy_mesh(mesh)?;
        let index = self.add_raw_chunk(
            ChunkKind::ProxyMesh,
            NO_BASE_VIEW,
            mesh.object_id,
            &bytes,
            len,
            None,
        )?;
        self.proxy_vertices
            .insert(mesh.object_id, mesh.positions.len() as u32);
        Ok(index)
    }

    /// Encodes and adds the pack's animation tracks (key 0).
    pub fn add_tracks(&mut self, tracks: &AnimationTracks) -> Result<usize> {
        let (bytes, len) = encode_tracks(tracks)?;
        self.add_raw_chunk(
            ChunkKind::AnimationTracks,
            NO_BASE_VIEW,
            0,
            &bytes,
            len,
            None,
        )
    }

    /// Encodes and adds the environment's equirectangular image (key 0); the manifest's
    /// [`crate::EnvironmentEntry`] gives its intensity and rotation. Texels above
    /// [`crate::environment::ENVIRONMENT_TEXEL_MAX`] are clamped.
    pub fn add_environment_image(&mut self, image: &plenoptic_sky::EquirectImage) -> Result<usize> {
        let (bytes, len) = crate::environment::encode_environment_image(image)?;
        self.add_raw_chunk(
            ChunkKind::EnvironmentImage,
            NO_BASE_VIEW,
            0,
            &bytes,
            len,
            None,
        )
    }

    /// Encodes and adds a material texture with its mip chain under `index`, its entry in the
    /// manifest's `textures` table ([`PackWriter::finish`] checks that entry against it).
    pub fn add_texture(&mut self, index: u32, texture: &TextureImage) -> Result<usize> {
        let (bytes, len) = encode_texture(texture)?;
        let row = self.add_raw_chunk(
            ChunkKind::MaterialTexture,
            NO_BASE_VIEW,
            index,
            &bytes,
            len,
            None,
        )?;
        self.textures.insert(
            index,
            TextureEntry {
                width: texture.width(),
                height: texture.height(),
                levels: texture.levels.len() as u32,
                colour_space: texture.colour_space,
            },
        );
        Ok(row)
    }

    /// Encodes and adds the UVs and tangents of object `attributes.object_id`'s proxy mesh,
    /// which must have been added before with [`PackWriter::add_proxy_mesh`] (each list is
    /// empty or one entry per vertex).
    pub fn add_proxy_attributes(&mut self, attributes: &ProxyAttributes) -> Result<usize> {
        let vertices = *self
            .proxy_vertices
            .get(&attributes.object_id)
            .ok_or_else(|| {
                PackError::input(format!(
                    "proxy attributes of object {} before its proxy mesh",
                    attributes.object_id
                ))
            })?;
        attributes
            .check_vertex_count(vertices as usize)
            .map_err(PackError::input)?;
        let (bytes, len) = encode_proxy_attributes(attributes)?;
        self.add_raw_chunk(
            ChunkKind::ProxyAttributes,
            NO_BASE_VIEW,
            attributes.object_id,
            &bytes,
            len,
            None,
        )
    }

    /// Writes the manifest and directory, then the header, fsyncs and renames the file to the
    /// target path. Fails (leaving the target untouched) if a chunk names a base view the
    /// manifest does not have.
    pub fn finish(mut self, manifest: &Manifest) -> Result<PathBuf> {
        manifest.validate()?;
        if let Some(env) = &manifest.environment {
            env.validate()
                .map_err(|reason| PackError::input(format!("environment: {reason}")))?;
        }
        let has_texture_chunk = |i: u32| {
            self.addresses
                .contains(&(ChunkKind::MaterialTexture, NO_BASE_VIEW, i))
        };
        validate_materials(manifest, Some(&has_texture_chunk))
            .map_err(|reason| PackError::input(format!("materials: {reason}")))?;
        for (i, entry) in manifest.textures.iter().enumerate() {
            if let Some(added) = self.textures.get(&(i as u32))
                && added != entry
            {
                return Err(PackError::input(format!(
                    "materials: the table says texture {i} is {entry:?}, the texture added is {added:?}"
                )));
            }
        }
        for (i, e) in self.entries.iter().enumerate() {
            if e.base_view != NO_BASE_VIEW && e.base_view as usize >= manifest.base_views.len() {
                return Err(PackError::UnknownBaseView {
                    chunk: e.chunk_ref(i),
                    base_view: e.base_view,
                    count: manifest.base_views.len(),
                });
            }
        }
        let json = manifest.to_json()?;
        let mut dir = Vec::with_capacity(self.entries.len() * DIRECTORY_ROW_LEN as usize);
        for e in &self.entries {
            e.write(&mut dir);
        }
        let manifest_offset = self.offset;
        let directory_offset = manifest_offset + json.len() as u64;
        let header = Header {
            version_major: VERSION_MAJOR,
            version_minor: VERSION_MINOR,
            flags: 0,
            file_length: directory_offset + dir.len() as u64,
            manifest_offset,
            manifest_length: json.len() as u64,
            manifest_checksum: checksum(&json),
            directory_offset,
            directory_count: self.entries.len() as u64,
            directory_checksum: checksum(&dir),
        };
        let path = self.path.clone();
        let tmp_path = self.tmp.path().to_path_buf();
        let io = |e| PackError::io(&tmp_path, e);
        let file: &mut File = self.tmp.as_file_mut();
        file.write_all(&json).map_err(io)?;
        file.write_all(&dir).map_err(io)?;
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.write_all(&header.to_bytes()).map_err(io)?;
        file.sync_all().map_err(io)?;
        self.tmp
            .persist(&path)
            .map_err(|e| PackError::io(&path, e.error))?;
        // Make the rename itself durable.
        #[cfg(unix)]
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty())
            && let Ok(d) = File::open(parent)
        {
            let _ = d.sync_all();
        }
        Ok(path)
    }
}
