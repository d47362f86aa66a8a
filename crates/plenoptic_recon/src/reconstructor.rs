//! The [`Reconstructor`]: an open pack, its proxy geometry, a cache of decoded chunks, and
//! [`Reconstructor::render`] for every mode.
//!
//! Failure policy: a chunk that is missing or unreadable (read error, checksum mismatch,
//! corrupt data) is left out — the frame is reconstructed from what remains and the
//! [`Report`] lists every such chunk. Only when nothing at all can be used (no base view with
//! one readable range image) does `render` return [`Error::Unusable`].

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};

use glam::Vec3;
use plenoptic_pack::{ChunkKind, CubeImage, PackReader, VolumeBlock};

use crate::background::{self, Coverage, PackEnvironment};
use crate::cache::{Cache, Cached};
use crate::camera::Camera;
use crate::frame::{FallbackReport, Frame, Mode, Report};
use crate::geometry::{Layer, Shot};
use crate::lookup::PackedTexels;
use crate::proxy::{GeometryMask, ProxyGeometry};
pub use crate::settings::{CubeFilter, ReconSettings, Shading};
use crate::shading::Channel;
use crate::streamed::KeySource;
use crate::temporal::{bezier_weights, nearest_key};
use crate::volume::BlockBins;
use crate::warp::{ViewCubes, Warped, background_fill, blend_warped, warp_view};
use crate::{Error, Result};

/// Reconstructs frames from one pack.
pub struct Reconstructor {
    pub(crate) pack: PackReader,
    proxy: Option<ProxyGeometry>,
    proxy_missing: Vec<String>,
    environment: PackEnvironment,
    /// Settings (may be changed between frames).
    pub settings: ReconSettings,
    pub(crate) cache: Mutex<Cache>,
    /// Volume blocks binned by direction for the geometry-assisted fallback, by (view,
    /// bucket); an entry is rebuilt when the chunk cache has reloaded its block.
    bins: Mutex<HashMap<(u32, u32), Arc<BlockBins>>>,
    /// Interleaved texels of (view, key) for the geometry-assisted lookups; an entry is
    /// rebuilt when the chunk cache has reloaded its cubes.
    packed: Mutex<HashMap<(u32, u32, Channel), Arc<PackedTexels>>>,
    /// The pack's materials, proxy UVs and decoded textures, loaded on first use.
    materials: std::sync::OnceLock<crate::material::Materials>,
    /// The runtime sun, read on first use.
    sun: std::sync::OnceLock<Option<crate::sun::RuntimeSun>>,
    /// The proxies as rays see them (the sun's shadow rays, reflected rays that leave the
    /// scene), built on first use.
    rays: std::sync::OnceLock<Option<crate::shadow::ShadowScene>>,
    /// Where cube chunks come from when a runtime streams them ([`crate::streamed`]).
    pub(crate) source: std::sync::RwLock<Option<Arc<dyn KeySource>>>,
    /// Chunks read from the pack so far.
    pub(crate) chunks_read: std::sync::atomic::AtomicU64,
    /// The light groups' weights and what they make of the pack ([`crate::relight`]).
    pub(crate) relight: Arc<crate::relight::Relight>,
    /// Lighting, non-diffuse cubes and volume blocks blended at the groups' weights.
    pub(crate) relit: Mutex<crate::relight::Memo>,
}

impl std::fmt::Debug for Reconstructor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reconstructor")
            .field("proxy", &self.proxy)
            .field("settings", &self.settings)
            .finish()
    }
}

/// The cubes of one base view at one time key.
#[derive(Clone)]
pub(crate) struct KeyCubes {
    /// The colour looked up: the radiance, or the channel [`Reconstructor::key_cubes_in`] was
    /// asked for (lighting, non-diffuse radiance).
    pub radiance: Arc<CubeImage<Vec3>>,
    pub distance: Arc<CubeImage<f32>>,
    pub ids: Arc<CubeImage<u32>>,
    /// Normals, when readable (sharpen the distance test at grazing angles).
    pub normal: Option<Arc<CubeImage<Vec3>>>,
}

/// The most samples per pixel along each axis [`ReconSettings::supersampling`] is taken at.
pub const MAX_SUPERSAMPLING: u32 = 8;

