//! Bad packs: each kind of damage gives its own error, naming the chunk where there is one.

mod common;

use std::io::Cursor;

use common::*;
use glam::Vec3;
use plenoptic_pack::*;

fn small_pack() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.pack");
    write_small_pack(&path);
    std::fs::read(path).unwrap()
}

fn open(bytes: Vec<u8>) -> Result<PackReader> {
    PackReader::from_reader(Cursor::new(bytes))
}

fn header(bytes: &[u8]) -> Header {
    Header::parse(bytes[..128].try_into().unwrap()).unwrap()
}

/// Edits directory row `row` (byte offset `field` inside the 48-byte row) and fixes up the
/// directory and header checksums so that only the edit is wrong.
fn edit_row(bytes: &mut [u8], row: usize, field: usize, value: u64, width: usize) {
    let mut h = header(bytes);
    let at = h.directory_offset as usize + row * 48 + field;
    bytes[at..at + width].copy_from_slice(&value.to_le_bytes()[..width]);
    let dir = &bytes[h.directory_offset as usize..][..h.directory_count as usize * 48];
    h.directory_checksum = checksum(dir);
    bytes[..128].copy_from_slice(&h.to_bytes());
}

fn rewrite_header(bytes: &mut [u8], f: impl FnOnce(&mut Header)) {
    let mut h = header(bytes);
    f(&mut h);
    bytes[..128].copy_from_slice(&h.to_bytes());
}

#[test]
fn truncated_file() {
    let mut b = small_pack();
    let len = b.len() as u64;
    b.truncate(b.len() - 10);
    match open(b).unwrap_err() {
        PackError::Truncated { expected, actual } => {
            assert_eq!((expected, actual), (len, len - 10))
        }
        e => panic!("{e}"),
    }
    assert!(matches!(
        open(vec![0; 20]).unwrap_err(),
        PackError::Truncated {
            expected: 128,
            actual: 20
        }
    ));
}

#[test]
fn wrong_magic() {
    let mut b = small_pack();
    b[..8].copy_from_slice(b"NOTAPACK");
    assert!(matches!(open(b).unwrap_err(), PackError::BadMagic(m) if &m == b"NOTAPACK"));
}

#[test]
fn unknown_major_version() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.version_major = 6);
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::UnsupportedVersion {
            major: 6,
            supported: 5,
            ..
        }
    ));
}

#[test]
fn version_two_packs_still_open() {
    // 2.x is 3.x without a runtime sun: its lighting holds all of the light.
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.version_major = 2);
    let r = open(b).unwrap();
    assert_eq!(r.header().version_major, 2);
    assert!(r.direct_sun().is_none());
    assert!(!r.runtime_emission());
}

#[test]
fn version_three_packs_keep_the_emission_in_the_non_diffuse_radiance() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.version_major = 3);
    assert!(!open(b).unwrap().runtime_emission());
    assert!(open(small_pack()).unwrap().runtime_emission());
}

/// A pack of no chunks whose manifest has `lights` and says `lamps_at_runtime`.
fn lamp_pack(lights: Vec<Light>) -> Result<Vec<u8>> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lamps.pack");
    let mut m = Manifest::new(TimeRange::default(), 1.0);
    m.lights = lights;
    m.lamps_at_runtime = true;
    PackWriter::create(&path)?.finish(&m)?;
    Ok(std::fs::read(path).unwrap())
}

#[test]
fn only_a_pack_of_five_or_later_leaves_its_lamps_to_the_runtime() {
    let mut lights = manifest(0).lights;
    lights.retain(|l| l.placed.is_some());
    let bytes = lamp_pack(lights.clone()).unwrap();
    assert!(open(bytes.clone()).unwrap().lamps_at_runtime());
    // A 4.x pack's lighting was baked with its lamps, whatever its manifest says.
    let mut four = bytes;
    rewrite_header(&mut four, |h| h.version_major = 4);
    assert!(!open(four).unwrap().lamps_at_runtime());
    // A lamp the runtime cannot place: the manifest is refused.
    lights[0].placed = None;
    let err = lamp_pack(lights).unwrap_err();
    assert!(
        matches!(&err, PackError::InvalidManifest { reason } if reason.contains("lamps_at_runtime")),
        "{err}"
    );
}

