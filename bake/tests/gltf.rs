//! glTF 2.0 scenes: files written here, read back, checked against hand-computed values.

use crate::gltf_builder;

use std::f32::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec2, Vec3};
use gltf_builder::{Builder, U8};
use oslf_scene::environment::Environment;
use oslf_scene::gltf::{load, Import, Options};
use oslf_scene::light::Light;
use oslf_scene::material::Material;
use oslf_scene::scene::Scene;
use oslf_shading::color::srgb_to_linear;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::integrator::Integrator;
use serde_json::json;

/// A fresh directory for one test, under Cargo's target tmp; the next run replaces it.
fn dir(test: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("gltf/{test}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

fn import(path: &Path, options: &Options) -> (Import, Vec<Material>) {
    let mut materials = Vec::new();
    let import = load(path, options, &mut materials).unwrap();
    (import, materials)
}

fn load_err(path: &Path) -> String {
    let mut materials = Vec::new();
    match load(path, &Options::default(), &mut materials) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e.to_string(),
    }
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn node_transforms_compose_with_the_include_transform() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let doc = json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"name": "Parent", "translation": [1, 2, 3], "scale": [2, 2, 2], "children": [1]},
            // 90° about z, then translate (1, 0, 0); column-major.
            {"name": "Child", "mesh": 0,
             "matrix": [0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1]},
            // 90° about y.
            {"name": "Rotated", "mesh": 0, "rotation": [0, h, 0, h]},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    let d = dir("transforms");
    let path = write(&d, "t.glb", &b.glb(doc));
    let options = Options {
        transform: Affine3A::from_translation(Vec3::new(10.0, 0.0, 0.0))
            * Affine3A::from_rotation_x(FRAC_PI_2),
        ..Default::default()
    };
    let (import, _) = import(&path, &options);
    assert_eq!(import.shapes.len(), 2);
    // Child: Rz90 then +x; parent: ×2 then +(1, 2, 3) → (3,2,3), (3,4,3), (1,2,3);
    // include: (x, y, z) → (x + 10, −z, y).
    let m = &import.shapes[0].mesh;
    assert_eq!(m.triangles.len(), 1);
    let expect = [
        Vec3::new(13.0, -3.0, 2.0),
        Vec3::new(13.0, -3.0, 4.0),
        Vec3::new(11.0, -3.0, 2.0),
    ];
    for (k, e) in expect.iter().enumerate() {
        let t = m.triangles[0][k] as usize;
        assert!(close(m.positions[t], *e), "{k}: {} vs {e}", m.positions[t]);
        // No NORMAL: the flat normal, +z in the file, −y in the scene.
        assert!(close(m.normals[t], Vec3::NEG_Y), "{}", m.normals[t]);
    }
    // Ry90: (1, 0, 0) → (0, 0, −1) → include → (10, 1, 0).
    let m = &import.shapes[1].mesh;
    let p1 = m.positions[m.triangles[0][1] as usize];
    assert!(close(p1, Vec3::new(10.0, 1.0, 0.0)), "{p1}");
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
}

