//! Proxy geometry and animation tracks: what the runtime's mask pass and motion mapping need
//! (see `docs/pack-format.md`, "Proxy mesh" and "Animation tracks"). Storage only; evaluation
//! lives in `plenoptic_scene`.

use glam::{Quat, Vec3};

use crate::bytes::{ByteReader, PutLe, zstd_compress, zstd_decompress_exact};
use crate::error::{PackError, Result};

/// Most vertices one proxy mesh may have.
pub const MAX_PROXY_VERTICES: u32 = 1 << 24;
/// Most indices one proxy mesh may have.
pub const MAX_PROXY_INDICES: u32 = 3 << 24;
/// Largest uncompressed animation-tracks payload, bytes.
pub const MAX_TRACK_BYTES: u64 = 256 << 20;

const MESH_MAGIC: [u8; 4] = *b"PPM1";
const TRACKS_MAGIC: [u8; 4] = *b"PAT1";

/// A triangle mesh in object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProxyMesh {
    /// The object the mesh belongs to.
    pub object_id: u32,
    /// Vertex positions, object space, metres. Stored as f32: exact.
    pub positions: Vec<Vec3>,
    /// Triangle list: three indices per triangle into `positions`. Exact.
    pub indices: Vec<u32>,
    /// Optional per-vertex normals (same length as `positions`). Exact.
    pub normals: Option<Vec<Vec3>>,
}

fn put_vec3s(out: &mut Vec<u8>, v: &[Vec3]) {
    for p in v {
        out.put_f32(p.x);
        out.put_f32(p.y);
        out.put_f32(p.z);
    }
}

fn vec3(r: &mut ByteReader<'_>) -> Result<Vec3> {
    Ok(Vec3::new(r.f32()?, r.f32()?, r.f32()?))
}

/// Encodes a proxy mesh; returns the chunk bytes and the uncompressed length.
pub fn encode_proxy_mesh(mesh: &ProxyMesh) -> Result<(Vec<u8>, u64)> {
    let vc = mesh.positions.len();
    let ic = mesh.indices.len();
    if vc > MAX_PROXY_VERTICES as usize || ic > MAX_PROXY_INDICES as usize || !ic.is_multiple_of(3)
    {
        return Err(PackError::input(format!(
            "proxy mesh with {vc} vertices and {ic} indices (caps {MAX_PROXY_VERTICES}, {MAX_PROXY_INDICES}; indices a multiple of 3)"
        )));
    }
    if let Some(i) = mesh.indices.iter().find(|&&i| i as usize >= vc) {
        return Err(PackError::input(format!("proxy index {i} ≥ {vc} vertices")));
    }
    if mesh.normals.as_ref().is_some_and(|n| n.len() != vc) {
        return Err(PackError::input(
            "proxy normals and positions differ in length",
        ));
    }
    let mut raw = Vec::new();
    put_vec3s(&mut raw, &mesh.positions);
    for &i in &mesh.indices {
        raw.put_u32(i);
    }
    if let Some(n) = &mesh.normals {
        put_vec3s(&mut raw, n);
    }
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&MESH_MAGIC);
    bytes.put_u32(mesh.object_id);
    bytes.put_u32(vc as u32);
    bytes.put_u32(ic as u32);
    bytes.put_u32(mesh.normals.is_some() as u32);
    bytes.put_u32(0);
    bytes.extend_from_slice(&zstd_compress(&raw)?);
    Ok((bytes, raw.len() as u64))
}

/// Reads a proxy mesh header: (object id, vertices, indices, has normals, uncompressed length).
pub(crate) fn proxy_header(bytes: &[u8]) -> Result<(u32, u32, u32, bool, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != MESH_MAGIC {
        return Err(r.fail("not a proxy mesh (bad magic)"));
    }
    let id = r.u32()?;
    let vc = r.u32()?;
    let ic = r.u32()?;
    let flags = r.u32()?;
    let reserved = r.u32()?;
    if flags > 1 || reserved != 0 {
        return Err(r.fail(format!("unknown flags {flags:#x} / reserved {reserved:#x}")));
    }
    if vc > MAX_PROXY_VERTICES || ic > MAX_PROXY_INDICES {
        return Err(PackError::CountTooLarge {
            what: "proxy mesh vertices/indices",
            count: vc.max(ic) as u64,
            max: MAX_PROXY_VERTICES as u64,
        });
    }
    if !ic.is_multiple_of(3) {
        return Err(r.fail(format!("{ic} indices is not a whole number of triangles")));
    }
    let has_normals = flags == 1;
    let len = vc as u64 * 12 * (1 + has_normals as u64) + ic as u64 * 4;
    Ok((id, vc, ic, has_normals, len))
}

