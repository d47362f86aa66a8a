//! Shading attributes of a proxy mesh (pack 1.2; docs/architecture.md, "Pack v2",
//! **Materials**: "proxies with UVs and tangents"; `docs/pack-format.md`, "Proxy attributes"):
//! per-vertex TEXCOORD_0 and tangents of the [`crate::ProxyMesh`] with the same key, in a chunk
//! of their own ([`crate::ChunkKind::ProxyAttributes`]) so that the proxy-mesh chunk of 1.0 and
//! 1.1 keeps its layout and older readers skip the new data.
//!
//! UVs are glTF's TEXCOORD_0 as the file has them (origin top left, v down); a texture's
//! `KHR_texture_transform` stays with the material's texture binding
//! ([`crate::TextureBinding::transform`]), because each texture of a material may have its own.
//! Tangents are xyz unit vectors with the bitangent's sign in w (±1), as glTF's TANGENT.

use glam::{Vec2, Vec4};

use crate::bytes::{ByteReader, PutLe, zstd_compress, zstd_decompress_exact};
use crate::error::{PackError, Result};
use crate::proxy::MAX_PROXY_VERTICES;

const MAGIC: [u8; 4] = *b"PPA1";
/// Bytes before the zstd frame of a proxy-attributes chunk.
pub const PROXY_ATTRIBUTES_HEADER_LEN: usize = 24;

/// UVs and tangents of one object's proxy mesh. An empty list means the mesh has none; a
/// non-empty one has one entry per proxy vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProxyAttributes {
    /// The object (the key of the chunk and of its proxy mesh).
    pub object_id: u32,
    /// TEXCOORD_0 per vertex. Exact (f32).
    pub uvs: Vec<Vec2>,
    /// Tangent per vertex: unit xyz, w = ±1 the bitangent's sign. Exact (f32).
    pub tangents: Vec<Vec4>,
}

impl ProxyAttributes {
    /// Checks the attributes against a proxy mesh of `vertex_count` vertices: each list empty
    /// or one entry per vertex. The message says which list disagrees.
    pub fn check_vertex_count(&self, vertex_count: usize) -> std::result::Result<(), String> {
        for (what, n) in [("UVs", self.uvs.len()), ("tangents", self.tangents.len())] {
            if n != 0 && n != vertex_count {
                return Err(format!(
                    "{n} {what} for a proxy mesh of {vertex_count} vertices (object {})",
                    self.object_id
                ));
            }
        }
        Ok(())
    }
}

fn check_values(uvs: &[Vec2], tangents: &[Vec4]) -> std::result::Result<(), String> {
    if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
        return Err(format!("UV {i} is not finite"));
    }
    if let Some(i) = tangents
        .iter()
        .position(|t| !(t.is_finite() && t.w.abs() == 1.0))
    {
        return Err(format!(
            "tangent {i} is not finite or its w is not ±1: {:?}",
            tangents[i].to_array()
        ));
    }
    Ok(())
}

/// Encodes proxy attributes; returns the chunk bytes and the uncompressed length.
pub fn encode_proxy_attributes(a: &ProxyAttributes) -> Result<(Vec<u8>, u64)> {
    let (uc, tc) = (a.uvs.len(), a.tangents.len());
    if uc.max(tc) > MAX_PROXY_VERTICES as usize {
        return Err(PackError::input(format!(
            "{uc} UVs / {tc} tangents exceed the proxy vertex cap {MAX_PROXY_VERTICES}"
        )));
    }
    check_values(&a.uvs, &a.tangents).map_err(PackError::input)?;
    let mut raw = Vec::with_capacity(uc * 8 + tc * 16);
    for uv in &a.uvs {
        raw.put_f32(uv.x);
        raw.put_f32(uv.y);
    }
    for t in &a.tangents {
        for c in t.to_array() {
            raw.put_f32(c);
        }
    }
    let mut out = Vec::new();
    out.extend_from_slice(&MAGIC);
    out.put_u32(a.object_id);
    out.put_u32(uc as u32);
    out.put_u32(tc as u32);
    out.put_u32(0);
    out.put_u32(0);
    out.extend_from_slice(&zstd_compress(&raw)?);
    Ok((out, raw.len() as u64))
}

