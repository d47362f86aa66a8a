//! What one camera looks up this frame on its pack (its view buffer, [`super::view`]), and
//! the per-object uniform of the geometry-assisted shader: shared by the proxy materials
//! ([`super`]) and the app's own meshes lit by the pack ([`crate::lit::scene`]), so that both
//! are shaded from the same lookups (thesis §8.2.3; `docs/architecture.md`, "The runtime
//! plugin").
//!
//! The lookups are those of `plenoptic_recon`'s geometry mode: the view-space weights of
//! the nearest [`ReconSettings::max_views`] base views ([`ReconSettings::view_weights`]),
//! each at its bracketing keys with linear time weights
//! ([`plenoptic_recon::temporal::bracketing`]), over the keys that are resident and uploaded.

use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;
use plenoptic_recon::relight::Relight;
use plenoptic_recon::temporal::bracketing;

use super::view::{LookupParams, ViewFlags, ViewParams, motion_slot};
use super::{MaterialFactors, ObjectFlags, ObjectParams, lamps, reflect, sun, view, volume};
use crate::asset::RadiancePack;
use crate::camera::{PlenopticCamera, ReconMode, ReconSettings};
use crate::reconstruct::environment::EnvironmentUniform;
use crate::reconstruct::{KeyTexture, MAX_LOOKUPS};
use crate::streaming::StreamCache;

/// One lookup of a frame: a resident, uploaded (base view, time key).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lookup {
    base: Vec3,
    slot: u32,
    weight: f32,
    tau: f32,
    normals: bool,
}

/// What every object of a pack looks up this frame for one camera.
#[derive(Debug, Clone, Default)]
pub(crate) struct FrameLookups {
    /// (base view, normalised view weight), heaviest first.
    pub(crate) views: Vec<(usize, f32)>,
    /// At most [`MAX_LOOKUPS`].
    lookups: Vec<Lookup>,
    /// Index of the heaviest lookup (`plenoptic_recon`'s "background" and environment key).
    heaviest: Option<usize>,
}

impl FrameLookups {
    /// The first array layer of the heaviest lookup's key, if there is one: in the pack's
    /// key texture, or with `relit` in the camera's relit keys.
    pub(crate) fn heaviest_layer(&self, relit: bool) -> Option<u32> {
        let slot = |h: usize| {
            if relit {
                h as u32
            } else {
                self.lookups[h].slot
            }
        };
        self.heaviest.map(|h| 6 * slot(h))
    }
}

/// The lookups of a camera at `position` and time `t` on pack `id` (see the module doc).
pub(crate) fn frame_lookups(
    id: AssetId<RadiancePack>,
    pack: &RadiancePack,
    tex: &KeyTexture,
    cache: &StreamCache,
    settings: &ReconSettings,
    position: Vec3,
    t: f32,
) -> FrameLookups {
    let m = pack.reader.manifest();
    let views = settings.view_weights(m, &pack.usable_views, position);
    let mut out = FrameLookups::default();
    // Weight of the heaviest lookup.
    let mut heaviest = f32::NEG_INFINITY;
    for &(v, w) in &views {
        let bv = &m.base_views[v];
        let Some((k0, k1, f)) = bracketing(&bv.time_keys, t) else {
            continue;
        };
        let mut pairs = vec![(k0, 1.0 - f)];
        if k1 != k0 {
            pairs.push((k1, f));
        }
        let got: Vec<_> = pairs
            .into_iter()
            .filter_map(|(k, wt)| {
                let r = cache.get(id, (v as u32, k as u32))?;
                (tex.uploaded.get(&r.slot) == Some(&(v as u32, k as u32)))
                    .then_some((k, wt, r.slot))
            })
            .collect();
        let total: f32 = got.iter().map(|g| g.1).sum::<f32>().max(1e-9);
        for (k, wt, slot) in got {
            let weight = w * wt / total;
            if out.lookups.len() == MAX_LOOKUPS || weight <= 1e-4 {
                continue;
            }
            // Ties go to the later lookup, as Iterator::max_by does on the CPU.
            if weight >= heaviest {
                heaviest = weight;
                out.heaviest = Some(out.lookups.len());
            }
            out.lookups.push(Lookup {
                base: bv.position,
                slot,
                weight,
                tau: bv.time_keys[k],
                normals: tex.normals.contains(&slot),
            });
        }
    }
    out.views = views;
    out
}

