// The fragment's reconstructed radiance with plenoptic_recon's fallbacks, in its order
// (thesis §8.2.3): its own lookups (lookup.wgsl), else the same-object hole fill over the
// nearest ring of pixels, else the object's nearby texels, else the heaviest key's texel
// ("background"); in image mode the image-mode frame's texel.
//
// The hole fill runs in one of two places. On a camera with the screen-space fill
// (PLENOPTIC_SCREEN_FILL, VIEW_SCREEN_FILL; screen_fill.rs) a fragment drawn in the opaque
// pass leaves its terms in the camera's fill entries (fill_entry.wgsl), or appends its hole to
// the camera's hole list and leaves the pixel to the fill kernel (screen_fill.wgsl), which
// takes the ring search and the fallbacks after it: no neighbour's lookups are computed
// again. Elsewhere (glazing and glass in the transparent pass, cameras without the fill, a
// hole beyond the list's room) the fragment recomputes its ring pixels' lookups at the points
// they show (from the depth prepass, or on the fragment's plane).
#define_import_path plenoptic::geometry::fill

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#import bevy_pbr::prepass_utils
#import plenoptic::geometry::bindings::{
    cam, params, image_frame, image_mode, view_has, lit, pixel_albedo, face_normal, world_face_normal,
    local_from_world,
    non_diffuse_weight, VIEW_SCREEN_FILL, VIEW_LOOKUP_KERNEL, VIEW_SPARSE_LIGHTING, object_has, OBJECT_OPAQUE_PASS,
    glazing,
}
#ifdef PLENOPTIC_SCREEN_FILL
#import plenoptic::geometry::bindings::{fill_entries, hole_list}
#import plenoptic::fill_entry::{
    HOLE, HOLE_NON_DIFFUSE, HOLE_MATERIAL, pack_pair, pack_normal, RECORD_HOLE, RECORD_LOOKUP, RECORD_SPARSE,
    COVERAGE_SHIFT,
}
#endif
#import plenoptic::fill_entry::ring_step
#import plenoptic::geometry::lookup::{reconstruct, object_point, shade}
#import plenoptic::geometry::fallback::{neighbour_texels, heaviest_texel}
#import plenoptic::counters::{tally, C_LOADS_16, C_LOADS_4, C_FILL, C_FILL_LOOKUPS}

// What the fragment leaves in the fill entries: nothing, its terms, or its hole.
const ENTRY_NONE: u32 = 0u;
const ENTRY_ANSWERED: u32 = 1u;
const ENTRY_HOLE: u32 = 2u;
// Its lookups left to the lookup kernel (VIEW_LOOKUP_KERNEL).
const ENTRY_LOOKUP: u32 = 3u;
var<private> entry_kind: u32 = ENTRY_NONE;
// The fragment's terms (lookup.wgsl's Weighted), with ENTRY_ANSWERED.
var<private> entry_terms: mat2x3<f32>;
// With ENTRY_HOLE: its record's index in the hole list and its point.
var<private> hole_index: u32;
var<private> hole_point: vec3<f32>;
// The fragment's sample mask and the nearest depth its surface reaches in its pixel
// (note_fragment), for its hole's record.
var<private> fragment_coverage: u32 = 1u;
var<private> fragment_near_depth: f32 = 0.0;

// Notes the fragment's sample mask and the nearest depth of its surface in its pixel: its
// centre's depth plus half the depth's change across the pixel, and a margin of 1e-4 of it
// (Bevy's depth is reversed, nearer is larger). Called by the fragment entry points before
// any non-uniform branch (it takes a derivative).
fn note_fragment(position: vec4<f32>, coverage: u32) {
#ifdef PLENOPTIC_SCREEN_FILL
    fragment_coverage = coverage;
    fragment_near_depth = (position.z + 0.5 * fwidth(position.z)) * (1.0 + 1e-4);
#endif
}

// Whether this fragment's hole is left to the screen-space fill kernel: the camera has it
// (PLENOPTIC_SCREEN_FILL, compiled with the depth test forced before the fragment shader, so
// that only the fragment the depth prepass kept runs and writes), and the object is drawn in
// the opaque pass (OBJECT_OPAQUE_PASS), before the kernel runs.
fn screen_fill() -> bool {
#ifdef PLENOPTIC_SCREEN_FILL
    return view_has(VIEW_SCREEN_FILL) && object_has(OBJECT_OPAQUE_PASS);
#else
    return false;
#endif
}

// Appends the fragment's hole (at `p`) to the camera's hole list; false (the fragment fills
// it itself) where the list is full.
fn claim_hole(p: vec3<f32>) -> bool {
#ifdef PLENOPTIC_SCREEN_FILL
    let i = atomicAdd(&hole_list.count, 1u);
    if i >= arrayLength(&hole_list.records) {
        return false;
    }
    hole_index = i;
    hole_point = p;
    return true;
#else
    return false;
#endif
}

