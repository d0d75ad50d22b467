//! `examples/gazebo.toml`: every preset docs/scene-format.md names loads, and `thesis-compact` is the
//! thesis preset with 3 RGB9E5 mantissa bits.

use std::path::Path;

use oslf_bake::scene::Scene;

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
