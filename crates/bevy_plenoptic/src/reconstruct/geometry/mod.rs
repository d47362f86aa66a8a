//! GPU geometry-assisted reconstruction (thesis §8.2.3).
//!
//! Every proxy mesh is drawn with a [`PlenopticMaterial`] whose fragment shader
//! (`geometry.wgsl`, beside this file) shades it, and whose points are looked up as in
//! `plenoptic_recon`'s geometry mode, by the fragment itself or, on a camera with the
//! screen-space fill, by the lookup kernel ([`lookup_kernel`]) over the fragments' records:
//! for each resident (base view, bracketing time key) the fragment's point is carried along
//! its object's motion, `p_τ = M_o(τ) M_o(t)⁻¹ p`, looked up in that key's cube (the nearest
//! texel, or seamlessly bilinear over the texels of the same object and distance with the
//! camera's `CubeFilter::Bilinear`, as on the CPU), accepted if the cube saw the same object at the same distance, and blended with
//! weight `w_view · w_time · ((1 + cos θ)/2)^p`. The result, times the camera's exposure
//! (`view.exposure`, as Bevy's lights), is written unlit into the camera's HDR target; depth
//! comes from the rasterised proxy mesh.
//!
//! Where no lookup is accepted, the same fallbacks as `plenoptic_recon`, in its order:
//! 1. the temporal volumes ([`volume`]): samples of the object near the point's direction
//!    from each base view, within `t ± tε`;
//! 2. the same-object hole fill: the nearest ring of pixels (radius up to
//!    [`ReconSettings::hole_fill_radius`]) whose points have a direct or volume lookup of this
//!    object, their mean. On a camera with the screen-space fill ([`screen_fill`]: a device
//!    that forces early depth tests) a compute pass after the opaque
//!    pass reads the ring from what the fragments wrote. Elsewhere a fragment cannot read its
//!    neighbours' results, so it recomputes them at the points the neighbouring pixels show,
//!    read from the depth prepass ([`PlenopticCamera`] requires one); a lookup accepted there
//!    means the neighbour shows this object, as the CPU's mask test does. Without a prepass (a
//!    camera that removed it) each ring pixel's ray is intersected with the fragment's surface
//!    plane instead, exact on planar faces only;
//! 3. the object's nearest texels around its lookups (thin objects);
//! 4. the heaviest key's texel in the point's direction ("background").
//!
//! See-through glazing (objects with a pack coverage c < 1: glass exported as `alphaMode:
//! BLEND`) is drawn in Bevy's transparent pass with alpha c over what lies behind it, the
//! environment included, as `plenoptic_recon`'s glazing module composites it; its hole fill
//! finds ring pixels on its plane (it is not in the depth prepass). Pixels no proxy covers
//! show the camera's background ([`super::background`]).
//!
//! What a camera looks up this frame is in its view buffer ([`view`]), which all its
//! materials bind; a material's own uniform holds its object ([`ObjectParams`]). Every
//! plenoptic camera has its own proxies and materials on its own render layer
//! ([`crate::camera::layers`]): any number of cameras, each with its own pack, time and mode,
//! render in one app.
//!
//! - `mod.rs`: the material and the plugin; `geometry.wgsl`: its fragment shader, whose
//!   libraries beside it (`plenoptic::geometry::*`) are `bindings.wgsl` (the bindings and
//!   the fragment's state), `material.wgsl` (albedo, textures, normal map), `lookup.wgsl`
//!   (the lookups and the volume fallback), `fill.wgsl` (the hole fill and the fallbacks
//!   after it), `bsdf.wgsl`, `sun.wgsl` (the runtime sun), `lamps.wgsl` (the placed lamps'
//!   light) and `specular.wgsl` (reflections for the camera); [`prepare`]: the main-world systems that attach
//!   materials to proxies and keep them bound to their camera; [`view`] and [`frame`]: the
//!   per-view buffer and the lookups it is filled from; [`volume`], [`rays`], [`reflect`],
//!   [`sun`] and [`lamps`]: the volume fallback's buffers, the ray-cast proxies, the
//!   reflection march, the runtime sun and the placed lamps; [`screen_fill`] (`screen_fill.wgsl`, `fill_entry.wgsl`): the
//!   hole-fill kernel, and [`lookup_kernel`] the lookup kernel before it; [`blend`] (`blend.wgsl`): each view's two time keys blended once per
//!   frame where they agree, which a lit object still between the keys' times looks up once.
//!   The material is drawn by Bevy's own mesh passes; the key blend runs before its opaque
//!   pass, the fill kernel between its opaque and transparent passes.
//!
//! On a pack 3 whose lighting leaves the sun to the runtime, lit objects add the sun's direct
//! light per fragment through their BSDF, shadowed by Bevy's shadow map of a directional
//! light the plugin keeps aimed along the pack's sun ([`sun`]). Proxies are drawn with both
//! faces in every pass (the CPU's raster and shadow rays see both).

