// The screen-space hole fill (thesis §8.2.3, plenoptic_recon's geometry::fill), a compute
// pass per view between Bevy's opaque and transparent passes, one thread per record of the
// room of the camera's hole list (fill_entry.wgsl); the threads past the holes listed return
// at once. A hole takes the nearest ring of pixels (radius 1 to `radius`) holding answered
// pixels of its own object, averages their terms and shades them with its own albedo and
// non-diffuse weight; where no ring has one, its object's nearby
// texels around its lookups, else the heaviest key's texel (lookup.wgsl's fallbacks, as its
// fragment would take them). What its fragment added comes on top, and the colour is written
// over the hole's record, which the composite pass (fill_composite.wgsl) draws into the
// view's target. No pixel's lookups are computed again: a ring pixel costs one 16-byte load.
//
// The lookups' bindings (the keys, their shading texels, the camera's view buffer, the
// counters) are the material's, bound here as group 1 (MATERIAL_BIND_GROUP).
#import plenoptic::fill_entry::{
    HoleList, FillParams, HOLE_NON_DIFFUSE, HOLE_MATERIAL, OBJECT_BITS, unpack_pair, pack_pair,
    ring_step, unpack_normal, RECORD_HOLE, RECORD_LOOKUP, RECORD_ANSWERED,
}
#import plenoptic::geometry::lookup::{
    Weighted, nearby_texels, heaviest_texel, direct_lookups_at, volume_lookups,
}
#import plenoptic::geometry::bindings::{point_slot, point_material, face_normal}
#import plenoptic::counters::{tally, flush_kernel_counters, C_LOADS_16, C_LOADS_4, C_FILL}

@group(0) @binding(0) var<storage, read_write> entries: array<vec4<u32>>;
@group(0) @binding(1) var<uniform> fill: FillParams;
@group(0) @binding(2) var<storage, read_write> holes: HoleList;
// Threads per workgroup of fill_holes.
const GROUP: u32 = 64u;

// The holes listed this frame (the count may pass the list's room).
fn listed() -> u32 {
    return min(atomicLoad(&holes.count), arrayLength(&holes.records));
}

// The mean terms of the nearest ring around pixel `c` holding answered pixels of `tag`
// (object + 1), already times the exposure; w = 0 where no ring within the radius has one.
fn ring_mean(c: vec2<i32>, tag: u32) -> Weighted {
    let size = vec2<i32>(fill.size);
    for (var r = 1; r <= i32(fill.radius); r++) {
        var sum = mat2x3<f32>();
        var n = 0.0;
        for (var dy = -r; dy <= r; dy++) {
            for (var dx = -r; dx <= r; dx += ring_step(r, dy)) {
                let q = c + vec2<i32>(dx, dy);
                if any(q < vec2<i32>(0)) || any(q >= size) {
                    continue;
                }
                tally(C_LOADS_16, 1u);
                let o = entries[u32(q.y) * fill.size.x + u32(q.x)];
                if o.w == tag {
                    sum += unpack_pair(o.xyz);
                    n += 1.0;
                }
            }
        }
        if n > 0.0 {
            return Weighted(sum * (1.0 / n), 1.0);
        }
    }
    return Weighted(mat2x3<f32>(), 0.0);
}

// The lookups of the records the opaque fragments left to it (RECORD_LOOKUP; thesis
// §8.2.3's direct lookups, else the temporal volumes, lookup.wgsl's as a fragment makes
// them), one thread per record: an answered point's terms go into its pixel's entry, where
// the fill kernel's ring search reads them, and its colour (shaded with the record's albedo
// and non-diffuse weight, plus what its fragment added) over its record; a point nothing
// answers becomes a hole (RECORD_HOLE) for fill_holes.
@compute @workgroup_size(GROUP, 1, 1)
fn lookup_records(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= listed() {
        return;
    }
    tally(C_LOADS_16, 4u);
    let record = holes.records[i];
    if record.state != RECORD_LOOKUP {
        return;
    }
    let object = (record.tag & OBJECT_BITS) - 1u;
    point_slot = i32(record.local.w);
    point_material = (record.tag & HOLE_MATERIAL) != 0u;
    face_normal = unpack_normal(record.normal);
    let p = record.world.xyz;
    var got = direct_lookups_at(vec4<f32>(record.local.xyz, 1.0), p, fill.eye.xyz, object);
    if got.w <= 0.0 {
        got = volume_lookups(p, object);
    }
    let px = vec2<f32>(fill.offset + vec2<u32>(record.pixel % fill.size.x, record.pixel / fill.size.x));
    if got.w <= 0.0 {
        tally(C_FILL, 1u);
        holes.records[i].state = RECORD_HOLE;
        flush_kernel_counters(px);
        return;
    }
    let terms = got.terms * (fill.exposure / got.w);
    entries[record.pixel] = vec4<u32>(pack_pair(terms[0], terms[1]), object + 1u);
    let own = unpack_pair(record.pair);
    let nd = select(0.0, 1.0, (record.tag & HOLE_NON_DIFFUSE) != 0u);
    let colour = own[1] * terms[0] + terms[1] * nd + own[0];
    holes.records[i].pair = pack_pair(colour, vec3<f32>(0.0));
    holes.records[i].state = RECORD_ANSWERED;
    flush_kernel_counters(px);
}

@compute @workgroup_size(GROUP, 1, 1)
fn fill_holes(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= listed() {
        return;
    }
    tally(C_LOADS_4, 1u);
    if holes.records[i].state != RECORD_HOLE {
        return;
    }
    tally(C_LOADS_16, 4u);
    let record = holes.records[i];
    let p = vec2<u32>(record.pixel % fill.size.x, record.pixel / fill.size.x);
    let object = record.tag & OBJECT_BITS;
    let material = (record.tag & HOLE_MATERIAL) != 0u;
    // What the fragment added (column 0) and the albedo it shades with (column 1).
    let own = unpack_pair(record.pair);
    let nd = select(0.0, 1.0, (record.tag & HOLE_NON_DIFFUSE) != 0u);
    let ring = ring_mean(vec2<i32>(p), object);
    var terms = ring.terms;
    if ring.w == 0.0 {
        let near = nearby_texels(vec4<f32>(record.local.xyz, 1.0), object - 1u, record.local.w, material);
        if near.w > 0.0 {
            terms = near.terms * (fill.exposure / near.w);
        } else {
            terms = heaviest_texel(record.world.xyz, material).terms * fill.exposure;
        }
    }
    let colour = own[1] * terms[0] + terms[1] * nd + own[0];
    holes.records[i].pair = pack_pair(colour, vec3<f32>(0.0));
    flush_kernel_counters(vec2<f32>(fill.offset + p));
}
