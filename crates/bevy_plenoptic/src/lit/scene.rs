//! Your own glTF scene lit by the pack, as a lightmap lights it: the meshes of a scene the
//! app spawned with Bevy's own glTF loader (`WorldAssetRoot`) keep their `StandardMaterial`
//! (base colour, normal and metallic-roughness textures, as Bevy's PBR reads them) and are
//! shaded with the pack's reconstructed lighting at the camera's time instead of Bevy's
//! lights (thesis §8.2.3, geometry-assisted lookups; `docs/architecture.md`, "The runtime
//! plugin").
//!
//! - **Matching.** [`PlenopticLit`] on the scene's root names the plenoptic camera whose pack
//!   and time light it. Each mesh under it is matched to the pack's object by glTF node path:
//!   the names of the mesh's ancestors (Bevy names a node's entity after the glTF node,
//!   `GltfNode{i}` when unnamed, which the baker calls `node{i}`) end with the object's
//!   `node_path`, the longest such path winning; a node with several primitives picks the
//!   object of the primitive the mesh's asset label names (`…/Primitive{k}`, the baker's
//!   `#k`). A mesh that matches no object keeps its material and is lit by the light probes
//!   ([`super`]), as any mesh not in the pack.
//! - **Shading.** A matched mesh's material becomes an `ExtendedMaterial<StandardMaterial,
//!   PlenopticLighting>` ([`LitMaterial`]), a copy of its own material made when it is matched
//!   (later edits to the original do not reach it), whose fragment shader is the proxies'
//!   (`reconstruct/geometry/geometry.wgsl` with `PLENOPTIC_STANDARD`): the same lookups,
//!   weights and fallbacks, the same marched reflections and runtime sun, with the mesh's own
//!   base colour, metalness, roughness and normal map per pixel. Its object uniform is filled
//!   by the same code as a proxy's ([`crate::reconstruct::geometry::frame`]) and it binds the
//!   camera's view buffer ([`crate::reconstruct::geometry::view`]), as the camera's proxies
//!   do; the shader carries a fragment's point into the pack's object frame with the mesh's
//!   own inverse transform for an animated object (so the lighting follows the object
//!   wherever the app's animation puts it), not at all for a static one (its proxy is in
//!   world space).
//! - **Proxies.** The camera's proxy of a matched object is moved from the camera's render
//!   layer to its shadow-only layer ([`crate::camera::layers::ViewLayer::shadow_only`]): the
//!   camera no longer draws it (the app's mesh is there instead, no depth fight), but the
//!   plugin's runtime sun still sees it as a shadow caster.
//!
//! The scene's punctual lights (`KHR_lights_punctual`, which Bevy's loader spawns as lights)
//! are hidden: their light is baked into the pack, and the meshes not in the pack get it from
//! the light probes.
//!
//! When the camera is despawned or the scene's [`PlenopticLit`] removed, the meshes get their
//! own materials back (the scene's lights stay hidden).
//!
//! What it assumes, as a lightmap does: the scene is spawned where it was baked (its root at
//! the identity), and the matched meshes are the baked ones. A mesh is lit for one camera's
//! time and lookups, whichever cameras see it (it is one entity for all of them); the
//! lookups' angular weights and reflections are per view. An app with several plenoptic
//! cameras spawns the scene once per camera with [`PlenopticLit::only_for`], and each camera
//! draws its own copy ([`super::exclusive`]). On the CPU backend a matched mesh
//! shows the camera's CPU frame in screen space, as the proxies do there (the pack's own
//! materials: the app's are not used).

use std::collections::HashSet;

use bevy::asset::AssetPath;
use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

