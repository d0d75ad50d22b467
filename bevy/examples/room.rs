//! The room of `examples/room.glb`, drawn by Bevy (its meshes, materials and lights), with the
//! teapot baked from `examples/room.toml` drawn by the OSLF plugin on its table.
//!
//! ```text
//! oslf bake examples/room.toml -o examples/room.oslf
//! cargo run --release -p oslf-bevy --features viewer --example room --ignore-rust-version
//! ```
//!
//! Drag with the left mouse button to orbit the teapot, scroll to move closer. Keys, as in
//! `oslf view`: 1–6 the mode, `e` OSLF or the environment-map baseline, `d` depth-corrected
//! lookups, `b` the blend, `[` `]` halve or double M, Esc quits.

mod shared;

use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;
use oslf_bevy::{Mode, OslfCacheStats, OslfObject, OslfPlugin};
use shared::keys::{apply, describe, ShadingKey};
use shared::{assets, keep_only_the_orbit_camera, spawn_room, Orbit};

fn main() {
    App::new()
        .add_plugins(DefaultPlugins.set(AssetPlugin {
            file_path: assets(),
            ..default()
        }))
        .add_plugins(OslfPlugin::default())
        .add_systems(Startup, setup)
        .add_systems(Update, (keep_only_the_orbit_camera, orbit, keys, report))
        .run();
}

fn setup(mut commands: Commands, assets: Res<AssetServer>) {
    spawn_room(&mut commands, &assets, true);
    commands.spawn((
        Camera3d::default(),
        bevy::camera::Hdr,
        Msaa::Off,
        Orbit {
            yaw: 0.6,
            pitch: 0.35,
            distance: 1.6,
        },
    ));
}

fn orbit(
    mut cameras: Query<(&mut Orbit, &mut Transform)>,
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
) {
    for (mut o, mut t) in &mut cameras {
        if buttons.pressed(MouseButton::Left) {
            o.yaw -= motion.delta.x * 0.005;
            o.pitch = (o.pitch + motion.delta.y * 0.005).clamp(-1.4, 1.4);
        }
        o.distance = (o.distance * (1.0 - scroll.delta.y * 0.1)).clamp(0.3, 6.0);
        *t = o.transform();
    }
}

fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut objects: Query<&mut OslfObject>,
    mut exit: MessageWriter<AppExit>,
) {
    if keys.just_pressed(KeyCode::Escape) {
        exit.write(AppExit::Success);
    }
    let modes = [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
        KeyCode::Digit6,
    ];
    let mut pressed: Vec<ShadingKey> = modes
        .iter()
        .zip(Mode::ALL)
        .filter(|(key, _)| keys.just_pressed(**key))
        .map(|(_, mode)| ShadingKey::Mode(mode))
        .collect();
    for (key, shading) in [
        (KeyCode::KeyE, ShadingKey::Source),
        (KeyCode::KeyD, ShadingKey::Depth),
        (KeyCode::KeyB, ShadingKey::Blend),
        (KeyCode::BracketRight, ShadingKey::MoreSamples),
        (KeyCode::BracketLeft, ShadingKey::FewerSamples),
    ] {
        if keys.just_pressed(key) {
            pressed.push(shading);
        }
    }
    for mut object in &mut objects {
        for key in &pressed {
            apply(&mut object.params, *key);
        }
    }
}

/// Once a second: the shading settings and the cache.
fn report(
    time: Res<Time>,
    mut last: Local<f32>,
    objects: Query<&OslfObject>,
    stats: Res<OslfCacheStats>,
) {
    if time.elapsed_secs() - *last < 1.0 {
        return;
    }
    *last = time.elapsed_secs();
    for o in &objects {
        let p = &o.params;
        info!(
            "{}; cache: {} frames booked, miss rate {:.3}, {} loads",
            describe(p),
            stats.total.frames,
            stats.total.miss_rate,
            stats.total.loads
        );
    }
}