/// Pairs the lookups of one base view's two time keys (consecutive in `lookups`, with the
/// same normals) for the blended keys ([`super::blend`]), at most `room`.
fn pair_keys(params: &mut ViewParams, lookups: &[Lookup], room: u32) {
    let mut k = 0;
    while k + 1 < lookups.len() && params.pair_count < room {
        let (a, b) = (&lookups[k], &lookups[k + 1]);
        if a.base == b.base && a.normals == b.normals {
            let pair = params.pair_count;
            params.pairs[pair as usize] = UVec4::new(k as u32, k as u32 + 1, 0, 0);
            params.lookups[k].pair = pair + 1;
            params.pair_count += 1;
            k += 2;
        } else {
            k += 1;
        }
    }
}

/// Whether `mode` shows the frame of the image-mode passes (image and volume modes).
pub(crate) fn warped(mode: ReconMode) -> bool {
    matches!(mode, ReconMode::Image | ReconMode::Volume)
}

/// One camera's frame on its pack: what its view buffer is filled from.
pub(crate) struct CameraFrame<'a> {
    /// The camera.
    pub(crate) cam: &'a PlenopticCamera,
    /// Its pack.
    pub(crate) pack: &'a RadiancePack,
    /// The pack's key texture.
    pub(crate) tex: &'a KeyTexture,
    /// The pack's resident temporal volumes.
    pub(crate) volumes: Option<&'a volume::PackVolumes>,
    /// This frame's lookups.
    pub(crate) lookups: &'a FrameLookups,
    /// Whether the camera shows the image-mode passes' frame.
    pub(crate) image_mode: bool,
    /// With [`crate::reconstruct::relight::RelitKeys`]: the pack's stored light groups.
    pub(crate) relit: Option<u32>,
    /// What the camera's light-group weights give each emitter of the pack.
    pub(crate) relight: &'a Relight,
}

/// What an object's uniform is made for.
pub(crate) struct ObjectShading<'a> {
    /// Pack object id.
    pub(crate) id: u32,
    /// The object's glazing coverage (1: opaque).
    pub(crate) coverage: f32,
    /// Its material from the pack, if any.
    pub(crate) factors: Option<&'a MaterialFactors>,
    /// Whether it is drawn in Bevy's opaque pass (its holes may be left to the screen-space
    /// fill, which runs before the transparent pass).
    pub(crate) opaque_pass: bool,
}

impl ObjectShading<'_> {
    /// The object's uniform as camera `cam` shows it from `pack`: its id, motion slot,
    /// coverage and material. It changes only with the camera's settings.
    pub(crate) fn params(
        &self,
        cam: &PlenopticCamera,
        pack: &RadiancePack,
        relight: &Relight,
    ) -> ObjectParams {
        let mut params = ObjectParams {
            id: self.id,
            motion_slot: motion_slot(pack, self.id).map_or(-1, |s| s as i32),
            coverage: self.coverage,
            ..default()
        };
        if let Some(factors) = self.factors
            && cam.settings.shading == plenoptic_recon::Shading::Materials
        {
            factors.fill(&mut params);
            params.emissive *= relight.object(self.id).extend(1.0);
            if let Some(t) = plenoptic_recon::specular::see_through_transmittance(
                &cam.settings,
                &factors.material,
            ) && self.coverage >= 1.0
            {
                params.flags |= ObjectFlags::SEE_THROUGH;
                params.transmittance = (t.x + t.y + t.z) / 3.0;
            }
        }
        if self.opaque_pass {
            params.flags |= ObjectFlags::OPAQUE_PASS;
        }
        params
    }
}