impl Reconstructor {
    /// Opens the pack at `path` with default settings.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::new(PackReader::open(path)?, ReconSettings::default()))
    }

    /// A reconstructor over an open pack. Reads the proxy geometry and tracks now (what cannot
    /// be read is reported with every frame).
    pub fn new(pack: PackReader, settings: ReconSettings) -> Self {
        let (proxy, mut proxy_missing) = ProxyGeometry::from_pack(&pack);
        let (environment, env_error) = PackEnvironment::from_pack(&pack);
        proxy_missing.extend(env_error);
        Reconstructor {
            proxy,
            proxy_missing,
            environment,
            settings,
            cache: Mutex::new(Cache::default()),
            bins: Mutex::new(HashMap::new()),
            packed: Mutex::new(HashMap::new()),
            materials: std::sync::OnceLock::new(),
            sun: std::sync::OnceLock::new(),
            rays: std::sync::OnceLock::new(),
            source: std::sync::RwLock::new(None),
            chunks_read: std::sync::atomic::AtomicU64::new(0),
            relight: Arc::new(crate::relight::Relight::new(
                pack.manifest(),
                &plenoptic_pack::GroupWeights::identity(),
            )),
            relit: Mutex::new(crate::relight::Memo::default()),
            pack,
        }
    }

    /// Takes every cube chunk from `source` from now on (`None`: from the pack again), so
    /// that a runtime's streaming decides what is resident ([`crate::streamed`]).
    pub fn set_key_source(&self, source: Option<Arc<dyn KeySource>>) {
        *self.source.write().unwrap_or_else(|e| e.into_inner()) = source;
    }

    /// Chunks this reconstructor has read from the pack (each read once while cached).
    pub fn chunks_read(&self) -> u64 {
        self.chunks_read.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The pack.
    pub fn pack(&self) -> &PackReader {
        &self.pack
    }

    /// The pack's environment and sun track.
    pub fn environment(&self) -> &PackEnvironment {
        &self.environment
    }

    /// The proxy geometry, if the pack has readable proxy meshes.
    pub fn proxy(&self) -> Option<&ProxyGeometry> {
        self.proxy.as_ref()
    }

    /// The pack's materials and proxy UVs (read on first use).
    pub(crate) fn materials(&self) -> &crate::material::Materials {
        self.materials
            .get_or_init(|| crate::material::Materials::load(&self.pack))
    }

    /// The pack's runtime sun, when its lighting leaves the sun's direct light out (pack 3)
    /// and it has proxies to cast shadows.
    pub fn runtime_sun(&self) -> Option<&crate::sun::RuntimeSun> {
        self.proxy.as_ref()?;
        self.sun
            .get_or_init(|| crate::sun::RuntimeSun::load(&self.pack))
            .as_ref()
    }

    /// The proxies' ray-cast geometry (BVHs built on first use), when the pack has proxies;
    /// the pack's glazing (objects with a coverage) is see-through to its shadow rays.
    pub(crate) fn proxy_rays(&self) -> Option<&crate::shadow::ShadowScene> {
        let proxy = self.proxy.as_ref()?;
        self.rays
            .get_or_init(|| {
                let glazing = self.pack.manifest().objects.iter();
                let coverage = glazing.filter_map(|o| Some((o.id, o.coverage?)));
                Some(crate::shadow::ShadowScene::new(proxy).with_see_through(coverage))
            })
            .as_ref()
    }

    /// The temporal filter half-width in use.
    pub fn time_epsilon(&self) -> f32 {
        self.settings.time_epsilon_on(self.pack.manifest())
    }

    /// The radiance, distance, id (and normal) cubes of (view, key), or a description of
    /// what failed.
    pub(crate) fn key_cubes(
        &self,
        view: usize,
        key: usize,
        missing: &mut Vec<String>,
    ) -> Option<KeyCubes> {
        self.key_cubes_in(view, key, Channel::Radiance, missing)
    }

    /// [`Self::key_cubes`] with the colour of `channel` in place of the radiance.
    pub(crate) fn key_cubes_in(
        &self,
        view: usize,
        key: usize,
        channel: Channel,
        missing: &mut Vec<String>,
    ) -> Option<KeyCubes> {
        let (v, k) = (view as u32, key as u32);
        let mut fail = |kind: &str, e: String| -> Option<KeyCubes> {
            missing.push(format!("{kind} cube of base view {view}, key {key}: {e}"));
            None
        };
        let radiance = match self.cached(channel.kind(), v, k) {
            Cached::Radiance(c) => c,
            Cached::Failed(e) => return fail(channel.name(), e),
            _ => return None,
        };
        let distance = match self.cached(ChunkKind::DistanceCube, v, k) {
            Cached::Distance(c) => c,
            Cached::Failed(e) => return fail("distance", e),
            _ => return None,
        };
        let ids = match self.cached(ChunkKind::ObjectIdCube, v, k) {
            Cached::Ids(c) => c,
            Cached::Failed(e) => return fail("object-id", e),
            _ => return None,
        };
        if radiance.face_size != distance.face_size || ids.face_size != distance.face_size {
            missing.push(format!(
                "base view {view}, key {key}: cube face sizes differ"
            ));
            return None;
        }
        let normal = match self.cached(ChunkKind::NormalCube, v, k) {
            Cached::Normal(c) if c.face_size == distance.face_size => Some(c),
            Cached::Failed(e) => {
                missing.push(format!("normal cube of base view {view}, key {key}: {e}"));
                None
            }
            _ => None,
        };
        Some(KeyCubes {
            radiance,
            distance,
            ids,
            normal,
        })
    }

    /// The volume block of (view, bucket), if present and readable (absence of a block is not
    /// reported: volumes are optional).
    pub(crate) fn volume_block(
        &self,
        view: usize,
        bucket: u32,
        missing: &mut Vec<String>,
    ) -> Option<Arc<VolumeBlock>> {
        self.pack
            .find(ChunkKind::VolumeBlock, view as u32, bucket)?;
        match self.cached(ChunkKind::VolumeBlock, view as u32, bucket) {
            Cached::Volume(b) => Some(b),
            Cached::Failed(e) => {
                missing.push(format!(
                    "volume block of base view {view}, bucket {bucket}: {e}"
                ));
                None
            }
            _ => None,
        }
    }

    /// The volume block of (view, bucket) binned by direction (built once per decoded block).
    pub(crate) fn block_bins(
        &self,
        view: usize,
        bucket: u32,
        missing: &mut Vec<String>,
    ) -> Option<Arc<BlockBins>> {
        let block = self.volume_block(view, bucket, missing)?;
        let key = (view as u32, bucket);
        let mut bins = self.bins.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(b) = bins.get(&key)
            && Arc::ptr_eq(&b.block, &block)
        {
            return Some(b.clone());
        }
        // Bound what stale entries can hold: the index is cheap to rebuild.
        let held: usize = bins.values().map(|b| b.bytes()).sum();
        if held > self.settings.cache_bytes / 8 {
            bins.clear();
        }
        let b = Arc::new(BlockBins::new(block));
        bins.insert(key, b.clone());
        Some(b)
    }

    /// The cubes of (view, key) interleaved per texel (built once per decoded key and
    /// channel).
    pub(crate) fn packed_texels(
        &self,
        view: usize,
        key: usize,
        channel: Channel,
        cubes: &KeyCubes,
    ) -> Arc<PackedTexels> {
        let k = (view as u32, key as u32, channel);
        let mut packed = self.packed.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = packed.get(&k)
            && p.built_from(cubes)
        {
            return p.clone();
        }
        // Bound what stale entries can hold: they are cheap to rebuild.
        let held: usize = packed.values().map(|p| p.bytes()).sum();
        if held > self.settings.cache_bytes / 2 {
            packed.clear();
        }
        let p = Arc::new(PackedTexels::new(cubes));
        packed.insert(k, p.clone());
        p
    }

    /// The connectivity (tetrahedra over stored sample indices) of the volume block of (view,
    /// bucket), if present and readable (absence is not reported; a read failure is).
    pub(crate) fn connectivity(
        &self,
        view: usize,
        bucket: u32,
        missing: &mut Vec<String>,
    ) -> Option<Arc<Vec<[u32; 4]>>> {
        self.pack
            .find(ChunkKind::VolumeConnectivity, view as u32, bucket)?;
        match self.cached(ChunkKind::VolumeConnectivity, view as u32, bucket) {
            Cached::Connectivity(t) => Some(t),
            Cached::Failed(e) => {
                missing.push(format!(
                    "volume connectivity of base view {view}, bucket {bucket}: {e}: triangulated the samples at t instead"
                ));
                None
            }
            _ => None,
        }
    }

    /// View-space weights of the base views for `camera`, over the views that have a readable
    /// radiance cube at some key (known failures excluded).
    pub(crate) fn view_weights(&self, position: Vec3) -> Vec<(usize, f32)> {
        let m = self.pack.manifest();
        let usable: Vec<bool> = m
            .base_views
            .iter()
            .enumerate()
            .map(|(i, v)| {
                (0..v.time_keys.len()).any(|k| {
                    self.pack
                        .find(ChunkKind::RadianceCube, i as u32, k as u32)
                        .is_some()
                })
            })
            .collect();
        self.settings.view_weights(m, &usable, position)
    }

    /// Reconstructs the frame `camera` sees at time `t` in `mode`, with
    /// [`ReconSettings::supersampling`] samples per pixel along each axis.
    pub fn render(&self, camera: &Camera, t: f32, mode: Mode) -> Result<(Frame, Report)> {
        camera.validate()?;
        let n = self.settings.supersampling.clamp(1, MAX_SUPERSAMPLING);
        if n == 1 {
            return self.render_samples(camera, t, mode);
        }
        let fine = Camera {
            width: camera.width * n,
            height: camera.height * n,
            ..*camera
        };
        let (frame, report) = self.render_samples(&fine, t, mode)?;
        Ok((crate::frame::box_filter(&frame, n), report))
    }

    /// [`Reconstructor::render`] with one sample per pixel (its centre).
    fn render_samples(&self, camera: &Camera, t: f32, mode: Mode) -> Result<(Frame, Report)> {
        camera.validate()?;
        let mut report = Report {
            mode,
            used_mode: mode,
            missing: self.proxy_missing.clone(),
            ..Report::default()
        };
        let glazing = crate::glazing::glazing_objects(self);
        let mut frame = match mode {
            Mode::GeometryAssisted if self.proxy.is_some() && !glazing.is_empty() => {
                // The environment is shown behind the glazing already.
                let frame = crate::glazing::render(self, camera, t, &glazing, &mut report)?;
                return Ok((frame, report));
            }
            Mode::GeometryAssisted if self.proxy.is_some() => {
                crate::shading::render(Shot::new(self, camera, t, None), Layer::All, &mut report)?
            }
            Mode::GeometryAssisted => {
                report
                    .missing
                    .push("no usable proxy geometry: fell back to image mode".into());
                report.used_mode = Mode::Image;
                self.render_image(camera, t, &mut report)?
            }
            Mode::Image => self.render_image(camera, t, &mut report)?,
            Mode::Volume => crate::volume::render(self, camera, t, &mut report)?,
        };
        background::show(self, camera, t, report.used_mode, &mut frame);
        Ok((frame, report))
    }

    /// Reconstructs the frame `camera` sees at time `t` in geometry-assisted mode from a
    /// geometry mask computed elsewhere (`plenoptic_eval`'s ray-cast mask, the reference the
    /// rasterized mask is tested against) instead of rasterizing the proxies. Fails when the
    /// pack has no proxy geometry or the mask's size is not the camera's.
    pub fn render_with_mask(
        &self,
        camera: &Camera,
        t: f32,
        mask: &GeometryMask,
    ) -> Result<(Frame, Report)> {
        camera.validate()?;
        let n = camera.pixel_count();
        if (mask.width, mask.height) != (camera.width, camera.height)
            || mask.object.len() != n
            || mask.position.len() != n
            || mask.depth.len() != n
        {
            return Err(Error::Camera(format!(
                "geometry mask of {}×{} for a {}×{} camera",
                mask.width, mask.height, camera.width, camera.height
            )));
        }
        let mut report = Report {
            mode: Mode::GeometryAssisted,
            used_mode: Mode::GeometryAssisted,
            missing: self.proxy_missing.clone(),
            ..Report::default()
        };
        let mut frame = crate::shading::render(
            Shot::new(self, camera, t, Some(mask)),
            Layer::All,
            &mut report,
        )?;
        let env = self.environment.at(t);
        background::apply(&env, camera, Coverage::Mask(mask), &mut frame);
        Ok((frame, report))
    }

    /// Image mode: Bézier blend of each view's keys, then warp and blend.
    fn render_image(&self, camera: &Camera, t: f32, report: &mut Report) -> Result<Frame> {
        let views = self.view_weights(camera.position);
        let mut cubes = Vec::new();
        for &(v, w) in &views {
            if let Some(c) = self.view_at_time(v, t, &mut report.missing) {
                cubes.push((v, w, c));
            }
        }
        if cubes.is_empty() {
            return Err(Error::Unusable(format!(
                "no readable range image near t = {t}: {}",
                report.missing.join("; ")
            )));
        }
        report.base_views = cubes.iter().map(|c| (c.0, c.1)).collect();
        let warped: Vec<(Warped, f32)> = {
            use rayon::prelude::*;
            let basis = camera.basis();
            let positions: Vec<Vec3> = cubes
                .iter()
                .map(|c| self.pack.manifest().base_views[c.0].position)
                .collect();
            cubes
                .par_iter()
                .zip(positions)
                .map(|((_, w, c), position)| {
                    let view = ViewCubes {
                        position,
                        radiance: &c.0,
                        distance: &c.1.distance,
                        object: &c.1.ids,
                    };
                    (
                        warp_view(&view, &basis, camera.width, camera.height, &self.settings),
                        *w,
                    )
                })
                .collect()
        };
        Ok(self.finish_warped(camera, &warped, report, false))
    }

    /// Blends warped views, fills holes, converts depth, fills the report.
    pub(crate) fn finish_warped(
        &self,
        camera: &Camera,
        warped: &[(Warped, f32)],
        report: &mut Report,
        volume: bool,
    ) -> Frame {
        let (w, h) = (camera.width, camera.height);
        let (mut rad, mut z, mut obj, mut cov) =
            blend_warped(warped, w, h, self.settings.depth_tolerance);
        let direct = cov.iter().filter(|&&c| c).count();
        let filled = background_fill(
            w,
            h,
            &mut rad,
            &mut z,
            &mut obj,
            &mut cov,
            self.settings.background_passes,
        );
        let rest = cov.len() - direct - filled;
        let basis = camera.basis();
        let mut frame = Frame::new(w, h);
        for (j, zz) in z.iter().enumerate() {
            if zz.is_finite() {
                let (x, y) = ((j % w as usize) as f32 + 0.5, (j / w as usize) as f32 + 0.5);
                let cos = basis.direction(x, y).dot(basis.forward).max(1e-6);
                frame.depth[j] = zz / cos;
            }
        }
        frame.radiance = rad;
        frame.object = obj;
        report.fallback = if volume {
            FallbackReport::from_counts(0, direct, filled, rest, 0)
        } else {
            FallbackReport::from_counts(direct, 0, filled, rest, 0)
        };
        frame
    }

    /// One base view's range image at time t: radiance by the Bézier weights over the keys
    /// that could be read, distance and ids from the nearest readable key.
    pub(crate) fn view_at_time(
        &self,
        view: usize,
        t: f32,
        missing: &mut Vec<String>,
    ) -> Option<(CubeImage<Vec3>, KeyCubes)> {
        let times = &self.pack.manifest().base_views.get(view)?.time_keys;
        let weights = bezier_weights(times, t);
        let mut parts = Vec::new();
        for &(k, w) in &weights {
            if let Some(c) = self.key_cubes(view, k, missing) {
                parts.push((k, w, c));
            }
        }
        if parts.len() < weights.len() {
            // Some keys are unreadable: fall back to linear weights over the readable nearest.
            let mut readable: Vec<(usize, KeyCubes)> =
                parts.drain(..).map(|(k, _, c)| (k, c)).collect();
            if readable.is_empty() {
                let k = nearest_key(times, t)?;
                let mut order: Vec<usize> = (0..times.len()).collect();
                order.sort_by(|&a, &b| {
                    (times[a] - times[k])
                        .abs()
                        .total_cmp(&(times[b] - times[k]).abs())
                });
                readable = order
                    .into_iter()
                    .take(3)
                    .filter_map(|k| self.key_cubes(view, k, missing).map(|c| (k, c)))
                    .collect();
            }
            let ws: Vec<f32> = readable
                .iter()
                .map(|(k, _)| 1.0 / ((times[*k] - t).abs() + 1e-4))
                .collect();
            let s: f32 = ws.iter().sum();
            parts = readable
                .into_iter()
                .zip(ws)
                .map(|((k, c), w)| (k, w / s, c))
                .collect();
        }
        let nearest = parts
            .iter()
            .min_by(|a, b| (times[a.0] - t).abs().total_cmp(&(times[b.0] - t).abs()))?
            .2
            .clone();
        let list: Vec<(&CubeImage<Vec3>, f32)> = parts
            .iter()
            .filter(|p| p.2.radiance.face_size == nearest.radiance.face_size)
            .map(|p| (&*p.2.radiance, p.1))
            .collect();
        let sum: f32 = list.iter().map(|x| x.1).sum();
        let list: Vec<(&CubeImage<Vec3>, f32)> =
            list.into_iter().map(|(c, w)| (c, w / sum)).collect();
        let radiance = crate::temporal::blend_cubes(&list)?;
        Some((radiance, nearest))
    }
}
