//! Round trips, field by field, against each field's documented quantization bound.

mod common;

use common::*;
use glam::Vec3;
use plenoptic_pack::*;

fn angle(a: Vec3, b: Vec3) -> f32 {
    let (a, b) = (a.normalize(), b.normalize());
    a.cross(b).length().atan2(a.dot(b))
}

#[test]
fn radiance_rgb9e5_error_bound() {
    let img = room_image(16, 0.1);
    let mut cube = img.radiance.clone();
    // Add extremes: tiny, large, zero, saturated.
    cube.texels[0] = Vec3::new(1e-6, 2e-6, 0.0);
    cube.texels[1] = Vec3::new(60000.0, 1.0, 0.001);
    let decoded =
        decode_radiance(&encode_radiance(&cube, RadianceFormat::Rgb9e5).unwrap()).unwrap();
    assert_eq!(decoded.face_size, 16);
    for (a, b) in cube.texels.iter().zip(&decoded.texels) {
        let bound = a.max_element() * 2f32.powi(-9) + 2f32.powi(-24);
        assert!((*a - *b).abs().max_element() <= bound, "{a} vs {b}");
    }
}

#[test]
fn radiance_rgba16f_error_bound() {
    let cube = room_image(8, 0.0).radiance;
    let decoded =
        decode_radiance(&encode_radiance(&cube, RadianceFormat::Rgba16Float).unwrap()).unwrap();
    for (a, b) in cube.texels.iter().zip(&decoded.texels) {
        assert!(((*a - *b).abs() - a.abs() * 2f32.powi(-11)).max_element() <= 1e-7);
    }
}

#[test]
fn distance_formats() {
    let cube = room_image(8, 0.0).distance;
    let exact =
        decode_distance(&encode_distance(&cube, DistanceFormat::R32Float).unwrap()).unwrap();
    assert_eq!(exact, cube);
    let half = decode_distance(&encode_distance(&cube, DistanceFormat::R16Float).unwrap()).unwrap();
    for (a, b) in cube.texels.iter().zip(&half.texels) {
        assert!((a - b).abs() <= a * 2f32.powi(-11), "{a} vs {b}");
    }
}

#[test]
fn object_ids_exact() {
    let mut cube = room_image(8, 0.0).object_id;
    assert_eq!(
        decode_object_id(&encode_object_id(&cube, ObjectIdFormat::R16Uint).unwrap()).unwrap(),
        cube
    );
    cube.texels[5] = u32::MAX - 1;
    assert_eq!(
        decode_object_id(&encode_object_id(&cube, ObjectIdFormat::R32Uint).unwrap()).unwrap(),
        cube
    );
    assert!(matches!(
        encode_object_id(&cube, ObjectIdFormat::R16Uint),
        Err(PackError::InvalidInput { .. })
    ));
}

#[test]
fn normals_angular_bound() {
    let mut rng = Rng(42);
    let cube = CubeImage::from_fn(16, |_, _| rng.direction());
    let snorm = decode_normal(&encode_normal(&cube, NormalFormat::Rg16Snorm).unwrap()).unwrap();
    let float = decode_normal(&encode_normal(&cube, NormalFormat::Rg16Float).unwrap()).unwrap();
    for ((a, s), f) in cube.texels.iter().zip(&snorm.texels).zip(&float.texels) {
        assert!(angle(*a, *s) <= 1e-4, "snorm {}", angle(*a, *s));
        assert!(angle(*a, *f) <= 2e-3, "f16 {}", angle(*a, *f));
        assert!((s.length() - 1.0).abs() < 1e-5);
    }
}

