//! The screen-space fill's composite ([`super::screen_fill`]): after the fill kernel, one point
//! per record of the room of the view's hole list, drawn into its target with its depth
//! buffer (`fill_composite.wgsl`). A listed hole's point writes its filled colour to the
//! samples of its pixel that its fragment covered and that are no nearer than its surface; the
//! other points fall outside the view. A render pass rather than a storage write, so that it
//! works on a multisampled target as on a single-sampled one, and so that where MSAA puts two
//! objects in one pixel each keeps its own samples. On a camera without an HDR target the
//! colour is tonemapped in the shader, with the view's [`Tonemapping`] and colour grading, as
//! the proxies' fragments are (Bevy's `TONEMAP_IN_SHADER`).

use bevy::asset::load_embedded_asset;
use bevy::core_pipeline::core_3d::CORE_3D_DEPTH_FORMAT;
use bevy::core_pipeline::tonemapping::{
    Tonemapping, TonemappingLuts, get_lut_bind_group_layout_entries, get_lut_bindings,
};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, uniform_buffer,
};
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedRenderPipelineId,
    ColorTargetState, ColorWrites, CompareFunction, DepthStencilState, FragmentState,
    MultisampleState, PipelineCache, PrimitiveState, PrimitiveTopology, RenderPassDescriptor,
    RenderPipelineDescriptor, ShaderStages, StoreOp, TextureFormat, UniformBuffer, VertexState,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::texture::{FallbackImage, GpuImage};
use bevy::render::view::{
    ViewDepthTexture, ViewTarget, ViewUniform, ViewUniformOffset, ViewUniforms,
};
use bevy::shader::{Shader, ShaderDefVal};

use super::screen_fill::{FillParams, ScreenFill};

/// The tonemapping LUT's bindings in the composite's own group (`fill_composite.wgsl`).
const LUT_BINDINGS: [u32; 2] = [2, 3];

/// What a view's composite pipeline depends on.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct CompositeKey {
    /// The target's samples (MSAA).
    samples: u32,
    /// Whether the cost counters count.
    counting: bool,
    /// The view target's format.
    format: TextureFormat,
    /// The tonemapping done in the shader: on a target that is not HDR, the view's.
    tonemap: Option<Tonemapping>,
}

/// The shader def that selects `method` in `bevy_core_pipeline::tonemapping` (as Bevy's mesh
/// pipeline names it for `TONEMAP_IN_SHADER`).
fn tonemap_method_def(method: Tonemapping) -> &'static str {
    match method {
        Tonemapping::None => "TONEMAP_METHOD_NONE",
        Tonemapping::Reinhard => "TONEMAP_METHOD_REINHARD",
        Tonemapping::ReinhardLuminance => "TONEMAP_METHOD_REINHARD_LUMINANCE",
        Tonemapping::AcesFitted => "TONEMAP_METHOD_ACES_FITTED",
        Tonemapping::AgX => "TONEMAP_METHOD_AGX",
        Tonemapping::SomewhatBoringDisplayTransform => {
            "TONEMAP_METHOD_SOMEWHAT_BORING_DISPLAY_TRANSFORM"
        }
        Tonemapping::TonyMcMapface => "TONEMAP_METHOD_TONY_MC_MAPFACE",
        Tonemapping::BlenderFilmic => "TONEMAP_METHOD_BLENDER_FILMIC",
        Tonemapping::KhronosPbrNeutral => "TONEMAP_METHOD_PBR_NEUTRAL",
    }
}

/// The composite's layouts (its own bindings; the counters at the materials' binding), its
/// shaders, and its pipelines by [`CompositeKey`], queued as views need them.
#[derive(Resource)]
pub(super) struct CompositePipelines {
    layouts: [BindGroupLayoutDescriptor; 2],
    shader: Handle<Shader>,
    ids: HashMap<CompositeKey, CachedRenderPipelineId>,
}

impl CompositePipelines {
    /// The pipeline for `key`.
    fn id(&mut self, cache: &PipelineCache, key: CompositeKey) -> CachedRenderPipelineId {
        *self.ids.entry(key).or_insert_with(|| {
            let mut shader_defs = vec![ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 1)];
            if key.counting {
                shader_defs.push("PLENOPTIC_COUNTERS".into());
            }
            if let Some(method) = key.tonemap {
                shader_defs.extend([
                    "TONEMAP_IN_SHADER".into(),
                    tonemap_method_def(method).into(),
                    ShaderDefVal::UInt(
                        "TONEMAPPING_LUT_TEXTURE_BINDING_INDEX".into(),
                        LUT_BINDINGS[0],
                    ),
                    ShaderDefVal::UInt(
                        "TONEMAPPING_LUT_SAMPLER_BINDING_INDEX".into(),
                        LUT_BINDINGS[1],
                    ),
                ]);
            }
            cache.queue_render_pipeline(RenderPipelineDescriptor {
                label: Some("plenoptic screen fill composite".into()),
                layout: self.layouts.to_vec(),
                vertex: VertexState {
                    shader: self.shader.clone(),
                    shader_defs: shader_defs.clone(),
                    entry_point: Some("hole_point".into()),
                    buffers: Vec::new(),
                },
                primitive: PrimitiveState {
                    topology: PrimitiveTopology::PointList,
                    ..default()
                },
                // Bevy's reversed depth: a sample is written where the hole's surface is at
                // least as near as what the opaque pass left there.
                depth_stencil: Some(DepthStencilState {
                    format: CORE_3D_DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(CompareFunction::GreaterEqual),
                    stencil: default(),
                    bias: default(),
                }),
                fragment: Some(FragmentState {
                    shader: self.shader.clone(),
                    shader_defs,
                    entry_point: Some("composite".into()),
                    targets: vec![Some(ColorTargetState {
                        format: key.format,
                        blend: None,
                        write_mask: ColorWrites::ALL,
                    })],
                }),
                multisample: MultisampleState {
                    count: key.samples,
                    ..default()
                },
                ..default()
            })
        })
    }
}

