//! The chunk directory: one fixed-size row per chunk (see `docs/pack-format.md`, "Directory").

use serde::{Deserialize, Serialize};

use crate::bytes::{ByteReader, PutLe};
use crate::error::{ChunkRef, PackError, Result};

/// Size of one directory row in bytes.
pub const DIRECTORY_ROW_LEN: u64 = 48;
/// `base_view` of a chunk that belongs to no base view (proxy meshes, animation tracks).
pub const NO_BASE_VIEW: u32 = u32::MAX;

/// First code of [`ChunkKind::GroupLighting`]; group `g` is `GROUP_LIGHTING + g`, `g < 256`.
const GROUP_LIGHTING: u32 = 0x100;
/// First code of [`ChunkKind::GroupNonDiffuse`].
const GROUP_NON_DIFFUSE: u32 = 0x200;
/// First code of [`ChunkKind::GroupVolume`].
const GROUP_VOLUME: u32 = 0x300;

/// What a chunk holds. The numeric codes are part of the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ChunkKind {
    /// KTX2 cube of HDR radiance (code 1). Key: time key index.
    RadianceCube,
    /// KTX2 cube of distance from the base view along each texel's ray, metres (code 2).
    DistanceCube,
    /// KTX2 cube of object ids (code 3).
    ObjectIdCube,
    /// KTX2 cube of octahedral-encoded world-space normals (code 4).
    NormalCube,
    /// Temporal-volume block: the samples of one base view in one time bucket (code 5).
    /// Key: time bucket index.
    VolumeBlock,
    /// Tetrahedra over a volume block's samples in (x, y, t) (code 6). Key: time bucket index.
    VolumeConnectivity,
    /// Proxy mesh of one object (code 7). Base view: [`NO_BASE_VIEW`]. Key: object id.
    ProxyMesh,
    /// Animation tracks of all objects (code 8). Base view: [`NO_BASE_VIEW`]. Key: 0.
    AnimationTracks,
    /// The environment's equirectangular image (code 9, since version 1.1). Base view:
    /// [`NO_BASE_VIEW`]. Key: 0.
    EnvironmentImage,
    /// A material texture: a mipmapped KTX2 2-D texture (code 10, since version 1.2). Base
    /// view: [`NO_BASE_VIEW`]. Key: index into the manifest's `textures` table.
    MaterialTexture,
    /// UVs and tangents of the proxy mesh with the same key (code 11, since version 1.2). Base
    /// view: [`NO_BASE_VIEW`]. Key: object id.
    ProxyAttributes,
    /// KTX2 cube of diffuse lighting (code 12, since version 2.0): per texel, the factor by
    /// which the surface's diffuse albedo turns into outgoing radiance. Key: time key index.
    LightingCube,
    /// KTX2 cube of the radiance that is not the Lambertian lobe's (code 13, since version
    /// 2.0): emission plus the specular part as seen from the base view. Key: time key index.
    NonDiffuseCube,
    /// KTX2 cube of light group `g`'s diffuse lighting (code `0x100 + g`, since version 4.2;
    /// [`crate::groups`]). Key: time key index.
    GroupLighting(u32),
    /// KTX2 cube of light group `g`'s non-diffuse radiance (code `0x200 + g`, since 4.2).
    /// Key: time key index.
    GroupNonDiffuse(u32),
    /// Light group `g`'s lighting and non-diffuse values of the volume block with the same
    /// base view and key (code `0x300 + g`, since 4.2). Key: time bucket index.
    GroupVolume(u32),
    /// A kind written by a newer minor version. It is validated like every other chunk and its
    /// raw bytes can be read, but it cannot be decoded.
    Unknown(u32),
}

impl ChunkKind {
    /// The kind's code in a directory row.
    pub fn code(self) -> u32 {
        match self {
            ChunkKind::RadianceCube => 1,
            ChunkKind::DistanceCube => 2,
            ChunkKind::ObjectIdCube => 3,
            ChunkKind::NormalCube => 4,
            ChunkKind::VolumeBlock => 5,
            ChunkKind::VolumeConnectivity => 6,
            ChunkKind::ProxyMesh => 7,
            ChunkKind::AnimationTracks => 8,
            ChunkKind::EnvironmentImage => 9,
            ChunkKind::MaterialTexture => 10,
            ChunkKind::ProxyAttributes => 11,
            ChunkKind::LightingCube => 12,
            ChunkKind::NonDiffuseCube => 13,
            ChunkKind::GroupLighting(g) => GROUP_LIGHTING + g,
            ChunkKind::GroupNonDiffuse(g) => GROUP_NON_DIFFUSE + g,
            ChunkKind::GroupVolume(g) => GROUP_VOLUME + g,
            ChunkKind::Unknown(c) => c,
        }
    }

