//! The material of an app mesh lit by the pack ([`super::scene`]): its own
//! `StandardMaterial` extended with the proxy material's bindings (the pack's lighting at the
//! mesh's points, `geometry.wgsl` with `PLENOPTIC_STANDARD`), kept bound to its camera's view
//! buffer as a proxy's material is.

use bevy::pbr::{ExtendedMaterial, MaterialExtension, MaterialExtensionKey};
use bevy::prelude::*;
use bevy::render::render_resource::AsBindGroup;
use bevy::render::storage::ShaderBuffer;
use bevy::shader::ShaderRef;

use crate::reconstruct::geometry::frame::{self, ObjectShading};
use crate::reconstruct::geometry::view::ViewBuffer;
use crate::reconstruct::geometry::{GeometryKey, MaterialFactors, ObjectParams};

/// The material of a lit mesh: its own `StandardMaterial` and the pack's lighting.
pub type LitMaterial = ExtendedMaterial<StandardMaterial, PlenopticLighting>;

/// The pack's lighting for one lit mesh: the proxy material's bindings (from 100, after the
/// standard material's), less its pack textures.
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
#[bind_group_data(GeometryKey)]
pub struct PlenopticLighting {
    /// Resident keys ([`crate::reconstruct`]), with their nearest sampler for gathers.
    #[texture(100, dimension = "2d_array", sample_type = "u_int")]
    #[sampler(115, sampler_type = "non_filtering")]
    pub cubes: Handle<Image>,
    /// The mesh's object: its id, motion slot, coverage and material.
    #[uniform(101)]
    pub params: ObjectParams,
    /// Resident temporal-volume samples of the pack.
    #[storage(102, read_only)]
    pub volume_samples: Handle<ShaderBuffer>,
    /// Their bin offsets.
    #[storage(103, read_only)]
    pub volume_bins: Handle<ShaderBuffer>,
    /// The camera's image-mode frame, shown in image and volume modes.
    #[texture(104, sample_type = "float", filterable = false)]
    pub image_frame: Handle<Image>,
    /// The resident keys' lighting and non-diffuse radiance.
    #[texture(105, dimension = "2d_array", sample_type = "u_int")]
    pub shading_cubes: Handle<Image>,
    /// The camera's view buffer ([`crate::reconstruct::geometry::view::ViewBuffer`]): its lookups,
    /// tunables, sun, environment and the animated objects' motion this frame.
    #[storage(110, read_only)]
    pub view: Handle<ShaderBuffer>,
    /// The pack's environment image.
    #[texture(111, sample_type = "float", filterable = false)]
    pub environment_image: Handle<Image>,
    /// The pack's proxies as reflected rays are cast against them
    /// ([`crate::reconstruct::geometry::rays`]).
    #[storage(112, read_only)]
    pub rays: Handle<ShaderBuffer>,
    /// The camera's moving proxies placed at its time.
    #[storage(113, read_only)]
    pub ray_placements: Handle<ShaderBuffer>,
    /// The camera's cost counters, written when `cost_counters` is on.
    #[storage(114, visibility(fragment))]
    pub counters: Handle<ShaderBuffer>,
    /// The camera's screen-fill entries, written when the camera has the screen-space fill.
    #[storage(116, visibility(fragment))]
    pub fill_entries: Handle<ShaderBuffer>,
    /// The camera's hole list.
    #[storage(117, visibility(fragment))]
    pub hole_list: Handle<ShaderBuffer>,
    /// The camera's blended keys' geometry: per pair and face the first key's id,
    /// distance and normal.
    #[texture(118, dimension = "2d_array", sample_type = "u_int")]
    pub blended_geometry: Handle<Image>,
    /// Their blended lighting and non-diffuse terms.
    #[texture(119, dimension = "2d_array", sample_type = "u_int")]
    pub blended_terms: Handle<Image>,
    /// Whether the shader counts its cost ([`crate::PlenopticSettings::cost_counters`]).
    pub cost_counters: bool,
    /// Whether the camera has the screen-space fill (its fragments write fill entries).
    pub screen_fill: bool,
    /// Whether the device can force early depth tests.
    pub early_depth: bool,
    /// Whether the app's material discards (alpha mask): no forced early depth test then.
    pub masked: bool,
    /// The object's material in the pack (its transmission, IOR and emission; the per-pixel
    /// base colour, metalness and roughness are the standard material's).
    pub factors: Option<MaterialFactors>,
    /// The object's glazing coverage (1: opaque).
    pub coverage: f32,
    /// The camera's [`ViewBuffer::bindings`] when the bind group was last prepared.
    pub bindings: u64,
}

impl From<&PlenopticLighting> for GeometryKey {
    fn from(m: &PlenopticLighting) -> Self {
        Self::new(m.cost_counters, m.screen_fill, m.early_depth, m.masked)
    }
}

impl MaterialExtension for PlenopticLighting {
    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/geometry/geometry.wgsl".into()
    }

    fn specialize(
        _pipeline: &bevy::pbr::MaterialExtensionPipeline,
        descriptor: &mut bevy::render::render_resource::RenderPipelineDescriptor,
        _layout: &bevy::mesh::MeshVertexBufferLayoutRef,
        key: MaterialExtensionKey<Self>,
    ) -> Result<(), bevy::render::render_resource::SpecializedMeshPipelineError> {
        if let Some(fragment) = descriptor.fragment.as_mut() {
            fragment.shader_defs.push("PLENOPTIC_STANDARD".into());
        }
        key.bind_group_data.add_shader_defs(descriptor);
        Ok(())
    }
}

impl frame::BindsView for LitMaterial {
    fn shading(&self, id: u32) -> ObjectShading<'_> {
        let e = &self.extension;
        ObjectShading {
            id,
            coverage: e.coverage,
            factors: e.factors.as_ref(),
            opaque_pass: matches!(self.base.alpha_mode, AlphaMode::Opaque),
        }
    }

    fn bound(&self) -> (&ObjectParams, u64, &Handle<ShaderBuffer>) {
        let e = &self.extension;
        (&e.params, e.bindings, &e.view)
    }

    fn bind(&mut self, params: ObjectParams, view: &ViewBuffer) {
        let e = &mut self.extension;
        e.params = params;
        e.bindings = view.bindings;
        e.view = view.buffer.clone();
        e.counters = view.counters.clone();
        e.fill_entries = view.fill_entries.clone();
        e.hole_list = view.hole_list.clone();
        e.screen_fill = view.screen_fill();
        if let Some((geometry, terms)) = &view.blended {
            e.blended_geometry = geometry.clone();
            e.blended_terms = terms.clone();
        }
        if let Some((cubes, shading)) = &view.keys {
            e.cubes = cubes.clone();
            e.shading_cubes = shading.clone();
        }
    }
}
