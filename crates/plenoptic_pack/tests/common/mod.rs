//! Shared fixtures: a fully populated manifest, smooth synthetic range images and volume
//! samples, and a small complete pack.
#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use plenoptic_pack::*;

/// Deterministic xorshift PRNG.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn direction(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.unit(), self.unit(), self.unit()) * 2.0 - Vec3::ONE;
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

pub fn manifest(base_views: usize) -> Manifest {
    let mut m = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 2.0,
        },
        0.5,
    );
    m.scene_bounds = Aabb {
        min: Vec3::new(-3.0, 0.0, -4.0),
        max: Vec3::new(3.0, 2.7, 4.0),
    };
    m.view_space = ViewSpace::Rectangle {
        corners: [
            Vec3::new(-1.0, 1.6, -1.0),
            Vec3::new(1.0, 1.6, -1.0),
            Vec3::new(1.0, 1.6, 1.0),
            Vec3::new(-1.0, 1.6, 1.0),
        ],
    };
    m.base_views = (0..base_views)
        .map(|i| BaseView {
            id: 100 + i as u32,
            position: Vec3::new(i as f32 * 0.5 - 1.0, 1.6, 0.1 * i as f32),
            time_keys: vec![0.0, 0.75, 2.0],
        })
        .collect();
    m.objects = vec![
        ObjectEntry {
            id: 1,
            name: "walls".into(),
            node_path: "/Scene/Room/Walls".into(),
            motion: Motion::Static,
            proxy_mesh: Some(1),
            material: None,
            coverage: None,
        },
        ObjectEntry {
            id: 2,
            name: "chair".into(),
            node_path: "/Scene/Room/Chair".into(),
            motion: Motion::Animated,
            proxy_mesh: Some(2),
            material: None,
            coverage: None,
        },
    ];
    m.lights = vec![
        Light {
            kind: LightKind::Spot {
                inner_cone: 0.3,
                outer_cone: 0.6,
            },
            colour: Vec3::new(1.0, 0.9, 0.8),
            intensity: 800.0,
            follows_object: Some(2),
            node_path: Some("/Scene/Lamp".into()),
            placed: None,
        },
        Light {
            kind: LightKind::Point,
            colour: Vec3::new(1.0, 0.8, 0.6),
            intensity: 20.0,
            follows_object: None,
            node_path: Some("/Scene/Bulb".into()),
            placed: Some(plenoptic_pack::LightPlacement {
                position: Vec3::new(0.5, 2.2, -1.0),
                direction: Vec3::NEG_Y,
                range: Some(8.0),
            }),
        },
        Light {
            kind: LightKind::Area {
                width: 1.2,
                height: 0.8,
            },
            colour: Vec3::ONE,
            intensity: 12.5,
            follows_object: None,
            node_path: None,
            placed: None,
        },
        Light {
            kind: LightKind::Directional,
            colour: Vec3::new(1.0, 0.95, 0.9),
            intensity: 3.0,
            follows_object: None,
            node_path: Some("/Scene/Sun".into()),
            placed: None,
        },
    ];
    m.bake = BakeSettings {
        quality: 0.9,
        cube_face_size: 16,
        samples_per_texel: 64,
        volume_samples_per_view: 10_000,
        extra: BTreeMap::from([("recipe".to_string(), "room".to_string())]),
    };
    m.stats = BakeStatistics {
        phase_seconds: BTreeMap::from([("range_images".to_string(), 12.345_678_9)]),
        sample_counts: BTreeMap::from([("camera_rays".to_string(), 123_456_789_012)]),
        bytes: BTreeMap::from([("radiance".to_string(), 98_765)]),
    };
    m
}

