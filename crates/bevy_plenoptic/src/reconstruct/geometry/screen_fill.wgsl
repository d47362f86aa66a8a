// The screen-space hole fill (thesis §8.2.3, plenoptic_recon's geometry::fill), a compute
// pass per view between Bevy's opaque and transparent passes, one thread per record of the
// room of the camera's hole list (fill_entry.wgsl); the threads past the holes listed return
// at once. A hole takes the nearest ring of pixels (radius 1 to `radius`) holding answered
// pixels of its own object, averages their terms and shades them with its own albedo and
// non-diffuse weight; where no ring has one, its object's nearby
// texels around its lookups, else the heaviest key's texel (fallback.wgsl's, as its
// fragment would take them). What its fragment added comes on top, and the colour is written
// over the hole's record, which the composite pass (fill_composite.wgsl) draws into the
// view's target. No pixel's lookups are computed again: a ring pixel costs one 16-byte load.
//
// Before it, with the lookup kernel, the records' lookups: lookup_records, or with the
// sparse lighting anchor_lookups, interpolate_records and listed_lookups.
//
// The lookups' bindings (the keys, their shading texels, the camera's view buffer, the
// counters) are the material's, bound here as group 1 (MATERIAL_BIND_GROUP).
#import plenoptic::fill_entry::{
    HoleList, FillParams, HOLE, HOLE_NON_DIFFUSE, HOLE_MATERIAL, OBJECT_BITS, unpack_pair, pack_pair,
    ring_step, unpack_normal, HoleRecord, RECORD_HOLE, RECORD_LOOKUP, RECORD_ANSWERED, RECORD_SPARSE,
    record_state, with_state,
}
#import plenoptic::geometry::lookup::{Weighted, direct_lookups_at, volume_lookups, lookup_accepted}
#import plenoptic::geometry::fallback::{nearby_texels, heaviest_texel}
#import plenoptic::geometry::bindings::{cam, point_slot, point_material, face_normal, world_face_normal}
#import plenoptic::counters::{tally, flush_kernel_counters, C_LOADS_16, C_LOADS_4, C_FILL}

@group(0) @binding(0) var<storage, read_write> entries: array<vec4<u32>>;
@group(0) @binding(1) var<uniform> fill: FillParams;
@group(0) @binding(2) var<storage, read_write> holes: HoleList;
// The sparse lighting's anchors (the pixels of even row and column), one cell each: the keys
// its direct lookups accepted (lookup.wgsl's lookup_accepted; 0: none), its distance from
// the eye, its packed face normal and its object + 1. Cleared each frame.
@group(0) @binding(3) var<storage, read_write> anchors: array<vec4<u32>>;
// The sparse lighting's work list: the records whose lookups listed_lookups makes, so that
// the threads of a group all look up (lookup_kernel.rs's SparseBuffers).
struct WorkList {
    count: atomic<u32>,
    items: array<u32>,
}
@group(0) @binding(4) var<storage, read_write> work: WorkList;
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

// The pixel of `record`, in the viewport.
fn record_pixel(record: HoleRecord) -> vec2<u32> {
    return vec2<u32>(record.pixel % fill.size.x, record.pixel / fill.size.x);
}

// The lookups' private state for `record`: its motion slot, material and face normal.
fn begin_record(record: HoleRecord) {
    point_slot = i32(record.local.w);
    point_material = (record.tag & HOLE_MATERIAL) != 0u;
    face_normal = unpack_normal(record.normal);
    world_face_normal = unpack_normal(record.world_normal);
}

// The direct lookups of `record` (begin_record's): (Σ w·terms, Σ w); lookup_accepted says
// which keys answered.
fn direct_of(record: HoleRecord) -> Weighted {
    let local = vec4<f32>(record.local.xyz, 1.0);
    return direct_lookups_at(local, record.world.xyz, fill.eye.xyz, (record.tag & OBJECT_BITS) - 1u);
}

// The answer of `record` from its `direct` lookups, else the temporal volumes, normalized and
// times the exposure; w = 0 where none answers.
fn with_volumes(record: HoleRecord, direct: Weighted) -> Weighted {
    var got = direct;
    if got.w <= 0.0 {
        got = volume_lookups(record.world.xyz, (record.tag & OBJECT_BITS) - 1u);
    }
    if got.w <= 0.0 {
        return Weighted(mat2x3<f32>(), 0.0);
    }
    return Weighted(got.terms * (fill.exposure / got.w), 1.0);
}

