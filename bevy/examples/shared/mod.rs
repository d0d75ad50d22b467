//! The room scene both examples draw: `examples/room.glb` by Bevy, the teapot of
//! `examples/room.toml` by the OSLF plugin.

pub mod headless;
// The room example uses it; the frame-cost example, which shares this module, does not.
#[allow(dead_code)]
pub mod keys;

use std::f32::consts::FRAC_PI_2;

use bevy::prelude::*;
use oslf_bevy::OslfObject;

/// Where the bake put the teapot (room.toml: on the table top, z = 0.78 in the bake's Z-up
/// metres), in Bevy's Y-up world: its middle.
pub const TEAPOT: Vec3 = Vec3::new(0.0, 0.95, 0.0);

/// The asset folder: `OSLF_ASSETS` where set (a binary run from another checkout, as
/// scripts/device-kit.sh does on a lent GPU), else the repository's `examples/` (room.glb,
/// room.oslf).
pub fn assets() -> String {
    std::env::var("OSLF_ASSETS")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../examples").to_string())
}

/// The camera orbiting the teapot.
#[derive(Component, Clone, Copy)]
pub struct Orbit {
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
}

impl Orbit {
    pub fn transform(&self) -> Transform {
        let offset = Quat::from_euler(EulerRot::YXZ, self.yaw, -self.pitch, 0.0) * Vec3::Z;
        Transform::from_translation(TEAPOT + offset * self.distance).looking_at(TEAPOT, Vec3::Y)
    }
}

/// Spawns the room (Bevy's glTF scene) and, with `teapot`, the OSLF object. Returns the
/// assets to wait for.
pub fn spawn_room(
    commands: &mut Commands,
    assets: &AssetServer,
    teapot: bool,
) -> Vec<bevy::asset::UntypedAssetId> {
    let scene = assets.load(GltfAssetLabel::Scene(0).from_asset("room.glb"));
    let mut ids = vec![scene.id().untyped()];
    commands.spawn(WorldAssetRoot(scene));
    if teapot {
        let store = assets.load("room.oslf");
        ids.push(store.id().untyped());
        // The bake's scene is room.glb turned 90° about x (Z up): turning back puts the
        // teapot's light field in Bevy's Y-up room. Its radiance is in watts (the lights at
        // 683 lm/W): ×683 gives Bevy's luminance.
        commands.spawn((
            OslfObject::new(store).with_radiance_scale(683.0),
            Transform::from_rotation(Quat::from_rotation_x(-FRAC_PI_2)),
        ));
    }
    ids
}

/// The glTF file's own camera would draw into the same target: only the orbit camera draws.
pub fn keep_only_the_orbit_camera(
    mut cameras: Query<&mut Camera, (Added<Camera>, Without<Orbit>)>,
) {
    for mut camera in &mut cameras {
        camera.is_active = false;
    }
}
