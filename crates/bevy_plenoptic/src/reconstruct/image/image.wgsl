// Image mode (plenoptic_recon::warp) in compute passes: each weighted base view's cube
// texels are splatted into the camera through a per-view z-buffer, the views are blended per
// pixel within a relative depth tolerance of the nearest, and holes are filled from the
// farthest covered neighbour, pass after pass.

#import plenoptic::cube::{rgb9e5_decode, texel_direction}
#import plenoptic::relight::{LightLayer, stored_terms, blend_base, blend_layer, blend_end, relit_radiance}

const MAX_VIEWS: u32 = 8u;
const EMPTY: u32 = 0xffffffffu;

struct ImageParams {
    // Eye (xyz), focal length in pixels (w).
    eye: vec4<f32>,
    // Camera right (xyz), tan of half the horizontal field of view (w).
    right: vec4<f32>,
    // Camera up (xyz), tan of half the vertical field of view (w).
    up: vec4<f32>,
    // Viewing direction (xyz), relative depth tolerance of the blend (w).
    forward: vec4<f32>,
    // Width, height, face size, view count.
    size: vec4<u32>,
    // x: background-fill passes.
    misc: vec4<u32>,
    // x: relative depth under which two splats are the same surface, y: largest splat edge in
    // pixels (ReconSettings::same_surface and max_splat_px).
    splat: vec4<f32>,
    // Per view: position (xyz), view weight (w).
    views: array<vec4<f32>, 8>,
    // Per view: first array layer of each key blended.
    layers: array<vec4<u32>, 8>,
    // Per view: each key's weight (0 for unused).
    key_weights: array<vec4<f32>, 8>,
    // Per view: x: first layer of the nearest key (distance), y: key count.
    nearest: array<vec4<u32>, 8>,
    // Light groups (reconstruct/relight.rs): stored groups (x), layers blended (y), 1 where
    // the keys' radiance is relit per texel (z).
    light: vec4<u32>,
    // The blend's weight of the total (xyz); the sky's multiplier (xyz).
    light_base: vec4<f32>,
    light_sky: vec4<f32>,
    // The layers blended (light.y of them).
    light_layers: array<LightLayer, 16>,
}

@group(0) @binding(0) var cubes: texture_2d_array<u32>;
@group(0) @binding(1) var<uniform> params: ImageParams;
// Two words per (view, pixel): nearest splat depth (f32 bits), then the winning centre key.
@group(0) @binding(2) var<storage, read_write> splat_keys: array<atomic<u32>>;
// Winning texel per (view, pixel).
@group(0) @binding(3) var<storage, read_write> splat_texels: array<u32>;
// Radiance (rgb) and camera depth (w, < 0 where uncovered) per pixel; the fill reads `frame_in`
// and writes `frame_out`.
@group(0) @binding(4) var<storage, read_write> frame_in: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> frame_out: array<vec4<f32>>;
@group(0) @binding(6) var output: texture_storage_2d<rgba32float, write>;
// The keys' stored (lighting, non-diffuse) RGB9E5 pairs and, per key slot and stored light
// group, six faces of its layer's pairs (reconstruct/relight.rs).
@group(0) @binding(7) var shading_cubes: texture_2d_array<u32>;
@group(0) @binding(8) var<storage, read> group_layers: array<vec2<u32>>;

fn pixel_count() -> u32 {
    return params.size.x * params.size.y;
}

// (column, row, face) of texel `i` of a cube of face size `n`.
fn texel_coords(i: u32, n: u32) -> vec3<u32> {
    let rem = i % (n * n);
    return vec3<u32>(rem % n, rem / n, i / (n * n));
}

struct Splat {
    ok: bool,
    // Continuous image position.
    px: vec2<f32>,
    // Camera depth.
    z: f32,
    // Half the splat's edge, pixels.
    half: f32,
}

