// What the geometry-assisted fragment shader (geometry.wgsl; thesis §8.2.3) reads and keeps:
// the camera's view buffer and the material's uniform (view.rs's ViewParams, mod.rs's
// ObjectParams), the material's bindings (those of a lit app mesh's extension with
// PLENOPTIC_STANDARD), the lookup limits, and the fragment's private state: its material at
// the pixel, set once per fragment before any lookup.
#define_import_path plenoptic::geometry::bindings

#import plenoptic::environment::Environment
#import plenoptic::fill_entry::HoleList
#import plenoptic::relight::LightLayer

const MAX_LOOKUPS: u32 = 16u;
const MAX_VOLUMES: u32 = 8u;
// Face size of the volume samples' direction bins (plenoptic_recon's VolumeIndex).
const BIN_FACE: u32 = 16u;
// Key pairs blended at most (blend.rs, MAX_PAIRS).
const MAX_PAIRS: u32 = 8u;
// The id of a blended texel that changes between its pair's two keys.
const PAIR_CHANGING: u32 = 0xffffffffu;

// Bits of ViewParams.flags (view.rs, ViewFlags).
// Accepted lookups filtered seamlessly bilinear (ReconSettings::cube_filter).
const VIEW_BILINEAR: u32 = 1u;
// The image-mode frame is shown instead of the lookups.
const VIEW_IMAGE_MODE: u32 = 2u;
// The pack has a runtime sun (pack 3).
const VIEW_SUN: u32 = 4u;
// Reflections are marched for the camera.
const VIEW_MARCHED: u32 = 8u;
// Holes of the opaque pass are filled by the screen-space fill kernel (screen_fill.rs).
const VIEW_SCREEN_FILL: u32 = 16u;
// The camera reads its relit keys (reconstruct/relight.rs): lookup k's key at layers 6k.
const VIEW_RELIT: u32 = 32u;
// The opaque fragments leave their lookups to the lookup kernel (screen_fill.wgsl).
const VIEW_LOOKUP_KERNEL: u32 = 64u;
// With it, materials' lighting is looked up at the anchors and interpolated (screen_fill.wgsl).
const VIEW_SPARSE_LIGHTING: u32 = 128u;
// The pack leaves its lamps' direct diffuse light to the runtime (pack 5.0; lamps.wgsl).
const VIEW_LAMPS: u32 = 256u;

// A placed lamp (view.rs, LampParams; plenoptic_recon's lamps::RuntimeLamp).
struct Lamp {
    // Position (metres) and range (−1: none).
    position: vec3<f32>,
    range: f32,
    // A spot light's axis and the cosine of its outer cone (−2: a point light).
    axis: vec3<f32>,
    cos_outer: f32,
    // Colour × intensity, scaled by its light group; 1 / (cos inner − cos outer) of a spot.
    radiant: vec3<f32>,
    cone_scale: f32,
}

// One lookup: a base view's key (view.rs, LookupParams).
struct Lookup {
    // The base view's position; the view's weight × the key's time weight.
    base: vec3<f32>,
    weight: f32,
    // Its first array layer in the camera's keys (6 per lookup); with light groups, its
    // key's first layer in the pack's key texture (relight_keys.wgsl), and first_layer is
    // then 6k, its layers in the camera's relit keys.
    first_layer: u32,
    source_layer: u32,
    // 1 + its pair where it is the first key of a blended pair (0: none); whether the key
    // has normals (1) or not (0).
    pair: u32,
    normals: u32,
}

// A base view's temporal-volume block (view.rs, VolumeParams).
struct VolumeBlock {
    // The base view's position and weight.
    base: vec3<f32>,
    weight: f32,
    // Its first sample and first direction-bin offset in the pack's buffers.
    first_sample: u32,
    first_bin: u32,
}

