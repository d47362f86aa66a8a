// What the screen-space hole fill (screen_fill.rs; thesis §8.2.3's hole fill over the first
// pass's output) reads: what each proxy fragment drawn in the opaque pass leaves for the fill
// kernel (screen_fill.wgsl). Per pixel an entry of 16 bytes:
// - a pixel its lookups answered: its terms (lighting and non-diffuse, or radiance and 0;
//   lookup.wgsl's Weighted) times the camera's exposure (xyz), its object + 1 (w);
// - a hole, or a point left to the lookup kernel: its record's index in the hole list (x),
//   its object + 1 with HOLE (w);
// - nothing drawn there: 0.
// Per hole fragment a record in the camera's hole list (HoleRecord), appended by the fragment.
// With MSAA two fragments may share a pixel and its entry (the last write stays); a record is
// the fragment's own, so the kernel and the composite read only records.
// Colours are kept as half floats (the HDR target's own precision), two per word.
#define_import_path plenoptic::fill_entry

// Tag bits (w): a hole; a hole that adds the non-diffuse term; the object + 1 below them.
const HOLE: u32 = 0x80000000u;
const HOLE_NON_DIFFUSE: u32 = 0x40000000u;
const OBJECT_BITS: u32 = 0x3fffffffu;

// A hole's record.
struct HoleRecord {
    // What its fragment adds to the reconstructed radiance (reflection, emission, the runtime
    // sun) times the exposure, and the albedo it shades filled terms with (pack_pair).
    pair: vec3<u32>,
    // Its pixel (row-major in the viewport).
    pixel: u32,
    // Its point in its object's frame (lookup.wgsl's object_point) and its motion slot (w).
    local: vec4<f32>,
    // Its world point, and the nearest depth its surface reaches in the pixel (w; Bevy's
    // reversed depth): the composite writes only samples no nearer than that.
    world: vec4<f32>,
    // Its object + 1, with HOLE_NON_DIFFUSE and HOLE_MATERIAL.
    tag: u32,
    // The same in the world (lookup.wgsl's world_face_normal), packed alike.
    world_normal: u32,
    // Its surface normal facing the eye in its lookups' frame (lookup.wgsl's face_normal),
    // oct-encoded as two snorm16 (pack_normal).
    normal: u32,
    // RECORD_HOLE, RECORD_LOOKUP, RECORD_SPARSE or RECORD_ANSWERED (RECORD_STATE's bits),
    // and above them the samples its fragment covers (its sample mask; 1 without MSAA).
    state: u32,
}

// A record's state: a hole the fill kernel fills; a point whose lookups the lookup kernel
// makes (VIEW_LOOKUP_KERNEL); a point the lookup kernel answered (its colour in `pair`); a
// point the sparse lighting interpolates from its anchors or looks up after them.
const RECORD_HOLE: u32 = 0u;
const RECORD_LOOKUP: u32 = 1u;
const RECORD_ANSWERED: u32 = 2u;
const RECORD_SPARSE: u32 = 3u;
// The bits of a record's state word that hold its state; its coverage is above them.
const RECORD_STATE: u32 = 0xffu;
const COVERAGE_SHIFT: u32 = 8u;

// The state of a record's state word.
fn record_state(word: u32) -> u32 {
    return word & RECORD_STATE;
}

// A record's state word with its state set to `state`, its coverage kept.
fn with_state(word: u32, state: u32) -> u32 {
    return (word & ~RECORD_STATE) | state;
}

// The packed normal of no normal (the face test left out).
const NO_NORMAL: u32 = 0xffffffffu;

// Unit `n` oct-encoded into two snorm16 (zero: NO_NORMAL).
fn pack_normal(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if l1 == 0.0 {
        return NO_NORMAL;
    }
    var e = n.xy / l1;
    if n.z < 0.0 {
        e = (1.0 - abs(e.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
    }
    return pack2x16snorm(e);
}

// The unit normal of `pack_normal` (NO_NORMAL: zero).
fn unpack_normal(w: u32) -> vec3<f32> {
    if w == NO_NORMAL {
        return vec3<f32>(0.0);
    }
    let e = unpack2x16snorm(w);
    var v = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-v.z, 0.0);
    v = vec3<f32>(v.x + select(t, -t, v.x >= 0.0), v.y + select(t, -t, v.y >= 0.0), v.z);
    return normalize(v);
}

// A record's tag bit: its object is shaded from its material.
const HOLE_MATERIAL: u32 = 0x80000000u;

// A camera's hole list: records appended, the first `count` of them written (count may pass
// the list's length: those holes were filled by their fragments). The fill kernel writes each
// record's filled colour over its `pair` (column 0).
struct HoleList {
    count: atomic<u32>,
    records: array<HoleRecord>,
}

// The same list, read.
struct HoleRecords {
    count: u32,
    records: array<HoleRecord>,
}

// The fill passes' uniform (screen_fill.rs, FillParams).
struct FillParams {
    // The entries' size (the view's viewport) and its offset in the target.
    size: vec2<u32>,
    offset: vec2<u32>,
    // The ring search's largest radius; the camera's exposure.
    radius: u32,
    exposure: f32,
    // The camera's position (xyz), which the lookup kernel weighs views from.
    eye: vec4<f32>,
}

// The step along row `dy` of the ring of radius `r` around a pixel (plenoptic_recon's ring
// search): whole rows at the ring's top and bottom, the two ends elsewhere.
fn ring_step(r: i32, dy: i32) -> i32 {
    return select(2 * r, 1, abs(dy) == r);
}

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