#[test]
fn ktx2_headers_parse_with_ktx2_crate() {
    let img = room_image(8, 0.0);
    let cases = [
        (encode_radiance(&img.radiance, RadianceFormat::Rgb9e5), 123),
        (
            encode_radiance(&img.radiance, RadianceFormat::Rgba16Float),
            97,
        ),
        (
            encode_distance(&img.distance, DistanceFormat::R32Float),
            100,
        ),
        (encode_distance(&img.distance, DistanceFormat::R16Float), 76),
        (
            encode_object_id(&img.object_id, ObjectIdFormat::R32Uint),
            98,
        ),
        (
            encode_object_id(&img.object_id, ObjectIdFormat::R16Uint),
            74,
        ),
        (encode_normal(&img.normal, NormalFormat::Rg16Snorm), 78),
        (encode_normal(&img.normal, NormalFormat::Rg16Float), 83),
    ];
    for (bytes, vk) in cases {
        let bytes = bytes.unwrap();
        let r = ktx2::Reader::new(&bytes[..]).expect("ktx2 parses");
        let h = r.header();
        assert_eq!(h.format.unwrap().value(), vk);
        assert_eq!((h.pixel_width, h.pixel_height, h.pixel_depth), (8, 8, 0));
        assert_eq!((h.face_count, h.layer_count, h.level_count), (6, 0, 1));
        assert_eq!(
            h.supercompression_scheme,
            Some(ktx2::SupercompressionScheme::Zstandard)
        );
        assert_eq!(r.levels().len(), 1);
        let level = r.levels().next().unwrap();
        let raw = zstd::decode_all(level.data).unwrap();
        assert_eq!(raw.len() as u64, level.uncompressed_byte_length);
        assert!(r.basic_dfd().is_some());
        assert!(r.writer().unwrap().starts_with("plenoptic_pack"));
    }
}

#[test]
fn volume_block_fields() {
    let (t0, t1) = (0.5, 1.0);
    let samples = volume_samples(2000, t0, t1, 99);
    let enc = encode_volume_block(t0, t1, &samples).unwrap();
    let block = decode_volume_block(&enc.bytes).unwrap();
    assert_eq!((block.t_start, block.t_end), (t0, t1));
    assert_eq!(block.samples.len(), samples.len());
    // The order is a permutation.
    let mut seen = vec![false; samples.len()];
    for &i in &enc.order {
        assert!(!std::mem::replace(&mut seen[i as usize], true));
    }
    for (stored, &input) in block.samples.iter().zip(&enc.order) {
        let s = &samples[input as usize];
        assert!(angle(s.direction, stored.direction) <= 1e-4);
        assert!((s.t - stored.t).abs() <= (t1 - t0) / 131070.0 + 1e-6);
        for (want, got) in [
            (s.radiance, stored.radiance),
            (s.lighting, stored.lighting),
            (s.non_diffuse, stored.non_diffuse),
        ] {
            let bound = want.max_element() * 2f32.powi(-9) + 2f32.powi(-24);
            assert!((want - got).abs().max_element() <= bound);
        }
        assert_eq!(s.distance, stored.distance);
        assert!(angle(s.normal, stored.normal) <= 1e-4);
        assert_eq!(s.object_id, stored.object_id);
        assert!((s.radius - stored.radius).abs() <= s.radius * 2f32.powi(-11));
    }
    // Samples out of the span are rejected.
    let mut bad = samples.clone();
    bad[3].t = 2.0;
    assert!(encode_volume_block(t0, t1, &bad).is_err());
}

#[test]
fn volume_order_is_local() {
    // Morton order: consecutive stored samples are mostly close in direction.
    let samples = volume_samples(4000, 0.0, 1.0, 5);
    let block =
        decode_volume_block(&encode_volume_block(0.0, 1.0, &samples).unwrap().bytes).unwrap();
    let mean = |s: &[VolumeSample]| {
        s.windows(2)
            .map(|w| angle(w[0].direction, w[1].direction))
            .sum::<f32>()
            / (s.len() - 1) as f32
    };
    assert!(mean(&block.samples) < 0.5 * mean(&samples));
}

#[test]
fn connectivity_round_trip_and_remap() {
    let samples = volume_samples(10, 0.0, 1.0, 3);
    let tets = vec![[0, 1, 2, 3], [4, 5, 6, 9]];
    let enc = encode_volume_block(0.0, 1.0, &samples).unwrap();
    let remapped = plenoptic_pack::volume::remap_tetrahedra(&tets, &enc.order).unwrap();
    for (t, r) in tets.iter().zip(&remapped) {
        for k in 0..4 {
            assert_eq!(enc.order[r[k] as usize], t[k]);
        }
    }
    let (bytes, _) = encode_connectivity(10, &remapped).unwrap();
    assert_eq!(decode_connectivity(&bytes).unwrap(), (10, remapped));
    assert!(encode_connectivity(3, &tets).is_err());
}

