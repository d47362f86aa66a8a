//! # plenoptic_bake
//!
//! The baker: turns a bake recipe and its animated glTF scenes into a radiance pack
//! (docs/architecture.md, "Baking", steps 4–8), following the "recipe" of Nimeroff's thesis (1997),
//! chapter 6 (decomposition of space by id-image coherence, of time by light and view
//! id-images, of indirect illumination by irradiance RMS) and chapter 7 (temporal volumes).
//!
//! - [`plan`]: the bake plan, computed from id-images only: base views by subdividing the
//!   view space while the fitness f (fraction of pixels with the same object id in all corner
//!   id-images) is below q ([`plan::space`]); time keys from light id-images, refined per base
//!   view ([`plan::time`]); ambient-field key times from the relative RMS of irradiance
//!   ([`plan::ambient`]).
//! - [`render`]: range images (radiance, distance, object id, normal cubes) at every base
//!   view and time key with the multi-stage renderer, the ambient field interpolated linearly
//!   in time; [`volume`]: temporal volumes, random and adaptive (direction, t) samples with
//!   validity radii; [`denoise`]: the edge-aware à-trous filter of the range images' diffuse
//!   lighting (demodulated by albedo, seam-aware, guided by id, normal and distance).
//! - [`write`](mod@write): chunks, proxy geometry, animation tracks, manifest and statistics; the pack is
//!   assembled in a canonical order. [`lights`]: the manifest's lights, with the place of
//!   each lamp that never moves (pack 4.1).
//! - [`work`]: the work directory that makes bakes resumable and shardable, and merging.
//! - [`bake`](mod@bake): the whole pipeline; [`progress`]: progress bars with ETA;
//!   [`reference`](mod@reference): path-traced reference frames along a camera path.
//! - [`delaunay3`]: the 3D Delaunay complex (x, y, t) of temporal volumes (a re-export of
//!   [`plenoptic_recon::delaunay3`], which also slices it at reconstruction).
//!
//! The `plenoptic` command (`src/main.rs`) exposes `plan`, `bake` (`--resume`,
//! `--shard i/N`, `--volume-complex`), `merge`, `inspect`, `reference` (path-traced frames
//! along a camera path, `--halves` for two independent halves), and `render` / `compare`
//! (reconstruction and variance-corrected metrics from `plenoptic_eval::tools`). Cluster use: `docs/baking-on-a-cluster.md`.
//!
//! Decisions the design leaves open, documented in the modules: object ids are stored as scene
//! id + 1 (0 = none, [`render::pack_object_id`]); the decomposition of space uses the scene at
//! the start time; a static scene gets one time key per base view and no temporal volume;
//! timings go to a sidecar file ([`write`](mod@write)).
//!
//! Same inputs give a byte-identical pack, whatever the thread count and whether the bake ran
//! in one go, resumed, or in shards: wall-clock timings are kept out of the pack (sidecar
//! `<output>.timings.json`) unless asked for.
//!
//! Planning a tiny scene: a box seen from a segment, static, so one key per base view.
//!
//! ```
//! use glam::Vec3;
//! use plenoptic_bake::plan;
//! use plenoptic_scene::builder::{MaterialDesc, SceneBuilder};
//! use plenoptic_scene::recipe::Recipe;
//! use plenoptic_trace::SceneAccel;
//!
//! let mut b = SceneBuilder::new();
//! let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
//! let mesh = b.add_box("box", Vec3::ONE, grey);
//! b.add_node(plenoptic_scene::builder::NodeDesc::new("box").mesh(mesh));
//! let scene = b.build_scene().unwrap();
//!
//! let recipe = Recipe::from_str_named(
//!     r#"
//!     output = "box.pack"
//!     [[scene]]
//!     file = "box.glb"
//!     [view_space]
//!     kind = "segment"
//!     a = [-3.0, 0.0, 2.0]
//!     b = [3.0, 0.0, 2.0]
//!     [time]
//!     start = 0.0
//!     end = 1.0
//!     frame_rate = 10.0
//!     [quality]
//!     preset = "draft"
//!     q = 0.0
//!     id_image_size = 8
//!     "#,
//!     "doc.toml",
//!     std::path::Path::new("."),
//! )
//! .unwrap();
//! let accel = SceneAccel::new(&scene).unwrap();
//! let (plan, _) = plan::decompose(&recipe, &scene, &accel);
//! // q = 0: the two ends of the segment only, each with one time key (nothing moves).
//! assert_eq!(plan.base_views.len(), 2);
//! assert!(plan.base_views.iter().all(|v| v.time_keys == vec![0.0]));
//! ```

pub mod bake;
pub mod daylight;
pub mod denoise;
pub mod error;
pub mod groups;
pub mod input;
pub mod lights;
pub mod materials;
pub mod plan;
pub mod progress;
pub mod quantise;
pub mod reference;
pub mod render;
pub mod volume;
pub mod work;
pub mod write;

pub use plenoptic_recon::delaunay3;

pub use bake::{BakeOptions, BakeReport, bake, bake_recipe, merge, merge_recipe};
pub use error::{BakeError, Result};
pub use plan::{Plan, PlanCost, PlannedView};
pub use work::{Shard, WorkDir, WorkItem};
