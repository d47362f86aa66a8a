// Cube texel helpers shared by the reconstruction shaders: the pack's RGB9E5 radiance and
// its cube face convention (plenoptic_pack::cube, Vulkan/KTX2 face order).
#define_import_path plenoptic::cube

fn rgb9e5_decode(v: u32) -> vec3<f32> {
    let e = f32(v >> 27u) - 15.0 - 9.0;
    let s = exp2(e);
    return vec3<f32>(f32(v & 0x1ffu), f32((v >> 9u) & 0x1ffu), f32((v >> 18u) & 0x1ffu)) * s;
}

// plenoptic_pack::cube::rgb9e5_pack: the shared exponent from the largest channel (clamped
// to the format's range, NaN as 0), each mantissa rounded to nearest.
fn rgb9e5_encode(rgb: vec3<f32>) -> u32 {
    let c = select(clamp(rgb, vec3<f32>(0.0), vec3<f32>(65408.0)), vec3<f32>(0.0), rgb != rgb);
    let maxc = max(c.x, max(c.y, c.z));
    var floor_log2 = -16;
    if maxc > 0.0 {
        floor_log2 = i32(floor(log2(maxc)));
    }
    var e = max(floor_log2, -16) + 16;
    if i32(floor(maxc / exp2(f32(e - 24)) + 0.5)) == 512 {
        e += 1;
    }
    e = clamp(e, 0, 31);
    let q = min(vec3<u32>(floor(c / exp2(f32(e - 24)) + 0.5)), vec3<u32>(511u));
    return q.x | (q.y << 9u) | (q.z << 18u) | (u32(e) << 27u);
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

// plenoptic_recon's sample::face_uv: (face, u, v) of a direction, u and v in [0, 1].
fn face_uv(dir: vec3<f32>) -> vec3<f32> {
    let a = abs(dir);
    var r = vec4<f32>(0.0);
    if a.x >= a.y && a.x >= a.z {
        r = select(vec4<f32>(1.0, dir.z, -dir.y, a.x), vec4<f32>(0.0, -dir.z, -dir.y, a.x), dir.x >= 0.0);
    } else if a.y >= a.z {
        r = select(vec4<f32>(3.0, dir.x, -dir.z, a.y), vec4<f32>(2.0, dir.x, dir.z, a.y), dir.y >= 0.0);
    } else {
        r = select(vec4<f32>(5.0, -dir.x, -dir.y, a.z), vec4<f32>(4.0, dir.x, -dir.y, a.z), dir.z >= 0.0);
    }
    return vec3<f32>(r.x, 0.5 * (r.y / r.w + 1.0), 0.5 * (r.z / r.w + 1.0));
}

// plenoptic_recon's sample::face_uv_direction: the direction through (u, v) on face `face`'s
// plane, u and v not limited to [0, 1] (not normalised).
fn face_uv_direction(face: u32, u: f32, v: f32) -> vec3<f32> {
    let sc = 2.0 * u - 1.0;
    let tc = 2.0 * v - 1.0;
    switch face {
        case 0u: { return vec3<f32>(1.0, -tc, -sc); }
        case 1u: { return vec3<f32>(-1.0, -tc, sc); }
        case 2u: { return vec3<f32>(sc, 1.0, tc); }
        case 3u: { return vec3<f32>(sc, -1.0, -tc); }
        case 4u: { return vec3<f32>(sc, -tc, 1.0); }
        default: { return vec3<f32>(-sc, -tc, -1.0); }
    }
}

// The 2 × 2 texels of the bilinear filter of a face-size `n` cube around a direction, on
// the direction's face (plenoptic_recon's sample::bilinear_taps before the seam).
struct Footprint {
    // The first tap's (column, row); -1 or n - 1 where the footprint leaves the face.
    corner: vec2<f32>,
    // The face.
    face: u32,
    // The fractions that weight the taps.
    f: vec2<f32>,
    // Whether all four taps lie on the face.
    inside: bool,
}

// The footprint of direction `dir` in a cube of face size `n`.
fn footprint(dir: vec3<f32>, n: u32) -> Footprint {
    let fuv = face_uv(dir);
    let nf = f32(n);
    let s = fuv.yz * nf - 0.5;
    var fp: Footprint;
    fp.corner = floor(s);
    fp.face = u32(fuv.x);
    fp.f = s - fp.corner;
    fp.inside = all(fp.corner >= vec2<f32>(0.0)) && all(fp.corner + 1.0 < vec2<f32>(nf));
    return fp;
}

// The bilinear weight of tap `k` (0..4: (0,0), (1,0), (0,1), (1,1)) for fractions `f`.
fn tap_weight(f: vec2<f32>, k: u32) -> f32 {
    let wx = select(1.0 - f.x, f.x, (k & 1u) == 1u);
    let wy = select(1.0 - f.y, f.y, (k >> 1u) == 1u);
    return wx * wy;
}

// Tap `k` (0..4: (0,0), (1,0), (0,1), (1,1)) of the seamless bilinear filter of a face-size
// `n` cube around `dir` (plenoptic_recon's sample::bilinear_taps): (column, row, face) and its
// weight in w; weight 0 where the tap is the missing fourth texel of a cube corner.
fn bilinear_tap(dir: vec3<f32>, n: u32, k: u32) -> vec4<f32> {
    let fp = footprint(dir, n);
    let face = fp.face;
    let nf = f32(n);
    let w = tap_weight(fp.f, k);
    let i = fp.corner.x + f32(k & 1u);
    let j = fp.corner.y + f32(k >> 1u);
    let in_i = i >= 0.0 && i < nf;
    let in_j = j >= 0.0 && j < nf;
    if in_i && in_j {
        return vec4<f32>(i, j, f32(face), w);
    }
    if in_i || in_j {
        let d = face_uv_direction(face, (i + 0.5) / nf, (j + 0.5) / nf);
        return vec4<f32>(vec3<f32>(cube_texel(d, n)), w);
    }
    return vec4<f32>(0.0);
}