pub use super::lighting::{LitMaterial, PlenopticLighting};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;
use crate::proxy::{PlenopticScene, ProxyOf};
use crate::reconstruct::counters::CounterBuffer;
use crate::reconstruct::cpu::CpuFrameMaterial;
use crate::reconstruct::environment::EnvironmentImages;
use crate::reconstruct::frames::{CpuFrameImage, ImageFrame};
use crate::reconstruct::geometry::blend::BlendedKeys;
use crate::reconstruct::geometry::frame;
use crate::reconstruct::geometry::rays::{CameraRays, PackRays};
use crate::reconstruct::geometry::screen_fill::EarlyDepthSupport;
use crate::reconstruct::geometry::view::ViewBuffer;
use crate::reconstruct::geometry::volume::VolumeBuffers;
use crate::reconstruct::geometry::{ObjectParams, material_factors, object_coverage};
use crate::reconstruct::{KeyTextures, ReconstructSystems};
use crate::settings::{Backend, PlenopticSettings, PlenopticSystems, ResolvedBackend};

/// Lights the meshes under this entity (a `WorldAssetRoot`, or any ancestor of them) with the
/// pack of a plenoptic camera at that camera's time (see the module doc).
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlenopticLit {
    /// The [`PlenopticCamera`] whose pack and time light the scene.
    pub camera: Entity,
    /// Whether only that camera draws the scene's meshes ([`super::exclusive`]): for an app
    /// with several plenoptic cameras that spawns the scene once per camera, each copy lit
    /// for its own camera. Otherwise every camera that sees the meshes draws them, lit for
    /// `camera`'s time and lookups.
    pub only_this_camera: bool,
}

/// A mesh of a [`PlenopticLit`] scene matched to a pack object, shaded with the pack's
/// lighting.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct LitObject {
    /// The camera whose pack and time light it.
    pub camera: Entity,
    /// The pack object it was matched to.
    pub id: u32,
    /// Its own material before it was lit (the lit material's base is a copy).
    pub original: Handle<StandardMaterial>,
}

/// A mesh of a [`PlenopticLit`] scene that matches no pack object (checked once).
#[derive(Component, Debug, Clone, Copy)]
pub struct NotInPack;

/// Adds the lit-scene systems (part of [`super::PlenopticLitPlugin`]).
pub(super) fn build(app: &mut App) {
    app.add_plugins(MaterialPlugin::<LitMaterial>::default())
        .add_systems(
            Update,
            (
                release_lit_materials,
                hide_scene_lights,
                attach_lit_materials,
                attach_cpu_frames,
                update_lit_materials,
                proxy_layers,
            )
                .chain()
                .after(PlenopticSystems::Streaming)
                .after(ReconstructSystems::Materials),
        );
}

/// The node path the baker gives a mesh under `names` (its ancestors' names, the root's
/// first): every suffix, longest first, as `/a/b/c`, with Bevy's `GltfNode{i}` for an
/// unnamed node written as the baker's `node{i}`.
pub fn node_paths(names: &[&str]) -> Vec<String> {
    let names: Vec<String> = names
        .iter()
        .map(|n| match n.strip_prefix("GltfNode") {
            Some(i) if !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()) => {
                format!("node{i}")
            }
            _ => (*n).to_owned(),
        })
        .collect();
    (0..names.len())
        .map(|i| format!("/{}", names[i..].join("/")))
        .collect()
}

/// The primitive index in a glTF mesh asset's label (`Mesh{m}/Primitive{k}`).
pub fn primitive_index(path: Option<&AssetPath>) -> Option<usize> {
    let label = path?.label()?;
    label.rsplit_once("Primitive")?.1.parse().ok()
}

/// The pack object a mesh under ancestors `names` (root first) with primitive `primitive`
/// is, if any (see the module doc).
pub fn match_object(
    objects: &[plenoptic_pack::ObjectEntry],
    names: &[&str],
    primitive: Option<usize>,
) -> Option<u32> {
    for path in node_paths(names) {
        let at: Vec<_> = objects.iter().filter(|o| o.node_path == path).collect();
        match at.as_slice() {
            [] => continue,
            [one] => return Some(one.id),
            several => {
                let k = primitive?;
                return several
                    .iter()
                    .find(|o| {
                        o.name
                            .rsplit_once('#')
                            .is_some_and(|(_, i)| i == k.to_string())
                    })
                    .map(|o| o.id);
            }
        }
    }
    None
}