/// A material that binds one object's uniform and its camera's view buffer: the proxies'
/// [`super::PlenopticMaterial`] and the lit meshes' material.
pub(crate) trait BindsView {
    /// Object `id` with the coverage and material this material was given.
    fn shading(&self, id: u32) -> ObjectShading<'_>;
    /// The object's uniform, the camera bindings' generation and the view buffer it binds.
    fn bound(&self) -> (&ObjectParams, u64, &Handle<ShaderBuffer>);
    /// Binds the uniform and the camera's view buffer and counters.
    fn bind(&mut self, params: ObjectParams, view: &view::ViewBuffer);
}

/// Binds material `handle` to object `id`'s uniform as camera `cam` shows it from `pack` and
/// to the camera's view `view`, writing the asset only when one of them changed: a written
/// asset's bind group is prepared again (and `materials` is only marked changed then).
pub(crate) fn rebind<M: Asset + BindsView>(
    materials: &mut ResMut<Assets<M>>,
    handle: &Handle<M>,
    id: u32,
    (cam, pack): (&PlenopticCamera, &RadiancePack),
    view: &view::ViewBuffer,
) {
    let Some(m) = materials.get(handle) else {
        return;
    };
    let params = m.shading(id).params(cam, pack, &view.relight);
    let (bound, bindings, buffer) = m.bound();
    let stale = *bound != params || bindings != view.bindings || *buffer != view.buffer;
    if stale && let Some(mut m) = materials.get_mut(handle) {
        m.bind(params, view);
    }
}

impl CameraFrame<'_> {
    /// The camera's view buffer contents ([`super::view`]).
    pub(crate) fn view_params(&self) -> ViewParams {
        let (cam, pack, tex, f) = (self.cam, self.pack, self.tex, self.lookups);
        let (m, relight) = (pack.reader.manifest(), self.relight);
        let mut params = ViewParams {
            lookup_count: f.lookups.len() as u32,
            face: tex.face,
            depth_tolerance: cam.settings.depth_tolerance,
            angular_power: cam.settings.angular_power,
            fill_radius: cam.settings.hole_fill_radius,
            heaviest: f.heaviest.unwrap_or(MAX_LOOKUPS) as u32,
            flags: if self.image_mode {
                ViewFlags::IMAGE_MODE
            } else {
                0
            } | if cam.settings.cube_filter == plenoptic_recon::CubeFilter::Bilinear {
                ViewFlags::BILINEAR
            } else {
                0
            },
            environment: EnvironmentUniform::new(
                &pack.environment.at(cam.time).scaled(relight.sky),
            ),
            ..default()
        };
        let positions: Vec<Vec3> = m.base_views.iter().map(|b| b.position).collect();
        volume::fill_params(
            &mut params,
            self.volumes,
            &f.views,
            &positions,
            cam.settings.volume_buckets(m, cam.time),
            cam.time,
            cam.settings.time_epsilon_on(m),
        );
        for (n, l) in f.lookups.iter().enumerate() {
            params.lookups[n] = LookupParams {
                base: l.base,
                weight: l.weight,
                first_layer: l.slot * 6,
                normals: u32::from(l.normals),
                ..LookupParams::default()
            };
        }
        // Only lookups of lighting read the blended pairs: none for radiance or image mode.
        if cam.settings.shading == plenoptic_recon::Shading::Materials && !self.image_mode {
            pair_keys(
                &mut params,
                &f.lookups,
                super::blend::pair_room(&cam.settings),
            );
        }
        let taus: Vec<f32> = f.lookups.iter().map(|l| l.tau).collect();
        view::fill_motion(&mut params, pack, &taus);
        if cam.settings.shading == plenoptic_recon::Shading::Materials {
            sun::fill(&mut params, pack, cam.time, relight.sun);
            reflect::fill(&mut params, pack, &cam.settings);
            lamps::fill(&mut params, pack, relight);
        }
        if let Some(groups) = self.relit {
            params.flags |= ViewFlags::RELIT;
            super::relight::fill(&mut params, relight, groups);
        }
        params
    }
}