#[test]
fn version_one_packs_must_be_rebaked() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| {
        h.version_major = 1;
        h.version_minor = 2;
    });
    let err = open(b).unwrap_err();
    assert!(
        matches!(err, PackError::NeedsRebake { major: 1, minor: 2 }),
        "{err}"
    );
    assert!(err.to_string().contains("re-bake"), "{err}");
}

#[test]
fn newer_minor_version_opens() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.version_minor = 7);
    assert_eq!(open(b).unwrap().header().version_minor, 7);
}

#[test]
fn header_checksum() {
    let mut b = small_pack();
    b[100] ^= 1;
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::SectionChecksumMismatch {
            section: Section::Header,
            ..
        }
    ));
}

#[test]
fn directory_entry_past_eof() {
    let mut b = small_pack();
    let len = b.len() as u64;
    edit_row(&mut b, 3, 16, len - 5, 8);
    match open(b).unwrap_err() {
        PackError::ChunkOutOfBounds { chunk, limit, .. } => {
            assert_eq!(chunk.index, 3);
            assert_eq!(chunk.kind, ChunkKind::DistanceCube);
            assert_eq!(limit, len);
        }
        e => panic!("{e}"),
    }
}

#[test]
fn chunk_overlapping_manifest() {
    let mut b = small_pack();
    let h = header(&b);
    edit_row(&mut b, 0, 16, h.manifest_offset - 10, 8);
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::ChunkOutOfBounds { .. }
    ));
}

#[test]
fn overlapping_chunks() {
    let mut b = small_pack();
    let h = header(&b);
    let row0 = h.directory_offset as usize;
    let off0 = u64::from_le_bytes(b[row0 + 16..row0 + 24].try_into().unwrap());
    edit_row(&mut b, 1, 16, off0 + 1, 8);
    match open(b).unwrap_err() {
        PackError::OverlappingChunks { a, b } => assert_eq!((a.index, b.index), (0, 1)),
        e => panic!("{e}"),
    }
}

#[test]
fn counts_larger_than_the_file() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.directory_count = 1 << 40);
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::CountTooLarge {
            what: "directory rows",
            ..
        }
    ));
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.manifest_length = u64::MAX);
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::CountTooLarge {
            what: "manifest bytes",
            ..
        }
    ));
}

#[test]
fn section_out_of_bounds() {
    let mut b = small_pack();
    rewrite_header(&mut b, |h| h.manifest_offset = 3);
    assert!(matches!(
        open(b).unwrap_err(),
        PackError::SectionOutOfBounds {
            section: Section::Manifest,
            ..
        }
    ));
}

#[test]
fn chunk_checksum_mismatch() {
    let mut b = small_pack();
    let h = header(&b);
    // Row 9: the distance cube of base view 0 at time key 1 (six cubes per range image).
    let row = h.directory_offset as usize + 9 * 48;
    let off = u64::from_le_bytes(b[row + 16..row + 24].try_into().unwrap()) as usize;
    b[off + 200] ^= 0x40;
    let r = open(b).unwrap();
    match r.chunk(9).unwrap_err() {
        PackError::ChecksumMismatch { chunk, .. } => {
            assert_eq!(chunk.index, 9);
            assert_eq!(chunk.kind, ChunkKind::DistanceCube);
            assert_eq!(chunk.base_view, 0);
            assert_eq!(chunk.key, 1);
        }
        e => panic!("{e}"),
    }
    // Other chunks still read.
    assert!(r.chunk(0).is_ok());
}

fn pack_with_raw(kind: ChunkKind, bytes: &[u8]) -> PackReader {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("raw.pack");
    let mut w = PackWriter::create(&path).unwrap();
    w.add_raw_chunk(kind, 0, 0, bytes, 6 * 64 * 4, None)
        .unwrap();
    w.finish(&manifest(1)).unwrap();
    PackReader::open(&path).unwrap()
}

