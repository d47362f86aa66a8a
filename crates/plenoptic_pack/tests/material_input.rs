//! Hostile material data (pack 1.2): truncated texture chunks, bad mip chains, materials and
//! objects that index past their tables, proxy UV and tangent counts that disagree with the
//! mesh. Each is an error that names the pack or the chunk, never a panic.

mod common;

use std::io::Cursor;

use common::*;
use plenoptic_pack::*;

fn open(bytes: Vec<u8>) -> Result<PackReader> {
    PackReader::from_reader(Cursor::new(bytes))
}

/// A pack with [`write_material_pack`]'s manifest whose texture 0 chunk is `texture0` (stored
/// as given) and whose object 1 attributes chunk is `attributes` (stored as given).
fn pack_with(texture0: &[u8], attributes: &[u8]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("h.pack");
    let mut m = manifest(1);
    let mut w = PackWriter::create(&path).unwrap();
    w.add_proxy_mesh(&proxy_mesh(1, true)).unwrap();
    w.add_proxy_mesh(&proxy_mesh(2, false)).unwrap();
    // The uncompressed lengths the chunks' headers declare, where they can be read.
    let counts = |at: usize| {
        attributes
            .get(at..at + 4)
            .map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap()) as u64)
    };
    let attributes_len = counts(8) * 8 + counts(12) * 16;
    w.add_raw_chunk(
        ChunkKind::ProxyAttributes,
        NO_BASE_VIEW,
        1,
        attributes,
        attributes_len,
        None,
    )
    .unwrap();
    let texture_len = texture::inspect_texture(texture0).map_or(0, |i| i.uncompressed_length);
    w.add_raw_chunk(
        ChunkKind::MaterialTexture,
        NO_BASE_VIEW,
        0,
        texture0,
        texture_len,
        None,
    )
    .unwrap();
    let t1 = TextureImage::with_mips(ColourSpace::Linear, 16, 4, gradient(16, 4)).unwrap();
    w.add_texture(1, &t1).unwrap();
    (m.textures, m.materials) = common::materials();
    m.objects[0].material = Some(0);
    w.finish(&m).unwrap();
    std::fs::read(path).unwrap()
}

fn checker_chunk() -> Vec<u8> {
    let t = TextureImage::with_mips(ColourSpace::Srgb, 64, 64, checker(64)).unwrap();
    encode_texture(&t).unwrap().0
}

fn good_attributes() -> Vec<u8> {
    encode_proxy_attributes(&proxy_attributes(1)).unwrap().0
}

/// Replaces the manifest of a pack by `edit` of its JSON, fixing lengths and checksums.
fn with_manifest(bytes: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let mut h = Header::parse(bytes[..128].try_into().unwrap()).unwrap();
    let (mo, ml) = (h.manifest_offset as usize, h.manifest_length as usize);
    let mut json: serde_json::Value = serde_json::from_slice(&bytes[mo..mo + ml]).unwrap();
    edit(&mut json);
    let json = serde_json::to_vec(&json).unwrap();
    let directory = &bytes[h.directory_offset as usize..];
    let mut out = bytes[..mo].to_vec();
    out.extend_from_slice(&json);
    h.manifest_length = json.len() as u64;
    h.manifest_checksum = checksum(&json);
    h.directory_offset = out.len() as u64;
    out.extend_from_slice(directory);
    h.file_length = out.len() as u64;
    out[..128].copy_from_slice(&h.to_bytes());
    out
}

fn material_error(e: PackError) -> String {
    match e {
        PackError::InvalidMaterial { reason, .. } => reason,
        e => panic!("not InvalidMaterial: {e}"),
    }
}

#[test]
fn the_fixture_is_good() {
    let r = open(pack_with(&checker_chunk(), &good_attributes())).unwrap();
    assert_eq!(r.texture(0).unwrap().levels.len(), 7);
    assert!(r.proxy_attributes(1).unwrap().is_some());
}

#[test]
fn truncated_texture_chunk() {
    let chunk = checker_chunk();
    for len in [10, 100, chunk.len() / 2, chunk.len() - 1] {
        let r = open(pack_with(&chunk[..len], &good_attributes())).unwrap();
        let e = r.texture(0).unwrap_err();
        let text = e.to_string();
        match e {
            PackError::InvalidTexture { index, source, .. } => {
                assert_eq!(index, 0);
                assert!(
                    matches!(*source, PackError::MalformedKtx2 { chunk: Some(c), .. } if c.kind == ChunkKind::MaterialTexture),
                    "{len}: {source}"
                );
            }
            e => panic!("{len}: {e}"),
        }
        assert!(text.starts_with("texture 0 of "), "{text}");
    }
}

