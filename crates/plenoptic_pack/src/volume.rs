//! Temporal-volume blocks (thesis ch. 7): the (direction, t) samples of one base view in one
//! time bucket, ordered along a Morton curve, quantized column by column and zstd-compressed;
//! and the optional tetrahedral connectivity over them (see `docs/pack-format.md`, "Volume
//! block").

use glam::Vec3;
use half::f16;

use crate::bytes::{ByteReader, PutLe, zstd_compress, zstd_decompress_exact};
use crate::cube::{from_oct_unorm16, oct_unorm16, rgb9e5_pack, rgb9e5_unpack};
use crate::error::{PackError, Result};

/// Most samples one block may hold.
pub const MAX_BLOCK_SAMPLES: u32 = 1 << 24;
/// Most tetrahedra one connectivity chunk may hold.
pub const MAX_TETRAHEDRA: u32 = 1 << 26;

const BLOCK_MAGIC: [u8; 4] = *b"PVB1";
const CONNECTIVITY_MAGIC: [u8; 4] = *b"PVC1";
/// Stored bytes per sample before zstd.
pub const SAMPLE_BYTES: usize = 32;

/// One temporal-volume sample as the baker produced it (before quantization).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSample {
    /// Unit direction from the base view. Stored octahedral, 2×16-bit unorm: angular error
    /// ≤ 1e-4 rad.
    pub direction: Vec3,
    /// Time, seconds, inside the block's span. Stored as 16-bit unorm of the span: error
    /// ≤ span / 131070.
    pub t: f32,
    /// HDR radiance, linear RGB. Stored RGB9E5: per-channel error ≤ max(r,g,b)·2⁻⁹.
    pub radiance: Vec3,
    /// Diffuse lighting (version 2): what the surface's diffuse albedo multiplies, as in a
    /// range image's lighting cube. Stored RGB9E5.
    pub lighting: Vec3,
    /// Emission plus the specular part of `radiance` (version 2). Stored RGB9E5.
    pub non_diffuse: Vec3,
    /// Distance along the direction, metres. Stored as f32: exact.
    pub distance: f32,
    /// Unit normal. Stored like `direction`: angular error ≤ 1e-4 rad.
    pub normal: Vec3,
    /// Object id. Exact.
    pub object_id: u32,
    /// Angular validity radius in radians: the half-angle of the cone around `direction` the
    /// sample stands for. Stored as f16: relative error ≤ 2⁻¹¹.
    pub radius: f32,
}

/// A decoded block: its time span and samples in stored (Morton) order.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeBlock {
    /// Start of the time span, seconds.
    pub t_start: f32,
    /// End of the time span, seconds (> start).
    pub t_end: f32,
    /// Samples, in stored order.
    pub samples: Vec<VolumeSample>,
}

/// An encoded block and the order it stored the samples in.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodedVolumeBlock {
    /// The chunk bytes.
    pub bytes: Vec<u8>,
    /// `order[i]` is the input index of stored sample `i`. Connectivity built on input indices
    /// must be remapped with [`remap_tetrahedra`] before it is stored.
    pub order: Vec<u32>,
    /// Uncompressed payload bytes (for the directory row).
    pub uncompressed_length: u64,
}

