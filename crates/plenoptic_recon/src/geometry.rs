//! Geometry-assisted reconstruction (the default mode; thesis §8.2.3 with the range images of
//! chapter 6 and the temporal volumes of chapter 7).
//!
//! 1. The geometry mask ([`crate::proxy`]) gives, per pixel, the object `o` and the point `p`
//!    on it at time t.
//! 2. For each base view `v` of the view-space blend and each time key τ bracketing t, the
//!    point is carried along the object's motion, `p_τ = M_o(τ) M_o(t)⁻¹ p`, and looked up in
//!    the cube of `v` at τ in the direction `p_τ − v`. The lookup is *accepted* only if the
//!    cube saw the same object there and at the same distance (relative tolerance
//!    [`crate::ReconSettings::depth_tolerance`]); otherwise something occluded the point.
//! 3. Accepted lookups are blended with weight `w_view · w_time · w_angle`: the view-space
//!    weight, the linear weight of τ between the bracketing keys, and the angular closeness
//!    `((1 + cos θ)/2)^p` of the view's direction to the point and the camera's.
//! 4. No accepted lookup: the temporal-volume samples of the same object near that direction
//!    and within t ± tε (tent filter in time); then the nearest accepted pixel of the same
//!    object in screen space (same-object hole fill); then, in each key, the nearest texel
//!    of the object itself, else of any surface at the point's distance, within
//!    [`crate::NEIGHBOUR_TEXELS`] of the lookup's texel (`neighbour.rs`: a thin object, a
//!    window's mullion seen from afar, that no texel centre met; without this it would show
//!    the sky behind it); then the nearest view's cube in the point's direction regardless of id
//!    ("background").
//!
//! The per-object matrices `M_o(τ) M_o(t)⁻¹` are computed once per frame and key. The pixel
//! loop is parallel over bands of rows: each band of the mask is rasterized and then looked up
//! while it is in cache, a row at a time as a structure of arrays ([`crate::lookup`]), with the
//! keys' cubes interleaved per texel (cached by the reconstructor). The volume fallback and
//! the hole fill then visit only the pixels that need them.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::{Affine3A, Vec3};
use plenoptic_pack::CubeImage;
use rayon::iter::Either;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::frame::{FallbackReport, Frame, Report};
use crate::lookup::{FastKey, NO_SLOT, PackedTexels, Scratch, Shade};
use crate::proxy::{GeometryMask, ProxyGeometry};
use crate::reconstructor::{CubeFilter, KeyCubes, Reconstructor};
use crate::shading::Channel;
use crate::temporal::bracketing;
use crate::volume::VolumeIndex;
use crate::{Error, Result};

mod fill;
mod rows;
mod sparse;

use rows::{Rows, lookup_some};

struct ViewKey {
    /// Base view and time key indices.
    view: usize,
    key: usize,
    base: Vec3,
    weight: f32,
    cubes: KeyCubes,
    /// The pass's second channel at this key (same face size as `cubes`).
    second: Option<Arc<CubeImage<Vec3>>>,
    packed: Arc<PackedTexels>,
    /// Per object slot: M(τ) M(t)⁻¹.
    motion: Vec<Affine3A>,
}

const DIRECT: u8 = 1;
const VOLUME: u8 = 2;
const HOLE: u8 = 0;
const NONE: u8 = 4;

/// Which proxies a rasterized mask holds (see [`crate::glazing`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Layer<'a> {
    /// Every proxy.
    All,
    /// The proxies except these pack ids (what lies behind glazing).
    Without(&'a [u32]),
    /// Only these pack ids (the see-through layer: glazing, and transmissive glass, whose
    /// reflection is then marched for the camera; [`crate::glazing`]).
    Only(&'a [u32]),
}

/// What one geometry-assisted pass looks up ([`crate::shading`] runs one per channel).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pass<'a> {
    /// The proxies rasterized.
    pub layer: Layer<'a>,
    /// The colour looked up in the cubes and volume samples.
    pub channel: Channel,
    /// Pack ids whose pixels are left black and unfilled (another pass shades them).
    pub skip: &'a [u32],
    /// How the cubes are read.
    pub filter: CubeFilter,
    /// A second colour looked up with the same lookups, weights and fallbacks (the
    /// non-diffuse radiance beside the lighting), returned beside the frame by
    /// [`render_pair`]. A key whose second cube cannot be read is not used.
    pub second: Option<Channel>,
    /// Where no proxy is, the environment: the heaviest key's cube of this channel read with
    /// this filter (`None`: the pass's own channel and filter).
    pub environment: Option<(Channel, CubeFilter)>,
    /// Look up a quarter of the pixels and interpolate between them where that stands for the
    /// others' lookups (sparse.rs): for a channel smooth at cube resolution (the lighting).
    pub sparse: bool,
}