#[test]
fn indexed_non_indexed_strip_and_fan_primitives() {
    let mut b = Builder::new();
    let six = b.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
        [2.0, 1.0, 0.0],
    ]);
    let quad = b.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ]);
    let up4 = b.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let i16 = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let i8 = b.indices_u8(&[0, 1, 2, 3]);
    let five = b.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ]);
    let up5 = b.vec3(&[[0.0, 0.0, 1.0]; 5]);
    let i32 = b.indices_u32(&[0, 1, 2, 3, 4]);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "Parts", "primitives": [
            {"attributes": {"POSITION": six}},
            {"attributes": {"POSITION": quad, "NORMAL": up4}, "indices": i16},
            {"attributes": {"POSITION": quad, "NORMAL": up4}, "indices": i8, "mode": 5},
            {"attributes": {"POSITION": five, "NORMAL": up5}, "indices": i32, "mode": 6},
        ]}],
    });
    let d = dir("primitives");
    // Also the .gltf forms: data URI and external buffer.
    let glb = write(&d, "p.glb", &b.glb(doc.clone()));
    let embedded = write(&d, "p.gltf", &b.gltf_embedded(doc.clone()));
    let (text, bin) = b.gltf_external(doc, "p%20data.bin");
    let external = write(&d, "external.gltf", &text);
    write(&d, "p data.bin", &bin);
    for path in [glb, embedded, external] {
        let (import, _) = import(&path, &Options::default());
        let s = &import.shapes;
        assert_eq!(s.len(), 4, "{}", path.display());
        // Non-indexed, no normals: two flat triangles.
        assert_eq!(s[0].mesh.triangles.len(), 2);
        let t = s[0].mesh.triangles[1];
        assert!(close(
            s[0].mesh.positions[t[2] as usize],
            Vec3::new(2.0, 1.0, 0.0)
        ));
        // Indexed u16, with normals: the vertices as they are.
        assert_eq!(s[1].mesh.positions.len(), 4);
        assert_eq!(s[1].mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(close(s[1].mesh.normals[2], Vec3::Z));
        // Strip: the odd triangle's first two swapped to keep the winding.
        assert_eq!(s[2].mesh.triangles, vec![[0, 1, 2], [2, 1, 3]]);
        // Fan around vertex 0.
        assert_eq!(s[3].mesh.triangles, vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        assert!((s[3].mesh.area() - 1.5).abs() < 1e-6);
        assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    }
}

/// sRGB 2×2: red, green / blue, grey 128.
const TEXELS: [u8; 12] = [255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128];

#[test]
fn base_colour_factor_texture_and_texture_transform() {
    let mut b = Builder::new();
    let png = b.png(2, 2, &TEXELS);
    let pos = b.positions(&TRIANGLE);
    let uv = |b: &mut Builder, a: [f32; 2]| b.vec2(&[a, [0.0, 0.0], [1.0, 0.0]]);
    let uv0 = uv(&mut b, [0.5, 1.5]);
    let uv1 = uv(&mut b, [-0.25, 0.75]);
    let uv_clamp = b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    let uv_red = b.vec2(&[[0.25, 0.25]; 3]);
    let uv_grey = b.vec2(&[[0.75, 0.75]; 3]);
    let doc = json!({
        "extensionsUsed": ["KHR_texture_transform"],
        "nodes": [{"mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}, {"wrapS": 33071, "wrapT": 33071}],
        "textures": [{"source": 0}, {"source": 0, "sampler": 0}, {"source": 0, "sampler": 1}],
        "materials": [
            {"name": "Offset", "pbrMetallicRoughness": {"metallicFactor": 0,
                "baseColorFactor": [0.5, 1, 1, 1],
                "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                    {"offset": [0.5, 0], "scale": [0.5, 0.5]}}}}},
            {"name": "Rotated", "pbrMetallicRoughness": {"metallicFactor": 0,
                "baseColorTexture": {"index": 1, "extensions": {"KHR_texture_transform":
                    {"rotation": FRAC_PI_2}}}}},
            {"name": "Plain", "pbrMetallicRoughness": {"metallicFactor": 0,
                "baseColorFactor": [0.2, 0.4, 0.6, 1]}},
            {"name": "Clamped", "pbrMetallicRoughness": {"metallicFactor": 0,
                "baseColorTexture": {"index": 2}}},
            {"name": "Set1", "pbrMetallicRoughness": {"metallicFactor": 0,
                "baseColorTexture": {"index": 0, "texCoord": 0,
                    "extensions": {"KHR_texture_transform": {"texCoord": 1}}}}},
        ],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv0}, "material": 0},
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv1}, "material": 1},
            {"attributes": {"POSITION": pos}, "material": 2},
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv_clamp}, "material": 3},
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv_red, "TEXCOORD_1": uv_grey},
             "material": 4},
            {"attributes": {"POSITION": pos}},
        ]}],
    });
    let d = dir("materials");
    let path = write(&d, "m.glb", &b.glb(doc));
    let (import, materials) = import(&path, &Options::default());
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    let albedo = |shape: usize, corner: usize| {
        let s = &import.shapes[shape];
        let v = s.mesh.triangles[0][corner] as usize;
        materials[s.material as usize].eval(s.mesh.uvs[v])
    };
    let grey = srgb_to_linear(128.0 / 255.0);
    assert!((grey - 0.215_861).abs() < 1e-5);
    // (0.5, 1.5) × ½ + (½, 0) = (0.75, 0.75): the bottom-right texel's centre (v down in
    // glTF), times the factor (0.5, 1, 1).
    let a = albedo(0, 0);
    assert!(close(a, Vec3::new(0.5 * grey, grey, grey)), "{a}");
    // Rotation π/2: (−0.25, 0.75) → (0.75, 0.25): top-right, green.
    let a = albedo(1, 0);
    assert!(close(a, Vec3::Y), "{a}");
    // The factor alone.
    assert!(close(albedo(2, 1), Vec3::new(0.2, 0.4, 0.6)));
    // CLAMP_TO_EDGE: the corners read the corner texels unblended.
    assert!(close(albedo(3, 0), Vec3::X), "{}", albedo(3, 0));
    assert!(close(albedo(3, 1), Vec3::Y), "{}", albedo(3, 1));
    assert!(close(albedo(3, 2), Vec3::Z), "{}", albedo(3, 2));
    // texCoord overridden by the transform: TEXCOORD_1, the grey texel.
    assert!(close(albedo(4, 0), Vec3::splat(grey)), "{}", albedo(4, 0));
    // No material: glTF's default, white.
    assert!(close(albedo(5, 0), Vec3::ONE));
}

fn lights_doc(b: &mut Builder) -> serde_json::Value {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let _ = b;
    json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "Bulb", "type": "point", "color": [1, 0.5, 0.25], "intensity": 683},
            {"name": "Spot", "type": "spot", "intensity": 1366,
             "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}},
            {"name": "Sun", "type": "directional", "intensity": 2049},
        ]}},
        "nodes": [
            {"translation": [1, 2, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            // −90° about x: the light's −z looks along −y.
            {"translation": [0, 5, 0], "rotation": [-h, 0, 0, h],
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"extensions": {"KHR_lights_punctual": {"light": 2}}},
        ],
    })
}

