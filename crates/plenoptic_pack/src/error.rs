//! The crate's one error type, [`PackError`], and the [`ChunkRef`] that names a chunk in it.

use std::fmt;
use std::path::PathBuf;

use crate::directory::ChunkKind;

/// `Result` with [`PackError`].
pub type Result<T, E = PackError> = std::result::Result<T, E>;

/// Names one chunk of a pack: its row in the directory and its address (kind, base view, key).
///
/// Every error about a chunk carries one, so that a message says which chunk is bad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChunkRef {
    /// Row of the chunk in the directory.
    pub index: usize,
    /// Kind of the chunk.
    pub kind: ChunkKind,
    /// Base view index, or [`crate::NO_BASE_VIEW`].
    pub base_view: u32,
    /// Time key, time bucket or object id, depending on the kind.
    pub key: u32,
}

impl fmt::Display for ChunkRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "chunk #{} ({:?}", self.index, self.kind)?;
        if self.base_view != crate::NO_BASE_VIEW {
            write!(f, ", base view {}", self.base_view)?;
        }
        write!(f, ", key {})", self.key)
    }
}

/// Shows an optional chunk: `chunk #3 (RadianceCube, ...)`, or `detached bytes` for bytes that
/// were decoded outside of a pack.
pub(crate) struct At<'a>(pub &'a Option<ChunkRef>);

impl fmt::Display for At<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(c) => c.fmt(f),
            None => f.write_str("detached chunk bytes"),
        }
    }
}

/// A fixed section of the file (not a chunk).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    /// The fixed-size header at offset 0.
    Header,
    /// The JSON manifest.
    Manifest,
    /// The chunk directory.
    Directory,
}

