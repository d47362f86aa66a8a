//! The pack's environment: every kind round-trips through a file, and damaged or
//! inconsistent environments give errors that name the pack and the problem.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::manifest;
use plenoptic_pack::glam::Vec3;
use plenoptic_pack::plenoptic_sky::{
    Environment, EquirectImage, SkyParams, SunTrack, SunTrackSample,
};
use plenoptic_pack::*;

fn track() -> SunTrack {
    SunTrack::new(vec![
        SunTrackSample {
            time: 0.0,
            direction: Vec3::new(1.0, 0.2, 0.0).normalize(),
            illuminance: Vec3::splat(50_000.0),
        },
        SunTrackSample {
            time: 1.0,
            direction: Vec3::new(0.0, 1.0, 0.3).normalize(),
            illuminance: Vec3::splat(100_000.0),
        },
    ])
    .unwrap()
}

fn image() -> EquirectImage {
    let texels = (0..16 * 8)
        .map(|i| Vec3::new(i as f32 * 0.25, 2.0, 0.5 + (i % 3) as f32))
        .collect();
    EquirectImage::new(16, 8, texels).unwrap()
}

/// Writes a pack with `env` and returns what it reads back.
fn round_trip(path: &Path, env: &Environment, sun: Option<SunTrack>) -> (Environment, PackReader) {
    let mut w = PackWriter::create(path).unwrap();
    if let Environment::Image { image, .. } = env {
        w.add_environment_image(image).unwrap();
    }
    let mut m = manifest(1);
    m.environment = Some(EnvironmentEntry::new(env, sun));
    w.finish(&m).unwrap();
    let r = PackReader::open(path).unwrap();
    assert_eq!(r.manifest(), &m);
    (r.environment().unwrap(), r)
}

#[test]
fn every_kind_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("env.pack");
    let (env, r) = round_trip(&path, &Environment::None, None);
    assert_eq!(env, Environment::None);
    assert!(r.sun_track().is_none());

    let uniform = Environment::Uniform(Vec3::new(0.5, 1.0, 2.0));
    assert_eq!(round_trip(&path, &uniform, None).0, uniform);

    let sky = Environment::Sky(SkyParams {
        turbidity: 4.5,
        ground_albedo: Vec3::new(0.1, 0.2, 0.3),
        scale: 1000.0,
        ground: true,
    });
    let (env, r) = round_trip(&path, &sky, Some(track()));
    assert_eq!(env, sky);
    assert_eq!(r.sun_track(), Some(&track()));

    let img = Environment::Image {
        image: Arc::new(image()),
        intensity: 3.0,
        rotation_deg: 30.0,
    };
    let (env, _) = round_trip(&path, &img, None);
    let Environment::Image {
        image: back,
        intensity,
        rotation_deg,
    } = env
    else {
        panic!("not an image: {env:?}");
    };
    assert_eq!((intensity, rotation_deg), (3.0, 30.0));
    assert_eq!((back.width, back.height), (16, 8));
    for (a, b) in image().texels.iter().zip(&back.texels) {
        // f16: relative 2⁻¹¹.
        assert!(
            (*a - *b).abs().max_element() <= a.max_element() * 4.9e-4,
            "{a} {b}"
        );
    }
}

#[test]
fn a_pack_without_an_entry_reads_as_no_environment() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("old.pack");
    common::write_small_pack(&path);
    let r = PackReader::open(&path).unwrap();
    assert!(r.manifest().environment.is_none());
    assert_eq!(r.environment().unwrap(), Environment::None);
    // The manifest of a pack without an environment has no `environment` key at all.
    let json = r.manifest().to_json().unwrap();
    assert!(!String::from_utf8(json).unwrap().contains("environment"));
}

fn write_image_pack(path: &Path, chunk: &[u8], width: u32, height: u32) {
    let mut w = PackWriter::create(path).unwrap();
    w.add_raw_chunk(
        ChunkKind::EnvironmentImage,
        NO_BASE_VIEW,
        0,
        chunk,
        u64::from(width) * u64::from(height) * 6,
        None,
    )
    .unwrap();
    let mut m = manifest(1);
    m.environment = Some(EnvironmentEntry {
        source: EnvironmentSource::Image {
            width,
            height,
            intensity: 1.0,
            rotation_deg: 0.0,
        },
        sun: None,
        direct_sun: None,
    });
    w.finish(&m).unwrap();
}

