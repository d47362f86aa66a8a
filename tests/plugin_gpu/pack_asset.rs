//! The `RadiancePack` asset: a good pack loads (header, manifest, directory and proxies); a
//! truncated or damaged pack is an asset load failure naming the problem; a chunk that fails
//! its checksum while streaming becomes a `PlenopticEvent::ChunkFailed`. The app never panics.

use crate::common::*;
use crate::pack::{PackSpec, room, write_pack};
use bevy::asset::LoadState;
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::streaming::StreamingStats;
use plenoptic_pack::{ChunkKind, PackReader};

fn make_pack(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("room.pack");
    write_pack(
        &room(true),
        &PackSpec::segment(2, vec![0.0, 1.0, 2.0], 8),
        &path,
    );
    path
}

/// Updates until the pack's load state settles; returns it.
fn load_state(app: &mut App, handle: &Handle<RadiancePack>) -> LoadState {
    for _ in 0..500 {
        app.update();
        let state = app.world().resource::<AssetServer>().load_state(handle);
        if !matches!(state, LoadState::Loading | LoadState::NotLoaded) {
            return state;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!("pack never finished loading");
}

#[test]
fn good_pack_loads_and_streams() {
    let dir = tempfile::tempdir().unwrap();
    make_pack(dir.path());
    let mut app = headless_app_in(dir.path());
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    app.world_mut().spawn((
        PlenopticCamera {
            playback: Playback::Manual,
            time: 0.5,
            ..PlenopticCamera::new(handle.clone())
        },
        Transform::from_xyz(0.0, 1.3, 1.0),
    ));
    assert!(matches!(load_state(&mut app, &handle), LoadState::Loaded));
    let packs = app.world().resource::<Assets<RadiancePack>>();
    let pack = packs.get(&handle).unwrap();
    assert_eq!(pack.reader.manifest().base_views.len(), 2);
    assert_eq!(pack.proxies.len(), 9);
    assert!(pack.failed.is_empty());
    // Streaming brings in both views at keys 0 and 1.
    for _ in 0..200 {
        app.update();
        if app.world().resource::<StreamingStats>().decoded_keys >= 4 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let stats = app.world().resource::<StreamingStats>().clone();
    assert!(stats.decoded_keys >= 4, "{stats:?}");
    assert!(stats.hits > 0, "{stats:?}");
}

#[test]
fn truncated_and_damaged_packs_fail_to_load() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_pack(dir.path());
    let bytes = std::fs::read(&path).unwrap();
    // Truncated: the directory (at the end) is cut off.
    std::fs::write(dir.path().join("truncated.pack"), &bytes[..bytes.len() / 2]).unwrap();
    // Damaged header magic.
    let mut bad = bytes.clone();
    bad[0] ^= 0xff;
    std::fs::write(dir.path().join("badmagic.pack"), &bad).unwrap();
    // Not even a header.
    std::fs::write(dir.path().join("empty.pack"), b"").unwrap();

    let mut app = headless_app_in(dir.path());
    for name in ["truncated.pack", "badmagic.pack", "empty.pack"] {
        let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load(name);
        match load_state(&mut app, &handle) {
            LoadState::Failed(err) => {
                let msg = err.to_string();
                assert!(msg.contains(name), "{name}: {msg}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
    // The app keeps running.
    for _ in 0..3 {
        app.update();
    }
}

#[derive(Resource, Default)]
struct Failures(Vec<PlenopticEvent>);

fn collect(mut events: MessageReader<PlenopticEvent>, mut out: ResMut<Failures>) {
    out.0.extend(events.read().cloned());
}

#[test]
fn corrupted_chunk_is_reported_while_streaming() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_pack(dir.path());
    let reader = PackReader::open(&path).unwrap();
    let i = reader.find(ChunkKind::RadianceCube, 0, 0).unwrap();
    let e = reader.entries()[i];
    drop(reader);
    let mut bytes = std::fs::read(&path).unwrap();
    for b in &mut bytes[e.offset as usize + 40..e.offset as usize + 48] {
        *b ^= 0x5a;
    }
    std::fs::write(&path, &bytes).unwrap();

    let mut app = headless_app_in(dir.path());
    app.init_resource::<Failures>()
        .add_systems(Update, collect.after(PlenopticSystems::Streaming));
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    app.world_mut().spawn((
        PlenopticCamera {
            playback: Playback::Manual,
            ..PlenopticCamera::new(handle.clone())
        },
        Transform::from_xyz(-1.0, 1.3, 1.0),
    ));
    assert!(matches!(load_state(&mut app, &handle), LoadState::Loaded));
    for _ in 0..300 {
        app.update();
        if !app.world().resource::<Failures>().0.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let failures = &app.world().resource::<Failures>().0;
    let [PlenopticEvent::ChunkFailed { chunk, reason }] = failures.as_slice() else {
        panic!("{failures:?}");
    };
    assert!(chunk.contains("RadianceCube view 0 key 0"), "{chunk}");
    assert!(reason.to_lowercase().contains("checksum"), "{reason}");
    for _ in 0..5 {
        app.update();
    }
}
