// The lookups of geometry-assisted reconstruction (thesis §8.2.3; plenoptic_recon's geometry,
// lookup, neighbour and volume modules, the same tests and weights): a point of the
// fragment's object carried along its motion to each resident key's time, looked up in the
// key's cube (the nearest texel, or seamlessly bilinear over the taps of the same surface),
// accepted if the cube saw the same object at the same distance, and blended with
// w_view · w_time · ((1 + cos θ)/2)^p; the temporal-volume fallback (thesis §7.4) where no
// lookup is accepted (the fallbacks after the hole fill are fallback.wgsl's).
#define_import_path plenoptic::geometry::lookup

#import plenoptic::cube::{rgb9e5_decode, cube_texel, texel_direction, bilinear_tap, Footprint, footprint, tap_weight}
#import plenoptic::fill_entry::unpack_pair
#import plenoptic::geometry::relight::volume_terms
#import plenoptic::counters::{tally, C_LOOKUPS, C_LOADS_16, C_LOADS_8, C_LOADS_4, C_GATHERS, C_VOLUME}
#import plenoptic::geometry::bindings::{
    MAX_LOOKUPS, MAX_VOLUMES, BIN_FACE, cam, params, cubes, shading_cubes, cube_sampler, volume_samples,
    volume_bins, pixel_albedo, non_diffuse_weight, local_from_world, face_normal, world_face_normal, lit, view_has, VIEW_BILINEAR,
    point_slot, point_material,
    blended_geometry, blended_terms, PAIR_CHANGING,
}

// Whether the last filtered lookup kept all four of its bilinear taps (the nearest texel's
// alone: true; across a face seam: false), as plenoptic_recon's lookup records it.
var<private> taps_whole: bool;
// The keys that answered the last direct_lookups_at: bit 2k for lookup k, bit 2k + 1 where
// it kept all four taps (plenoptic_recon's Scratch::accepted; the sparse lighting's
// signature, screen_fill.wgsl).
var<private> lookup_accepted: u32;

// Point `p` of this object in the object's own frame (homogeneous): local_from_world · p
// for an animated object; `p` itself for a static one (in world space), which is not
// carried. Computed once per point, before its lookups.
fn object_point(p: vec3<f32>) -> vec4<f32> {
    if point_slot < 0 {
        return vec4<f32>(p, 1.0);
    }
    return local_from_world * vec4<f32>(p, 1.0);
}

// The point whose `object_point` is `local`, carried to lookup k's key time τ: M_o(τ) · local
// for an animated object (its motion slot `slot`), the point itself for a static one (−1).
fn carried(local: vec4<f32>, k: u32, slot: f32) -> vec3<f32> {
    if slot < 0.0 {
        return local.xyz;
    }
    return (cam.motion[u32(slot) * MAX_LOOKUPS + k] * local).xyz;
}

// A colour as its two terms, kept apart until a pixel's own material is applied (`shade`):
// column 0 the lighting (or, for an object not shaded from its material, the radiance),
// column 1 the non-diffuse radiance (zero for radiance). Every blend below is linear, so the
// terms blend exactly as their shaded colour would; the hole fill averages its neighbours'
// terms and shades them with the hole's own albedo, as the CPU fills its lighting and
// non-diffuse planes apart. Terms with a weight: (Σ w·terms, Σ w), or normalised (w = 1).
struct Weighted {
    terms: mat2x3<f32>,
    w: f32,
}

// A shading texel's terms: (lighting, non-diffuse).
fn shaded(s: vec2<u32>) -> mat2x3<f32> {
    return mat2x3<f32>(rgb9e5_decode(s.x), rgb9e5_decode(s.y));
}

// A radiance texel's terms: (radiance, 0).
fn radiance_terms(x: u32) -> mat2x3<f32> {
    return mat2x3<f32>(rgb9e5_decode(x), vec3<f32>(0.0));
}

// The fragment's colour from terms: albedo · lighting + non-diffuse for an object shaded from
// its material, else the radiance.
fn shade(terms: mat2x3<f32>) -> vec3<f32> {
    if lit() {
        return pixel_albedo * terms[0] + terms[1] * non_diffuse_weight;
    }
    return terms[0];
}

