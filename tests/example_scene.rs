//! `examples/gazebo.toml`: every preset docs/scene-format.md names loads, and `thesis-compact` is the
//! thesis preset with 3 RGB9E5 mantissa bits.

use std::path::Path;

use oslf_scene::scene::Scene;

fn load(preset: Option<&str>) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gazebo.toml");
    Scene::load(&path, preset).unwrap_or_else(|e| panic!("preset {preset:?}: {e}"))
}

#[test]
fn every_preset_loads() {
    let quick = load(None);
    assert_eq!(quick.bake.cube_resolution, 32);
    assert_eq!(quick.bake.mantissa_bits, 9);
    let thesis = load(Some("thesis"));
    assert_eq!(thesis.bake.cube_resolution, 128);
    assert_ne!(thesis.bake.sample_count, quick.bake.sample_count);
    assert_eq!(load(Some("cube64")).bake.cube_resolution, 64);
    let cube128 = load(Some("cube128")).bake;
    assert_eq!(
        (cube128.cube_resolution, cube128.samples_per_texel),
        (128, 16)
    );
    assert_eq!(cube128.sample_count, quick.bake.sample_count);
    let compact = load(Some("thesis-compact"));
    assert_eq!(compact.bake.mantissa_bits, 3);
    let mut lossless = compact.bake.clone();
    lossless.mantissa_bits = 9;
    assert_eq!(
        lossless, thesis.bake,
        "thesis-compact differs from thesis only in mantissa_bits"
    );
}

/// `examples/room.toml` includes `examples/room.glb` (the generator's output is committed): it
/// loads with its glTF geometry and lights, warns about nothing, and its presets load.
#[test]
fn the_gltf_room_example_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/room.toml");
    for preset in [None, Some("thesis")] {
        let scene = Scene::load(&path, preset).unwrap_or_else(|e| panic!("{preset:?}: {e}"));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        assert!(!scene.objects.is_empty(), "the teapot is the OSLF object");
        assert!(!scene.lights.is_empty(), "the glTF lights are imported");
    }
}

/// `examples/meshes.toml` includes `examples/room.glb` and `examples/blob.glb` (both generators'
/// outputs are committed) and makes two of their nodes mesh OSLF objects: the blob, without
/// texture coordinates, gets an atlas of charts of its own; the ball keeps its TEXCOORD_0.
#[test]
fn the_mesh_objects_example_loads_and_lays_out_its_atlases() {
    use oslf_bake::surface::Surfaces;
    use oslf_geometry::atlas::UvSource;

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/meshes.toml");
    for preset in [None, Some("thesis")] {
        let scene = Scene::load(&path, preset).unwrap_or_else(|e| panic!("{preset:?}: {e}"));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["Ball", "Blob"]);
        assert!(scene.objects.iter().all(|o| o.patches.is_empty()));
        let blob = scene.objects[1].mesh.as_ref().expect("a mesh object");
        assert_eq!(blob.mesh.triangles.len(), 1280);
        let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
        let ball = surfaces.atlas(0).expect("the ball's atlas");
        let blob = surfaces.atlas(1).expect("the blob's atlas");
        assert_eq!(ball.source, UvSource::Texture, "{:?}", ball.rejected);
        assert_eq!(blob.source, UvSource::Charts);
        assert_eq!(
            surfaces.map_count(),
            ball.grid * ball.grid + blob.grid * blob.grid
        );
    }
}