// Record i's own lookups, its answer written (answer): lookup_records' and listed_lookups'
// thread.
fn look_up(i: u32) {
    tally(C_LOADS_16, 4u);
    let record = holes.records[i];
    begin_record(record);
    answer(i, record.pixel, record.tag, record.pair, with_volumes(record, direct_of(record)));
    flush_kernel_counters(vec2<f32>(fill.offset + record_pixel(record)));
}

// Record i's answer `got` (terms times the exposure) for its `pixel`, `tag` and `pair`: its
// terms into its pixel's entry, where the fill kernel's ring search reads them, and its
// colour (shaded with the record's albedo and non-diffuse weight, plus what its fragment
// added) over its record; with w = 0 the record becomes a hole (RECORD_HOLE) for fill_holes.
fn answer(i: u32, pixel: u32, tag: u32, pair: vec3<u32>, got: Weighted) {
    if got.w <= 0.0 {
        tally(C_FILL, 1u);
        holes.records[i].state = with_state(holes.records[i].state, RECORD_HOLE);
        return;
    }
    entries[pixel] = vec4<u32>(pack_pair(got.terms[0], got.terms[1]), tag & OBJECT_BITS);
    let own = unpack_pair(pair);
    let nd = select(0.0, 1.0, (tag & HOLE_NON_DIFFUSE) != 0u);
    let colour = own[1] * got.terms[0] + got.terms[1] * nd + own[0];
    holes.records[i].pair = pack_pair(colour, vec3<f32>(0.0));
    holes.records[i].state = with_state(holes.records[i].state, RECORD_ANSWERED);
}

// The lookups of the records the opaque fragments left to it (RECORD_LOOKUP; thesis
// §8.2.3's direct lookups, else the temporal volumes, lookup.wgsl's as a fragment makes
// them), one thread per record, on a camera without the sparse lighting (with it, a
// material's fragment leaves its record RECORD_SPARSE for anchor_lookups and
// interpolate_records, and the rest go to the work list there). A record's 64 bytes count as
// four 16-byte loads.
@compute @workgroup_size(GROUP, 1, 1)
fn lookup_records(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= listed() {
        return;
    }
    // A record left RECORD_SPARSE in a frame whose fill turned the sparse lighting off is
    // looked up too. (Its state is counted with the record's four loads.)
    let state = record_state(holes.records[i].state);
    if state != RECORD_LOOKUP && state != RECORD_SPARSE {
        return;
    }
    look_up(i);
}

// Threads per workgroup side of anchor_lookups.
const ANCHOR_GROUP: u32 = 8u;

// The sparse lighting's anchors (ReconSettings::sparse_lighting; plenoptic_recon's
// geometry::sparse): one thread per anchor, the pixel of even row and column (2x, 2y), in
// 8 × 8 groups of neighbouring anchors. Where the pixel's entry names a record left to it
// (RECORD_SPARSE), the record's lookups are made and its cell written for its neighbours.
// The records are found through the entries, not in the list's order, so that the threads
// of a group are anchors side by side, all looking up, and none waits on another's work.
@compute @workgroup_size(ANCHOR_GROUP, ANCHOR_GROUP, 1)
fn anchor_lookups(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = 2u * id.xy;
    if any(p >= fill.size) {
        return;
    }
    tally(C_LOADS_16, 1u);
    let e = entries[p.y * fill.size.x + p.x];
    let i = e.x;
    if (e.w & HOLE) == 0u || i >= listed() {
        return;
    }
    tally(C_LOADS_16, 4u);
    let record = holes.records[i];
    if record_state(record.state) != RECORD_SPARSE || record.pixel != p.y * fill.size.x + p.x {
        return;
    }
    begin_record(record);
    let direct = direct_of(record);
    // The anchor's cell: what answered it directly (0: nothing did), its distance, face
    // normal and object.
    let signature = select(0u, lookup_accepted, direct.w > 0.0);
    let dist = bitcast<u32>(distance(record.world.xyz, fill.eye.xyz));
    anchors[id.y * anchor_size().x + id.x] = vec4<u32>(signature, dist, record.normal, record.tag & OBJECT_BITS);
    answer(i, record.pixel, record.tag, record.pair, with_volumes(record, direct));
    flush_kernel_counters(vec2<f32>(fill.offset + p));
}

// plenoptic_recon's sparse CREASE: anchors whose triangles' normals differ by more than about
// 6° lie on both sides of a crease.
const CREASE: f32 = 0.995;

// The anchors' grid: one per 2 × 2 pixels, rounded up.
fn anchor_size() -> vec2<u32> {
    return (fill.size + 1u) / 2u;
}