pub mod blend;
pub mod fill_composite;
pub mod frame;
mod key_pass;
pub mod lamps;
pub mod lookup_kernel;
pub mod prepare;
pub mod rays;
pub mod reflect;
pub mod relight;
pub mod screen_fill;
pub mod sun;
pub mod view;
pub mod volume;

use bevy::asset::embedded_asset;
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, ShaderType};
use bevy::render::storage::ShaderBuffer;
use bevy::shader::ShaderRef;

use super::ReconstructSystems;
use crate::asset::RadiancePack;
#[cfg(doc)]
use crate::camera::{PlenopticCamera, ReconMode, ReconSettings};

/// Geometry-assisted reconstruction on the GPU: the proxy material, its view buffers and
/// fallbacks.
#[derive(Debug, Default)]
pub struct GeometryAssistedPlugin;

impl Plugin for GeometryAssistedPlugin {
    fn finish(&self, app: &mut App) {
        screen_fill::finish(app);
    }

    fn build(&self, app: &mut App) {
        // The reflection march (`plenoptic::reflect`) and the ray cast (`plenoptic::rays`).
        bevy::shader::load_shader_library!(app, "reflect.wgsl");
        bevy::shader::load_shader_library!(app, "rays.wgsl");
        // The fragment shader's libraries (`plenoptic::geometry::*`), imported by its entry
        // file `geometry.wgsl`.
        bevy::shader::load_shader_library!(app, "bindings.wgsl");
        bevy::shader::load_shader_library!(app, "material.wgsl");
        bevy::shader::load_shader_library!(app, "lookup.wgsl");
        bevy::shader::load_shader_library!(app, "fallback.wgsl");
        bevy::shader::load_shader_library!(app, "fill.wgsl");
        bevy::shader::load_shader_library!(app, "bsdf.wgsl");
        bevy::shader::load_shader_library!(app, "sun.wgsl");
        bevy::shader::load_shader_library!(app, "lamps.wgsl");
        bevy::shader::load_shader_library!(app, "specular.wgsl");
        bevy::shader::load_shader_library!(app, "relight.wgsl");
        embedded_asset!(app, "geometry.wgsl");
        screen_fill::build(app);
        blend::build(app);
        relight::build(app);
        app.add_plugins(MaterialPlugin::<PlenopticMaterial>::default())
            .init_resource::<volume::VolumeBuffers>()
            .init_resource::<rays::PackRays>()
            .add_systems(
                Update,
                (
                    (
                        volume::upload_volumes,
                        rays::add_camera_rays,
                        rays::place_rays,
                        view::add_view_buffers,
                        screen_fill::prepare_screen_fill,
                    )
                        .chain()
                        .in_set(ReconstructSystems::Resources),
                    prepare::attach_materials.in_set(ReconstructSystems::Attach),
                    sun::update_suns.in_set(ReconstructSystems::Jobs),
                    (
                        relight::add_relit_keys,
                        view::update_view_buffers,
                        (blend::prepare_blended_keys, relight::update_relit_keys),
                    )
                        .chain()
                        .in_set(ReconstructSystems::Views),
                    prepare::update_materials.in_set(ReconstructSystems::Materials),
                ),
            );
    }
}

