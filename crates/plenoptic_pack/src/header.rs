//! The fixed-size header at offset 0 (see `docs/pack-format.md`, "Header").

use crate::bytes::{ByteReader, PutLe, checksum};
use crate::error::{PackError, Result, Section};

/// The 8 bytes every pack starts with.
pub const MAGIC: [u8; 8] = *b"PLNPACK\0";
/// The major format version this crate writes (and reads, with [`OLDEST_MAJOR`]).
pub const VERSION_MAJOR: u16 = 5;
/// The oldest major format version this crate reads: a 4.x pack is a 5.x pack whose lighting
/// holds its lamps' direct light ([`crate::Manifest::lamps_at_runtime`] false), a 3.x pack
/// also one whose non-diffuse radiance holds the emission
/// ([`crate::PackReader::runtime_emission`]), a 2.x pack also one without a runtime sun
/// ([`crate::DirectSun`]); version 1 is refused with [`PackError::NeedsRebake`].
pub const OLDEST_MAJOR: u16 = 2;
/// The minor format version this crate writes. Readers accept any minor of their major.
pub const VERSION_MINOR: u16 = 0;
/// The first major whose non-diffuse radiance leaves the emission to the runtime.
pub const RUNTIME_EMISSION_MAJOR: u16 = 4;
/// The first major whose lighting may leave its lamps' direct light to the runtime
/// ([`crate::Manifest::lamps_at_runtime`]).
pub const RUNTIME_LAMPS_MAJOR: u16 = 5;
/// Size of the header in bytes.
pub const HEADER_LEN: u64 = 128;

/// The decoded header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Major format version.
    pub version_major: u16,
    /// Minor format version.
    pub version_minor: u16,
    /// Flags; none are defined in 1.0 (writers store 0, readers ignore unknown bits).
    pub flags: u32,
    /// Length of the whole file in bytes.
    pub file_length: u64,
    /// Offset of the manifest.
    pub manifest_offset: u64,
    /// Length of the manifest.
    pub manifest_length: u64,
    /// xxh3-64 of the manifest bytes.
    pub manifest_checksum: u64,
    /// Offset of the chunk directory.
    pub directory_offset: u64,
    /// Number of rows in the chunk directory.
    pub directory_count: u64,
    /// xxh3-64 of the directory bytes.
    pub directory_checksum: u64,
}

impl Header {
    /// Serializes the header, including its own checksum at bytes 120..128.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN as usize] {
        let mut v = Vec::with_capacity(HEADER_LEN as usize);
        v.extend_from_slice(&MAGIC);
        v.put_u16(self.version_major);
        v.put_u16(self.version_minor);
        v.put_u32(self.flags);
        v.put_u64(self.file_length);
        v.put_u64(self.manifest_offset);
        v.put_u64(self.manifest_length);
        v.put_u64(self.manifest_checksum);
        v.put_u64(self.directory_offset);
        v.put_u64(self.directory_count);
        v.put_u64(self.directory_checksum);
        v.resize(120, 0);
        let c = checksum(&v);
        v.put_u64(c);
        let mut out = [0u8; HEADER_LEN as usize];
        out.copy_from_slice(&v);
        out
    }

    /// Parses and checks magic, version and the header checksum (not the offsets: the reader
    /// checks those against the file).
    pub fn parse(bytes: &[u8; HEADER_LEN as usize]) -> Result<Self> {
        let mut r = ByteReader::new(bytes, |reason| PackError::InvalidManifest { reason });
        let magic: [u8; 8] = r.array()?;
        if magic != MAGIC {
            return Err(PackError::BadMagic(magic));
        }
        let version_major = r.u16()?;
        let version_minor = r.u16()?;
        if version_major == 1 {
            return Err(PackError::NeedsRebake {
                major: version_major,
                minor: version_minor,
            });
        }
        if !(OLDEST_MAJOR..=VERSION_MAJOR).contains(&version_major) {
            return Err(PackError::UnsupportedVersion {
                major: version_major,
                minor: version_minor,
                supported: VERSION_MAJOR,
            });
        }
        let stored = u64::from_le_bytes(bytes[120..128].try_into().unwrap_or([0; 8]));
        let actual = checksum(&bytes[..120]);
        if stored != actual {
            return Err(PackError::SectionChecksumMismatch {
                section: Section::Header,
                expected: stored,
                actual,
            });
        }
        Ok(Header {
            version_major,
            version_minor,
            flags: r.u32()?,
            file_length: r.u64()?,
            manifest_offset: r.u64()?,
            manifest_length: r.u64()?,
            manifest_checksum: r.u64()?,
            directory_offset: r.u64()?,
            directory_count: r.u64()?,
            directory_checksum: r.u64()?,
        })
    }
}
