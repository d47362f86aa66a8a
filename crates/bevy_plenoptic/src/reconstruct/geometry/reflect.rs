//! Reflections for the actual camera on the GPU (docs/architecture.md, "Pack v2"), as
//! `plenoptic_recon::specular` makes them on the CPU: on a mirror, or a glossy surface where
//! no baked lamp's highlight would be lost, the fragment marches the reflected ray through
//! each lookup's distance cube (`reflect.wgsl`: the same steps, refinement and acceptance),
//! reads the hit's radiance around it from that key, blends the keys with their lookup
//! weights × the angular closeness, and shows
//!
//! `albedo · lighting + emission(uv) + W(n·ω_o) · L_in`
//!
//! instead of the baked non-diffuse radiance (`geometry.wgsl`). Glossy lobes march 8 rays
//! reflected about GGX half-vectors from the same Hammersley set, turned per pixel by the
//! same golden-ratio sequence; rays that leave the scene see the pack's environment at the
//! camera's time. Where no lookup answers, the baked non-diffuse radiance stays.
//!
//! The emission is the material's at the fragment's UV (`pixel_emission`), as on the CPU.

use bevy::prelude::*;
use plenoptic_recon::Specular;
use plenoptic_recon::specular::{GLOSSY_RAYS, glossy_allowed_in, march_distance};

use super::view::ViewParams;
use crate::asset::RadiancePack;
use crate::camera::ReconSettings;

/// The view buffer's reflection fields on `pack`, as the camera's `settings` ask.
pub(super) fn fill(params: &mut ViewParams, pack: &RadiancePack, settings: &ReconSettings) {
    let manifest = pack.reader.manifest();
    params.specular = match settings.specular {
        Specular::Baked => Vec4::ZERO,
        Specular::Marched { max_roughness } => {
            let glossy = glossy_allowed_in(manifest, pack.reader.direct_sun().is_some());
            Vec4::new(
                1.0,
                if glossy { max_roughness } else { -1.0 },
                march_distance(manifest),
                GLOSSY_RAYS as f32,
            )
        }
    };
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
        let geometry = include_str!("geometry.wgsl");
        let line = format!("const RAY_OFFSET: f32 = {RAY_OFFSET:?};");
        assert!(geometry.contains(&line), "geometry.wgsl lacks `{line}`");
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
            assert!(geometry.contains(&line), "geometry.wgsl lacks `{line}`");
        }
        let rays = include_str!("rays.wgsl");
        let line = format!("const NO_TRIANGLES: u32 = {NO_TRIANGLES:#x}u;");
        assert!(rays.contains(&line), "rays.wgsl lacks `{line}`");
    }
}
