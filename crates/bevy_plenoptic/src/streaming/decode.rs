//! Reading and decoding, run on the I/O task pool: a key's cubes to GPU-ready texel bytes
//! (checksum, zstd, KTX2), or for the CPU backend to the cubes `plenoptic_recon` looks up; a
//! temporal-volume block binned by direction; and the bytes each will occupy, known from the
//! pack's directory before the read (see the [module doc](super)).

use plenoptic_pack::{ChunkKind, PackReader, cube, ktx, range_image};
use plenoptic_recon::streamed::{CUBE_KINDS, StreamedCube, read_cube};

use super::schedule::{BlockRef, KeyRef};

/// The GPU-ready texel bytes of one key (tightly packed faces +X, −X, +Y, −Y, +Z, −Z).
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedKey {
    /// Face size in texels.
    pub face_size: u32,
    /// Radiance texels (the pack's format, RGB9E5 by default).
    pub radiance: Vec<u8>,
    /// Distance texels (R32F or R16F).
    pub distance: Vec<u8>,
    /// Object id texels (R32Uint or R16Uint).
    pub object_id: Vec<u8>,
    /// Normal texels, when the pack has them.
    pub normal: Option<Vec<u8>>,
    /// Diffuse-lighting texels (pack 2.0; the radiance formats).
    pub lighting: Option<Vec<u8>>,
    /// Non-diffuse radiance texels (pack 2.0; the radiance formats).
    pub non_diffuse: Option<Vec<u8>>,
    /// Per stored light group (pack 4.2, `LightGroupsEntry::stored`), its lighting and
    /// non-diffuse texels (the radiance formats); empty for a pack without groups.
    pub groups: Vec<[Vec<u8>; 2]>,
    /// On the CPU backend, the key's cubes decoded for `plenoptic_recon` instead of the
    /// GPU's texel bytes above (which are then empty): what its reconstructor looks up
    /// ([`decode_cpu_key`]).
    pub cpu: Vec<(ChunkKind, StreamedCube)>,
}

impl DecodedKey {
    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.radiance.len()
            + self.distance.len()
            + self.object_id.len()
            + self.normal.as_ref().map_or(0, Vec::len)
            + self.lighting.as_ref().map_or(0, Vec::len)
            + self.non_diffuse.as_ref().map_or(0, Vec::len)
            + self
                .groups
                .iter()
                .map(|g| g[0].len() + g[1].len())
                .sum::<usize>()) as u64
            + self.cpu.iter().map(|(_, c)| c.bytes()).sum::<u64>()
    }
}

/// Reads and decodes one key: its radiance, distance, object-id (and normal, lighting and
/// non-diffuse) cubes to
/// GPU-ready texel bytes. The error names the failing chunk.
pub fn decode_key(pack: &PackReader, (view, key): KeyRef) -> Result<DecodedKey, (String, String)> {
    let name = |kind: ChunkKind| format!("{kind:?} view {view} key {key}");
    type Read = Result<Option<(u32, Vec<u8>)>, (String, String)>;
    let read = |kind: ChunkKind| -> Read {
        let Some(i) = pack.find(kind, view, key) else {
            return Ok(None);
        };
        let fail = |e: plenoptic_pack::PackError| (name(kind), e.to_string());
        let bytes = pack.chunk_bytes(i).map_err(fail)?;
        let formats = match kind {
            ChunkKind::RadianceCube
            | ChunkKind::LightingCube
            | ChunkKind::NonDiffuseCube
            | ChunkKind::GroupLighting(_)
            | ChunkKind::GroupNonDiffuse(_) => &range_image::RADIANCE_FORMATS[..],
            ChunkKind::DistanceCube => &range_image::DISTANCE_FORMATS[..],
            ChunkKind::ObjectIdCube => &range_image::OBJECT_ID_FORMATS[..],
            _ => &range_image::NORMAL_FORMATS[..],
        };
        let (info, raw) = ktx::read_cube(&bytes, formats).map_err(fail)?;
        Ok(Some((info.face_size, raw)))
    };
    let required =
        |kind: ChunkKind| read(kind)?.ok_or_else(|| (name(kind), "not in the pack".to_string()));
    let (face_size, radiance) = required(ChunkKind::RadianceCube)?;
    let distance = required(ChunkKind::DistanceCube)?.1;
    let object_id = required(ChunkKind::ObjectIdCube)?.1;
    let normal = read(ChunkKind::NormalCube)?.map(|n| n.1);
    let lighting = read(ChunkKind::LightingCube)?.map(|n| n.1);
    let non_diffuse = read(ChunkKind::NonDiffuseCube)?.map(|n| n.1);
    let groups = group_kinds(pack)
        .map(|[l, n]| Ok([required(l)?.1, required(n)?.1]))
        .collect::<Result<_, (String, String)>>()?;
    Ok(DecodedKey {
        face_size,
        radiance,
        distance,
        object_id,
        normal,
        lighting,
        non_diffuse,
        groups,
        cpu: Vec::new(),
    })
}