/// A procedural room seen from its centre: analytic distance to an axis-aligned box room, a
/// few surfaces with their own ids, smooth light falloff and a bright window.
pub fn room_image(n: u32, phase: f32) -> RangeImage {
    let half = Vec3::new(3.0, 1.4, 4.0);
    let mut img = RangeImage::new(n);
    let mut dist = Vec::new();
    let mut ids = Vec::new();
    let mut normals = Vec::new();
    let mut rad = Vec::new();
    let mut lighting = Vec::new();
    let mut non_diffuse = Vec::new();
    for i in 0..6 * (n as usize).pow(2) {
        let d = plenoptic_pack::cube::texel_direction(n, i);
        // Distance to the room's walls along d.
        let ratios = half / d.abs().max(Vec3::splat(1e-9));
        let t = ratios.min_element();
        let p = d * t;
        let axis = if ratios.x == t {
            0
        } else if ratios.y == t {
            1
        } else {
            2
        };
        let mut normal = Vec3::ZERO;
        normal[axis] = -d[axis].signum();
        let mut id = 1 + axis as u32 * 2 + (d[axis] > 0.0) as u32;
        let mut dist_v = t;
        // A box (table) in front: a depth discontinuity.
        let table_t = (0.9 - 0.0) / d.z.max(1e-6);
        let q = d * table_t;
        if d.z > 0.2 && q.x.abs() < 0.6 && q.y < -0.2 && q.y > -0.8 {
            dist_v = table_t;
            id = 9;
            normal = -Vec3::Z;
        }
        let light = Vec3::new(0.5 + phase, 1.2, 0.0);
        let hit = d * dist_v;
        let falloff = 2.0 / (1.0 + (hit - light).length_squared());
        let albedo = Vec3::new(0.6 + 0.05 * id as f32, 0.55, 0.5 - 0.03 * id as f32);
        let mut r = albedo * falloff;
        let mut l = Vec3::splat(falloff);
        let mut e = Vec3::ZERO;
        // A bright window on the +X wall.
        if axis == 0 && d.x > 0.0 && p.y.abs() < 0.5 && p.z.abs() < 1.0 {
            r = Vec3::new(40.0, 38.0, 35.0);
            (l, e) = (Vec3::ZERO, r);
            id = 20;
        }
        lighting.push(l);
        non_diffuse.push(e);
        dist.push(dist_v);
        ids.push(id);
        normals.push(normal);
        rad.push(r);
    }
    img.radiance.texels = rad;
    img.lighting.texels = lighting;
    img.non_diffuse.texels = non_diffuse;
    img.distance.texels = dist;
    img.object_id.texels = ids;
    img.normal.texels = normals;
    img
}

pub fn volume_samples(count: usize, t0: f32, t1: f32, seed: u64) -> Vec<VolumeSample> {
    let mut rng = Rng(seed | 1);
    (0..count)
        .map(|i| VolumeSample {
            direction: rng.direction(),
            t: t0 + (t1 - t0) * rng.unit(),
            radiance: Vec3::new(rng.unit() * 10.0, rng.unit(), rng.unit() * 0.1),
            lighting: Vec3::new(rng.unit() * 4.0, rng.unit(), rng.unit() * 0.5),
            non_diffuse: Vec3::new(rng.unit() * 0.2, 0.0, rng.unit()),
            distance: 0.5 + rng.unit() * 8.0,
            normal: rng.direction(),
            object_id: (i % 7) as u32,
            radius: 0.001 + rng.unit() * 0.05,
        })
        .collect()
}

pub fn proxy_mesh(object_id: u32, with_normals: bool) -> ProxyMesh {
    ProxyMesh {
        object_id,
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.5, 0.0),
            Vec3::new(0.25, 0.125, -3.5),
        ],
        indices: vec![0, 1, 2, 2, 1, 3],
        normals: with_normals.then(|| vec![Vec3::Z, Vec3::Z, Vec3::Y, -Vec3::X]),
    }
}

pub fn tracks() -> AnimationTracks {
    AnimationTracks {
        objects: vec![
            ObjectTracks {
                object_id: 2,
                translation: Some(Track {
                    interpolation: Interpolation::Linear,
                    times: vec![0.0, 1.0, 2.0],
                    values: vec![Vec3::ZERO, Vec3::new(0.5, 0.0, 0.25), Vec3::X],
                }),
                rotation: Some(Track {
                    interpolation: Interpolation::CubicSpline,
                    times: vec![0.0, 2.0],
                    values: vec![
                        Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
                        Quat::IDENTITY,
                        Quat::from_xyzw(0.0, 0.1, 0.0, 0.0),
                        Quat::from_xyzw(0.0, 0.2, 0.0, 0.0),
                        Quat::from_rotation_y(1.0),
                        Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
                    ],
                }),
                scale: None,
            },
            ObjectTracks {
                object_id: 3,
                translation: None,
                rotation: None,
                scale: Some(Track {
                    interpolation: Interpolation::Step,
                    times: vec![0.5],
                    values: vec![Vec3::splat(2.0)],
                }),
            },
        ],
    }
}

