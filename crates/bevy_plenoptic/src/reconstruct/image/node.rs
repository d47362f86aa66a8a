//! The image-mode compute passes, run for each view with a job, one after the other, before
//! the cameras render (the views share the scratch buffers).

use bevy::prelude::*;
use bevy::render::render_resource::{ComputePassDescriptor, PipelineCache};
use bevy::render::renderer::RenderContext;

use super::prepare::{ImageBindGroups, ImagePipelines};

pub(super) fn run_passes(
    mut render_context: RenderContext,
    views: Query<&ImageBindGroups>,
    pipelines: Option<Res<ImagePipelines>>,
    pipeline_cache: Res<PipelineCache>,
) {
    let Some(pipelines) = pipelines else {
        return;
    };
    let Some(passes) = pipelines
        .passes
        .iter()
        .map(|&id| pipeline_cache.get_compute_pipeline(id))
        .collect::<Option<Vec<_>>>()
    else {
        return;
    };
    for groups in &views {
        let p = &groups.params;
        let (w, h, face, views) = (p.size.x, p.size.y, p.size.z, p.size.w);
        let texels = 6 * face * face;
        let mut pass =
            render_context
                .command_encoder()
                .begin_compute_pass(&ComputePassDescriptor {
                    label: Some("plenoptic image mode"),
                    ..default()
                });
        pass.set_bind_group(0, &groups.groups[0], &[]);
        pass.set_pipeline(passes[0]);
        pass.dispatch_workgroups((w * h).div_ceil(64), views, 1);
        for splat in &passes[1..4] {
            pass.set_pipeline(splat);
            pass.dispatch_workgroups(texels.div_ceil(64), views, 1);
        }
        pass.set_pipeline(passes[4]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        pass.set_pipeline(passes[5]);
        for k in 0..p.misc.x {
            pass.set_bind_group(0, &groups.groups[k as usize % 2], &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        pass.set_bind_group(0, &groups.groups[p.misc.x as usize % 2], &[]);
        pass.set_pipeline(passes[6]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
}