/// Bevy's punctual lights (what the glTF loader spawns for `KHR_lights_punctual`).
type PunctualLight = Or<(With<DirectionalLight>, With<PointLight>, With<SpotLight>)>;

/// The pack object the mesh `entity` under the lit scene's `root` is, if any (the names of
/// its ancestors below `root` and its primitive, [`match_object`]).
fn mesh_object(
    pack: &RadiancePack,
    (root, entity): (Entity, Entity),
    mesh: &Mesh3d,
    parents: &Query<&ChildOf>,
    names: &Query<&Name>,
) -> Option<u32> {
    let mut chain: Vec<&str> = parents
        .iter_ancestors(entity)
        .take_while(|&a| a != root)
        .filter_map(|a| names.get(a).ok().map(Name::as_str))
        .collect();
    chain.reverse();
    let objects = &pack.reader.manifest().objects;
    match_object(objects, &chain, primitive_index(mesh.0.path()))
}

/// Hides the punctual lights of every [`PlenopticLit`] scene: their light is in the pack.
fn hide_scene_lights(
    mut commands: Commands,
    roots: Query<Entity, With<PlenopticLit>>,
    children: Query<&Children>,
    lights: Query<&Visibility, PunctualLight>,
) {
    for root in &roots {
        for entity in children.iter_descendants(root) {
            if lights.get(entity).is_ok_and(|v| *v != Visibility::Hidden) {
                commands.entity(entity).insert(Visibility::Hidden);
            }
        }
    }
}

/// On the CPU backend, matched meshes show the camera's CPU frame in screen space, as the
/// proxies there do (the CPU frame is the pack's reconstruction with the pack's own
/// materials; the app's materials are not used).
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn attach_cpu_frames(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    roots: Query<(Entity, &PlenopticLit)>,
    children: Query<&Children>,
    parents: Query<&ChildOf>,
    names: Query<&Name>,
    unchecked: Query<Unchecked, (Without<LitObject>, Without<NotInPack>)>,
    cameras: Query<(&PlenopticCamera, &CpuFrameImage)>,
    packs: Res<Assets<RadiancePack>>,
    mut materials: ResMut<Assets<CpuFrameMaterial>>,
) {
    if backend.0 != Backend::Cpu {
        return;
    }
    for (root, scene) in &roots {
        let Ok((cam, CpuFrameImage(frame))) = cameras.get(scene.camera) else {
            continue;
        };
        let Some(pack) = packs.get(cam.pack.id()) else {
            continue;
        };
        let mut material = None;
        for entity in children.iter_descendants(root) {
            let Ok((mesh, original)) = unchecked.get(entity) else {
                continue;
            };
            let Some(object) = mesh_object(pack, (root, entity), mesh, &parents, &names) else {
                commands.entity(entity).insert(NotInPack);
                continue;
            };
            let material = material
                .get_or_insert_with(|| {
                    materials.add(CpuFrameMaterial {
                        frame: frame.clone(),
                    })
                })
                .clone();
            commands
                .entity(entity)
                .remove::<MeshMaterial3d<StandardMaterial>>()
                .insert((
                    MeshMaterial3d(material),
                    LitObject {
                        camera: scene.camera,
                        id: object,
                        original: original.0.clone(),
                    },
                ));
        }
    }
}

/// Candidates of [`attach_lit_materials`]: meshes with a standard material not yet checked.
type Unchecked<'a> = (&'a Mesh3d, &'a MeshMaterial3d<StandardMaterial>);

