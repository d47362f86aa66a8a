//! Fuzzes the pack reader: open from memory, then read and decode every chunk. Any input must
//! give `Ok` or `Err`, never a panic or an unbounded allocation.
//!
//! Run with `cargo +nightly fuzz run pack_reader` from the repository root.
#![no_main]

use libfuzzer_sys::fuzz_target;
use plenoptic_pack::PackReader;

fuzz_target!(|data: &[u8]| {
    if let Ok(reader) = PackReader::from_reader(std::io::Cursor::new(data.to_vec())) {
        for i in 0..reader.entries().len() {
            let _ = reader.chunk(i);
        }
        for i in 0..reader.textures().len() {
            let _ = reader.texture(i as u32);
        }
        for o in &reader.manifest().objects {
            let _ = reader.proxy_attributes(o.id);
        }
    }
    // The chunk decoders on their own, for inputs that are a single chunk.
    let _ = plenoptic_pack::decode_radiance(data);
    let _ = plenoptic_pack::decode_volume_block(data);
    let _ = plenoptic_pack::proxy::decode_tracks(data);
    let _ = plenoptic_pack::decode_texture(data);
    let _ = plenoptic_pack::decode_proxy_attributes(data);
});