/// What [`render_pair`] renders.
pub(crate) struct PairFrame {
    /// The frame of the pass's channel.
    pub frame: Frame,
    /// The second channel per pixel (black where the frame has no lookup: nothing, or a
    /// skipped object; empty without a second channel).
    pub second: Vec<Vec3>,
    /// Whether the environment's cube could be read (pixels where nothing is are black
    /// otherwise).
    pub environment: bool,
    /// Where the pass rasterized the proxies with their triangles (a sparse pass): the
    /// projected triangles and each pixel's triangle (index into their sources; `u32::MAX`:
    /// none), for the surfaces of the same pixels ([`crate::surface`]).
    pub triangles: Option<(crate::raster::Projected, Vec<u32>)>,
    /// Pixels that took their anchors' mean instead of a lookup of their own (sparse.rs;
    /// the anchors themselves not counted).
    pub interpolated: usize,
}

impl<'a> Pass<'a> {
    /// Radiance of every proxy of `layer`, read as the settings say.
    pub fn radiance(layer: Layer<'a>, filter: CubeFilter) -> Self {
        Pass {
            layer,
            channel: Channel::Radiance,
            skip: &[],
            filter,
            second: None,
            environment: None,
            sparse: false,
        }
    }
}

/// The frame a geometry-assisted render makes: the reconstructor, the camera, the scene time
/// and, where one was computed beforehand, the geometry mask (used whole).
#[derive(Clone, Copy)]
pub(crate) struct Shot<'a> {
    pub rec: &'a Reconstructor,
    pub camera: &'a Camera,
    pub t: f32,
    pub mask: Option<&'a GeometryMask>,
}

impl<'a> Shot<'a> {
    /// The frame of `camera` at `t` reconstructed by `rec`, with `mask` if given.
    pub fn new(
        rec: &'a Reconstructor,
        camera: &'a Camera,
        t: f32,
        mask: Option<&'a GeometryMask>,
    ) -> Self {
        Shot {
            rec,
            camera,
            t,
            mask,
        }
    }
}

/// Renders one frame in geometry-assisted mode, from the proxies of `pass.layer`.
pub(crate) fn render(shot: Shot<'_>, pass: Pass<'_>, report: &mut Report) -> Result<Frame> {
    let pass = Pass {
        second: None,
        ..pass
    };
    render_pair(shot, pass, report).map(|p| p.frame)
}