/// Matches the meshes of every [`PlenopticLit`] scene to the pack's objects and gives the
/// matched ones a [`LitMaterial`]. Runs every frame: a scene's meshes appear once its glTF
/// has loaded.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn attach_lit_materials(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    volumes: Res<VolumeBuffers>,
    roots: Query<(Entity, &PlenopticLit)>,
    children: Query<&Children>,
    parents: Query<&ChildOf>,
    names: Query<&Name>,
    unchecked: Query<Unchecked, (Without<LitObject>, Without<NotInPack>)>,
    cameras: Query<(
        &PlenopticCamera,
        &ImageFrame,
        &CameraRays,
        &ViewBuffer,
        &CounterBuffer,
        &BlendedKeys,
    )>,
    packs: Res<Assets<RadiancePack>>,
    standard: Res<Assets<StandardMaterial>>,
    mut lit: ResMut<Assets<LitMaterial>>,
    mut env_images: ResMut<EnvironmentImages>,
    mut images: ResMut<Assets<Image>>,
    (mut pack_rays, mut buffers, settings, early_depth): (
        ResMut<PackRays>,
        ResMut<Assets<ShaderBuffer>>,
        Res<PlenopticSettings>,
        Res<EarlyDepthSupport>,
    ),
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (root, scene) in &roots {
        let Ok((cam, image_frame, camera_rays, view, counters, blended)) =
            cameras.get(scene.camera)
        else {
            continue;
        };
        let id = cam.pack.id();
        let (Some(pack), Some(tex), Some(vol)) =
            (packs.get(id), keys.0.get(&id), volumes.0.get(&id))
        else {
            continue;
        };
        for entity in children.iter_descendants(root) {
            let Ok((mesh, material)) = unchecked.get(entity) else {
                continue;
            };
            let Some(base) = standard.get(&material.0) else {
                // Its material has not loaded yet: next frame.
                continue;
            };
            let Some(object) = mesh_object(pack, (root, entity), mesh, &parents, &names) else {
                commands.entity(entity).insert(NotInPack);
                continue;
            };
            let factors = material_factors(pack, object);
            let coverage = object_coverage(pack, object);
            let transmissive = factors
                .as_ref()
                .is_some_and(|f| f.material.transmission > 0.0);
            let mut base = base.clone();
            let masked = matches!(base.alpha_mode, AlphaMode::Mask(_));
            // Blended as the proxy would be (see `PlenopticMaterial::transmissive`).
            if coverage < 1.0 {
                base.alpha_mode = AlphaMode::Blend;
            } else if transmissive {
                base.alpha_mode = AlphaMode::Premultiplied;
            }
            let handle = lit.add(LitMaterial {
                base,
                extension: PlenopticLighting {
                    cubes: tex.image.clone(),
                    params: ObjectParams::default(),
                    volume_samples: vol.samples.clone(),
                    volume_bins: vol.bins.clone(),
                    image_frame: image_frame.image.clone(),
                    shading_cubes: tex.shading.clone(),
                    view: view.buffer.clone(),
                    environment_image: env_images.get(id, pack, &mut images),
                    rays: pack_rays.get(id, pack, &mut buffers),
                    ray_placements: camera_rays.buffer.clone(),
                    counters: counters.buffer.clone(),
                    fill_entries: view.fill_entries.clone(),
                    hole_list: view.hole_list.clone(),
                    blended_geometry: blended.geometry.clone(),
                    blended_terms: blended.terms.clone(),
                    cost_counters: settings.cost_counters,
                    screen_fill: view.screen_fill(),
                    early_depth: early_depth.0,
                    masked,
                    factors,
                    coverage,
                    bindings: view.bindings,
                },
            });
            commands
                .entity(entity)
                .remove::<MeshMaterial3d<StandardMaterial>>()
                .insert((
                    MeshMaterial3d(handle),
                    LitObject {
                        camera: scene.camera,
                        id: object,
                        original: material.0.clone(),
                    },
                ));
        }
    }
}