/// Makes the composite's layouts; its pipelines are queued per view.
pub(super) fn init_composite(mut commands: Commands, asset_server: Res<AssetServer>) {
    let [lut_texture, lut_sampler] = get_lut_bind_group_layout_entries();
    let own = BindGroupLayoutDescriptor::new(
        "plenoptic screen fill composite",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer::<FillParams>(false),
                storage_buffer_read_only_sized(false, None),
                lut_texture,
                lut_sampler,
                uniform_buffer::<ViewUniform>(true),
            ),
        ),
    );
    let counters = BindGroupLayoutDescriptor::new(
        "plenoptic screen fill composite counters",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::FRAGMENT,
            ((18, storage_buffer_sized(false, None)),),
        ),
    );
    commands.insert_resource(CompositePipelines {
        layouts: [own, counters],
        shader: load_embedded_asset!(asset_server.as_ref(), "fill_composite.wgsl"),
        ids: HashMap::default(),
    });
}

/// The render world's resources the composite binds besides its view's: the tonemapping
/// LUTs and the view uniforms.
#[derive(bevy::ecs::system::SystemParam)]
pub(super) struct CompositeInputs<'w> {
    images: Res<'w, RenderAssets<GpuImage>>,
    luts: Option<Res<'w, TonemappingLuts>>,
    fallback: Res<'w, FallbackImage>,
    view_uniforms: Res<'w, ViewUniforms>,
}

/// Draws a view's filled holes into its target after the fill kernel.
#[expect(
    clippy::too_many_arguments,
    clippy::type_complexity,
    reason = "a Bevy render system"
)]
pub(super) fn composite_fill(
    view: ViewQuery<(
        (&ScreenFill, &ViewTarget, &ViewDepthTexture),
        (&ExtractedCamera, &ViewUniformOffset),
        (Option<&Msaa>, Option<&Tonemapping>),
    )>,
    pipelines: Option<ResMut<CompositePipelines>>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    inputs: CompositeInputs,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut ctx: RenderContext,
) {
    let ((fill, target, depth), (camera, view_offset), (msaa, tonemapping)) = view.into_inner();
    let Some(mut pipelines) = pipelines else {
        return;
    };
    if !fill.on() {
        return;
    }
    let key = CompositeKey {
        samples: msaa.map_or(1, Msaa::samples),
        counting: fill.counting,
        format: target.main_texture_format(),
        tonemap: if camera.hdr {
            None
        } else {
            tonemapping.copied()
        },
    };
    let id = pipelines.id(&pipeline_cache, key);
    let (Some(pipeline), Some(holes), Some(counters), Some(luts), Some(view_uniform)) = (
        pipeline_cache.get_render_pipeline(id),
        buffers.get(&fill.holes),
        buffers.get(&fill.counters),
        inputs.luts.as_deref(),
        inputs.view_uniforms.uniforms.binding(),
    ) else {
        return;
    };
    let (lut_view, lut_sampler) = get_lut_bindings(
        &inputs.images,
        luts,
        &key.tonemap.unwrap_or(Tonemapping::None),
        &inputs.fallback,
    );
    let mut uniform = UniformBuffer::from(FillParams::new(fill, camera, Vec3::ZERO));
    uniform.write_buffer(&device, &queue);
    let Some(params) = uniform.binding() else {
        return;
    };
    let own = device.create_bind_group(
        "plenoptic screen fill composite",
        &pipeline_cache.get_bind_group_layout(&pipelines.layouts[0]),
        &BindGroupEntries::sequential((
            params,
            holes.buffer.as_entire_binding(),
            lut_view,
            lut_sampler,
            view_uniform,
        )),
    );
    let counting = device.create_bind_group(
        "plenoptic screen fill composite counters",
        &pipeline_cache.get_bind_group_layout(&pipelines.layouts[1]),
        &BindGroupEntries::with_indices(((18, counters.buffer.as_entire_binding()),)),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("plenoptic screen fill composite"),
        color_attachments: &[Some(target.get_color_attachment())],
        depth_stencil_attachment: Some(depth.get_attachment(StoreOp::Store)),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let span = diagnostics.pass_span(&mut pass, "plenoptic/screen_fill_composite");
    if let Some(viewport) = camera.viewport.as_ref() {
        pass.set_camera_viewport(viewport);
    }
    pass.set_render_pipeline(pipeline);
    pass.set_bind_group(0, &own, &[view_offset.offset]);
    pass.set_bind_group(1, &counting, &[]);
    pass.draw(0..fill.room(), 0..1);
    span.end(&mut pass);
}
