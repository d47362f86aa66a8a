//! Light groups: the scene's emitters partitioned into named groups, so that a bake can store
//! each group's light apart and a runtime can relight the baked animation (lamps on and off,
//! the daylight dimmed).
//!
//! Light transport is linear in the emitters (thesis §2.1's rendering equation: the radiance
//! is a linear function of the emitted radiance), so the radiance with every group at a colour
//! × intensity `w_g` is `Σ_g w_g · L_g`, where `L_g` is the radiance with only group `g` on.
//! [`Scene::relit`] gives the scene whose emitters are scaled by their groups' weights; the
//! baker renders one such scene per group and the path tracer renders the reference at any
//! weights with it.
//!
//! An emitter is a punctual light (by its glTF name), the sun (`sun`), the environment (`sky`,
//! its lit ground included), or the emission of objects (an emissive material by name: every
//! object that uses it; or an object by its node's name). Emitters that no group names form
//! the *default group*. A recipe names groups in `[[light_group]]` tables
//! ([`crate::recipe::LightGroupSpec`]); [`LightGroups::resolve`] checks them against a scene.

use glam::Vec3;

use crate::error::RecipeError;
use crate::model::Scene;
use crate::recipe::LightGroupSpec;

/// The emitter name that stands for the sun (the scene's [`crate::Sun`]).
pub const SUN: &str = "sun";
/// The emitter name that stands for the environment (sky, image or uniform colour).
pub const SKY: &str = "sky";

/// Which group each emitter of a scene belongs to. Indices are into [`LightGroups::names`];
/// `None` is the default group (emitters no group names).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LightGroups {
    /// The declared groups' names, in recipe order.
    pub names: Vec<String>,
    /// Per light of [`Scene::lights`] (the sun's light included): its group.
    pub lights: Vec<Option<u32>>,
    /// Per object of [`Scene::objects`]: the group of its emission.
    pub objects: Vec<Option<u32>>,
    /// The environment's group.
    pub sky: Option<u32>,
}

impl LightGroups {
    /// Whether the scene declares no group (everything in the default group).
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The index of the group named `name` (`None` for an unknown name).
    pub fn index_of(&self, name: &str) -> Option<u32> {
        self.names.iter().position(|n| n == name).map(|i| i as u32)
    }

    /// Light `i`'s group (the default group for a light the table does not list).
    pub fn light(&self, i: usize) -> Option<u32> {
        self.lights.get(i).copied().flatten()
    }

    /// Object `i`'s emission group.
    pub fn object(&self, i: usize) -> Option<u32> {
        self.objects.get(i).copied().flatten()
    }

    /// The sun's group, when the scene has a sun.
    pub fn sun(&self, scene: &Scene) -> Option<u32> {
        scene.sun.as_ref().and_then(|s| self.light(s.light))
    }

    /// Whether the default group holds an emitter of `scene`: a light, an emissive object or
    /// a non-empty environment that no group names.
    pub fn default_has_emitters(&self, scene: &Scene) -> bool {
        let light = (0..scene.lights.len()).any(|i| self.light(i).is_none());
        let object = scene.objects.iter().enumerate().any(|(i, o)| {
            self.object(i).is_none() && scene.materials[o.material].emissive.max_element() > 0.0
        });
        let sky = self.sky.is_none() && !scene.environment.is_none();
        light || object || sky
    }

