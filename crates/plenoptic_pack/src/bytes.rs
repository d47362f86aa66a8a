//! Little-endian byte I/O: a bounds-checked cursor over a slice, a writer into a `Vec`, and
//! bounded zstd helpers. Everything above this module reads bytes only through these.

use crate::error::{PackError, Result};

/// A cursor over untrusted bytes. Every read checks bounds and returns the error built by
/// `err` when the bytes run out; nothing here panics.
pub(crate) struct ByteReader<'a> {
    data: &'a [u8],
    pos: usize,
    err: fn(String) -> PackError,
}

impl<'a> ByteReader<'a> {
    /// A cursor at the start of `data` whose errors are made by `err`.
    pub(crate) fn new(data: &'a [u8], err: fn(String) -> PackError) -> Self {
        Self { data, pos: 0, err }
    }

    /// A malformed-chunk cursor.
    pub(crate) fn payload(data: &'a [u8]) -> Self {
        Self::new(data, PackError::payload)
    }

    pub(crate) fn fail(&self, reason: impl Into<String>) -> PackError {
        (self.err)(reason.into())
    }

    pub(crate) fn position(&self) -> usize {
        self.pos
    }

    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    pub(crate) fn bytes(&mut self, n: usize) -> Result<&'a [u8]> {
        if n > self.remaining() {
            return Err(self.fail(format!(
                "needs {n} bytes at offset {}, only {} left",
                self.pos,
                self.remaining()
            )));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    pub(crate) fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.bytes(N)?);
        Ok(a)
    }

    pub(crate) fn u8(&mut self) -> Result<u8> {
        Ok(self.array::<1>()?[0])
    }
    pub(crate) fn u16(&mut self) -> Result<u16> {
        Ok(u16::from_le_bytes(self.array()?))
    }
    pub(crate) fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(crate) fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub(crate) fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_le_bytes(self.array()?))
    }
}

/// Appends little-endian values to a `Vec<u8>`.
pub(crate) trait PutLe {
    fn put_u8(&mut self, v: u8);
    fn put_u16(&mut self, v: u16);
    fn put_u32(&mut self, v: u32);
    fn put_u64(&mut self, v: u64);
    fn put_f32(&mut self, v: f32);
}

impl PutLe for Vec<u8> {
    fn put_u8(&mut self, v: u8) {
        self.push(v);
    }
    fn put_u16(&mut self, v: u16) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_u64(&mut self, v: u64) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_f32(&mut self, v: f32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
}

/// The zstd level the writer uses for every compressed payload. On the tour's cubes (RGB9E5
/// and f32 texels), level 15 stores 9 % less than 9 at 10 MB/s against 48 (level 12: 0.6 %
/// less; 19: 10 % less at 3 MB/s). Its frames decode at 0.62 of level 9's speed (512 against
/// 821 MiB/s of texels; `PLENOPTIC_BENCH_PACK=tour.pack cargo bench --no-default-features
/// --bench pack_io -- zstd_decode`); on that bench's synthetic fixture, at 0.93.
pub(crate) const ZSTD_LEVEL: i32 = 15;

/// Compresses `data` as one zstd frame (content size recorded, no dictionary).
pub(crate) fn zstd_compress(data: &[u8]) -> Result<Vec<u8>> {
    zstd::bulk::compress(data, ZSTD_LEVEL)
        .map_err(|e| PackError::input(format!("zstd compression failed: {e}")))
}

/// Decompresses one zstd frame that must decode to exactly `expected` bytes. The caller has
/// already checked `expected` against a cap; no more than `expected` bytes are ever allocated.
pub(crate) fn zstd_decompress_exact(
    data: &[u8],
    expected: usize,
    err: fn(String) -> PackError,
) -> Result<Vec<u8>> {
    let out = zstd::bulk::decompress(data, expected).map_err(|e| {
        err(format!(
            "zstd frame does not decode to {expected} bytes: {e}"
        ))
    })?;
    if out.len() != expected {
        return Err(err(format!(
            "zstd frame decodes to {} bytes, expected {expected}",
            out.len()
        )));
    }
    Ok(out)
}

/// xxh3-64 of `data`: the checksum of every section and chunk.
pub(crate) fn checksum(data: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(data)
}
