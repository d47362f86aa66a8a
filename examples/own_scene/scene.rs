//! The example's app, apart from its `main` so that the plugin's GPU tests run it (on a
//! tiny pack, for a few frames, headless): the glTF scene spawned by Bevy's own loader and
//! lit by the pack ([`PlenopticLit`]), a plenoptic camera, and a sphere that is not in the
//! pack, moving through the room, lit by the pack's light probes.

use bevy::camera::Exposure;
use bevy::prelude::*;
use bevy_plenoptic::lit::scene::PlenopticLit;
use bevy_plenoptic::prelude::*;

/// What the example shows.
#[derive(Resource, Clone, Debug)]
pub struct OwnScene {
    /// The glb, as an asset path.
    pub glb: String,
    /// The pack baked from it, as an asset path.
    pub pack: String,
    /// The pack's time shown (seconds).
    pub time: f32,
    /// Where the camera stands and what it looks at.
    pub eye: (Vec3, Vec3),
    /// The sphere's path: a circle (centre, radius) at the sphere's height.
    pub orbit: (Vec3, f32),
    /// The camera's exposure (EV100).
    pub ev100: f32,
    /// Whether the glb is spawned and lit (false: the pack's proxies show the scene, for
    /// comparison).
    pub own_scene: bool,
}

impl Default for OwnScene {
    /// Room A of the architectural tour, looking at the table, at 4 s.
    fn default() -> Self {
        Self {
            glb: "tour.glb".into(),
            pack: "pack://tour.pack".into(),
            time: 4.0,
            eye: (Vec3::new(-6.5, 1.6, 3.0), Vec3::new(-8.5, 0.8, -1.0)),
            orbit: (Vec3::new(-8.0, 0.9, 0.5), 0.8),
            ev100: bevy_plenoptic::camera::EV100_UNIT - 1.0,
            own_scene: true,
        }
    }
}

/// The sphere that is not in the pack.
#[derive(Component, Debug)]
pub struct Unbaked;

/// Adds the example's systems; `camera` is what the plenoptic camera renders to (a window
/// or an image), spawned with the camera.
pub fn add(app: &mut App, scene: OwnScene, camera: impl Bundle) {
    let camera = std::sync::Mutex::new(Some(camera));
    app.insert_resource(scene)
        .add_systems(
            Startup,
            move |mut commands: Commands,
                  assets: Res<AssetServer>,
                  scene: Res<OwnScene>,
                  mut meshes: ResMut<Assets<Mesh>>,
                  mut materials: ResMut<Assets<StandardMaterial>>| {
                let target = camera.lock().unwrap().take().expect("startup runs once");
                let (eye, look) = scene.eye;
                let id = commands
                    .spawn((
                        target,
                        Transform::from_translation(eye).looking_at(look, Vec3::Y),
                        Exposure { ev100: scene.ev100 },
                        PlenopticCamera {
                            playback: Playback::Manual,
                            time: scene.time,
                            ..PlenopticCamera::new(assets.load(scene.pack.clone()))
                        },
                    ))
                    .id();
                // The glb through Bevy's own glTF loader, lit by the camera's pack.
                if scene.own_scene {
                    commands.spawn((
                        WorldAssetRoot(
                            assets.load(GltfAssetLabel::Scene(0).from_asset(scene.glb.clone())),
                        ),
                        PlenopticLit::new(id),
                    ));
                }
                // Not in the pack: lit by the pack's light probes.
                commands.spawn((
                    Unbaked,
                    Mesh3d(meshes.add(Sphere::new(0.25).mesh().uv(32, 16))),
                    MeshMaterial3d(materials.add(StandardMaterial {
                        base_color: Color::srgb(0.9, 0.9, 0.9),
                        perceptual_roughness: 0.4,
                        metallic: 0.0,
                        ..default()
                    })),
                    Transform::from_translation(scene.orbit.0),
                ));
            },
        )
        .add_systems(Update, orbit);
}

/// Moves the sphere around its circle, a turn every 8 s.
fn orbit(time: Res<Time>, scene: Res<OwnScene>, mut spheres: Query<&mut Transform, With<Unbaked>>) {
    let (centre, radius) = scene.orbit;
    let a = time.elapsed_secs() * std::f32::consts::TAU / 8.0;
    for mut t in &mut spheres {
        t.translation = centre + Vec3::new(a.cos(), 0.0, a.sin()) * radius;
    }
}
