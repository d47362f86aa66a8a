//! Per-view state of the geometry-assisted path (thesis §8.2.3; `docs/architecture.md`, "The
//! runtime plugin"): what one camera looks up this frame, in one storage buffer per camera
//! that every material it draws binds.
//!
//! A camera's [`ViewBuffer`] holds its [`ViewParams`]: the lookups (base views, bracketing
//! keys, weights), the volume blocks, its tunables from [`ReconSettings`], the runtime sun,
//! the reflection settings and the pack's environment at its time, and per animated object
//! of the pack the object's transform at each lookup's key time, `M_o(τ)`. It is rewritten
//! in place once per camera per frame (Bevy reuses a storage buffer of the same size), so a
//! material's own uniform ([`super::ObjectParams`]) holds only what belongs to its object:
//! the object's id, its motion slot, its coverage and its material. A fragment carries its
//! point into key τ's frame as `M_o(τ) · local_from_world · p`, with the drawn mesh's own
//! inverse transform from Bevy's mesh uniform: for a proxy placed at the camera's time that
//! is `M_o(t)⁻¹`, for an app mesh its own global transform (so its lighting follows it
//! wherever the app's animation puts it). Static objects are in world space and not carried.
//!
//! [`ViewBuffer::bindings`] changes whenever something the camera's materials bind was
//! replaced (its view buffer grew, the pack's volume buffers were repacked, the image-mode
//! frame was resized); a material bound with another value is marked modified, so that Bevy
//! prepares its bind group again. Bevy does not do this itself for a material's handles.

use std::hash::{Hash, Hasher};

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::ShaderType;
use bevy::render::storage::ShaderBuffer;

use super::blend::BlendedKeys;
use super::frame::{CameraFrame, FrameLookups, frame_lookups, warped};
use super::screen_fill::ScreenFill;
use super::volume;
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
#[cfg(doc)]
use crate::camera::ReconSettings;
use crate::reconstruct::counters::CounterBuffer;
use crate::reconstruct::environment::EnvironmentUniform;
use crate::reconstruct::frames::{ImageFrame, ViewDisplay};
use crate::reconstruct::relight::{LightLayerParams, RelitKeys};
use crate::reconstruct::{KeyTextures, MAX_LOOKUPS};
use crate::streaming::StreamCache;
use plenoptic_pack::MAX_LIGHT_GROUPS;
use plenoptic_recon::lamps::MAX_RUNTIME_LAMPS;
use plenoptic_recon::relight::Relight;

/// One lookup of the view buffer, a base view's key (`Lookup` in `bindings.wgsl`).
#[derive(ShaderType, Debug, Clone, Copy, Default, PartialEq)]
pub struct LookupParams {
    /// The base view's position.
    pub base: Vec3,
    /// The view's weight × the key's time weight.
    pub weight: f32,
    /// Its first array layer in the camera's keys (6 per lookup).
    pub first_layer: u32,
    /// With light groups, its key's first layer in the pack's key texture
    /// ([`crate::reconstruct::relight`]); `first_layer` is then `6k`, its layers in the
    /// camera's relit keys.
    pub source_layer: u32,
    /// 1 + the index of the blended pair it is the first key of (0: none).
    pub pair: u32,
    /// Whether the key has normals (1) or not (0).
    pub normals: u32,
}

/// A base view's temporal-volume block in the view buffer (`VolumeBlock` in
/// `bindings.wgsl`; [`super::volume`]).
#[derive(ShaderType, Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeParams {
    /// The base view's position.
    pub base: Vec3,
    /// The base view's weight.
    pub weight: f32,
    /// Its first sample in the pack's sample buffer.
    pub first_sample: u32,
    /// Its first direction-bin offset in the pack's bin buffer.
    pub first_bin: u32,
}

/// A placed lamp in the view buffer (`Lamp` in `bindings.wgsl`), as
/// `plenoptic_recon::lamps::RuntimeLamp` describes it.
#[derive(ShaderType, Debug, Clone, Copy, Default, PartialEq)]
pub struct LampParams {
    /// Position, metres.
    pub position: Vec3,
    /// Range, metres (−1: none).
    pub range: f32,
    /// A spot light's axis (unit).
    pub axis: Vec3,
    /// The cosine of a spot light's outer cone (−2: a point light).
    pub cos_outer: f32,
    /// Colour × intensity, scaled by the lamp's light group.
    pub radiant: Vec3,
    /// A spot light's `1 / (cos inner − cos outer)` (0: a point light).
    pub cone_scale: f32,
}