/// [`render`], with the colour of `pass.second` per pixel beside the frame.
pub(crate) fn render_pair(
    shot: Shot<'_>,
    pass: Pass<'_>,
    report: &mut Report,
) -> Result<PairFrame> {
    let Shot { rec, camera, t, .. } = shot;
    let start = Instant::now();
    let Some(proxy) = rec.proxy() else {
        return Err(Error::Unusable("no proxy geometry".into()));
    };
    let views = rec.view_weights(camera.position);
    let ids = proxy.object_ids();
    let slot_of = SlotMap::new(ids);
    let skipped: Vec<bool> = ids.iter().map(|o| pass.skip.contains(o)).collect();
    let (keys, volumes) = read_keys(rec, proxy, &views, t, pass, report)?;
    report.base_views = views;
    report.stage_ms.push(("setup".into(), ms(start)));
    let start = Instant::now();
    let source = mask_source(proxy, shot, pass.layer);
    report.stage_ms.push(("mask_setup".into(), ms(start)));
    let start = Instant::now();
    let (mut frame, mut plane2) = blank_frame(camera, pass.second.is_some());
    let fast = fast_keys(&keys, ids.len());
    let w = camera.width as usize;
    let basis = camera.basis();
    let tol = rec.settings.depth_tolerance;
    let shade = shade(rec, &fast, pass.filter);
    let env = environment(rec, &keys, pass, report);
    let env_filter = pass.environment.map_or(pass.filter, |e| e.1);
    let rows = Rows {
        basis: &basis,
        source: &source,
        slot_of: &slot_of,
        skipped: &skipped,
        env: env.as_deref(),
        env_bilinear: env_filter == CubeFilter::Bilinear,
        width: w,
    };
    let mut prims: Vec<u32> = Vec::new();
    let sparse = pass.sparse && fast.len() <= 16;
    let anchors = anchor_pass(&rows, &shade, sparse, &mut frame, &mut prims);
    let lookups = Lookups {
        rows: &rows,
        shade: &shade,
        anchors: anchors.as_ref(),
    };
    let mut class = vec![HOLE; frame.radiance.len()];
    let interpolated = lookups.run(&mut frame, &mut plane2, &mut class, &mut prims);
    report.stage_ms.push(("mask_and_lookups".into(), ms(start)));
    let start = Instant::now();
    // The hit point of a pixel (for the fallbacks), as the pixel loop computed it.
    let depth = std::mem::take(&mut frame.depth);
    let point = |j: usize| match &source {
        MaskSource::Mask(m) => m.position[j],
        MaskSource::Raster(_) => {
            let dir = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            basis.position + dir * depth[j]
        }
    };
    let fallback = VolumeFallback {
        volumes: &volumes,
        tol,
        second: pass.second,
    };
    // A pixel's surface normal facing the eye, in the world as the volume samples' normals are,
    // for their face test (zero: none).
    let normal = |j: usize| -> Vec3 {
        let n = match &source {
            MaskSource::Mask(m) => m.normal.get(j).copied().unwrap_or_default(),
            MaskSource::Raster(tris) => prims
                .get(j)
                .map_or(Vec3::ZERO, |&p| tris.world_normal(&basis, p)),
        };
        let to_eye = basis.position - point(j);
        if n.dot(to_eye) < 0.0 { -n } else { n }
    };
    fallback.run(&point, &normal, &mut frame, &mut plane2, &mut class);
    report.stage_ms.push(("volume".into(), ms(start)));
    let start = Instant::now();
    let slot = |o: u32| slot_of.get(o);
    let (hole, background) = fill::hole_fill(
        &mut frame,
        &mut plane2,
        &mut class,
        rec.settings.hole_fill_radius as i64,
        &keys,
        &point,
        &slot,
    );
    frame.depth = depth;
    report.stage_ms.push(("hole_fill".into(), ms(start)));
    let count = |c: u8| class.iter().filter(|&&x| x == c).count();
    report.fallback =
        FallbackReport::from_counts(count(DIRECT), count(VOLUME), hole, background, count(NONE));
    let triangles = match source {
        MaskSource::Raster(tris) if anchors.is_some() => Some((tris, prims)),
        _ => None,
    };
    Ok(PairFrame {
        frame,
        second: plane2,
        environment: env.is_some(),
        triangles,
        interpolated,
    })
}

/// Where a sparse pass rasterizes the proxies: the anchors' lookups, at half resolution
/// (sparse.rs), with the mask rasterized on the way into `frame` (its depths become
/// distances along the rays) and each pixel's triangle into `prims`.
fn anchor_pass(
    rows: &Rows<'_>,
    shade: &Shade<'_>,
    sparse: bool,
    frame: &mut Frame,
    prims: &mut Vec<u32>,
) -> Option<sparse::Anchors> {
    let MaskSource::Raster(tris) = rows.source else {
        return None;
    };
    let pass = sparse::AnchorPass {
        tris,
        rows,
        shade,
        band: ROWS * rows.width.max(1),
    };
    sparse.then(|| pass.run(&mut frame.depth, &mut frame.object, prims))
}

/// The mask of `layer`: the proxies projected, to be rasterized band by band inside the
/// pixel loop, or the shot's mask (computed beforehand, e.g. ray cast by plenoptic_eval).
fn mask_source<'a>(proxy: &ProxyGeometry, shot: Shot<'a>, layer: Layer<'_>) -> MaskSource<'a> {
    let (camera, t) = (shot.camera, shot.t);
    match shot.mask {
        None => MaskSource::Raster(match layer {
            Layer::All => proxy.project(camera, t),
            Layer::Without(ids) => proxy.project_only(camera, t, |o| !ids.contains(&o)),
            Layer::Only(ids) => proxy.project_only(camera, t, |o| ids.contains(&o)),
        }),
        Some(m) => MaskSource::Mask(m),
    }
}

