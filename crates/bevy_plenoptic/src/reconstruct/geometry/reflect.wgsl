// The reflection march of one lookup's cube (plenoptic_recon's specular module, the same
// steps): along x(s) = origin + s·dir the point is projected into the key's cube; the ray has
// hit where |x(s) − centre| first passes the cube's distance there. The crossing is refined
// by bisection and accepted when the ray meets the stored surface (the distance step within
// the tolerance plus a texel), else the ray went behind what the view saw.
#define_import_path plenoptic::reflect

#import plenoptic::cube::{rgb9e5_decode, cube_texel}
#import plenoptic::counters::{tally, C_LOADS_16, C_STEPS}

// plenoptic_recon::specular's MAX_STEPS, REFINE_STEPS and STEP_TEXELS (checked by a test in
// reflect.rs).
const MAX_STEPS: u32 = 160u;
const REFINE_STEPS: u32 = 6u;
// Cube texels the projected point moves per step.
const STEP_TEXELS: f32 = 2.0;

// (|x(s) − centre| − the cube's distance there, |x(s) − centre|).
fn gap(cubes: texture_2d_array<u32>, layer0: u32, n: u32, centre: vec3<f32>, origin: vec3<f32>, dir: vec3<f32>, s: f32) -> vec2<f32> {
    let q = origin + dir * s - centre;
    let d = length(q);
    let t = cube_texel(q, n);
    tally(C_STEPS, 1u);
    tally(C_LOADS_16, 1u);
    let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), layer0 + t.z, 0);
    return vec2<f32>(d - bitcast<f32>(texel.y), d);
}

// Marches the ray through the key at `layer0` (face size `n`, seen from `centre`): (s, 1)
// where it meets a surface the view saw, (0, 2) where it leaves the scene (beyond `far`),
// (0, 0) where the view cannot tell.
fn march(cubes: texture_2d_array<u32>, layer0: u32, n: u32, centre: vec3<f32>, origin: vec3<f32>, dir: vec3<f32>, far: f32, tol: f32) -> vec2<f32> {
    let texel_angle = 2.0 / f32(n);
    let start = gap(cubes, layer0, n, centre, origin, dir, 0.0).y;
    var s = max(start * texel_angle, 0.01);
    var prev_s = 0.0;
    for (var i = 0u; i < MAX_STEPS; i++) {
        if s > far {
            return vec2<f32>(0.0, 2.0);
        }
        let g = gap(cubes, layer0, n, centre, origin, dir, s);
        if g.x > 0.0 {
            var lo = prev_s;
            var hi = s;
            var g_hi = g.x;
            for (var k = 0u; k < REFINE_STEPS; k++) {
                let mid = 0.5 * (lo + hi);
                let gm = gap(cubes, layer0, n, centre, origin, dir, mid).x;
                if gm > 0.0 {
                    hi = mid;
                    g_hi = gm;
                } else {
                    lo = mid;
                }
            }
            let d_hit = length(origin + dir * hi - centre);
            let step = (hi - lo) + d_hit * texel_angle;
            if g_hi <= tol * d_hit + step {
                return vec2<f32>(hi, 1.0);
            }
            return vec2<f32>(0.0, 0.0);
        }
        prev_s = s;
        let q = (origin + dir * s - centre) / max(g.y, 1e-6);
        let sin = max(length(cross(q, dir)), 0.15);
        s += clamp(STEP_TEXELS * g.y * texel_angle / sin, 0.005, 1.0);
    }
    return vec2<f32>(0.0, 0.0);
}

// Two unit vectors completing unit `v` to an orthonormal basis (glam's any_orthonormal_pair:
// Duff et al. 2017).
fn orthonormal_pair(v: vec3<f32>) -> array<vec3<f32>, 2> {
    let sign = select(-1.0, 1.0, v.z >= 0.0);
    let a = -1.0 / (sign + v.z);
    let b = v.x * v.y * a;
    return array<vec3<f32>, 2>(
        vec3<f32>(1.0 + sign * v.x * v.x * a, sign * b, -sign * v.x),
        vec3<f32>(b, sign + v.y * v.y * a, -v.y),
    );
}

// The key's radiance around direction `to` from its view, over a cone of half-angle `angle`
// (a 5 × 5 Gaussian-weighted set of directions; the nearest texel for a narrow cone).
fn fetch(cubes: texture_2d_array<u32>, layer0: u32, n: u32, to: vec3<f32>, angle: f32) -> vec3<f32> {
    let axis = normalize(to);
    if angle < 0.5 * (2.0 / f32(n)) {
        let t = cube_texel(axis, n);
        tally(C_LOADS_16, 1u);
        return rgb9e5_decode(textureLoad(cubes, vec2<u32>(t.x, t.y), layer0 + t.z, 0).x);
    }
    let pair = orthonormal_pair(axis);
    tally(C_LOADS_16, 25u);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    for (var i = -2; i <= 2; i++) {
        for (var j = -2; j <= 2; j++) {
            let w = exp(-0.5 * f32(i * i + j * j));
            let d = axis + (pair[0] * f32(i) + pair[1] * f32(j)) * (0.5 * angle);
            let t = cube_texel(d, n);
            sum += rgb9e5_decode(textureLoad(cubes, vec2<u32>(t.x, t.y), layer0 + t.z, 0).x) * w;
            total += w;
        }
    }
    return sum / total;
}
