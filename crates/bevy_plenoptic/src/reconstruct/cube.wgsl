// Cube texel helpers shared by the reconstruction shaders: the pack's RGB9E5 radiance and
// its cube face convention (plenoptic_pack::cube, Vulkan/KTX2 face order).
#define_import_path plenoptic::cube

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