/// Everything that can go wrong reading or writing a pack.
///
/// Errors about a chunk carry `chunk: Option<ChunkRef>`: `Some` when the chunk came out of a
/// pack (the reader fills it in), `None` when bytes were decoded on their own.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PackError {
    /// An operating-system I/O error, with the file it concerns.
    #[error("I/O error on {}: {source}", path.display())]
    Io {
        /// The file (empty for in-memory sources).
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The first 8 bytes are not the pack magic.
    #[error("not a radiance pack: magic is {0:02x?}")]
    BadMagic([u8; 8]),
    /// A version-1 pack: it stores outgoing radiance only, without the lighting apart from
    /// reflectance that version 2 reconstructs from.
    #[error(
        "pack version {major}.{minor} predates version 2 (lighting stored apart from the \
         materials); re-bake it with `plenoptic bake`"
    )]
    NeedsRebake {
        /// Major version in the file.
        major: u16,
        /// Minor version in the file.
        minor: u16,
    },
    /// The major version is one this reader does not know.
    #[error("unsupported pack version {major}.{minor} (this reader reads 2.x to {supported}.x)")]
    UnsupportedVersion {
        /// Major version in the file.
        major: u16,
        /// Minor version in the file.
        minor: u16,
        /// The major version this reader supports.
        supported: u16,
    },
    /// The file (or a section of it) is shorter than it says it is.
    #[error("truncated: expected {expected} bytes, found {actual}")]
    Truncated {
        /// Bytes expected.
        expected: u64,
        /// Bytes found.
        actual: u64,
    },
    /// The file is longer than its header says.
    #[error("file has {actual} bytes but the header says {expected}")]
    TrailingData {
        /// Length in the header.
        expected: u64,
        /// Actual length.
        actual: u64,
    },
    /// A section (header, manifest, directory) lies outside the file or overlaps another.
    #[error("{section:?} at {offset}..+{length} is outside the file or overlaps another section")]
    SectionOutOfBounds {
        /// The section.
        section: Section,
        /// Its offset.
        offset: u64,
        /// Its length.
        length: u64,
    },
    /// A section's checksum does not match its bytes.
    #[error("{section:?} checksum mismatch: stored {expected:#018x}, computed {actual:#018x}")]
    SectionChecksumMismatch {
        /// The section.
        section: Section,
        /// Stored checksum.
        expected: u64,
        /// Computed checksum.
        actual: u64,
    },
    /// The manifest is not valid (JSON syntax, a missing field, a bad value).
    #[error("invalid manifest: {reason}")]
    InvalidManifest {
        /// What is wrong.
        reason: String,
    },
    /// A count or length is larger than the file could hold or than a cap allows.
    #[error("{what}: {count} exceeds the limit {max}")]
    CountTooLarge {
        /// What was counted.
        what: &'static str,
        /// The count found.
        count: u64,
        /// The largest allowed.
        max: u64,
    },
    /// A directory row points outside the file's chunk area.
    #[error(
        "{chunk} at {offset}..+{length} lies outside the chunk area 0..{limit} or overlaps the header, manifest or directory"
    )]
    ChunkOutOfBounds {
        /// The chunk.
        chunk: ChunkRef,
        /// Its offset.
        offset: u64,
        /// Its length.
        length: u64,
        /// The file length.
        limit: u64,
    },
    /// Two chunks share bytes.
    #[error("{a} and {b} overlap")]
    OverlappingChunks {
        /// The first chunk.
        a: ChunkRef,
        /// The second chunk.
        b: ChunkRef,
    },
    /// Two chunks have the same (kind, base view, key).
    #[error("{a} and {b} have the same address")]
    DuplicateChunk {
        /// The first chunk.
        a: ChunkRef,
        /// The second chunk.
        b: ChunkRef,
    },
    /// A directory row names a base view the manifest does not have.
    #[error("{chunk} names base view {base_view}, but the manifest has {count}")]
    UnknownBaseView {
        /// The chunk.
        chunk: ChunkRef,
        /// The base view it names.
        base_view: u32,
        /// Number of base views in the manifest.
        count: usize,
    },
    /// The light-group chunks disagree with the manifest's `light_groups`: a group chunk of a
    /// group the manifest does not declare, or a range image or volume block without a
    /// declared group's layer.
    #[error("{chunk}: {problem}")]
    LightGroupMismatch {
        /// The chunk.
        chunk: ChunkRef,
        /// What is wrong.
        problem: String,
    },
    /// A directory row has a non-zero reserved field.
    #[error("{chunk}: reserved directory field is {value:#x}, expected 0")]
    ReservedNotZero {
        /// The chunk.
        chunk: ChunkRef,
        /// The value found.
        value: u32,
    },
    /// A chunk's bytes do not match the checksum in the directory.
    #[error("{chunk} checksum mismatch: stored {expected:#018x}, computed {actual:#018x}")]
    ChecksumMismatch {
        /// The chunk.
        chunk: ChunkRef,
        /// Stored checksum.
        expected: u64,
        /// Computed checksum.
        actual: u64,
    },
    /// No chunk has the requested address.
    #[error("no {kind:?} chunk for base view {base_view}, key {key}")]
    ChunkNotFound {
        /// Requested kind.
        kind: ChunkKind,
        /// Requested base view.
        base_view: u32,
        /// Requested key.
        key: u32,
    },
    /// A chunk index past the directory's end.
    #[error("chunk index {index} out of range (the pack has {count} chunks)")]
    NoSuchChunk {
        /// Requested index.
        index: usize,
        /// Number of chunks.
        count: usize,
    },
    /// A chunk of a kind this reader does not know (a newer minor version wrote it).
    #[error("{chunk}: unknown chunk kind, cannot decode")]
    UnknownChunkKind {
        /// The chunk.
        chunk: ChunkRef,
    },
    /// A chunk was asked to decode as a kind it is not.
    #[error("{chunk}: is not a {expected:?} chunk")]
    WrongChunkKind {
        /// The chunk.
        chunk: ChunkRef,
        /// The kind the caller asked for.
        expected: ChunkKind,
    },
    /// A range-image chunk is not a valid KTX2 cube file of an accepted format.
    #[error("malformed KTX2 in {}: {reason}", At(chunk))]
    MalformedKtx2 {
        /// The chunk, if the bytes came from a pack.
        chunk: Option<ChunkRef>,
        /// What is wrong.
        reason: String,
    },
    /// A non-KTX2 chunk (volume block, connectivity, proxy mesh, tracks) is malformed.
    #[error("malformed chunk payload in {}: {reason}", At(chunk))]
    MalformedChunk {
        /// The chunk, if the bytes came from a pack.
        chunk: Option<ChunkRef>,
        /// What is wrong.
        reason: String,
    },
    /// A chunk's decoded size differs from the uncompressed length in its directory row.
    #[error("{chunk}: directory says {expected} uncompressed bytes, chunk decodes to {actual}")]
    UncompressedLengthMismatch {
        /// The chunk.
        chunk: ChunkRef,
        /// The directory's value.
        expected: u64,
        /// The chunk's own value.
        actual: u64,
    },
    /// The pack's environment (manifest entry or image chunk) is not valid.
    #[error("environment of {}: {reason}", path.display())]
    InvalidEnvironment {
        /// The pack (empty for in-memory sources).
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The pack's materials (manifest tables or a texture chunk) are not valid.
    #[error("materials of {}: {reason}", path.display())]
    InvalidMaterial {
        /// The pack (empty for in-memory sources).
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A material texture's chunk could not be read or decoded: the pack, the texture's index
    /// in the texture table, and the chunk error (which names the chunk and the problem).
    #[error("texture {index} of {}: {source}", path.display())]
    InvalidTexture {
        /// The pack (empty for in-memory sources).
        path: PathBuf,
        /// Index in the manifest's `textures` table.
        index: u32,
        /// What went wrong reading the chunk.
        source: Box<PackError>,
    },
    /// The caller handed the writer or an encoder something it cannot store.
    #[error("invalid input: {reason}")]
    InvalidInput {
        /// What is wrong.
        reason: String,
    },
}

impl PackError {
    /// Attaches `chunk` to an error about detached chunk bytes (no effect on other errors).
    pub fn in_chunk(self, chunk: ChunkRef) -> Self {
        match self {
            PackError::MalformedKtx2 {
                chunk: None,
                reason,
            } => PackError::MalformedKtx2 {
                chunk: Some(chunk),
                reason,
            },
            PackError::MalformedChunk {
                chunk: None,
                reason,
            } => PackError::MalformedChunk {
                chunk: Some(chunk),
                reason,
            },
            other => other,
        }
    }

    /// The chunk an error is about, if any.
    pub fn chunk(&self) -> Option<ChunkRef> {
        match self {
            PackError::ChunkOutOfBounds { chunk, .. }
            | PackError::UnknownBaseView { chunk, .. }
            | PackError::LightGroupMismatch { chunk, .. }
            | PackError::ReservedNotZero { chunk, .. }
            | PackError::ChecksumMismatch { chunk, .. }
            | PackError::UnknownChunkKind { chunk }
            | PackError::WrongChunkKind { chunk, .. }
            | PackError::UncompressedLengthMismatch { chunk, .. } => Some(*chunk),
            PackError::OverlappingChunks { a, .. } | PackError::DuplicateChunk { a, .. } => {
                Some(*a)
            }
            PackError::MalformedKtx2 { chunk, .. } | PackError::MalformedChunk { chunk, .. } => {
                *chunk
            }
            PackError::InvalidTexture { source, .. } => source.chunk(),
            _ => None,
        }
    }

    pub(crate) fn ktx(reason: impl Into<String>) -> Self {
        PackError::MalformedKtx2 {
            chunk: None,
            reason: reason.into(),
        }
    }

    pub(crate) fn payload(reason: impl Into<String>) -> Self {
        PackError::MalformedChunk {
            chunk: None,
            reason: reason.into(),
        }
    }

    pub(crate) fn input(reason: impl Into<String>) -> Self {
        PackError::InvalidInput {
            reason: reason.into(),
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        PackError::Io {
            path: path.into(),
            source,
        }
    }
}
