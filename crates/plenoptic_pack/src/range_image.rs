//! Range images (thesis ch. 6): per base view and time key, cubes of radiance, distance,
//! object id and normal, each stored as its own KTX2 chunk; since version 2 also the diffuse
//! lighting and the non-diffuse radiance (`docs/architecture.md`, "Pack v2"), so that the
//! runtime can multiply the lighting by the material's albedo at screen resolution.

use glam::{Vec2, Vec3};
use half::f16;
use ktx2::Format;

use crate::cube::{
    from_snorm16, oct_decode, oct_encode, oct_snorm16_pack, rgb9e5_pack, rgb9e5_unpack,
};
use crate::error::{PackError, Result};
use crate::ktx::{read_cube, write_cube};

/// One cube of `6·face_size²` texels of `T`, faces in KTX2 order, rows top to bottom
/// (see [`crate::cube`] for the addressing).
#[derive(Clone, Debug, PartialEq)]
pub struct CubeImage<T> {
    /// Texels per face edge.
    pub face_size: u32,
    /// `6·face_size²` texels: face-major, then row-major.
    pub texels: Vec<T>,
}

impl<T: Clone> CubeImage<T> {
    /// A cube with every texel set to `value`.
    pub fn filled(face_size: u32, value: T) -> Self {
        let n = face_size as usize;
        Self {
            face_size,
            texels: vec![value; 6 * n * n],
        }
    }

    /// A cube whose texel `i` is `f(i, direction of texel i)`.
    pub fn from_fn(face_size: u32, mut f: impl FnMut(usize, Vec3) -> T) -> Self {
        let n = face_size as usize;
        Self {
            face_size,
            texels: (0..6 * n * n)
                .map(|i| f(i, crate::cube::texel_direction(face_size, i)))
                .collect(),
        }
    }

    /// The texel the direction `dir` falls in (nearest, no filtering).
    pub fn lookup(&self, dir: Vec3) -> Option<&T> {
        self.texels
            .get(crate::cube::direction_to_texel(self.face_size, dir))
    }

    fn check(&self) -> Result<()> {
        let n = self.face_size as usize;
        if self.texels.len() != 6 * n * n {
            return Err(PackError::input(format!(
                "cube of face size {n} has {} texels, expected {}",
                self.texels.len(),
                6 * n * n
            )));
        }
        Ok(())
    }
}

/// HDR radiance per texel, linear RGB.
pub type RadianceCube = CubeImage<Vec3>;
/// Distance from the base view along each texel's ray, metres (`f32::INFINITY` or a large
/// value where the ray escapes).
pub type DistanceCube = CubeImage<f32>;
/// Object id per texel (0: background).
pub type ObjectIdCube = CubeImage<u32>;
/// Unit world-space normal per texel.
pub type NormalCube = CubeImage<Vec3>;

/// How radiance is stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RadianceFormat {
    /// `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` (123): 4 bytes; per-channel error ≤ max(r,g,b)·2⁻⁹.
    #[default]
    Rgb9e5,
    /// `VK_FORMAT_R16G16B16A16_SFLOAT` (97), alpha 1: 8 bytes; relative error ≤ 2⁻¹¹.
    Rgba16Float,
}

/// How distance is stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistanceFormat {
    /// `VK_FORMAT_R32_SFLOAT` (100): exact.
    #[default]
    R32Float,
    /// `VK_FORMAT_R16_SFLOAT` (76): relative error ≤ 2⁻¹¹ within 6.1e-5..65504 m.
    R16Float,
}

/// How object ids are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ObjectIdFormat {
    /// `VK_FORMAT_R32_UINT` (98): exact.
    #[default]
    R32Uint,
    /// `VK_FORMAT_R16_UINT` (74): exact; ids above 65535 are rejected by the encoder.
    R16Uint,
}

/// How normals are stored (octahedral encoding in both cases).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalFormat {
    /// `VK_FORMAT_R16G16_SNORM` (78): angular error ≤ 1e-4 rad. Sampling it on the GPU needs
    /// wgpu's `TEXTURE_FORMAT_16BIT_NORM` feature (native backends).
    #[default]
    Rg16Snorm,
    /// `VK_FORMAT_R16G16_SFLOAT` (83): angular error ≤ 2e-3 rad; core in WebGPU.
    Rg16Float,
}