/// The chunk kinds of each stored light group's lighting and non-diffuse cubes.
fn group_kinds(pack: &PackReader) -> impl Iterator<Item = [ChunkKind; 2]> {
    let stored = pack.manifest().light_groups.as_ref().map(|e| e.stored());
    stored
        .unwrap_or_default()
        .map(|g| [ChunkKind::GroupLighting(g), ChunkKind::GroupNonDiffuse(g)])
}

/// Reads and decodes one key for the CPU backend: its cubes as `plenoptic_recon` looks them
/// up ([`plenoptic_recon::streamed`]), none of the GPU's texel bytes. The error names the
/// failing chunk.
pub fn decode_cpu_key(
    pack: &PackReader,
    (view, key): KeyRef,
) -> Result<DecodedKey, (String, String)> {
    let mut cpu = Vec::new();
    for kind in CUBE_KINDS {
        let name = || format!("{kind:?} view {view} key {key}");
        match read_cube(pack, kind, view, key) {
            Ok(Some(c)) => cpu.push((kind, c)),
            Ok(None)
                if matches!(
                    kind,
                    ChunkKind::RadianceCube | ChunkKind::DistanceCube | ChunkKind::ObjectIdCube
                ) =>
            {
                return Err((name(), "not in the pack".to_string()));
            }
            Ok(None) => {}
            Err(e) => return Err((name(), e.to_string())),
        }
    }
    let face_size = match cpu.first() {
        Some((_, StreamedCube::Colour(c))) => c.face_size,
        _ => 0,
    };
    Ok(DecodedKey {
        face_size,
        radiance: Vec::new(),
        distance: Vec::new(),
        object_id: Vec::new(),
        normal: None,
        lighting: None,
        non_diffuse: None,
        groups: Vec::new(),
        cpu,
    })
}

/// Bytes a key occupies once decoded for the CPU backend ([`decode_cpu_key`]), from the
/// directory and the pack's face size (known before reading): 12 per texel of a colour or
/// normal cube, 4 of a distance or id cube. Saturates (a hostile face size then exceeds any
/// budget and the key is never read).
pub fn cpu_key_bytes(pack: &PackReader, (view, key): KeyRef) -> u64 {
    let face = u64::from(pack.manifest().bake.cube_face_size);
    let texels = face.saturating_mul(face).saturating_mul(6);
    CUBE_KINDS
        .into_iter()
        .filter(|&k| pack.find(k, view, key).is_some())
        .map(|k| match k {
            ChunkKind::DistanceCube | ChunkKind::ObjectIdCube => texels.saturating_mul(4),
            _ => texels.saturating_mul(12),
        })
        .fold(0u64, u64::saturating_add)
}

/// Bytes a key will occupy once decoded, from the directory (known before reading).
pub fn key_bytes(pack: &PackReader, (view, key): KeyRef) -> u64 {
    CUBE_KINDS
        .into_iter()
        .chain(group_kinds(pack).flatten())
        .filter_map(|k| pack.find(k, view, key))
        .map(|i| pack.entries()[i].uncompressed_length)
        .sum()
}

/// Face size of the direction bins of a [`BinnedVolume`] (`plenoptic_recon`'s
/// `VolumeIndex` bins the same way).
pub const VOLUME_BIN_FACE: u32 = 16;
/// Number of bin offsets of a [`BinnedVolume`]: one per bin and the end.
pub const VOLUME_BIN_OFFSETS: usize = 6 * (VOLUME_BIN_FACE * VOLUME_BIN_FACE) as usize + 1;
/// 32-bit words per sample of a [`BinnedVolume`].
pub const VOLUME_SAMPLE_WORDS: usize = 12;

