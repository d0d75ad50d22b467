//! A real headless Bevy app (no window: the camera renders into an image, read back by Bevy's
//! screenshot) with the plugin: the object's pixels against the runtime's own render of the
//! same store, camera and settings; Bevy meshes in front of and behind the object; damaged and
//! missing stores.
//!
//! On lavapipe in CI; these tests fail, never skip, without an adapter.

#[path = "../../runtime/tests/common/mod.rs"]
mod common;
#[path = "../examples/shared/headless.rs"]
mod headless;
#[path = "../examples/shared/keys.rs"]
mod keys;

use std::path::Path;

use bevy::app::{App, Startup};
use bevy::asset::{AssetServer, Assets};
use bevy::color::Color;
use bevy::core_pipeline::prepass::{DeferredPrepass, DepthPrepass, NormalPrepass};
use bevy::ecs::prelude::*;
use bevy::image::Image;
use bevy::material::OpaqueRendererMethod;
use bevy::math::Vec3;
use bevy::mesh::{Mesh, Mesh3d};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::render::view::Msaa;
use bevy::shape::Cuboid;
use bevy::transform::components::Transform;
use oslf_bevy::{Mode, OslfCacheStats, OslfMessages, OslfObject, ShadingParams};
use oslf_runtime::{CacheConfig, Camera, Gpu, Order, RenderOptions, Renderer};

const W: u32 = 160;
const H: u32 = 120;

/// What a test puts in the scene besides the camera.
#[derive(Clone, Copy, PartialEq)]
enum Extra {
    None,
    /// A red cube between the camera and the object's left part.
    Front,
    /// A green wall behind the object.
    Behind,
}

#[derive(Resource, Clone)]
struct Setup {
    camera: Camera,
    store: Option<String>,
    extra: Extra,
    params: ShadingParams,
    msaa: Msaa,
    /// A prepass on the camera, which the plugin writes the object into and shades it from.
    prepass: Prepass,
}

/// The prepass of the test's camera.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Prepass {
    None,
    /// Depth and normals (what SSAO asks for).
    DepthNormal,
    /// Bevy's deferred G-buffer with depth: Bevy's meshes are lit in its deferred lighting
    /// pass, the object drawn over it as a forward mesh.
    Deferred,
}

fn setup(
    mut commands: Commands,
    setup: Res<Setup>,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let c = &setup.camera;
    let v = |a: glam::Vec3| Vec3::from_array(a.to_array());
    let mut camera =
        headless::spawn_linear_camera(&mut commands, &mut images, c, (W, H), setup.msaa);
    match setup.prepass {
        Prepass::None => {}
        Prepass::DepthNormal => {
            camera.insert((DepthPrepass, NormalPrepass));
        }
        Prepass::Deferred => {
            camera.insert((DepthPrepass, DeferredPrepass));
        }
    }
    if let Some(store) = &setup.store {
        commands.spawn(OslfObject::new(assets.load(store.clone())).with_params(setup.params));
    }
    // With Bevy's deferred G-buffer, Bevy's meshes are drawn into it and lit in its deferred
    // lighting pass.
    let method = if setup.prepass == Prepass::Deferred {
        OpaqueRendererMethod::Deferred
    } else {
        OpaqueRendererMethod::Auto
    };
    let unlit = |color: Color| StandardMaterial {
        base_color: color,
        unlit: true,
        opaque_render_method: method,
        ..Default::default()
    };
    // The teapot of the fixture sits near the origin, about 3 units across; the camera looks
    // at it from the store's view.
    let towards = (v(c.target) - v(c.position)).normalize();
    match setup.extra {
        Extra::None => {}
        Extra::Front => {
            let at = v(c.position) + towards * 2.0;
            let left = towards.cross(v(c.up)).normalize() * -0.6;
            commands.spawn((
                Mesh3d(meshes.add(Cuboid::new(0.5, 3.0, 0.5))),
                MeshMaterial3d(materials.add(unlit(Color::srgb(1.0, 0.0, 0.0)))),
                Transform::from_translation(at + left).looking_to(towards, v(c.up)),
            ));
        }
        Extra::Behind => {
            let at = v(c.target) + towards * 6.0;
            commands.spawn((
                Mesh3d(meshes.add(Cuboid::new(40.0, 40.0, 0.1))),
                MeshMaterial3d(materials.add(unlit(Color::srgb(0.0, 1.0, 0.0)))),
                Transform::from_translation(at).looking_to(towards, v(c.up)),
            ));
        }
    }
}

