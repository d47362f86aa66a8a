//! The recipe's daylight applied to the loaded scene (docs/architecture.md, "Daylight"): the
//! sun study drives a directional light (the one the recipe names, or a new "Sun"), the sky
//! becomes the scene's environment, and environment images are read from disk.
//!
//! Images are equirectangular: Radiance `.hdr` through the `radiant` crate (its header gives
//! the size before any allocation) and OpenEXR through the `exr` crate (its metadata is read
//! first, for the same reason). Either is refused beyond `EquirectImage::MAX_SIDE` per side.

use std::path::Path;
use std::sync::Arc;

use glam::Vec3;
use plenoptic_scene::recipe::BakeRecipe;
use plenoptic_scene::recipe::daylight::{SkySpec, SunSpec};
use plenoptic_scene::{Environment, Light, LightKind, Node, Scene, Sun, Trs};
use plenoptic_sky::EquirectImage;

use crate::error::{BakeError, Result};

/// Largest number of samples of a sun study's track (one per frame below it).
pub const MAX_TRACK_SAMPLES: u32 = 4096;

/// Applies `recipe`'s `[sun]` and `[sky]` to `scene`.
pub fn apply(scene: &mut Scene, recipe: &BakeRecipe) -> Result<()> {
    let daylight = &recipe.daylight;
    let invalid = |key: &str, problem: String| {
        BakeError::Invalid(format!("{}: {key}: {problem}", recipe.name))
    };
    if let Some(spec) = &daylight.sun {
        let light = sun_light(scene, spec).map_err(|p| invalid("sun.light", p))?;
        let samples = recipe.time.frame_count().clamp(2, MAX_TRACK_SAMPLES) as usize;
        let track = spec
            .study
            .track(recipe.time.start, recipe.time.end, samples)
            .map_err(|e| invalid("sun", e.to_string()))?;
        scene.sun = Some(Sun {
            light,
            track: Some(track),
        });
    }
    scene.environment = match &daylight.sky {
        SkySpec::None => Environment::None,
        SkySpec::Uniform(c) => Environment::Uniform(*c),
        SkySpec::Image {
            path,
            intensity,
            rotation_deg,
        } => Environment::Image {
            image: Arc::new(read_equirect(path)?),
            intensity: *intensity,
            rotation_deg: *rotation_deg,
        },
        SkySpec::HosekWilkie { params, sun_light } => {
            if scene.sun.is_none() {
                let light = match sun_light {
                    Some(name) => directional_named(scene, name).map_err(|p| invalid("sky.sun", p))?,
                    None => scene
                        .lights
                        .iter()
                        .position(|l| l.kind == LightKind::Directional)
                        .ok_or_else(|| {
                            invalid(
                                "sky",
                                "a Hosek–Wilkie sky needs a sun: add [sun] or a directional light to the scene".into(),
                            )
                        })?,
                };
                scene.sun = Some(Sun { light, track: None });
            }
            Environment::Sky(*params)
        }
    };
    // Without a sun study or a sky, the brightest directional light is the sun: the one whose
    // direct light the runtime evaluates (pack 3). Other punctual lights stay in the bake.
    if scene.sun.is_none()
        && let Some(light) = brightest_directional(scene)
    {
        scene.sun = Some(Sun { light, track: None });
    }
    Ok(())
}

/// The directional light with the largest luminous illuminance, if any.
fn brightest_directional(scene: &Scene) -> Option<usize> {
    let lux = |l: &plenoptic_scene::Light| l.intensity * plenoptic_trace::image::luminance(l.color);
    scene
        .lights
        .iter()
        .enumerate()
        .filter(|(_, l)| l.kind == LightKind::Directional && lux(l) > 0.0)
        .max_by(|a, b| lux(a.1).total_cmp(&lux(b.1)))
        .map(|(i, _)| i)
}

fn directional_named(scene: &Scene, name: &str) -> std::result::Result<usize, String> {
    let i = scene
        .lights
        .iter()
        .position(|l| l.name == name)
        .ok_or_else(|| format!("the scene has no light named \"{name}\""))?;
    if scene.lights[i].kind != LightKind::Directional {
        return Err(format!("light \"{name}\" is not a directional light"));
    }
    Ok(i)
}

/// The light the sun study drives: the named one (given the study's disc), or a new "Sun".
fn sun_light(scene: &mut Scene, spec: &SunSpec) -> std::result::Result<usize, String> {
    let radius = (0.5 * spec.angular_diameter_deg).to_radians();
    let i = match &spec.light {
        Some(name) => directional_named(scene, name)?,
        None => {
            scene.nodes.push(Node {
                name: "Sun".into(),
                parent: None,
                rest: Trs::default(),
                track: None,
            });
            scene.lights.push(Light {
                name: "Sun".into(),
                kind: LightKind::Directional,
                color: spec.study.color,
                intensity: spec.study.illuminance,
                range: None,
                angular_radius: radius,
                node: scene.nodes.len() - 1,
            });
            scene.lights.len() - 1
        }
    };
    scene.lights[i].angular_radius = radius;
    Ok(i)
}

fn env_error(path: &Path, message: impl Into<String>) -> BakeError {
    BakeError::Environment {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// Reads an equirectangular `.hdr` or `.exr` image.
pub fn read_equirect(path: &Path) -> Result<EquirectImage> {
    let lower = path.to_string_lossy().to_ascii_lowercase();
    let max = EquirectImage::MAX_SIDE as usize;
    let (w, h, texels) = if lower.ends_with(".hdr") {
        let file = std::fs::File::open(path).map_err(|e| env_error(path, e.to_string()))?;
        let loader = radiant::Loader::new(std::io::BufReader::new(file))
            .map_err(|e| env_error(path, format!("not a Radiance HDR file: {e}")))?;
        if loader.width == 0 || loader.height == 0 || loader.width > max || loader.height > max {
            return Err(env_error(
                path,
                format!(
                    "size {} × {} is outside 1 – {max}",
                    loader.width, loader.height
                ),
            ));
        }
        let image = loader
            .load_image()
            .map_err(|e| env_error(path, format!("truncated or corrupt: {e}")))?;
        let texels = image
            .data
            .iter()
            .map(|p| Vec3::new(p.r, p.g, p.b))
            .collect();
        (image.width, image.height, texels)
    } else if lower.ends_with(".exr") {
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| env_error(path, format!("not an OpenEXR file: {e}")))?;
        for header in &meta.headers {
            let size = header.layer_size;
            if size.width() > max || size.height() > max {
                return Err(env_error(
                    path,
                    format!("size {} × {} is over {max}", size.width(), size.height()),
                ));
            }
        }
        let (w, h, texels) =
            plenoptic_eval::frame_io::read_exr(path).map_err(|e| env_error(path, e.to_string()))?;
        (w as usize, h as usize, texels)
    } else {
        return Err(env_error(
            path,
            "must be an equirectangular .hdr or .exr file",
        ));
    };
    // Negative or non-finite texels (possible in EXR) are clamped rather than refused: other
    // renderers read such files.
    let texels: Vec<Vec3> = texels
        .into_iter()
        .map(|t: Vec3| {
            if t.is_finite() {
                t.max(Vec3::ZERO)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    if w != 2 * h {
        eprintln!(
            "warning: {}: {w} × {h} is not 2:1; read as equirectangular anyway",
            path.display()
        );
    }
    EquirectImage::new(w as u32, h as u32, texels).map_err(|e| env_error(path, e.to_string()))
}
