//! Test pack builder: analytic scenes rendered with a deterministic shading function through
//! `plenoptic_trace`'s accel, written with `PackWriter`. Shared by the tests and (via
//! `#[path]`) the benchmark, so it uses only crates both can see.
#![allow(dead_code, reason = "each test binary uses a part of it")]

use std::path::Path;

use plenoptic_pack::{
    AnimationTracks, BaseView, CubeFormats, CubeImage, Interpolation, Manifest, Motion,
    ObjectEntry, ObjectTracks, PackWriter, ProxyMesh, RangeImage, TimeRange, Track, ViewSpace,
    VolumeSample, cube,
};
use plenoptic_scene::Scene;
use plenoptic_trace::glam::{Quat, Vec2, Vec3};
use plenoptic_trace::{Image, PlacedScene, Ray, SceneAccel, shapes};

/// The point light of the shading function.
pub const LIGHT: Vec3 = Vec3::new(0.3, 2.3, 0.2);

/// A closed room 4 × 2.6 × 5 m with a static box and (optionally) a box sliding along x from
/// t = 0 to t = 2. Scene object i has pack id i + 1.
pub fn room(moving: bool) -> Scene {
    room_with(moving, true)
}

/// The room of [`room`] without its ceiling: a skylight 4 × 5 m open to the environment.
pub fn open_room() -> Scene {
    room_with(false, false)
}

/// The room of [`open_room`] with a ball hanging above its middle (high enough for the test
/// packs' low sun to reach it over the walls): a coarse UV sphere (12 × 6) whose vertex
/// normals are smooth, so that its shading normals differ from its facets' (which a renderer
/// shades with shows in the sun's light on it). The ball is the last object.
pub fn open_room_with_ball() -> Scene {
    let mut b = room_builder(false, false, true);
    let m = b.material(shapes::diffuse(Vec3::new(0.8, 0.7, 0.5)));
    b.object(
        "ball",
        shapes::uv_sphere(0.4, 12, 6),
        m,
        Vec3::new(-0.3, 1.6, -1.0),
    );
    b.build()
}

/// The window of [`windowed_room`] in the front wall (z = 2.5): x from −0.8 to 0.8, y from
/// 0.8 to 2.0.
pub const WINDOW: (Vec2, Vec2) = (Vec2::new(-0.8, 0.8), Vec2::new(0.8, 2.0));

/// The closed room of [`room`] (static) whose front wall has a [`WINDOW`] open to the
/// environment; with `glazing`, the window holds a pane of that base-colour alpha exported as
/// `alphaMode: BLEND`, as CAD/BIM tools write glass. The pane is the last object.
pub fn windowed_room(glazing: Option<f32>) -> Scene {
    let mut b = room_builder(false, true, false);
    let m = b.material(shapes::diffuse(Vec3::splat(0.7)));
    let (lo, hi) = WINDOW;
    let front = Quat::from_rotation_arc(Vec3::Y, Vec3::NEG_Z);
    let piece = |b: &mut shapes::SceneBuilder, name: &str, x: (f32, f32), y: (f32, f32), m| {
        b.object_trs(
            name,
            shapes::quad(Vec2::new(x.1 - x.0, y.1 - y.0)),
            m,
            plenoptic_scene::Trs {
                translation: Vec3::new(0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1), 2.5),
                rotation: front,
                scale: Vec3::ONE,
            },
        );
    };
    piece(&mut b, "front left", (-2.0, lo.x), (0.0, 2.6), m);
    piece(&mut b, "front right", (hi.x, 2.0), (0.0, 2.6), m);
    piece(&mut b, "sill", (lo.x, hi.x), (0.0, lo.y), m);
    piece(&mut b, "lintel", (lo.x, hi.x), (hi.y, 2.6), m);
    if let Some(alpha) = glazing {
        let mut glass = shapes::diffuse(Vec3::new(0.6, 0.75, 0.7));
        glass.base_color.w = alpha;
        glass.alpha_mode = plenoptic_scene::AlphaMode::Blend;
        let g = b.material(glass);
        piece(&mut b, "pane", (lo.x, hi.x), (lo.y, hi.y), g);
    }
    b.build()
}

