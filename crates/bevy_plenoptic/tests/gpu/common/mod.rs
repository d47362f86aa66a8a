//! Headless rendering harness shared by the GPU tests: an app without a window whose camera
//! renders into an image that is read back to the CPU. Also included (by `#[path]`) by the
//! facade package's plugin tests (`tests/plugin_*.rs` at the workspace root), which build
//! their packs through the tracer.
#![allow(dead_code, reason = "each test binary uses a part of it")]

use std::sync::{Arc, Mutex};

use bevy::{
    camera::RenderTarget,
    core_pipeline::tonemapping::Tonemapping,
    prelude::*,
    render::{
        gpu_readback::{Readback, ReadbackComplete},
        render_resource::{TextureFormat, TextureUsages},
    },
    window::ExitCondition,
};

/// Size of the off-screen target.
pub const WIDTH: u32 = 64;
/// Size of the off-screen target.
pub const HEIGHT: u32 = 48;

/// An app on the default plugins with no window, rendering on whatever adapter wgpu finds
/// (Mesa's lavapipe on CI).
pub fn headless_app() -> App {
    let mut app = App::new();
    app.add_plugins(headless_plugins());
    app
}

/// `DefaultPlugins` without a window (and without winit's event loop, which must run on the
/// main thread and needs a display, when the `winit` feature is on), recording shader
/// compile errors for [`assert_shaders_compile`].
#[allow(
    unexpected_cfgs,
    reason = "each package that includes this file has one of the two window features"
)]
pub fn headless_plugins() -> bevy::app::PluginGroupBuilder {
    let plugins = DefaultPlugins
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        })
        .build();
    // `winit` is this crate's feature; `window` the facade package's (its default), which
    // turns on the same Bevy window backend when the facade's tests include this file.
    #[cfg(any(feature = "winit", feature = "window"))]
    let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
    plugins.add(ShaderErrorsPlugin)
}

/// Like [`headless_app`], with assets read from `dir` and the plenoptic plugin added
/// (finished and cleaned up, ready to update).
pub fn headless_app_in(dir: &std::path::Path) -> App {
    let mut app = App::new();
    app.add_plugins((
        headless_plugins().set(AssetPlugin {
            file_path: dir.to_string_lossy().into_owned(),
            ..default()
        }),
        bevy_plenoptic::PlenopticPlugin,
    ));
    app.finish();
    app.cleanup();
    app
}

/// A `WIDTH` × `HEIGHT` `Rgba16Float` render target that can be read back.
pub fn hdr_target(app: &mut App) -> Handle<Image> {
    let mut img = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba16Float, None);
    img.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    app.world_mut().resource_mut::<Assets<Image>>().add(img)
}

/// Creates the render target image and returns the camera's target for it.
pub fn target_image(images: &mut Assets<Image>) -> Handle<Image> {
    let mut image = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba8Unorm, None);
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    images.add(image)
}

/// A 3D camera that renders into `image` with no tonemapping and an exposure multiplier of
/// 1 ([`bevy_plenoptic::camera::EV100_UNIT`]), so colours reach the target unchanged.
pub fn camera_into(image: Handle<Image>, transform: Transform) -> impl Bundle {
    (
        Camera3d::default(),
        bevy::camera::Exposure {
            ev100: bevy_plenoptic::camera::EV100_UNIT,
        },
        Camera {
            clear_color: ClearColorConfig::Custom(Color::linear_rgb(1.0, 0.0, 0.0)),
            ..default()
        },
        RenderTarget::Image(image.into()),
        Tonemapping::None,
        transform,
    )
}

