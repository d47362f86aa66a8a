//! The bake's input: a recipe's scene files loaded and joined into one [`Scene`].
//!
//! Each scene file of a recipe gets a new root node carrying the file's placement; its nodes,
//! meshes, materials, textures, objects, lights and cameras are appended in recipe order, so
//! object ids are stable for a given recipe: file 0's objects first, then file 1's, and so on.

use std::path::Path;

use plenoptic_scene::recipe::{BakeRecipe, Recipe};
use plenoptic_scene::{LightGroups, Node, Scene, Trs};

use crate::error::Result;

/// Reads and validates the recipe at `path` and loads its scenes.
pub fn load_recipe(path: &Path) -> Result<(BakeRecipe, Scene)> {
    let recipe = Recipe::from_path(path)?;
    let scene = load_scenes(&recipe)?;
    Ok((recipe, scene))
}

/// Loads every scene file of `recipe`, joins them into one scene, applies the recipe's sun
/// and sky ([`crate::daylight`]) and assigns its emitters to the recipe's light groups
/// ([`plenoptic_scene::groups`]).
pub fn load_scenes(recipe: &BakeRecipe) -> Result<Scene> {
    let mut out = Scene::default();
    for source in &recipe.scenes {
        let scene = plenoptic_scene::load(&source.path)?;
        append(&mut out, scene, source.transform, &source.path);
    }
    crate::daylight::apply(&mut out, recipe)?;
    out.light_groups = LightGroups::resolve(&out, &recipe.light_groups, &recipe.name)?;
    Ok(out)
}

/// Appends `scene` to `out` under a new root node placed at `transform`.
pub fn append(out: &mut Scene, scene: Scene, transform: Trs, path: &Path) {
    let identity = transform == Trs::default();
    let root = if identity {
        None
    } else {
        out.nodes.push(Node {
            name: format!(
                "{}",
                path.file_name()
                    .map_or(path.display(), |n| Path::new(n).display())
            ),
            parent: None,
            rest: transform,
            track: None,
        });
        Some(out.nodes.len() - 1)
    };
    let node0 = out.nodes.len();
    let mesh0 = out.meshes.len();
    let mat0 = out.materials.len();
    let tex0 = out.textures.len();
    for mut n in scene.nodes {
        n.parent = match n.parent {
            Some(p) => Some(p + node0),
            None => root,
        };
        out.nodes.push(n);
    }
    out.meshes.extend(scene.meshes);
    out.textures.extend(scene.textures);
    for mut m in scene.materials {
        for t in [
            &mut m.base_color_texture,
            &mut m.metallic_roughness_texture,
            &mut m.emissive_texture,
            &mut m.normal_texture,
        ]
        .into_iter()
        .flatten()
        {
            t.texture += tex0;
        }
        out.materials.push(m);
    }
    for mut o in scene.objects {
        o.node += node0;
        o.mesh += mesh0;
        o.material += mat0;
        out.objects.push(o);
    }
    for mut l in scene.lights {
        l.node += node0;
        out.lights.push(l);
    }
    for mut c in scene.cameras {
        c.node += node0;
        out.cameras.push(c);
    }
    out.warnings.extend(
        scene
            .warnings
            .into_iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
}

/// Whether anything in the scene changes: an object or a light under an animated node, or a
/// sun that moves (a sun study).
pub fn scene_is_animated(scene: &Scene) -> bool {
    (0..scene.objects.len()).any(|i| scene.object_is_animated(i as u32))
        || scene.lights.iter().any(|l| scene.node_is_animated(l.node))
        || scene.sun_is_animated()
}