/// Writes a small pack with every chunk kind to `path`; returns the manifest.
pub fn write_small_pack(path: &std::path::Path) -> Manifest {
    let m = manifest(2);
    let mut w = PackWriter::create(path).unwrap();
    for v in 0..2u32 {
        for k in 0..2u32 {
            w.add_range_image(v, k, &room_image(8, k as f32 * 0.3), CubeFormats::default())
                .unwrap();
        }
        let s = volume_samples(64, 0.0, 0.5, 7 + v as u64);
        let tets: Vec<[u32; 4]> = (0..20u32).map(|i| [i, i + 1, i + 2, i + 3]).collect();
        w.add_volume_block(v, 0, (0.0, 0.5), &s, Some(&tets))
            .unwrap();
    }
    w.add_proxy_mesh(&proxy_mesh(1, true)).unwrap();
    w.add_proxy_mesh(&proxy_mesh(2, false)).unwrap();
    w.add_tracks(&tracks()).unwrap();
    w.finish(&m).unwrap();
    m
}

/// Reads and decodes every chunk, and every texture and proxy's attributes through their
/// checked accessors; returns how many chunks decoded.
pub fn read_all(r: &PackReader) -> usize {
    for i in 0..r.textures().len() {
        let _ = r.texture(i as u32);
    }
    for o in &r.manifest().objects {
        let _ = r.proxy_attributes(o.id);
        let _ = r.object_material(o.id);
    }
    (0..r.entries().len())
        .filter(|&i| r.chunk(i).is_ok())
        .count()
}

/// A `n × n` RGBA8 checker of 1-texel cells: RGB 0 and 255, alpha 255 and 0 (alpha opposite).
pub fn checker(n: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity((n * n * 4) as usize);
    for y in 0..n {
        for x in 0..n {
            let v = if (x + y) % 2 == 0 { 0 } else { 255 };
            out.extend([v, v, v, 255 - v]);
        }
    }
    out
}

/// A texture whose every texel differs: a gradient in R and G, noise in B, alpha from both.
pub fn gradient(w: u32, h: u32) -> Vec<u8> {
    let mut rng = Rng(99);
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            out.extend([
                (x * 255 / w.max(2).saturating_sub(1).max(1)) as u8,
                (y * 255 / h.max(2).saturating_sub(1).max(1)) as u8,
                rng.next_u64() as u8,
                ((x + y) * 7) as u8,
            ]);
        }
    }
    out
}

/// The materials of [`write_material_pack`]: a textured one with every slot, an untextured
/// one, and texture 0 shared by two materials.
pub fn materials() -> (Vec<TextureEntry>, Vec<MaterialEntry>) {
    let bind = |texture| TextureBinding {
        texture,
        wrap_s: WrapMode::Repeat,
        wrap_t: WrapMode::MirroredRepeat,
        transform: None,
    };
    let textures = vec![
        TextureEntry {
            width: 64,
            height: 64,
            levels: 7,
            colour_space: ColourSpace::Srgb,
        },
        TextureEntry {
            width: 16,
            height: 4,
            levels: 5,
            colour_space: ColourSpace::Linear,
        },
    ];
    let full = MaterialEntry {
        name: "tiles".into(),
        base_colour: glam::Vec4::new(0.9, 0.8, 0.7, 0.5),
        base_colour_texture: Some(TextureBinding {
            transform: Some(UvTransform {
                offset: glam::Vec2::new(0.25, -0.5),
                rotation: 0.3,
                scale: glam::Vec2::new(2.0, 3.0),
            }),
            ..bind(0)
        }),
        metallic: 0.25,
        roughness: 0.625,
        metallic_roughness_texture: Some(bind(1)),
        normal_texture: Some(bind(1)),
        normal_scale: 0.75,
        emissive: Vec3::new(2.0, 0.0, 5.5),
        emissive_texture: Some(bind(0)),
        transmission: 0.5,
        ior: 1.45,
        thickness: 0.01,
        double_sided: true,
        alpha_mode: AlphaMode::Mask { cutoff: 0.3 },
    };
    let plain = MaterialEntry {
        name: "plain".into(),
        alpha_mode: AlphaMode::Blend,
        ..MaterialEntry::default()
    };
    (textures, vec![full, plain])
}