    /// Checks `specs` against `scene` and assigns every emitter its group. Errors name the
    /// recipe `file`, the group's key and line, and the emitter: an emitter that does not
    /// exist (or an object or material that emits nothing), one named twice (directly, or an
    /// object named and its material named), and a group name used twice or empty.
    pub fn resolve(
        scene: &Scene,
        specs: &[LightGroupSpec],
        file: &str,
    ) -> Result<Self, RecipeError> {
        let mut out = LightGroups {
            names: Vec::with_capacity(specs.len()),
            lights: vec![None; scene.lights.len()],
            objects: vec![None; scene.objects.len()],
            sky: None,
        };
        // Who claimed each light, object and the sky first: (group index, emitter name).
        let mut light_by: Vec<Option<(u32, String)>> = vec![None; scene.lights.len()];
        let mut object_by: Vec<Option<(u32, String)>> = vec![None; scene.objects.len()];
        let mut sky_by: Option<(u32, String)> = None;
        for (g, spec) in specs.iter().enumerate() {
            let g = g as u32;
            let err = |key: String, problem: String| RecipeError::Invalid {
                file: file.to_owned(),
                key,
                problem,
            };
            let group_key = format!("light_group[{g}]{}", line_suffix(spec.line));
            if spec.name.trim().is_empty() || out.names.contains(&spec.name) {
                return Err(err(
                    format!("{group_key}.name"),
                    format!("'{}' must be a name no other group has", spec.name),
                ));
            }
            out.names.push(spec.name.clone());
            for e in &spec.emitters {
                let key = format!("light_group[{g}].emitters{}", line_suffix(e.line));
                let twice = |other: &(u32, String)| {
                    err(
                        key.clone(),
                        format!(
                            "emitter '{}' is already in group '{}' (as '{}'); an emitter belongs to one group",
                            e.name, specs[other.0 as usize].name, other.1
                        ),
                    )
                };
                let claim = |slot: &mut Option<(u32, String)>| match slot {
                    Some(other) => Err(twice(other)),
                    None => {
                        *slot = Some((g, e.name.clone()));
                        Ok(())
                    }
                };
                match find_emitter(scene, &e.name) {
                    Some(Emitter::Sky) => claim(&mut sky_by)?,
                    Some(Emitter::Light(i)) => claim(&mut light_by[i])?,
                    Some(Emitter::Objects(list)) => {
                        for i in list {
                            claim(&mut object_by[i])?;
                        }
                    }
                    None => {
                        return Err(err(
                            key,
                            format!(
                                "no emitter '{}' in the scene: name `{SUN}`, `{SKY}`, a glTF light, an emissive material or an emissive object",
                                e.name
                            ),
                        ));
                    }
                }
            }
        }
        out.lights = light_by.into_iter().map(|c| c.map(|(g, _)| g)).collect();
        out.objects = object_by.into_iter().map(|c| c.map(|(g, _)| g)).collect();
        out.sky = sky_by.map(|(g, _)| g);
        Ok(out)
    }
}

/// ` (line N)` for a known line, else nothing.
fn line_suffix(line: Option<usize>) -> String {
    line.map(|l| format!(" (line {l})")).unwrap_or_default()
}

/// What an emitter name refers to.
enum Emitter {
    Sky,
    Light(usize),
    /// Emissive objects: every object of an emissive material, or one emissive object.
    Objects(Vec<usize>),
}

/// The emitter `name` names in `scene`: `sun`, `sky`, a light, an emissive material, then an
/// emissive object, in that order. `None` when nothing by that name emits.
fn find_emitter(scene: &Scene, name: &str) -> Option<Emitter> {
    if name == SUN {
        return scene.sun.as_ref().map(|s| Emitter::Light(s.light));
    }
    if name == SKY {
        return (!scene.environment.is_none()).then_some(Emitter::Sky);
    }
    if let Some(i) = scene.lights.iter().position(|l| l.name == name) {
        return Some(Emitter::Light(i));
    }
    let emits = |m: usize| scene.materials[m].emissive.max_element() > 0.0;
    let by_material: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| {
            let m = scene.objects[i].material;
            scene.materials[m].name == name && emits(m)
        })
        .collect();
    if !by_material.is_empty() {
        return Some(Emitter::Objects(by_material));
    }
    let by_object: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| scene.objects[i].name == name && emits(scene.objects[i].material))
        .collect();
    (!by_object.is_empty()).then_some(Emitter::Objects(by_object))
}

/// Multipliers of the emitters the scene evaluates through its accessors rather than its
/// data: the sun (in [`Scene::placed_light`], whose sun track would otherwise give its
/// unscaled illuminance) and the environment (in [`Scene::environment_at`], after its ground
/// is lit by the unscaled sun, so that the ground stays the sky group's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmitterWeights {
    /// Multiplies the sun's light.
    pub sun: Vec3,
    /// Multiplies the environment's radiance.
    pub sky: Vec3,
}

impl Default for EmitterWeights {
    fn default() -> Self {
        Self {
            sun: Vec3::ONE,
            sky: Vec3::ONE,
        }
    }
}

impl Scene {
    /// The scene with each emitter's light multiplied by its group's weight (`weight(None)`
    /// for the default group). Lights' colours and objects' emission are scaled in the copy's
    /// data (an object whose material other objects share outside its group gets a material
    /// of its own); the sun and the environment through [`Scene::weights`].
    pub fn relit(&self, weight: impl Fn(Option<u32>) -> Vec3) -> Scene {
        let groups = &self.light_groups;
        let mut out = self.clone();
        let sun_light = self.sun.as_ref().map(|s| s.light);
        for (i, light) in out.lights.iter_mut().enumerate() {
            let w = weight(groups.light(i));
            if Some(i) == sun_light {
                out.weights.sun = self.weights.sun * w;
            } else {
                light.color *= w;
            }
        }
        out.weights.sky = self.weights.sky * weight(groups.sky);
        // One scaled copy per (material, group) that emits.
        let mut copies: std::collections::HashMap<(usize, Option<u32>), usize> =
            std::collections::HashMap::new();
        for (i, object) in out.objects.iter_mut().enumerate() {
            let m = object.material;
            if self.materials[m].emissive.max_element() <= 0.0 {
                continue;
            }
            let g = groups.object(i);
            let w = weight(g);
            if w == Vec3::ONE {
                continue;
            }
            object.material = *copies.entry((m, g)).or_insert_with(|| {
                let mut scaled = self.materials[m].clone();
                scaled.emissive *= w;
                out.materials.push(scaled);
                out.materials.len() - 1
            });
        }
        out
    }