/// The proxy material of the GPU path: one instance per proxy object of each camera. Its
/// uniform holds its object's part ([`ObjectParams`]), and it binds its camera's view buffer
/// ([`view::ViewBuffer`]) for the camera's lookups, which every material of the camera
/// shares.
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
#[bind_group_data(GeometryKey)]
pub struct PlenopticMaterial {
    /// Resident keys (see the module doc), with their nearest sampler for gathers.
    #[texture(0, dimension = "2d_array", sample_type = "u_int")]
    #[sampler(19, sampler_type = "non_filtering")]
    pub cubes: Handle<Image>,
    /// The object's id, motion slot, coverage and material.
    #[uniform(1)]
    pub params: ObjectParams,
    /// Resident temporal-volume samples of the pack ([`volume::PackVolumes::samples`]).
    #[storage(2, read_only)]
    pub volume_samples: Handle<ShaderBuffer>,
    /// Their bin offsets ([`volume::PackVolumes::bins`]).
    #[storage(3, read_only)]
    pub volume_bins: Handle<ShaderBuffer>,
    /// The camera's image-mode frame ([`crate::reconstruct::frames::ImageFrame`]), shown
    /// instead of the lookups while the camera is in [`ReconMode::Image`] or
    /// [`ReconMode::Volume`].
    #[texture(4, sample_type = "float", filterable = false)]
    pub image_frame: Handle<Image>,
    /// The resident keys' lighting and non-diffuse radiance
    /// ([`crate::reconstruct::KeyTexture::shading`]).
    #[texture(5, dimension = "2d_array", sample_type = "u_int")]
    pub shading_cubes: Handle<Image>,
    /// The object's base-colour texture from the pack (sRGB; white when it has none).
    #[texture(6)]
    #[sampler(7)]
    pub base_colour_texture: Option<Handle<Image>>,
    /// Its metallic-roughness texture (blue: metallic; white when it has none).
    #[texture(8)]
    #[sampler(9)]
    pub metallic_roughness_texture: Option<Handle<Image>>,
    /// Its normal map (linear; a flat one when it has none).
    #[texture(14)]
    #[sampler(15)]
    pub normal_texture: Option<Handle<Image>>,
    /// Its emissive texture (sRGB; white when it has none).
    #[texture(16)]
    #[sampler(17)]
    pub emissive_texture: Option<Handle<Image>>,
    /// The camera's view buffer ([`view::ViewBuffer`]): its lookups, tunables, sun,
    /// environment and the animated objects' motion this frame.
    #[storage(10, read_only)]
    pub view: Handle<ShaderBuffer>,
    /// The pack's environment image (`Rgba32Float`; 1 × 1 black when it has none).
    #[texture(11, sample_type = "float", filterable = false)]
    pub environment_image: Handle<Image>,
    /// The pack's proxies as reflected rays are cast against them ([`rays`]).
    #[storage(12, read_only)]
    pub rays: Handle<ShaderBuffer>,
    /// The camera's moving proxies placed at its time ([`rays::CameraRays`]).
    #[storage(13, read_only)]
    pub ray_placements: Handle<ShaderBuffer>,
    /// The camera's cost counters ([`crate::reconstruct::counters::CounterBuffer`]), written
    /// when `cost_counters` is on.
    #[storage(18, visibility(fragment))]
    pub counters: Handle<ShaderBuffer>,
    /// The camera's screen-fill entries ([`screen_fill::ScreenFill`]), written by the
    /// fragments of the opaque pass when the camera has the screen-space fill.
    #[storage(20, visibility(fragment))]
    pub fill_entries: Handle<ShaderBuffer>,
    /// The camera's hole list ([`screen_fill::ScreenFill::holes`]).
    #[storage(21, visibility(fragment))]
    pub hole_list: Handle<ShaderBuffer>,
    /// The camera's blended keys' geometry ([`blend::BlendedKeys`]): per pair and face the
    /// first key's id, distance and normal.
    #[texture(22, dimension = "2d_array", sample_type = "u_int")]
    pub blended_geometry: Handle<Image>,
    /// Their blended lighting and non-diffuse terms.
    #[texture(23, dimension = "2d_array", sample_type = "u_int")]
    pub blended_terms: Handle<Image>,
    /// Whether the shader counts its cost ([`crate::PlenopticSettings::cost_counters`]).
    pub cost_counters: bool,
    /// Whether the camera has the screen-space fill (its fragments write fill entries).
    pub screen_fill: bool,
    /// Whether the device can force the depth test before the fragment shader
    /// ([`screen_fill::EarlyDepthSupport`]).
    pub early_depth: bool,
    /// The object's diffuse albedo factors from its material in the pack: base-colour factor
    /// × (1 − metallic)(1 − transmission), and the metallic and transmission factors apart
    /// (the textures multiply per pixel); `None` for an object without a material, which
    /// shows its radiance.
    pub albedo: Option<MaterialFactors>,
    /// The object's coverage when it is see-through glazing (the pack's
    /// [`plenoptic_pack::ObjectEntry::coverage`]), else 1. Glazing is drawn in Bevy's
    /// transparent pass, blended over what lies behind it with this alpha in
    /// geometry-assisted mode, as `plenoptic_recon`'s glazing module composites it.
    pub coverage: f32,
    /// Whether the object's material in the pack is transmissive glass. Such glass is drawn
    /// in Bevy's transparent pass with premultiplied alpha: where the camera's settings show
    /// it see-through ([`plenoptic_recon::specular::see_through_transmittance`]), the
    /// fragment is its reflection marched for the camera over what lies behind, which shows
    /// through with the mean of the per-surface transmittance T, both faces drawn (T², as
    /// `plenoptic_recon`'s glazing module composites a pane); elsewhere it is opaque (alpha 1).
    /// Glazing (`coverage` < 1) is blended as glazing even where its material transmits.
    pub transmissive: bool,
    /// The camera's [`view::ViewBuffer::bindings`] when the bind group was last prepared.
    pub bindings: u64,
}