#[test]
fn bad_mip_chains() {
    let good = checker_chunk();
    // levelCount 6 for a 64 × 64 texture (the full chain has 7).
    let mut b = good.clone();
    b[40..44].copy_from_slice(&6u32.to_le_bytes());
    let e = open(pack_with(&b, &good_attributes()))
        .unwrap()
        .texture(0)
        .unwrap_err();
    assert!(e.to_string().contains("levelCount 6"), "{e}");
    // levelCount 0 ("generate mips at load") is refused too.
    b[40..44].copy_from_slice(&0u32.to_le_bytes());
    let e = open(pack_with(&b, &good_attributes()))
        .unwrap()
        .texture(0)
        .unwrap_err();
    assert!(e.to_string().contains("levelCount 0"), "{e}");
    // Level 2 claims the size of level 1.
    let mut b = good.clone();
    let at = 80 + 2 * 24 + 16;
    b[at..at + 8].copy_from_slice(&(4u64 * 32 * 32).to_le_bytes());
    let e = open(pack_with(&b, &good_attributes()))
        .unwrap()
        .texture(0)
        .unwrap_err();
    assert!(e.to_string().contains("level 2"), "{e}");
    // Level 3's frame swapped for level 4's: the frame declares the wrong size.
    let mut b = good.clone();
    let entry = |b: &[u8], l: usize| {
        let at = 80 + l * 24;
        let off = u64::from_le_bytes(b[at..at + 8].try_into().unwrap());
        let len = u64::from_le_bytes(b[at + 8..at + 16].try_into().unwrap());
        (off, len)
    };
    let (off4, len4) = entry(&b, 4);
    b[80 + 3 * 24..80 + 3 * 24 + 16]
        .copy_from_slice(&[off4.to_le_bytes(), len4.to_le_bytes()].concat());
    let e = open(pack_with(&b, &good_attributes()))
        .unwrap()
        .texture(0)
        .unwrap_err();
    assert!(
        e.to_string().contains("level 3: zstd frame declares"),
        "{e}"
    );
    // A chain that disagrees with the table: the table says 32 × 32.
    let bytes = with_manifest(&pack_with(&good, &good_attributes()), |j| {
        j["textures"][0]["width"] = 32.into();
        j["textures"][0]["height"] = 32.into();
        j["textures"][0]["levels"] = 6.into();
    });
    let e = material_error(open(bytes).unwrap().texture(0).unwrap_err());
    assert!(e.contains("the table says 32 × 32"), "{e}");
    // A table whose chain is not full.
    let bytes = with_manifest(&pack_with(&good, &good_attributes()), |j| {
        j["textures"][0]["levels"] = 3.into();
    });
    let e = material_error(open(bytes).unwrap_err());
    assert!(e.contains("texture 0 has 3 levels"), "{e}");
    // A texture far beyond the cap is refused before anything is allocated.
    let mut b = good.clone();
    b[20..24].copy_from_slice(&(1u32 << 30).to_le_bytes());
    let e = open(pack_with(&b, &good_attributes()))
        .unwrap()
        .texture(0)
        .unwrap_err();
    assert!(e.to_string().contains("texture width"), "{e}");
}

#[test]
fn a_material_indexing_past_its_textures() {
    let good = pack_with(&checker_chunk(), &good_attributes());
    let bytes = with_manifest(&good, |j| {
        j["materials"][0]["normal_texture"]["texture"] = 2.into();
    });
    let e = material_error(open(bytes).unwrap_err());
    assert!(
        e.contains("material 0 'tiles': normal texture is texture 2, but the pack has 2 textures"),
        "{e}"
    );
    // An object whose material is past the table.
    let bytes = with_manifest(&good, |j| {
        j["objects"][1]["material"] = 9.into();
    });
    let e = material_error(open(bytes).unwrap_err());
    assert!(
        e.contains("has material 9, but the pack has 2 materials"),
        "{e}"
    );
    // A base colour texture bound to a linear texture.
    let bytes = with_manifest(&good, |j| {
        j["materials"][0]["base_colour_texture"]["texture"] = 1.into();
    });
    let e = material_error(open(bytes).unwrap_err());
    assert!(e.contains("the slot needs Srgb"), "{e}");
    // A texture in the table with no chunk.
    let bytes = with_manifest(&good, |j| {
        let t = j["textures"][1].clone();
        j["textures"].as_array_mut().unwrap().push(t);
    });
    let e = material_error(open(bytes).unwrap_err());
    assert!(e.contains("texture 2 has no MaterialTexture chunk"), "{e}");
}

fn attributes_error(attributes: &ProxyAttributes) -> String {
    let (bytes, _) = encode_proxy_attributes(attributes).unwrap();
    let r = open(pack_with(&checker_chunk(), &bytes)).unwrap();
    match r.proxy_attributes(1).unwrap_err() {
        PackError::MalformedChunk {
            chunk: Some(c),
            reason,
        } => {
            assert_eq!(c.kind, ChunkKind::ProxyAttributes);
            reason
        }
        e => panic!("{e}"),
    }
}

#[test]
fn a_uv_count_that_disagrees_with_the_positions() {
    let mut a = proxy_attributes(1);
    a.uvs.push(glam::Vec2::ONE);
    let e = attributes_error(&a);
    assert!(e.contains("5 UVs for a proxy mesh of 4 vertices"), "{e}");
}

#[test]
fn a_tangent_count_that_disagrees_with_the_positions() {
    let mut a = proxy_attributes(1);
    a.tangents.truncate(3);
    let e = attributes_error(&a);
    assert!(
        e.contains("3 tangents for a proxy mesh of 4 vertices"),
        "{e}"
    );
}

#[test]
fn damaged_attribute_chunks() {
    let good = good_attributes();
    // Truncated.
    for len in [3, 20, good.len() - 1] {
        let r = open(pack_with(&checker_chunk(), &good[..len])).unwrap();
        assert!(
            matches!(
                r.proxy_attributes(1).unwrap_err(),
                PackError::MalformedChunk { .. }
            ),
            "{len}"
        );
    }
    // A count past the cap.
    let mut b = good.clone();
    b[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let r = open(pack_with(&checker_chunk(), &b)).unwrap();
    assert!(matches!(
        r.proxy_attributes(1).unwrap_err(),
        PackError::CountTooLarge { .. }
    ));
}