// Writes the fragment's fill entry, if it has one (`frag`: its framebuffer position;
// `added`: what it adds to its reconstructed radiance, before the exposure), and a hole's
// record.
fn write_fill_entry(frag: vec4<f32>, added: vec3<f32>) {
#ifdef PLENOPTIC_SCREEN_FILL
    if entry_kind == ENTRY_NONE {
        return;
    }
    let px = vec2<u32>(frag.xy - view.viewport.xy);
    let size = vec2<u32>(view.viewport.zw);
    if any(px >= size) {
        return;
    }
    let i = px.y * size.x + px.x;
    let object = params.id + 1u;
    let e = view.exposure;
    if entry_kind == ENTRY_ANSWERED {
        fill_entries[i] = vec4<u32>(pack_pair(entry_terms[0] * e, entry_terms[1] * e), object);
        return;
    }
    var albedo = vec3<f32>(1.0);
    var tag = object;
    if lit() {
        albedo = pixel_albedo;
        tag |= HOLE_MATERIAL;
        if non_diffuse_weight != 0.0 {
            tag |= HOLE_NON_DIFFUSE;
        }
    }
    fill_entries[i] = vec4<u32>(hole_index, 0u, 0u, object | HOLE);
    let r = &hole_list.records[hole_index];
    var state = select(RECORD_HOLE, RECORD_LOOKUP, entry_kind == ENTRY_LOOKUP);
    if state == RECORD_LOOKUP && lit() && view_has(VIEW_SPARSE_LIGHTING) {
        state = RECORD_SPARSE;
    }
    (*r).state = state | (fragment_coverage << COVERAGE_SHIFT);
    (*r).normal = pack_normal(face_normal);
    (*r).world_normal = pack_normal(world_face_normal);
    (*r).pair = pack_pair(added * e, albedo);
    (*r).pixel = i;
    (*r).local = vec4<f32>(object_point(hole_point).xyz, f32(params.motion_slot));
    (*r).world = vec4<f32>(hole_point, fragment_near_depth);
    (*r).tag = tag;
#endif
}