/// One camera's lookups and settings, as the geometry-assisted shader reads them (`ViewParams`
/// in `bindings.wgsl`).
#[derive(ShaderType, Debug, Clone, Default, PartialEq)]
pub struct ViewParams {
    /// Lookups in use (of `lookups`).
    pub lookup_count: u32,
    /// Face size of the keys, in texels.
    pub face: u32,
    /// Volume blocks in use (of `volumes`).
    pub volume_count: u32,
    /// [`ViewFlags`] bits.
    pub flags: u32,
    /// Relative depth tolerance of the same-surface test.
    pub depth_tolerance: f32,
    /// Angular power p of the lookups' weight ((1 + cos θ)/2)^p.
    pub angular_power: f32,
    /// The camera's time t.
    pub time: f32,
    /// The temporal window tε of the volume samples.
    pub time_window: f32,
    /// Same-object hole-fill radius, in pixels.
    pub fill_radius: u32,
    /// Index of the heaviest lookup (the "background" fallback; ≥ `lookup_count`: none).
    pub heaviest: u32,
    /// How many of `lamps` are in use.
    pub lamp_count: u32,
    /// Rays per glossy pixel ([`super::reflect`]).
    pub glossy_rays: u32,
    /// The roughest glossy surface marched (−1: ideal mirrors only).
    pub glossy_roughness: f32,
    /// How far reflected rays are marched.
    pub march_distance: f32,
    /// Key pairs blended this frame (of `pairs`; [`super::blend`]).
    pub pair_count: u32,
    /// The runtime sun: unit direction towards it (xyz; w unused), with [`ViewFlags::SUN`].
    pub sun: Vec4,
    /// The runtime sun's illuminance at the camera's time (xyz).
    pub sun_illuminance: Vec4,
    /// The placed lamps ([`super::lamps`], `plenoptic_recon::lamps`): their highlights on
    /// marched glossy surfaces, and with [`ViewFlags::LAMPS`] their diffuse light on every lit
    /// fragment; `lamp_count` counts them.
    pub lamps: [LampParams; MAX_RUNTIME_LAMPS],
    /// The lookups in use (`lookup_count` of them).
    pub lookups: [LookupParams; MAX_LOOKUPS],
    /// Per blended pair: its two lookups (x, y) ([`super::blend`]).
    pub pairs: [UVec4; super::blend::MAX_PAIRS as usize],
    /// The volume blocks in use (`volume_count` of them).
    pub volumes: [VolumeParams; volume::MAX_VOLUMES],
    /// Light groups stored per key and volume sample ([`crate::reconstruct::relight`]; 0:
    /// the camera reads the pack's keys as stored).
    pub light_groups: u32,
    /// Layers blended (of `light_layers`).
    pub light_layer_count: u32,
    /// First `vec4` of the volume samples' group words in the pack's sample buffer.
    pub volume_groups: u32,
    /// The blend's weight of the total (xyz).
    pub light_base: Vec4,
    /// The sky's multiplier (xyz): relit radiance where a texel sees no object.
    pub light_sky: Vec4,
    /// The layers blended.
    pub light_layers: [LightLayerParams; MAX_LIGHT_GROUPS],
    /// The pack's environment at the camera's time: what reflected rays that leave the scene
    /// see.
    pub environment: EnvironmentUniform,
    /// `M_o(τ)` of each lookup per animated object: entry `slot · MAX_LOOKUPS + k` for the
    /// object in motion slot `slot` (its index among the pack's animated objects) and lookup `k`.
    #[shader(size(runtime))]
    pub motion: Vec<Mat4>,
}

/// Bits of [`ViewParams::flags`] (`VIEW_*` in `bindings.wgsl`).
#[derive(Debug, Clone, Copy)]
pub struct ViewFlags;