    /// The scene with only the emitters of `group` on (`None`: the default group), each at
    /// its own intensity.
    pub fn group_only(&self, group: Option<u32>) -> Scene {
        self.relit(|g| if g == group { Vec3::ONE } else { Vec3::ZERO })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
    use crate::recipe::EmitterRef;

    fn scene() -> Scene {
        let mut b = SceneBuilder::new();
        let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
        let glow = b.add_material(MaterialDesc::emitter(Vec3::ONE, 4.0).named("Glow"));
        let cube = b.add_box("cube", Vec3::ONE, grey);
        let lamp = b.add_box("lamp", Vec3::splat(0.1), glow);
        b.add_node(NodeDesc::new("Table").mesh(cube));
        b.add_node(NodeDesc::new("Bulb").mesh(lamp));
        b.add_node(NodeDesc::new("Bulb2").mesh(lamp).translation(Vec3::X));
        b.add_node(
            NodeDesc::new("DeskNode")
                .light(LightDesc::point(Vec3::ONE, 10.0).named("Desk"))
                .translation(Vec3::Y),
        );
        b.build_scene().unwrap()
    }

    fn spec(name: &str, emitters: &[&str]) -> LightGroupSpec {
        LightGroupSpec {
            name: name.to_owned(),
            line: Some(7),
            emitters: emitters
                .iter()
                .map(|e| EmitterRef {
                    name: (*e).to_owned(),
                    line: Some(9),
                })
                .collect(),
        }
    }

    #[test]
    fn emitters_resolve_to_their_groups() {
        let scene = scene();
        let g =
            LightGroups::resolve(&scene, &[spec("lamps", &["Desk", "Glow"])], "r.toml").unwrap();
        assert_eq!(g.lights, vec![Some(0)]);
        let bulbs: Vec<_> = (0..scene.objects.len()).map(|i| g.object(i)).collect();
        assert_eq!(bulbs, vec![None, Some(0), Some(0)]);
        assert!(!g.default_has_emitters(&scene));
    }

    #[test]
    fn unknown_and_twice_named_emitters_are_refused_with_the_line() {
        let scene = scene();
        let e = LightGroups::resolve(&scene, &[spec("a", &["Lamp9"])], "r.toml").unwrap_err();
        let text = e.to_string();
        assert!(text.contains("r.toml") && text.contains("line 9") && text.contains("Lamp9"));
        // A material and one of its objects are the same emitter.
        let e = LightGroups::resolve(&scene, &[spec("a", &["Glow"]), spec("b", &["Bulb2"])], "r")
            .unwrap_err();
        assert!(e.to_string().contains("already in group 'a'"), "{e}");
        // A non-emissive object is no emitter.
        assert!(LightGroups::resolve(&scene, &[spec("a", &["Table"])], "r").is_err());
        assert!(LightGroups::resolve(&scene, &[spec("a", &[]), spec("a", &[])], "r").is_err());
    }

    #[test]
    fn relit_scales_only_the_groups_emitters() {
        let mut scene = scene();
        scene.light_groups =
            LightGroups::resolve(&scene, &[spec("bulb", &["Bulb"])], "r.toml").unwrap();
        let relit = scene.relit(|g| match g {
            Some(0) => Vec3::splat(2.0),
            _ => Vec3::splat(0.5),
        });
        assert_eq!(relit.lights[0].color, Vec3::splat(0.5));
        let emission = |s: &Scene, i: usize| s.materials[s.objects[i].material].emissive;
        assert_eq!(emission(&relit, 1), Vec3::splat(8.0));
        assert_eq!(emission(&relit, 2), Vec3::splat(2.0));
        // The source scene's material is untouched.
        assert_eq!(emission(&scene, 1), Vec3::splat(4.0));
        let off = scene.group_only(Some(0));
        assert_eq!(off.lights[0].color, Vec3::ZERO);
        assert_eq!(emission(&off, 2), Vec3::ZERO);
    }
}