/// The UVs and tangents of [`proxy_mesh`] (4 vertices).
pub fn proxy_attributes(object_id: u32) -> ProxyAttributes {
    ProxyAttributes {
        object_id,
        uvs: vec![
            glam::Vec2::new(0.0, 0.0),
            glam::Vec2::new(1.0, 0.0),
            glam::Vec2::new(0.0, 1.5),
            glam::Vec2::new(-0.25, 7.0),
        ],
        tangents: vec![
            glam::Vec4::new(1.0, 0.0, 0.0, 1.0),
            glam::Vec4::new(1.0, 0.0, 0.0, 1.0),
            glam::Vec4::new(0.0, 1.0, 0.0, -1.0),
            glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
        ],
    }
}

/// [`write_small_pack`] plus materials (1.2): two textures, two materials (object 1 textured,
/// object 2 plain), and UVs and tangents for object 1's proxy. Returns the manifest.
pub fn write_material_pack(path: &std::path::Path) -> Manifest {
    let mut m = manifest(2);
    let mut w = PackWriter::create(path).unwrap();
    w.add_range_image(0, 0, &room_image(4, 0.0), CubeFormats::default())
        .unwrap();
    w.add_proxy_mesh(&proxy_mesh(1, true)).unwrap();
    w.add_proxy_mesh(&proxy_mesh(2, false)).unwrap();
    w.add_proxy_attributes(&proxy_attributes(1)).unwrap();
    let t0 = TextureImage::with_mips(ColourSpace::Srgb, 64, 64, checker(64)).unwrap();
    let t1 = TextureImage::with_mips(ColourSpace::Linear, 16, 4, gradient(16, 4)).unwrap();
    w.add_texture(0, &t0).unwrap();
    w.add_texture(1, &t1).unwrap();
    let (textures, materials) = materials();
    m.textures = textures;
    m.materials = materials;
    m.objects[0].material = Some(0);
    m.objects[1].material = Some(1);
    w.finish(&m).unwrap();
    m
}

/// Writes a pack with two light groups ([`plenoptic_pack::groups`]): two range images and a
/// volume block, each with both groups' layers; returns the manifest.
pub fn write_group_pack(path: &std::path::Path) -> Manifest {
    let mut m = manifest(1);
    m.light_groups = Some(LightGroupsEntry {
        names: vec!["lamp".into(), "daylight".into()],
        lights: vec![None; m.lights.len()],
        objects: vec![Some(0); m.objects.len()],
        sun: Some(1),
        sky: Some(1),
        default_has_emitters: true,
    });
    let mut w = PackWriter::create(path).unwrap();
    for k in 0..2u32 {
        let image = room_image(4, k as f32 * 0.3);
        w.add_range_image(0, k, &image, CubeFormats::default())
            .unwrap();
        for g in 0..2u32 {
            let share = |c: &CubeImage<glam::Vec3>| CubeImage {
                face_size: c.face_size,
                texels: c
                    .texels
                    .iter()
                    .map(|t| *t * (0.25 + 0.5 * g as f32))
                    .collect(),
            };
            let l = encode_radiance(&share(&image.lighting), RadianceFormat::Rgb9e5).unwrap();
            w.add_chunk(ChunkKind::GroupLighting(g), 0, k, &l).unwrap();
            let n = encode_radiance(&share(&image.non_diffuse), RadianceFormat::Rgb9e5).unwrap();
            w.add_chunk(ChunkKind::GroupNonDiffuse(g), 0, k, &n)
                .unwrap();
        }
    }
    let s = volume_samples(32, 0.0, 0.5, 3);
    let order = w.add_volume_block(0, 0, (0.0, 0.5), &s, None).unwrap();
    for g in 0..2u32 {
        let values: Vec<[glam::Vec3; 2]> = s
            .iter()
            .map(|x| [x.lighting * (0.25 + 0.5 * g as f32), x.non_diffuse * 0.5])
            .collect();
        let (bytes, len) = groups::encode_group_volume(&values, &order).unwrap();
        w.add_raw_chunk(ChunkKind::GroupVolume(g), 0, 0, &bytes, len, None)
            .unwrap();
    }
    w.add_proxy_mesh(&proxy_mesh(1, true)).unwrap();
    w.finish(&m).unwrap();
    m
}
