//! A minimal KTX 2.0 writer and a strict reader for the pack's KTX2 chunks: the range-image
//! cubes (see `docs/pack-format.md`, "Range-image chunks") and, through the same writer and
//! header checks, the mipmapped material textures of [`crate::texture`].
//!
//! Written cube files: cubemap (`faceCount` 6, `layerCount` 0, `pixelDepth` 0), one mip level,
//! `supercompressionScheme` 2 (Zstandard, the level is one zstd frame, no dictionary), the
//! Basic Data Format Descriptor of the vkFormat, and one key/value pair `KTXwriter`.
//!
//! The reader checks the header itself, requires the canonical DFD for the vkFormat (which also
//! keeps malformed DFDs away from a panic in `ktx2` 0.5's DFD parser), then parses with
//! [`ktx2::Reader`] and decompresses with an exact, capped output size.

use ktx2::dfd::{Basic, Block};
use ktx2::{Format, SupercompressionScheme};

use crate::bytes::{PutLe, zstd_compress, zstd_decompress_exact};
use crate::error::{PackError, Result};

/// Largest cube face size (texels) the writer writes and the reader accepts.
pub const MAX_FACE_SIZE: u32 = 4096;

const KTX_HEADER_LEN: usize = 80;
const LEVEL_INDEX_LEN: usize = 24;
const WRITER_ID: &str = concat!("plenoptic_pack ", env!("CARGO_PKG_VERSION"));

/// What the header of a KTX2 cube chunk says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CubeInfo {
    /// The vkFormat.
    pub format: Format,
    /// Face size in texels.
    pub face_size: u32,
    /// Uncompressed byte length of the level (all six faces).
    pub uncompressed_length: u64,
}

/// Bytes per texel of the formats the pack uses (0 for any other).
pub(crate) fn texel_size(format: Format) -> usize {
    match format {
        Format::E5B9G9R9_UFLOAT_PACK32
        | Format::R32_SFLOAT
        | Format::R32_UINT
        | Format::R16G16_SNORM
        | Format::R16G16_SFLOAT => 4,
        Format::R16G16B16A16_SFLOAT => 8,
        Format::R16_SFLOAT | Format::R16_UINT => 2,
        _ => 0,
    }
}

fn canonical_dfd(format: Format) -> Result<(Vec<u8>, u32)> {
    let (basic, type_size) = Basic::from_format(format)
        .map_err(|e| PackError::input(format!("no DFD for {format:?}: {e:?}")))?;
    let block = Block::Basic(basic).to_vec();
    let mut dfd = Vec::with_capacity(4 + block.len());
    dfd.put_u32(4 + block.len() as u32);
    dfd.extend_from_slice(&block);
    Ok((dfd, type_size))
}

fn align(v: &mut Vec<u8>, to: usize) {
    while !v.len().is_multiple_of(to) {
        v.push(0);
    }
}

/// Writes a complete KTX2 cube file: `raw` holds the six faces (+X, −X, +Y, −Y, +Z, −Z), each
/// `face_size²` texels, rows top to bottom.
pub fn write_cube(format: Format, face_size: u32, raw: &[u8]) -> Result<Vec<u8>> {
    let ts = texel_size(format);
    if ts == 0 {
        return Err(PackError::input(format!(
            "{format:?} is not a pack cube format"
        )));
    }
    if face_size == 0 || face_size > MAX_FACE_SIZE {
        return Err(PackError::input(format!(
            "cube face size {face_size} not in 1..={MAX_FACE_SIZE}"
        )));
    }
    let expected = 6 * (face_size as usize).pow(2) * ts;
    if raw.len() != expected {
        return Err(PackError::input(format!(
            "cube data is {} bytes, expected {expected}",
            raw.len()
        )));
    }
    write_ktx2(format, (face_size, face_size), 6, &[raw])
}

/// Writes a complete KTX2 file of `faces` faces (1, or 6 for a cube), `layerCount` 0,
/// `pixelDepth` 0 and one mip level per entry of `levels` (level 0, the largest, first; each
/// the raw bytes of all faces of that level). Every level becomes one zstd frame
/// (`supercompressionScheme` 2); the level data are stored smallest level first, as the KTX2
/// specification orders them, from a 16-byte aligned offset, with no padding between them
/// (the alignment of supercompressed levels is 1). The caller has checked sizes and format.
pub(crate) fn write_ktx2(
    format: Format,
    (width, height): (u32, u32),
    faces: u32,
    levels: &[&[u8]],
) -> Result<Vec<u8>> {
    let compressed = levels
        .iter()
        .map(|l| zstd_compress(l))
        .collect::<Result<Vec<_>>>()?;
    let (dfd, type_size) = canonical_dfd(format)?;

    let index_len = LEVEL_INDEX_LEN * levels.len();
    let mut out = vec![0u8; KTX_HEADER_LEN + index_len];
    let dfd_offset = out.len();
    out.extend_from_slice(&dfd);
    align(&mut out, 4);
    let kvd_offset = out.len();
    let key_value = [b"KTXwriter\0".as_slice(), WRITER_ID.as_bytes(), b"\0"].concat();
    out.put_u32(key_value.len() as u32);
    out.extend_from_slice(&key_value);
    align(&mut out, 4);
    let kvd_length = out.len() - kvd_offset;
    align(&mut out, 16);
    let mut offsets = vec![0u64; levels.len()];
    for (l, data) in compressed.iter().enumerate().rev() {
        offsets[l] = out.len() as u64;
        out.extend_from_slice(data);
    }

    let header = ktx2::Header {
        format: Some(format),
        type_size,
        pixel_width: width,
        pixel_height: height,
        pixel_depth: 0,
        layer_count: 0,
        face_count: faces,
        level_count: levels.len() as u32,
        supercompression_scheme: Some(SupercompressionScheme::Zstandard),
        index: ktx2::Index {
            dfd_byte_offset: dfd_offset as u32,
            dfd_byte_length: dfd.len() as u32,
            kvd_byte_offset: kvd_offset as u32,
            kvd_byte_length: kvd_length as u32,
            sgd_byte_offset: 0,
            sgd_byte_length: 0,
        },
    };
    out[..KTX_HEADER_LEN].copy_from_slice(&header.as_bytes());
    for (l, (raw, data)) in levels.iter().zip(&compressed).enumerate() {
        let level = ktx2::LevelIndex {
            byte_offset: offsets[l],
            byte_length: data.len() as u64,
            uncompressed_byte_length: raw.len() as u64,
        };
        let at = KTX_HEADER_LEN + l * LEVEL_INDEX_LEN;
        out[at..at + LEVEL_INDEX_LEN].copy_from_slice(&level.as_bytes());
    }
    Ok(out)
}

