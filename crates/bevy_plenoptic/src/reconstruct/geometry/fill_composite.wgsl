// The screen-space fill's composite (screen_fill.rs): after the fill kernel, one point per
// record of the room of the camera's hole list, drawn into the view's target with its depth
// buffer. A listed hole's point covers its pixel and writes its filled colour to the samples
// its fragment covered (the record's sample mask) that are no nearer than its surface (the
// record's depth, tested against the depth buffer): where MSAA puts two objects in a pixel,
// each keeps its own samples. Points past the holes listed fall outside the view and are not
// drawn. On a camera without an HDR target (TONEMAP_IN_SHADER) the colour is tonemapped with
// the view's tonemapping and colour grading, as geometry.wgsl's fragments are.
#import plenoptic::fill_entry::{HoleRecords, FillParams, unpack_pair, COVERAGE_SHIFT}
#import plenoptic::counters::{tally, flush_kernel_counters, C_LOADS_16}
#ifdef TONEMAP_IN_SHADER
#import bevy_render::view::View
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif

@group(0) @binding(0) var<uniform> fill: FillParams;
@group(0) @binding(1) var<storage, read> holes: HoleRecords;
// Bindings 2 and 3: the tonemapping LUT (bevy_core_pipeline's lut_bindings.wgsl, at the
// indices the pipeline gives TONEMAPPING_LUT_TEXTURE/SAMPLER_BINDING_INDEX).
#ifdef TONEMAP_IN_SHADER
@group(0) @binding(4) var<uniform> view: View;
#endif

struct HolePoint {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) record: u32,
}

// The point of record `i`: its pixel's centre in the viewport's clip space.
@vertex
fn hole_point(@builtin(vertex_index) i: u32) -> HolePoint {
    if i >= min(holes.count, arrayLength(&holes.records)) {
        return HolePoint(vec4<f32>(2.0, 2.0, 2.0, 1.0), i);
    }
    let pixel = holes.records[i].pixel;
    let p = vec2<f32>(vec2<u32>(pixel % fill.size.x, pixel / fill.size.x)) + 0.5;
    let uv = p / vec2<f32>(fill.size);
    return HolePoint(vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0), i);
}

struct Filled {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
    @builtin(sample_mask) coverage: u32,
}

@fragment
fn composite(in: HolePoint) -> Filled {
    tally(C_LOADS_16, 3u);
    let r = holes.records[in.record];
    flush_kernel_counters(in.position.xy);
    var colour = vec4<f32>(unpack_pair(r.pair)[0], 1.0);
#ifdef TONEMAP_IN_SHADER
    colour = tone_mapping(colour, view.color_grading);
#endif
    return Filled(colour, r.world.w, r.state >> COVERAGE_SHIFT);
}