// Texel `i` of view `v` as plenoptic_recon::warp::warp_view projects it.
fn splat_of(v: u32, i: u32) -> Splat {
    let n = params.size.z;
    var s: Splat;
    s.ok = false;
    if i >= 6u * n * n {
        return s;
    }
    let t = texel_coords(i, n);
    let d = bitcast<f32>(textureLoad(cubes, t.xy, params.nearest[v].x + t.z, 0).y);
    if !(d > 0.0) || d > 3.0e38 {
        return s;
    }
    let dir = texel_direction(t, n);
    let rel = params.views[v].xyz + dir * d - params.eye.xyz;
    let z = dot(rel, params.forward.xyz);
    if !(z > 1e-4) {
        return s;
    }
    let sx = dot(rel, params.right.xyz) / (z * params.right.w);
    let sy = dot(rel, params.up.xyz) / (z * params.up.w);
    s.px = vec2<f32>((sx + 1.0) * 0.5 * f32(params.size.x), (1.0 - sy) * 0.5 * f32(params.size.y));
    let m = max(abs(dir.x), max(abs(dir.y), abs(dir.z)));
    let size = min(2.0 * d * m * params.eye.w / (f32(n) * z), params.splat.y);
    s.half = max(size * 0.5, 0.5);
    s.z = z;
    s.ok = true;
    return s;
}

// Pixel bounds (x0, y0, x1, y1) of a splat; x0 > x1 when off screen.
fn splat_bounds(s: Splat) -> vec4<i32> {
    let lo = max(floor(s.px - vec2<f32>(s.half)), vec2<f32>(0.0));
    let hi = min(
        floor(s.px + vec2<f32>(s.half)),
        vec2<f32>(f32(params.size.x) - 1.0, f32(params.size.y) - 1.0),
    );
    if lo.x > hi.x || lo.y > hi.y {
        return vec4<i32>(1, 1, 0, 0);
    }
    return vec4<i32>(i32(lo.x), i32(lo.y), i32(hi.x), i32(hi.y));
}

// Squared distance from the splat's centre to pixel (x, y)'s centre, quantised.
fn centre_key(s: Splat, x: i32, y: i32) -> u32 {
    let dx = f32(x) + 0.5 - s.px.x;
    let dy = f32(y) + 0.5 - s.px.y;
    return u32(min((dx * dx + dy * dy) * 4096.0, 4.0e9));
}

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    let v = id.y;
    if p >= pixel_count() || v >= params.size.w {
        return;
    }
    let j = v * pixel_count() + p;
    atomicStore(&splat_keys[2u * j], EMPTY);
    atomicStore(&splat_keys[2u * j + 1u], EMPTY);
    splat_texels[j] = EMPTY;
}

// The three splat passes.
const PASS_DEPTH: u32 = 0u;
const PASS_CENTRE: u32 = 1u;
const PASS_TEXEL: u32 = 2u;

// Splat pass `which` over the footprint of texel id.x of view id.y: PASS_DEPTH keeps the
// nearest splat depth per (view, pixel); PASS_CENTRE, among the splats of the nearest surface
// (within params.splat.x), the nearest centre; PASS_TEXEL writes the winning texel.
fn splat_pass(id: vec3<u32>, which: u32) {
    let v = id.y;
    if v >= params.size.w {
        return;
    }
    let s = splat_of(v, id.x);
    if !s.ok {
        return;
    }
    let b = splat_bounds(s);
    let base = v * pixel_count();
    for (var y = b.y; y <= b.w; y++) {
        for (var x = b.x; x <= b.z; x++) {
            let j = base + u32(y) * params.size.x + u32(x);
            if which == PASS_DEPTH {
                atomicMin(&splat_keys[2u * j], bitcast<u32>(s.z));
                continue;
            }
            let zmin = bitcast<f32>(atomicLoad(&splat_keys[2u * j]));
            if !(s.z <= zmin * (1.0 + params.splat.x)) {
                continue;
            }
            let key = centre_key(s, x, y);
            if which == PASS_CENTRE {
                atomicMin(&splat_keys[2u * j + 1u], key);
            } else if atomicLoad(&splat_keys[2u * j + 1u]) == key {
                splat_texels[j] = id.x;
            }
        }
    }
}

// Pass 1: the nearest splat depth per (view, pixel).
@compute @workgroup_size(64)
fn splat_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    splat_pass(id, PASS_DEPTH);
}