/// Decodes a proxy mesh chunk (indices are checked against the vertex count).
pub fn decode_proxy_mesh(bytes: &[u8]) -> Result<ProxyMesh> {
    let (object_id, vc, ic, has_normals, len) = proxy_header(bytes)?;
    let raw = zstd_decompress_exact(&bytes[24..], len as usize, PackError::payload)?;
    let mut r = ByteReader::payload(&raw);
    let positions = (0..vc).map(|_| vec3(&mut r)).collect::<Result<Vec<_>>>()?;
    let indices = (0..ic).map(|_| r.u32()).collect::<Result<Vec<_>>>()?;
    if let Some(i) = indices.iter().find(|&&i| i >= vc) {
        return Err(PackError::payload(format!(
            "proxy index {i} ≥ {vc} vertices"
        )));
    }
    let normals = if has_normals {
        Some((0..vc).map(|_| vec3(&mut r)).collect::<Result<Vec<_>>>()?)
    } else {
        None
    };
    Ok(ProxyMesh {
        object_id,
        positions,
        indices,
        normals,
    })
}

/// How a track interpolates between keys (glTF `sampler.interpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold the previous key.
    Step,
    /// Linear (slerp for rotations).
    Linear,
    /// Cubic Hermite spline; values are `[in-tangent, value, out-tangent]` per key, as glTF.
    CubicSpline,
}

impl Interpolation {
    fn code(self) -> u8 {
        match self {
            Interpolation::Step => 0,
            Interpolation::Linear => 1,
            Interpolation::CubicSpline => 2,
        }
    }
    fn from_code(c: u8) -> Option<Self> {
        match c {
            0 => Some(Interpolation::Step),
            1 => Some(Interpolation::Linear),
            2 => Some(Interpolation::CubicSpline),
            _ => None,
        }
    }
    /// Values stored per key: 3 for cubic splines, 1 otherwise.
    pub fn values_per_key(self) -> usize {
        if self == Interpolation::CubicSpline {
            3
        } else {
            1
        }
    }
}

/// One keyframed channel. `values.len() == times.len() · interpolation.values_per_key()`.
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T> {
    /// Interpolation.
    pub interpolation: Interpolation,
    /// Key times, seconds, non-decreasing. Exact.
    pub times: Vec<f32>,
    /// Key values (with tangents for cubic splines). Exact.
    pub values: Vec<T>,
}

/// The TRS tracks of one object (object space → world space).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectTracks {
    /// The object.
    pub object_id: u32,
    /// Translation track.
    pub translation: Option<Track<Vec3>>,
    /// Rotation track (quaternion x, y, z, w).
    pub rotation: Option<Track<Quat>>,
    /// Scale track.
    pub scale: Option<Track<Vec3>>,
}

/// The animation tracks of every animated object: one chunk per pack.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationTracks {
    /// Per object.
    pub objects: Vec<ObjectTracks>,
}

fn put_track<const N: usize>(
    out: &mut Vec<u8>,
    target: u8,
    interp: Interpolation,
    times: &[f32],
    values: &[[f32; N]],
) -> Result<()> {
    if values.len() != times.len() * interp.values_per_key() {
        return Err(PackError::input(format!(
            "track has {} times but {} values for {interp:?}",
            times.len(),
            values.len()
        )));
    }
    out.put_u8(target);
    out.put_u8(interp.code());
    out.put_u16(0);
    out.put_u32(times.len() as u32);
    for &t in times {
        out.put_f32(t);
    }
    for v in values {
        for &c in v {
            out.put_f32(c);
        }
    }
    Ok(())
}

/// Encodes the animation tracks; returns the chunk bytes and the uncompressed length.
pub fn encode_tracks(tracks: &AnimationTracks) -> Result<(Vec<u8>, u64)> {
    let mut raw = Vec::new();
    for o in &tracks.objects {
        raw.put_u32(o.object_id);
        let count =
            o.translation.is_some() as u32 + o.rotation.is_some() as u32 + o.scale.is_some() as u32;
        raw.put_u32(count);
        if let Some(t) = &o.translation {
            let v: Vec<[f32; 3]> = t.values.iter().map(|v| v.to_array()).collect();
            put_track(&mut raw, 0, t.interpolation, &t.times, &v)?;
        }
        if let Some(t) = &o.rotation {
            let v: Vec<[f32; 4]> = t.values.iter().map(|v| v.to_array()).collect();
            put_track(&mut raw, 1, t.interpolation, &t.times, &v)?;
        }
        if let Some(t) = &o.scale {
            let v: Vec<[f32; 3]> = t.values.iter().map(|v| v.to_array()).collect();
            put_track(&mut raw, 2, t.interpolation, &t.times, &v)?;
        }
    }
    if raw.len() as u64 > MAX_TRACK_BYTES {
        return Err(PackError::input("animation tracks exceed the size cap"));
    }
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&TRACKS_MAGIC);
    bytes.put_u32(tracks.objects.len() as u32);
    bytes.put_u64(raw.len() as u64);
    bytes.extend_from_slice(&zstd_compress(&raw)?);
    Ok((bytes, raw.len() as u64))
}