/// How the pixel loop weighs and reads the `fast` keys: the settings' depth tolerance and
/// angular power (as an integer power where it is one, which is faster), and the filter.
fn shade<'a>(rec: &Reconstructor, fast: &'a [FastKey<'a>], filter: CubeFilter) -> Shade<'a> {
    let power = rec.settings.angular_power;
    let power_int = if power.fract() == 0.0 && (1.0..=64.0).contains(&power) {
        power as u32
    } else {
        0
    };
    Shade {
        fast,
        tol: rec.settings.depth_tolerance,
        power,
        power_int,
        bilinear: filter == CubeFilter::Bilinear,
    }
}

/// A base view's temporal volume: its position, its view-space weight and its index.
type ViewVolume = (Vec3, f32, VolumeIndex);

/// The keys of the weighted base `views` at `t` with their cubes and motions, and the views'
/// temporal volumes; an error where no key can be read.
fn read_keys(
    rec: &Reconstructor,
    proxy: &ProxyGeometry,
    views: &[(usize, f32)],
    t: f32,
    pass: Pass<'_>,
    report: &mut Report,
) -> Result<(Vec<ViewKey>, Vec<ViewVolume>)> {
    let ids = proxy.object_ids();
    let inv_now: Vec<Affine3A> = ids
        .iter()
        .map(|&o| proxy.transform(o, t).inverse())
        .collect();
    let manifest = rec.pack().manifest();
    let mut keys: Vec<ViewKey> = Vec::new();
    let mut volumes: Vec<ViewVolume> = Vec::new();
    for &(v, w) in views {
        let bv = &manifest.base_views[v];
        let Some(got) = view_keys(rec, v, t, pass, report) else {
            continue;
        };
        let total: f32 = got.iter().map(|g| g.1).sum::<f32>().max(1e-9);
        for (k, wt, (c, second)) in got {
            let tau = bv.time_keys[k];
            let motion = ids
                .iter()
                .zip(&inv_now)
                .map(|(&o, inv)| proxy.transform(o, tau) * *inv)
                .collect();
            keys.push(ViewKey {
                view: v,
                key: k,
                base: bv.position,
                weight: w * wt / total,
                packed: rec.packed_texels(v, k, pass.channel, &c),
                cubes: c,
                second,
                motion,
            });
        }
        if let Some(index) = VolumeIndex::build(rec, v, t, pass.channel, &mut report.missing) {
            volumes.push((bv.position, w, index));
        }
    }
    if keys.is_empty() {
        return Err(Error::Unusable(format!(
            "no readable range image near t = {t}: {}",
            report.missing.join("; ")
        )));
    }
    Ok((keys, volumes))
}

/// A key's cubes of the pass's channel, and its second channel's cube.
type KeyRead = (KeyCubes, Option<Arc<CubeImage<Vec3>>>);

/// Base view `v`'s readable keys at `t` with their time weights (not normalised): the
/// bracketing keys, or where neither can be read the nearest readable key; `None` where no
/// keys bracket `t`.
fn view_keys(
    rec: &Reconstructor,
    v: usize,
    t: f32,
    pass: Pass<'_>,
    report: &mut Report,
) -> Option<Vec<(usize, f32, KeyRead)>> {
    let bv = &rec.pack().manifest().base_views[v];
    let (k0, k1, s) = bracketing(&bv.time_keys, t)?;
    let mut pairs = vec![(k0, 1.0 - s)];
    if k1 != k0 {
        pairs.push((k1, s));
    }
    // A key's cubes, and its second channel's cube of the same size.
    let mut read = |k: usize| {
        let c = rec.key_cubes_in(v, k, pass.channel, &mut report.missing)?;
        let Some(ch) = pass.second else {
            return Some((c, None));
        };
        let s = rec.key_cubes_in(v, k, ch, &mut report.missing)?.radiance;
        (s.face_size == c.ids.face_size).then_some((c, Some(s)))
    };
    let mut got = Vec::new();
    for (k, wt) in pairs {
        if let Some(c) = read(k) {
            got.push((k, wt, c));
        }
    }
    if got.is_empty() {
        // Both bracketing keys unreadable: try the nearest readable key.
        let mut order: Vec<usize> = (0..bv.time_keys.len()).collect();
        order.sort_by(|&a, &b| {
            (bv.time_keys[a] - t)
                .abs()
                .total_cmp(&(bv.time_keys[b] - t).abs())
        });
        if let Some((k, c)) = order
            .into_iter()
            .filter(|&k| k != k0 && k != k1)
            .take(2)
            .find_map(|k| read(k).map(|c| (k, c)))
        {
            got.push((k, 1.0, c));
        }
    }
    Some(got)
}

/// The frame and the second colour's plane, cleared: black, at infinite depth, no object.
/// They are filled in parallel (the first touch of their pages is a good part of the cost).
fn blank_frame(camera: &Camera, second: bool) -> (Frame, Vec<Vec3>) {
    let n = camera.width as usize * camera.height as usize;
    let mut frame = Frame {
        width: camera.width,
        height: camera.height,
        radiance: Vec::with_capacity(n),
        depth: Vec::with_capacity(n),
        object: Vec::with_capacity(n),
    };
    frame
        .radiance
        .par_extend(rayon::iter::repeat_n(Vec3::ZERO, n));
    frame
        .depth
        .par_extend(rayon::iter::repeat_n(f32::INFINITY, n));
    frame.object.par_extend(rayon::iter::repeat_n(0, n));
    let mut plane2: Vec<Vec3> = Vec::new();
    if second {
        plane2.par_extend(rayon::iter::repeat_n(Vec3::ZERO, n));
    }
    (frame, plane2)
}

/// Flat views of the keys' cubes for the pixel loop, keys of negligible weight skipped;
/// each marks the object slots whose lookup it shares with the key before it.
fn fast_keys(keys: &[ViewKey], slots: usize) -> Vec<FastKey<'_>> {
    let mut fast: Vec<FastKey<'_>> = keys
        .iter()
        .filter(|k| k.weight > 1e-4)
        .map(|k| {
            let second = k.second.as_deref();
            FastKey::new(k.base, k.weight, &k.cubes, &k.packed, second, &k.motion)
        })
        .collect();
    for i in 0..fast.len() {
        let reuse = (0..slots)
            .map(|s| {
                i > 0
                    && fast[i - 1].base == fast[i].base
                    && fast[i - 1].face == fast[i].face
                    && fast[i - 1].motion[s] == fast[i].motion[s]
            })
            .collect();
        fast[i].reuse = reuse;
    }
    fast
}

