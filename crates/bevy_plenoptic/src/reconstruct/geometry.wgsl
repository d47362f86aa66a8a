// Geometry-assisted reconstruction (thesis §8.2.3), per fragment of a proxy mesh.
// Same lookups and weights as plenoptic_recon::geometry (nearest texel, id + distance test,
// w_view · w_time · ((1 + cos θ)/2)^p); no volume fallback or hole fill.

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view

const MAX_LOOKUPS: u32 = 16u;

struct ReconParams {
    // x: lookup count, y: object id, z: face size (all as floats), w: unused.
    header: vec4<f32>,
    // x: depth tolerance, y: angular power.
    tuning: vec4<f32>,
    // Per lookup: base view position (xyz) and first layer (w).
    base: array<vec4<f32>, 16>,
    // Per lookup: weight (x).
    weight: array<vec4<f32>, 16>,
    // Per lookup: M_o(τ) M_o(t)⁻¹ of this material's object.
    motion: array<mat4x4<f32>, 16>,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> params: ReconParams;

fn rgb9e5_decode(v: u32) -> vec3<f32> {
    let e = f32(v >> 27u) - 15.0 - 9.0;
    let s = exp2(e);
    return vec3<f32>(f32(v & 0x1ffu), f32((v >> 9u) & 0x1ffu), f32((v >> 18u) & 0x1ffu)) * s;
}

// plenoptic_pack::cube::direction_to_face_uv followed by direction_to_texel.
fn cube_texel(dir: vec3<f32>, n: u32) -> vec3<u32> {
    let a = abs(dir);
    var face = 0u;
    var sc = 0.0;
    var tc = 0.0;
    var ma = 0.0;
    if a.x >= a.y && a.x >= a.z {
        if dir.x >= 0.0 { face = 0u; sc = -dir.z; tc = -dir.y; } else { face = 1u; sc = dir.z; tc = -dir.y; }
        ma = a.x;
    } else if a.y >= a.z {
        if dir.y >= 0.0 { face = 2u; sc = dir.x; tc = dir.z; } else { face = 3u; sc = dir.x; tc = -dir.z; }
        ma = a.y;
    } else {
        if dir.z >= 0.0 { face = 4u; sc = dir.x; tc = -dir.y; } else { face = 5u; sc = -dir.x; tc = -dir.y; }
        ma = a.z;
    }
    let u = 0.5 * (sc / ma + 1.0);
    let v = 0.5 * (tc / ma + 1.0);
    let i = min(u32(max(u, 0.0) * f32(n)), n - 1u);
    let j = min(u32(max(v, 0.0) * f32(n)), n - 1u);
    return vec3<u32>(i, j, face);
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

// plenoptic_pack::cube::face_uv_to_direction at the texel's centre.
fn texel_direction(t: vec3<u32>, n: u32) -> vec3<f32> {
    let sc = 2.0 * ((f32(t.x) + 0.5) / f32(n)) - 1.0;
    let tc = 2.0 * ((f32(t.y) + 0.5) / f32(n)) - 1.0;
    var d = vec3<f32>(0.0);
    switch t.z {
        case 0u: { d = vec3<f32>(1.0, -tc, -sc); }
        case 1u: { d = vec3<f32>(-1.0, -tc, sc); }
        case 2u: { d = vec3<f32>(sc, 1.0, tc); }
        case 3u: { d = vec3<f32>(sc, -1.0, -tc); }
        case 4u: { d = vec3<f32>(sc, -tc, 1.0); }
        default: { d = vec3<f32>(-sc, -tc, -1.0); }
    }
    return normalize(d);
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let count = u32(params.header.x);
    let object = u32(params.header.y);
    let n = u32(params.header.z);
    let tol = params.tuning.x;
    let power = params.tuning.y;
    let p = in.world_position.xyz;
    let to_eye = normalize(view.world_position - p);
    var sum = vec3<f32>(0.0);
    var ws = 0.0;
    var fallback = vec3<f32>(0.0);
    var fallback_w = -1.0;
    for (var k = 0u; k < min(count, MAX_LOOKUPS); k++) {
        let q = (params.motion[k] * vec4<f32>(p, 1.0)).xyz;
        let d = q - params.base[k].xyz;
        let dist = length(d);
        if dist <= 1e-6 {
            continue;
        }
        let t = cube_texel(d, n);
        let layer = u32(params.base[k].w) + t.z;
        let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), layer, 0);
        let radiance = rgb9e5_decode(texel.x);
        if params.weight[k].x > fallback_w {
            fallback_w = params.weight[k].x;
            fallback = radiance;
        }
        if texel.z != object {
            continue;
        }
        let dc = bitcast<f32>(texel.y);
        // Fast path: the texel's centre distance agrees. Otherwise compare with the distance
        // to the texel's surface plane along the lookup direction (grazing surfaces).
        if abs(dc - dist) > tol * dist {
            if texel.w == 0u {
                continue;
            }
            let nrm = oct_decode(max(unpack2x16snorm(texel.w), vec2<f32>(-1.0)));
            let denom = dot(d, nrm) / dist;
            if abs(denom) <= 0.05 {
                continue;
            }
            let expected = dot(texel_direction(t, n) * dc, nrm) / denom;
            if abs(expected - dist) > tol * dist {
                continue;
            }
        }
        var wa = 1.0;
        if power > 0.0 {
            let c = max((1.0 - dot(d, to_eye) / dist) * 0.5, 1e-3);
            wa = pow(c, power);
        }
        let w = params.weight[k].x * wa;
        sum += radiance * w;
        ws += w;
    }
    if ws > 0.0 {
        return vec4<f32>(sum / ws, 1.0);
    }
    // No accepted lookup: the heaviest view's texel in the point's direction.
    return vec4<f32>(fallback, 1.0);
}