/// A temporal-volume block ready for the GPU: its samples sorted by direction bin (a cube of
/// [`VOLUME_BIN_FACE`]² texels per face, bin = `cube::direction_to_texel`), each as
/// [`VOLUME_SAMPLE_WORDS`] words `(direction.xyz, radius, radiance, normal, 0, distance, t,
/// object id, lighting, non-diffuse)` (floats as their bits; radiance, lighting and
/// non-diffuse RGB9E5, as the pack stores them; the normal octahedral as two snorm16, as the
/// key textures' normals), and the offset of each bin's first sample.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedVolume {
    /// Sample words, bin by bin.
    pub words: Vec<u32>,
    /// [`VOLUME_BIN_OFFSETS`] sample offsets: bin `b` holds samples `bins[b]..bins[b + 1]`.
    pub bins: Vec<u32>,
    /// Per sample (in `words`' order), per stored light group, its lighting and non-diffuse
    /// (RGB9E5): `2 · groups` words a sample; empty for a pack without groups.
    pub groups: Vec<u32>,
}

impl BinnedVolume {
    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        4 * (self.words.len() + self.bins.len() + self.groups.len()) as u64
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.words.len() / VOLUME_SAMPLE_WORDS
    }

    /// True if it has no samples.
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }
}

/// Reads, decodes and bins one temporal-volume block. The error names the chunk.
pub fn decode_volume(
    pack: &PackReader,
    (view, bucket): BlockRef,
) -> Result<BinnedVolume, (String, String)> {
    let block = pack.volume_block(view, bucket).map_err(|e| {
        (
            format!("VolumeBlock view {view} bucket {bucket}"),
            e.to_string(),
        )
    })?;
    let bin: Vec<usize> = block
        .samples
        .iter()
        .map(|s| cube::direction_to_texel(VOLUME_BIN_FACE, s.direction))
        .collect();
    let mut bins = vec![0u32; VOLUME_BIN_OFFSETS];
    for &b in &bin {
        bins[b + 1] += 1;
    }
    for i in 0..VOLUME_BIN_OFFSETS - 1 {
        bins[i + 1] += bins[i];
    }
    let stored = pack.manifest().light_groups.as_ref().map(|e| e.stored());
    let layers = stored
        .unwrap_or_default()
        .map(|g| {
            let layer = pack.group_volume(view, bucket, g);
            match layer {
                Ok(l) if l.len() == block.samples.len() => Ok(l),
                Ok(_) => Err("its sample count differs from the block's".to_string()),
                Err(e) => Err(e.to_string()),
            }
            .map_err(|e| (format!("GroupVolume({g}) view {view} bucket {bucket}"), e))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut fill = bins.clone();
    let mut words = vec![0u32; block.samples.len() * VOLUME_SAMPLE_WORDS];
    let mut groups = vec![0u32; block.samples.len() * 2 * layers.len()];
    for (i, (s, &b)) in block.samples.iter().zip(&bin).enumerate() {
        let at = fill[b] as usize;
        for (g, layer) in layers.iter().enumerate() {
            let o = 2 * (at * layers.len() + g);
            groups[o] = cube::rgb9e5_pack(layer[i][0]);
            groups[o + 1] = cube::rgb9e5_pack(layer[i][1]);
        }
        let o = at * VOLUME_SAMPLE_WORDS;
        fill[b] += 1;
        let f = [s.direction.x, s.direction.y, s.direction.z, s.radius];
        for (w, x) in words[o..o + 4].iter_mut().zip(f) {
            *w = x.to_bits();
        }
        words[o + 4] = cube::rgb9e5_pack(s.radiance);
        words[o + 5] = cube::oct_snorm16_pack(s.normal);
        words[o + 7] = s.distance.to_bits();
        words[o + 8] = s.t.to_bits();
        words[o + 9] = s.object_id;
        words[o + 10] = cube::rgb9e5_pack(s.lighting);
        words[o + 11] = cube::rgb9e5_pack(s.non_diffuse);
    }
    Ok(BinnedVolume {
        words,
        bins,
        groups,
    })
}

/// Bytes a volume block will occupy once binned, from the directory (known before reading):
/// its samples at 48 bytes (against [`plenoptic_pack::volume::SAMPLE_BYTES`] stored) and 8
/// more per stored light group, plus the bin offsets.
pub fn volume_bytes(pack: &PackReader, (view, bucket): BlockRef) -> Option<u64> {
    let i = pack.find(ChunkKind::VolumeBlock, view, bucket)?;
    let samples =
        pack.entries()[i].uncompressed_length / plenoptic_pack::volume::SAMPLE_BYTES as u64;
    let groups = group_kinds(pack).count() as u64;
    Some(samples * 4 * (VOLUME_SAMPLE_WORDS as u64 + 2 * groups) + 4 * VOLUME_BIN_OFFSETS as u64)
}