impl ViewFlags {
    /// Accepted lookups filtered seamlessly bilinear, as `plenoptic_recon` does with
    /// `CubeFilter::Bilinear` (else the nearest texel).
    pub const BILINEAR: u32 = 1 << 0;
    /// The image-mode passes' frame is shown instead (image and volume modes).
    pub const IMAGE_MODE: u32 = 1 << 1;
    /// The pack has a runtime sun (`sun`, `sun_illuminance`).
    pub const SUN: u32 = 1 << 2;
    /// Reflections are marched for the camera ([`super::reflect`]).
    pub const MARCHED: u32 = 1 << 3;
    /// Holes of the opaque pass are left to the screen-space fill ([`super::screen_fill`]).
    pub const SCREEN_FILL: u32 = 1 << 4;
    /// The camera reads its relit keys ([`crate::reconstruct::relight`]): lookup `k`'s key at
    /// layers `6k..6k + 6`, volume samples blended with their group layers.
    pub const RELIT: u32 = 1 << 5;
    /// The opaque fragments leave their lookups to the lookup kernel
    /// ([`super::lookup_kernel`]).
    pub const LOOKUP_KERNEL: u32 = 1 << 6;
    /// The lookup kernel looks materials' lighting up at the anchors and interpolates the
    /// rest (`ReconSettings::sparse_lighting`): a material's record is left to its passes.
    pub const SPARSE_LIGHTING: u32 = 1 << 7;
    /// The pack leaves its lamps' direct diffuse light to the runtime (pack 5.0): lit
    /// fragments add it ([`super::lamps`]).
    pub const LAMPS: u32 = 1 << 8;
}

/// A camera's [`ViewParams`] buffer and this frame's lookups.
#[derive(Component, Debug, Clone)]
pub struct ViewBuffer {
    /// The storage buffer its materials bind.
    pub buffer: Handle<ShaderBuffer>,
    /// What it holds now.
    params: ViewParams,
    /// This frame's lookups (the background's key comes from them).
    pub(crate) lookups: FrameLookups,
    /// Changes when something the camera's materials bind was replaced (see the module doc).
    pub bindings: u64,
    /// The camera's cost counters ([`CounterBuffer`]), which its materials bind too.
    pub counters: Handle<ShaderBuffer>,
    /// The camera's screen-fill entries ([`ScreenFill`]), which its materials bind too.
    pub fill_entries: Handle<ShaderBuffer>,
    /// Its hole list ([`ScreenFill::holes`]), which its materials bind too.
    pub hole_list: Handle<ShaderBuffer>,
    /// Its blended keys' two textures ([`BlendedKeys`]), which its materials bind too.
    pub blended: Option<(Handle<Image>, Handle<Image>)>,
    /// The key and shading textures its lookups read: its [`RelitKeys`] when it has them,
    /// else its pack's.
    pub keys: Option<(Handle<Image>, Handle<Image>)>,
    /// What the camera's light-group weights give each emitter of its pack this frame (its
    /// materials' emission reads it).
    pub relight: Relight,
}

impl ViewBuffer {
    /// What the buffer holds now.
    pub fn params(&self) -> &ViewParams {
        &self.params
    }

    /// Whether the camera's holes are left to the screen-space fill this frame.
    pub fn screen_fill(&self) -> bool {
        self.params.flags & ViewFlags::SCREEN_FILL != 0
    }
}

/// The motion slot of the pack's object `id`: its index among the pack's animated objects,
/// or `None` for a static one (in world space).
pub(crate) fn motion_slot(pack: &RadiancePack, id: u32) -> Option<u32> {
    pack.proxies
        .iter()
        .filter(|p| p.track.is_some())
        .position(|p| p.id == id)
        .map(|s| s as u32)
}

fn shader_buffer(params: &ViewParams) -> ShaderBuffer {
    let mut b = ShaderBuffer::new(&[], RenderAssetUsages::RENDER_WORLD);
    b.set_data(params.clone());
    b
}

/// Gives every plenoptic camera its view buffer and its [`ViewDisplay`].
pub(super) fn add_view_buffers(
    mut commands: Commands,
    cameras: Query<Entity, (With<PlenopticCamera>, Without<ViewBuffer>)>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for camera in &cameras {
        let params = ViewParams {
            motion: vec![Mat4::IDENTITY],
            ..default()
        };
        commands.entity(camera).insert((
            ViewBuffer {
                buffer: buffers.add(shader_buffer(&params)),
                params,
                lookups: FrameLookups::default(),
                bindings: 0,
                counters: Handle::default(),
                fill_entries: Handle::default(),
                hole_list: Handle::default(),
                blended: None,
                keys: None,
                relight: Relight::default(),
            },
            ViewDisplay::default(),
        ));
    }
}