impl RadianceFormat {
    /// The vkFormat.
    pub fn vk_format(self) -> Format {
        match self {
            RadianceFormat::Rgb9e5 => Format::E5B9G9R9_UFLOAT_PACK32,
            RadianceFormat::Rgba16Float => Format::R16G16B16A16_SFLOAT,
        }
    }
}
impl DistanceFormat {
    /// The vkFormat.
    pub fn vk_format(self) -> Format {
        match self {
            DistanceFormat::R32Float => Format::R32_SFLOAT,
            DistanceFormat::R16Float => Format::R16_SFLOAT,
        }
    }
}
impl ObjectIdFormat {
    /// The vkFormat.
    pub fn vk_format(self) -> Format {
        match self {
            ObjectIdFormat::R32Uint => Format::R32_UINT,
            ObjectIdFormat::R16Uint => Format::R16_UINT,
        }
    }
}
impl NormalFormat {
    /// The vkFormat.
    pub fn vk_format(self) -> Format {
        match self {
            NormalFormat::Rg16Snorm => Format::R16G16_SNORM,
            NormalFormat::Rg16Float => Format::R16G16_SFLOAT,
        }
    }
}

/// vkFormats a radiance cube may have.
pub const RADIANCE_FORMATS: [Format; 2] =
    [Format::E5B9G9R9_UFLOAT_PACK32, Format::R16G16B16A16_SFLOAT];
/// vkFormats a distance cube may have.
pub const DISTANCE_FORMATS: [Format; 2] = [Format::R32_SFLOAT, Format::R16_SFLOAT];
/// vkFormats an object-id cube may have.
pub const OBJECT_ID_FORMATS: [Format; 2] = [Format::R32_UINT, Format::R16_UINT];
/// vkFormats a normal cube may have.
pub const NORMAL_FORMATS: [Format; 2] = [Format::R16G16_SNORM, Format::R16G16_SFLOAT];

/// The four storage formats of a range image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CubeFormats {
    /// Radiance format.
    pub radiance: RadianceFormat,
    /// Distance format.
    pub distance: DistanceFormat,
    /// Object-id format.
    pub object_id: ObjectIdFormat,
    /// Normal format.
    pub normal: NormalFormat,
}

fn h(x: f32) -> [u8; 2] {
    f16::from_f32(x).to_le_bytes()
}
fn unh(b: &[u8]) -> f32 {
    f16::from_le_bytes([b[0], b[1]]).to_f32()
}
fn le32(b: &[u8]) -> [u8; 4] {
    [b[0], b[1], b[2], b[3]]
}

/// Encodes a radiance cube as a KTX2 chunk.
pub fn encode_radiance(cube: &RadianceCube, format: RadianceFormat) -> Result<Vec<u8>> {
    cube.check()?;
    let mut raw = Vec::with_capacity(cube.texels.len() * 8);
    for c in &cube.texels {
        match format {
            RadianceFormat::Rgb9e5 => raw.extend_from_slice(&rgb9e5_pack(*c).to_le_bytes()),
            RadianceFormat::Rgba16Float => {
                for x in [c.x, c.y, c.z, 1.0] {
                    raw.extend_from_slice(&h(x.clamp(-65504.0, 65504.0)));
                }
            }
        }
    }
    write_cube(format.vk_format(), cube.face_size, &raw)
}

/// Decodes a radiance cube chunk (either radiance format).
pub fn decode_radiance(bytes: &[u8]) -> Result<RadianceCube> {
    let (info, raw) = read_cube(bytes, &RADIANCE_FORMATS)?;
    let texels = if info.format == Format::E5B9G9R9_UFLOAT_PACK32 {
        raw.chunks_exact(4)
            .map(|b| rgb9e5_unpack(u32::from_le_bytes(le32(b))))
            .collect()
    } else {
        raw.chunks_exact(8)
            .map(|b| Vec3::new(unh(&b[0..2]), unh(&b[2..4]), unh(&b[4..6])))
            .collect()
    };
    Ok(CubeImage {
        face_size: info.face_size,
        texels,
    })
}

/// Encodes a distance cube as a KTX2 chunk.
pub fn encode_distance(cube: &DistanceCube, format: DistanceFormat) -> Result<Vec<u8>> {
    cube.check()?;
    let mut raw = Vec::with_capacity(cube.texels.len() * 4);
    for &d in &cube.texels {
        match format {
            DistanceFormat::R32Float => raw.extend_from_slice(&d.to_le_bytes()),
            DistanceFormat::R16Float => raw.extend_from_slice(&h(d)),
        }
    }
    write_cube(format.vk_format(), cube.face_size, &raw)
}

/// Decodes a distance cube chunk (either distance format).
pub fn decode_distance(bytes: &[u8]) -> Result<DistanceCube> {
    let (info, raw) = read_cube(bytes, &DISTANCE_FORMATS)?;
    let texels = if info.format == Format::R32_SFLOAT {
        raw.chunks_exact(4)
            .map(|b| f32::from_le_bytes(le32(b)))
            .collect()
    } else {
        raw.chunks_exact(2).map(unh).collect()
    };
    Ok(CubeImage {
        face_size: info.face_size,
        texels,
    })
}

