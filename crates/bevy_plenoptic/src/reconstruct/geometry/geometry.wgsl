// Geometry-assisted reconstruction (thesis §8.2.3), per fragment of a proxy mesh.
// Same lookups and weights as plenoptic_recon::geometry (nearest or seamless bilinear texel, id + distance test,
// w_view · w_time · ((1 + cos θ)/2)^p), with its volume fallback and hole fill. An object with a
// material in a 2.0 pack is shaded as plenoptic_recon's shading module does it:
// albedo (the material's factors × textures) · lighting + non-diffuse, both looked up
// bilinearly, the runtime sun through the normal-mapped shading normal; on
// mirrors and glossy metals the non-diffuse part is replaced by reflections marched for the
// camera through the lookups' distance cubes (reflect.rs, reflect.wgsl).

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::{view, lights}
#import bevy_pbr::shadows::fetch_directional_shadow
#ifdef TONEMAP_IN_SHADER
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif
#import bevy_pbr::prepass_utils
#import bevy_pbr::mesh_functions::get_local_from_world
#ifdef PLENOPTIC_STANDARD
#import bevy_pbr::pbr_fragment::pbr_input_from_standard_material
#import bevy_pbr::pbr_functions::alpha_discard
#endif

#import plenoptic::cube::{rgb9e5_decode, cube_texel, texel_direction, bilinear_tap}
#import plenoptic::environment::{Environment, environment}
#import plenoptic::reflect::{march, fetch, orthonormal_pair}
#import plenoptic::rays::{has_rays, occluded}

const MAX_LOOKUPS: u32 = 16u;
const MAX_VOLUMES: u32 = 8u;
// How far off its surface a reflected ray is cast (plenoptic_recon::specular's RAY_OFFSET).
const RAY_OFFSET: f32 = 0.001;
// Face size of the volume samples' direction bins (plenoptic_recon's VolumeIndex).
const BIN_FACE: u32 = 16u;

// A camera's view buffer (view.rs, ViewParams): its lookups and settings this frame.
struct ViewParams {
    // x: lookup count, y: face size, z: volume block count (all as floats), w: unused.
    header: vec4<f32>,
    // x: depth tolerance, y: angular power, z: time t, w: temporal window tε.
    tuning: vec4<f32>,
    // x: hole-fill radius (pixels), y: index of the heaviest lookup, z: 1 for the image-mode
    // frame.
    fill: vec4<f32>,
    // x: 1 for seamless bilinear filtering of accepted lookups (ReconSettings::cube_filter);
    // y: how many lamps are in use.
    flags: vec4<f32>,
    // The runtime sun (pack 3): direction towards it (xyz), w: 1 when there is one.
    sun: vec4<f32>,
    // Its illuminance at the camera's time (xyz).
    sun_illuminance: vec4<f32>,
    // Reflections marched for the camera: x: 1 when on, y: the roughest glossy surface
    // marched (−1: ideal mirrors only), z: how far rays are marched, w: rays per glossy
    // pixel (plenoptic_recon's GLOSSY_RAYS).
    specular: vec4<f32>,
    // The placed lamps (plenoptic_recon's lamps module), 3 per lamp: position (xyz), range
    // (w, −1: none); spot axis (xyz), cos outer cone (w, −2: a point light); colour ×
    // intensity (xyz), 1 / (cos inner − cos outer) (w).
    lamps: array<vec4<f32>, 12>,
    // Per lookup: base view position (xyz) and first layer (w).
    base: array<vec4<f32>, 16>,
    // Per lookup: weight (x), whether the key has normals (y).
    weight: array<vec4<f32>, 16>,
    // Per volume block: base view position (xyz), view weight (w).
    volume: array<vec4<f32>, 8>,
    // Per volume block: first sample (x), first bin offset (y).
    volume_range: array<vec4<u32>, 8>,
    // The pack's environment at the camera's time, for reflected rays that leave the scene
    // (not named `environment`: naga_oil would take the field for the imported function).
    env: Environment,
    // M_o(τ) per animated object (its motion slot) and lookup: entry slot · 16 + k.
    motion: array<mat4x4<f32>>,
}

// A material's uniform (mod.rs, ObjectParams): its object and material.
struct ObjectParams {
    // x: object id, y: motion slot (−1: static, in world space), z: coverage of glazing,
    // w: 1 to shade as albedo · lighting + non-diffuse (pack 2.0, Shading::Materials).
    object: vec4<f32>,
    // x: 1 for see-through transmissive glass (its reflection over what lies behind), y: its
    // mean transmittance per surface.
    glass: vec4<f32>,
    // The object's base-colour factor (xyz) and metallic factor (w) when object.w is 1.
    albedo: vec4<f32>,
    // x: transmission factor; y, z, w: largest side of the base-colour and metallic-roughness
    // textures and of the normal map (0: none).
    material: vec4<f32>,
    // KHR_texture_transform of the three textures: offset (xy), scale (zw); rotations in
    // uv_rotation.xyz.
    base_uv: vec4<f32>,
    mr_uv: vec4<f32>,
    normal_uv: vec4<f32>,
    uv_rotation: vec4<f32>,
    // x: roughness factor, y: IOR (the runtime sun's BSDF), z: the normal map's scale.
    surface: vec4<f32>,
    // The material's emissive factor (xyz).
    emissive: vec4<f32>,
    // The emissive texture's transform: offset (xy), scale (zw).
    emissive_uv: vec4<f32>,
    // x: the emissive texture's largest side (0: none), y: 1 when the pack leaves the
    // emission to the runtime, z: 1 when double-sided, w: the texture's UV rotation.
    emission: vec4<f32>,
}

