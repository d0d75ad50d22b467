//! The object in Bevy's own passes, in a real headless Bevy app: through its shadow proxy
//! (src/proxy.rs) it casts a shadow on a Bevy table under a Bevy light; through the plugin's
//! prepass (src/draw.rs) SSAO darkens the table where the object stands, and the object itself
//! is still drawn as the runtime draws it, shaded from the G-buffer that prepass rasterised.
//!
//! On lavapipe in CI; these tests fail, never skip, without an adapter.

#[path = "../../runtime/tests/common/mod.rs"]
mod common;
#[path = "../examples/shared/headless.rs"]
mod headless;

use std::path::Path;

use bevy::app::{App, Startup};
use bevy::asset::{AssetServer, Assets};
use bevy::color::Color;
use bevy::ecs::prelude::*;
use bevy::image::Image;
use bevy::light::{DirectionalLight, GlobalAmbientLight, NotShadowCaster};
use bevy::math::Vec3;
use bevy::mesh::{Mesh, Mesh3d};
use bevy::pbr::{MeshMaterial3d, ScreenSpaceAmbientOcclusion, StandardMaterial};
use bevy::render::view::Msaa;
use bevy::shape::Cuboid;
use bevy::transform::components::Transform;
use oslf_bevy::{Mode, OslfMessages, OslfObject, OslfProxy, ShadingParams};
use oslf_runtime::{CacheConfig, Camera, Gpu, RenderOptions, Renderer};

const W: u32 = 160;
const H: u32 = 120;

/// What a frame holds: the table always; the object, casting a shadow or not; a sun or an
/// ambient light; SSAO or not.
#[derive(Resource, Clone, Copy)]
struct Setup {
    camera: Camera,
    /// The object's lowest point and the centre of its bounds (the store's space, z up).
    floor: f32,
    centre: glam::Vec3,
    object: bool,
    casts_shadow: bool,
    sun: bool,
    ssao: bool,
}

fn setup(
    mut commands: Commands,
    setup: Res<Setup>,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let s = *setup;
    let v = |a: glam::Vec3| Vec3::from_array(a.to_array());
    let mut camera =
        headless::spawn_linear_camera(&mut commands, &mut images, &s.camera, (W, H), Msaa::Off);
    if s.ssao {
        camera.insert(ScreenSpaceAmbientOcclusion::default());
    }
    if s.object {
        let params = ShadingParams::of_mode(Mode::ReconMirror);
        let mut object =
            commands.spawn(OslfObject::new(assets.load("teapot.oslf")).with_params(params));
        if !s.casts_shadow {
            object.insert(NotShadowCaster);
        }
    }
    // A grey table whose top touches the object's lowest point.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(40.0, 40.0, 0.2))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.5, 0.5, 0.5),
            perceptual_roughness: 1.0,
            reflectance: 0.0,
            ..Default::default()
        })),
        Transform::from_translation(Vec3::new(s.centre.x, s.centre.y, s.floor - 0.1)),
    ));
    if s.sun {
        commands.insert_resource(GlobalAmbientLight::NONE);
        // From above and behind the object as the camera sees it: the shadow falls towards
        // the camera, onto the table in view.
        let away = (v(s.centre) - v(s.camera.position)).with_z(0.0).normalize();
        let travel = (away * 0.6 + Vec3::new(0.0, 0.0, -1.0)).normalize();
        commands.spawn((
            DirectionalLight {
                illuminance: 3.0,
                shadow_maps_enabled: true,
                ..Default::default()
            },
            Transform::default().looking_to(travel, Vec3::Z),
        ));
    } else {
        commands.insert_resource(GlobalAmbientLight {
            color: Color::WHITE,
            brightness: 1.0,
            ..GlobalAmbientLight::NONE
        });
    }
}

/// A settled frame's pixels, the plugin's messages and Bevy's render diagnostics.
type Frame = (Vec<[f32; 4]>, Vec<String>, Vec<(String, f64)>);