/// The environment's cube, where no proxy is: the heaviest key's, of the pass's environment
/// channel.
fn environment(
    rec: &Reconstructor,
    keys: &[ViewKey],
    pass: Pass<'_>,
    report: &mut Report,
) -> Option<Arc<CubeImage<Vec3>>> {
    let env_channel = pass.environment.map_or(pass.channel, |e| e.0);
    keys.iter()
        .max_by(|a, b| a.weight.total_cmp(&b.weight))
        .and_then(|k| {
            if env_channel == pass.channel {
                return Some(k.cubes.radiance.clone());
            }
            rec.key_cubes_in(k.view, k.key, env_channel, &mut report.missing)
                .map(|c| c.radiance)
        })
}

/// The pixel loop: parallel over bands of [`ROWS`] rows, each band's mask rasterized (unless
/// the anchors' pass did) and then looked up a row at a time while it is in cache.
struct Lookups<'a> {
    rows: &'a Rows<'a>,
    shade: &'a Shade<'a>,
    /// The anchors' lookups of a sparse pass.
    anchors: Option<&'a sparse::Anchors>,
}

/// One band of the frame's planes.
struct Band<'b> {
    /// Index of the band.
    index: usize,
    rad: &'b mut [Vec3],
    dep: &'b mut [f32],
    obj: &'b mut [u32],
    cls: &'b mut [u8],
    /// Each pixel's proxy triangle (an index into the projection's normals).
    prim: &'b mut [u32],
    /// The second colour, where there is one.
    rad2: Option<&'b mut [Vec3]>,
}

/// What a worker of the pixel loop keeps between bands: the row's scratch, the gathered
/// pixels' scratch, and the pixels to look up.
type Workspace = (Scratch, Scratch, Vec<usize>);