/// The pipeline key of a [`PlenopticMaterial`] and of a lit mesh's lighting: what its
/// shader is compiled with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct GeometryKey {
    /// Counting the cost (the `PLENOPTIC_COUNTERS` shader def).
    pub cost_counters: bool,
    /// Writing the screen-space fill's entries (`PLENOPTIC_SCREEN_FILL`).
    pub screen_fill: bool,
    /// The depth test forced before the fragment shader (`PLENOPTIC_EARLY_DEPTH`,
    /// `@early_depth_test(force)`): a shader that writes storage would otherwise run for
    /// every fragment the depth prepass already hid, and write for it.
    pub early_depth: bool,
}

impl GeometryKey {
    /// The key of a material counting or not, writing fill entries or not, on a device that
    /// can force early depth tests or not, whose fragments may discard (alpha mask: a forced
    /// early test would write the depth of discarded fragments) or not.
    pub fn new(cost_counters: bool, screen_fill: bool, early_depth: bool, discards: bool) -> Self {
        Self {
            cost_counters,
            screen_fill,
            early_depth: early_depth && !discards && (cost_counters || screen_fill),
        }
    }
}

impl From<&PlenopticMaterial> for GeometryKey {
    fn from(m: &PlenopticMaterial) -> Self {
        Self::new(m.cost_counters, m.screen_fill, m.early_depth, false)
    }
}

impl GeometryKey {
    /// Adds this key's shader defs to a pipeline's fragment stage.
    pub fn add_shader_defs(
        self,
        descriptor: &mut bevy::render::render_resource::RenderPipelineDescriptor,
    ) {
        if let Some(fragment) = descriptor.fragment.as_mut() {
            for (on, def) in [
                (self.cost_counters, "PLENOPTIC_COUNTERS"),
                (self.screen_fill, "PLENOPTIC_SCREEN_FILL"),
                (self.early_depth, "PLENOPTIC_EARLY_DEPTH"),
            ] {
                if on {
                    fragment.shader_defs.push(def.into());
                }
            }
        }
    }
}

impl Material for PlenopticMaterial {
    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/geometry/geometry.wgsl".into()
    }

    fn alpha_mode(&self) -> AlphaMode {
        if self.coverage < 1.0 {
            AlphaMode::Blend
        } else if self.transmissive {
            AlphaMode::Premultiplied
        } else {
            AlphaMode::Opaque
        }
    }

    /// Both faces, in every pass: the CPU's raster and shadow rays see both, and a room's
    /// proxies face inwards, so with back faces culled the runtime sun's shadow map would miss
    /// a ceiling seen from above.
    fn specialize(
        _pipeline: &bevy::pbr::MaterialPipeline,
        descriptor: &mut bevy::render::render_resource::RenderPipelineDescriptor,
        _layout: &bevy::mesh::MeshVertexBufferLayoutRef,
        key: bevy::pbr::MaterialPipelineKey<Self>,
    ) -> Result<(), bevy::render::render_resource::SpecializedMeshPipelineError> {
        descriptor.primitive.cull_mode = None;
        key.bind_group_data.add_shader_defs(descriptor);
        Ok(())
    }
}