/// [`windowed_room`] with its window glazed by a pane of clear transmissive glass
/// (`KHR_materials_transmission` 1, IOR 1.5) 1 cm thick: both faces in one mesh. The pane is
/// the last object; [`Materials::Glass`] writes its material.
pub fn glass_window_room() -> Scene {
    let mut b = room_builder(false, true, false);
    let m = b.material(shapes::diffuse(Vec3::splat(0.7)));
    let glass = b.material(shapes::glass(1.5, 0.0));
    let (lo, hi) = WINDOW;
    let front = Quat::from_rotation_arc(Vec3::Y, Vec3::NEG_Z);
    let place = |x: (f32, f32), y: (f32, f32)| plenoptic_scene::Trs {
        translation: Vec3::new(0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1), 2.5),
        rotation: front,
        scale: Vec3::ONE,
    };
    let quad = |x: (f32, f32), y: (f32, f32)| shapes::quad(Vec2::new(x.1 - x.0, y.1 - y.0));
    b.object_trs(
        "front left",
        quad((-2.0, lo.x), (0.0, 2.6)),
        m,
        place((-2.0, lo.x), (0.0, 2.6)),
    );
    b.object_trs(
        "front right",
        quad((hi.x, 2.0), (0.0, 2.6)),
        m,
        place((hi.x, 2.0), (0.0, 2.6)),
    );
    b.object_trs(
        "sill",
        quad((lo.x, hi.x), (0.0, lo.y)),
        m,
        place((lo.x, hi.x), (0.0, lo.y)),
    );
    b.object_trs(
        "lintel",
        quad((lo.x, hi.x), (hi.y, 2.6)),
        m,
        place((lo.x, hi.x), (hi.y, 2.6)),
    );
    // The back face 1 cm further out (the quad's local −y is the room's outside), wound the
    // other way.
    let mut pane = quad((lo.x, hi.x), (lo.y, hi.y));
    let back = pane.clone();
    let base = pane.positions.len() as u32;
    pane.positions
        .extend(back.positions.iter().map(|p| *p - Vec3::Y * 0.01));
    pane.normals.extend(back.normals.iter().map(|n| -*n));
    pane.uvs.extend(back.uvs.iter().copied());
    pane.triangles.extend(
        back.triangles
            .iter()
            .map(|t| [t[0] + base, t[2] + base, t[1] + base]),
    );
    b.object_trs("pane", pane, glass, place((lo.x, hi.x), (lo.y, hi.y)));
    b.build()
}

fn room_with(moving: bool, ceiling: bool) -> Scene {
    room_builder(moving, ceiling, true).build()
}