/// Parses the 80-byte KTX2 header and checks what every pack KTX2 chunk shares: a vkFormat
/// from `accepted`, Zstandard supercompression, the canonical DFD of the format (which keeps
/// malformed DFDs away from `ktx2` 0.5's DFD parser) and its `typeSize`. Returns the header
/// and the format.
pub(crate) fn check_header(bytes: &[u8], accepted: &[Format]) -> Result<(ktx2::Header, Format)> {
    let head: &[u8; KTX_HEADER_LEN] = bytes
        .get(..KTX_HEADER_LEN)
        .and_then(|h| h.try_into().ok())
        .ok_or_else(|| {
            PackError::ktx(format!(
                "{} bytes is shorter than a KTX2 header",
                bytes.len()
            ))
        })?;
    let h = ktx2::Header::from_bytes(head).map_err(|e| PackError::ktx(format!("header: {e:?}")))?;
    let format = h.format.filter(|f| accepted.contains(f)).ok_or_else(|| {
        PackError::ktx(format!("vkFormat {:?} not one of {accepted:?}", h.format))
    })?;
    if h.supercompression_scheme != Some(SupercompressionScheme::Zstandard) {
        return Err(PackError::ktx(format!(
            "supercompression {:?}, expected Zstandard",
            h.supercompression_scheme
        )));
    }
    let (dfd, type_size) = canonical_dfd(format).map_err(|_| PackError::ktx("no DFD"))?;
    let start = h.index.dfd_byte_offset as usize;
    let found = bytes.get(start..start.saturating_add(h.index.dfd_byte_length as usize));
    if found != Some(dfd.as_slice()) {
        return Err(PackError::ktx(
            "data format descriptor is not the canonical one for its vkFormat",
        ));
    }
    if h.type_size != type_size {
        return Err(PackError::ktx(format!(
            "typeSize {} for {format:?}, expected {type_size}",
            h.type_size
        )));
    }
    Ok((h, format))
}

/// Checks a KTX2 cube chunk's header against the pack's rules without decompressing it.
/// `accepted` lists the vkFormats allowed for the chunk's kind.
pub fn inspect_cube(bytes: &[u8], accepted: &[Format]) -> Result<CubeInfo> {
    let (h, format) = check_header(bytes, accepted)?;
    if h.face_count != 6 || h.layer_count != 0 || h.pixel_depth != 0 || h.level_count != 1 {
        return Err(PackError::ktx(format!(
            "not a single-level cube: faceCount {}, layerCount {}, pixelDepth {}, levelCount {}",
            h.face_count, h.layer_count, h.pixel_depth, h.level_count
        )));
    }
    if h.pixel_width != h.pixel_height || h.pixel_width > MAX_FACE_SIZE {
        return Err(PackError::ktx(format!(
            "faces are {}x{}; must be square and at most {MAX_FACE_SIZE}",
            h.pixel_width, h.pixel_height
        )));
    }
    let n = h.pixel_width as u64;
    Ok(CubeInfo {
        format,
        face_size: h.pixel_width,
        uncompressed_length: 6 * n * n * texel_size(format) as u64,
    })
}

/// Parses a KTX2 cube chunk and returns its header and the decompressed level (six faces).
pub fn read_cube(bytes: &[u8], accepted: &[Format]) -> Result<(CubeInfo, Vec<u8>)> {
    let info = inspect_cube(bytes, accepted)?;
    let reader = ktx2::Reader::new(bytes).map_err(|e| PackError::ktx(format!("{e:?}")))?;
    let level = reader
        .levels()
        .next()
        .ok_or_else(|| PackError::ktx("no level"))?;
    if level.uncompressed_byte_length != info.uncompressed_length {
        return Err(PackError::ktx(format!(
            "level uncompressedByteLength {} but a {}² cube of {:?} has {}",
            level.uncompressed_byte_length, info.face_size, info.format, info.uncompressed_length
        )));
    }
    let raw = zstd_decompress_exact(
        level.data,
        info.uncompressed_length as usize,
        PackError::ktx,
    )?;
    Ok((info, raw))
}
