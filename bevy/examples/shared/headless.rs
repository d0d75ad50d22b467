//! A windowless Bevy app with the OSLF plugin, driven frame by frame, and screenshots of an
//! image target read back as linear RGBA: shared by the headless tests and the measuring
//! examples.
#![allow(dead_code)] // each user takes its part

use std::path::Path;
use std::sync::{Arc, Mutex};

use bevy::app::{App, PluginGroup};
use bevy::asset::{AssetPlugin, Assets, Handle};
use bevy::camera::{Camera3d, Exposure, Hdr, PerspectiveProjection, Projection, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::ecs::prelude::*;
use bevy::ecs::system::EntityCommands;
use bevy::image::Image;
use bevy::math::Vec3;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::render::view::Msaa;
use bevy::render::RenderPlugin;
use bevy::transform::components::Transform;
use bevy::window::{ExitCondition, WindowPlugin};
use bevy::DefaultPlugins;
use oslf_bevy::{CacheConfig, OslfCacheStats, OslfPlugin};

/// The image the camera of [`spawn_linear_camera`] draws into.
#[derive(Resource)]
pub struct Target(pub Handle<Image>);

/// Spawns a camera that sees as `camera` does (the runtime's: position, target, up, vertical
/// field of view) into a new `width`×`height` `Rgba16Float` image: HDR at exposure 1
/// (2^-ev100 / 1.2) without tonemapping or dithering, so the image holds linear radiance as
/// the runtime writes it. Inserts [`Target`].
pub fn spawn_linear_camera<'a>(
    commands: &'a mut Commands,
    images: &mut Assets<Image>,
    camera: &oslf_runtime::Camera,
    (width, height): (u32, u32),
    msaa: Msaa,
) -> EntityCommands<'a> {
    let target = images.add(Image::new_target_texture(
        width,
        height,
        TextureFormat::Rgba16Float,
        None,
    ));
    commands.insert_resource(Target(target.clone()));
    let v = |a: glam::Vec3| Vec3::from_array(a.to_array());
    commands.spawn((
        Camera3d::default(),
        Hdr,
        msaa,
        Tonemapping::None,
        DebandDither::Disabled,
        Exposure {
            ev100: -(1.2f32).log2(),
        },
        Projection::Perspective(PerspectiveProjection {
            fov: camera.vfov_deg.to_radians(),
            near: 0.01,
            ..Default::default()
        }),
        RenderTarget::from(target),
        Transform::from_translation(v(camera.position)).looking_at(v(camera.target), v(camera.up)),
    ))
}

/// Bevy's default plugins without a window (nor winit, when built in), pipelines compiled
/// before the frame that needs them, frames rendered in the update that makes them; assets
/// from `asset_dir`; the OSLF plugin with `cache`. Ready for `App::update`.
pub fn headless_app(asset_dir: &Path, cache: CacheConfig) -> App {
    let plugins = DefaultPlugins
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..Default::default()
        })
        .set(RenderPlugin {
            synchronous_pipeline_compilation: true,
            ..Default::default()
        })
        .set(AssetPlugin {
            file_path: asset_dir.to_string_lossy().into_owned(),
            ..Default::default()
        })
        .disable::<bevy::render::pipelined_rendering::PipelinedRenderingPlugin>();
    #[cfg(feature = "viewer")]
    let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
    let mut app = App::new();
    app.add_plugins(plugins).add_plugins(OslfPlugin { cache });
    app
}