/// Gives a lit mesh its own material back once its camera is gone or its scene is no longer
/// [`PlenopticLit`] (it is matched again if it is lit again).
fn release_lit_materials(
    mut commands: Commands,
    cameras: Query<(), With<PlenopticCamera>>,
    roots: Query<&PlenopticLit>,
    parents: Query<&ChildOf>,
    objects: Query<(Entity, &LitObject)>,
) {
    for (entity, object) in &objects {
        let lit_by = parents
            .iter_ancestors(entity)
            .find_map(|a| roots.get(a).ok())
            .map(|l| l.camera);
        if lit_by == Some(object.camera) && cameras.contains(object.camera) {
            continue;
        }
        commands
            .entity(entity)
            .remove::<(
                MeshMaterial3d<LitMaterial>,
                MeshMaterial3d<CpuFrameMaterial>,
                LitObject,
            )>()
            .insert(MeshMaterial3d(object.original.clone()));
    }
}

/// Keeps every lit mesh's uniform and bindings up to date with its camera, as the proxies'
/// are ([`crate::reconstruct::geometry::prepare::update_materials`]): written only when they
/// changed.
fn update_lit_materials(
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(&PlenopticCamera, &ViewBuffer)>,
    objects: Query<(&LitObject, &MeshMaterial3d<LitMaterial>)>,
    mut materials: ResMut<Assets<LitMaterial>>,
) {
    for (object, handle) in &objects {
        let Ok((cam, view)) = cameras.get(object.camera) else {
            continue;
        };
        let Some(pack) = packs.get(cam.pack.id()) else {
            continue;
        };
        frame::rebind(&mut materials, &handle.0, object.id, (cam, pack), view);
    }
}

/// Puts each camera's proxy of an object its lit scene shows on the camera's shadow-only
/// layer, and every other proxy on the camera's own layer.
fn proxy_layers(
    lit: Query<&LitObject>,
    cameras: Query<&ViewLayer>,
    roots: Query<&PlenopticScene>,
    mut proxies: Query<(&ChildOf, &ProxyOf, &mut RenderLayers)>,
) {
    let shown: HashSet<(Entity, u32)> = lit.iter().map(|o| (o.camera, o.id)).collect();
    for (parent, of, mut layers) in &mut proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let Ok(layer) = cameras.get(scene.camera) else {
            continue;
        };
        let wanted = if shown.contains(&(scene.camera, of.id)) {
            layer.shadow_only()
        } else {
            layer.layers()
        };
        if *layers != wanted {
            *layers = wanted;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(id: u32, name: &str, node_path: &str) -> plenoptic_pack::ObjectEntry {
        plenoptic_pack::ObjectEntry {
            id,
            name: name.into(),
            node_path: node_path.into(),
            motion: plenoptic_pack::Motion::Static,
            proxy_mesh: Some(id),
            material: None,
            coverage: None,
        }
    }

    #[test]
    fn meshes_match_objects_by_node_path_and_primitive() {
        let objects = [
            object(1, "Door", "/House/Door"),
            object(2, "Door", "/Door"),
            object(3, "Lamp#0", "/House/Lamp"),
            object(4, "Lamp#1", "/House/Lamp"),
            object(5, "node7", "/House/node7"),
        ];
        // Bevy's chain: the glTF scene's root entity, then the nodes.
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "Door"], None),
            Some(1)
        );
        // The longest path wins over a shorter one that also ends the chain.
        assert_eq!(match_object(&objects, &["House", "Door"], None), Some(1));
        assert_eq!(match_object(&objects, &["Scene0", "Door"], None), Some(2));
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "Lamp"], Some(1)),
            Some(4)
        );
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "Lamp"], Some(0)),
            Some(3)
        );
        // Several primitives and no label: no guess.
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "Lamp"], None),
            None
        );
        // Bevy's name of an unnamed node is the baker's.
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "GltfNode7"], None),
            Some(5)
        );
        assert_eq!(
            match_object(&objects, &["Scene0", "House", "Chair"], None),
            None
        );
    }

    #[test]
    fn primitive_indices_come_from_the_asset_label() {
        let path = AssetPath::parse("tour.glb#Mesh3/Primitive2");
        assert_eq!(primitive_index(Some(&path)), Some(2));
        assert_eq!(primitive_index(Some(&AssetPath::parse("tour.glb"))), None);
        assert_eq!(primitive_index(None), None);
    }
}
