//! Range-image chunks of a radiance pack are complete KTX2 files: Bevy's own KTX2 loader
//! (`bevy_image` with `ktx2` and `zstd_rust`) must open each of the six cube kinds as a cube
//! `Image` with the texels the baker wrote, and (pack 1.2) each material texture as a 2-D
//! `Image` with its whole mip chain.

use std::time::Duration;

use bevy::{
    asset::{AssetPlugin, LoadState, RenderAssetUsages},
    image::{CompressedImageFormats, ImageLoader, ImageSampler, ImageType},
    prelude::*,
    render::render_resource::{TextureFormat, TextureViewDimension},
};
use plenoptic_pack::{
    BaseView, ChunkKind, CubeFormats, CubeImage, Manifest, PackReader, PackWriter, RangeImage,
    TimeRange, cube::rgb9e5_pack,
};
use plenoptic_pack::{ColourSpace, TextureEntry, TextureImage};

const FACE: u32 = 8;

/// A range image with a different value in every texel: radiance and distance vary with the
/// direction, ids change per face.
fn range_image() -> RangeImage {
    RangeImage {
        radiance: CubeImage::from_fn(FACE, |_, d| {
            Vec3::new(d.x.abs() * 4.0, d.y.abs(), 0.25 + d.z.abs() * 100.0)
        }),
        lighting: CubeImage::from_fn(FACE, |_, d| Vec3::new(0.5 + d.x.abs(), d.y.abs(), 2.0)),
        non_diffuse: CubeImage::from_fn(FACE, |_, d| Vec3::new(0.0, d.z.abs() * 3.0, 0.1)),
        distance: CubeImage::from_fn(FACE, |i, d| 1.0 + i as f32 * 0.01 + d.x.abs()),
        object_id: CubeImage::from_fn(FACE, |i, _| {
            (i as u32 / (FACE * FACE)) * 1000 + i as u32 % 7
        }),
        normal: CubeImage::from_fn(FACE, |_, d| -d),
    }
}

/// Writes a one-view pack and returns the raw bytes of its six range-image chunks, read back
/// through the pack reader (so the checksum path is exercised too).
fn chunks(dir: &std::path::Path) -> Vec<(ChunkKind, Vec<u8>)> {
    let path = dir.join("one.pack");
    let mut writer = PackWriter::create(&path).unwrap();
    writer
        .add_range_image(0, 0, &range_image(), CubeFormats::default())
        .unwrap();
    let mut manifest = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 1.0,
        },
        1.0,
    );
    manifest.base_views.push(BaseView {
        id: 0,
        position: Vec3::ZERO,
        time_keys: vec![0.0],
    });
    writer.finish(&manifest).unwrap();
    let reader = PackReader::open(&path).unwrap();
    [
        ChunkKind::RadianceCube,
        ChunkKind::LightingCube,
        ChunkKind::NonDiffuseCube,
        ChunkKind::DistanceCube,
        ChunkKind::ObjectIdCube,
        ChunkKind::NormalCube,
    ]
    .into_iter()
    .map(|kind| {
        let index = reader.find(kind, 0, 0).expect("chunk written");
        (kind, reader.chunk_bytes(index).unwrap())
    })
    .collect()
}

fn load_with_bevy(bytes: &[u8]) -> Image {
    load_with_bevy_srgb(bytes, false)
}

fn load_with_bevy_srgb(bytes: &[u8], is_srgb: bool) -> Image {
    Image::from_buffer(
        bytes,
        ImageType::Extension("ktx2"),
        CompressedImageFormats::NONE,
        is_srgb,
        ImageSampler::Default,
        RenderAssetUsages::default(),
    )
    .expect("Bevy's KTX2 loader accepts the chunk")
}

fn words(data: &[u8]) -> Vec<u32> {
    data.chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
        .collect()
}

#[test]
fn every_range_image_chunk_loads_as_a_bevy_cubemap() {
    let dir = tempfile::tempdir().unwrap();
    let expected = range_image();
    let texels = (6 * FACE * FACE) as usize;
    for (kind, bytes) in chunks(dir.path()) {
        let image = load_with_bevy(&bytes);
        let size = image.texture_descriptor.size;
        assert_eq!((size.width, size.height), (FACE, FACE), "{kind:?}");
        assert_eq!(size.depth_or_array_layers, 6, "{kind:?}: six faces");
        let view = image.texture_view_descriptor.as_ref().expect("a view");
        assert_eq!(view.dimension, Some(TextureViewDimension::Cube), "{kind:?}");
        let data = image.data.as_ref().expect("texels on the CPU");
        match kind {
            ChunkKind::RadianceCube => {
                assert_eq!(image.texture_descriptor.format, TextureFormat::Rgb9e5Ufloat);
                let want: Vec<u32> = expected
                    .radiance
                    .texels
                    .iter()
                    .map(|&c| rgb9e5_pack(c))
                    .collect();
                assert_eq!(words(data), want);
            }
            ChunkKind::LightingCube | ChunkKind::NonDiffuseCube => {
                assert_eq!(image.texture_descriptor.format, TextureFormat::Rgb9e5Ufloat);
                let cube = if kind == ChunkKind::LightingCube {
                    &expected.lighting
                } else {
                    &expected.non_diffuse
                };
                let want: Vec<u32> = cube.texels.iter().map(|&c| rgb9e5_pack(c)).collect();
                assert_eq!(words(data), want);
            }
            ChunkKind::DistanceCube => {
                assert_eq!(image.texture_descriptor.format, TextureFormat::R32Float);
                let got: Vec<f32> = words(data).into_iter().map(f32::from_bits).collect();
                assert_eq!(got, expected.distance.texels);
            }
            ChunkKind::ObjectIdCube => {
                assert_eq!(image.texture_descriptor.format, TextureFormat::R32Uint);
                assert_eq!(words(data), expected.object_id.texels);
            }
            ChunkKind::NormalCube => {
                assert_eq!(image.texture_descriptor.format, TextureFormat::Rg16Snorm);
                assert_eq!(data.len(), texels * 4);
                // Octahedral decode of Bevy's texels gives back the normals to 16-bit precision.
                for (i, pair) in data.chunks_exact(4).enumerate() {
                    let x = i16::from_le_bytes([pair[0], pair[1]]) as f32 / 32767.0;
                    let y = i16::from_le_bytes([pair[2], pair[3]]) as f32 / 32767.0;
                    let n = plenoptic_pack::cube::oct_decode(Vec2::new(x, y));
                    let angle = n.angle_between(expected.normal.texels[i]);
                    assert!(angle < 1e-3, "texel {i}: {angle} rad");
                }
            }
            other => unreachable!("{other:?}"),
        }
    }
}

