//! # plenoptic_scene
//!
//! The scene side of baking: docs/architecture.md "Baking", step 1, and the scene and bake description
//! that the thesis (Nimeroff 1997, ch. 5) takes as the input of the decomposition of space and
//! time. This crate
//!
//! - holds the [scene model](model) the tracer consumes: object-space meshes, glTF
//!   metallic-roughness materials with emission, transmission and IOR, punctual lights,
//!   cameras and a node hierarchy whose [TRS animation](anim) (step, linear, cubic spline)
//!   places every object at any time t;
//! - [imports](import) glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`), naming the
//!   file and the element in every error and naming unsupported features (skinning, morph
//!   targets, other extensions) in warnings; it keeps what architectural exports use:
//!   `alphaMode`/`alphaCutoff`, `KHR_texture_transform`, sampler wrap modes and `COLOR_0`
//!   ([`texture`]);
//! - [builds](builder) scenes in code and writes them as glTF, for tests, benchmarks and tour
//!   scenes;
//! - reads the [bake recipe](recipe) (TOML): scenes, view space, time range, quality.
//!
//! The main flow — build a scene, write it as `.glb`, load it, place an object at time t:
//!
//! ```
//! use glam::{Quat, Vec3};
//! use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
//! use plenoptic_scene::{Track, load};
//!
//! let mut b = SceneBuilder::new();
//! let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
//! let cube = b.add_box("cube", Vec3::ONE, grey);
//! let cart = b.add_node(NodeDesc::new("Cart"));
//! b.add_node(NodeDesc::new("Crate").parent(cart).mesh(cube).translation(Vec3::Y));
//! b.animate_translation(cart, Track::linear([(0.0, Vec3::ZERO), (2.0, Vec3::new(4.0, 0.0, 0.0))]));
//!
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("cart.glb");
//! b.write_glb(&path).unwrap();
//!
//! let scene = load(&path).unwrap();
//! let id = scene.object_by_name("Crate").unwrap();
//! let at_one_second = scene.object_transform(id, 1.0);
//! assert!(at_one_second.translation.abs_diff_eq(Vec3::new(2.0, 1.0, 0.0).into(), 1e-6));
//! assert_eq!(scene.animation_range(), (0.0, 2.0));
//! ```

pub mod anim;
pub mod builder;
pub mod error;
pub mod groups;
pub mod import;
pub mod model;
pub mod recipe;
pub mod texture;
mod util;

pub use anim::{Interpolation, Key, Track, TrsTrack};
pub use error::{RecipeError, Result, SceneError};
pub use groups::{EmitterWeights, LightGroups};
pub use import::{load, load_slice};
pub use model::*;