/// The uniform of a [`PlenopticMaterial`]: what belongs to its object (the camera's part is
/// in its view buffer, [`view::ViewParams`]). It changes only with the camera's settings.
#[derive(ShaderType, Debug, Clone, Default, PartialEq)]
pub struct ObjectParams {
    /// The object's id.
    pub id: u32,
    /// Its motion slot ([`view::ViewParams::motion`]); −1 for a static object, in world
    /// space.
    pub motion_slot: i32,
    /// Its coverage: its output alpha as glazing in geometry-assisted mode; 1 for opaque
    /// objects.
    pub coverage: f32,
    /// [`ObjectFlags`] bits.
    pub flags: u32,
    /// See-through glass's mean transmittance per surface ([`ObjectFlags::SEE_THROUGH`]).
    pub transmittance: f32,
    /// The material's transmission factor.
    pub transmission: f32,
    /// Its roughness factor.
    pub roughness: f32,
    /// Its IOR (the runtime sun's BSDF, [`sun`]).
    pub ior: f32,
    /// Its normal map's scale.
    pub normal_scale: f32,
    /// The base-colour texture's largest side (0: none).
    pub base_colour_size: f32,
    /// The metallic-roughness texture's largest side (0: none).
    pub metallic_roughness_size: f32,
    /// The normal map's largest side (0: none).
    pub normal_map_size: f32,
    /// The emissive texture's largest side (0: none).
    pub emissive_size: f32,
    /// The object's base-colour factor (xyz) and metallic factor (w) with
    /// [`ObjectFlags::MATERIALS`].
    pub albedo: Vec4,
    /// The base-colour texture's `KHR_texture_transform`: offset (xy), scale (zw).
    pub base_uv: Vec4,
    /// The metallic-roughness texture's: offset (xy), scale (zw).
    pub mr_uv: Vec4,
    /// The normal map's: offset (xy), scale (zw).
    pub normal_uv: Vec4,
    /// The rotations of the base-colour, metallic-roughness, normal and emissive transforms
    /// (x, y, z, w), radians.
    pub uv_rotation: Vec4,
    /// The material's emissive factor (xyz).
    pub emissive: Vec4,
    /// The emissive texture's `KHR_texture_transform`: offset (xy), scale (zw).
    pub emissive_uv: Vec4,
}

/// Bits of [`ObjectParams::flags`] (`bindings.wgsl`'s `OBJECT_*`).
pub struct ObjectFlags;

impl ObjectFlags {
    /// Shaded as albedo · lighting + non-diffuse (`Shading::Materials`; those lookups are
    /// always bilinear).
    pub const MATERIALS: u32 = 1 << 0;
    /// See-through transmissive glass: its reflection over what lies behind.
    pub const SEE_THROUGH: u32 = 1 << 1;
    /// Drawn in Bevy's opaque pass: its holes may be left to the screen-space fill.
    pub const OPAQUE_PASS: u32 = 1 << 2;
    /// The pack leaves the emission to the runtime (pack 4: every lit fragment adds it).
    pub const RUNTIME_EMISSION: u32 = 1 << 3;
    /// The material is double-sided (else it emits from its front only).
    pub const DOUBLE_SIDED: u32 = 1 << 4;
}

/// The coverage of the pack's object `id`: its manifest coverage if it is see-through
/// glazing, else 1 (opaque).
pub(crate) fn object_coverage(pack: &RadiancePack, id: u32) -> f32 {
    pack.coverage(id).unwrap_or(1.0)
}

