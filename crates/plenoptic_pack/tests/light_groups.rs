//! Light groups in a pack (4.2): the groups' layers read back, and packs whose chunks disagree
//! with their declared groups are refused with an error that names the chunk.

mod common;

use common::*;
use plenoptic_pack::*;

#[test]
fn group_layers_read_back_beside_the_total() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.pack");
    let m = write_group_pack(&path);
    let r = PackReader::open(&path).unwrap();
    assert_eq!(r.manifest().light_groups, m.light_groups);
    let total = r.lighting(0, 1).unwrap();
    let daylight = r.group_lighting(0, 1, 1).unwrap();
    // The fixture's daylight layer is 0.75 of the total (RGB9E5 rounding aside).
    for (t, d) in total.texels.iter().zip(&daylight.texels) {
        assert!((*t * 0.75).abs_diff_eq(*d, 0.01 * t.max_element() + 1e-6));
    }
    let block = r.volume_block(0, 0).unwrap();
    let values = r.group_volume(0, 0, 0).unwrap();
    assert_eq!(values.len(), block.samples.len());
    for (s, v) in block.samples.iter().zip(&values) {
        assert!((s.lighting * 0.25).abs_diff_eq(v[0], 0.01 * s.lighting.max_element() + 1e-6));
    }
    assert!(matches!(
        r.group_lighting(0, 0, 2),
        Err(PackError::ChunkNotFound { .. })
    ));
}

/// `write_group_pack`'s chunks with `keep` deciding which are written again, under
/// `manifest` (which the writer checks).
fn rewrite(
    dir: &std::path::Path,
    manifest: &Manifest,
    keep: impl Fn(&ChunkEntry) -> bool,
) -> Result<std::path::PathBuf> {
    let source = dir.join("source.pack");
    write_group_pack(&source);
    let r = PackReader::open(&source).unwrap();
    let out = dir.join("damaged.pack");
    let mut w = PackWriter::create(&out).unwrap();
    for (i, e) in r.entries().iter().enumerate() {
        if keep(e) {
            let bytes = r.chunk_bytes(i).unwrap();
            w.add_raw_chunk(
                e.kind,
                e.base_view,
                e.key,
                &bytes,
                e.uncompressed_length,
                None,
            )
            .unwrap();
        }
    }
    w.finish(manifest)?;
    Ok(out)
}

#[test]
fn a_missing_layer_or_an_undeclared_group_is_refused_naming_the_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let m = write_group_pack(&dir.path().join("m.pack"));
    let missing = rewrite(dir.path(), &m, |e| e.kind != ChunkKind::GroupNonDiffuse(1)).unwrap();
    let e = PackReader::open(&missing).err().unwrap();
    assert!(matches!(e, PackError::LightGroupMismatch { .. }), "{e}");
    assert!(e.to_string().contains("GroupNonDiffuse(1)"), "{e}");

    let no_volume = rewrite(dir.path(), &m, |e| e.kind != ChunkKind::GroupVolume(0)).unwrap();
    assert!(matches!(
        PackReader::open(&no_volume),
        Err(PackError::LightGroupMismatch { .. })
    ));

    // One group declared, two stored.
    let mut one = m.clone();
    let g = one.light_groups.as_mut().unwrap();
    g.names.truncate(1);
    g.objects = vec![Some(0); one.objects.len()];
    g.sun = None;
    g.sky = None;
    let extra = rewrite(dir.path(), &one, |_| true).unwrap();
    let e = PackReader::open(&extra).err().unwrap();
    assert!(e.to_string().contains("light group 1"), "{e}");

    // Groups' chunks in a pack that declares none.
    let mut none = m.clone();
    none.light_groups = None;
    assert!(PackReader::open(rewrite(dir.path(), &none, |_| true).unwrap()).is_err());
}

#[test]
fn a_manifest_whose_group_indices_are_out_of_range_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.pack");
    let mut m = write_group_pack(&path);
    // The writer refuses it.
    m.light_groups.as_mut().unwrap().sky = Some(5);
    let e = rewrite(dir.path(), &m, |_| true).err().unwrap();
    assert!(e.to_string().contains("index 5"), "{e}");
    // A file that says it anyway (the manifest edited, its checksums fixed) does not open.
    let mut b = std::fs::read(&path).unwrap();
    let mut h = Header::parse(b[..128].try_into().unwrap()).unwrap();
    let (start, len) = (h.manifest_offset as usize, h.manifest_length as usize);
    let text = String::from_utf8(b[start..start + len].to_vec()).unwrap();
    let edited = text.replace("\"sky\":1", "\"sky\":5");
    assert_ne!(edited, text, "the fixture's manifest names the sky's group");
    b[start..start + len].copy_from_slice(edited.as_bytes());
    h.manifest_checksum = checksum(edited.as_bytes());
    b[..128].copy_from_slice(&h.to_bytes());
    let e = PackReader::from_reader(std::io::Cursor::new(b))
        .err()
        .unwrap();
    assert!(matches!(e, PackError::InvalidManifest { .. }), "{e}");
    assert!(e.to_string().contains("index 5"), "{e}");
}