/// The same chunk through the asset server, as a game would load an extracted `.ktx2`.
#[test]
fn asset_server_loads_an_extracted_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let (_, radiance) = chunks(dir.path()).swap_remove(0);
    std::fs::write(dir.path().join("radiance.ktx2"), radiance).unwrap();

    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin {
            file_path: dir.path().to_string_lossy().into_owned(),
            ..default()
        },
        ImagePlugin::default(),
    ));
    // `ImagePlugin` only pre-registers the loader; the render plugin registers it once it knows
    // the GPU's compressed formats. Without a GPU, register it as the render plugin does.
    app.register_asset_loader(ImageLoader::new(CompressedImageFormats::NONE));
    app.finish();
    app.cleanup();
    let handle: Handle<Image> = app.world().resource::<AssetServer>().load("radiance.ktx2");
    for _ in 0..500 {
        app.update();
        let state = app.world().resource::<AssetServer>().load_state(&handle);
        if let LoadState::Failed(err) = state {
            panic!("load failed: {err}");
        }
        if state.is_loaded() {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let state = app.world().resource::<AssetServer>().load_state(&handle);
    let images = app.world().resource::<Assets<Image>>();
    let image = images
        .get(&handle)
        .unwrap_or_else(|| panic!("not loaded: {state:?}"));
    assert_eq!(image.texture_descriptor.size.depth_or_array_layers, 6);
    assert_eq!(image.texture_descriptor.format, TextureFormat::Rgb9e5Ufloat);
}

/// A material-texture chunk (pack 1.2) loads as a 2-D image with its full mip chain in Bevy's
/// mip-major order; Bevy takes sRGB-ness from the loader's `is_srgb` (the pack's
/// `ColourSpace::is_srgb`), not from the vkFormat.
#[test]
fn material_texture_chunks_load_as_mipmapped_bevy_images() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("textures.pack");
    let checker: Vec<u8> = (0..64u32 * 64)
        .flat_map(|i| {
            let v = if (i % 64 + i / 64).is_multiple_of(2) {
                0
            } else {
                255
            };
            [v, v, v, 255]
        })
        .collect();
    let gradient: Vec<u8> = (0..32 * 8).flat_map(|i| [i as u8, 7, 200, 255]).collect();
    let textures = [
        TextureImage::with_mips(ColourSpace::Srgb, 64, 64, checker).unwrap(),
        TextureImage::with_mips(ColourSpace::Linear, 32, 8, gradient).unwrap(),
    ];
    let mut writer = PackWriter::create(&path).unwrap();
    let mut manifest = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 1.0,
        },
        1.0,
    );
    for (i, t) in textures.iter().enumerate() {
        writer.add_texture(i as u32, t).unwrap();
        manifest.textures.push(TextureEntry {
            width: t.width(),
            height: t.height(),
            levels: t.levels.len() as u32,
            colour_space: t.colour_space,
        });
    }
    writer.finish(&manifest).unwrap();
    let reader = PackReader::open(&path).unwrap();
    for (i, t) in textures.iter().enumerate() {
        let bytes = reader.texture_ktx2(i as u32).unwrap();
        let image = load_with_bevy_srgb(&bytes, t.colour_space.is_srgb());
        let d = &image.texture_descriptor;
        assert_eq!((d.size.width, d.size.height), (t.width(), t.height()));
        assert_eq!(d.size.depth_or_array_layers, 1);
        assert_eq!(d.mip_level_count, t.levels.len() as u32);
        assert_eq!(
            d.dimension,
            bevy::render::render_resource::TextureDimension::D2
        );
        assert_eq!(
            d.format,
            if t.colour_space.is_srgb() {
                TextureFormat::Rgba8UnormSrgb
            } else {
                TextureFormat::Rgba8Unorm
            }
        );
        assert!(image.texture_view_descriptor.is_none(), "no cube view");
        let want: Vec<u8> = t.levels.iter().flat_map(|l| l.texels.clone()).collect();
        assert_eq!(image.data.as_deref(), Some(want.as_slice()));
    }
}