/// What the shader needs of an object's material to compute its diffuse albedo per pixel as
/// `plenoptic_recon`'s material module does: `(1 − metallic · mr.b)(1 − transmission) ·
/// base colour · texture`.
#[derive(Debug, Clone)]
pub struct MaterialFactors {
    /// The material.
    pub material: plenoptic_pack::MaterialEntry,
    /// Its base-colour texture, when it has one that loaded.
    pub base_colour: Option<Handle<Image>>,
    /// Its metallic-roughness texture, likewise.
    pub metallic_roughness: Option<Handle<Image>>,
    /// Its normal map, likewise.
    pub normal: Option<Handle<Image>>,
    /// Its emissive texture, likewise.
    pub emissive: Option<Handle<Image>>,
    /// Largest sides of level 0 of the base-colour, metallic-roughness and normal textures
    /// (0: none).
    pub sizes: (u32, u32, u32),
    /// The emissive texture's (0: none).
    pub emissive_size: u32,
    /// Whether the pack leaves the emission to the runtime
    /// ([`plenoptic_pack::PackReader::runtime_emission`]).
    pub runtime_emission: bool,
}

impl MaterialFactors {
    /// The uniform's material fields.
    pub(crate) fn fill(&self, params: &mut ObjectParams) {
        let m = &self.material;
        params.flags |= ObjectFlags::MATERIALS;
        params.albedo = m.base_colour.truncate().extend(m.metallic.clamp(0.0, 1.0));
        params.transmission = m.transmission.clamp(0.0, 1.0);
        params.base_colour_size = self.sizes.0 as f32;
        params.metallic_roughness_size = self.sizes.1 as f32;
        params.normal_map_size = self.sizes.2 as f32;
        params.roughness = m.roughness.clamp(0.0, 1.0);
        params.ior = if m.ior > 0.0 { m.ior } else { 1.5 };
        params.normal_scale = m.normal_scale;
        let uv = |b: Option<plenoptic_pack::TextureBinding>| {
            b.and_then(|b| b.transform)
                .map_or((Vec4::new(0.0, 0.0, 1.0, 1.0), 0.0), |t| {
                    (
                        Vec4::new(t.offset.x, t.offset.y, t.scale.x, t.scale.y),
                        t.rotation,
                    )
                })
        };
        let (base, rb) = uv(m.base_colour_texture);
        let (mr, rm) = uv(m.metallic_roughness_texture);
        let (normal, rn) = uv(m.normal_texture);
        let (emissive, re) = uv(m.emissive_texture);
        params.base_uv = base;
        params.mr_uv = mr;
        params.normal_uv = normal;
        params.uv_rotation = Vec4::new(rb, rm, rn, re);
        params.emissive = m.emissive.extend(0.0);
        params.emissive_uv = emissive;
        params.emissive_size = self.emissive_size as f32;
        if self.runtime_emission {
            params.flags |= ObjectFlags::RUNTIME_EMISSION;
        }
        if m.double_sided {
            params.flags |= ObjectFlags::DOUBLE_SIDED;
        }
    }
}

/// The material of the pack's object `id` with its loaded textures; `None` without one.
pub(crate) fn material_factors(pack: &RadiancePack, id: u32) -> Option<MaterialFactors> {
    let m = pack.reader.object_material(id)?;
    let texture = |b: Option<plenoptic_pack::TextureBinding>| {
        let b = b?;
        let handle = pack.textures.get(b.texture as usize)?.clone()?;
        let entry = pack.reader.textures().get(b.texture as usize)?;
        Some((handle, entry.width.max(entry.height)))
    };
    let base = texture(m.base_colour_texture);
    let mr = texture(m.metallic_roughness_texture);
    let normal = texture(m.normal_texture);
    let emissive = texture(m.emissive_texture);
    Some(MaterialFactors {
        material: m.clone(),
        sizes: (
            base.as_ref().map_or(0, |t| t.1),
            mr.as_ref().map_or(0, |t| t.1),
            normal.as_ref().map_or(0, |t| t.1),
        ),
        base_colour: base.map(|t| t.0),
        metallic_roughness: mr.map(|t| t.0),
        normal: normal.map(|t| t.0),
        emissive_size: emissive.as_ref().map_or(0, |t| t.1),
        emissive: emissive.map(|t| t.0),
        runtime_emission: pack.reader.runtime_emission(),
    })
}