// plenoptic_pack::cube::oct_decode.
fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if v.z < 0.0 {
        let x = (1.0 - abs(v.y)) * select(-1.0, 1.0, v.x >= 0.0);
        let y = (1.0 - abs(v.x)) * select(-1.0, 1.0, v.y >= 0.0);
        v.x = x;
        v.y = y;
    }
    return normalize(v);
}

// plenoptic_recon's SAME_FACE_COS.
const SAME_FACE_COS: f32 = 0.5;

// Whether a key texel whose packed normal is `normal` faces as the lookup's surface does,
// whose normal is `np` in the key's frame (plenoptic_recon's lookup::same_face): within
// SAME_FACE_COS, or no test where the key has no normals or `np` is zero.
fn same_face(normal: u32, np: vec3<f32>, normals: bool) -> bool {
    if !normals || all(np == vec3<f32>(0.0)) {
        return true;
    }
    let nrm = oct_decode(max(unpack2x16snorm(normal), vec2<f32>(-1.0)));
    return dot(nrm, np) >= SAME_FACE_COS;
}

// Whether key texel `c` (its key-texture texel `texel`) shows the surface of the lookup `d`
// (length `l`, surface normal `np`) of `object`: the same object facing alike (same_face) at
// the distance within `tol · l`, or, where the key has normals (`normals`), its centre point
// on the plane through the lookup's point with the texel's normal within `tol · l`
// (plenoptic_recon's lookup::same_surface).
fn same_surface(c: vec3<u32>, n: u32, texel: vec4<u32>, object: u32, d: vec3<f32>, np: vec3<f32>, l: f32, tol: f32, normals: bool) -> bool {
    if texel.z != object || !same_face(texel.w, np, normals) {
        return false;
    }
    let dc = bitcast<f32>(texel.y);
    if abs(dc - l) <= tol * l {
        return true;
    }
    if !normals {
        return false;
    }
    let nrm = oct_decode(max(unpack2x16snorm(texel.w), vec2<f32>(-1.0)));
    return abs(dot(texel_direction(c, n) * dc - d, nrm)) <= tol * l;
}

// The radiance of the key at `layer0` in direction `d` (length `l`), seamlessly bilinear
// over the taps that show the lookup's surface of `object` (same_surface) or are the
// nearest texel `t`, whose key texel `nearest` the caller has loaded (plenoptic_recon's
// lookup::filtered). Each tap is loaded on its own: the path of a footprint across a face
// seam (gathered_filter takes the others).
fn filtered(layer0: u32, n: u32, d: vec3<f32>, np: vec3<f32>, t: vec3<u32>, nearest: vec4<u32>, object: u32, l: f32, tol: f32, normals: bool) -> mat2x3<f32> {
    taps_whole = false;
    var acc = mat2x3<f32>();
    var aw = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let tap = bilinear_tap(d, n, k);
        if tap.w <= 0.0 {
            continue;
        }
        let c = vec3<u32>(tap.xyz);
        if all(c == t) {
            acc += colour(c, layer0, nearest) * tap.w;
            aw += tap.w;
            continue;
        }
        tally(C_LOADS_16, 1u);
        let texel = textureLoad(cubes, c.xy, layer0 + c.z, 0);
        if same_surface(c, n, texel, object, d, np, l, tol, normals) {
            acc += colour(c, layer0, texel) * tap.w;
            aw += tap.w;
        }
    }
    if aw > 0.0 {
        return acc * (1.0 / aw);
    }
    return colour(t, layer0, nearest);
}

// The terms of key texel `c` (in the key at `layer0`, whose key-texture texel is `texel`) for
// this fragment's object.
fn colour(c: vec3<u32>, layer0: u32, texel: vec4<u32>) -> mat2x3<f32> {
    return texel_terms(c, layer0, texel, point_material);
}

// The terms of key texel `c`: its radiance, or its lighting and non-diffuse radiance for an
// object shaded from its material (`material`).
fn texel_terms(c: vec3<u32>, layer0: u32, texel: vec4<u32>, material: bool) -> mat2x3<f32> {
    if material {
        tally(C_LOADS_8, 1u);
        return shaded(textureLoad(shading_cubes, c.xy, layer0 + c.z, 0).xy);
    }
    return radiance_terms(texel.x);
}