impl Lookups<'_> {
    /// Looks up every pixel of `frame` (and `plane2`, where not empty), classing each in
    /// `class`; returns how many took their anchors' mean. `prims` holds each pixel's proxy
    /// triangle where the anchors' pass rasterized, else the bands rasterize it there.
    fn run(
        &self,
        frame: &mut Frame,
        plane2: &mut [Vec3],
        class: &mut [u8],
        prims: &mut Vec<u32>,
    ) -> usize {
        let w = self.rows.width;
        let band = ROWS * w.max(1);
        let n = frame.radiance.len();
        if prims.len() != n {
            prims.clear();
            prims.resize(n, u32::MAX);
        }
        let interpolated = AtomicUsize::new(0);
        // The second colour's band, where there is one.
        let bands2 = if !plane2.is_empty() {
            Either::Left(plane2.par_chunks_mut(band).map(Some))
        } else {
            Either::Right((0..n.div_ceil(band)).into_par_iter().map(|_| None))
        };
        frame
            .radiance
            .par_chunks_mut(band)
            .zip(frame.depth.par_chunks_mut(band))
            .zip(frame.object.par_chunks_mut(band))
            .zip(class.par_chunks_mut(band))
            .zip(prims.par_chunks_mut(band))
            .zip(bands2)
            .enumerate()
            .for_each_init(
                || (Scratch::default(), Scratch::default(), Vec::new()),
                |work, (index, (((((rad, dep), obj), cls), prim), rad2))| {
                    let band = Band {
                        index,
                        rad,
                        dep,
                        obj,
                        cls,
                        prim,
                        rad2,
                    };
                    let between = self.band(work, band);
                    interpolated.fetch_add(between, Ordering::Relaxed);
                },
            );
        interpolated.into_inner()
    }

    /// Rasterizes (where needed) and looks up one band; returns how many of its pixels took
    /// their anchors' mean.
    fn band(&self, work: &mut Workspace, b: Band<'_>) -> usize {
        let w = self.rows.width;
        let y0 = b.index * ROWS;
        if let (MaskSource::Raster(tris), None) = (self.rows.source, &self.anchors) {
            // Camera-space depth into `dep`, object into `obj`, triangle into `prim`.
            crate::raster::raster_band(tris, w, y0, b.dep, b.obj, Some(&mut *b.prim));
        }
        let mut between_count = 0;
        let mut rad2 = b.rad2;
        let lines = b
            .rad
            .chunks_mut(w)
            .zip(b.dep.chunks_mut(w))
            .zip(b.obj.chunks_mut(w))
            .zip(b.cls.chunks_mut(w))
            .zip(b.prim.chunks(w));
        for (r, ((((rad, dep), obj), cls), prim)) in lines.enumerate() {
            let row2 = rad2.as_deref_mut().map(|b| &mut b[r * w..(r + 1) * w]);
            between_count += self.row(work, (y0 + r, prim), rad, dep, obj, cls, row2);
        }
        between_count
    }

    /// Looks up row `y`: each pixel's lookup, or its anchors' mean where they stand for it;
    /// returns how many took the anchors' mean.
    #[allow(
        clippy::too_many_arguments,
        reason = "the row's planes, each borrowed apart"
    )]
    fn row(
        &self,
        (s, packed, xs): &mut Workspace,
        (y, prim): (usize, &[u32]),
        rad: &mut [Vec3],
        dep: &mut [f32],
        obj: &mut [u32],
        cls: &mut [u8],
        mut row2: Option<&mut [Vec3]>,
    ) -> usize {
        let (w, tol, anchors) = (self.rows.width, self.shade.tol, self.anchors);
        if anchors.is_some() {
            s.slot.resize(w, NO_SLOT);
            self.rows.slots(&mut s.slot, y, obj, Some((rad, cls)));
        } else {
            self.rows.prepare(s, y, dep, obj, Some((rad, cls)));
            self.rows.normals(s, y, None, prim);
        }
        let mut between_count = 0;
        xs.clear();
        for x in (0..w).filter(|&x| s.slot[x] != NO_SLOT) {
            let between = anchors.and_then(|a| a.interpolate(x, y, obj[x], dep[x], tol));
            match between {
                Some((c, c2)) => {
                    // The anchors themselves are looked up, not interpolated.
                    between_count += usize::from(x % 2 == 1 || y % 2 == 1);
                    rad[x] = c;
                    if let Some(row2) = row2.as_deref_mut() {
                        row2[x] = c2;
                    }
                    cls[x] = DIRECT;
                }
                None => xs.push(x),
            }
        }
        let gathered = anchors.is_some();
        let lanes = if gathered && !xs.is_empty() {
            packed.gather_rays(self.rows.basis, y, xs, dep, &s.slot);
            self.rows.normals(packed, y, Some(xs), prim);
            packed
        } else {
            s
        };
        lookup_some(self.shade, lanes, gathered, xs, obj, |_, x, c, c2| {
            if c.w > 0.0 {
                rad[x] = c.truncate() / c.w;
                if let Some(row2) = row2.as_deref_mut() {
                    row2[x] = c2 / c.w;
                }
                cls[x] = DIRECT;
            } else {
                cls[x] = HOLE;
            }
        });
        between_count
    }
}