/// Encodes an object-id cube as a KTX2 chunk.
pub fn encode_object_id(cube: &ObjectIdCube, format: ObjectIdFormat) -> Result<Vec<u8>> {
    cube.check()?;
    let mut raw = Vec::with_capacity(cube.texels.len() * 4);
    for &id in &cube.texels {
        match format {
            ObjectIdFormat::R32Uint => raw.extend_from_slice(&id.to_le_bytes()),
            ObjectIdFormat::R16Uint => {
                let id16 = u16::try_from(id).map_err(|_| {
                    PackError::input(format!("object id {id} does not fit R16_UINT"))
                })?;
                raw.extend_from_slice(&id16.to_le_bytes());
            }
        }
    }
    write_cube(format.vk_format(), cube.face_size, &raw)
}

/// Decodes an object-id cube chunk (either id format).
pub fn decode_object_id(bytes: &[u8]) -> Result<ObjectIdCube> {
    let (info, raw) = read_cube(bytes, &OBJECT_ID_FORMATS)?;
    let texels = if info.format == Format::R32_UINT {
        raw.chunks_exact(4)
            .map(|b| u32::from_le_bytes(le32(b)))
            .collect()
    } else {
        raw.chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32)
            .collect()
    };
    Ok(CubeImage {
        face_size: info.face_size,
        texels,
    })
}

/// Encodes a normal cube (octahedral) as a KTX2 chunk.
pub fn encode_normal(cube: &NormalCube, format: NormalFormat) -> Result<Vec<u8>> {
    cube.check()?;
    let mut raw = Vec::with_capacity(cube.texels.len() * 4);
    for n in &cube.texels {
        let e = oct_encode(*n);
        match format {
            NormalFormat::Rg16Snorm => raw.extend_from_slice(&oct_snorm16_pack(*n).to_le_bytes()),
            NormalFormat::Rg16Float => {
                raw.extend_from_slice(&h(e.x));
                raw.extend_from_slice(&h(e.y));
            }
        }
    }
    write_cube(format.vk_format(), cube.face_size, &raw)
}

/// Decodes a normal cube chunk (either normal format) to unit vectors.
pub fn decode_normal(bytes: &[u8]) -> Result<NormalCube> {
    let (info, raw) = read_cube(bytes, &NORMAL_FORMATS)?;
    let snorm = info.format == Format::R16G16_SNORM;
    let texels = raw
        .chunks_exact(4)
        .map(|b| {
            let e = if snorm {
                Vec2::new(
                    from_snorm16(i16::from_le_bytes([b[0], b[1]])),
                    from_snorm16(i16::from_le_bytes([b[2], b[3]])),
                )
            } else {
                Vec2::new(unh(&b[0..2]), unh(&b[2..4]))
            };
            oct_decode(e)
        })
        .collect();
    Ok(CubeImage {
        face_size: info.face_size,
        texels,
    })
}

/// The cubes of one base view at one time key (thesis §6.1: a range image is radiance plus
/// range; id and normal serve reprojection and masks; lighting and the non-diffuse part are
/// version 2's split of the radiance).
///
/// Per texel, `radiance ≈ albedo · lighting + non_diffuse`, where `albedo` is the surface's
/// diffuse albedo, `(1 − metallic)(1 − transmission) · base colour`.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeImage {
    /// Radiance: what image and volume modes warp (the thesis's input).
    pub radiance: RadianceCube,
    /// Diffuse lighting: the factor by which the diffuse albedo turns into outgoing radiance
    /// (direct light through the Lambertian lobe plus indirect diffuse light). Texels whose
    /// surface has no diffuse albedo carry their neighbours' lighting on the same object, or
    /// zero.
    pub lighting: RadianceCube,
    /// Emission plus the specular part of the radiance, as seen from the base view.
    pub non_diffuse: RadianceCube,
    /// Distance along each texel's ray.
    pub distance: DistanceCube,
    /// Object ids.
    pub object_id: ObjectIdCube,
    /// Normals.
    pub normal: NormalCube,
}

impl RangeImage {
    /// An empty range image (black, infinitely far, background, +Z normals) of face size `n`.
    pub fn new(face_size: u32) -> Self {
        RangeImage {
            radiance: CubeImage::filled(face_size, Vec3::ZERO),
            lighting: CubeImage::filled(face_size, Vec3::ZERO),
            non_diffuse: CubeImage::filled(face_size, Vec3::ZERO),
            distance: CubeImage::filled(face_size, f32::INFINITY),
            object_id: CubeImage::filled(face_size, 0),
            normal: CubeImage::filled(face_size, Vec3::Z),
        }
    }

    /// Face size of the radiance cube.
    pub fn face_size(&self) -> u32 {
        self.radiance.face_size
    }
}