// Lookup k of a point: where in its key the point is looked up.
struct Lookup {
    // Whether the point is away from the key's centre (else the lookup has no direction).
    ok: bool,
    // From the key's centre to the point carried to the key's time.
    d: vec3<f32>,
    // |d|.
    dist: f32,
    // The key texel in direction d: (column, row, face).
    t: vec3<u32>,
    // The point's surface normal in the key's frame (face_normal carried; zero: no face
    // test).
    np: vec3<f32>,
}

// Lookup k of the point whose `object_point` is `local` (of an object with motion slot
// `slot`), in keys of face size `n`.
fn lookup_of(local: vec4<f32>, k: u32, n: u32, slot: f32) -> Lookup {
    var l: Lookup;
    l.d = carried(local, k, slot) - cam.lookups[k].base;
    l.dist = length(l.d);
    l.ok = !(l.dist <= 1e-6);
    if l.ok {
        l.t = cube_texel(l.d, n);
    }
    l.np = face_normal;
    if slot >= 0.0 && any(face_normal != vec3<f32>(0.0)) {
        l.np = normalize((cam.motion[u32(slot) * MAX_LOOKUPS + k] * vec4<f32>(face_normal, 0.0)).xyz);
    }
    return l;
}

// Whether the nearest key texel of lookup `l` (its distance `dc`, its packed normal
// `normal`), already known to show `object`, shows the lookup's point: its centre distance
// agrees within `tol`, or, on a key with normals (grazing surfaces), the distance to the
// texel's surface plane along the lookup direction does (plenoptic_recon's lookup test).
fn nearest_accepts(l: Lookup, n: u32, dc: f32, normal: u32, tol: f32, normals: bool) -> bool {
    if !same_face(normal, l.np, normals) {
        return false;
    }
    if abs(dc - l.dist) <= tol * l.dist {
        return true;
    }
    if !normals {
        return false;
    }
    let nrm = oct_decode(max(unpack2x16snorm(normal), vec2<f32>(-1.0)));
    let denom = dot(l.d, nrm) / l.dist;
    if abs(denom) <= 0.05 {
        return false;
    }
    let expected = dot(texel_direction(l.t, n) * dc, nrm) / denom;
    return abs(expected - l.dist) <= tol * l.dist;
}

// Lookup `l` in the key at `layer0`: (terms, 1) when its nearest texel (one load) shows the
// point of `object`, else w = 0. The terms are the nearest texel's, or filtered
// (`bilinear`): gathered where the footprint lies on one face, else tap by tap across the
// seam.
fn key_lookup(l: Lookup, layer0: u32, n: u32, object: u32, tol: f32, normals: bool, bilinear: bool) -> Weighted {
    tally(C_LOADS_16, 1u);
    let texel = textureLoad(cubes, l.t.xy, layer0 + l.t.z, 0);
    if texel.z != object || !nearest_accepts(l, n, bitcast<f32>(texel.y), texel.w, tol, normals) {
        return Weighted(mat2x3<f32>(), 0.0);
    }
    if !bilinear {
        taps_whole = true;
        return Weighted(colour(l.t, layer0, texel), 1.0);
    }
    let fp = footprint(l.d, n);
    if fp.inside {
        return Weighted(gathered_filter(l, fp, layer0, n, object, tol, normals), 1.0);
    }
    return Weighted(filtered(layer0, n, l.d, l.np, l.t, texel, object, l.dist, tol, normals), 1.0);
}

// Tap k's lane of a gather (taps in bilinear_tap's order (0,0), (1,0), (0,1), (1,1); a
// gather returns (0,1), (1,1), (1,0), (0,0)).
fn lane(v: vec4<u32>, k: u32) -> u32 {
    switch k {
        case 0u: { return v.w; }
        case 1u: { return v.z; }
        case 2u: { return v.x; }
        default: { return v.y; }
    }
}

// A footprint's geometry from gathers: its object ids and distances (two gathers), and its
// normals where the lookup has a face test or a tap of `object` misses the distance test of
// lookup `l`, on a key with normals (else zero). `tex`: the key texture, or a camera's blended keys (blend.rs).
struct Gathered {
    ids: vec4<u32>,
    dists: vec4<u32>,
    nrms: vec4<u32>,
}