/// The temporal-volume fallback where no lookup was accepted.
struct VolumeFallback<'a> {
    volumes: &'a [ViewVolume],
    /// The relative depth tolerance of the lookups.
    tol: f32,
    /// The pass's second channel.
    second: Option<Channel>,
}

impl VolumeFallback<'_> {
    /// Fills the pixels of `class` [`HOLE`] that the volumes' samples of the same object near
    /// their `point`, facing as their surface `normal` does, answer, both colours with the
    /// same samples and weights.
    fn run(
        &self,
        point: &(impl Fn(usize) -> Vec3 + Sync),
        normal: &(impl Fn(usize) -> Vec3 + Sync),
        frame: &mut Frame,
        plane2: &mut [Vec3],
        class: &mut [u8],
    ) {
        let misses: Vec<usize> = (0..class.len()).filter(|&j| class[j] == HOLE).collect();
        if self.volumes.is_empty() || misses.is_empty() {
            return;
        }
        let found: Vec<(usize, Vec3, Vec3)> = misses
            .par_iter()
            .filter_map(|&j| {
                let (p, o, n) = (point(j), frame.object[j], normal(j));
                let (mut vs, mut vs2, mut vw) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
                for (base, w, index) in self.volumes {
                    let near = index.lookup_pair(p - *base, o, self.tol * 3.0, self.second, n);
                    if let Some((c, c2, wt)) = near {
                        vs += c * wt * *w;
                        vs2 += c2 * wt * *w;
                        vw += wt * *w;
                    }
                }
                (vw > 0.0).then(|| (j, vs / vw, vs2 / vw))
            })
            .collect();
        for (j, c, c2) in found {
            frame.radiance[j] = c;
            if let Some(x) = plane2.get_mut(j) {
                *x = c2;
            }
            class[j] = VOLUME;
        }
    }
}

/// Rows per band of the pixel loop (a band is rasterized, then shaded, while in cache).
const ROWS: usize = 4;

/// Where the geometry mask comes from.
enum MaskSource<'a> {
    /// Projected proxy triangles, rasterized per band.
    Raster(crate::raster::Projected),
    /// A mask computed beforehand.
    Mask(&'a GeometryMask),
}

/// Pack object id → slot in the per-object tables (dense for small ids).
struct SlotMap {
    dense: Vec<u32>,
    sparse: Vec<(u32, usize)>,
}

impl SlotMap {
    fn new(ids: &[u32]) -> Self {
        let max = ids.iter().copied().max().unwrap_or(0) as usize;
        if max < 1 << 20 {
            let mut dense = vec![u32::MAX; max + 1];
            for (i, &o) in ids.iter().enumerate() {
                dense[o as usize] = i as u32;
            }
            SlotMap {
                dense,
                sparse: Vec::new(),
            }
        } else {
            SlotMap {
                dense: Vec::new(),
                sparse: ids.iter().enumerate().map(|(i, &o)| (o, i)).collect(),
            }
        }
    }

    #[inline]
    fn get(&self, id: u32) -> Option<usize> {
        if !self.dense.is_empty() {
            return self
                .dense
                .get(id as usize)
                .filter(|&&s| s != u32::MAX)
                .map(|&s| s as usize);
        }
        self.sparse.iter().find(|x| x.0 == id).map(|x| x.1)
    }
}

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