/// The room's builder: floor, walls (the front one if `front`), ceiling if `ceiling`, box,
/// pillar, the slider if `moving`, and the light.
fn room_builder(moving: bool, ceiling: bool, front: bool) -> shapes::SceneBuilder {
    let mut b = shapes::SceneBuilder::default();
    let m = b.material(shapes::diffuse(Vec3::splat(0.7)));
    let wall = |b: &mut shapes::SceneBuilder, name: &str, size: Vec2, pos: Vec3, n: Vec3| {
        let rot = if n.dot(Vec3::Y) < -0.999 {
            Quat::from_rotation_x(std::f32::consts::PI)
        } else {
            Quat::from_rotation_arc(Vec3::Y, n)
        };
        b.object_trs(
            name,
            shapes::quad(size),
            m,
            plenoptic_scene::Trs {
                translation: pos,
                rotation: rot,
                scale: Vec3::ONE,
            },
        );
    };
    wall(&mut b, "floor", Vec2::new(4.0, 5.0), Vec3::ZERO, Vec3::Y);
    if ceiling {
        wall(
            &mut b,
            "ceiling",
            Vec2::new(4.0, 5.0),
            Vec3::new(0.0, 2.6, 0.0),
            -Vec3::Y,
        );
    }
    wall(
        &mut b,
        "back",
        Vec2::new(4.0, 2.6),
        Vec3::new(0.0, 1.3, -2.5),
        Vec3::Z,
    );
    if front {
        wall(
            &mut b,
            "front",
            Vec2::new(4.0, 2.6),
            Vec3::new(0.0, 1.3, 2.5),
            -Vec3::Z,
        );
    }
    wall(
        &mut b,
        "left",
        Vec2::new(2.6, 5.0),
        Vec3::new(-2.0, 1.3, 0.0),
        Vec3::X,
    );
    wall(
        &mut b,
        "right",
        Vec2::new(2.6, 5.0),
        Vec3::new(2.0, 1.3, 0.0),
        -Vec3::X,
    );
    b.object(
        "box",
        shapes::cuboid(Vec3::splat(0.7)),
        m,
        Vec3::new(0.6, 0.35, -1.0),
    );
    b.object(
        "pillar",
        shapes::cuboid(Vec3::new(0.3, 1.6, 0.3)),
        m,
        Vec3::new(-0.9, 0.8, -0.6),
    );
    if moving {
        let id = b.object(
            "slider",
            shapes::cuboid(Vec3::new(0.5, 0.5, 0.5)),
            m,
            Vec3::new(-1.2, 0.25, -0.2),
        );
        b.animate_translation(
            id,
            &[
                (0.0, Vec3::new(-1.2, 0.25, -0.2)),
                (2.0, Vec3::new(1.2, 0.25, -0.2)),
            ],
        );
    }
    // A light so that the reference path tracer (benchmark) sees the room lit like `shade`.
    b.point_light(LIGHT, Vec3::ONE, 3.0);
    b
}

fn object_colour(id: u32) -> Vec3 {
    let h = id.wrapping_mul(2654435761);
    Vec3::new(
        0.35 + 0.6 * ((h & 255) as f32 / 255.0),
        0.35 + 0.6 * (((h >> 8) & 255) as f32 / 255.0),
        0.35 + 0.6 * (((h >> 16) & 255) as f32 / 255.0),
    )
}

/// One analytic hit as a pack stores it.
#[derive(Clone, Copy, Debug)]
pub struct Shaded {
    /// Radiance: `albedo · lighting + non_diffuse`.
    pub radiance: Vec3,
    /// Diffuse lighting (pack v2).
    pub lighting: Vec3,
    /// The view-dependent highlight (pack v2's non-diffuse part).
    pub non_diffuse: Vec3,
    /// Distance along the ray.
    pub distance: f32,
    /// Pack object id.
    pub object: u32,
    /// Normal facing the ray.
    pub normal: Vec3,
}

/// Deterministic shading of a hit seen along `ray`: object colour × object-space checker ×
/// (ambient + shadowed diffuse) + a view-dependent highlight.
pub fn shade(placed: &PlacedScene<'_>, ray: &Ray) -> Option<Shaded> {
    let hit = placed.intersect(ray)?;
    let local = placed
        .object_transform(hit.object)
        .inverse()
        .transform_point3(hit.position);
    let c = ((local * 4.0).floor().dot(Vec3::ONE) as i32).rem_euclid(2) as f32;
    let albedo = object_colour(hit.object) * (0.6 + 0.4 * c);
    let mut n = hit.geometric_normal.normalize();
    if n.dot(ray.direction) > 0.0 {
        n = -n;
    }
    let to_light = LIGHT - hit.position;
    let dl = to_light.length();
    let l = to_light / dl;
    let lit = !placed.segment_occluded(hit.offset_origin(l), LIGHT);
    let diffuse = if lit {
        n.dot(l).max(0.0) * 3.0 / (dl * dl)
    } else {
        0.0
    };
    let refl = (2.0 * n.dot(l) * n - l).normalize();
    let spec = if lit {
        refl.dot(-ray.direction).max(0.0).powi(12) * 0.6
    } else {
        0.0
    };
    let lighting = Vec3::splat(0.15 + diffuse);
    let non_diffuse = Vec3::splat(spec);
    Some(Shaded {
        radiance: albedo * lighting + non_diffuse,
        lighting,
        non_diffuse,
        distance: hit.distance,
        object: hit.object + 1,
        normal: n,
    })
}