/// Updates `frames` times, or with `until_cached` until the cache's feedback reports a frame
/// with no misses, then takes screenshots of the [`Target`] image (made by the app's start-up
/// systems) until two in a row agree and every pixel was drawn: linear RGBA per pixel, top
/// row first. Bevy loads its shaders on the task pools that all apps of a process share, so
/// an app can draw nothing for seconds while another loads a store: the screenshots are
/// retaken, a few updates apart, for up to [`SETTLE_SECONDS`].
pub fn settle_and_capture(app: &mut App, frames: usize, until_cached: bool) -> Vec<[f32; 4]> {
    for _ in 0..frames.max(1) {
        app.update();
        let stats = app.world().resource::<OslfCacheStats>();
        if until_cached && stats.latest.frames > 0 && stats.latest.misses == 0 {
            break;
        }
    }
    let target = app.world().resource::<Target>().0.clone();
    let start = std::time::Instant::now();
    let mut last = capture(app, &target);
    loop {
        let next = capture(app, &target);
        if next == last && next.iter().all(|p| p[3] == 1.0) {
            return next;
        }
        if start.elapsed().as_secs() >= SETTLE_SECONDS {
            panic!(
                "the frame never settled in {SETTLE_SECONDS} s: of {} pixels, {}",
                next.len(),
                unsettled(&last, &next)
            );
        }
        last = next;
        for _ in 0..4 {
            app.update();
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
}

/// How long [`settle_and_capture`] retakes screenshots before it gives up.
pub const SETTLE_SECONDS: u64 = 120;

/// What keeps two screenshots from counting as settled, with an example of each fault.
fn unsettled(last: &[[f32; 4]], next: &[[f32; 4]]) -> String {
    let differ: Vec<usize> = (0..next.len())
        .filter(|&i| last[i].map(f32::to_bits) != next[i].map(f32::to_bits))
        .collect();
    let undrawn: Vec<usize> = (0..next.len()).filter(|&i| next[i][3] != 1.0).collect();
    let nonfinite = next.iter().flatten().filter(|c| !c.is_finite()).count();
    let example = |what: &[usize]| {
        what.first()
            .map(|&i| format!(" (pixel {i}: {:?} then {:?})", last[i], next[i]))
            .unwrap_or_default()
    };
    format!(
        "{} differ between the last two screenshots{}, {} have alpha other than 1{}, and {} \
         channels are not finite",
        differ.len(),
        example(&differ),
        undrawn.len(),
        example(&undrawn),
        nonfinite
    )
}

/// One screenshot of `target`, an `Rgba16Float` image.
pub fn capture(app: &mut App, target: &Handle<Image>) -> Vec<[f32; 4]> {
    let shot: Arc<Mutex<Option<Image>>> = Arc::default();
    let sink = Arc::clone(&shot);
    app.world_mut()
        .spawn(Screenshot::image(target.clone()))
        .observe(move |ev: bevy::ecs::observer::On<ScreenshotCaptured>| {
            *sink.lock().unwrap() = Some(ev.image.clone());
        });
    // The read-back arrives some updates later: ten on lavapipe, where an update takes
    // milliseconds; a hardware GPU's updates can all pass before the copy is mapped, so wait by
    // the clock (up to 20 s), not by a count.
    let start = std::time::Instant::now();
    while shot.lock().unwrap().is_none() && start.elapsed().as_secs() < 20 {
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let image = shot
        .lock()
        .unwrap()
        .take()
        .expect("no screenshot arrived in 20 s");
    assert_eq!(image.texture_descriptor.format, TextureFormat::Rgba16Float);
    let data = image.data.expect("screenshot without data");
    data.chunks_exact(8)
        .map(|p| {
            std::array::from_fn(|k| half::f16::from_le_bytes([p[2 * k], p[2 * k + 1]]).to_f32())
        })
        .collect()
}

/// With `OSLF_BEVY_DUMP=DIR`, writes `pixels` (`width`×`height`) as `DIR/NAME.ppm` (clamped
/// to 0..1, sRGB) to look at.
pub fn dump(name: &str, pixels: &[[f32; 4]], (width, height): (u32, u32)) {
    let Some(dir) = std::env::var_os("OSLF_BEVY_DUMP") else {
        return;
    };
    let srgb = |v: f32| {
        let v = v.clamp(0.0, 1.0);
        let s = if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    let mut bytes = format!("P6\n{width} {height}\n255\n").into_bytes();
    bytes.extend(
        pixels
            .iter()
            .flat_map(|p| [srgb(p[0]), srgb(p[1]), srgb(p[2])]),
    );
    std::fs::write(Path::new(&dir).join(format!("{name}.ppm")), bytes).unwrap();
}
