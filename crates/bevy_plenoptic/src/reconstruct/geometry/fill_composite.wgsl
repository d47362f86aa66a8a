// The screen-space fill's composite (screen_fill.rs): a full-screen pass over the view's
// target, after the fill kernel, that writes each listed hole's filled colour (its record,
// screen_fill.wgsl) into the hole's pixel, every sample of it, and leaves every other pixel
// as the opaque pass drew it. It reads one entry per pixel of the viewport.
#import bevy_core_pipeline::fullscreen_vertex_shader::FullscreenVertexOutput
#import plenoptic::fill_entry::{HoleRecords, FillParams, HOLE, unpack_pair}
#import plenoptic::counters::{tally, flush_kernel_counters, C_LOADS_16}

@group(0) @binding(0) var<storage, read> entries: array<vec4<u32>>;
@group(0) @binding(1) var<uniform> fill: FillParams;
@group(0) @binding(2) var<storage, read> holes: HoleRecords;

@fragment
fn composite(in: FullscreenVertexOutput) -> @location(0) vec4<f32> {
    let p = vec2<u32>(in.position.xy) - fill.offset;
    if any(p >= fill.size) {
        discard;
    }
    tally(C_LOADS_16, 1u);
    let e = entries[p.y * fill.size.x + p.x];
    let listed = (e.w & HOLE) != 0u && e.x < min(holes.count, arrayLength(&holes.records));
    if listed {
        tally(C_LOADS_16, 1u);
    }
    flush_kernel_counters(in.position.xy);
    if !listed {
        discard;
    }
    return vec4<f32>(unpack_pair(holes.records[e.x].pair)[0], 1.0);
}