fn frame(dir: &Path, s: Setup) -> (Vec<[f32; 4]>, Vec<String>) {
    let (pixels, messages, _) = frame_with(dir, s, false);
    (pixels, messages)
}

/// The settled frame, the plugin's messages, and with `diagnostics` Bevy's render
/// diagnostics (`RenderDiagnosticsPlugin`: each span's path and its average over the frames
/// drawn, ms).
fn frame_with(dir: &Path, s: Setup, diagnostics: bool) -> Frame {
    let mut app: App = headless::headless_app(dir, CacheConfig::default());
    if diagnostics {
        app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
    }
    app.insert_resource(s).add_systems(Startup, setup);
    app.finish();
    app.cleanup();
    let pixels = headless::settle_and_capture(&mut app, 60, s.object);
    if s.object {
        let mut proxies = app.world_mut().query::<&OslfProxy>();
        let mut kinds: Vec<OslfProxy> = proxies.iter(app.world()).copied().collect();
        kinds.sort_by_key(|k| *k as u8);
        assert_eq!(kinds, [OslfProxy::Shadow], "one shadow proxy per object");
    }
    let messages = app.world().resource::<OslfMessages>().all();
    let spans = app
        .world()
        .get_resource::<bevy::diagnostic::DiagnosticsStore>()
        .map(|store| {
            store
                .iter()
                .filter_map(|d| Some((d.path().to_string(), d.average()?)))
                .filter(|(p, _)| p.starts_with("render/") || p.starts_with("oslf/"))
                .collect()
        })
        .unwrap_or_default();
    (pixels, messages, spans)
}