#[test]
fn lights_and_their_unit_conversion() {
    let mut b = Builder::new();
    let doc = lights_doc(&mut b);
    let d = dir("lights");
    let path = write(&d, "l.gltf", &b.gltf_embedded(doc));
    let (import, _) = import(&path, &Options::default());
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    let [point, spot, sun] = &import.lights[..] else {
        panic!("{:?}", import.lights)
    };
    // 683 cd × 1/683 W/lm = 1 W/sr, times the colour.
    match point {
        Light::Point {
            position,
            intensity,
        } => {
            assert!(close(*position, Vec3::new(1.0, 2.0, 3.0)));
            assert!(close(*intensity, Vec3::new(1.0, 0.5, 0.25)), "{intensity}");
        }
        other => panic!("{other:?}"),
    }
    match spot {
        Light::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            assert!(close(*position, Vec3::new(0.0, 5.0, 0.0)));
            assert!(close(*direction, Vec3::NEG_Y), "{direction}");
            assert!(close(*intensity, Vec3::splat(2.0)));
            assert_eq!((*inner_angle, *outer_angle), (0.3, 0.6));
        }
        other => panic!("{other:?}"),
    }
    // Directional: 2049 lx → 3 W/m², towards the light = the node's +z.
    match sun {
        Light::Sun {
            direction,
            irradiance,
            angular_radius,
        } => {
            assert!(close(*direction, Vec3::Z));
            assert!(close(*irradiance, Vec3::splat(3.0)));
            assert_eq!(*angular_radius, 0.0);
        }
        other => panic!("{other:?}"),
    }
    // Rotated from Y-up to Z-up, another conversion factor.
    let options = Options {
        transform: Affine3A::from_rotation_x(FRAC_PI_2),
        watts_per_lumen: 0.01,
        lights: true,
        ..Default::default()
    };
    let (import, _) = self::import(&path, &options);
    let Light::Point {
        position,
        intensity,
    } = import.lights[0]
    else {
        panic!()
    };
    assert!(close(position, Vec3::new(1.0, -3.0, 2.0)));
    assert!(
        close(intensity, Vec3::new(6.83, 3.415, 1.7075)),
        "{intensity}"
    );
    let Light::Spot { direction, .. } = import.lights[1] else {
        panic!()
    };
    assert!(close(direction, Vec3::NEG_Z), "{direction}");
    let Light::Sun { direction, .. } = import.lights[2] else {
        panic!()
    };
    assert!(close(direction, Vec3::NEG_Y), "{direction}");
    // lights = false
    let options = Options {
        lights: false,
        ..Default::default()
    };
    assert!(self::import(&path, &options).0.lights.is_empty());
}

#[test]
fn spot_light_shades_a_floor_in_a_path_traced_view() {
    // A grey floor (y = 0, glTF Y-up) under a spot 2 above, seen by a camera looking down.
    let mut b = Builder::new();
    let floor = b.positions(&[
        [-5.0, 0.0, 5.0],
        [5.0, 0.0, 5.0],
        [5.0, 0.0, -5.0],
        [-5.0, 0.0, -5.0],
    ]);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let doc = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "intensity": 2732,
             "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}]}},
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "Floor", "mesh": 0},
            {"name": "Spot", "translation": [0, 2, 0], "rotation": [-h, 0, 0, h],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "Eye", "camera": 0, "translation": [0, 4, 0], "rotation": [-h, 0, 0, h]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
            "metallicFactor": 0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": floor}, "indices": idx,
            "material": 0}]}],
    });
    let d = dir("spot-render");
    let path = write(&d, "floor.glb", &b.glb(doc));
    let mut scene = Scene::from_gltf(&path).unwrap();
    assert!(scene.objects.is_empty());
    assert_eq!(scene.bake.epsilon, 0.1);
    // Z-up now: the camera 4 above the floor, looking down; the spot 2 above it.
    let camera = scene.camera.unwrap();
    assert!(
        close(camera.position, Vec3::new(0.0, 0.0, 4.0)),
        "{}",
        camera.position
    );
    assert!(close(camera.target, Vec3::new(0.0, 0.0, 3.0)));
    scene.environment = Environment::Constant(Vec3::ZERO);
    let geometry =
        TriangleScene::build(oslf_trace::bvh::scene_instances(&scene, false, 0.01)).unwrap();
    let integrator = Integrator::for_scene(&scene, &geometry);
    let (pixels, _) = oslf_trace::preview::render(&integrator, &camera, 9, 9, 4, 1);
    // Centre (inside the inner cone): E = 4 W/sr / 2² = 1 W/m², L = f E, less cos³ over the
    // pixel's 0.11 half-width on the floor (under 0.5 %). The material is glTF's dielectric
    // at roughness 1 (the default): at normal incidence Fresnel is 0.04, D = 1/π, V = 1/4, so
    // f = 0.96 · 0.5/π + 0.04 / (4π).
    let centre = pixels[4 * 9 + 4];
    let pi = std::f32::consts::PI;
    let expect = 0.96 * 0.5 / pi + 0.04 / (4.0 * pi);
    assert!((centre.x - expect).abs() < 5e-3 * expect, "{centre}");
    // The corners see the floor 1.4 from the axis, 0.62 rad off the spot's axis: beyond its
    // 0.5 rad cone, dark. Nothing is brighter than the centre.
    assert!(pixels[0].x < 1e-6, "{}", pixels[0]);
    assert!(pixels
        .iter()
        .all(|p| p.is_finite() && p.x <= centre.x + 1e-6));
}

