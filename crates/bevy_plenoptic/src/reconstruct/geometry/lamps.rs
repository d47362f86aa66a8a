//! The placed lamps on the GPU (packs 4.1 and 5.0; `plenoptic_recon::lamps`, the same
//! formulas; thesis ch. 5, direct light at a finer accuracy than indirect light): the view
//! buffer's lamps, each scaled by its light group, which glossy surfaces whose reflection is
//! marched light with their highlights (`specular.wgsl`), and, where the pack leaves the
//! lamps' direct diffuse light to the runtime ([`ViewFlags::LAMPS`]), every lit fragment
//! with its Lambertian lobe (`lamps.wgsl`). Each lamp's light is shadowed by a ray against
//! the proxies that the glazing dims by `1 − c` per surface (`rays.wgsl`'s `transmittance`,
//! as `PlacedShadows::transmittance` on the CPU).

use plenoptic_recon::lamps::runtime_lamps;
use plenoptic_recon::relight::Relight;

use super::view::{LampParams, ViewFlags, ViewParams};
use crate::asset::RadiancePack;

/// The view buffer's lamps on `pack`, scaled by `relight`'s groups.
pub(super) fn fill(params: &mut ViewParams, pack: &RadiancePack, relight: &Relight) {
    let lamps = runtime_lamps(pack.reader.manifest()).unwrap_or_default();
    params.lamp_count = lamps.len() as u32;
    for (k, lamp) in lamps.iter().enumerate() {
        let (cos_outer, scale) = lamp.cone.unwrap_or((-2.0, 0.0));
        let range = if lamp.range.is_finite() {
            lamp.range
        } else {
            -1.0
        };
        params.lamps[k] = LampParams {
            position: lamp.position,
            range,
            axis: lamp.direction,
            cos_outer,
            radiant: lamp.radiant * relight.light(lamp.light),
            cone_scale: scale,
        };
    }
    if pack.reader.lamps_at_runtime() && !lamps.is_empty() {
        params.flags |= ViewFlags::LAMPS;
    }
}