    /// The kind for a code; codes this version does not know give [`ChunkKind::Unknown`].
    pub fn from_code(code: u32) -> Self {
        match code {
            1 => ChunkKind::RadianceCube,
            2 => ChunkKind::DistanceCube,
            3 => ChunkKind::ObjectIdCube,
            4 => ChunkKind::NormalCube,
            5 => ChunkKind::VolumeBlock,
            6 => ChunkKind::VolumeConnectivity,
            7 => ChunkKind::ProxyMesh,
            8 => ChunkKind::AnimationTracks,
            9 => ChunkKind::EnvironmentImage,
            10 => ChunkKind::MaterialTexture,
            11 => ChunkKind::ProxyAttributes,
            12 => ChunkKind::LightingCube,
            13 => ChunkKind::NonDiffuseCube,
            c if (GROUP_LIGHTING..GROUP_LIGHTING + 0x100).contains(&c) => {
                ChunkKind::GroupLighting(c - GROUP_LIGHTING)
            }
            c if (GROUP_NON_DIFFUSE..GROUP_NON_DIFFUSE + 0x100).contains(&c) => {
                ChunkKind::GroupNonDiffuse(c - GROUP_NON_DIFFUSE)
            }
            c if (GROUP_VOLUME..GROUP_VOLUME + 0x100).contains(&c) => {
                ChunkKind::GroupVolume(c - GROUP_VOLUME)
            }
            c => ChunkKind::Unknown(c),
        }
    }

    /// Whether chunks of this kind are KTX2 cube files.
    pub fn is_cube(self) -> bool {
        matches!(
            self,
            ChunkKind::RadianceCube
                | ChunkKind::DistanceCube
                | ChunkKind::ObjectIdCube
                | ChunkKind::NormalCube
                | ChunkKind::LightingCube
                | ChunkKind::NonDiffuseCube
                | ChunkKind::GroupLighting(_)
                | ChunkKind::GroupNonDiffuse(_)
        )
    }

    /// The light group of a group kind, `None` for other kinds.
    pub fn light_group(self) -> Option<u32> {
        match self {
            ChunkKind::GroupLighting(g)
            | ChunkKind::GroupNonDiffuse(g)
            | ChunkKind::GroupVolume(g) => Some(g),
            _ => None,
        }
    }
}

/// One row of the chunk directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkEntry {
    /// What the chunk holds.
    pub kind: ChunkKind,
    /// Base view index into [`crate::Manifest::base_views`], or [`NO_BASE_VIEW`].
    pub base_view: u32,
    /// Time key index (cubes), time bucket index (volume kinds), object id (proxy mesh and
    /// attributes), texture index (material textures), 0 (animation tracks, environment).
    pub key: u32,
    /// Offset of the chunk's bytes in the file.
    pub offset: u64,
    /// Number of stored bytes.
    pub length: u64,
    /// Size of the decoded payload (KTX2: the level's uncompressed byte length), for memory
    /// budgets. Readers check it against the chunk's own header when decoding.
    pub uncompressed_length: u64,
    /// xxh3-64 of the stored bytes.
    pub checksum: u64,
}

impl ChunkEntry {
    /// The row as a [`ChunkRef`] for error messages.
    pub fn chunk_ref(&self, index: usize) -> ChunkRef {
        ChunkRef {
            index,
            kind: self.kind,
            base_view: self.base_view,
            key: self.key,
        }
    }

    /// Appends the 48-byte row.
    pub(crate) fn write(&self, out: &mut Vec<u8>) {
        out.put_u32(self.kind.code());
        out.put_u32(self.base_view);
        out.put_u32(self.key);
        out.put_u32(0);
        out.put_u64(self.offset);
        out.put_u64(self.length);
        out.put_u64(self.uncompressed_length);
        out.put_u64(self.checksum);
    }

    /// Reads one row; `index` names it in errors.
    pub(crate) fn read(r: &mut ByteReader<'_>, index: usize) -> Result<Self> {
        let kind = ChunkKind::from_code(r.u32()?);
        let base_view = r.u32()?;
        let key = r.u32()?;
        let reserved = r.u32()?;
        let e = ChunkEntry {
            kind,
            base_view,
            key,
            offset: r.u64()?,
            length: r.u64()?,
            uncompressed_length: r.u64()?,
            checksum: r.u64()?,
        };
        if reserved != 0 {
            return Err(PackError::ReservedNotZero {
                chunk: e.chunk_ref(index),
                value: reserved,
            });
        }
        Ok(e)
    }
}