/// Range image of face size `n` from `position` with the scene placed at `placed`.
pub fn range_image(placed: &PlacedScene<'_>, position: Vec3, n: u32) -> RangeImage {
    let img = Image::render(n, 6 * n, |x, y| {
        let i = (y * n + x) as usize;
        let dir = cube::texel_direction(n, i);
        shade(placed, &Ray::new(position, dir))
    });
    let mut r = RangeImage::new(n);
    for (i, s) in img.pixels.into_iter().enumerate() {
        if let Some(s) = s {
            r.radiance.texels[i] = s.radiance;
            r.lighting.texels[i] = s.lighting;
            r.non_diffuse.texels[i] = s.non_diffuse;
            r.distance.texels[i] = s.distance;
            r.object_id.texels[i] = s.object;
            r.normal.texels[i] = s.normal;
        }
    }
    r
}

/// The radiance of a reconstructed frame as the tracer's image type (for its metrics).
pub fn to_image(frame: &plenoptic_recon::Frame) -> Image<Vec3> {
    Image {
        width: frame.width,
        height: frame.height,
        pixels: frame.radiance.clone(),
    }
}

/// The reference image of a pinhole camera (1 ray per pixel centre, same shading).
pub fn reference(placed: &PlacedScene<'_>, camera: &plenoptic_recon::Camera) -> Image<Vec3> {
    let b = camera.basis();
    Image::render(camera.width, camera.height, |x, y| {
        let dir = b.direction(x as f32 + 0.5, y as f32 + 0.5);
        shade(placed, &Ray::new(camera.position, dir)).map_or(Vec3::ZERO, |s| s.radiance)
    })
}

/// What to put in a test pack.
#[derive(Clone, Debug)]
pub struct PackSpec {
    /// Base view positions.
    pub views: Vec<Vec3>,
    /// Time keys (the same for every view).
    pub keys: Vec<f32>,
    /// Cube face size.
    pub face: u32,
    /// Temporal-volume samples per view and bucket (0: none).
    pub volume_samples: usize,
    /// Time range.
    pub time: (f32, f32),
    /// Bucket span.
    pub bucket: f32,
    /// (view, key) pairs to leave out.
    pub skip: Vec<(usize, usize)>,
    /// Whether `BLEND` objects are written with their coverage (see-through at runtime, as
    /// the baker writes them) or without it (opaque proxies showing their baked texels).
    pub glazing: bool,
    /// Which materials the objects get.
    pub materials: Materials,
    /// Whether range images carry pack 2.0's lighting and non-diffuse cubes (false: only
    /// radiance, distance, id and normal, as a damaged pack might).
    pub lighting_chunks: bool,
    /// Whether the pack leaves the sun's direct light to the runtime (pack 3's
    /// `direct_sun`, with [`runtime_sun`] as the sun; a delta sun): the runtime adds it to the
    /// stored lighting with shadow rays. The stored texels are not changed, so this tests
    /// that both backends add the same light, not the physics.
    pub direct_sun: bool,
    /// Whether the pack places the analytic shading's light (a point light at [`LIGHT`]) and
    /// leaves its direct diffuse light to the runtime (pack 5's `lamps_at_runtime`): the
    /// runtime adds it to the stored lighting with shadow rays. The stored texels are not
    /// changed, so this tests that both backends add the same light, not the physics.
    pub runtime_lamps: bool,
}