/// A headless app with the plugin, as `setup` says; the store directory is the asset root.
fn app(dir: &Path, setup_: Setup) -> App {
    let mut app = headless::headless_app(dir, CacheConfig::default());
    app.insert_resource(setup_).add_systems(Startup, setup);
    app.finish();
    app.cleanup();
    app
}

/// Updates until the cache's feedback reports a frame with no misses (at most `frames`), then
/// screenshots the camera's image until it settles ([`headless::settle_and_capture`]).
fn run_and_capture(app: &mut App, frames: usize) -> Vec<[f32; 4]> {
    headless::settle_and_capture(app, frames, true)
}

fn params() -> ShadingParams {
    ShadingParams::of_mode(Mode::ReconMirror)
}

/// The store's default camera and the runtime's own render of it at W×H (as `oslf render`
/// does), converged.
fn reference(store: &Path, params: &ShadingParams) -> (Camera, Vec<[f32; 4]>) {
    let gpu = Gpu::headless().unwrap();
    let store = oslf_format::Store::open(store).unwrap();
    let mut r = Renderer::new(gpu, store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let frame = r
        .render(
            &camera,
            params,
            &RenderOptions {
                width: W,
                height: H,
                ..Default::default()
            },
        )
        .unwrap();
    (camera, frame.pixels)
}

fn setup_for(camera: Camera, extra: Extra, with_object: bool) -> Setup {
    Setup {
        camera,
        store: with_object.then(|| "teapot.oslf".to_string()),
        extra,
        params: params(),
        msaa: Msaa::Off,
        prepass: Prepass::None,
    }
}

/// The share of `object` pixels (alpha 1 in `reference`) where `a` is within `tol` relative
/// of `reference`, and their count.
fn agreement(a: &[[f32; 4]], reference: &[[f32; 4]], tol: f32) -> (usize, f64) {
    let (mut n, mut ok) = (0usize, 0usize);
    for (p, r) in a.iter().zip(reference) {
        if r[3] != 1.0 {
            continue;
        }
        n += 1;
        let good = (0..3).all(|k| (p[k] - r[k]).abs() <= tol * r[k].abs().max(1.0));
        ok += usize::from(good);
    }
    (n, ok as f64 / n.max(1) as f64)
}

#[test]
fn the_object_in_a_bevy_frame_equals_the_runtimes_render() {
    let store = common::store_path();
    let dir = store.parent().unwrap();
    let (camera, reference) = reference(&store, &params());
    // Multisampled: shaded once per pixel, written to each sample, resolved by the plugin.
    // With a prepass: written into it, then shaded from the G-buffer that pass rasterised.
    for (msaa, prepass) in [
        (Msaa::Off, Prepass::None),
        (Msaa::Sample4, Prepass::None),
        (Msaa::Off, Prepass::DepthNormal),
        (Msaa::Sample4, Prepass::DepthNormal),
        (Msaa::Off, Prepass::Deferred),
    ] {
        let setup = Setup {
            msaa,
            prepass,
            ..setup_for(camera, Extra::None, true)
        };
        let msaa = format!("{msaa:?}, prepass {prepass:?}");
        let mut app = app(dir, setup);
        let pixels = run_and_capture(&mut app, 60);
        dump(&format!("bevy-{msaa}"), &pixels);
        let stats = app.world().resource::<OslfCacheStats>().clone();
        assert!(
            stats.total.misses > 0 && stats.latest.misses == 0,
            "{msaa}: the first frames should miss and later ones not: {stats:?}"
        );
        assert!(pixels.iter().flatten().all(|v| v.is_finite()));
        let (n, share) = agreement(&pixels, &reference, 1e-2);
        println!(
            "{msaa}: {n} object pixels, {:.2}% within 1% of the runtime's render",
            share * 100.0
        );
        assert!(n > 1000, "{msaa}: {n} object pixels");
        assert!(share >= 0.99, "{msaa}: {share}");
        let messages = app.world().resource::<OslfMessages>().all();
        assert!(messages.is_empty(), "{messages:?}");
    }
}

fn dump(name: &str, pixels: &[[f32; 4]]) {
    headless::dump(name, pixels, (W, H));
}

#[test]
fn bevy_meshes_in_front_hide_the_object_and_it_hides_those_behind() {
    let store = common::store_path();
    let dir = store.parent().unwrap();
    let (camera, reference) = reference(&store, &params());
    dump("runtime", &reference);
    // Bevy's frame with nothing in it: its clear colour.
    let empty = run_and_capture(&mut app(dir, setup_for(camera, Extra::None, false)), 4);
    // With a prepass, Bevy's main pass tests its meshes against the object's depth the plugin
    // wrote there, and the plugin shades the G-buffer it rasterised then.
    for (extra, prepass) in [
        (Extra::Front, Prepass::None),
        (Extra::Behind, Prepass::None),
        (Extra::Front, Prepass::DepthNormal),
        (Extra::Behind, Prepass::DepthNormal),
        (Extra::Front, Prepass::Deferred),
        (Extra::Behind, Prepass::Deferred),
    ] {
        let setup = |with_object| Setup {
            prepass,
            ..setup_for(camera, extra, with_object)
        };
        let without = run_and_capture(&mut app(dir, setup(false)), 4);
        let with = run_and_capture(&mut app(dir, setup(true)), 60);
        let side = if extra == Extra::Front {
            "front"
        } else {
            "behind"
        };
        let name = format!("{side}-{prepass:?}");
        dump(&format!("bevy-{name}"), &with);
        let (mut hidden, mut shown) = (0, 0);
        let mut object = (Vec::new(), Vec::new());
        for (((w, o), r), clear) in with.iter().zip(&without).zip(&reference).zip(&empty) {
            let mesh = o != clear;
            let on_object = r[3] == 1.0;
            if extra == Extra::Front && mesh {
                // The cube in front: exactly its pixels, the object hidden behind it.
                assert_eq!(w, o);
                hidden += usize::from(on_object);
            } else if on_object {
                shown += 1;
                object.0.push(*w);
                object.1.push(*r);
            } else {
                assert_eq!(w, o, "off the object the scene is Bevy's alone");
            }
        }
        let (_, share) = agreement(&object.0, &object.1, 1e-2);
        println!(
            "{name}: {hidden} object pixels hidden, {shown} shown, {:.2}% within 1%",
            share * 100.0
        );
        assert!(shown > 1000 && share >= 0.99, "{shown} {share}");
        if extra == Extra::Front {
            assert!(hidden > 100, "{hidden}");
        }
    }
}

/// The room example's keys (examples/shared/keys.rs) change what they say, where the mode has
/// it, and nothing where it does not.
#[test]
fn the_examples_keys_change_the_shading_they_name() {
    use keys::{apply, describe, ShadingKey};
    use oslf_bevy::{Blend, Lookup, Source};
    let mut p = ShadingParams::of_mode(Mode::ReconGlossy);
    let m = p.monte_carlo().unwrap().m;
    apply(&mut p, ShadingKey::MoreSamples);
    assert_eq!(p.monte_carlo().unwrap().m, 2 * m);
    apply(&mut p, ShadingKey::FewerSamples);
    apply(&mut p, ShadingKey::FewerSamples);
    assert_eq!(p.monte_carlo().unwrap().m, m / 2);
    let depth = p.depth();
    apply(&mut p, ShadingKey::Depth);
    assert_eq!(p.depth(), !depth);
    let (blend, n) = p.blend().unwrap();
    apply(&mut p, ShadingKey::Blend);
    let i = Blend::ALL.iter().position(|b| *b == blend).unwrap();
    assert_eq!(p.blend(), Some((Blend::ALL[(i + 1) % Blend::ALL.len()], n)));
    apply(&mut p, ShadingKey::Source);
    assert_eq!(p.source(), Source::EnvMap);
    assert_eq!(p.blend(), None);
    apply(&mut p, ShadingKey::Source);
    assert_eq!(p.source(), Source::Oslf);
    assert_eq!(p.blend(), Some(Lookup::DEFAULT_BLEND));
    assert!(
        describe(&p).starts_with("ReconGlossy Oslf depth"),
        "{}",
        describe(&p)
    );
    // The mode key gives the mode's defaults; keys for what it lacks change nothing.
    apply(&mut p, ShadingKey::Mode(Mode::Recon));
    let recon = ShadingParams::of_mode(Mode::Recon);
    assert_eq!(p, recon);
    for key in [
        ShadingKey::Source,
        ShadingKey::Blend,
        ShadingKey::MoreSamples,
    ] {
        apply(&mut p, key);
        assert_eq!(p, recon, "{key:?} changed the recon mode");
    }
}

/// The objects extracted to the render world in each of `frames` updates
/// (`oslf/extracted_objects`).
fn extracted_per_update(app: &mut App, frames: usize) -> Vec<f64> {
    (0..frames)
        .map(|_| {
            app.update();
            app.world()
                .resource::<bevy::diagnostic::DiagnosticsStore>()
                .get(&oslf_bevy::stats::EXTRACTED_OBJECTS)
                .and_then(|d| d.value())
                .unwrap_or(f64::NAN)
        })
        .collect()
}

/// The render world keeps the last extraction while nothing changes, and follows every
/// change: the object hidden, shown and moved, moved back, its component removed.
#[test]
fn the_object_follows_its_entity_and_still_frames_extract_nothing() {
    let store = common::store_path();
    let dir = store.parent().unwrap();
    let (camera, reference) = reference(&store, &params());
    let mut app = app(dir, setup_for(camera, Extra::None, true));
    let settled = run_and_capture(&mut app, 60);
    let (n, share) = agreement(&settled, &reference, 1e-2);
    assert!(n > 1000 && share >= 0.99, "{n} object pixels, {share}");
    // Nothing changes: nothing is extracted, and the object is still drawn.
    let still = extracted_per_update(&mut app, 5);
    assert!(
        still.iter().all(|&e| e == 0.0),
        "still frames extracted {still:?}"
    );
    assert!(agreement(&run_and_capture(&mut app, 1), &reference, 1e-2).1 >= 0.99);
    let object = {
        let mut q = app.world_mut().query_filtered::<Entity, With<OslfObject>>();
        q.single(app.world()).unwrap()
    };
    let change = |app: &mut App, what: &dyn Fn(&mut bevy::ecs::world::EntityWorldMut)| {
        what(&mut app.world_mut().entity_mut(object));
        let extracted = extracted_per_update(app, 3);
        assert!(
            extracted.contains(&1.0),
            "the change was not extracted: {extracted:?}"
        );
        agreement(&run_and_capture(app, 1), &reference, 1e-2).1
    };
    let hidden = change(&mut app, &|e| {
        e.insert(bevy::camera::visibility::Visibility::Hidden);
    });
    assert!(hidden < 0.05, "hidden, still drawn: {hidden}");
    let moved = change(&mut app, &|e| {
        e.insert((
            bevy::camera::visibility::Visibility::Inherited,
            Transform::from_xyz(0.4, 0.0, 0.0),
        ));
    });
    assert!(moved < 0.9, "moved, drawn where it was: {moved}");
    let back = change(&mut app, &|e| {
        e.insert(Transform::IDENTITY);
    });
    assert!(back >= 0.99, "moved back, not drawn where it was: {back}");
    app.world_mut().entity_mut(object).remove::<OslfObject>();
    let gone = agreement(&run_and_capture(&mut app, 1), &reference, 1e-2).1;
    assert!(gone < 0.05, "removed, still drawn: {gone}");
}

#[test]
fn damaged_and_missing_stores_are_said_once_and_draw_nothing() {
    let store = common::store_path();
    let tmp = tempfile::tempdir().unwrap();
    // Cut short: the store's table of contents points past its end.
    let bytes = std::fs::read(&store).unwrap();
    std::fs::write(tmp.path().join("damaged.oslf"), &bytes[..bytes.len() / 2]).unwrap();
    let (camera, _) = reference(&store, &params());
    for (name, says) in [
        (
            "damaged.oslf",
            format!(
                "header says {} bytes, the file has {}",
                bytes.len(),
                bytes.len() / 2
            ),
        ),
        ("missing.oslf", "Path not found".to_string()),
    ] {
        let setup = Setup {
            store: Some(name.to_string()),
            ..setup_for(camera, Extra::None, true)
        };
        let mut app = app(tmp.path(), setup);
        let pixels = run_and_capture(&mut app, 20);
        let without = run_and_capture(
            &mut self::app(tmp.path(), setup_for(camera, Extra::None, false)),
            4,
        );
        assert_eq!(pixels, without, "{name}: nothing is drawn");
        let messages = app.world().resource::<OslfMessages>().all();
        assert_eq!(messages.len(), 1, "{name}: said once: {messages:?}");
        assert!(
            messages[0].contains(name)
                && messages[0].contains(&says)
                && !messages[0].contains('\n'),
            "{messages:?}"
        );
    }
}

/// An order that reads distances without depth-corrected lookups is said once, naming the
/// order, and draws nothing (rather than per point's frame under its name).
#[test]
fn an_order_that_reads_distances_without_depth_is_said_once_and_draws_nothing() {
    let store = common::store_path();
    let dir = store.parent().unwrap();
    let (camera, _) = reference(&store, &params());
    let mut bad = ShadingParams::of_mode(Mode::Glossy);
    bad.set_depth(false).unwrap();
    bad.monte_carlo_mut().unwrap().order = Order::PerPointSearched;
    let setup = Setup {
        params: bad,
        ..setup_for(camera, Extra::None, true)
    };
    let mut app = app(dir, setup);
    let pixels = run_and_capture(&mut app, 10);
    let without = run_and_capture(
        &mut self::app(dir, setup_for(camera, Extra::None, false)),
        4,
    );
    assert_eq!(pixels, without, "nothing is drawn");
    let messages = app.world().resource::<OslfMessages>().all();
    assert_eq!(messages.len(), 1, "said once: {messages:?}");
    assert!(
        messages[0].contains("per-point-searched") && messages[0].contains("depth"),
        "{messages:?}"
    );
}

/// examples/orb.toml baked small into `dir` as `orb.oslf`: a glTF object whose roughness
/// texture the store carries (format version 8).
fn bake_orb(dir: &Path) -> std::path::PathBuf {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/orb.toml");
    let mut scene = oslf_scene::scene::Scene::load(&scene_path, None).unwrap();
    scene.bake.sample_count = oslf_scene::scene::SampleDensity::Count(80);
    scene.bake.cube_resolution = 16;
    scene.bake.sample_map_resolution = 32;
    scene.bake.samples_per_texel = 1;
    let output = dir.join("orb.oslf");
    let options = oslf_bake::bake::BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    oslf_bake::bake::bake(&scene, &options).unwrap();
    output
}

/// A textured object (its roughness from its texture, in the pbr mode) in a Bevy frame equals
/// the runtime's render: the plugin draws through the same G-buffer with the material target.
#[test]
fn a_textured_object_in_a_bevy_frame_equals_the_runtimes_render() {
    let tmp = tempfile::tempdir().unwrap();
    let store = bake_orb(tmp.path());
    let opened = oslf_format::Store::open(&store).unwrap();
    assert!(opened.meta().objects[0].textures.is_some());
    // A format 1.1 store: the diffuse part of a dielectric reads its stored irradiance.
    assert!(opened.irradiance().is_some());
    let mut params = ShadingParams::of_mode(Mode::Pbr);
    params.monte_carlo_mut().unwrap().m = 8;
    // The orb's own (gold) material, then a dielectric of the same colours, whose diffuse
    // base is read from the stored irradiance.
    let mut dielectric = params;
    *dielectric.material_mut().unwrap() = oslf_runtime::PbrMaterial {
        metallic: 0.0,
        roughness: 0.5,
        object_material: false,
    };
    for (params, label) in [(params, "bevy-orb"), (dielectric, "bevy-orb-dielectric")] {
        let (camera, reference) = reference(&store, &params);
        let setup = Setup {
            store: Some("orb.oslf".into()),
            params,
            ..setup_for(camera, Extra::None, true)
        };
        let mut app = app(tmp.path(), setup);
        let pixels = run_and_capture(&mut app, 60);
        dump(label, &pixels);
        let (n, share) = agreement(&pixels, &reference, 1e-2);
        println!(
            "{label}: {n} object pixels, {:.2}% within 1% of the runtime's render",
            share * 100.0
        );
        assert!(n > 500, "{label}: {n} object pixels");
        assert!(share >= 0.99, "{label}: {share}");
        let messages = app.world().resource::<OslfMessages>().all();
        assert!(messages.is_empty(), "{label}: {messages:?}");
    }
}
