//! What the passes over a camera's keys share (the key blend, [`super::blend`], and the
//! light-group relight, [`super::relight`]): the keys and view buffer bound at the materials'
//! binding numbers, and a dispatch of one thread per texel of a number of cube faces, with
//! its `time_span` in Bevy's render diagnostics.

use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, texture_2d_array,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    ComputePassDescriptor, ComputePipeline, PipelineCache, ShaderStages, TextureSampleType,
};
use bevy::render::renderer::{RenderContext, RenderDevice};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::texture::GpuImage;

/// A pass's workgroup: 8 × 8 texels of one face.
const GROUP: u32 = 8;

/// The layout of the keys (binding 0), their shading texels (5) and the camera's view buffer
/// (10), as the materials bind them (`bindings.wgsl`).
pub(super) fn keys_layout(label: &'static str) -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        label,
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, texture_2d_array(TextureSampleType::Uint)),
                (5, texture_2d_array(TextureSampleType::Uint)),
                (10, storage_buffer_read_only_sized(false, None)),
            ),
        ),
    )
}

/// The bind group of [`keys_layout`].
pub(super) fn keys_group(
    (device, pipeline_cache): (&RenderDevice, &PipelineCache),
    (label, layout): (&'static str, &BindGroupLayoutDescriptor),
    (cubes, shading): (&GpuImage, &GpuImage),
    view: &GpuShaderBuffer,
) -> BindGroup {
    device.create_bind_group(
        label,
        &pipeline_cache.get_bind_group_layout(layout),
        &BindGroupEntries::with_indices((
            (0, &cubes.texture_view),
            (5, &shading.texture_view),
            (10, view.buffer.as_entire_binding()),
        )),
    )
}

/// Runs `pipeline` with `groups` (0 and 1) over `faces` cube faces of `face` × `face`
/// texels, inside the render diagnostics' span `span`.
pub(super) fn dispatch_faces(
    ctx: &mut RenderContext,
    (label, span): (&'static str, &'static str),
    (pipeline, groups): (&ComputePipeline, [&BindGroup; 2]),
    face: u32,
    faces: u32,
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx
        .command_encoder()
        .begin_compute_pass(&ComputePassDescriptor {
            label: Some(label),
            ..default()
        });
    let span = diagnostics.pass_span(&mut pass, span);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, groups[0], &[]);
    pass.set_bind_group(1, groups[1], &[]);
    let n = face.div_ceil(GROUP);
    pass.dispatch_workgroups(n, n, faces);
    span.end(&mut pass);
}