fn gather_geometry(tex: texture_2d_array<u32>, uv: vec2<f32>, layer: u32, l: Lookup, object: u32, tol: f32, normals: bool) -> Gathered {
    tally(C_GATHERS, 2u);
    var g: Gathered;
    g.ids = textureGather(2, tex, cube_sampler, uv, layer);
    g.dists = textureGather(1, tex, cube_sampler, uv, layer);
    let fd = bitcast<vec4<f32>>(g.dists);
    let face_test = any(l.np != vec3<f32>(0.0));
    if normals && (face_test || any((g.ids == vec4<u32>(object)) & (abs(fd - l.dist) > vec4<f32>(tol * l.dist)))) {
        tally(C_GATHERS, 1u);
        g.nrms = textureGather(3, tex, cube_sampler, uv, layer);
    }
    return g;
}

// The bilinear filter of lookup `l`, whose nearest texel was accepted, over its footprint
// `fp` on one face, given the footprint's geometry `g` and each tap's terms: the taps that
// show the lookup's surface, weighted; the nearest tap's terms where none has weight. The
// same tests, weights and order as `filtered`.
fn filter_taps(l: Lookup, fp: Footprint, n: u32, object: u32, tol: f32, normals: bool, g: Gathered, terms: array<mat2x3<f32>, 4>) -> mat2x3<f32> {
    let corner = vec2<u32>(fp.corner);
    let kt = min(l.t.xy - corner, vec2<u32>(1u));
    let kn = kt.x + 2u * kt.y;
    var acc = mat2x3<f32>();
    var aw = 0.0;
    var kept = 0u;
    for (var k = 0u; k < 4u; k++) {
        let w = tap_weight(fp.f, k);
        let c = vec3<u32>(corner + vec2<u32>(k & 1u, k >> 1u), fp.face);
        let texel = vec4<u32>(0u, lane(g.dists, k), lane(g.ids, k), lane(g.nrms, k));
        if k == kn || same_surface(c, n, texel, object, l.d, l.np, l.dist, tol, normals) {
            acc += terms[k] * w;
            aw += w;
            kept += 1u;
        }
    }
    taps_whole = kept == 4u;
    if aw > 0.0 {
        return acc * (1.0 / aw);
    }
    return terms[kn];
}

// The bilinear filter of lookup `l` over its footprint `fp` on one face of the key at
// `layer0`, from gathers: the geometry (gather_geometry) and the colours from one gather
// (radiance) or two (lighting, non-diffuse radiance): 3 to 5 gathers where its other three
// taps take 3 loads (radiance) or 7 (lighting, with their shading texels).
fn gathered_filter(l: Lookup, fp: Footprint, layer0: u32, n: u32, object: u32, tol: f32, normals: bool) -> mat2x3<f32> {
    let uv = (fp.corner + 1.0) / f32(n);
    let layer = layer0 + fp.face;
    let g = gather_geometry(cubes, uv, layer, l, object, tol, normals);
    var c0 = vec4<u32>(0u);
    var c1 = vec4<u32>(0u);
    if point_material {
        tally(C_GATHERS, 2u);
        c0 = textureGather(0, shading_cubes, cube_sampler, uv, layer);
        c1 = textureGather(1, shading_cubes, cube_sampler, uv, layer);
    } else {
        tally(C_GATHERS, 1u);
        c0 = textureGather(0, cubes, cube_sampler, uv, layer);
    }
    var terms: array<mat2x3<f32>, 4>;
    for (var k = 0u; k < 4u; k++) {
        terms[k] = gathered_colour(lane(c0, k), lane(c1, k));
    }
    return filter_taps(l, fp, n, object, tol, normals, g, terms);
}

