//! Pack 1.2's materials: textures with their mip chains, the material table, object materials
//! and the proxies' UVs and tangents round-trip through a file; the sRGB box filter is
//! checked numerically; packs without materials (1.0, 1.1) read as "no material".

mod common;

use std::io::Cursor;

use common::*;
use plenoptic_pack::texture::{linear_to_srgb, srgb_to_linear};
use plenoptic_pack::*;

#[test]
fn materials_textures_and_attributes_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mat.pack");
    let m = write_material_pack(&path);
    let r = PackReader::open(&path).unwrap();
    assert_eq!(
        (r.header().version_major, r.header().version_minor),
        (VERSION_MAJOR, VERSION_MINOR)
    );
    assert_eq!(r.manifest(), &m);
    let (textures, materials) = common::materials();
    assert_eq!(r.textures(), textures.as_slice());
    assert_eq!(r.materials(), materials.as_slice());
    assert_eq!(r.object_material(1), Some(&materials[0]));
    assert_eq!(r.object_material(2), Some(&materials[1]));
    assert_eq!(r.object_material(77), None);

    // Texture 0: the 64×64 sRGB checker. Level 0 exact, log2(64) + 1 = 7 levels.
    let t = r.texture(0).unwrap();
    assert_eq!(t.colour_space, ColourSpace::Srgb);
    assert_eq!(t.levels.len(), 7);
    assert_eq!(t.levels[0].texels, checker(64));
    for (l, level) in t.levels.iter().enumerate() {
        assert_eq!((level.width, level.height), (64 >> l, 64 >> l));
        assert_eq!(level.texels.len(), 4 * (64 >> l) * (64 >> l));
    }
    // Level 1 averages black and white in linear light: linear 0.5, sRGB 0.7354 → 188, not
    // the 128 of a gamma-unaware average; alpha (linear) averages 255 and 0 to 127.5 → 128.
    let grey = 255.0 * linear_to_srgb(0.5);
    for level in &t.levels[1..] {
        for px in level.texels.chunks_exact(4) {
            for &c in &px[..3] {
                assert!((c as f32 - grey).abs() <= 1.0, "{c} vs {grey}");
            }
            assert!((px[3] as f32 - 127.5).abs() <= 1.0, "alpha {}", px[3]);
        }
    }
    // And the linear value of that grey is half the white's.
    assert!((srgb_to_linear(188.0 / 255.0) - 0.5).abs() < 0.005);

    // Texture 1: 16×4 linear gradient, 5 levels down to 1×1, each a 2×2 box of the one above.
    let t = r.texture(1).unwrap();
    assert_eq!(t.colour_space, ColourSpace::Linear);
    let sizes: Vec<_> = t.levels.iter().map(|l| (l.width, l.height)).collect();
    assert_eq!(sizes, [(16, 4), (8, 2), (4, 1), (2, 1), (1, 1)]);
    assert_eq!(t.levels[0].texels, gradient(16, 4));
    for pair in t.levels.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        for y in 0..b.height as usize {
            for x in 0..b.width as usize {
                for c in 0..4 {
                    let at = |xx: usize, yy: usize| {
                        let xx = xx.min(a.width as usize - 1);
                        let yy = yy.min(a.height as usize - 1);
                        a.texels[(yy * a.width as usize + xx) * 4 + c] as f32
                    };
                    let mean = (at(2 * x, 2 * y)
                        + at(2 * x + 1, 2 * y)
                        + at(2 * x, 2 * y + 1)
                        + at(2 * x + 1, 2 * y + 1))
                        / 4.0;
                    let got = b.texels[(y * b.width as usize + x) * 4 + c] as f32;
                    assert!((got - mean).abs() <= 0.5 + 1e-3, "{got} vs {mean}");
                }
            }
        }
    }

    // Proxy attributes: object 1 has them, object 2 not.
    assert_eq!(r.proxy_attributes(1).unwrap(), Some(proxy_attributes(1)));
    assert_eq!(r.proxy_attributes(2).unwrap(), None);
    // The texture chunk is a complete KTX2 file on its own.
    let ktx = r.texture_ktx2(0).unwrap();
    assert_eq!(decode_texture(&ktx).unwrap(), r.texture(0).unwrap());
}