#[test]
fn whole_pack_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("small.pack");
    let m = write_small_pack(&path);
    let r = PackReader::open(&path).unwrap();
    assert_eq!(r.manifest(), &m);
    assert_eq!(r.header().version_major, VERSION_MAJOR);
    assert_eq!(read_all(&r), r.entries().len());
    let img = room_image(8, 0.3);
    let back = r.range_image(1, 1).unwrap();
    assert_eq!(back.distance, img.distance);
    assert_eq!(back.object_id, img.object_id);
    // Version 2's lighting and non-diffuse cubes, within RGB9E5's bound.
    for (stored, want) in [
        (&back.lighting, &img.lighting),
        (&back.non_diffuse, &img.non_diffuse),
    ] {
        for (a, b) in stored.texels.iter().zip(&want.texels) {
            assert!((*a - *b).abs().max_element() <= b.max_element() / 256.0 + 1e-6);
        }
    }
    assert!(img.lighting.texels.iter().any(|l| l.x > 0.1));
    assert!(img.non_diffuse.texels.iter().any(|e| e.x > 1.0));
    assert_eq!(r.proxy_mesh(1).unwrap(), proxy_mesh(1, true));
    assert_eq!(r.proxy_mesh(2).unwrap(), proxy_mesh(2, false));
    assert_eq!(r.tracks().unwrap(), tracks());
    let block = r.volume_block(1, 0).unwrap();
    assert_eq!(block.samples.len(), 64);
    let tets = r.connectivity(1, 0).unwrap();
    assert_eq!(tets.len(), 20);
    assert!(matches!(
        r.radiance(0, 7),
        Err(PackError::ChunkNotFound { .. })
    ));
    // Each directory row's uncompressed length matches the decoded payload.
    let e = r.entries()[r.find(ChunkKind::RadianceCube, 0, 0).unwrap()];
    assert_eq!(e.uncompressed_length, 6 * 64 * 4);
    // The same pack reads from memory.
    let mem = PackReader::from_reader(std::io::Cursor::new(std::fs::read(&path).unwrap())).unwrap();
    assert_eq!(mem.range_image(1, 1).unwrap(), back);
}

#[test]
fn manifest_json_exact_and_buckets() {
    let m = manifest(3);
    let back = Manifest::from_json(&m.to_json().unwrap()).unwrap();
    assert_eq!(back, m);
    assert_eq!(m.bucket_of(0.0), 0);
    assert_eq!(m.bucket_of(0.49), 0);
    assert_eq!(m.bucket_of(0.5), 1);
    assert_eq!(m.bucket_of(-3.0), 0);
    assert_eq!(m.bucket_of(f32::NAN), 0);
    assert_eq!(m.bucket_range(2), (1.0, 1.5));
    assert_eq!(m.bucket_count(), 5);
}

#[test]
fn reader_is_shareable_across_threads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.pack");
    write_small_pack(&path);
    let r = std::sync::Arc::new(PackReader::open(&path).unwrap());
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let r = r.clone();
            std::thread::spawn(move || read_all(&r))
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), r.entries().len());
    }
}

#[test]
fn levels_decode_with_ruzstd_as_bevy_does() {
    use std::io::Read;
    let img = room_image(16, 0.0);
    for bytes in [
        encode_radiance(&img.radiance, RadianceFormat::Rgb9e5).unwrap(),
        encode_distance(&img.distance, DistanceFormat::R32Float).unwrap(),
        encode_object_id(&img.object_id, ObjectIdFormat::R32Uint).unwrap(),
        encode_normal(&img.normal, NormalFormat::Rg16Snorm).unwrap(),
    ] {
        let r = ktx2::Reader::new(&bytes[..]).unwrap();
        let level = r.levels().next().unwrap();
        let mut cursor = std::io::Cursor::new(level.data);
        let mut decoder = ruzstd::decoding::StreamingDecoder::new(&mut cursor).unwrap();
        let mut out = Vec::new();
        decoder.read_to_end(&mut out).unwrap();
        assert_eq!(out, zstd::decode_all(level.data).unwrap());
        assert_eq!(out.len(), 6 * 16 * 16 * 4);
    }
}