#[test]
fn camera_from_gltf_and_include_transform_in_a_toml_scene() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let doc = json!({
        "nodes": [
            {"name": "Cam", "camera": 0, "translation": [0, 1, 5]},
            {"name": "Flat", "camera": 1},
            {"name": "Tri", "mesh": 0, "translation": [1, 0, 0]},
        ],
        "cameras": [
            {"name": "Lens", "type": "perspective",
             "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1}},
            {"type": "orthographic",
             "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    let d = dir("camera");
    let path = write(&d, "room.glb", &b.glb(doc));
    let (import, _) = import(&path, &Options::default());
    assert_eq!(import.cameras.len(), 1);
    let c = &import.cameras[0];
    assert_eq!(c.node, "Cam");
    assert_eq!(c.name.as_deref(), Some("Lens"));
    assert_eq!(c.aspect_ratio, Some(1.5));
    assert!(close(c.camera.position, Vec3::new(0.0, 1.0, 5.0)));
    assert!(close(c.camera.target, Vec3::new(0.0, 1.0, 4.0)));
    assert!(close(c.camera.up, Vec3::Y));
    assert!((c.camera.vfov_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!(import.warnings.len(), 1, "{:?}", import.warnings);
    assert!(
        import.warnings[0].contains("nodes[1] \"Flat\"")
            && import.warnings[0].contains("orthographic"),
        "{:?}",
        import.warnings
    );

    // In a TOML scene, rotated Y-up → Z-up, scaled and moved.
    let toml = |camera: &str| {
        format!(
            r#"
{camera}
[[object]]
patches = "newell-teapot"
material = {{ color = [0.5, 0.5, 0.5] }}

[[plane]]
size = [1, 1]
material = {{ color = [0.1, 0.1, 0.1] }}

[[gltf]]
path = "room.glb"
transform = {{ translate = [0, 0, 1], rotate = [90, 0, 0], scale = 2 }}
"#
        )
    };
    let scene_path = d.join("scene.toml");
    let scene = Scene::from_str(&toml("[camera]\ngltf = \"Cam\""), &scene_path, None).unwrap();
    let cam = scene.camera.unwrap();
    // (0, 1, 5) ×2 → (0, 2, 10) → Rx90 → (0, −10, 2) → +z → (0, −10, 3).
    assert!(
        close(cam.position, Vec3::new(0.0, -10.0, 3.0)),
        "{}",
        cam.position
    );
    assert!(close(cam.up, Vec3::Z));
    assert!(close((cam.target - cam.position).normalize(), Vec3::Y));
    // The plane first, then the glTF triangle: (1,0,0)+(0,1,0)... vertex (1, 1, 0) → ×2 →
    // (2, 2, 0) → (2, 0, 2) → (2, 0, 3).
    assert_eq!(scene.shapes.len(), 2);
    let tri = &scene.shapes[1].mesh;
    let v = tri.positions[tri.triangles[0][2] as usize];
    assert!(close(v, Vec3::new(2.0, 0.0, 3.0)), "{v}");
    assert_eq!(scene.warnings.len(), 1);
    // The camera is also found by the camera's own name; without [camera], the first one.
    let by_name = Scene::from_str(&toml("[camera]\ngltf = \"Lens\""), &scene_path, None).unwrap();
    assert_eq!(by_name.camera, scene.camera);
    let first = Scene::from_str(&toml(""), &scene_path, None).unwrap();
    assert_eq!(first.camera, scene.camera);
    // Unknown names and mixed keys are located errors.
    let e = Scene::from_str(&toml("[camera]\ngltf = \"Nope\""), &scene_path, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scene.toml:3:") && e.contains("\"Nope\"") && e.contains("\"Cam\""),
        "{e}"
    );
    let e = Scene::from_str(
        &toml("[camera]\ngltf = \"Cam\"\nvfov = 30"),
        &scene_path,
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("gltf"), "{e}");
    let e = Scene::from_str(&toml("[camera]\nvfov = 30"), &scene_path, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("position") && e.contains("target"), "{e}");
    // A missing include is a located error.
    let text = toml("").replace("room.glb", "nowhere.glb");
    let e = Scene::from_str(&text, &scene_path, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("file not found") && e.contains("nowhere.glb"),
        "{e}"
    );
}

#[test]
fn a_gltf_file_without_a_marked_object_is_refused_with_a_reason() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    let d = dir("direct");
    let path = write(&d, "only.glb", &b.glb(doc));
    let e = Scene::load(&path, None).unwrap_err().to_string();
    assert!(
        e.contains("only.glb") && e.contains("no node is marked as an OSLF object"),
        "{e}"
    );
    // Its defaults: a camera framing the bounds, a white uniform environment, no object.
    let scene = Scene::from_gltf(&path).unwrap();
    let cam = scene.camera.unwrap();
    // The triangle, Z-up: (0,0,0), (1,0,0), (0,0,1); centre (0.5, 0, 0.5).
    assert!(
        close(cam.target, Vec3::new(0.5, 0.0, 0.5)),
        "{}",
        cam.target
    );
    assert!(cam.position.y < 0.0 && cam.position.z > cam.target.z);
    assert!(matches!(scene.environment, Environment::Constant(c) if c == Vec3::ONE));
    assert!(scene.objects.is_empty() && scene.lights.is_empty());
    assert_eq!(scene.shapes.len(), 1);
}

#[test]
fn unsupported_features_warn_naming_what_uses_them() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let doc = json!({
        "extensionsUsed": ["KHR_materials_variants", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 1, "range": 4}]}},
        "nodes": [
            {"name": "Body", "mesh": 0, "skin": 0},
            {"name": "Bone"},
            {"name": "Lamp", "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "scenes": [{"nodes": [0, 1, 2]}, {"name": "Other", "nodes": []}],
        "skins": [{"joints": [1]}],
        "materials": [{"name": "Glow", "emissiveFactor": [1, 0, 0], "alphaMode": "BLEND",
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5}}}],
        "meshes": [{"name": "Wire", "primitives": [
            {"attributes": {"POSITION": pos}, "material": 0},
            {"attributes": {"POSITION": pos}, "mode": 1},
        ]}],
    });
    let d = dir("warnings");
    let path = write(&d, "w.glb", &b.glb(doc));
    let (import, _) = import(&path, &Options::default());
    let all = import.warnings.join("\n");
    let has = |a: &str, b: &str| {
        import
            .warnings
            .iter()
            .any(|w| w.starts_with("w.glb: ") && w.contains(a) && w.contains(b))
    };
    assert!(has("KHR_materials_variants", "not supported"), "{all}");
    assert!(!all.contains("KHR_materials_emissive_strength"), "{all}");
    assert!(has("nodes[0] \"Body\"", "skins"), "{all}");
    assert!(has("materials[0] \"Glow\"", "alphaMode"), "{all}");
    assert!(has("meshes[0] \"Wire\" primitive 1", "Lines"), "{all}");
    assert!(has("nodes[2] \"Lamp\"", "range"), "{all}");
    assert!(has("2 scenes", "scenes[0]"), "{all}");
    // The triangle is still there; the lines are not.
    assert_eq!(import.shapes.len(), 1);
    assert_eq!(import.lights.len(), 1);
}