#ifdef PLENOPTIC_STANDARD
// An app mesh's StandardMaterial extended with the pack's lighting (lit/scene.rs): the
// standard material's bindings come first, this extension's from 100 (the same bindings as
// the proxy material's below, less its pack textures: the standard material has its own).
@group(#{MATERIAL_BIND_GROUP}) @binding(100) var cubes: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(101) var<uniform> params: ObjectParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(102) var<storage, read> volume_samples: array<vec4<u32>>;
@group(#{MATERIAL_BIND_GROUP}) @binding(103) var<storage, read> volume_bins: array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(104) var image_frame: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(105) var shading_cubes: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(110) var<storage, read> cam: ViewParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(111) var env_image: texture_2d<f32>;
#else
@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> params: ObjectParams;
// Three words per sample: (direction.xyz, radius), (radiance.rgb, distance), (t, object,
// lighting RGB9E5, non-diffuse RGB9E5).
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var<storage, read> volume_samples: array<vec4<u32>>;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var<storage, read> volume_bins: array<u32>;
// The image-mode frame (image.wgsl), shown when cam.fill.z is 1.
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var image_frame: texture_2d<f32>;
// Per texel of the key texture: (lighting RGB9E5, non-diffuse RGB9E5).
@group(#{MATERIAL_BIND_GROUP}) @binding(5) var shading_cubes: texture_2d_array<u32>;

@group(#{MATERIAL_BIND_GROUP}) @binding(6) var base_colour_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(7) var base_colour_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(8) var metallic_roughness_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(9) var metallic_roughness_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(14) var normal_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(15) var normal_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(16) var emissive_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(17) var emissive_sampler: sampler;
// The camera's view buffer: its lookups, settings, environment and objects' motion.
@group(#{MATERIAL_BIND_GROUP}) @binding(10) var<storage, read> cam: ViewParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(11) var env_image: texture_2d<f32>;
#endif

// The fragment's diffuse albedo (set once per fragment, before any lookup).
var<private> pixel_albedo: vec3<f32>;
// Its textured base colour, metalness and roughness (the runtime sun's BSDF).
var<private> pixel_base: vec3<f32>;
var<private> pixel_metallic: f32;
var<private> pixel_roughness: f32;
// 0 where a marched reflection replaces the baked non-diffuse radiance.
var<private> non_diffuse_weight: f32 = 1.0;
// Its emission at its UV (pack 4 and marched surfaces; zero for app meshes).
var<private> pixel_emission: vec3<f32>;
// The drawn mesh's local_from_world (Bevy's mesh uniform): M_o(t)⁻¹ for a proxy placed at
// the camera's time, the app mesh's own inverse transform for a lit mesh.
var<private> local_from_world: mat4x4<f32>;

// Point `p` of this object in the object's own frame (homogeneous): local_from_world · p
// for an animated object; `p` itself for a static one (in world space), which is not
// carried. Computed once per point, before its lookups.
fn object_point(p: vec3<f32>) -> vec4<f32> {
    if params.object.y < 0.0 {
        return vec4<f32>(p, 1.0);
    }
    return local_from_world * vec4<f32>(p, 1.0);
}

// The point whose `object_point` is `local`, carried to lookup k's key time τ: M_o(τ) · local
// for an animated object, the point itself for a static one.
fn carried(local: vec4<f32>, k: u32) -> vec3<f32> {
    let slot = params.object.y;
    if slot < 0.0 {
        return local.xyz;
    }
    return (cam.motion[u32(slot) * MAX_LOOKUPS + k] * local).xyz;
}

// Whether this object is shaded from its material (albedo · lighting + non-diffuse).
fn lit() -> bool {
    return params.object.w == 1.0;
}

// The shaded colour of a shading texel: the fragment's albedo · lighting + non-diffuse (in the
// hole fill, the neighbours' lighting times this fragment's own albedo, as on the CPU).
fn shaded(s: vec2<u32>) -> vec3<f32> {
    return pixel_albedo * rgb9e5_decode(s.x) + rgb9e5_decode(s.y) * non_diffuse_weight;
}

// KHR_texture_transform: offset + R(rotation) · (scale ∘ uv).
fn uv_transform(uv: vec2<f32>, t: vec4<f32>, rotation: f32) -> vec2<f32> {
    let s = uv * t.zw;
    let c = cos(rotation);
    let n = sin(rotation);
    return t.xy + vec2<f32>(c * s.x + n * s.y, -n * s.x + c * s.y);
}

// The mip level plenoptic_recon's material module picks: log2 of the pixel's footprint in UV
// units (√ of the UV area one pixel covers, `footprint`) × the transform's scale × the side.
fn level(footprint: f32, t: vec4<f32>, side: f32) -> f32 {
    let texels = footprint * max(abs(t.z), abs(t.w)) * side;
    return select(0.0, log2(texels), texels > 1.0);
}

#ifndef PLENOPTIC_STANDARD
// The diffuse albedo at UV `uv`, whose pixel covers `footprint` UV units (√area):
// (1 − metallic · mr.b)(1 − transmission) · base colour · texture.
fn material_albedo(uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    var base = params.albedo.xyz;
    var metallic = params.albedo.w;
    var roughness = params.surface.x;
    if params.material.y > 0.0 {
        let st = uv_transform(uv, params.base_uv, params.uv_rotation.x);
        let lod = level(footprint, params.base_uv, params.material.y);
        base *= textureSampleLevel(base_colour_texture, base_colour_sampler, st, lod).rgb;
    }
    if params.material.z > 0.0 {
        let st = uv_transform(uv, params.mr_uv, params.uv_rotation.y);
        let lod = level(footprint, params.mr_uv, params.material.z);
        let mr = textureSampleLevel(metallic_roughness_texture, metallic_roughness_sampler, st, lod);
        metallic *= mr.b;
        roughness *= mr.g;
    }
    pixel_base = base;
    pixel_metallic = clamp(metallic, 0.0, 1.0);
    pixel_roughness = clamp(roughness, 0.0, 1.0);
    return base * ((1.0 - clamp(metallic, 0.0, 1.0)) * (1.0 - params.material.x));
}

// The emission at UV `uv` (footprint as above), as plenoptic_recon's Materials::emission:
// the emissive factor × the sRGB texture; from the front only unless double-sided.
fn material_emission(in: VertexOutput, uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    var e = params.emissive.xyz;
    let front = dot(view.world_position - in.world_position.xyz, in.world_normal) > 0.0;
    if params.emission.z != 1.0 && !front {
        return vec3<f32>(0.0);
    }
    if params.emission.x > 0.0 && any(e != vec3<f32>(0.0)) {
        let st = uv_transform(uv, params.emissive_uv, params.emission.w);
        let lod = level(footprint, params.emissive_uv, params.emission.x);
        e *= textureSampleLevel(emissive_texture, emissive_sampler, st, lod).rgb;
    }
    return e;
}

// The shading normal `ns` bent by the normal map at UV `uv` (footprint as above) in the
// frame of `tangent` (xyz, the bitangent's sign in w), as plenoptic_recon's
// material::bend_normal bends it; `ns` without a normal map or where the frame degenerates.
fn bent_normal(ns: vec3<f32>, tangent: vec4<f32>, uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    if params.material.w <= 0.0 {
        return ns;
    }
    let st = uv_transform(uv, params.normal_uv, params.uv_rotation.z);
    let lod = level(footprint, params.normal_uv, params.material.w);
    let c = textureSampleLevel(normal_texture, normal_sampler, st, lod).rgb * 2.0 - 1.0;
    let local = vec3<f32>(c.xy * params.surface.z, c.z);
    let t = tangent.xyz - ns * dot(ns, tangent.xyz);
    if dot(t, t) <= 1e-20 {
        return ns;
    }
    let tn = normalize(t);
    let b = cross(ns, tn) * select(1.0, -1.0, tangent.w < 0.0);
    let n = tn * local.x + b * local.y + ns * local.z;
    return select(ns, normalize(n), dot(n, n) > 1e-20);
}

// plenoptic_pack::cube::oct_decode.
#endif

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

// Whether key texel `c` (its key-texture texel `texel`) shows the surface of the lookup `d`
// (length `l`) of `object`: the same object at the distance within `tol · l`, or, where the
// key has normals (`normals`), its centre point on the plane through the lookup's point with
// the texel's normal within `tol · l` (plenoptic_recon's lookup::same_surface).
fn same_surface(c: vec3<u32>, n: u32, texel: vec4<u32>, object: u32, d: vec3<f32>, l: f32, tol: f32, normals: bool) -> bool {
    if texel.z != object {
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
// nearest texel `t` (plenoptic_recon's lookup::filtered).
fn filtered(layer0: u32, n: u32, d: vec3<f32>, t: vec3<u32>, object: u32, l: f32, tol: f32, normals: bool) -> vec3<f32> {
    var acc = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let tap = bilinear_tap(d, n, k);
        if tap.w <= 0.0 {
            continue;
        }
        let c = vec3<u32>(tap.xyz);
        let texel = textureLoad(cubes, c.xy, layer0 + c.z, 0);
        let nearest = all(c == t);
        if nearest || same_surface(c, n, texel, object, d, l, tol, normals) {
            acc += vec4<f32>(colour(c, layer0, texel), 1.0) * tap.w;
        }
    }
    if acc.w > 0.0 {
        return acc.rgb / acc.w;
    }
    return colour(t, layer0, textureLoad(cubes, t.xy, layer0 + t.z, 0));
}

// The colour of key texel `c` (in the key at `layer0`, whose key-texture texel is `texel`):
// its radiance, or its shaded lighting for an object shaded from its material.
fn colour(c: vec3<u32>, layer0: u32, texel: vec4<u32>) -> vec3<f32> {
    if lit() {
        return shaded(textureLoad(shading_cubes, c.xy, layer0 + c.z, 0).xy);
    }
    return rgb9e5_decode(texel.x);
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
}

// Lookup k of the point whose `object_point` is `local`, in keys of face size `n`.
fn lookup_of(local: vec4<f32>, k: u32, n: u32) -> Lookup {
    var l: Lookup;
    l.d = carried(local, k) - cam.base[k].xyz;
    l.dist = length(l.d);
    l.ok = !(l.dist <= 1e-6);
    if l.ok {
        l.t = cube_texel(l.d, n);
    }
    return l;
}

// The accepted lookups of point `p` of `object` (seen from `eye`): (Σ w·radiance, Σ w).
fn direct_lookups(p: vec3<f32>, eye: vec3<f32>, object: u32) -> vec4<f32> {
    let count = u32(cam.header.x);
    let n = u32(cam.header.y);
    let tol = cam.tuning.x;
    let power = cam.tuning.y;
    let to_eye = normalize(eye - p);
    let local = object_point(p);
    var sum = vec3<f32>(0.0);
    var ws = 0.0;
    for (var k = 0u; k < min(count, MAX_LOOKUPS); k++) {
        let l = lookup_of(local, k, n);
        if !l.ok {
            continue;
        }
        let d = l.d;
        let dist = l.dist;
        let t = l.t;
        let layer = u32(cam.base[k].w) + t.z;
        let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), layer, 0);
        if texel.z != object {
            continue;
        }
        let dc = bitcast<f32>(texel.y);
        // Fast path: the texel's centre distance agrees. Otherwise compare with the distance
        // to the texel's surface plane along the lookup direction (grazing surfaces).
        if abs(dc - dist) > tol * dist {
            if cam.weight[k].y == 0.0 {
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
        let w = cam.weight[k].x * wa;
        var radiance = rgb9e5_decode(texel.x);
        // Lighting is always filtered (plenoptic_recon's shading module).
        if cam.flags.x == 1.0 || lit() {
            radiance = filtered(u32(cam.base[k].w), n, d, t, object, dist, tol, cam.weight[k].y != 0.0);
        }
        sum += radiance * w;
        ws += w;
    }
    return vec4<f32>(sum, ws);
}

// plenoptic_recon's NEIGHBOUR_TEXELS and NEIGHBOUR_TOLERANCE.
const NEIGHBOUR_TEXELS: i32 = 8;
const NEIGHBOUR_TOLERANCE: f32 = 0.25;
// Ranks another object's texel behind every texel of the object itself.
const OTHER_OBJECT: i32 = 2 * NEIGHBOUR_TEXELS * NEIGHBOUR_TEXELS + 1;
// Above every score.
const NO_TEXEL: i32 = 1073741824;

// The fallback after the hole fill (plenoptic_recon's neighbour_texel): in each lookup's key,
// the nearest texel at about the distance of `p` within NEIGHBOUR_TEXELS of the lookup's
// texel on its face, `object`'s own first, then any surface's (the first in row order on
// ties). Returns (Σ w·colour, Σ w).
fn neighbour_texels(p: vec3<f32>, object: u32) -> vec4<f32> {
    var sum = vec3<f32>(0.0);
    var ws = 0.0;
    let count = u32(cam.header.x);
    let n = u32(cam.header.y);
    let local = object_point(p);
    for (var k = 0u; k < min(count, MAX_LOOKUPS); k++) {
        let l = lookup_of(local, k, n);
        if !l.ok {
            continue;
        }
        let dist = l.dist;
        let t = l.t;
        let layer0 = u32(cam.base[k].w);
        var best = NO_TEXEL;
        var best_c = t;
        for (var dj = -NEIGHBOUR_TEXELS; dj <= NEIGHBOUR_TEXELS; dj++) {
            for (var di = -NEIGHBOUR_TEXELS; di <= NEIGHBOUR_TEXELS; di++) {
                let x = i32(t.x) + di;
                let y = i32(t.y) + dj;
                if x < 0 || y < 0 || x >= i32(n) || y >= i32(n) {
                    continue;
                }
                let c = vec3<u32>(u32(x), u32(y), t.z);
                let texel = textureLoad(cubes, c.xy, layer0 + c.z, 0);
                // The object's own texels first, then any surface at the point's distance.
                let score = di * di + dj * dj + select(OTHER_OBJECT, 0, texel.z == object);
                if texel.z != 0u && abs(bitcast<f32>(texel.y) - dist) <= NEIGHBOUR_TOLERANCE * dist
                    && score < best {
                    best = score;
                    best_c = c;
                }
            }
        }
        if best < NO_TEXEL {
            let texel = textureLoad(cubes, best_c.xy, layer0 + best_c.z, 0);
            sum += colour(best_c, layer0, texel) * cam.weight[k].x;
            ws += cam.weight[k].x;
        }
    }
    return vec4<f32>(sum, ws);
}

// The temporal-volume fallback (plenoptic_recon's VolumeIndex::lookup, summed over the views
// with their weights): samples of `object` in the direction bin of `p` from each base view,
// whose cone contains that direction, whose distance agrees within 3× the depth tolerance and
// whose time is within t ± tε, weighted by the tent filter and the angular falloff.
// Returns (Σ w·radiance, Σ w).
fn volume_lookups(p: vec3<f32>, object: u32) -> vec4<f32> {
    let count = min(u32(cam.header.z), MAX_VOLUMES);
    let tol = cam.tuning.x * 3.0;
    let t = cam.tuning.z;
    let eps = cam.tuning.w;
    let half_bin = 1.0 / f32(BIN_FACE);
    var sum = vec3<f32>(0.0);
    var ws = 0.0;
    for (var i = 0u; i < count; i++) {
        let d = p - cam.volume[i].xyz;
        let dist = length(d);
        if dist <= 1e-6 {
            continue;
        }
        let dir = d / dist;
        let bt = cube_texel(dir, BIN_FACE);
        let bin = cam.volume_range[i].y + (bt.z * BIN_FACE + bt.y) * BIN_FACE + bt.x;
        let first = cam.volume_range[i].x;
        let view_w = cam.volume[i].w;
        for (var j = volume_bins[bin]; j < volume_bins[bin + 1u]; j++) {
            let s = 3u * (first + j);
            let c = volume_samples[s + 2u];
            if c.y != object {
                continue;
            }
            let dt = abs(bitcast<f32>(c.x) - t);
            if dt > eps {
                continue;
            }
            let b = bitcast<vec4<f32>>(volume_samples[s + 1u]);
            if abs(b.w - dist) > tol * dist {
                continue;
            }
            let a = bitcast<vec4<f32>>(volume_samples[s]);
            let angle = acos(clamp(dot(a.xyz, dir), -1.0, 1.0));
            let r = max(a.w, half_bin);
            if angle < r {
                let w = (1.0 - dt / eps) * max(1.0 - angle / r, 1e-3) * view_w;
                var value = b.rgb;
                if lit() {
                    value = shaded(c.zw);
                }
                sum += value * w;
                ws += w;
            }
        }
    }
    return vec4<f32>(sum, ws);
}

// Direct lookups, else the temporal-volume fallback: (radiance, 1) or (0, 0) for a hole.
fn reconstruct(p: vec3<f32>, eye: vec3<f32>, object: u32) -> vec4<f32> {
    let direct = direct_lookups(p, eye, object);
    if direct.w > 0.0 {
        return vec4<f32>(direct.rgb / direct.w, 1.0);
    }
    let volume = volume_lookups(p, object);
    if volume.w > 0.0 {
        return vec4<f32>(volume.rgb / volume.w, 1.0);
    }
    return vec4<f32>(0.0);
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

// The image-mode frame's texel of the fragment's pixel.
fn image_frame_texel(position: vec2<f32>) -> vec4<f32> {
    let size = textureDimensions(image_frame);
    let uv = (position - view.viewport.xy) / view.viewport.zw;
    let p = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
    return vec4<f32>(textureLoad(image_frame, p, 0).rgb, 1.0);
}

// The reconstructed radiance, times the camera's exposure as Bevy's own lights are
// (`view.exposure`, from its `Exposure`), kept inside the f16 HDR target's range; tonemapped
// here for cameras without an HDR target, as Bevy's PBR does (HDR cameras are tonemapped by
// Bevy's post-process pass).
#ifdef PLENOPTIC_STANDARD
// An app mesh: its own StandardMaterial's base colour, metalness, roughness and normal (its
// textures and normal map, as Bevy's PBR reads them) with the pack's lighting at this
// object's points, exactly as a proxy fragment of the same object is shaded.
@fragment
fn fragment(vertex: VertexOutput, @builtin(front_facing) is_front: bool) -> @location(0) vec4<f32> {
    local_from_world = get_local_from_world(vertex.instance_index);
    let ng = cross(dpdx(vertex.world_position.xyz), dpdy(vertex.world_position.xyz));
    var pbr = pbr_input_from_standard_material(vertex, is_front);
    pbr.material.base_color = alpha_discard(pbr.material, pbr.material.base_color);
    pixel_base = pbr.material.base_color.rgb;
    pixel_metallic = clamp(pbr.material.metallic, 0.0, 1.0);
    pixel_roughness = clamp(pbr.material.perceptual_roughness, 0.0, 1.0);
    pixel_albedo = pixel_base * ((1.0 - pixel_metallic) * (1.0 - params.material.x));
    var in = vertex;
    // The shading normal, normal-mapped (viewer() turns it towards the eye where needed).
    in.world_normal = pbr.N;
    return shade(in, ng);
}
#else
@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    local_from_world = get_local_from_world(in.instance_index);
    // The triangle's plane, before any non-uniform branch.
    let ng = cross(dpdx(in.world_position.xyz), dpdy(in.world_position.xyz));
    // The material's albedo at the pixel (derivatives are taken before any non-uniform
    // branch). Without UVs the smallest level: the texture's mean, as on the CPU.
    var v = in;
#ifdef VERTEX_UVS_A
    let duv = abs(determinant(mat2x2<f32>(dpdx(in.uv), dpdy(in.uv))));
    pixel_albedo = material_albedo(in.uv, sqrt(duv));
    pixel_emission = material_emission(in, in.uv, sqrt(duv));
#ifdef VERTEX_TANGENTS
    v.world_normal = bent_normal(normalize(in.world_normal), in.world_tangent, in.uv, sqrt(duv));
#endif
#else
    pixel_albedo = material_albedo(vec2<f32>(0.0), 1e9);
    pixel_emission = material_emission(in, vec2<f32>(0.0), 1e9);
#endif
    return shade(v, ng);
}
#endif

// The fragment's output, once the private pixel_* values are set: its reflection, radiance
// and sun light, times the exposure.
fn shade(in: VertexOutput, ng: vec3<f32>) -> vec4<f32> {
    var reflected = vec3<f32>(0.0);
    if lit() && cam.fill.z != 1.0 && marched() {
        let r = reflection(in, ng);
        if r.w > 0.0 {
            non_diffuse_weight = 0.0;
            reflected = pixel_emission + r.rgb;
        }
    }
    // Pack 4 leaves the emission to the runtime: where no marched reflection carries it.
    if lit() && cam.fill.z != 1.0 && params.emission.y == 1.0 && non_diffuse_weight != 0.0
        && !see_through() {
        reflected += pixel_emission;
    }
    var c: vec4<f32>;
    if see_through() {
        // Transmissive glass: its reflection alone (none where no lookup answers; the baked
        // radiance holds what it lets through), what lies behind blended in by the
        // premultiplied alpha below.
        c = vec4<f32>(reflected, 1.0);
    } else {
        c = radiance(in, ng);
        c = vec4<f32>(c.rgb + reflected, c.a);
    }
    if lit() && cam.sun.w == 1.0 && cam.fill.z != 1.0 {
        c = vec4<f32>(c.rgb + sun_light(in, ng), c.a);
    }
    // Glazing (fill.w < 1) is blended over what lies behind it with its coverage in
    // geometry-assisted mode; the image-mode frame already holds what is behind.
    let glazing = params.object.z > 0.0 && params.object.z < 1.0 && cam.fill.z != 1.0;
    var alpha = select(c.a, params.object.z, glazing);
    if see_through() {
        alpha = 1.0 - params.glass.y;
    }
    var out = vec4<f32>(min(c.rgb * view.exposure, vec3<f32>(65504.0)), alpha);
#ifdef TONEMAP_IN_SHADER
    out = tone_mapping(out, view.color_grading);
#endif
    return out;
}

// The reconstructed radiance of the fragment (linear, before exposure).
// `ng_raw`: the triangle's plane from the position's derivatives (taken by the caller).
fn radiance(in: VertexOutput, ng_raw: vec3<f32>) -> vec4<f32> {
    let object = u32(params.object.x);
    let n = u32(cam.header.y);
    let p = in.world_position.xyz;
    let eye = view.world_position;
    // The surface plane.
    var nrm = ng_raw;
    if dot(nrm, nrm) < 1e-20 {
        nrm = in.world_normal;
    }
    nrm = normalize(nrm);
    if cam.fill.z == 1.0 {
        return image_frame_texel(in.position.xy);
    }
    let own = reconstruct(p, eye, object);
    if own.w > 0.0 {
        return vec4<f32>(own.rgb, 1.0);
    }
    // Same-object hole fill (plenoptic_recon's ring search): the nearest ring of pixels around
    // this one whose points (neighbour_point) have a direct or volume lookup of this object;
    // their mean.
    let radius = i32(cam.fill.x);
    let centre = in.position.xy;
    for (var r = 1; r <= radius; r++) {
        var sum = vec3<f32>(0.0);
        var count = 0.0;
        for (var dy = -r; dy <= r; dy++) {
            // Whole rows at the ring's top and bottom, the two ends elsewhere.
            let step = select(2 * r, 1, abs(dy) == r);
            for (var dx = -r; dx <= r; dx += step) {
                let c = centre + vec2<f32>(f32(dx), f32(dy));
                if any(c < view.viewport.xy) || any(c >= view.viewport.xy + view.viewport.zw) {
                    continue;
                }
                // Glazing is not in the depth prepass (Bevy's transparent pass): its ring
                // pixels are found on its plane, panes being flat.
                var q: vec4<f32>;
                if params.object.z > 0.0 && params.object.z < 1.0 {
                    q = pixel_on_plane(c, p, nrm);
                } else {
                    q = neighbour_point(c, p, nrm);
                }
                if q.w == 0.0 {
                    continue;
                }
                let got = reconstruct(q.xyz, eye, object);
                if got.w > 0.0 {
                    sum += got.rgb;
                    count += 1.0;
                }
            }
        }
        if count > 0.0 {
            return vec4<f32>(sum / count, 1.0);
        }
    }
    // A thin object no texel centre met where the lookups fell: its own nearest texels, else
    // those of the surface around it at its distance.
    let near = neighbour_texels(p, object);
    if near.w > 0.0 {
        return vec4<f32>(near.rgb / near.w, 1.0);
    }
    // Nothing: the heaviest key's texel in the point's direction ("background").
    let h = u32(cam.fill.y);
    if h < min(u32(cam.header.x), MAX_LOOKUPS) {
        let t = cube_texel(p - cam.base[h].xyz, n);
        let layer0 = u32(cam.base[h].w);
        let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), layer0 + t.z, 0);
        return vec4<f32>(colour(t, layer0, texel), 1.0);
    }
    return vec4<f32>(0.0, 0.0, 0.0, 1.0);
}

// ---- The runtime sun (pack 3; plenoptic_recon's sun and brdf modules, the same formulas) ----

const PI: f32 = 3.14159265358979;

fn fresnel_dielectric(cos_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}

fn fresnel_schlick(f0: vec3<f32>, cos: f32) -> vec3<f32> {
    let m = pow(1.0 - clamp(cos, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

fn ggx_d(alpha: f32, cos_h: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

fn smith_g1(alpha: f32, cos: f32) -> f32 {
    let c = abs(cos);
    let a2 = alpha * alpha;
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

// The BSDF for light from `wi` seen along `wo`, with shading normal `n` and geometric normal
// `ng` (both on wo's side), relative IOR `eta`; the fragment's material.
fn sun_bsdf(wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, eta: f32) -> vec3<f32> {
    let cos_i = dot(wi, n);
    let reflect = cos_i > 0.0;
    if reflect != (dot(wi, ng) > 0.0) {
        return vec3<f32>(0.0);
    }
    let cos_o = dot(wo, n);
    let m = pixel_metallic;
    let tr = params.material.x;
    let alpha = max(pixel_roughness * pixel_roughness, 1e-4);
    let delta = pixel_roughness < 0.02;
    if reflect {
        let h = normalize(wo + wi);
        let voh = clamp(dot(wo, h), 0.0, 1.0);
        let fd = fresnel_dielectric(voh, eta);
        let f = pixel_base * ((1.0 - m) * (1.0 - tr) * (1.0 - fd) / PI);
        if delta {
            return f;
        }
        return f + glossy_bsdf(wi, wo, n, ng, alpha, eta);
    }
    if delta || tr <= 0.0 || m >= 1.0 {
        return vec3<f32>(0.0);
    }
    var h = normalize(wo + wi * eta);
    if dot(h, n) < 0.0 {
        h = -h;
    }
    let woh = dot(wo, h);
    let wih = dot(wi, h);
    if woh * wih >= 0.0 {
        return vec3<f32>(0.0);
    }
    let denom = (wih + woh / eta) * (wih + woh / eta);
    let fd = fresnel_dielectric(abs(woh), eta);
    let d = ggx_d(alpha, dot(h, n));
    let g = smith_g1(alpha, cos_o) * smith_g1(alpha, cos_i);
    let ft = d * (1.0 - fd) * g * abs(wih * woh / (cos_i * cos_o * denom)) / (eta * eta);
    return pixel_base * ((1.0 - m) * tr * ft);
}

// The sun's direct light towards the eye: BSDF × illuminance × cosine × the shadow of the
// plugin's sun light (Bevy's cascaded shadow map of the proxies). `ng_raw`: the triangle's
// plane from the position's derivatives.
// The shading frame of a fragment seen from the eye: the shading normal `n` and geometric
// normal `ng` on the viewer's side (n bent towards the viewer where it faces away, as
// plenoptic_recon's Bsdf::new), the direction `wo` towards the eye and the relative IOR.
struct Viewer {
    n: vec3<f32>,
    ng: vec3<f32>,
    wo: vec3<f32>,
    eta: f32,
}

fn viewer(in: VertexOutput, ng_raw: vec3<f32>) -> Viewer {
    let p = in.world_position.xyz;
    let wo = normalize(view.world_position - p);
    var ns = normalize(in.world_normal);
    var ng = ns;
    if dot(ng_raw, ng_raw) > 1e-20 {
        ng = normalize(ng_raw);
        // The winding's side: the vertex normals follow it.
        if dot(ng, ns) < 0.0 {
            ng = -ng;
        }
    }
    let front = dot(wo, ng) > 0.0;
    let side = select(-1.0, 1.0, dot(wo, ng) >= 0.0);
    ng = ng * side;
    var n = ns * side;
    if dot(n, wo) < 1e-4 {
        n = n - wo * (dot(n, wo) - 1e-4);
        n = select(ng, normalize(n), dot(n, n) > 0.0);
    }
    let ior = select(1.5, params.surface.y, params.surface.y > 0.0);
    return Viewer(n, ng, wo, select(1.0 / ior, ior, front));
}

fn sun_light(in: VertexOutput, ng_raw: vec3<f32>) -> vec3<f32> {
    let v = viewer(in, ng_raw);
    let n = v.n;
    let ng = v.ng;
    let wo = v.wo;
    let eta = v.eta;
    // Surfaces whose every lobe is ideal take no light sample (as the tracer).
    let fd = fresnel_dielectric(clamp(dot(wo, n), 1e-4, 1.0), eta);
    let lum = dot(pixel_base, vec3<f32>(0.2126, 0.7152, 0.0722));
    let diffuse = (1.0 - pixel_metallic) * (1.0 - params.material.x) * (1.0 - fd) * max(lum, 0.0) > 0.0;
    if !diffuse && pixel_roughness < 0.02 {
        return vec3<f32>(0.0);
    }
    let wi = normalize(cam.sun.xyz);
    let f = sun_bsdf(wi, wo, n, ng, eta);
    if all(f == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    // The plugin's sun light: the directional light aimed along the same direction.
    var shadow = 1.0;
    for (var i = 0u; i < lights.n_directional_lights; i++) {
        let l = &lights.directional_lights[i];
        if dot((*l).direction_to_light, wi) > 0.99999 {
            let view_z = dot(vec4<f32>(
                view.view_from_world[0].z,
                view.view_from_world[1].z,
                view.view_from_world[2].z,
                view.view_from_world[3].z
            ), in.world_position);
            let towards = select(-ng, ng, dot(wi, ng) >= 0.0);
            shadow = fetch_directional_shadow(i, in.world_position, towards, view_z, in.position.xy);
            break;
        }
    }
    return f * cam.sun_illuminance.xyz * abs(dot(wi, n)) * shadow;
}

// ---- Reflections for the camera (plenoptic_recon's specular module, the same formulas) ----

// Whether this fragment's surface is marched: no transmission, an ideal mirror, or glossy
// up to the roughest surface marched.
fn marched() -> bool {
    return cam.specular.x == 1.0 && (params.material.x <= 0.0 || see_through())
        && (pixel_roughness < 0.02 || pixel_roughness <= cam.specular.y);
}

// Whether this fragment is see-through transmissive glass (flags.z).
fn see_through() -> bool {
    return params.glass.x == 1.0 && cam.fill.z != 1.0;
}

// Radiance arriving at `origin` along unit `dir`, over a cone of half-angle `cone`, from the
// lookups' keys: (radiance, 1), or (0, 0) where no lookup can tell.
fn incoming(origin: vec3<f32>, dir: vec3<f32>, cone: f32) -> vec4<f32> {
    // A ray that meets no proxy has left the scene (plenoptic_recon::specular's escape
    // test, cast off the surface it starts on).
    if has_rays() && !occluded(origin + dir * RAY_OFFSET, dir, cam.specular.z) {
        return vec4<f32>(environment(cam.env, env_image, dir), 1.0);
    }
    let count = min(u32(cam.header.x), MAX_LOOKUPS);
    let n = u32(cam.header.y);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    var escaped = false;
    for (var k = 0u; k < count; k++) {
        if cam.weight[k].x <= 0.0 {
            continue;
        }
        let centre = cam.base[k].xyz;
        let layer0 = u32(cam.base[k].w);
        let m = march(cubes, layer0, n, centre, origin, dir, cam.specular.z, cam.tuning.x);
        if m.y == 1.0 {
            let to = origin + dir * m.x - centre;
            let d = length(to);
            let cos = dot(to, dir) / max(d, 1e-6);
            let w = cam.weight[k].x * pow(max((1.0 + cos) * 0.5, 1e-3), cam.tuning.y);
            let angle = min(cone * m.x / max(d, 1e-3), 0.5);
            sum += fetch(cubes, layer0, n, to, angle) * w;
            total += w;
        } else if m.y == 2.0 {
            escaped = true;
        }
    }
    if total > 0.0 {
        return vec4<f32>(sum / total, 1.0);
    }
    if escaped {
        return vec4<f32>(environment(cam.env, env_image, dir), 1.0);
    }
    return vec4<f32>(0.0);
}

// The radiance the glossy lobe (roughness `alpha`, the fragment's material) reflects
// towards `wo` around `n` (geometric normal `ng`, relative IOR `eta`): cam.specular.w
// directions reflected about GGX half-vectors, a Hammersley set turned by `turn`, each
// weighted by F · G · (ω_o·h) / ((n·ω_o)(n·h)) (plenoptic_recon's Bsdf::glossy_weight).
fn lobe(origin: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, alpha: f32, eta: f32, turn: f32) -> vec4<f32> {
    let pair = orthonormal_pair(n);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    let rays = u32(cam.specular.w);
    for (var k = 0u; k < rays; k++) {
        let u1 = (f32(k) + 0.5) / f32(rays);
        let u2 = fract(f32(reverseBits(k)) / 4294967296.0 + turn);
        let tan2 = alpha * alpha * u1 / (1.0 - u1);
        let cos_h = 1.0 / sqrt(1.0 + tan2);
        let sin_h = sqrt(max(1.0 - cos_h * cos_h, 0.0));
        let phi = 6.28318530717959 * u2;
        let h = n * cos_h + (pair[0] * cos(phi) + pair[1] * sin(phi)) * sin_h;
        let wi = h * (2.0 * dot(wo, h)) - wo;
        let w = glossy_weight(h, wi, wo, n, ng, alpha, eta);
        if all(w == vec3<f32>(0.0)) {
            // Below the surface: no light, but the lobe's share all the same.
            count += 1.0;
            continue;
        }
        let l = incoming(origin, wi, 0.7 * alpha);
        if l.w > 0.0 {
            sum += l.rgb * w;
            count += 1.0;
        }
    }
    if count > 0.0 {
        return vec4<f32>(sum / count, 1.0);
    }
    return vec4<f32>(0.0);
}

// plenoptic_recon's Bsdf::glossy_weight for the fragment's material.
fn glossy_weight(h: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    let cos_o = dot(wo, n);
    let cos_i = dot(wi, n);
    let cos_h = dot(h, n);
    if cos_i <= 0.0 || cos_h <= 0.0 || dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let voh = clamp(dot(wo, h), 0.0, 1.0);
    let g = smith_g1(alpha, cos_o) * smith_g1(alpha, cos_i);
    return glossy_fresnel(voh, eta) * (g * voh / max(cos_o * cos_h, 1e-8));
}

// The glossy lobe's Fresnel term at ω_o·h (plenoptic_recon's Bsdf::glossy_fresnel): the exact
// dielectric one for the non-metallic part, Schlick's with the base colour for the metallic.
fn glossy_fresnel(voh: f32, eta: f32) -> vec3<f32> {
    let m = pixel_metallic;
    return vec3<f32>((1.0 - m) * fresnel_dielectric(voh, eta)) + fresnel_schlick(pixel_base, voh) * m;
}

// plenoptic_recon's Bsdf::eval_glossy: the GGX reflection lobe alone.
fn glossy_bsdf(wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    let cos_i = dot(wi, n);
    if cos_i <= 0.0 || dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let voh = clamp(dot(wo, h), 0.0, 1.0);
    let d = ggx_d(alpha, dot(h, n));
    let g = smith_g1(alpha, dot(wo, n)) * smith_g1(alpha, cos_i);
    return glossy_fresnel(voh, eta) * (d * g / max(4.0 * dot(wo, n) * cos_i, 1e-8));
}

// The placed lamps' highlights at `p` (plenoptic_recon's lamps::highlights): the glossy lobe
// × the lamp's irradiance (glTF's spot falloff, nothing beyond its range) × the cosine, each
// shadowed by a ray against the proxies.
fn highlights(p: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let eps = 1e-4 * (1.0 + max(max(abs(p.x), abs(p.y)), abs(p.z)));
    for (var k = 0u; k < u32(cam.flags.y); k++) {
        let a = cam.lamps[3u * k];
        let b = cam.lamps[3u * k + 1u];
        let c = cam.lamps[3u * k + 2u];
        let d = a.xyz - p;
        let dist2 = dot(d, d);
        let dist = sqrt(dist2);
        if dist <= 0.0 || (a.w > 0.0 && dist > a.w) {
            continue;
        }
        let wi = d / dist;
        var value = c.xyz / dist2;
        if b.w > -1.5 {
            let att = clamp((dot(b.xyz, -wi) - b.w) * c.w, 0.0, 1.0);
            value *= att * att;
        }
        if all(value == vec3<f32>(0.0)) {
            continue;
        }
        let f = glossy_bsdf(wi, wo, n, ng, alpha, eta);
        if all(f == vec3<f32>(0.0)) {
            continue;
        }
        let origin = p + select(-ng, ng, dot(wi, ng) >= 0.0) * eps;
        if has_rays() && occluded(origin, wi, dist - 2.0 * eps) {
            continue;
        }
        sum += f * value * abs(dot(wi, n));
    }
    return sum;
}

// An ideal mirror's reflectance at n·ω_o = `cos_in` (plenoptic_recon's specular::reflectance):
// the exact Fresnel.
fn reflectance(cos_in: f32, eta: f32) -> vec3<f32> {
    let cos_o = clamp(cos_in, 1e-4, 1.0);
    let m = pixel_metallic;
    return vec3<f32>((1.0 - m) * fresnel_dielectric(cos_o, eta))
        + fresnel_schlick(pixel_base, cos_o) * m;
}

// The reflection at this fragment for the camera: (emission-free specular radiance, 1), or
// (0, 0) where no lookup answers.
fn reflection(in: VertexOutput, ng_raw: vec3<f32>) -> vec4<f32> {
    let v = viewer(in, ng_raw);
    let cos_o = dot(v.wo, v.n);
    let origin = in.world_position.xyz;
    var l: vec4<f32>;
    if pixel_roughness < 0.02 {
        let dir = normalize(v.n * (2.0 * cos_o) - v.wo);
        l = incoming(origin, dir, 0.0);
    } else {
        // The pixel's index in the frame, as the CPU's per-pixel turn.
        let px = vec2<u32>(in.position.xy - view.viewport.xy);
        let j = px.y * u32(view.viewport.z) + px.x;
        let turn = fract(f32(j) * 0.618034);
        let alpha = max(pixel_roughness * pixel_roughness, 1e-4);
        l = lobe(origin, v.n, v.ng, v.wo, alpha, v.eta, turn);
        if l.w == 0.0 {
            return l;
        }
        return vec4<f32>(l.rgb + highlights(origin, v.n, v.ng, v.wo, alpha, v.eta), 1.0);
    }
    if l.w == 0.0 {
        return l;
    }
    return vec4<f32>(reflectance(cos_o, v.eta) * l.rgb, 1.0);
}