/// Checks a proxy-attributes header: (object id, UV count, tangent count, uncompressed length).
pub(crate) fn attributes_header(bytes: &[u8]) -> Result<(u32, u32, u32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != MAGIC {
        return Err(r.fail("not a proxy-attributes chunk (bad magic)"));
    }
    let id = r.u32()?;
    let uc = r.u32()?;
    let tc = r.u32()?;
    let (a, b) = (r.u32()?, r.u32()?);
    if a != 0 || b != 0 {
        return Err(r.fail(format!("reserved fields are {a:#x}, {b:#x}, expected 0")));
    }
    if uc.max(tc) > MAX_PROXY_VERTICES {
        return Err(PackError::CountTooLarge {
            what: "proxy UVs/tangents",
            count: u64::from(uc.max(tc)),
            max: u64::from(MAX_PROXY_VERTICES),
        });
    }
    Ok((id, uc, tc, u64::from(uc) * 8 + u64::from(tc) * 16))
}

/// Decodes a proxy-attributes chunk (its counts are checked against its proxy mesh by
/// [`crate::PackReader::proxy_attributes`]).
pub fn decode_proxy_attributes(bytes: &[u8]) -> Result<ProxyAttributes> {
    let (object_id, uc, tc, len) = attributes_header(bytes)?;
    let frame = &bytes[PROXY_ATTRIBUTES_HEADER_LEN..];
    let raw = zstd_decompress_exact(frame, len as usize, PackError::payload)?;
    let mut r = ByteReader::payload(&raw);
    let uvs = (0..uc)
        .map(|_| Ok(Vec2::new(r.f32()?, r.f32()?)))
        .collect::<Result<Vec<_>>>()?;
    let tangents = (0..tc)
        .map(|_| Ok(Vec4::new(r.f32()?, r.f32()?, r.f32()?, r.f32()?)))
        .collect::<Result<Vec<_>>>()?;
    check_values(&uvs, &tangents).map_err(PackError::payload)?;
    Ok(ProxyAttributes {
        object_id,
        uvs,
        tangents,
    })
}

impl crate::PackReader {
    /// The UVs and tangents of object `object_id`'s proxy mesh, checked against the mesh's
    /// vertex count; `None` when the pack has no attributes for it (packs before 1.2, meshes
    /// without UVs).
    pub fn proxy_attributes(&self, object_id: u32) -> Result<Option<ProxyAttributes>> {
        use crate::{Chunk, ChunkKind, NO_BASE_VIEW};
        let Some(index) = self.find(ChunkKind::ProxyAttributes, NO_BASE_VIEW, object_id) else {
            return Ok(None);
        };
        let Chunk::ProxyAttributes(attributes) = self.chunk(index)? else {
            unreachable!("decoded by kind")
        };
        let chunk = self.entries()[index].chunk_ref(index);
        let mesh = self
            .find(ChunkKind::ProxyMesh, NO_BASE_VIEW, object_id)
            .ok_or_else(|| {
                PackError::payload(format!(
                    "object {object_id} has attributes but no proxy mesh"
                ))
                .in_chunk(chunk)
            })?;
        let (_, vertex_count, ..) = crate::proxy::proxy_header(&self.chunk_bytes(mesh)?)?;
        attributes
            .check_vertex_count(vertex_count as usize)
            .map_err(|reason| PackError::payload(reason).in_chunk(chunk))?;
        Ok(Some(attributes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_bad_values() {
        let a = ProxyAttributes {
            object_id: 3,
            uvs: vec![Vec2::new(0.0, 1.0), Vec2::new(-2.5, 3.25)],
            tangents: vec![
                Vec4::new(1.0, 0.0, 0.0, 1.0),
                Vec4::new(0.0, 1.0, 0.0, -1.0),
            ],
        };
        let (bytes, len) = encode_proxy_attributes(&a).unwrap();
        assert_eq!(len, 2 * 8 + 2 * 16);
        assert_eq!(decode_proxy_attributes(&bytes).unwrap(), a);
        assert!(a.check_vertex_count(2).is_ok());
        assert!(a.check_vertex_count(3).unwrap_err().contains("2 UVs"));
        let mut bad = a.clone();
        bad.tangents[1].w = 0.5;
        assert!(encode_proxy_attributes(&bad).is_err());
        // A header claiming more UVs than the frame holds.
        let mut lying = bytes.clone();
        lying[8..12].copy_from_slice(&5u32.to_le_bytes());
        assert!(decode_proxy_attributes(&lying).is_err());
    }
}
