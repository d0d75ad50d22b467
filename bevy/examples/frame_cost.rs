//! What the plugin costs in the room example, headless: the same orbit around the teapot drawn
//! with and without the OSLF object, each frame waited for on the GPU; and the cache on that
//! orbit (misses per frame converge, frames that load cost no more than others).
//!
//! ```text
//! oslf bake examples/room.toml -o examples/room.oslf
//! cargo run --release -p oslf-bevy --features viewer --example frame_cost --ignore-rust-version -- \
//!     [--ssao] [WIDTH HEIGHT FRAMES [GPU_SLOTS]]
//! ```
//!
//! Defaults: 640×360, 120 frames, a cache holding every cube, a camera without a prepass;
//! `--ssao` gives the camera Bevy's SSAO and with it a depth and normal prepass, which the
//! plugin writes the object into. Prints a summary and writes
//! `frame_cost.csv` (frame, ms without, ms with, misses, loads) and the last frame with the
//! object, `frame_cost.png`.

mod shared;

use std::path::Path;
use std::time::Instant;

use bevy::asset::UntypedAssetId;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::renderer::RenderDevice;
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use oslf_bevy::{CacheConfig, OslfCacheStats};
use shared::headless::headless_app;
use shared::{assets, keep_only_the_orbit_camera, spawn_room, Orbit};

/// The target's size, whether the teapot is in the room, whether the camera has SSAO.
#[derive(Resource, Clone, Copy)]
struct Size(u32, u32, bool, bool);

#[derive(Resource)]
struct Waiting(Vec<UntypedAssetId>);

#[derive(Resource)]
struct Target(Handle<Image>);

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    size: Res<Size>,
) {
    let ids = spawn_room(&mut commands, &assets, size.2);
    commands.insert_resource(Waiting(ids));
    let target = images.add(Image::new_target_texture(
        size.0,
        size.1,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    commands.insert_resource(Target(target.clone()));
    let orbit = Orbit {
        yaw: 0.0,
        pitch: 0.35,
        distance: 1.6,
    };
    let mut camera = commands.spawn((
        Camera3d::default(),
        bevy::camera::Hdr,
        Msaa::Off,
        RenderTarget::from(target),
        orbit,
        orbit.transform(),
    ));
    if size.3 {
        camera.insert(bevy::pbr::ScreenSpaceAmbientOcclusion::default());
    }
}

fn app(size: Size, cache: CacheConfig) -> App {
    let mut app = headless_app(Path::new(&assets()), cache);
    app.insert_resource(size)
        .add_systems(Startup, setup)
        .add_systems(Update, keep_only_the_orbit_camera);
    app.finish();
    app.cleanup();
    app
}

/// One frame, waited for on the GPU; its wall time in ms.
fn frame(app: &mut App) -> f64 {
    let t = Instant::now();
    app.update();
    app.world()
        .resource::<RenderDevice>()
        .wgpu_device()
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("waiting for the GPU");
    t.elapsed().as_secs_f64() * 1e3
}

/// Loads the scene, warms up, then orbits once in `frames` frames: each frame's ms and cache
/// counters (misses, loads). With `picture`, saves the last frame there as PNG.
fn orbit(app: &mut App, frames: usize, picture: Option<&'static str>) -> Vec<(f64, u64, u64)> {
    for _ in 0..600 {
        frame(app);
        let server = app.world().resource::<AssetServer>();
        let waiting = &app.world().resource::<Waiting>().0;
        if waiting
            .iter()
            .all(|id| server.is_loaded_with_dependencies(*id))
        {
            break;
        }
    }
    // Pipelines, shadow maps and the first view's cube maps.
    for _ in 0..10 {
        frame(app);
    }
    let mut out = Vec::with_capacity(frames);
    for i in 0..frames {
        let yaw = std::f32::consts::TAU * i as f32 / frames as f32;
        let world = app.world_mut();
        let mut q = world.query::<(&mut Orbit, &mut Transform)>();
        for (mut o, mut t) in q.iter_mut(world) {
            o.yaw = yaw;
            *t = o.transform();
        }
        let ms = frame(app);
        let s = &app.world().resource::<OslfCacheStats>().latest;
        out.push((ms, s.misses, s.loads));
    }
    if let Some(path) = picture {
        let target = app.world().resource::<Target>().0.clone();
        app.world_mut()
            .spawn(Screenshot::image(target))
            .observe(save_to_disk(path));
        for _ in 0..5 {
            frame(app);
        }
    }
    out
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let ssao = raw.iter().any(|a| a == "--ssao");
    let args: Vec<u32> = raw
        .iter()
        .filter(|a| *a != "--ssao")
        .map(|a| {
            a.parse()
                .expect("arguments: [--ssao] WIDTH HEIGHT FRAMES [GPU_SLOTS]")
        })
        .collect();
    let width = args.first().copied().unwrap_or(640);
    let height = args.get(1).copied().unwrap_or(360);
    let frames = args.get(2).copied().unwrap_or(120) as usize;
    let cache = CacheConfig {
        gpu_slots: args.get(3).copied(),
        ..Default::default()
    };
    let without = orbit(
        &mut app(Size(width, height, false, ssao), cache),
        frames,
        None,
    );
    let with = orbit(
        &mut app(Size(width, height, true, ssao), cache),
        frames,
        Some("frame_cost.png"),
    );
    let ms = |v: &[(f64, u64, u64)]| v.iter().map(|f| f.0).collect::<Vec<_>>();
    let (a, b) = (median(&ms(&without)), median(&ms(&with)));
    let loading: Vec<f64> = with.iter().filter(|f| f.2 > 0).map(|f| f.0).collect();
    let missing = with.iter().filter(|f| f.1 > 0).count();
    let last_miss = with.iter().rposition(|f| f.1 > 0);
    println!(
        "{width}×{height}, {frames} frames on one orbit, each waited for on the GPU{}",
        if ssao {
            ", SSAO (a depth and normal prepass)"
        } else {
            ""
        }
    );
    println!(
        "median frame: {a:.1} ms without the object, {b:.1} ms with it: ×{:.2}",
        b / a
    );
    println!(
        "slowest frame: {:.1} ms without, {:.1} ms with",
        ms(&without).iter().cloned().fold(0.0, f64::max),
        ms(&with).iter().cloned().fold(0.0, f64::max)
    );
    println!(
        "cache: feedback with misses in {missing} of {frames} frames (last: {}), {} misses and {} loads in all; frames that loaded: median {:.1} ms",
        last_miss.map_or("none".into(), |i| format!("frame {i}")),
        with.iter().map(|f| f.1).sum::<u64>(),
        with.iter().map(|f| f.2).sum::<u64>(),
        if loading.is_empty() { 0.0 } else { median(&loading) },
    );
    let mut csv = String::from("frame,ms_without,ms_with,misses,loads\n");
    for (i, (w, o)) in without.iter().zip(&with).enumerate() {
        csv += &format!("{i},{:.3},{:.3},{},{}\n", w.0, o.0, o.1, o.2);
    }
    std::fs::write("frame_cost.csv", csv).expect("writing frame_cost.csv");
}