/// The materials of a test pack's objects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Materials {
    /// None: every object shows its radiance.
    None,
    /// Each object's colour as its base-colour factor: the geometry-assisted mode shades it
    /// as that albedo × lighting + non-diffuse ([`plenoptic_recon::Shading::Materials`]).
    Factors,
    /// The factors times a 256 × 256 sRGB checker texture on planar proxy UVs. The analytic
    /// shading's own checker is not the texture's: for speed, not accuracy.
    Textured,
    /// [`Materials::Factors`], with the left wall an ideal mirror (metal, base 0.9) and the
    /// right wall glossy metal (roughness 0.3, base 0.8): the geometry-assisted mode marches
    /// their reflections for the camera ([`plenoptic_recon::Specular::Marched`]).
    Mirror,
    /// [`Materials::Factors`], with the object named `pane` clear glass (transmission 1, IOR
    /// 1.5, white, roughness 0): see-through in the geometry-assisted mode.
    Glass,
    /// [`Materials::Factors`] with a 64 × 64 normal map of stripes leaning ±30° on every
    /// object, on the planar UVs and one tangent off every axis: what the runtime sun's light
    /// shows of it tests that the backends bend the normal alike.
    Bumpy,
    /// [`Materials::Factors`], with the back wall emitting (factor (1, 0.7, 0.4)) through
    /// [`Materials::Textured`]'s checker as its emissive texture: the runtime adds the
    /// emission at each pixel's UV (pack 4).
    Glowing,
}

impl PackSpec {
    /// `count` base views evenly along the segment from (−1, 1.3, 1) to (1, 1.3, 1).
    pub fn segment(count: usize, keys: Vec<f32>, face: u32) -> Self {
        let (a, b) = segment_ends();
        let views = (0..count)
            .map(|i| {
                a.lerp(
                    b,
                    if count > 1 {
                        i as f32 / (count - 1) as f32
                    } else {
                        0.5
                    },
                )
            })
            .collect();
        PackSpec {
            views,
            keys,
            face,
            volume_samples: 0,
            time: (0.0, 2.0),
            bucket: 0.25,
            skip: Vec::new(),
            glazing: true,
            materials: Materials::None,
            lighting_chunks: true,
            direct_sun: false,
            runtime_lamps: false,
        }
    }
}

/// The test packs' sun: from low in the east (20,000 lx) at t = 0 to high (100,000 lx) at
/// t = 2.
pub fn moving_sun() -> plenoptic_pack::plenoptic_sky::SunTrack {
    use plenoptic_pack::plenoptic_sky::{SunTrack, SunTrackSample};
    SunTrack::new(vec![
        SunTrackSample {
            time: 0.0,
            direction: Vec3::new(1.0, 0.15, 0.2).normalize(),
            illuminance: Vec3::splat(20_000.0),
        },
        SunTrackSample {
            time: 2.0,
            direction: Vec3::new(-0.3, 1.0, -0.4).normalize(),
            illuminance: Vec3::splat(100_000.0),
        },
    ])
    .unwrap()
}

/// The sun of test packs with a runtime sun: [`moving_sun`]'s path at an illuminance of the
/// analytic shading's scale (1 at t = 0 to 3 at t = 2), so that it neither vanishes beside
/// the stored light nor leaves the f16 range of a GPU target.
pub fn runtime_sun() -> plenoptic_pack::plenoptic_sky::SunTrack {
    use plenoptic_pack::plenoptic_sky::{SunTrack, SunTrackSample};
    let m = moving_sun();
    SunTrack::new(
        [(0.0, 1.0), (2.0, 3.0)]
            .map(|(t, e)| SunTrackSample {
                time: t,
                direction: m.at(t).0,
                illuminance: Vec3::splat(e),
            })
            .to_vec(),
    )
    .unwrap()
}