/// The store's camera, the object's bounds and the runtime's own render (alpha 1 on the
/// object).
fn reference(store: &Path) -> (Camera, glam::Vec3, glam::Vec3, Vec<[f32; 4]>) {
    let gpu = Gpu::headless().unwrap();
    let store = oslf_format::Store::open(store).unwrap();
    let mut r = Renderer::new(gpu, store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let (lo, hi) = r.mesh().bounds();
    let frame = r
        .render(
            &camera,
            &ShadingParams::of_mode(Mode::ReconMirror),
            &RenderOptions {
                width: W,
                height: H,
                ..Default::default()
            },
        )
        .unwrap();
    (camera, lo, hi, frame.pixels)
}

/// The fixture store's directory; a frame of its object casting its shadow on the table
/// under the sun, without SSAO; and the runtime's own render of the object.
fn fixture() -> (std::path::PathBuf, Setup, Vec<[f32; 4]>) {
    let store = common::store_path();
    let (camera, lo, hi, reference) = reference(&store);
    let setup = Setup {
        camera,
        floor: lo.z,
        centre: (lo + hi) * 0.5,
        object: true,
        casts_shadow: true,
        sun: true,
        ssao: false,
    };
    (store.parent().unwrap().to_path_buf(), setup, reference)
}

fn luminance(p: &[f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// The share of object pixels of `reference` within 1 % of it in `a`.
fn object_agreement(a: &[[f32; 4]], reference: &[[f32; 4]]) -> f64 {
    let on: Vec<usize> = (0..a.len()).filter(|&i| reference[i][3] == 1.0).collect();
    let ok = on
        .iter()
        .filter(|&&i| {
            (0..3)
                .all(|k| (a[i][k] - reference[i][k]).abs() <= 1e-2 * reference[i][k].abs().max(1.0))
        })
        .count();
    ok as f64 / on.len().max(1) as f64
}

/// Each pixel's distance in pixels (up to `max`) to the nearest object pixel of `reference`.
fn distance_to_object(reference: &[[f32; 4]], max: i32) -> Vec<i32> {
    (0..reference.len())
        .map(|i| {
            let (x, y) = ((i as u32 % W) as i32, (i as u32 / W) as i32);
            let mut best = max;
            for dy in -max..=max {
                for dx in -max..=max {
                    let (px, py) = (x + dx, y + dy);
                    if px < 0 || py < 0 || px >= W as i32 || py >= H as i32 {
                        continue;
                    }
                    if reference[(py as u32 * W + px as u32) as usize][3] == 1.0 {
                        best = best.min(dx.abs().max(dy.abs()));
                    }
                }
            }
            best
        })
        .collect()
}

#[test]
fn the_object_casts_its_shadow_on_bevys_table() {
    let (dir, base, reference) = fixture();
    let (lit, m1) = frame(&dir, base);
    let (unshadowed, m2) = frame(
        &dir,
        Setup {
            casts_shadow: false,
            ..base
        },
    );
    assert!(m1.is_empty() && m2.is_empty(), "{m1:?} {m2:?}");
    headless::dump("shadow", &lit, (W, H));
    headless::dump("shadow-not-cast", &unshadowed, (W, H));
    let off: Vec<usize> = (0..lit.len()).filter(|&i| reference[i][3] != 1.0).collect();
    let table: Vec<usize> = off
        .iter()
        .copied()
        .filter(|&i| luminance(&unshadowed[i]) > 0.01)
        .collect();
    let dark = table
        .iter()
        .filter(|&&i| luminance(&lit[i]) <= 0.7 * luminance(&unshadowed[i]))
        .count();
    let brighter = table
        .iter()
        .filter(|&&i| luminance(&lit[i]) > 1.001 * luminance(&unshadowed[i]))
        .count();
    println!(
        "{} table pixels in view, {dark} in the object's shadow, {brighter} brighter",
        table.len()
    );
    assert!(
        table.len() > 2000,
        "the table should fill the view below the object"
    );
    assert!(
        dark >= 150,
        "only {dark} table pixels darkened by the object's shadow"
    );
    assert_eq!(brighter, 0);
    // The object itself is drawn alike either way, as the runtime draws it.
    for (name, pixels) in [("casting", &lit), ("not casting", &unshadowed)] {
        let share = object_agreement(pixels, &reference);
        assert!(
            share >= 0.99,
            "{name}: {share} of the object's pixels within 1 %"
        );
    }
}

#[test]
fn ssao_sees_the_object_through_the_plugins_prepass() {
    let (dir, base, reference) = fixture();
    let base = Setup {
        sun: false,
        ssao: true,
        ..base
    };
    let (with, m1) = frame(&dir, base);
    let (without, m2) = frame(
        &dir,
        Setup {
            object: false,
            ..base
        },
    );
    assert!(m1.is_empty() && m2.is_empty(), "{m1:?} {m2:?}");
    headless::dump("ssao", &with, (W, H));
    headless::dump("ssao-no-object", &without, (W, H));
    // The plugin wrote the object into Bevy's depth and normal prepass (no proxy mesh is in
    // it), then shaded the G-buffer that pass rasterised: the object is drawn everywhere, as
    // the runtime draws it.
    let share = object_agreement(&with, &reference);
    assert!(
        share >= 0.99,
        "{share} of the object's pixels within 1 % with a depth prepass"
    );
    let distance = distance_to_object(&reference, 24);
    let ratio = |near: bool| {
        let (mut a, mut b) = (0.0f64, 0.0f64);
        let mut n = 0;
        for i in 0..with.len() {
            let d = distance[i];
            let pick = if near { (1..=3).contains(&d) } else { d >= 24 };
            if pick && luminance(&without[i]) > 0.01 {
                a += f64::from(luminance(&with[i]));
                b += f64::from(luminance(&without[i]));
                n += 1;
            }
        }
        (a / b.max(1e-9), n)
    };
    let (near, n_near) = ratio(true);
    let (far, n_far) = ratio(false);
    println!("SSAO: table next to the object {near:.3} ({n_near} pixels), far {far:.3} ({n_far})");
    assert!(
        n_near >= 50 && n_far >= 500,
        "{n_near} near, {n_far} far pixels"
    );
    assert!(
        near <= 0.95,
        "the table next to the object is not darkened by SSAO: {near}"
    );
    assert!(
        (far - 1.0).abs() <= 0.02,
        "far from the object SSAO changed the table: {far}"
    );
}

#[test]
fn the_plugins_share_of_the_frame_is_a_bevy_render_diagnostic() {
    let (dir, base, _) = fixture();
    let base = Setup { ssao: true, ..base };
    let (_, messages, with) = frame_with(&dir, base, true);
    assert!(messages.is_empty(), "{messages:?}");
    let (_, _, without) = frame_with(
        &dir,
        Setup {
            object: false,
            ..base
        },
        true,
    );
    let show = |spans: &[(String, f64)]| {
        spans
            .iter()
            .filter(|(p, _)| p.ends_with("elapsed_gpu") || p.contains("oslf"))
            .map(|(p, v)| format!("{p} {v:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let triangles = {
        let store = oslf_format::Store::open(&common::store_path()).unwrap();
        oslf_runtime::geometry::ObjectMesh::of_store(&store)
            .indices
            .len()
            / 3
    };
    println!("the proxy: {triangles} triangles");
    println!("with the object: {}", show(&with));
    println!("without it: {}", show(&without));
    let oslf: Vec<&(String, f64)> = with.iter().filter(|(p, _)| p.contains("/oslf/")).collect();
    assert!(
        oslf.iter()
            .any(|(p, v)| p.ends_with("elapsed_cpu") && *v > 0.0),
        "no render/…/oslf/elapsed_cpu span among {with:?}"
    );
    assert!(
        !without.iter().any(|(p, _)| p.contains("/oslf/")),
        "{without:?}"
    );
    // The plugin's own passes, timed inside its frame (lavapipe has timestamp queries).
    // SSAO gives the camera a prepass: the object's prepass pass is timed too.
    for pass in [
        "oslf/gbuffer_gpu_ms",
        "oslf/prepass_gpu_ms",
        "oslf/shade_gpu_ms",
        "oslf/composite_gpu_ms",
    ] {
        let ms = with.iter().find(|(p, _)| p == pass).map(|(_, v)| *v);
        assert!(
            ms.is_some_and(|v| v > 0.0 && v.is_finite()),
            "{pass}: {ms:?} among {with:?}"
        );
    }
}

#[test]
fn the_proxy_follows_its_object() {
    let (dir, base, _) = fixture();
    let mut app: App = headless::headless_app(&dir, CacheConfig::default());
    app.insert_resource(base).add_systems(Startup, setup);
    app.finish();
    app.cleanup();
    let proxies = |app: &mut App| {
        let mut q = app.world_mut().query::<(
            &OslfProxy,
            &bevy::ecs::hierarchy::ChildOf,
            Has<NotShadowCaster>,
        )>();
        let mut found = q
            .iter(app.world())
            .map(|(kind, parent, no_shadow)| (*kind, parent.parent(), no_shadow))
            .collect::<Vec<_>>();
        found.sort_by_key(|(kind, _, _)| *kind as u8);
        found
    };
    let start = std::time::Instant::now();
    while proxies(&mut app).is_empty() && start.elapsed().as_secs() < 60 {
        app.update();
    }
    let object = {
        let mut q = app.world_mut().query_filtered::<Entity, With<OslfObject>>();
        q.single(app.world()).unwrap()
    };
    let shadow_proxy = |shadowless: bool| vec![(OslfProxy::Shadow, object, shadowless)];
    assert_eq!(proxies(&mut app), shadow_proxy(false));
    // The shadow proxy's shadow casting follows the object's.
    app.world_mut().entity_mut(object).insert(NotShadowCaster);
    app.update();
    assert_eq!(proxies(&mut app), shadow_proxy(true));
    app.world_mut()
        .entity_mut(object)
        .remove::<NotShadowCaster>();
    app.update();
    assert_eq!(proxies(&mut app), shadow_proxy(false));
    // An entity that is no longer an object keeps no proxy.
    app.world_mut().entity_mut(object).remove::<OslfObject>();
    app.update();
    app.update();
    assert!(proxies(&mut app).is_empty(), "{:?}", proxies(&mut app));
}