// A camera's view buffer (view.rs, ViewParams): its lookups and settings this frame.
struct ViewParams {
    // Lookups in use, the keys' face size, volume blocks in use, VIEW_* bits.
    lookup_count: u32,
    face: u32,
    volume_count: u32,
    flags: u32,
    // The same-surface test's relative depth tolerance; the angular power p.
    depth_tolerance: f32,
    angular_power: f32,
    // The camera's time t and the volume samples' temporal window tε.
    time: f32,
    time_window: f32,
    // Hole-fill radius (pixels); the heaviest lookup (≥ lookup_count: none).
    fill_radius: u32,
    heaviest: u32,
    // Lamps in use; rays per glossy pixel (plenoptic_recon's GLOSSY_RAYS).
    lamp_count: u32,
    glossy_rays: u32,
    // The roughest glossy surface marched (−1: ideal mirrors only); how far rays are marched.
    glossy_roughness: f32,
    march_distance: f32,
    // Key pairs blended this frame (blend.rs).
    pair_count: u32,
    // The runtime sun: direction towards it (xyz), with VIEW_SUN.
    sun: vec4<f32>,
    // Its illuminance at the camera's time (xyz).
    sun_illuminance: vec4<f32>,
    // The placed lamps (plenoptic_recon's lamps module); lamp_count of them in use.
    lamps: array<Lamp, 4>,
    // The lookups in use (lookup_count of them).
    lookups: array<Lookup, 16>,
    // Per blended pair: its two lookups (x, y); its layers in the blended keys are 6 × pair.
    pairs: array<vec4<u32>, 8>,
    // The volume blocks in use (volume_count of them).
    volumes: array<VolumeBlock, 8>,
    // Light groups (reconstruct/relight.rs): groups stored per key and volume sample (0: the
    // camera reads the pack's keys as stored); layers blended (of light_layers); the first
    // vec4 of the volume samples' group words in volume_samples.
    light_groups: u32,
    light_layer_count: u32,
    volume_groups: u32,
    // The blend's weight of the total (xyz); the sky's multiplier (xyz).
    light_base: vec4<f32>,
    light_sky: vec4<f32>,
    // The layers blended (light_layer_count of them).
    light_layers: array<LightLayer, 16>,
    // The pack's environment at the camera's time, for reflected rays that leave the scene
    // (not named `environment`: naga_oil would take the field for the imported function).
    env: Environment,
    // M_o(τ) per animated object (its motion slot) and lookup: entry slot · 16 + k.
    motion: array<mat4x4<f32>>,
}

// Bits of ObjectParams.flags (mod.rs, ObjectFlags).
// Shaded as albedo · lighting + non-diffuse (pack 2.0, Shading::Materials).
const OBJECT_MATERIALS: u32 = 1u;
// See-through transmissive glass: its reflection over what lies behind.
const OBJECT_SEE_THROUGH: u32 = 2u;
// Drawn in the opaque pass (its holes may be left to the screen-space fill).
const OBJECT_OPAQUE_PASS: u32 = 4u;
// The pack leaves the emission to the runtime: every lit fragment adds it.
const OBJECT_RUNTIME_EMISSION: u32 = 8u;
// The material is double-sided (else it emits from its front only).
const OBJECT_DOUBLE_SIDED: u32 = 16u;

