//! A reconstructor whose cubes come from a runtime's streaming (`plenoptic_recon::streamed`):
//! with every key in its source it renders the same frame as from the pack and reads no
//! chunk itself; with a key missing it renders from those it has, reporting nothing missing
//! (absence is not an error).

mod common;

use std::collections::HashMap;
use std::sync::Arc;

use common::*;
use plenoptic_pack::{ChunkKind, PackReader};
use plenoptic_recon::streamed::{CUBE_KINDS, read_cube};
use plenoptic_recon::{Camera, KeySource, Mode, Reconstructor, StreamedCube};
use plenoptic_trace::glam::Vec3;

/// The cubes of some keys, decoded up front.
struct Resident(HashMap<(ChunkKind, u32, u32), StreamedCube>);

impl Resident {
    /// The cubes of every (view, key) that `keep` accepts.
    fn of(pack: &PackReader, keep: impl Fn(u32, u32) -> bool) -> Self {
        let mut cubes = HashMap::new();
        for (v, bv) in pack.manifest().base_views.iter().enumerate() {
            for k in 0..bv.time_keys.len() as u32 {
                if !keep(v as u32, k) {
                    continue;
                }
                for kind in CUBE_KINDS {
                    if let Some(c) = read_cube(pack, kind, v as u32, k).unwrap() {
                        cubes.insert((kind, v as u32, k), c);
                    }
                }
            }
        }
        Resident(cubes)
    }
}

impl KeySource for Resident {
    fn cube(&self, kind: ChunkKind, view: u32, key: u32) -> Option<StreamedCube> {
        self.0.get(&(kind, view, key)).cloned()
    }
}

#[test]
fn a_key_source_replaces_the_packs_cubes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    let spec = PackSpec {
        materials: Materials::Factors,
        ..PackSpec::segment(3, vec![0.0, 0.5, 1.0], 16)
    };
    write_pack(&room(true), &spec, &path);
    let pack = PackReader::open(&path).unwrap();
    let cam = Camera::look_at(
        Vec3::new(0.3, 1.3, 1.0),
        Vec3::new(0.0, 0.8, -2.5),
        Vec3::Y,
        1.1,
        48,
        36,
    )
    .unwrap();
    let t = 0.7;

    let from_pack = Reconstructor::open(&path).unwrap();
    let (expected, _) = from_pack.render(&cam, t, Mode::GeometryAssisted).unwrap();
    assert!(from_pack.chunks_read() > 0);

    // Every key in the source: the same frame, and no chunk read from the pack.
    let streamed = Reconstructor::open(&path).unwrap();
    streamed.set_key_source(Some(Arc::new(Resident::of(&pack, |_, _| true))));
    let (frame, report) = streamed.render(&cam, t, Mode::GeometryAssisted).unwrap();
    assert_eq!(frame.radiance, expected.radiance);
    assert_eq!(streamed.chunks_read(), 0, "the pack's cubes were not read");
    assert!(report.missing.is_empty(), "{:?}", report.missing);

    // The key after t missing at every view: a frame from the key before it, nothing
    // reported missing, and it differs.
    let partial = Reconstructor::open(&path).unwrap();
    partial.set_key_source(Some(Arc::new(Resident::of(&pack, |_, k| k != 2))));
    let (frame, report) = partial.render(&cam, t, Mode::GeometryAssisted).unwrap();
    assert!(report.missing.is_empty(), "{:?}", report.missing);
    assert_eq!(partial.chunks_read(), 0);
    let lit = frame
        .radiance
        .iter()
        .filter(|c| c.max_element() > 0.0)
        .count();
    assert!(lit > frame.radiance.len() / 2, "{lit} pixels lit");
    assert_ne!(frame.radiance, expected.radiance);

    // The source removed: the pack again.
    partial.set_key_source(None);
    let (frame, _) = partial.render(&cam, t, Mode::GeometryAssisted).unwrap();
    assert_eq!(frame.radiance, expected.radiance);
    assert!(partial.chunks_read() > 0);
}