#[test]
fn truncated_or_inconsistent_image_chunks_are_named_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (bytes, _) = encode_environment_image(&image()).unwrap();
    let path = dir.path().join("truncated.pack");
    write_image_pack(&path, &bytes[..bytes.len() - 7], 16, 8);
    let r = PackReader::open(&path).unwrap();
    let e = r.environment().unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, PackError::InvalidEnvironment { .. }), "{e}");
    assert!(
        msg.contains("truncated.pack") && msg.contains("zstd"),
        "{msg}"
    );

    let path = dir.path().join("header.pack");
    write_image_pack(&path, &bytes[..9], 16, 8);
    let msg = environment_error(&path);
    assert!(
        msg.contains("header.pack") && msg.contains("EnvironmentImage"),
        "{msg}"
    );

    let path = dir.path().join("size.pack");
    write_image_pack(&path, &bytes, 32, 16);
    let e = PackReader::open(&path).unwrap().environment().unwrap_err();
    // The directory's uncompressed length disagrees with the chunk's own header.
    assert!(e.to_string().contains("size.pack"), "{e}");

    // A consistent directory but a manifest that disagrees with the chunk's size.
    let path = dir.path().join("manifest.pack");
    let mut w = PackWriter::create(&path).unwrap();
    w.add_environment_image(&image()).unwrap();
    let mut m = manifest(1);
    m.environment = Some(EnvironmentEntry {
        source: EnvironmentSource::Image {
            width: 8,
            height: 8,
            intensity: 1.0,
            rotation_deg: 0.0,
        },
        sun: None,
        direct_sun: None,
    });
    w.finish(&m).unwrap();
    let msg = environment_error(&path);
    assert!(
        msg.contains("manifest.pack") && msg.contains("8 × 8"),
        "{msg}"
    );

    // No chunk at all.
    let path = dir.path().join("missing.pack");
    let w = PackWriter::create(&path).unwrap();
    w.finish(&m).unwrap();
    let msg = environment_error(&path);
    assert!(
        msg.contains("missing.pack") && msg.contains("EnvironmentImage"),
        "{msg}"
    );
}

#[test]
fn invalid_sun_tracks_and_parameters_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun.pack");
    let sky = Environment::Sky(SkyParams::default());
    round_trip(&path, &sky, Some(track()));
    // Make the second sample's time equal the first's (same length), fix the checksums.
    let mut bytes = std::fs::read(&path).unwrap();
    let mut h = Header::parse(bytes[..128].try_into().unwrap()).unwrap();
    let (off, len) = (h.manifest_offset as usize, h.manifest_length as usize);
    let json = String::from_utf8(bytes[off..off + len].to_vec()).unwrap();
    assert!(json.contains("\"time\":1.0"), "{json}");
    let edited = json.replace("\"time\":1.0", "\"time\":0.0");
    bytes[off..off + len].copy_from_slice(edited.as_bytes());
    h.manifest_checksum = checksum(edited.as_bytes());
    bytes[..128].copy_from_slice(&h.to_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let e = PackReader::open(&path).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, PackError::InvalidEnvironment { .. }), "{e}");
    assert!(
        msg.contains("sun.pack") && msg.contains("times must increase"),
        "{msg}"
    );

    // The writer refuses what the reader would refuse.
    let w = PackWriter::create(dir.path().join("bad.pack")).unwrap();
    let mut m = manifest(1);
    m.environment = Some(EnvironmentEntry::new(
        &Environment::Sky(SkyParams {
            turbidity: 20.0,
            ..SkyParams::default()
        }),
        None,
    ));
    let msg = w.finish(&m).unwrap_err().to_string();
    assert!(msg.contains("turbidity"), "{msg}");
    let w = PackWriter::create(dir.path().join("bad.pack")).unwrap();
    m.environment = Some(EnvironmentEntry::new(
        &Environment::Uniform(Vec3::new(f32::NAN, 0.0, 0.0)),
        None,
    ));
    assert!(w.finish(&m).is_err());
}

/// The message of the error reading the environment of the pack at `path` (which opens).
fn environment_error(path: &std::path::Path) -> String {
    PackReader::open(path)
        .unwrap()
        .environment()
        .unwrap_err()
        .to_string()
}

#[test]
fn a_runtime_sun_round_trips_and_needs_its_track() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("direct.pack");
    let w = PackWriter::create(&path).unwrap();
    let mut m = manifest(1);
    let mut entry = EnvironmentEntry::new(&Environment::None, Some(track()));
    entry.direct_sun = Some(DirectSun {
        angular_radius: 0.00465,
    });
    m.environment = Some(entry.clone());
    w.finish(&m).unwrap();
    let r = PackReader::open(&path).unwrap();
    let (t, d) = r.direct_sun().unwrap();
    assert_eq!(t, &track());
    assert_eq!(d.angular_radius, 0.00465);

    // Without a track, or with a disc past the limit, the writer refuses it (and so would
    // the reader: both call the same check).
    for (sun, radius, expect) in [
        (None, 0.0, "without a sun track"),
        (Some(track()), 0.7, "angular radius 0.7"),
        (Some(track()), f32::NAN, "angular radius NaN"),
    ] {
        let w = PackWriter::create(dir.path().join("bad.pack")).unwrap();
        let mut e = entry.clone();
        e.sun = sun;
        e.direct_sun = Some(DirectSun {
            angular_radius: radius,
        });
        m.environment = Some(e);
        let msg = w.finish(&m).unwrap_err().to_string();
        assert!(msg.contains(expect), "{msg}");
    }
    // A pack without the entry has no runtime sun, even with a track.
    let (_, r) = round_trip(
        &dir.path().join("plain.pack"),
        &Environment::None,
        Some(track()),
    );
    assert!(r.direct_sun().is_none() && r.sun_track().is_some());
}
