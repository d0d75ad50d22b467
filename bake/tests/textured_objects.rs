//! A textured glTF object end to end on the bake side: examples/orb.toml's
//! gold orb, whose metallicRoughnessTexture bands its roughness, bakes into a store that carries
//! the texture with the file's own codes and one texture coordinate per store vertex; and the
//! ground truth shades each pixel with the roughness the texture holds there. A normal
//! texture goes into the store with MikkTSpace tangents, and turns the truth's normals.

use crate::gltf_builder;

use std::path::Path;

use oslf_bake::bake::{bake, BakeOptions};
use oslf_format::{Store, TextureKind};
use oslf_scene::scene::Scene;
use oslf_trace::ground_truth::{GroundTruth, Term, TruthSettings};

fn orb_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/orb.toml");
    let mut scene = Scene::load(&path, None).expect("examples/orb.toml");
    // Small and fast: the store's layout, not its accuracy, is checked here.
    scene.bake.sample_count = oslf_scene::scene::SampleDensity::Count(60);
    scene.bake.cube_resolution = 8;
    scene.bake.sample_map_resolution = 16;
    scene.bake.samples_per_texel = 1;
    scene
}

/// Bakes `scene` into `output` and opens the store.
fn bake_store(scene: &Scene, output: &Path) -> Store {
    let options = BakeOptions {
        output: output.to_path_buf(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    bake(scene, &options).unwrap();
    Store::open(output).unwrap()
}

#[test]
fn a_textured_glb_object_stores_its_texture_and_texture_coordinates() {
    let scene = orb_scene();
    let dir = tempfile::tempdir().unwrap();
    let store = bake_store(&scene, &dir.path().join("orb.oslf"));
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
    let camera = scene.camera.expect("orb.toml has a camera");
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
    // Inside a band's texel centres (v 0.78–0.97 and 0.53–0.72): the texture repeats, so at
    // the poles it blends the top band with the bottom one.
    let bands = [(0.8..0.95, &smooth, "top"), (0.55..0.7, &rough, "second")];
    let mut counts = [0usize; 2];
    for y in 0..settings.height {
        for x in 0..settings.width {
            let Some((_, hit)) = truth.primary_hit(x, y, settings.width, settings.height) else {
                continue;
            };
            let i = (y * settings.width + x) as usize;
            let Some(k) = bands.iter().position(|b| b.0.contains(&hit.uv.y)) else {
                continue;
            };
            let (_, want, name) = &bands[k];
            let same = (0..3).all(|c| (own[i][c] - want[i][c]).abs() <= 1e-4 * (1.0 + want[i][c]));
            assert!(
                same,
                "{name} band pixel ({x}, {y}): {:?} vs {:?}",
                own[i], want[i]
            );
            counts[k] += 1;
        }
    }
    let [top, bottom] = counts;
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

/// A normal-mapped metal square (2 × 2 texels tilting the normal four ways, scale 0.9) on
/// room.glb's table: `scene.toml` in `dir` includes `examples/room.glb` and `quad.glb`.
fn normal_mapped_scene(dir: &Path) -> Scene {
    use gltf_builder::Builder;
    let mut b = Builder::new();
    let s = 0.15;
    // glTF: y up; the square lies flat 5 cm above the table top (y = 0.78), normal +y.
    let pos = b.positions(&[[-s, 0.83, s], [s, 0.83, s], [s, 0.83, -s], [-s, 0.83, -s]]);
    let nor = b.vec3(&[[0.0, 1.0, 0.0]; 4]);
    let uv = b.vec2(&[[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let png = b.png(
        2,
        2,
        &[200, 128, 220, 60, 128, 220, 128, 200, 220, 128, 60, 220],
    );
    let doc = serde_json::json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Quad", "mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"name": "Hammered", "pbrMetallicRoughness": {"metallicFactor": 1.0,
            "roughnessFactor": 0.1}, "normalTexture": {"index": 0, "scale": 0.9}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nor,
            "TEXCOORD_0": uv}, "indices": idx, "material": 0}]}],
    });
    std::fs::write(dir.join("quad.glb"), b.glb(doc)).unwrap();
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/room.glb");
    std::fs::copy(room, dir.join("room.glb")).unwrap();
    let toml = r#"
[camera]
position = [0.5, -0.5, 1.3]
target = [0.0, 0.0, 0.83]
vfov = 40.0

[environment]
uniform = [0.55, 0.65, 0.85]

[[gltf]]
path = "room.glb"
transform = { rotate = [90.0, 0.0, 0.0] }

[[gltf]]
path = "quad.glb"
transform = { rotate = [90.0, 0.0, 0.0] }
objects = ["Quad"]

[bake]
epsilon = 0.01
sample_count = 40
cube_resolution = 8
sample_map_resolution = 16
samples_per_texel = 1
bounces = 1
"#;
    let path = dir.join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    Scene::load(&path, None).unwrap()
}