#[test]
fn malformed_ktx2_inside_a_good_chunk() {
    let good = encode_radiance(&room_image(8, 0.0).radiance, RadianceFormat::Rgb9e5).unwrap();
    let mut cases: Vec<(&str, Vec<u8>)> = Vec::new();
    let mut faces = good.clone();
    faces[36..40].copy_from_slice(&1u32.to_le_bytes());
    cases.push(("faceCount 1", faces));
    cases.push(("truncated", good[..good.len() - 7].to_vec()));
    let mut dfd = good.clone();
    // texelBlockDimension0 = 255 (would panic ktx2 0.5's DFD parser).
    let dfd_off = u32::from_le_bytes(good[48..52].try_into().unwrap()) as usize;
    dfd[dfd_off + 4 + 8 + 4] = 255;
    cases.push(("DFD", dfd));
    let mut sc = good.clone();
    sc[44..48].copy_from_slice(&0u32.to_le_bytes());
    cases.push(("no supercompression", sc));
    let mut level = good.clone();
    level[80 + 8..80 + 16].copy_from_slice(&u64::MAX.to_le_bytes());
    cases.push(("level length", level));
    // Version 2's lighting and non-diffuse cubes are checked like the radiance.
    for kind in [
        ChunkKind::RadianceCube,
        ChunkKind::LightingCube,
        ChunkKind::NonDiffuseCube,
    ] {
        for (what, bytes) in &cases {
            let r = pack_with_raw(kind, bytes);
            match r.chunk(0).unwrap_err() {
                PackError::MalformedKtx2 { chunk, reason } => {
                    assert_eq!(chunk.unwrap().kind, kind, "{what}: {reason}")
                }
                e => panic!("{kind:?} {what}: {e}"),
            }
        }
        // A distance cube is not a lighting cube.
        let d = room_image(8, 0.0);
        let wrong = encode_distance(&d.distance, DistanceFormat::R32Float).unwrap();
        let r = pack_with_raw(kind, &wrong);
        assert!(
            matches!(r.chunk(0).unwrap_err(), PackError::MalformedKtx2 { .. }),
            "{kind:?}"
        );
    }
    let r = pack_with_raw(ChunkKind::LightingCube, &good);
    assert_eq!(r.lighting(0, 0).unwrap().face_size, 8);
    assert!(matches!(
        r.non_diffuse(0, 0).unwrap_err(),
        PackError::ChunkNotFound { .. }
    ));
    // A good KTX2 of the wrong kind's format is malformed for that kind, too.
    let r = pack_with_raw(ChunkKind::DistanceCube, &good);
    assert!(matches!(
        r.chunk(0).unwrap_err(),
        PackError::MalformedKtx2 { .. }
    ));
}

#[test]
fn uncompressed_length_mismatch() {
    let good = encode_radiance(&room_image(4, 0.0).radiance, RadianceFormat::Rgb9e5).unwrap();
    let r = pack_with_raw(ChunkKind::RadianceCube, &good); // says 6·64·4, is 6·16·4
    assert!(matches!(
        r.chunk(0).unwrap_err(),
        PackError::UncompressedLengthMismatch {
            expected: 1536,
            actual: 384,
            ..
        }
    ));
}

#[test]
fn unknown_kind_opens_but_does_not_decode() {
    let r = pack_with_raw(ChunkKind::Unknown(77), b"future payload");
    assert_eq!(r.chunk_bytes(0).unwrap(), b"future payload");
    assert!(matches!(
        r.chunk(0).unwrap_err(),
        PackError::UnknownChunkKind { .. }
    ));
}

#[test]
fn writer_rejects_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("w.pack");
    let mut w = PackWriter::create(&path).unwrap();
    let img = room_image(4, 0.0);
    w.add_range_image(0, 0, &img, CubeFormats::default())
        .unwrap();
    assert!(matches!(
        w.add_range_image(0, 0, &img, CubeFormats::default())
            .unwrap_err(),
        PackError::DuplicateChunk { .. }
    ));
    assert!(matches!(
        w.add_chunk(ChunkKind::RadianceCube, 0, 1, b"junk")
            .unwrap_err(),
        PackError::MalformedKtx2 { chunk: Some(_), .. }
    ));
    assert!(matches!(
        w.add_raw_chunk(ChunkKind::VolumeBlock, 0, 0, b"x", 0, Some(1))
            .unwrap_err(),
        PackError::ChecksumMismatch { .. }
    ));
    w.add_range_image(5, 0, &img, CubeFormats::default())
        .unwrap();
    assert!(matches!(
        w.finish(&manifest(1)).unwrap_err(),
        PackError::UnknownBaseView { base_view: 5, .. }
    ));
    assert!(!path.exists());
}