#[test]
fn texture_levels_decode_with_ruzstd_as_bevy_does() {
    let t = TextureImage::with_mips(ColourSpace::Srgb, 8, 2, gradient(8, 2)).unwrap();
    let (bytes, _) = encode_texture(&t).unwrap();
    let reader = ktx2::Reader::new(&bytes[..]).unwrap();
    assert_eq!(reader.header().level_count, 4);
    for (level, want) in reader.levels().zip(&t.levels) {
        let mut cursor = level.data;
        let mut decoder = ruzstd::decoding::StreamingDecoder::new(&mut cursor).unwrap();
        let mut out = Vec::new();
        std::io::Read::read_to_end(&mut decoder, &mut out).unwrap();
        assert_eq!(out, want.texels);
    }
}

#[test]
fn packs_without_materials_read_as_none() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("old.pack");
    write_small_pack(&path);
    let json = String::from_utf8(
        PackReader::open(&path)
            .unwrap()
            .manifest()
            .to_json()
            .unwrap(),
    )
    .unwrap();
    // Nothing of 1.2 is written when there are no materials: the manifest is a 1.1 manifest.
    for key in ["\"materials\"", "\"textures\"", "\"material\""] {
        assert!(!json.contains(key), "{key} in {json}");
    }
    // The same bytes as a 1.0 and a 1.1 pack.
    let good = std::fs::read(&path).unwrap();
    for minor in [0, 1] {
        let mut b = good.clone();
        let mut h = Header::parse(b[..128].try_into().unwrap()).unwrap();
        h.version_minor = minor;
        b[..128].copy_from_slice(&h.to_bytes());
        let r = PackReader::from_reader(Cursor::new(b)).unwrap();
        assert_eq!(r.header().version_minor, minor);
        assert!(r.materials().is_empty() && r.textures().is_empty());
        for o in &r.manifest().objects {
            assert_eq!(o.material, None);
            assert_eq!(r.object_material(o.id), None);
            assert_eq!(r.proxy_attributes(o.id).unwrap(), None);
        }
        assert!(matches!(
            r.texture(0).unwrap_err(),
            PackError::InvalidMaterial { .. }
        ));
    }
}

#[test]
fn a_1_1_manifest_parses() {
    // An object table as a 1.1 writer wrote it: no `material` key, no tables.
    let mut m = manifest(1);
    m.objects[0].material = None;
    let json = String::from_utf8(m.to_json().unwrap()).unwrap();
    assert!(!json.contains("material"));
    let back = Manifest::from_json(json.as_bytes()).unwrap();
    assert_eq!(back.objects[0].material, None);
    assert!(back.materials.is_empty());
}

#[test]
fn the_writer_refuses_inconsistent_materials() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("w.pack");
    // A texture in the table without its chunk.
    let w = PackWriter::create(&path).unwrap();
    let mut m = manifest(0);
    (m.textures, m.materials) = common::materials();
    let e = w.finish(&m).unwrap_err();
    assert!(e.to_string().contains("no MaterialTexture chunk"), "{e}");
    assert!(!path.exists());
    // A table entry that disagrees with the texture added.
    let mut w = PackWriter::create(&path).unwrap();
    let t = TextureImage::with_mips(ColourSpace::Srgb, 64, 64, checker(64)).unwrap();
    w.add_texture(0, &t).unwrap();
    w.add_texture(1, &t).unwrap();
    let e = w.finish(&m).unwrap_err();
    assert!(e.to_string().contains("the table says texture 1"), "{e}");
    // Attributes before their mesh, or of the wrong length.
    let mut w = PackWriter::create(&path).unwrap();
    assert!(w.add_proxy_attributes(&proxy_attributes(1)).is_err());
    w.add_proxy_mesh(&proxy_mesh(1, false)).unwrap();
    let mut short = proxy_attributes(1);
    short.tangents.pop();
    let e = w.add_proxy_attributes(&short).unwrap_err();
    assert!(e.to_string().contains("3 tangents"), "{e}");
    // An incomplete mip chain.
    let mut t = TextureImage::with_mips(ColourSpace::Srgb, 4, 4, checker(4)).unwrap();
    t.levels.pop();
    assert!(w.add_texture(0, &t).is_err());
}
