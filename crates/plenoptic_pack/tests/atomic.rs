//! Atomic commit and bounded writer memory.

mod common;

use common::*;
use plenoptic_pack::*;

fn files_in(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn dropped_writer_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pack");
    {
        let mut w = PackWriter::create(&path).unwrap();
        w.add_range_image(0, 0, &room_image(8, 0.0), CubeFormats::default())
            .unwrap();
        assert_eq!(files_in(dir.path()).len(), 1, "only the temporary file");
        assert!(!path.exists());
    }
    assert!(!path.exists());
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}

#[test]
fn existing_pack_untouched_by_failed_or_dropped_write() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.pack");
    write_small_pack(&path);
    let before = std::fs::read(&path).unwrap();
    {
        let mut w = PackWriter::create(&path).unwrap();
        w.add_range_image(0, 0, &room_image(4, 0.0), CubeFormats::default())
            .unwrap();
    }
    assert_eq!(std::fs::read(&path).unwrap(), before);
    let mut w = PackWriter::create(&path).unwrap();
    w.add_range_image(9, 0, &room_image(4, 0.0), CubeFormats::default())
        .unwrap();
    assert!(w.finish(&manifest(1)).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_eq!(files_in(dir.path()), vec!["b.pack".to_string()]);
    // A successful write replaces it.
    let m = manifest(1);
    PackWriter::create(&path).unwrap().finish(&m).unwrap();
    assert_eq!(PackReader::open(&path).unwrap().manifest(), &m);
}

#[test]
fn partial_file_does_not_look_like_a_pack() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.pack");
    let mut w = PackWriter::create(&path).unwrap();
    w.add_range_image(0, 0, &room_image(4, 0.0), CubeFormats::default())
        .unwrap();
    let partial = dir.path().join(&files_in(dir.path())[0]);
    assert!(matches!(
        PackReader::open(&partial).unwrap_err(),
        PackError::BadMagic(_)
    ));
    drop(w);
}

#[test]
fn writer_memory_does_not_grow_with_payload() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.pack");
    let mut w = PackWriter::create(&path).unwrap();
    let payload = vec![0xa5u8; 1 << 20];
    for i in 0..64u32 {
        w.add_raw_chunk(ChunkKind::Unknown(99), NO_BASE_VIEW, i, &payload, 0, None)
            .unwrap();
    }
    // 64 MiB went to disk; the writer holds only its rows (and their address set).
    assert!(w.bytes_written() >= 64 << 20);
    assert!(w.buffered_bytes() < 64 * 1024, "{}", w.buffered_bytes());
    let per_row = w.buffered_bytes() / 64;
    assert!(per_row <= 256, "{per_row} bytes per row");
    w.finish(&manifest(0)).unwrap();
    assert_eq!(PackReader::open(&path).unwrap().entries().len(), 64);
}
