//! Mutation test: thousands of damaged copies of a valid pack must open and decode to `Ok` or
//! `Err`, never panic and never allocate without bound.

mod common;

use std::io::Cursor;

use common::*;
use plenoptic_pack::*;

/// The packs mutated: every chunk kind of 1.1, (1.2) materials, textures and proxy
/// attributes, and (4.2) light groups' layers.
fn fixtures() -> Vec<Vec<u8>> {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("m.pack"),
        dir.path().join("mat.pack"),
        dir.path().join("groups.pack"),
    );
    write_small_pack(&a);
    write_material_pack(&b);
    write_group_pack(&c);
    [a, b, c].map(|p| std::fs::read(p).unwrap()).to_vec()
}

#[test]
fn mutated_packs_never_panic() {
    for good in fixtures() {
        mutate_whole_file(&good);
    }
}

fn mutate_whole_file(good: &[u8]) {
    let header = Header::parse(good[..128].try_into().unwrap()).unwrap();
    let meta_start = header.manifest_offset as usize;
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut opened, mut decoded) = (0, 0);
    for round in 0..5000 {
        let mut b = good.to_vec();
        match round % 5 {
            // Flip bytes anywhere.
            0 => {
                for _ in 0..1 + rng.below(4) {
                    let i = rng.below(b.len() as u64) as usize;
                    b[i] ^= 1 << rng.below(8);
                }
            }
            // Flip bytes in the header/metadata and fix the checksums, so the damage gets past
            // them and reaches the validation behind.
            1 | 2 => {
                let region = if round % 5 == 1 {
                    8..120
                } else {
                    meta_start..b.len()
                };
                let i = region.start + rng.below((region.end - region.start) as u64) as usize;
                b[i] = rng.next_u64() as u8;
                if let Ok(mut h) = Header::parse(b[..128].try_into().unwrap()) {
                    let d = h.directory_offset as usize;
                    let n = (h.directory_count as usize).saturating_mul(48);
                    if let Some(dir) = d.checked_add(n).and_then(|e| b.get(d..e)) {
                        h.directory_checksum = checksum(dir);
                    }
                    let m = h.manifest_offset as usize;
                    if let Some(man) = m
                        .checked_add(h.manifest_length as usize)
                        .and_then(|e| b.get(m..e))
                    {
                        h.manifest_checksum = checksum(man);
                    }
                    b[..128].copy_from_slice(&h.to_bytes());
                } else {
                    let mut raw = [0u8; 128];
                    raw.copy_from_slice(&b[..128]);
                    // Re-seal the damaged header bytes.
                    let sum = checksum(&raw[..120]);
                    raw[120..].copy_from_slice(&sum.to_le_bytes());
                    b[..128].copy_from_slice(&raw);
                }
            }
            // Truncate.
            3 => {
                let n = rng.below(b.len() as u64) as usize;
                b.truncate(n);
            }
            // Splice a range of the file over another.
            _ => {
                let len = 1 + rng.below(256) as usize;
                let src = rng.below((b.len() - len) as u64) as usize;
                let dst = rng.below((b.len() - len) as u64) as usize;
                let piece = b[src..src + len].to_vec();
                b[dst..dst + len].copy_from_slice(&piece);
            }
        }
        if let Ok(r) = PackReader::from_reader(Cursor::new(b)) {
            opened += 1;
            decoded += read_all(&r);
        }
    }
    // The test also exercises the success paths.
    assert!(opened > 100, "{opened} opened");
    assert!(decoded > 100, "{decoded} decoded");
}

#[test]
fn chunk_payload_mutations_with_fixed_checksums() {
    // Damage inside chunks, with the directory checksum fixed so decoders see it.
    for good in fixtures() {
        mutate_chunks(&good);
    }
}

fn mutate_chunks(good: &[u8]) {
    let r = PackReader::from_reader(Cursor::new(good.to_vec())).unwrap();
    let entries = r.entries().to_vec();
    let mut rng = Rng(12345);
    for round in 0..2000 {
        let mut b = good.to_vec();
        let ci = rng.below(entries.len() as u64) as usize;
        let e = entries[ci];
        // Mostly the headers (first 160 bytes); every fourth round anywhere in the chunk.
        let span = if round % 4 == 3 {
            e.length
        } else {
            e.length.min(160)
        };
        let i = e.offset as usize + rng.below(span) as usize;
        b[i] = rng.next_u64() as u8;
        let sum = checksum(&b[e.offset as usize..(e.offset + e.length) as usize]);
        let h = Header::parse(b[..128].try_into().unwrap()).unwrap();
        let row = h.directory_offset as usize + ci * 48;
        b[row + 40..row + 48].copy_from_slice(&sum.to_le_bytes());
        let mut h2 = h;
        h2.directory_checksum =
            checksum(&b[h.directory_offset as usize..][..h.directory_count as usize * 48]);
        b[..128].copy_from_slice(&h2.to_bytes());
        let r = PackReader::from_reader(Cursor::new(b)).unwrap();
        let _ = r.chunk(ci);
        read_all(&r);
    }
}