/// Reads the tracks header: (object count, uncompressed length).
pub(crate) fn tracks_header(bytes: &[u8]) -> Result<(u32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != TRACKS_MAGIC {
        return Err(r.fail("not an animation-tracks chunk (bad magic)"));
    }
    let objects = r.u32()?;
    let len = r.u64()?;
    if len > MAX_TRACK_BYTES {
        return Err(PackError::CountTooLarge {
            what: "animation track bytes",
            count: len,
            max: MAX_TRACK_BYTES,
        });
    }
    // Each object takes at least 8 bytes.
    if objects as u64 * 8 > len {
        return Err(PackError::CountTooLarge {
            what: "animated objects",
            count: objects as u64,
            max: len / 8,
        });
    }
    Ok((objects, len))
}

/// A decoded track: target, interpolation, times, values.
type RawTrack<const N: usize> = (u8, Interpolation, Vec<f32>, Vec<[f32; N]>);

fn read_track<const N: usize>(r: &mut ByteReader<'_>) -> Result<RawTrack<N>> {
    let target = r.u8()?;
    let interp =
        Interpolation::from_code(r.u8()?).ok_or_else(|| r.fail("unknown interpolation"))?;
    if r.u16()? != 0 {
        return Err(r.fail("reserved track field is not 0"));
    }
    let keys = r.u32()? as usize;
    let nvals = keys.saturating_mul(interp.values_per_key());
    // Bound by the bytes that are really there before allocating.
    if keys
        .saturating_add(nvals.saturating_mul(N))
        .saturating_mul(4)
        > r.remaining()
    {
        return Err(r.fail(format!("track of {keys} keys runs past the payload")));
    }
    let times = (0..keys).map(|_| r.f32()).collect::<Result<Vec<_>>>()?;
    let mut values = Vec::with_capacity(nvals);
    for _ in 0..nvals {
        let mut v = [0f32; N];
        for c in &mut v {
            *c = r.f32()?;
        }
        values.push(v);
    }
    Ok((target, interp, times, values))
}

/// Decodes the animation-tracks chunk.
pub fn decode_tracks(bytes: &[u8]) -> Result<AnimationTracks> {
    let (count, len) = tracks_header(bytes)?;
    let raw = zstd_decompress_exact(&bytes[16..], len as usize, PackError::payload)?;
    let mut r = ByteReader::payload(&raw);
    let mut objects = Vec::with_capacity((count as usize).min(1024));
    for _ in 0..count {
        let mut o = ObjectTracks {
            object_id: r.u32()?,
            ..Default::default()
        };
        let tracks = r.u32()?;
        if tracks > 3 {
            return Err(r.fail(format!(
                "object {} has {tracks} tracks (max 3)",
                o.object_id
            )));
        }
        for _ in 0..tracks {
            // Peek the target to know the component count.
            let target = *raw
                .get(r.position())
                .ok_or_else(|| r.fail("track header runs past the payload"))?;
            match target {
                0 | 2 => {
                    let (_, interpolation, times, v) = read_track::<3>(&mut r)?;
                    let track = Track {
                        interpolation,
                        times,
                        values: v.into_iter().map(Vec3::from_array).collect(),
                    };
                    let slot = if target == 0 {
                        &mut o.translation
                    } else {
                        &mut o.scale
                    };
                    if slot.replace(track).is_some() {
                        return Err(r.fail("duplicate track"));
                    }
                }
                1 => {
                    let (_, interpolation, times, v) = read_track::<4>(&mut r)?;
                    let track = Track {
                        interpolation,
                        times,
                        values: v.into_iter().map(Quat::from_array).collect(),
                    };
                    if o.rotation.replace(track).is_some() {
                        return Err(r.fail("duplicate track"));
                    }
                }
                t => return Err(r.fail(format!("unknown track target {t}"))),
            }
        }
        objects.push(o);
    }
    if r.remaining() != 0 {
        return Err(r.fail("trailing bytes after the last track"));
    }
    Ok(AnimationTracks { objects })
}