#[test]
fn bad_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.pack");
    let mut m = manifest(1);
    m.bucket_span = 0.0;
    assert!(PackWriter::create(&path).unwrap().finish(&m).is_err());
    assert!(matches!(
        Manifest::from_json(b"{\"units\": 3}").unwrap_err(),
        PackError::InvalidManifest { .. }
    ));
}

#[test]
fn glazing_coverage_outside_zero_to_one_is_refused_and_named() {
    for bad in [0.0f32, 1.0, 1.5, -0.2, f32::NAN] {
        let mut m = manifest(1);
        m.objects[0].coverage = Some(bad);
        let err = m.validate().unwrap_err().to_string();
        assert!(
            err.contains("coverage") && err.contains("walls"),
            "{bad}: {err}"
        );
    }
    let mut m = manifest(1);
    m.objects[0].coverage = Some(0.12);
    m.validate().unwrap();
    // It survives the JSON round trip; absent reads as opaque.
    let back = Manifest::from_json(&m.to_json().unwrap()).unwrap();
    assert_eq!(back.objects[0].coverage, Some(0.12));
    assert_eq!(back.objects[1].coverage, None);
}

#[test]
fn a_lamp_placed_nowhere_is_refused_and_named() {
    let placed = |position: Vec3, direction: Vec3, range: Option<f32>| {
        let mut m = manifest(1);
        let i = m
            .lights
            .iter()
            .position(|l| l.placed.is_some())
            .expect("the test manifest places a lamp");
        m.lights[i].placed = Some(plenoptic_pack::LightPlacement {
            position,
            direction,
            range,
        });
        (i, m)
    };
    let nan = f32::NAN;
    for (position, direction, range) in [
        (Vec3::new(nan, 0.0, 0.0), Vec3::NEG_Y, None),
        (Vec3::ZERO, Vec3::new(0.0, -3.0, 0.0), None),
        (Vec3::ZERO, Vec3::ZERO, None),
        (Vec3::ZERO, Vec3::NEG_Y, Some(0.0)),
        (Vec3::ZERO, Vec3::NEG_Y, Some(f32::INFINITY)),
    ] {
        let (i, m) = placed(position, direction, range);
        let err = m.validate().unwrap_err().to_string();
        assert!(err.contains(&format!("light {i}")), "{err}");
        // A writer refuses it too.
        let dir = tempfile::tempdir().unwrap();
        assert!(
            PackWriter::create(dir.path().join("l.pack"))
                .unwrap()
                .finish(&m)
                .is_err()
        );
    }
    // A good placement survives the JSON round trip; absent reads as not placed.
    let (i, m) = placed(Vec3::new(1.0, 2.0, 3.0), Vec3::NEG_Y, Some(4.0));
    m.validate().unwrap();
    let back = Manifest::from_json(&m.to_json().unwrap()).unwrap();
    assert_eq!(back.lights[i].placed, m.lights[i].placed);
    assert!(back.lights.iter().filter(|l| l.placed.is_none()).count() >= 2);
}

#[test]
fn older_formats_are_outdated() {
    let dir = tempfile::tempdir().unwrap();
    for (major, minor, outdated) in [
        (1, 0, true),
        (2, 0, true),
        (3, 2, true),
        (4, 0, true),
        (4, 2, true),
        (5, 0, false),
        (5, 7, false),
    ] {
        let mut b = small_pack();
        rewrite_header(&mut b, |h| {
            h.version_major = major;
            h.version_minor = minor;
        });
        let path = dir.path().join(format!("v{major}.{minor}.pack"));
        std::fs::write(&path, &b).unwrap();
        assert_eq!(
            plenoptic_pack::is_outdated(&path),
            outdated,
            "version {major}.{minor}"
        );
    }
    assert!(!plenoptic_pack::is_outdated(
        dir.path().join("missing.pack")
    ));
}