fn spread3(x: u64) -> u64 {
    // Spread the low 21 bits of x to every third bit (standard 3D Morton magic numbers).
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Morton key over the quantized (u, v, t) of a sample.
fn morton(u: u16, v: u16, t: u16) -> u64 {
    spread3(u as u64) | (spread3(v as u64) << 1) | (spread3(t as u64) << 2)
}

fn quant_t(t: f32, t0: f32, t1: f32) -> u16 {
    crate::cube::unorm16((t - t0) / (t1 - t0))
}

/// Encodes the samples of one bucket `[t_start, t_end]`: sorts them along the Morton curve over
/// (octahedral u, v, t), quantizes, stores columns, compresses with zstd.
pub fn encode_volume_block(
    t_start: f32,
    t_end: f32,
    samples: &[VolumeSample],
) -> Result<EncodedVolumeBlock> {
    if !(t_start.is_finite() && t_end.is_finite() && t_end > t_start) {
        return Err(PackError::input(format!(
            "bad block span {t_start}..{t_end}"
        )));
    }
    if samples.len() > MAX_BLOCK_SAMPLES as usize {
        return Err(PackError::input(format!(
            "{} samples exceed the block cap {MAX_BLOCK_SAMPLES}",
            samples.len()
        )));
    }
    let mut keyed = Vec::with_capacity(samples.len());
    for (i, s) in samples.iter().enumerate() {
        if !(s.t >= t_start && s.t <= t_end) {
            return Err(PackError::input(format!(
                "sample {i} at t = {} outside the block span {t_start}..{t_end}",
                s.t
            )));
        }
        let [u, v] = oct_unorm16(s.direction);
        keyed.push((morton(u, v, quant_t(s.t, t_start, t_end)), i as u32));
    }
    keyed.sort_unstable();
    let order: Vec<u32> = keyed.iter().map(|k| k.1).collect();
    let n = samples.len();
    let mut raw = Vec::with_capacity(n * SAMPLE_BYTES);
    let col = |raw: &mut Vec<u8>, f: &dyn Fn(&VolumeSample) -> Vec<u8>| {
        for &i in &order {
            raw.extend_from_slice(&f(&samples[i as usize]));
        }
    };
    col(&mut raw, &|s| {
        oct_unorm16(s.direction)[0].to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        oct_unorm16(s.direction)[1].to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        quant_t(s.t, t_start, t_end).to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        rgb9e5_pack(s.radiance).to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| s.distance.to_le_bytes().to_vec());
    col(&mut raw, &|s| {
        rgb9e5_pack(s.lighting).to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        rgb9e5_pack(s.non_diffuse).to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        oct_unorm16(s.normal)[0].to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| {
        oct_unorm16(s.normal)[1].to_le_bytes().to_vec()
    });
    col(&mut raw, &|s| s.object_id.to_le_bytes().to_vec());
    col(&mut raw, &|s| {
        f16::from_f32(s.radius).to_le_bytes().to_vec()
    });
    debug_assert_eq!(raw.len(), n * SAMPLE_BYTES);

    let mut bytes = Vec::with_capacity(16 + raw.len() / 2);
    bytes.extend_from_slice(&BLOCK_MAGIC);
    bytes.put_u32(n as u32);
    bytes.put_f32(t_start);
    bytes.put_f32(t_end);
    bytes.extend_from_slice(&zstd_compress(&raw)?);
    Ok(EncodedVolumeBlock {
        bytes,
        order,
        uncompressed_length: raw.len() as u64,
    })
}

/// Reads a block's fixed header: (sample count, t_start, t_end, uncompressed length).
pub(crate) fn block_header(bytes: &[u8]) -> Result<(u32, f32, f32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != BLOCK_MAGIC {
        return Err(r.fail("not a volume block (bad magic)"));
    }
    let n = r.u32()?;
    let (t0, t1) = (r.f32()?, r.f32()?);
    if n > MAX_BLOCK_SAMPLES {
        return Err(PackError::CountTooLarge {
            what: "volume block samples",
            count: n as u64,
            max: MAX_BLOCK_SAMPLES as u64,
        });
    }
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return Err(r.fail(format!("bad block span {t0}..{t1}")));
    }
    Ok((n, t0, t1, n as u64 * SAMPLE_BYTES as u64))
}

/// Decodes a volume block chunk; samples come back in stored order.
pub fn decode_volume_block(bytes: &[u8]) -> Result<VolumeBlock> {
    let (n, t0, t1, len) = block_header(bytes)?;
    let raw = zstd_decompress_exact(&bytes[16..], len as usize, PackError::payload)?;
    let n = n as usize;
    let column = |index: usize, width: usize| &raw[index * n..(index + width) * n];
    // Column offsets in units of n bytes.
    let du = column(0, 2);
    let dv = column(2, 2);
    let tq = column(4, 2);
    let rad = column(6, 4);
    let dist = column(10, 4);
    let light = column(14, 4);
    let non_diffuse = column(18, 4);
    let nu = column(22, 2);
    let nv = column(24, 2);
    let ids = column(26, 4);
    let radius = column(30, 2);
    let u16_at = |c: &[u8], i: usize| u16::from_le_bytes([c[2 * i], c[2 * i + 1]]);
    let u32_at = |c: &[u8], i: usize| {
        u32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
    };
    let samples = (0..n)
        .map(|i| VolumeSample {
            direction: from_oct_unorm16([u16_at(du, i), u16_at(dv, i)]),
            t: t0 + crate::cube::from_unorm16(u16_at(tq, i)) * (t1 - t0),
            radiance: rgb9e5_unpack(u32_at(rad, i)),
            distance: f32::from_bits(u32_at(dist, i)),
            lighting: rgb9e5_unpack(u32_at(light, i)),
            non_diffuse: rgb9e5_unpack(u32_at(non_diffuse, i)),
            normal: from_oct_unorm16([u16_at(nu, i), u16_at(nv, i)]),
            object_id: u32_at(ids, i),
            radius: f16::from_bits(u16_at(radius, i)).to_f32(),
        })
        .collect();
    Ok(VolumeBlock {
        t_start: t0,
        t_end: t1,
        samples,
    })
}

/// Rewrites tetrahedra over input sample indices into stored indices, given the `order` an
/// [`encode_volume_block`] returned. Fails if an index is out of range.
pub fn remap_tetrahedra(tets: &[[u32; 4]], order: &[u32]) -> Result<Vec<[u32; 4]>> {
    let mut inverse = vec![0u32; order.len()];
    for (stored, &input) in order.iter().enumerate() {
        let slot = inverse
            .get_mut(input as usize)
            .ok_or_else(|| PackError::input("order is not a permutation"))?;
        *slot = stored as u32;
    }
    tets.iter()
        .map(|t| {
            let mut o = [0u32; 4];
            for (k, &i) in t.iter().enumerate() {
                o[k] = *inverse.get(i as usize).ok_or_else(|| {
                    PackError::input(format!("tetrahedron index {i} ≥ {} samples", order.len()))
                })?;
            }
            Ok(o)
        })
        .collect()
}

/// Encodes tetrahedra over a block of `sample_count` samples (indices in stored order).
/// Returns the chunk bytes and the uncompressed length.
pub fn encode_connectivity(sample_count: u32, tets: &[[u32; 4]]) -> Result<(Vec<u8>, u64)> {
    if tets.len() > MAX_TETRAHEDRA as usize {
        return Err(PackError::input(format!(
            "{} tetrahedra exceed the cap",
            tets.len()
        )));
    }
    let mut raw = Vec::with_capacity(tets.len() * 16);
    for t in tets {
        for &i in t {
            if i >= sample_count {
                return Err(PackError::input(format!(
                    "tetrahedron index {i} ≥ {sample_count} samples"
                )));
            }
            raw.put_u32(i);
        }
    }
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&CONNECTIVITY_MAGIC);
    bytes.put_u32(tets.len() as u32);
    bytes.put_u32(sample_count);
    bytes.put_u32(0);
    bytes.extend_from_slice(&zstd_compress(&raw)?);
    Ok((bytes, raw.len() as u64))
}

/// Reads a connectivity chunk's fixed header: (tetrahedron count, sample count, uncompressed
/// length).
pub(crate) fn connectivity_header(bytes: &[u8]) -> Result<(u32, u32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != CONNECTIVITY_MAGIC {
        return Err(r.fail("not a connectivity chunk (bad magic)"));
    }
    let count = r.u32()?;
    let samples = r.u32()?;
    if r.u32()? != 0 {
        return Err(r.fail("reserved field is not 0"));
    }
    if count > MAX_TETRAHEDRA {
        return Err(PackError::CountTooLarge {
            what: "tetrahedra",
            count: count as u64,
            max: MAX_TETRAHEDRA as u64,
        });
    }
    Ok((count, samples, count as u64 * 16))
}

/// Decodes a connectivity chunk: the block's sample count and the tetrahedra (every index is
/// checked to be below the sample count).
pub fn decode_connectivity(bytes: &[u8]) -> Result<(u32, Vec<[u32; 4]>)> {
    let (_, samples, len) = connectivity_header(bytes)?;
    let raw = zstd_decompress_exact(&bytes[16..], len as usize, PackError::payload)?;
    let mut tets = Vec::with_capacity(raw.len() / 16);
    for (k, c) in raw.chunks_exact(16).enumerate() {
        let mut t = [0u32; 4];
        for (j, v) in t.iter_mut().enumerate() {
            *v = u32::from_le_bytes([c[4 * j], c[4 * j + 1], c[4 * j + 2], c[4 * j + 3]]);
            if *v >= samples {
                return Err(PackError::payload(format!(
                    "tetrahedron {k} index {} ≥ {samples} samples",
                    *v
                )));
            }
        }
        tets.push(t);
    }
    Ok((samples, tets))
}
