//! A textured glTF object end to end on the bake side (format version 8): examples/orb.toml's
//! gold orb, whose metallicRoughnessTexture bands its roughness, bakes into a store that carries
//! the texture with the file's own codes and one texture coordinate per store vertex; and the
//! ground truth shades each pixel with the roughness the texture holds there.

use std::path::{Path, PathBuf};

use oslf_bake::bake::{bake, BakeOptions};
use oslf_bake::ground_truth::{GroundTruth, Term, TruthSettings};
use oslf_bake::scene::Scene;
use oslf_format::{Store, TextureKind};

fn orb_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/orb.toml");
    let mut scene = Scene::load(&path, None).expect("examples/orb.toml");
    // Small and fast: the store's layout, not its accuracy, is checked here.
    scene.bake.sample_count = oslf_bake::scene::SampleDensity::Count(60);
    scene.bake.cube_resolution = 8;
    scene.bake.sample_map_resolution = 16;
    scene.bake.samples_per_texel = 1;
    scene
}

#[test]
fn a_textured_glb_object_stores_its_texture_and_texture_coordinates() {
    let scene = orb_scene();
    let dir = tempfile::tempdir().unwrap();
    let output: PathBuf = dir.path().join("orb.oslf");
    let options = BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    bake(&scene, &options).unwrap();
    let store = Store::open(&output).unwrap();
    let object = &store.meta().objects[0];
    let mesh = object.mesh.as_ref().expect("a mesh object");
    let t = object
        .textures
        .as_ref()
        .expect("the orb's textures are stored");
    assert_eq!(t.texcoords.len(), mesh.positions.len());
    assert!(t.tangents.is_empty(), "no normal texture, no tangents");
    assert!(
        t.image(TextureKind::BaseColor).is_none(),
        "the base colour is a factor"
    );
    let mr = t
        .image(TextureKind::MetallicRoughness)
        .expect("roughness bands");
    assert_eq!((mr.width, mr.height), (4, 16));
    // The file's codes (make_orb_gltf): rows 0–3 roughness 0.05 … rows 12–15 0.6, metallic 1.
    for (row, g) in [(0, 13u8), (4, 38), (8, 77), (12, 153)] {
        for y in row..row + 4 {
            assert_eq!(mr.texels[y * 4], [0, g, 255, 255], "row {y}");
        }
    }
    // Each store vertex reads the file's texture coordinates: glTF v = 0 (the north pole) is the
    // store's v = 1, so the top vertex rows have v near 1.
    let top = mesh.positions.iter().map(|p| p[2]).fold(f32::MIN, f32::max);
    for (p, tc) in mesh.positions.iter().zip(&t.texcoords) {
        if p[2] > top - 1e-4 {
            assert!((tc[1] - 1.0).abs() < 1e-5, "north pole at v {}", tc[1]);
        }
        assert!((0.0..=1.0).contains(&tc[0]), "{tc:?}");
    }
}

#[test]
fn the_truth_reads_the_roughness_texture_at_each_pixel() {
    let scene = orb_scene();
    let camera = scene.camera.clone().expect("orb.toml has a camera");
    let truth = GroundTruth::new(&scene, camera).unwrap();
    let settings = TruthSettings {
        width: 64,
        height: 48,
        spp: 64,
        seed: 3,
    };
    let render = |metallic, roughness, object_material| {
        let term = Term::Pbr {
            metallic,
            roughness,
            object_material,
        };
        truth.render(term, &settings).unwrap().pixels
    };
    let own = render(1.0, 1.0, true);
    let smooth = render(1.0, 13.0 / 255.0, false);
    let rough = render(1.0, 38.0 / 255.0, false);
    // Same seed, same BRDF where the band's roughness equals the flag's: equal pixels in the
    // top band (0.05) and in the one below it (0.15).
    let (mut top, mut bottom) = (0, 0);
    for y in 0..settings.height {
        for x in 0..settings.width {
            let Some((_, hit)) = truth.primary_hit(x, y, settings.width, settings.height) else {
                continue;
            };
            let i = (y * settings.width + x) as usize;
            let same = |a: [f32; 4], b: [f32; 4]| {
                (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-4 * (1.0 + b[c]))
            };
            // Inside a band's texel centres (v 0.78–0.97 and 0.53–0.72): the texture repeats,
            // so at the poles it blends the top band with the bottom one.
            if (0.8..0.95).contains(&hit.uv.y) {
                assert!(
                    same(own[i], smooth[i]),
                    "top band pixel ({x}, {y}): {:?} vs {:?}",
                    own[i],
                    smooth[i]
                );
                top += 1;
            } else if (0.55..0.7).contains(&hit.uv.y) {
                assert!(
                    same(own[i], rough[i]),
                    "second band pixel ({x}, {y}): {:?} vs {:?}",
                    own[i],
                    rough[i]
                );
                bottom += 1;
            }
        }
    }
    assert!(
        top > 20 && bottom > 20,
        "{top} top and {bottom} second band pixels"
    );
    let differs = own
        .iter()
        .zip(&smooth)
        .filter(|(a, b)| (a[0] - b[0]).abs() > 1e-3)
        .count();
    assert!(
        differs > bottom / 2,
        "the bands differ from one roughness: {differs}"
    );
}