// A material's uniform (mod.rs, ObjectParams): its object and material.
struct ObjectParams {
    // The object's id.
    id: u32,
    // Its motion slot (ViewParams.motion; −1: static, in world space).
    motion_slot: i32,
    // Its coverage: its output alpha as glazing in geometry-assisted mode (1: opaque).
    coverage: f32,
    // OBJECT_* bits.
    flags: u32,
    // See-through glass's mean transmittance per surface.
    transmittance: f32,
    // The material's transmission, roughness, IOR (the runtime sun's BSDF) and normal scale.
    transmission: f32,
    roughness: f32,
    ior: f32,
    normal_scale: f32,
    // The largest side of each texture (0: none).
    base_colour_size: f32,
    metallic_roughness_size: f32,
    normal_map_size: f32,
    emissive_size: f32,
    // The object's base-colour factor (xyz) and metallic factor (w) with OBJECT_MATERIALS.
    albedo: vec4<f32>,
    // KHR_texture_transform of the base-colour, metallic-roughness and normal textures:
    // offset (xy), scale (zw).
    base_uv: vec4<f32>,
    mr_uv: vec4<f32>,
    normal_uv: vec4<f32>,
    // The rotations of the base-colour, metallic-roughness, normal and emissive transforms.
    uv_rotation: vec4<f32>,
    // The material's emissive factor (xyz).
    emissive: vec4<f32>,
    // The emissive texture's transform: offset (xy), scale (zw).
    emissive_uv: vec4<f32>,
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
@group(#{MATERIAL_BIND_GROUP}) @binding(115) var cube_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(110) var<storage, read> cam: ViewParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(111) var env_image: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(116) var<storage, read_write> fill_entries: array<vec4<u32>>;
@group(#{MATERIAL_BIND_GROUP}) @binding(117) var<storage, read_write> hole_list: HoleList;
@group(#{MATERIAL_BIND_GROUP}) @binding(118) var blended_geometry: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(119) var blended_terms: texture_2d_array<u32>;
#else
@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> params: ObjectParams;
// Three words per sample: (direction.xyz, radius), (radiance.rgb, distance), (t, object,
// lighting RGB9E5, non-diffuse RGB9E5).
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var<storage, read> volume_samples: array<vec4<u32>>;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var<storage, read> volume_bins: array<u32>;
// The image-mode frame (image.wgsl), shown with VIEW_IMAGE_MODE.
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var image_frame: texture_2d<f32>;
// Per texel of the key texture: (lighting RGB9E5, non-diffuse RGB9E5).
@group(#{MATERIAL_BIND_GROUP}) @binding(5) var shading_cubes: texture_2d_array<u32>;
// A nearest sampler for gathering the key textures' footprints (lookup.wgsl).
@group(#{MATERIAL_BIND_GROUP}) @binding(19) var cube_sampler: sampler;

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
// The camera's screen-fill entries (fill_entry.wgsl), one per viewport pixel, written with
// VIEW_SCREEN_FILL.
@group(#{MATERIAL_BIND_GROUP}) @binding(20) var<storage, read_write> fill_entries: array<vec4<u32>>;
// Its hole list (fill_entry.wgsl): the holes left to the fill kernel.
@group(#{MATERIAL_BIND_GROUP}) @binding(21) var<storage, read_write> hole_list: HoleList;
// The camera's blended keys (blend.rs): per pair and face, the first key's id, distance and
// normal (PAIR_CHANGING where the keys differ); the pair's blended terms (pack_pair).
@group(#{MATERIAL_BIND_GROUP}) @binding(22) var blended_geometry: texture_2d_array<u32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(23) var blended_terms: texture_2d_array<u32>;
#endif

// The point the lookups reconstruct: its object's motion slot (−1: static) and whether the
// object is shaded from its material. Set from the material's uniform by a fragment
// (geometry.wgsl), from a record by the lookup kernel (screen_fill.wgsl).
var<private> point_slot: i32 = -1;
var<private> point_material: bool = false;
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
// The fragment's surface normal facing the eye, in the frame its points are looked up from
// (the object's own for an animated one, as object_point): the lookups' face test
// (lookup.wgsl's same_face). Zero: no face test.
var<private> face_normal: vec3<f32>;
// The same normal in the world, where the temporal volume's samples keep theirs: their face
// test (lookup.wgsl's volume_lookups). Zero: no face test.
var<private> world_face_normal: vec3<f32>;

// Whether the camera's flags have `bit` (VIEW_*).
fn view_has(bit: u32) -> bool {
    return (cam.flags & bit) != 0u;
}

// Whether the image-mode frame is shown instead of the lookups.
fn image_mode() -> bool {
    return view_has(VIEW_IMAGE_MODE);
}

// Whether this object's flags have `bit` (OBJECT_*).
fn object_has(bit: u32) -> bool {
    return (params.flags & bit) != 0u;
}

// Whether this object is shaded from its material (albedo · lighting + non-diffuse).
fn lit() -> bool {
    return object_has(OBJECT_MATERIALS);
}

// Whether this object is glazing: partly covering, blended over what lies behind it.
fn glazing() -> bool {
    return params.coverage > 0.0 && params.coverage < 1.0;
}