// Lookup `l` of key pair `pair` in the camera's blended keys (blend.rs): (terms, 1) where
// both keys accept it, w = 0 where both refuse it, w = −1 where a texel of its footprint
// changes between the two keys or the footprint crosses a seam (then each key is looked up
// on its own). For an object shaded from its material and still between the keys' times: 1
// load and 5 or 6 gathers for the two keys.
fn pair_lookup(l: Lookup, pair: u32, n: u32, object: u32, tol: f32, normals: bool) -> Weighted {
    let undecided = Weighted(mat2x3<f32>(), -1.0);
    let layer0 = pair * 6u;
    tally(C_LOADS_16, 1u);
    let texel = textureLoad(blended_geometry, l.t.xy, layer0 + l.t.z, 0);
    if texel.z == PAIR_CHANGING {
        return undecided;
    }
    if texel.z != object || !nearest_accepts(l, n, bitcast<f32>(texel.y), texel.w, tol, normals) {
        return Weighted(mat2x3<f32>(), 0.0);
    }
    let fp = footprint(l.d, n);
    if !fp.inside {
        return undecided;
    }
    let uv = (fp.corner + 1.0) / f32(n);
    let layer = layer0 + fp.face;
    let g = gather_geometry(blended_geometry, uv, layer, l, object, tol, normals);
    if any(g.ids == vec4<u32>(PAIR_CHANGING)) {
        return undecided;
    }
    tally(C_GATHERS, 3u);
    let a = textureGather(0, blended_terms, cube_sampler, uv, layer);
    let b = textureGather(1, blended_terms, cube_sampler, uv, layer);
    let c = textureGather(2, blended_terms, cube_sampler, uv, layer);
    var terms: array<mat2x3<f32>, 4>;
    for (var k = 0u; k < 4u; k++) {
        terms[k] = unpack_pair(vec3<u32>(lane(a, k), lane(b, k), lane(c, k)));
    }
    return Weighted(filter_taps(l, fp, n, object, tol, normals, g, terms), 1.0);
}

// A gathered texel's terms: its lighting and non-diffuse radiance for an object shaded from
// its material (`a`, `b`), else its radiance (`a`).
fn gathered_colour(a: u32, b: u32) -> mat2x3<f32> {
    if point_material {
        return shaded(vec2<u32>(a, b));
    }
    return radiance_terms(a);
}

// Whether this object stands still between the key times of lookups k and k + 1 (static, or
// animated with the same transform at both): its point falls on the same texel of both keys.
fn still_between(k: u32) -> bool {
    let slot = f32(point_slot);
    if slot < 0.0 {
        return true;
    }
    let a = cam.motion[u32(slot) * MAX_LOOKUPS + k];
    let b = cam.motion[u32(slot) * MAX_LOOKUPS + k + 1u];
    return all(a[0] == b[0]) && all(a[1] == b[1]) && all(a[2] == b[2]) && all(a[3] == b[3]);
}

// Lookup k's bits of lookup_accepted, after its lookup was accepted.
fn accepted_bits(k: u32) -> u32 {
    return (1u | select(0u, 2u, taps_whole)) << (2u * k);
}

// The angular weight ((1 + cos θ)/2)^p of lookup `l` seen from the direction `to_eye`.
fn angular(l: Lookup, to_eye: vec3<f32>, power: f32) -> f32 {
    if power <= 0.0 {
        return 1.0;
    }
    let c = max((1.0 - dot(l.d, to_eye) / l.dist) * 0.5, 1e-3);
    return pow(c, power);
}

// The accepted lookups of point `p` of `object` (seen from `eye`): (Σ w·terms, Σ w). With
// bilinear filtering (always for lighting, plenoptic_recon's shading module) an accepted
// lookup whose footprint lies on one face is gathered, one across a seam loaded tap by tap.
fn direct_lookups(p: vec3<f32>, eye: vec3<f32>, object: u32) -> Weighted {
    return direct_lookups_at(object_point(p), p, eye, object);
}