// The world point where pixel centre `c` (framebuffer coordinates) sees the plane through `p`
// with normal `nrm`; w = 0 where the ray misses it.
fn pixel_on_plane(c: vec2<f32>, p: vec3<f32>, nrm: vec3<f32>) -> vec4<f32> {
    let uv = (c - view.viewport.xy) / view.viewport.zw;
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let a4 = view.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let b4 = view.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    let a = a4.xyz / a4.w;
    let dir = normalize(b4.xyz / b4.w - a);
    let denom = dot(dir, nrm);
    if abs(denom) < 1e-4 {
        return vec4<f32>(0.0);
    }
    let s = dot(p - a, nrm) / denom;
    if s <= 0.0 {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(a + dir * s, 1.0);
}

// The world point neighbouring pixel `c` (framebuffer coordinates, its centre) shows: from
// the depth prepass where the camera has one (w = 0 where nothing is there), else where its
// ray meets this fragment's surface plane (through `p`, normal `nrm`).
fn neighbour_point(c: vec2<f32>, p: vec3<f32>, nrm: vec3<f32>) -> vec4<f32> {
#ifdef DEPTH_PREPASS
    tally(C_LOADS_4, 1u);
    let depth = prepass_utils::prepass_depth(vec4<f32>(c, 0.0, 0.0), 0u);
    if depth <= 0.0 {
        return vec4<f32>(0.0);
    }
    let uv = (c - view.viewport.xy) / view.viewport.zw;
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let w4 = view.world_from_clip * vec4<f32>(ndc, depth, 1.0);
    return vec4<f32>(w4.xyz / w4.w, 1.0);
#else
    return pixel_on_plane(c, p, nrm);
#endif
}

// `n` turned to face the eye from point `p` (zero stays zero).
fn facing_eye(n: vec3<f32>, p: vec3<f32>, eye: vec3<f32>) -> vec3<f32> {
    return select(-n, n, dot(n, eye - p) >= 0.0);
}

// World normal `n` in the frame this object's points are looked up from (object_point's).
fn lookup_frame(n: vec3<f32>) -> vec3<f32> {
    if params.motion_slot < 0 || all(n == vec3<f32>(0.0)) {
        return n;
    }
    return normalize((local_from_world * vec4<f32>(n, 0.0)).xyz);
}

// The image-mode frame's texel of the fragment's pixel.
fn image_frame_texel(position: vec2<f32>) -> vec4<f32> {
    let size = textureDimensions(image_frame);
    let uv = (position - view.viewport.xy) / view.viewport.zw;
    let p = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
    tally(C_LOADS_16, 1u);
    return vec4<f32>(textureLoad(image_frame, p, 0).rgb, 1.0);
}

// The reconstructed radiance of the fragment (linear, before exposure).
// `ng_raw`: the triangle's plane from the position's derivatives (taken by the caller).
fn radiance(in: VertexOutput, ng_raw: vec3<f32>) -> vec4<f32> {
    let object = params.id;
    let p = in.world_position.xyz;
    let eye = view.world_position;
    // The surface plane.
    var nrm = ng_raw;
    if dot(nrm, nrm) < 1e-20 {
        nrm = in.world_normal;
    }
    nrm = normalize(nrm);
    if image_mode() {
        return image_frame_texel(in.position.xy);
    }
    // The face test of the lookups (lookup.wgsl's same_face): the fragment's surface normal
    // facing the eye, in its lookups' frame (fragment_fill keeps it for ring points on the
    // fragment's plane).
    world_face_normal = facing_eye(nrm, p, eye);
    face_normal = lookup_frame(world_face_normal);
    let deferred = screen_fill();
    if deferred && view_has(VIEW_LOOKUP_KERNEL) && claim_hole(p) {
        // The lookup kernel (screen_fill.wgsl) makes the point's lookups, then the fill
        // kernel fills it if none answers.
        entry_kind = ENTRY_LOOKUP;
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let own = reconstruct(p, eye, object);
    if own.w > 0.0 {
        if deferred {
            entry_kind = ENTRY_ANSWERED;
            entry_terms = own.terms;
        }
        return vec4<f32>(shade(own.terms), 1.0);
    }
    tally(C_FILL, 1u);
    if deferred && claim_hole(p) {
        // The fill kernel fills the pixel: its ring search, else the fallbacks below
        // (fallback.wgsl's nearby_texels and heaviest_texel, as here).
        entry_kind = ENTRY_HOLE;
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let filled = fragment_fill(in.position.xy, p, nrm, eye, object);
    if filled.w > 0.0 {
        return filled;
    }
    // A thin object no texel centre met where the lookups fell: its own nearest texels, else
    // those of the surface around it at its distance.
    let near = neighbour_texels(p, object);
    if near.w > 0.0 {
        return vec4<f32>(shade(near.terms * (1.0 / near.w)), 1.0);
    }
    // Nothing: the heaviest key's texel in the point's direction ("background").
    return vec4<f32>(shade(heaviest_texel(p, lit()).terms), 1.0);
}

// Same-object hole fill in the fragment (plenoptic_recon's ring search): the nearest ring of
// pixels around `centre` whose points (neighbour_point) have a direct or volume lookup of
// this object; their mean, shaded with this fragment's albedo (w = 0: none).
fn fragment_fill(centre: vec2<f32>, p: vec3<f32>, nrm: vec3<f32>, eye: vec3<f32>, object: u32) -> vec4<f32> {
    let radius = i32(cam.fill_radius);
    let own_face = face_normal;
    let own_world_face = world_face_normal;
    for (var r = 1; r <= radius; r++) {
        var sum = mat2x3<f32>();
        var count = 0.0;
        for (var dy = -r; dy <= r; dy++) {
            for (var dx = -r; dx <= r; dx += ring_step(r, dy)) {
                let c = centre + vec2<f32>(f32(dx), f32(dy));
                if any(c < view.viewport.xy) || any(c >= view.viewport.xy + view.viewport.zw) {
                    continue;
                }
                // Glazing is not in the depth prepass (Bevy's transparent pass): its ring
                // pixels are found on its plane, panes being flat.
                var q: vec4<f32>;
                if glazing() {
                    q = pixel_on_plane(c, p, nrm);
                } else {
                    q = neighbour_point(c, p, nrm);
                }
                if q.w == 0.0 {
                    continue;
                }
                // A ring pixel's lookups were face-tested with its own normal: the
                // fragment's where the pixel lies on the fragment's plane. Elsewhere it is not
                // known here and the test is left out (its normal from the depth prepass
                // measured the same frame at four more loads per ring point).
                let on_plane = abs(dot(q.xyz - p, nrm)) <= 0.01 * distance(q.xyz, eye);
                face_normal = select(vec3<f32>(0.0), own_face, on_plane);
                world_face_normal = select(vec3<f32>(0.0), own_world_face, on_plane);
                tally(C_FILL_LOOKUPS, 1u);
                let got = reconstruct(q.xyz, eye, object);
                if got.w > 0.0 {
                    sum += got.terms;
                    count += 1.0;
                }
            }
        }
        if count > 0.0 {
            return vec4<f32>(shade(sum * (1.0 / count)), 1.0);
        }
    }
    return vec4<f32>(0.0);
}
