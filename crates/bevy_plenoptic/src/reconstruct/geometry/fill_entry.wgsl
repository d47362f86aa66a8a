// The screen-space hole fill's per-pixel entries (screen_fill.rs; thesis §8.2.3's hole fill
// over the first pass's output): what a proxy fragment drawn in the opaque pass leaves at its
// pixel for the fill kernel (screen_fill.wgsl), 16 bytes:
// - a pixel its lookups answered: its terms (lighting and non-diffuse, or radiance and 0;
//   lookup.wgsl's Weighted) times the camera's exposure, and its object + 1;
// - a hole: what the fragment adds to its reconstructed radiance (reflection, emission, the
//   runtime sun) times the exposure, the albedo and non-diffuse weight it shades filled terms
//   with, its object + 1 and HOLE;
// - nothing drawn there: 0.
// Colours are kept as half floats (the HDR target's own precision), two per word.
#define_import_path plenoptic::fill_entry

// Tag bits (w): a hole; a hole that adds the non-diffuse term; the object + 1 below them.
const HOLE: u32 = 0x80000000u;
const HOLE_NON_DIFFUSE: u32 = 0x40000000u;
const OBJECT_BITS: u32 = 0x3fffffffu;

// The largest half float.
const HALF_MAX: f32 = 65504.0;

// Two colours as three words of half floats.
fn pack_pair(a: vec3<f32>, b: vec3<f32>) -> vec3<u32> {
    let x = clamp(a, vec3<f32>(-HALF_MAX), vec3<f32>(HALF_MAX));
    let y = clamp(b, vec3<f32>(-HALF_MAX), vec3<f32>(HALF_MAX));
    return vec3<u32>(pack2x16float(x.xy), pack2x16float(vec2<f32>(x.z, y.x)), pack2x16float(y.yz));
}

// The two colours of `pack_pair`, as the columns of a matrix.
fn unpack_pair(w: vec3<u32>) -> mat2x3<f32> {
    let a = unpack2x16float(w.x);
    let m = unpack2x16float(w.y);
    let b = unpack2x16float(w.z);
    return mat2x3<f32>(vec3<f32>(a, m.x), vec3<f32>(m.y, b));
}