#[test]
fn a_normal_texture_is_stored_with_tangents_and_turns_the_truths_normals() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = normal_mapped_scene(dir.path());
    let store = bake_store(&scene, &dir.path().join("quad.oslf"));
    let object = &store.meta().objects[0];
    let mesh = object.mesh.as_ref().unwrap();
    let t = object
        .textures
        .as_ref()
        .expect("the normal texture is stored");
    let image = t.image(TextureKind::Normal).expect("normal image");
    assert_eq!(image.texels[0], [200, 128, 220, 255]);
    assert_eq!(t.normal_scale, 0.9);
    // MikkTSpace on the square: u runs along glTF +x (the scene's +x), v (up, the bake's
    // convention) along glTF −z, the scene's +y: tangent +x, bitangent n × t = +y, w = +1.
    assert_eq!(t.tangents.len(), mesh.positions.len());
    for tangent in &t.tangents {
        let d = glam::Vec4::from(*tangent) - glam::Vec4::new(1.0, 0.0, 0.0, 1.0);
        assert!(d.length() < 1e-4, "{tangent:?}");
    }
    // The truth: the texture turns the normals, so the reflections move.
    let camera = scene.camera.unwrap();
    let settings = TruthSettings {
        width: 48,
        height: 36,
        spp: 16,
        seed: 5,
    };
    let term = Term::Pbr {
        metallic: 1.0,
        roughness: 0.1,
        object_material: true,
    };
    let mapped = GroundTruth::new(&scene, camera)
        .unwrap()
        .render(term, &settings)
        .unwrap()
        .pixels;
    for m in &mut scene.materials {
        m.normal_texture = None;
    }
    let flat = GroundTruth::new(&scene, camera)
        .unwrap()
        .render(term, &settings)
        .unwrap()
        .pixels;
    let covered = flat.iter().filter(|p| p[3] > 0.5).count();
    let moved = mapped
        .iter()
        .zip(&flat)
        .filter(|(a, b)| b[3] > 0.5 && (0..3).any(|c| (a[c] - b[c]).abs() > 0.02 * (b[c] + 0.05)))
        .count();
    assert!(covered > 100, "the square covers {covered} pixels");
    assert!(
        moved * 2 > covered,
        "only {moved} of {covered} pixels changed"
    );
}

/// The pbr truth of `scene` (the orb's, with its own material) at 32 × 24, 8 paths per pixel,
/// with `seed`.
fn small_pbr_truth(scene: &Scene, seed: u64) -> Vec<[f32; 4]> {
    let camera = scene.camera.expect("orb.toml has a camera");
    let settings = TruthSettings {
        width: 32,
        height: 24,
        spp: 8,
        seed,
    };
    let term = Term::Pbr {
        metallic: 1.0,
        roughness: 0.5,
        object_material: true,
    };
    GroundTruth::new(scene, camera)
        .unwrap()
        .render(term, &settings)
        .unwrap()
        .pixels
}

/// The pbr truth adds the object's own emission (its factor times its emissive texture at the
/// hit, as the runtime does): with the same seed, an emitting orb's pixels are the dark orb's
/// plus its emission, plus the little its light adds to the table it reflects.
#[test]
fn the_pbr_truth_adds_the_objects_emission() {
    let mut scene = orb_scene();
    let render = |scene: &Scene| small_pbr_truth(scene, 9);
    let dark = render(&scene);
    let glow = glam::Vec3::new(0.5, 0.25, 0.125);
    let orb = scene.objects[0].material as usize;
    scene.materials[orb].emission = glow;
    let lit = render(&scene);
    let mut covered = 0;
    for (a, b) in lit.iter().zip(&dark) {
        if b[3] < 0.5 {
            assert_eq!(a, b, "off the orb nothing changes");
            continue;
        }
        covered += 1;
        for c in 0..3 {
            let added = a[c] - b[c];
            assert!(
                added >= glow[c] * (1.0 - 1e-4) && added < 1.5 * glow[c],
                "{a:?} vs {b:?}"
            );
        }
    }
    assert!(covered > 50, "{covered} orb pixels");
}

/// An occlusion texture scales the light the object reflects (glTF's `occlusionTexture`, as
/// the runtime's pbr mode draws it): the store holds it with its strength, and with the same
/// seed the truth's orb pixels are those without it times `1 + strength·(R − 1)`, its
/// emission added unscaled.
#[test]
fn an_occlusion_texture_is_stored_and_scales_the_reflected_light() {
    use oslf_scene::material::OcclusionTexture;
    use oslf_scene::texture::{ImageTexture, Texture};
    let mut scene = orb_scene();
    let render = |scene: &Scene| small_pbr_truth(scene, 3);
    let orb = scene.objects[0].material as usize;
    let glow = glam::Vec3::new(0.05, 0.1, 0.0);
    scene.materials[orb].emission = glow;
    let open = render(&scene);
    // Red 0.4 at strength 0.5: the orb reflects 0.7 of its light.
    let image = ImageTexture::from_pixels(1, 1, vec![glam::Vec3::new(0.4, 0.8, 0.8)]).unwrap();
    scene.materials[orb].occlusion_texture = Some(OcclusionTexture {
        texture: Texture::Image(std::sync::Arc::new(image)),
        strength: 0.5,
    });
    let occluded = render(&scene);
    let mut covered = 0;
    for (a, b) in occluded.iter().zip(&open) {
        if b[3] < 0.5 {
            assert_eq!(a, b, "off the orb nothing changes");
            continue;
        }
        covered += 1;
        for c in 0..3 {
            let want = (b[c] - glow[c]) * 0.7 + glow[c];
            assert!((a[c] - want).abs() <= 1e-5 * (1.0 + want), "{a:?} vs {b:?}");
        }
    }
    assert!(covered > 50, "{covered} orb pixels");
    let dir = tempfile::tempdir().unwrap();
    let store = bake_store(&scene, &dir.path().join("orb.oslf"));
    let t = store.meta().objects[0].textures.as_ref().unwrap();
    assert_eq!(t.occlusion_strength, 0.5);
    let image = t.image(TextureKind::Occlusion).expect("occlusion image");
    assert_eq!(image.texels, [[102, 204, 204, 255]]);
}