/// A valid one-triangle document to break in the error tests.
fn triangle_doc(b: &mut Builder) -> serde_json::Value {
    let pos = b.positions(&TRIANGLE);
    let idx = b.indices_u16(&[0, 1, 2]);
    json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
    })
}

#[test]
fn invalid_files_name_the_file_and_the_json_path() {
    let d = dir("errors");
    let check = |name: &str, bytes: &[u8], wants: &[&str]| {
        let path = write(&d, name, bytes);
        let e = load_err(&path);
        assert!(e.contains(name), "{name}: {e}");
        for w in wants {
            assert!(e.contains(w), "{name}: {e:?} lacks {w:?}");
        }
    };
    // Not JSON.
    check(
        "bad.gltf",
        b"{\"asset\": {\"version\": \"2.0\"},",
        &["JSON", "line 1"],
    );
    // A buffer file that is not there.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    let (text, _) = b.gltf_external(doc, "gone.bin");
    check("missing.gltf", &text, &["buffers[0].uri", "gone.bin"]);
    // An accessor that reads past its buffer view.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    b.accessors[0]["count"] = json!(4);
    check(
        "range.glb",
        &b.glb(doc),
        &[
            "meshes[0].primitives[0].attributes.POSITION",
            "accessor 0",
            "runs past the end",
        ],
    );
    // An index beyond the vertices.
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let idx = b.indices_u16(&[0, 1, 7]);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
    });
    check(
        "index.glb",
        &b.glb(doc),
        &[
            "meshes[0].primitives[0].indices",
            "accessor 1",
            "index 7",
            "3 vertices",
        ],
    );
    // Positions of the wrong component type.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    b.accessors[0]["componentType"] = json!(U8);
    b.accessors[0]["normalized"] = json!(false);
    check(
        "type.glb",
        &b.glb(doc),
        &[
            "meshes[0].primitives[0].attributes.POSITION",
            "accessor 0 has 3 components of type u8, expected f32 vec3",
        ],
    );
    // An attribute naming an accessor the file does not have.
    let mut b = Builder::new();
    let mut doc = triangle_doc(&mut b);
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    check(
        "noaccessor.glb",
        &b.glb(doc),
        &["attributes.POSITION", "accessor 9 does not exist"],
    );
    // Indices naming an accessor the file does not have (the crate's validation).
    let mut b = Builder::new();
    let mut doc = triangle_doc(&mut b);
    doc["meshes"][0]["primitives"][0]["indices"] = json!(9);
    check(
        "noindices.glb",
        &b.glb(doc),
        &["meshes[0].primitives[0].indices", "index out of range"],
    );
    // A NaN position.
    let mut b = Builder::new();
    let pos = b.positions(&[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    check(
        "nan.glb",
        &b.glb(doc),
        &["attributes.POSITION", "vertex 1", "not finite"],
    );
    // A buffer view beyond its buffer.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    b.views[0]["byteLength"] = json!(4000);
    check(
        "view.glb",
        &b.glb(doc),
        &["bufferViews[0]", "outside buffer 0"],
    );
    // A GLB without the BIN chunk its buffer needs.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    let document = b.document(doc, None);
    check(
        "nobin.glb",
        &gltf_builder::glb_from(&document, &[]),
        &["buffers[0]", "BIN chunk"],
    );
    // A truncated GLB.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    let glb = b.glb(doc);
    check("cut.glb", &glb[..glb.len() / 2], &["GLB header"]);
    // A broken data URI.
    let mut b = Builder::new();
    let doc = triangle_doc(&mut b);
    let mut document = b.document(doc, Some("data:application/octet-stream;base64,@@@".into()));
    document["buffers"][0]["byteLength"] = json!(3);
    check(
        "uri.gltf",
        &serde_json::to_vec(&document).unwrap(),
        &["buffers[0].uri", "base64"],
    );
    // A node that is its own descendant.
    let mut b = Builder::new();
    let mut doc = triangle_doc(&mut b);
    doc["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    doc["scenes"] = json!([{"nodes": [0]}]);
    check("cycle.glb", &b.glb(doc), &["nodes[0]", "twice"]);
    // A spot light whose cone is wider than a hemisphere.
    let mut b = Builder::new();
    let mut doc = triangle_doc(&mut b);
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {"innerConeAngle": 0.2, "outerConeAngle": 2.0}}]}});
    doc["nodes"][0]["extensions"] = json!({"KHR_lights_punctual": {"light": 0}});
    check(
        "cone.glb",
        &b.glb(doc),
        &[
            "extensions.KHR_lights_punctual.lights[0]",
            "outer cone angle",
        ],
    );
    // A required extension that is not supported.
    let mut b = Builder::new();
    let mut doc = triangle_doc(&mut b);
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    check(
        "draco.glb",
        &b.glb(doc),
        &["extensionsRequired[0]", "does not support"],
    );
}

