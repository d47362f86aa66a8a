// Reflected rays cast against the proxies (rays.rs): plenoptic_recon::flat_rays's layout,
// walked as FlatRays::occluded walks it, step for step. A stackless walk over depth-first
// nodes with miss links (Smits 1998); every link points forward, so it ends.
#define_import_path plenoptic::rays

#import plenoptic::counters::{tally, C_LOADS_16, C_STEPS}

#ifdef PLENOPTIC_STANDARD
@group(#{MATERIAL_BIND_GROUP}) @binding(112) var<storage, read> rays: array<vec4<f32>>;
@group(#{MATERIAL_BIND_GROUP}) @binding(113) var<storage, read> ray_placements: array<vec4<f32>>;
#else
// The pack's words: header, moving table, nodes, triangles (flat_rays.rs's module doc).
@group(#{MATERIAL_BIND_GROUP}) @binding(12) var<storage, read> rays: array<vec4<f32>>;
// The camera's moving objects placed at its time: three rows of world → object per object.
@group(#{MATERIAL_BIND_GROUP}) @binding(13) var<storage, read> ray_placements: array<vec4<f32>>;
#endif

const NO_TRIANGLES: u32 = 0xffffffffu;

// Whether the pack has proxy geometry to cast against.
fn has_rays() -> bool {
    return bitcast<u32>(rays[0].w) != 0u;
}

fn safe_recip(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-12);
    let s = select(d, select(-tiny, tiny, d >= vec3<f32>(0.0)), abs(d) < tiny);
    return 1.0 / s;
}

fn meets_box(origin: vec3<f32>, inv: vec3<f32>, tmax: f32, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    let lo_t = min(a, b);
    let hi_t = max(a, b);
    let near = max(max(max(lo_t.x, lo_t.y), lo_t.z), 0.0);
    let far = min(min(min(hi_t.x, hi_t.y), hi_t.z), tmax);
    return near <= far;
}

// Möller–Trumbore, both faces, a hit at 0 ≤ t ≤ tmax.
fn hits_triangle(origin: vec3<f32>, dir: vec3<f32>, tmax: f32, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> bool {
    let e1 = v0 - v1;
    let e2 = v2 - v0;
    let n = cross(e1, e2);
    let c = v0 - origin;
    let r = cross(dir, c);
    let det = dot(n, dir);
    if det == 0.0 {
        return false;
    }
    let inv_det = 1.0 / det;
    let u = dot(r, e2) * inv_det;
    let v = dot(r, e1) * inv_det;
    let w = 1.0 - u - v;
    if u < 0.0 || v < 0.0 || w < 0.0 {
        return false;
    }
    let t = dot(n, c) * inv_det;
    return t >= 0.0 && t <= tmax;
}

// The walk of the node words first..end: how many triangles the ray meets, stopping at the
// first unless `all` (FlatRays::hits).
fn traverse(first: u32, end: u32, origin: vec3<f32>, dir: vec3<f32>, tmax: f32, all: bool) -> u32 {
    let inv = safe_recip(dir);
    var count = 0u;
    var i = first;
    while i < end {
        tally(C_STEPS, 1u);
        tally(C_LOADS_16, 2u);
        let a = rays[i];
        let b = rays[i + 1u];
        if !meets_box(origin, inv, tmax, a.xyz, b.xyz) {
            i = bitcast<u32>(a.w);
            continue;
        }
        let leaf = bitcast<u32>(b.w);
        if leaf == NO_TRIANGLES {
            i += 2u;
            continue;
        }
        var j = leaf;
        loop {
            tally(C_STEPS, 1u);
            tally(C_LOADS_16, 3u);
            let v0 = rays[j];
            if hits_triangle(origin, dir, tmax, v0.xyz, rays[j + 1u].xyz, rays[j + 2u].xyz) {
                count += 1u;
                if !all {
                    return count;
                }
            }
            if v0.w != 0.0 {
                break;
            }
            j += 3u;
        }
        i = bitcast<u32>(a.w);
    }
    return count;
}

// The ray moved into the space of moving BVH k (its three placement rows).
struct PlacedRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

fn placed_ray(k: u32, origin: vec3<f32>, dir: vec3<f32>) -> PlacedRay {
    let r0 = ray_placements[3u * k];
    let r1 = ray_placements[3u * k + 1u];
    let r2 = ray_placements[3u * k + 2u];
    let o = vec4<f32>(origin, 1.0);
    let d = vec4<f32>(dir, 0.0);
    return PlacedRay(vec3<f32>(dot(r0, o), dot(r1, o), dot(r2, o)), vec3<f32>(dot(r0, d), dot(r1, d), dot(r2, d)));
}

// Whether any proxy lies along the ray from `origin` along `dir` closer than `tmax`.
fn occluded(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> bool {
    let header = rays[0];
    if bitcast<u32>(header.w) == 0u {
        return false;
    }
    if traverse(bitcast<u32>(header.x), bitcast<u32>(header.y), origin, dir, tmax, false) > 0u {
        return true;
    }
    let moving = min(bitcast<u32>(header.z), arrayLength(&ray_placements) / 3u);
    for (var k = 0u; k < moving; k++) {
        let entry = rays[1u + k];
        let r = placed_ray(k, origin, dir);
        if traverse(bitcast<u32>(entry.x), bitcast<u32>(entry.y), r.origin, r.dir, tmax, false) > 0u {
            return true;
        }
    }
    return false;
}

// The fraction of light that passes along the ray within `tmax`: 0 where an opaque proxy
// lies on it, else the product of 1 − c over the glazing surfaces it crosses
// (plenoptic_recon's PlacedShadows::transmittance, the lamps' shadow rays).
fn transmittance(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> f32 {
    let header = rays[0];
    if bitcast<u32>(header.w) == 0u {
        return 1.0;
    }
    if traverse(bitcast<u32>(header.x), bitcast<u32>(header.y), origin, dir, tmax, false) > 0u {
        return 0.0;
    }
    let moving = min(bitcast<u32>(header.z), arrayLength(&ray_placements) / 3u);
    var through = 1.0;
    for (var k = 0u; k < moving; k++) {
        let entry = rays[1u + k];
        let r = placed_ray(k, origin, dir);
        let glazing = entry.w > 0.0;
        let n = traverse(bitcast<u32>(entry.x), bitcast<u32>(entry.y), r.origin, r.dir, tmax, glazing);
        if n > 0u && !glazing {
            return 0.0;
        }
        through *= select(1.0, pow(entry.w, f32(n)), glazing);
    }
    return through;
}

// The fraction of light the see-through glazing lets through along the ray: the product of
// 1 − c over the glazing surfaces it crosses, the other proxies ignored
// (FlatRays::see_through_pass). Glazing BVHs are the moving entries whose w is above 0.
fn see_through_pass(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> f32 {
    let moving = min(bitcast<u32>(rays[0].z), arrayLength(&ray_placements) / 3u);
    var through = 1.0;
    for (var k = 0u; k < moving; k++) {
        let entry = rays[1u + k];
        if entry.w > 0.0 {
            let r = placed_ray(k, origin, dir);
            let n = traverse(bitcast<u32>(entry.x), bitcast<u32>(entry.y), r.origin, r.dir, tmax, true);
            through *= pow(entry.w, f32(n));
        }
    }
    return through;
}