// Whether every key of signature `s` that answered kept all four of its bilinear taps.
fn whole(s: u32) -> bool {
    let even = 0x55555555u;
    return (s & even) == ((s >> 1u) & even);
}

// The terms of pixel `p` (of `object` + 1, at `dist` from the eye) from the two or four
// anchors around it (plenoptic_recon's Anchors::interpolate, the same rules): their mean where
// each shows the object, answered by the same keys with all their taps, their triangles
// facing the same way and the pixel within half the depth tolerance of their mean distance;
// w = 0 where the pixel must be looked up itself. Two loads per anchor: its cell and entry.
fn interpolated(p: vec2<u32>, object: u32, dist: f32) -> Weighted {
    let none = Weighted(mat2x3<f32>(), 0.0);
    let a = p / 2u;
    let span = 1u + p % 2u;
    let size = anchor_size();
    if any(a + span > size) {
        return none;
    }
    var signature = 0u;
    var normal = vec3<f32>(0.0);
    var sum = mat2x3<f32>();
    var d = 0.0;
    for (var j = 0u; j < span.y; j++) {
        for (var i = 0u; i < span.x; i++) {
            let q = a + vec2<u32>(i, j);
            tally(C_LOADS_16, 1u);
            let c = anchors[q.y * size.x + q.x];
            let n = unpack_normal(c.z);
            if i + j == 0u {
                signature = c.x;
                normal = n;
                if signature == 0u || !whole(signature) {
                    return none;
                }
            }
            if c.x != signature || c.w != object || abs(dot(n, normal)) < CREASE {
                return none;
            }
            tally(C_LOADS_16, 1u);
            let e = entries[2u * q.y * fill.size.x + 2u * q.x];
            if e.w != object {
                return none;
            }
            sum += unpack_pair(e.xyz);
            d += bitcast<f32>(c.y);
        }
    }
    let k = 1.0 / f32(span.x * span.y);
    if abs(d * k - dist) > 0.5 * cam.depth_tolerance * dist {
        return none;
    }
    return Weighted(sum * k, 1.0);
}

// The sparse lighting's second pass, after anchor_lookups: a record without a material goes
// to the work list; each record left (RECORD_SPARSE:
// off the anchors, or a second fragment of an anchor's pixel with MSAA, which takes that
// anchor's lookups as its own where they stand for them) takes its anchors' mean where they
// stand for its own lookups (reading its pixel, tag, colours and world point), else goes to
// the work list for its own lookups, so that object edges, creases and depth steps stay at
// full resolution and a group's threads here never wait on one that looks up.
@compute @workgroup_size(GROUP, 1, 1)
fn interpolate_records(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= listed() {
        return;
    }
    tally(C_LOADS_16, 1u);
    let state = record_state(holes.records[i].state);
    if state == RECORD_LOOKUP {
        // Without a material (or left by a fragment before the sparse lighting was on).
        to_work_list(i);
        return;
    }
    if state != RECORD_SPARSE {
        return;
    }
    let tag = holes.records[i].tag;
    tally(C_LOADS_16, 2u);
    let pixel = holes.records[i].pixel;
    let pair = holes.records[i].pair;
    let world = holes.records[i].world.xyz;
    let p = vec2<u32>(pixel % fill.size.x, pixel / fill.size.x);
    let got = interpolated(p, tag & OBJECT_BITS, distance(world, fill.eye.xyz));
    if got.w > 0.0 {
        answer(i, pixel, tag, pair, got);
    } else {
        to_work_list(i);
    }
    flush_kernel_counters(vec2<f32>(fill.offset + p));
}

// Appends record `i` to the work list (room for every record, so never past it).
fn to_work_list(i: u32) {
    let k = atomicAdd(&work.count, 1u);
    if k < arrayLength(&work.items) {
        work.items[k] = i;
    }
}

// The sparse lighting's last pass: the lookups of the records on the work list (those
// without a material, and those their anchors did not stand for), one thread per item.
@compute @workgroup_size(GROUP, 1, 1)
fn listed_lookups(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= min(atomicLoad(&work.count), arrayLength(&work.items)) {
        return;
    }
    tally(C_LOADS_4, 1u);
    look_up(work.items[id.x]);
}

@compute @workgroup_size(GROUP, 1, 1)
fn fill_holes(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= listed() {
        return;
    }
    tally(C_LOADS_4, 1u);
    if record_state(holes.records[i].state) != RECORD_HOLE {
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