#[test]
fn texture_coordinates_decode_normalized_integers() {
    // TEXCOORD_0 as normalized u8: 191/255 ≈ 0.75 reads the bottom-right texel.
    let mut b = Builder::new();
    let png = b.png(2, 2, &TEXELS);
    let pos = b.positions(&TRIANGLE);
    let uv = b.accessor(&[191, 191, 0, 0, 255, 0], U8, "VEC2", 3);
    b.accessors[uv]["normalized"] = json!(true);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0,
            "baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
            "material": 0}]}],
    });
    let d = dir("normalized");
    let path = write(&d, "n.glb", &b.glb(doc));
    let (import, materials) = import(&path, &Options::default());
    let s = &import.shapes[0];
    let uv0: Vec2 = s.mesh.uvs[s.mesh.triangles[0][0] as usize];
    let a = materials[s.material as usize].eval(uv0);
    // 191/255 is 0.749, a hair off the texel centre: nearly all grey.
    let grey = srgb_to_linear(128.0 / 255.0);
    assert!((a - Vec3::splat(grey)).length() < 0.01, "{a}");
}

#[test]
fn sparse_accessors_substitute_values() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let iv = b.view(&[1]);
    let vals: Vec<u8> = [5f32, 0.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let vv = b.view(&vals);
    let sparse = json!({"count": 1, "indices": {"bufferView": iv, "componentType": U8},
        "values": {"bufferView": vv}});
    b.accessors[pos]["sparse"] = sparse.clone();
    // The same, without a base view: zeros, then the substitution.
    b.accessors
        .push(json!({"componentType": 5126, "count": 3, "type": "VEC3",
        "min": [0, 0, 0], "max": [5, 0, 0], "sparse": sparse}));
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": pos}},
            {"attributes": {"POSITION": 1}},
        ]}],
    });
    let d = dir("sparse");
    let path = write(&d, "s.glb", &b.glb(doc));
    // The second primitive is degenerate (all on the x axis) but still read.
    let (import, _) = import(&path, &Options::default());
    let m = &import.shapes[0].mesh;
    assert!(close(
        m.positions[m.triangles[0][1] as usize],
        Vec3::new(5.0, 0.0, 0.0)
    ));
    assert!(close(m.positions[m.triangles[0][2] as usize], Vec3::Y));
    let m = &import.shapes[1].mesh;
    assert!(close(
        m.positions[m.triangles[0][1] as usize],
        Vec3::new(5.0, 0.0, 0.0)
    ));
    assert!(close(m.positions[m.triangles[0][2] as usize], Vec3::ZERO));
    // A sparse index beyond the accessor's elements is an error naming the accessor.
    let mut b2 = Builder::new();
    let pos = b2.positions(&TRIANGLE);
    let iv = b2.view(&[7]);
    let vv = b2.view(&vals);
    b2.accessors[pos]["sparse"] = json!({"count": 1,
        "indices": {"bufferView": iv, "componentType": U8}, "values": {"bufferView": vv}});
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    let path = write(&d, "bad-sparse.glb", &b2.glb(doc));
    let e = load_err(&path);
    assert!(
        e.contains("bad-sparse.glb")
            && e.contains("accessors[0].sparse.indices")
            && e.contains("index 7"),
        "{e}"
    );
}