/// Fills each camera's view buffer for this frame (rewritten only when it changed) and says
/// what it shows in its [`ViewDisplay`].
#[expect(clippy::type_complexity, reason = "a Bevy system's query")]
pub(super) fn update_view_buffers(
    keys: Res<KeyTextures>,
    volumes: Res<volume::VolumeBuffers>,
    cache: Res<StreamCache>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<(
        &PlenopticCamera,
        &GlobalTransform,
        &ImageFrame,
        &CounterBuffer,
        (
            Option<&ScreenFill>,
            Option<&BlendedKeys>,
            Option<&RelitKeys>,
        ),
        &mut ViewBuffer,
        &mut ViewDisplay,
    )>,
    images: Res<Assets<Image>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for (cam, transform, frame, counters, (fill, blended, relit), mut view, mut display) in
        &mut cameras
    {
        let id = cam.pack.id();
        let (Some(pack), Some(tex)) = (packs.get(id), keys.0.get(&id)) else {
            continue;
        };
        let lookups = frame_lookups(
            id,
            pack,
            tex,
            &cache,
            &cam.settings,
            transform.translation(),
            cam.time,
        );
        let pack_volumes = volumes.0.get(&id);
        let relight = cam.lights.relight(pack.reader.manifest());
        let ctx = CameraFrame {
            cam,
            pack,
            tex,
            volumes: pack_volumes,
            lookups: &lookups,
            image_mode: warped(cam.mode) && frame.active,
            relit: relit.map(|r| r.groups),
            relight: &relight,
        };
        let mut params = ctx.view_params();
        if let Some(fill) = fill.filter(|f| f.on() && !ctx.image_mode) {
            params.flags |= ViewFlags::SCREEN_FILL;
            if fill.kernel && fill.lookups.is_some() {
                params.flags |= ViewFlags::LOOKUP_KERNEL;
                if fill.sparse {
                    params.flags |= ViewFlags::SPARSE_LIGHTING;
                }
            }
        }
        let view = view.as_mut();
        if view.relight != relight {
            view.relight = relight;
        }
        if params.motion.len() != view.params.motion.len() {
            // Another size: a new buffer, which the materials must bind again.
            view.buffer = buffers.add(shader_buffer(&params));
        } else if params != view.params
            && let Some(mut b) = buffers.get_mut(&view.buffer)
        {
            b.set_data(params.clone());
        }
        let shown = ViewDisplay {
            heaviest_layer: lookups.heaviest_layer(relit.is_some()),
            image_mode: params.flags & ViewFlags::IMAGE_MODE != 0,
        };
        if *display != shown {
            *display = shown;
        }
        view.params = params;
        view.lookups = lookups;
        let mut h = std::collections::hash_map::DefaultHasher::new();
        view.buffer.id().hash(&mut h);
        pack_volumes.map(|v| v.generation).hash(&mut h);
        images.get(&frame.image).map(Image::size).hash(&mut h);
        counters.buffer.id().hash(&mut h);
        if view.counters != counters.buffer {
            view.counters = counters.buffer.clone();
        }
        if let Some(fill) = fill {
            fill.entries.id().hash(&mut h);
            fill.holes.id().hash(&mut h);
            if view.fill_entries != fill.entries {
                view.fill_entries = fill.entries.clone();
            }
            if view.hole_list != fill.holes {
                view.hole_list = fill.holes.clone();
            }
        }
        if let Some(b) = blended {
            let textures = (b.geometry.clone(), b.terms.clone());
            textures.0.id().hash(&mut h);
            textures.1.id().hash(&mut h);
            if view.blended.as_ref() != Some(&textures) {
                view.blended = Some(textures);
            }
        }
        let keys = match relit {
            Some(r) => (r.image.clone(), r.shading.clone()),
            None => (tex.image.clone(), tex.shading.clone()),
        };
        keys.0.id().hash(&mut h);
        keys.1.id().hash(&mut h);
        if view.keys.as_ref() != Some(&keys) {
            view.keys = Some(keys);
        }
        let bindings = h.finish();
        if view.bindings != bindings {
            view.bindings = bindings;
        }
    }
}

/// Fills the motion entries of `params` for `lookups`: per animated object of `pack`, its
/// transform at each lookup's key time.
pub(super) fn fill_motion(params: &mut ViewParams, pack: &RadiancePack, taus: &[f32]) {
    params.motion.clear();
    for p in pack.proxies.iter().filter(|p| p.track.is_some()) {
        for k in 0..MAX_LOOKUPS {
            params.motion.push(
                taus.get(k)
                    .map_or(Mat4::IDENTITY, |&tau| p.transform_at(tau).to_matrix()),
            );
        }
    }
    // Bindings may not be empty.
    if params.motion.is_empty() {
        params.motion.push(Mat4::IDENTITY);
    }
}