// Pass 2: among the splats of the nearest surface (within params.splat.x), the nearest centre.
@compute @workgroup_size(64)
fn splat_centre(@builtin(global_invocation_id) id: vec3<u32>) {
    splat_pass(id, PASS_CENTRE);
}

// Pass 3: the winning texel per (view, pixel).
@compute @workgroup_size(64)
fn splat_texel(@builtin(global_invocation_id) id: vec3<u32>) {
    splat_pass(id, PASS_TEXEL);
}

// Radiance of texel `i` of view `v`: its keys blended with their weights.
fn view_radiance(v: u32, i: u32) -> vec3<f32> {
    let n = params.size.z;
    let t = texel_coords(i, n);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < params.nearest[v].y; k++) {
        let texel = textureLoad(cubes, t.xy, params.layers[v][k] + t.z, 0);
        var radiance = rgb9e5_decode(texel.x);
        if params.light.z != 0u {
            radiance = relit(params.layers[v][k], i, texel, radiance);
        }
        sum += radiance * params.key_weights[v][k];
    }
    return sum;
}

// Texel `i` (key texel `key`, its radiance `radiance`) of the key at first layer `layer`,
// relit at the camera's light groups (plenoptic_recon's relight module).
fn relit(layer: u32, i: u32, key: vec4<u32>, radiance: vec3<f32>) -> vec3<f32> {
    let n = params.size.z;
    let t = texel_coords(i, n);
    let stored = stored_terms(textureLoad(shading_cubes, t.xy, layer + t.z, 0).xy);
    var acc = blend_base(params.light_base.xyz, stored);
    for (var l = 0u; l < params.light.y; l++) {
        let g = (layer / 6u) * params.light.x + params.light_layers[l].group;
        acc = blend_layer(acc, params.light_layers[l].coefficient, group_layers[g * 6u * n * n + i]);
    }
    // A texel that sees no object shows the sky.
    let fallback = select(params.light_base.xyz, params.light_sky.xyz, key.z == 0u);
    return relit_radiance(radiance, stored, blend_end(acc), fallback);
}

// plenoptic_recon::warp::blend_warped.
@compute @workgroup_size(8, 8)
fn blend(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let p = id.y * params.size.x + id.x;
    var z: array<f32, 8>;
    var zmin = 3.4e38;
    for (var v = 0u; v < params.size.w; v++) {
        z[v] = -1.0;
        let i = splat_texels[v * pixel_count() + p];
        if i != EMPTY {
            let s = splat_of(v, i);
            if s.ok {
                z[v] = s.z;
                zmin = min(zmin, s.z);
            }
        }
    }
    if zmin >= 3.4e38 {
        frame_in[p] = vec4<f32>(0.0, 0.0, 0.0, -1.0);
        return;
    }
    var sum = vec3<f32>(0.0);
    var ws = 0.0;
    for (var v = 0u; v < params.size.w; v++) {
        if z[v] >= 0.0 && z[v] <= zmin * (1.0 + params.forward.w) {
            let w = params.views[v].w;
            sum += view_radiance(v, splat_texels[v * pixel_count() + p]) * w;
            ws += w;
        }
    }
    var c = vec3<f32>(0.0);
    if ws > 0.0 {
        c = sum / ws;
    }
    frame_in[p] = vec4<f32>(c, zmin);
}

// One pass of plenoptic_recon::warp::background_fill.
@compute @workgroup_size(8, 8)
fn fill(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let p = id.y * params.size.x + id.x;
    let here = frame_in[p];
    if here.w >= 0.0 {
        frame_out[p] = here;
        return;
    }
    var best = here;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let nx = i32(id.x) + dx;
            let ny = i32(id.y) + dy;
            if nx < 0 || ny < 0 || nx >= i32(params.size.x) || ny >= i32(params.size.y) {
                continue;
            }
            let q = frame_in[u32(ny) * params.size.x + u32(nx)];
            if q.w >= 0.0 && (best.w < 0.0 || q.w > best.w) {
                best = q;
            }
        }
    }
    frame_out[p] = best;
}

@compute @workgroup_size(8, 8)
fn write_output(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let c = frame_in[id.y * params.size.x + id.x];
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(c.rgb, 1.0));
}