#[test]
fn damaged_files_give_errors_not_panics() {
    // Every byte of a small textured GLB overwritten in turn: each load either succeeds or
    // gives an error, and never reaches the importer's panic guard.
    let mut b = Builder::new();
    let png = b.png(2, 2, &TEXELS);
    let mut doc = triangle_doc(&mut b);
    let uv = b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["images"] = json!([{"bufferView": png, "mimeType": "image/png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    doc["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_texture_transform"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {"outerConeAngle": 0.5}}]}});
    doc["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 1, "znear": 0.1}}]);
    doc["nodes"] = json!([
        {"mesh": 0, "children": [1, 2]},
        {"camera": 0, "translation": [0, 0, 1]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [0, 0, 0, 1]},
    ]);
    let glb = b.glb(doc);
    let d = dir("damaged");
    let path = d.join("d.glb");
    let (mut ok, mut failed) = (0, 0);
    for i in 0..glb.len() {
        for value in [0xff, glb[i] ^ 0x10] {
            let mut bytes = glb.clone();
            bytes[i] = value;
            std::fs::write(&path, &bytes).unwrap();
            let mut materials = Vec::new();
            match load(&path, &Options::default(), &mut materials) {
                Ok(_) => ok += 1,
                Err(e) => {
                    let e = e.to_string();
                    assert!(!e.contains("parser failed"), "byte {i} = {value}: {e}");
                    assert!(e.contains("d.glb"), "{e}");
                    failed += 1;
                }
            }
        }
    }
    assert!(ok > 0 && failed > 0, "{ok} {failed}");
}

#[test]
fn accessors_without_a_buffer_view_are_zeros() {
    // TEXCOORD_0 with no bufferView and no sparse values: every coordinate (0, 0), which
    // reads the texture's bottom-left texel (glTF's v = 0 is the image's top).
    let mut b = Builder::new();
    let png = b.png(2, 2, &TEXELS);
    let pos = b.positions(&TRIANGLE);
    b.accessors
        .push(json!({"componentType": 5126, "count": 3, "type": "VEC2"}));
    let uv = b.accessors.len() - 1;
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0,
            "baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
            "material": 0}]}],
    });
    let d = dir("zeros");
    let path = write(&d, "z.glb", &b.glb(doc));
    let (import, _) = import(&path, &Options::default());
    let s = &import.shapes[0];
    assert!(
        s.mesh.uvs.iter().all(|&uv| uv == Vec2::new(0.0, 1.0)),
        "{:?}",
        s.mesh.uvs
    );
}

#[test]
fn metallic_roughness_factors_become_the_material() {
    use oslf_scene::material::Model;
    let doc = |metallic: f32| {
        let mut b = Builder::new();
        let pos = b.positions(&TRIANGLE);
        let doc = json!({
            "nodes": [{"mesh": 0}, {"mesh": 1}],
            "materials": [
                {"name": "Brass", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.7, 0.3, 1],
                    "metallicFactor": metallic, "roughnessFactor": 0.25}},
            ],
            "meshes": [
                {"primitives": [{"attributes": {"POSITION": pos}, "material": 0}]},
                {"primitives": [{"attributes": {"POSITION": pos}}]},
            ],
        });
        b.glb(doc)
    };
    let d = dir("metallic-roughness");
    let path = write(&d, "m.glb", &doc(1.0));
    let (import, materials) = import(&path, &Options::default());
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    let model = |s: usize| materials[import.shapes[s].material as usize].model;
    assert_eq!(
        model(0),
        Model::MetallicRoughness {
            metallic: 1.0,
            roughness: 0.25
        }
    );
    // No material: glTF's default, drawn white Lambertian.
    assert_eq!(model(1), Model::Lambertian);
    let path = write(&d, "bad.glb", &doc(1.5));
    let err = load_err(&path);
    assert!(
        err.contains("materials[0].pbrMetallicRoughness.metallicFactor"),
        "{err}"
    );
}

#[test]
fn emissive_factor_and_strength_make_the_emission() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let doc = json!({
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "nodes": [{"mesh": 0}],
        "materials": [{"name": "Lamp", "emissiveFactor": [1.0, 0.5, 0.25],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "material": 0}]}],
    });
    let d = dir("emissive");
    let path = write(&d, "lamp.glb", &b.glb(doc));
    let (import, materials) = import(&path, &Options::default());
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    let m = &materials[import.shapes[0].material as usize];
    assert_eq!(m.emission, Vec3::new(4.0, 2.0, 1.0));
}