/// Reads `image` back every frame and returns the pixels (RGBA8, row by row) of the first
/// frame for which `ready` holds, or of the last frame after `max_frames`. Pipelines compile
/// asynchronously (slowly on the software driver), so the first frames may show only the
/// clear colour; `ready` says when the scene is on screen.
pub fn render_until(
    app: &mut App,
    image: Handle<Image>,
    max_frames: u32,
    ready: impl Fn(&[u8]) -> bool,
) -> Vec<u8> {
    let latest: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let sink = latest.clone();
    app.world_mut()
        .spawn(Readback::texture(image))
        .observe(move |event: On<ReadbackComplete>| {
            *sink.lock().unwrap() = Some(event.data.clone());
        });
    let mut last = None;
    for _ in 0..max_frames {
        app.update();
        assert_shaders_compile(app);
        if let Some(data) = latest.lock().unwrap().take() {
            if ready(&data) {
                return data;
            }
            last = Some(data);
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    last.unwrap_or_else(|| panic!("no readback in {max_frames} frames"))
}

/// The first pipeline error the render world met, shared with the main world (the render
/// sub-app runs on its own thread with pipelined rendering).
#[derive(Resource, Clone, Default)]
pub struct ShaderErrors(Arc<Mutex<Option<String>>>);

/// How many pipelines the render world's cache was still compiling at its last frame, shared
/// with the main world as [`ShaderErrors`] is.
#[derive(Resource, Clone, Default)]
pub struct PipelinesWaiting(Arc<std::sync::atomic::AtomicUsize>);

/// Records in [`ShaderErrors`] the first pipeline whose shader failed to compile.
struct ShaderErrorsPlugin;

impl Plugin for ShaderErrorsPlugin {
    fn build(&self, app: &mut App) {
        use bevy::render::{Render, RenderApp, RenderSystems};
        let errors = ShaderErrors::default();
        let waiting = PipelinesWaiting::default();
        app.insert_resource(errors.clone())
            .insert_resource(waiting.clone());
        if let Some(render) = app.get_sub_app_mut(RenderApp) {
            render
                .insert_resource(errors)
                .insert_resource(waiting)
                .add_systems(
                    Render,
                    (record_shader_errors, record_waiting).in_set(RenderSystems::Cleanup),
                );
        }
    }
}

fn record_waiting(
    cache: Res<bevy::render::render_resource::PipelineCache>,
    waiting: Res<PipelinesWaiting>,
) {
    let n = cache.waiting_pipelines().count();
    waiting.0.store(n, std::sync::atomic::Ordering::Relaxed);
}

fn record_shader_errors(
    cache: Res<bevy::render::render_resource::PipelineCache>,
    errors: Res<ShaderErrors>,
) {
    use bevy::render::render_resource::CachedPipelineState;
    use bevy::shader::ShaderCacheError;
    let mut first = errors.0.lock().unwrap();
    if first.is_some() {
        return;
    }
    for pipeline in cache.pipelines() {
        if let CachedPipelineState::Err(
            e @ (ShaderCacheError::ProcessShaderError(_) | ShaderCacheError::CreateShaderModule(_)),
        ) = &pipeline.state
        {
            *first = Some(e.to_string());
            return;
        }
    }
}

/// Panics with the shader compiler's message where a pipeline failed to compile. A WGSL error
/// (a reserved word such as `filter` as a name, a function shadowed) otherwise leaves its
/// objects undrawn, and a test waiting for its frame to settle runs until its frame limit or
/// fails on a comparison far from the cause.
pub fn assert_shaders_compile(app: &App) {
    // The lock is released before the panic, so the render thread's next look finds it
    // unpoisoned.
    let first = app
        .world()
        .get_resource::<ShaderErrors>()
        .and_then(|errors| errors.0.lock().unwrap().clone());
    if let Some(e) = first {
        panic!("a pipeline failed to compile (the log has the shader's lines): {e}");
    }
}

/// Whether the render world's pipeline cache has compiled every pipeline queued so far:
/// until then Bevy skips what a pipeline not ready yet would draw or dispatch, and the frames
/// it shows meanwhile can be equal to each other and still wrong (a hole-fill kernel still
/// compiling leaves its holes black).
pub fn pipelines_ready(app: &App) -> bool {
    app.world()
        .get_resource::<PipelinesWaiting>()
        .is_none_or(|w| w.0.load(std::sync::atomic::Ordering::Relaxed) == 0)
}

/// The RGBA8 pixel at (x, y).
pub fn pixel(data: &[u8], x: u32, y: u32) -> [u8; 4] {
    let i = ((y * WIDTH + x) * 4) as usize;
    [data[i], data[i + 1], data[i + 2], data[i + 3]]
}

/// Linear RGB of each pixel of an `Rgba16Float` read-back.
pub fn rgba16f_pixels(d: &[u8]) -> Vec<bevy::math::Vec3> {
    d.chunks_exact(8)
        .map(|p| {
            let h = |i: usize| half::f16::from_le_bytes([p[i], p[i + 1]]).to_f32();
            bevy::math::Vec3::new(h(0), h(2), h(4))
        })
        .collect()
}

/// The frame `image` settles on (an `Rgba16Float` target): shown (every pixel drawn, not the
/// test's red clear colour, something lit), equal in two read-backs in a row, and still the
/// same after a further 0.3 s of updates. Two equal read-backs are not enough while a
/// pipeline still compiles: Bevy skips what it would draw (on a loaded machine, the depth
/// prepass or the glazing's transparent pipeline), and those frames are equal too.
pub fn settled_frame(app: &mut App, image: &Handle<Image>) -> Vec<u8> {
    let stable_frame = |app: &mut App| {
        let prev: std::cell::RefCell<Option<Vec<u8>>> = Default::default();
        render_until(app, image.clone(), 600, |d| {
            let px = rgba16f_pixels(d);
            let shown = px.len() == (WIDTH * HEIGHT) as usize
                && px.iter().all(|c| !(c.x > 0.99 && c.y < 0.01 && c.z < 0.01))
                && px.iter().any(|c| c.max_element() > 0.01);
            let stable = prev.borrow().as_deref() == Some(d);
            *prev.borrow_mut() = Some(d.to_vec());
            shown && stable
        })
    };
    let mut data = stable_frame(app);
    // Frames from before the last pipeline compiled can be stable and wrong.
    while !pipelines_ready(app) {
        data = stable_frame(app);
    }
    for _ in 0..20 {
        for _ in 0..15 {
            app.update();
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let again = stable_frame(app);
        if again == data {
            return data;
        }
        data = again;
    }
    panic!("the frame kept changing");
}