/// Ends of the test view-space segment.
pub fn segment_ends() -> (Vec3, Vec3) {
    (Vec3::new(-1.0, 1.3, 1.0), Vec3::new(1.0, 1.3, 1.0))
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// Writes a pack of `scene` per `spec` to `path`.
pub fn write_pack(scene: &Scene, spec: &PackSpec, path: &Path) {
    write_pack_with(scene, spec, path, None);
}

/// [`write_pack`] with an environment entry (its image, if any, is written too).
pub fn write_pack_with(
    scene: &Scene,
    spec: &PackSpec,
    path: &Path,
    environment: Option<(
        plenoptic_pack::plenoptic_sky::Environment,
        Option<plenoptic_pack::plenoptic_sky::SunTrack>,
    )>,
) {
    let accel = SceneAccel::new(scene).unwrap();
    let mut w = PackWriter::create(path).unwrap();
    let placed: Vec<PlacedScene<'_>> = spec.keys.iter().map(|&t| accel.at_time(t)).collect();
    for (v, &pos) in spec.views.iter().enumerate() {
        for (k, p) in placed.iter().enumerate() {
            if spec.skip.contains(&(v, k)) {
                continue;
            }
            let image = range_image(p, pos, spec.face);
            if spec.lighting_chunks {
                w.add_range_image(v as u32, k as u32, &image, CubeFormats::default())
                    .unwrap();
            } else {
                use plenoptic_pack::*;
                let f = CubeFormats::default();
                let (v, k) = (v as u32, k as u32);
                let r = encode_radiance(&image.radiance, f.radiance).unwrap();
                w.add_chunk(ChunkKind::RadianceCube, v, k, &r).unwrap();
                let d = encode_distance(&image.distance, f.distance).unwrap();
                w.add_chunk(ChunkKind::DistanceCube, v, k, &d).unwrap();
                let o = encode_object_id(&image.object_id, f.object_id).unwrap();
                w.add_chunk(ChunkKind::ObjectIdCube, v, k, &o).unwrap();
                let n = encode_normal(&image.normal, f.normal).unwrap();
                w.add_chunk(ChunkKind::NormalCube, v, k, &n).unwrap();
            }
        }
    }
    let mut manifest = Manifest::new(
        TimeRange {
            start: spec.time.0,
            end: spec.time.1,
        },
        spec.bucket,
    );
    if spec.materials == Materials::Mirror || spec.runtime_lamps {
        // The shading function's light, placed (pack 4.1): the glossy wall's highlight of it
        // is evaluated at runtime (plenoptic_recon::lamps), and with `runtime_lamps` every
        // surface's diffuse light of it. The stored texels are not changed, so this tests that
        // both backends add the same light, not the physics.
        manifest.lamps_at_runtime = spec.runtime_lamps;
        manifest.lights.push(plenoptic_pack::Light {
            kind: plenoptic_pack::LightKind::Point,
            colour: Vec3::ONE,
            intensity: 3.0,
            follows_object: None,
            node_path: None,
            placed: Some(plenoptic_pack::LightPlacement {
                position: LIGHT,
                direction: Vec3::NEG_Y,
                range: None,
            }),
        });
    }
    if spec.volume_samples > 0 {
        let mut rng = Lcg(7);
        for (v, &pos) in spec.views.iter().enumerate() {
            for bucket in 0..manifest.bucket_count() {
                let (t0, t1) = manifest.bucket_range(bucket);
                let m = spec.volume_samples;
                let times: Vec<f32> = (0..m).map(|_| t0 + (t1 - t0) * rng.next()).collect();
                let dirs: Vec<Vec3> = (0..m)
                    .map(|_| {
                        let z = 2.0 * rng.next() - 1.0;
                        let phi = std::f32::consts::TAU * rng.next();
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        Vec3::new(r * phi.cos(), r * phi.sin(), z)
                    })
                    .collect();
                let radius = (4.0 * std::f32::consts::PI / m as f32).sqrt();
                let samples: Vec<VolumeSample> = (0..m)
                    .filter_map(|i| {
                        let p = accel.at_time(times[i]);
                        shade(&p, &Ray::new(pos, dirs[i])).map(|s| VolumeSample {
                            direction: dirs[i],
                            t: times[i],
                            radiance: s.radiance,
                            lighting: s.lighting,
                            non_diffuse: s.non_diffuse,
                            distance: s.distance,
                            normal: s.normal,
                            object_id: s.object,
                            radius,
                        })
                    })
                    .collect();
                w.add_volume_block(v as u32, bucket, (t0, t1), &samples, None)
                    .unwrap();
            }
        }
    }
    let mut tracks = AnimationTracks::default();
    for (i, obj) in scene.objects.iter().enumerate() {
        let id = i as u32 + 1;
        let animated = scene.object_is_animated(i as u32);
        let mesh = &scene.meshes[obj.mesh];
        let to_world = scene.object_transform(i as u32, 0.0);
        let positions = if animated {
            mesh.positions.clone()
        } else {
            mesh.positions
                .iter()
                .map(|&p| to_world.transform_point3(p))
                .collect()
        };
        // Vertex normals placed as the positions are (the normal matrix for static objects).
        let normal_matrix = to_world.matrix3.inverse().transpose();
        let normals = (mesh.normals.len() == mesh.positions.len()).then(|| {
            mesh.normals
                .iter()
                .map(|&n| {
                    if animated {
                        n
                    } else {
                        (normal_matrix * n).normalize_or(n)
                    }
                })
                .collect()
        });
        w.add_proxy_mesh(&ProxyMesh {
            object_id: id,
            positions: positions.clone(),
            indices: mesh.triangles.iter().flatten().copied().collect(),
            normals,
        })
        .unwrap();
        if animated {
            let track = scene.nodes[obj.node]
                .track
                .as_ref()
                .unwrap()
                .translation
                .as_ref()
                .unwrap();
            tracks.objects.push(ObjectTracks {
                object_id: id,
                translation: Some(Track {
                    interpolation: Interpolation::Linear,
                    times: track.keys.iter().map(|k| k.time).collect(),
                    values: track.keys.iter().map(|k| k.value).collect(),
                }),
                rotation: None,
                scale: None,
            });
        }
        if spec.materials != Materials::None {
            let uvs = positions
                .iter()
                .map(|p: &Vec3| Vec2::new(p.x + 0.5 * p.z, p.y - 0.5 * p.z))
                .collect();
            let bumpy = spec.materials == Materials::Bumpy;
            w.add_proxy_attributes(&plenoptic_pack::ProxyAttributes {
                object_id: id,
                uvs,
                tangents: if bumpy {
                    vec![Vec3::new(1.0, 0.3, 0.2).normalize().extend(1.0); positions.len()]
                } else {
                    Vec::new()
                },
            })
            .unwrap();
            let (base, metallic, roughness) = match (spec.materials, obj.name.as_str()) {
                (Materials::Mirror, "left") => (Vec3::splat(0.9), 1.0, 0.0),
                (Materials::Mirror, "right") => (Vec3::splat(0.8), 1.0, 0.3),
                (Materials::Glass, "pane") => (Vec3::ONE, 0.0, 0.0),
                _ => (object_colour(i as u32), 0.0, 0.5),
            };
            let glass = spec.materials == Materials::Glass && obj.name == "pane";
            let glowing = spec.materials == Materials::Glowing && obj.name == "back";
            manifest.materials.push(plenoptic_pack::MaterialEntry {
                base_colour: base.extend(1.0),
                emissive: if glowing {
                    Vec3::new(1.0, 0.7, 0.4)
                } else {
                    Vec3::ZERO
                },
                emissive_texture: glowing.then_some(plenoptic_pack::TextureBinding {
                    texture: 0,
                    wrap_s: Default::default(),
                    wrap_t: Default::default(),
                    transform: None,
                }),
                base_colour_texture: (spec.materials == Materials::Textured).then_some(
                    plenoptic_pack::TextureBinding {
                        texture: 0,
                        wrap_s: Default::default(),
                        wrap_t: Default::default(),
                        transform: None,
                    },
                ),
                metallic,
                roughness,
                normal_texture: (spec.materials == Materials::Bumpy).then_some(
                    plenoptic_pack::TextureBinding {
                        texture: 0,
                        wrap_s: Default::default(),
                        wrap_t: Default::default(),
                        transform: None,
                    },
                ),
                normal_scale: 1.0,
                transmission: if glass { 1.0 } else { 0.0 },
                ior: 1.5,
                ..Default::default()
            });
        }
        manifest.objects.push(ObjectEntry {
            id,
            name: obj.name.clone(),
            node_path: obj.node_path.clone(),
            motion: if animated {
                Motion::Animated
            } else {
                Motion::Static
            },
            proxy_mesh: Some(id),
            material: (spec.materials != Materials::None).then_some(i as u32),
            // BLEND objects of the test scenes are untextured: their coverage is the factor's.
            coverage: {
                let m = &scene.materials[obj.material];
                (spec.glazing && m.alpha_mode == plenoptic_scene::AlphaMode::Blend)
                    .then_some(m.base_color.w)
            },
        });
    }
    w.add_tracks(&tracks).unwrap();
    if matches!(
        spec.materials,
        Materials::Textured | Materials::Bumpy | Materials::Glowing
    ) {
        let (n, space, texels) = if spec.materials != Materials::Bumpy {
            let n = 256u32;
            let texels: Vec<u8> = (0..n * n)
                .flat_map(|i| {
                    let v = if ((i % n) / 8 + (i / n) / 8).is_multiple_of(2) {
                        230
                    } else {
                        90
                    };
                    [v, v, v, 255]
                })
                .collect();
            (n, plenoptic_pack::ColourSpace::Srgb, texels)
        } else {
            let n = 64u32;
            // (±sin 30°, 0, cos 30°) as 8-bit linear values.
            let texels = (0..n * n)
                .flat_map(|i| {
                    let x = if ((i % n) / 8).is_multiple_of(2) {
                        191
                    } else {
                        64
                    };
                    [x, 128, 238, 255]
                })
                .collect();
            (n, plenoptic_pack::ColourSpace::Linear, texels)
        };
        let texture = plenoptic_pack::TextureImage::with_mips(space, n, n, texels).unwrap();
        w.add_texture(0, &texture).unwrap();
        manifest.textures.push(plenoptic_pack::TextureEntry {
            width: n,
            height: n,
            levels: texture.levels.len() as u32,
            colour_space: space,
        });
    }
    let (a, b) = segment_ends();
    manifest.view_space = ViewSpace::Segment { a, b };
    manifest.base_views = spec
        .views
        .iter()
        .enumerate()
        .map(|(i, &p)| BaseView {
            id: i as u32,
            position: p,
            time_keys: spec.keys.clone(),
        })
        .collect();
    manifest.bake.cube_face_size = spec.face;
    let environment = match environment {
        None if spec.direct_sun => Some((
            plenoptic_pack::plenoptic_sky::Environment::None,
            Some(runtime_sun()),
        )),
        e => e,
    };
    if let Some((env, sun)) = environment {
        if let plenoptic_pack::plenoptic_sky::Environment::Image { image, .. } = &env {
            w.add_environment_image(image).unwrap();
        }
        let mut entry = plenoptic_pack::EnvironmentEntry::new(&env, sun);
        if spec.direct_sun {
            entry.direct_sun = Some(plenoptic_pack::DirectSun {
                angular_radius: 0.0,
            });
        }
        manifest.environment = Some(entry);
    }
    w.finish(&manifest).unwrap();
}

/// The cube image `cube` sampled (nearest) along every pixel direction of `camera`.
pub fn sample_cube(cube: &CubeImage<Vec3>, camera: &plenoptic_recon::Camera) -> Vec<Vec3> {
    let b = camera.basis();
    (0..camera.pixel_count())
        .map(|j| {
            let (x, y) = (
                (j % camera.width as usize) as f32 + 0.5,
                (j / camera.width as usize) as f32 + 0.5,
            );
            *cube.lookup(b.direction(x, y)).unwrap()
        })
        .collect()
}