/// A metallic-roughness texture is drawn (roughness in green, metallic in blue, times the
/// factors, read as data, not sRGB) where it maps texture coordinates as the base colour
/// does, or alone; one that reads another TEXCOORD set than the base colour texture is
/// warned about by name and its factors drawn.
#[test]
fn metallic_roughness_textures_are_drawn_where_they_map_alike() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let uv = b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    // Texel 0: roughness 1, metallic 0; texel 1: roughness 0.2, metallic 1 (data values).
    let png = b.png(2, 1, &[0, 255, 0, 0, 51, 255]);
    let doc = json!({
        "nodes": [{"mesh": 0}, {"mesh": 1}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [
            {"name": "Worn", "pbrMetallicRoughness": {"metallicFactor": 1.0,
                "roughnessFactor": 0.5, "metallicRoughnessTexture": {"index": 0}}},
            {"name": "Elsewhere", "pbrMetallicRoughness": {"metallicFactor": 0.7,
                "roughnessFactor": 0.4, "baseColorTexture": {"index": 0},
                "metallicRoughnessTexture": {"index": 0, "texCoord": 1}}},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv,
                "TEXCOORD_1": uv}, "material": 1}]},
        ],
    });
    let d = dir("metallic-roughness-texture");
    let path = write(&d, "worn.glb", &b.glb(doc));
    let (import, materials) = import(&path, &Options::default());
    let worn = &materials[import.shapes[0].material as usize];
    let at = |u: f32| {
        let mr = worn.metallic_roughness(Vec2::new(u, 0.5)).unwrap();
        (mr.metallic, mr.roughness)
    };
    let close2 =
        |a: (f32, f32), b: (f32, f32)| (a.0 - b.0).abs() < 1e-3 && (a.1 - b.1).abs() < 1e-3;
    assert!(close2(at(0.25), (0.0, 0.5)), "{:?}", at(0.25));
    assert!(close2(at(0.75), (1.0, 0.1)), "{:?}", at(0.75));
    // The mesh's texture coordinates were read for the texture (v flipped).
    let uvs = &import.shapes[0].mesh.uvs;
    assert!(uvs.contains(&Vec2::new(1.0, 1.0)), "{uvs:?}");
    // The second material's texture reads TEXCOORD_1: its factors are drawn, with a warning.
    let elsewhere = &materials[import.shapes[1].material as usize];
    let mr = elsewhere.metallic_roughness(Vec2::new(0.75, 0.5)).unwrap();
    assert_eq!((mr.metallic, mr.roughness), (0.7, 0.4));
    assert_eq!(import.warnings.len(), 1, "{:?}", import.warnings);
    assert!(
        import.warnings[0].contains("\"Elsewhere\"")
            && import.warnings[0].contains("metallicRoughnessTexture"),
        "{:?}",
        import.warnings
    );
}

/// Normal, emissive and occlusion textures on environment geometry are said to be drawn on
/// OSLF objects only, naming the shape, once per material.
#[test]
fn normal_textures_on_environment_geometry_are_said_undrawn() {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let uv = b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    let png = b.png(1, 1, &[128, 128, 255]);
    let doc = json!({
        "nodes": [{"name": "Wall", "mesh": 0}, {"name": "Wall 2", "mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "materials": [{"name": "Brick", "normalTexture": {"index": 0},
            "emissiveFactor": [1.0, 0.5, 0.0], "emissiveTexture": {"index": 0},
            "occlusionTexture": {"index": 0, "strength": 0.5}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
            "material": 0}]}],
    });
    let d = dir("environment-normal-texture");
    let path = write(&d, "wall.glb", &b.glb(doc));
    let (import, materials) = import(&path, &Options::default());
    assert!(materials[import.shapes[0].material as usize]
        .normal_texture
        .is_some());
    let said: Vec<&String> = import
        .warnings
        .iter()
        .filter(|w| w.contains("drawn on OSLF objects only"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", import.warnings);
    assert!(
        said[0].starts_with("wall.glb: nodes[0] \"Wall\""),
        "{said:?}"
    );
    assert!(
        said[0].contains("normalTexture")
            && said[0].contains("emissiveTexture")
            && said[0].contains("occlusionTexture"),
        "{said:?}"
    );
    let m = &materials[import.shapes[0].material as usize];
    assert!(m.emissive_texture.is_some());
    // The texel's red code 128 at strength 0.5: 1 + 0.5·(128/255 − 1).
    let occlusion = m.occlusion_at(Vec2::new(0.3, 0.3));
    assert!(
        (occlusion - (1.0 + 0.5 * (128.0 / 255.0 - 1.0))).abs() < 1e-6,
        "{occlusion}"
    );
    assert!(!import
        .warnings
        .iter()
        .any(|w| w.contains("ignor") && w.contains("occlusion")));
}