// direct_lookups of the point whose object_point is `local`.
fn direct_lookups_at(local: vec4<f32>, p: vec3<f32>, eye: vec3<f32>, object: u32) -> Weighted {
    let count = cam.lookup_count;
    let n = cam.face;
    let tol = cam.depth_tolerance;
    let power = cam.angular_power;
    let bilinear = view_has(VIEW_BILINEAR) || point_material;
    let to_eye = normalize(eye - p);
    var sum = mat2x3<f32>();
    var ws = 0.0;
    // An object shaded from its material looks a view's two keys up once where it stands
    // still between their times and the keys agree (blend.rs).
    let paired = point_material;
    lookup_accepted = 0u;
    for (var k = 0u; k < min(count, MAX_LOOKUPS); k++) {
        let l = lookup_of(local, k, n, f32(point_slot));
        if !l.ok {
            continue;
        }
        let normals = cam.lookups[k].normals != 0u;
        let pair = cam.lookups[k].pair;
        if paired && pair > 0u && still_between(k) {
            let got = pair_lookup(l, pair - 1u, n, object, tol, normals);
            if got.w >= 0.0 {
                tally(C_LOOKUPS, 2u);
                if got.w > 0.0 {
                    lookup_accepted |= accepted_bits(k) | accepted_bits(k + 1u);
                    let w = (cam.lookups[k].weight + cam.lookups[k + 1u].weight) * angular(l, to_eye, power);
                    sum += got.terms * w;
                    ws += w;
                }
                // The pair's second key is decided with the first.
                k += 1u;
                continue;
            }
        }
        tally(C_LOOKUPS, 1u);
        let got = key_lookup(l, cam.lookups[k].first_layer, n, object, tol, normals, bilinear);
        if got.w == 0.0 {
            continue;
        }
        lookup_accepted |= accepted_bits(k);
        let w = cam.lookups[k].weight * angular(l, to_eye, power);
        sum += got.terms * w;
        ws += w;
    }
    return Weighted(sum, ws);
}

// The temporal-volume fallback (plenoptic_recon's VolumeIndex::lookup_pair, summed over the
// views with their weights): samples of `object` in the direction bin of `p` from each base
// view, whose cone contains that direction, whose distance agrees within 3× the depth
// tolerance, whose time is within t ± tε and that face as the point's surface does
// (world_face_normal; the lookups' same_face), weighted by the tent filter and the angular
// falloff. Returns (Σ w·terms, Σ w).
fn volume_lookups(p: vec3<f32>, object: u32) -> Weighted {
    tally(C_VOLUME, 1u);
    let count = min(cam.volume_count, MAX_VOLUMES);
    let tol = cam.depth_tolerance * 3.0;
    let t = cam.time;
    let eps = cam.time_window;
    let half_bin = 1.0 / f32(BIN_FACE);
    var sum = mat2x3<f32>();
    var ws = 0.0;
    for (var i = 0u; i < count; i++) {
        let d = p - cam.volumes[i].base;
        let dist = length(d);
        if dist <= 1e-6 {
            continue;
        }
        let dir = d / dist;
        let bt = cube_texel(dir, BIN_FACE);
        let bin = cam.volumes[i].first_bin + (bt.z * BIN_FACE + bt.y) * BIN_FACE + bt.x;
        let first = cam.volumes[i].first_sample;
        let view_w = cam.volumes[i].weight;
        tally(C_LOADS_4, 2u);
        for (var j = volume_bins[bin]; j < volume_bins[bin + 1u]; j++) {
            let s = 3u * (first + j);
            tally(C_LOADS_16, 1u);
            let c = volume_samples[s + 2u];
            if c.y != object {
                continue;
            }
            let dt = abs(bitcast<f32>(c.x) - t);
            if dt > eps {
                continue;
            }
            tally(C_LOADS_16, 1u);
            let b = volume_samples[s + 1u];
            if abs(bitcast<f32>(b.w) - dist) > tol * dist || !same_face(b.y, world_face_normal, true) {
                continue;
            }
            tally(C_LOADS_16, 1u);
            let a = bitcast<vec4<f32>>(volume_samples[s]);
            let angle = acos(clamp(dot(a.xyz, dir), -1.0, 1.0));
            let r = max(a.w, half_bin);
            if angle < r {
                let w = (1.0 - dt / eps) * max(1.0 - angle / r, 1e-3) * view_w;
                sum += volume_terms(first + j, c.zw, rgb9e5_decode(b.x)) * w;
                ws += w;
            }
        }
    }
    return Weighted(sum, ws);
}

// Direct lookups, else the temporal-volume fallback: (terms, 1), or w = 0 for a hole.
fn reconstruct(p: vec3<f32>, eye: vec3<f32>, object: u32) -> Weighted {
    let direct = direct_lookups(p, eye, object);
    if direct.w > 0.0 {
        return Weighted(direct.terms * (1.0 / direct.w), 1.0);
    }
    let volume = volume_lookups(p, object);
    if volume.w > 0.0 {
        return Weighted(volume.terms * (1.0 / volume.w), 1.0);
    }
    return Weighted(mat2x3<f32>(), 0.0);
}
