//! Reflections for the actual camera on the GPU (docs/architecture.md, "Pack v2"), as
//! `plenoptic_recon::specular` makes them on the CPU: on a mirror, or a glossy surface where
//! no baked lamp's highlight would be lost, the fragment marches the reflected ray through
//! each lookup's distance cube (`reflect.wgsl`: the same steps, refinement and acceptance),
//! reads the hit's radiance around it from that key, blends the keys with their lookup
//! weights × the angular closeness, and shows
//!
//! `albedo · lighting + emission(uv) + W(n·ω_o) · L_in`
//!
//! instead of the baked non-diffuse radiance (`specular.wgsl`). Glossy lobes march 8 rays
//! reflected about GGX half-vectors from the same Hammersley set, turned per pixel by the
//! same golden-ratio sequence, each weighted by `F · G · (ω_o·h) / ((n·ω_o)(n·h))`, and add
//! the highlights of the pack's placed lamps (pack 4.1, `plenoptic_recon::lamps`) with a
//! shadow ray against the proxies; rays that leave the scene see the pack's environment at
//! the camera's time. Where no lookup answers, the baked non-diffuse radiance stays.
//!
//! The emission is the material's at the fragment's UV (`pixel_emission`), as on the CPU.

use plenoptic_recon::Specular;
use plenoptic_recon::specular::{GLOSSY_RAYS, glossy_allowed_in, march_distance};

use super::view::ViewParams;
use crate::asset::RadiancePack;
use crate::camera::ReconSettings;

/// The view buffer's reflection fields on `pack`, as the camera's `settings` ask.
pub(super) fn fill(params: &mut ViewParams, pack: &RadiancePack, settings: &ReconSettings) {
    let manifest = pack.reader.manifest();
    if let Specular::Marched { max_roughness } = settings.specular {
        let glossy = glossy_allowed_in(manifest, pack.reader.direct_sun().is_some());
        params.flags |= super::view::ViewFlags::MARCHED;
        params.glossy_roughness = if glossy { max_roughness } else { -1.0 };
        params.march_distance = march_distance(manifest);
        params.glossy_rays = GLOSSY_RAYS as u32;
    }
}

#[cfg(test)]
mod tests {
    use plenoptic_recon::flat_rays::NO_TRIANGLES;
    use plenoptic_recon::specular::{MAX_STEPS, RAY_OFFSET, REFINE_STEPS, STEP_TEXELS};

    /// The march's constants in `reflect.wgsl` are the runtime core's (the GPU frame equals
    /// the CPU's only if both step alike).
    #[test]
    fn the_shader_marches_with_the_cores_constants() {
        let wgsl = include_str!("reflect.wgsl");
        for line in [
            format!("const MAX_STEPS: u32 = {MAX_STEPS}u;"),
            format!("const REFINE_STEPS: u32 = {REFINE_STEPS}u;"),
            format!("const STEP_TEXELS: f32 = {STEP_TEXELS:?};"),
        ] {
            assert!(wgsl.contains(&line), "reflect.wgsl lacks `{line}`");
        }
        let specular = include_str!("specular.wgsl");
        let line = format!("const RAY_OFFSET: f32 = {RAY_OFFSET:?};");
        assert!(specular.contains(&line), "specular.wgsl lacks `{line}`");
        let fallback = include_str!("fallback.wgsl");
        for line in [
            format!(
                "const NEIGHBOUR_TEXELS: i32 = {};",
                plenoptic_recon::NEIGHBOUR_TEXELS
            ),
            format!(
                "const NEIGHBOUR_TOLERANCE: f32 = {:?};",
                plenoptic_recon::NEIGHBOUR_TOLERANCE
            ),
        ] {
            assert!(fallback.contains(&line), "fallback.wgsl lacks `{line}`");
        }
        let line = format!(
            "lamps: array<Lamp, {}>,",
            plenoptic_recon::lamps::MAX_RUNTIME_LAMPS
        );
        let bindings = include_str!("bindings.wgsl");
        assert!(bindings.contains(&line), "bindings.wgsl lacks `{line}`");
        let rays = include_str!("rays.wgsl");
        let line = format!("const NO_TRIANGLES: u32 = {NO_TRIANGLES:#x}u;");
        assert!(rays.contains(&line), "rays.wgsl lacks `{line}`");
    }
}
