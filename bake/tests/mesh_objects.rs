//! Triangle-mesh OSLF objects on the bake side: glTF nodes and OBJ files imported as objects
//! (world space, uv sets, base colour), the errors of their scene keys, a `.glb` given as the
//! whole scene, the bake over mesh objects (atlas pages as sample maps, sample points on the
//! mesh, determinism), and the ground truth of a mesh sphere.

use crate::gltf_builder;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use glam::{Vec2, Vec3};
use gltf_builder::Builder;
use oslf_bake::bake::{bake, BakeOptions, BakeReport};
use oslf_bake::surface::{Surfaces, ATLAS_TEXELS_PER_SPACING};
use oslf_format::{Store, INVALID_INDEX};
use oslf_geometry::atlas::UvSource;
use oslf_scene::scene::Scene;
use oslf_scene::BakeError;
use oslf_shading::color::srgb_to_linear;
use oslf_trace::ground_truth::{GroundTruth, Term, TruthSettings};
use serde_json::{json, Value};

// ---------------------------------------------------------------------------------------------
// Helpers

/// A fresh directory for one test, under Cargo's target tmp; the next run replaces it.
fn dir(test: &str) -> PathBuf {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "mesh_objects/{test}-{}",
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).length() <= tolerance
}

/// Parses `text` as the scene file `dir/scene.toml`.
fn scene_in(dir: &Path, text: &str) -> Result<Scene, BakeError> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path, None)
}

/// The unit icosphere subdivided `levels` times: its vertices (unit directions) and triangles.
fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let m = oslf_geometry::mesh::Mesh::icosphere(levels);
    (m.positions, m.triangles)
}

/// A `.glb` of one node `name` holding a sphere (smooth normals, no texture coordinates) of
/// `radius` at `centre`, with a plain material of colour `color`; `extras` on the node if given.
fn sphere_glb(
    name: &str,
    centre: Vec3,
    radius: f32,
    levels: u32,
    color: [f32; 3],
    extras: Option<Value>,
) -> Vec<u8> {
    let (dirs, faces) = icosphere(levels);
    let positions: Vec<[f32; 3]> = dirs
        .iter()
        .map(|d| (centre + *d * radius).to_array())
        .collect();
    let normals: Vec<[f32; 3]> = dirs.iter().map(|d| d.to_array()).collect();
    let indices: Vec<u32> = faces.iter().flatten().copied().collect();
    let mut b = Builder::new();
    let pos = b.positions(&positions);
    let nor = b.vec3(&normals);
    let idx = b.indices_u32(&indices);
    let mut node = json!({"name": name, "mesh": 0});
    if let Some(extras) = extras {
        node["extras"] = extras;
    }
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [node],
        "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0.0,
            "baseColorFactor": [color[0], color[1], color[2], 1.0]}}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor},
            "indices": idx,
            "material": 0,
        }]}],
    }))
}

/// A Wavefront OBJ of the sphere (no normals, no uvs: the loader computes smooth normals).
fn sphere_obj(centre: Vec3, radius: f32, levels: u32) -> String {
    let (dirs, faces) = icosphere(levels);
    let mut text = String::new();
    for d in &dirs {
        let p = centre + *d * radius;
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for f in &faces {
        text += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    text
}

/// The closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Distance from `p` to the mesh, and the unit geometric normal of the nearest triangle.
fn distance_to_mesh(p: Vec3, mesh: &oslf_geometry::mesh::Mesh) -> (f32, Vec3) {
    let mut best = (f32::INFINITY, Vec3::Z);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let d = (closest_on_triangle(p, a, b, c) - p).length();
        if d < best.0 {
            best = (d, (b - a).cross(c - a).normalize());
        }
    }
    best
}

fn bake_to(scene: &Scene, output: &Path) -> BakeReport {
    let options = BakeOptions {
        output: output.to_path_buf(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    bake(scene, &options).unwrap()
}

/// Tiny bake settings.
const TINY_BAKE: &str = r#"
[bake]
epsilon = 0.08
sample_count = 60
cube_resolution = 4
sample_map_resolution = 16
samples_per_texel = 1
bounces = 1
"#;

/// A mesh ball (radius 0.5 at (0, 0, 1), 320 triangles, no uvs) floating over a plane under a
/// uniform sky, with tiny bake settings.
fn ball_scene(d: &Path) -> Scene {
    write(
        d,
        "ball.glb",
        &sphere_glb(
            "Ball",
            Vec3::new(0.0, 0.0, 1.0),
            0.5,
            2,
            [0.7, 0.5, 0.3],
            None,
        ),
    );
    let text = format!(
        r#"
[environment]
uniform = [0.8, 0.9, 1.0]

[[plane]]
size = [4.0, 4.0]
material = {{ color = [0.5, 0.5, 0.5] }}

[[gltf]]
path = "ball.glb"
objects = ["Ball"]
{TINY_BAKE}"#
    );
    scene_in(d, &text).unwrap()
}

// ---------------------------------------------------------------------------------------------
// 1. glTF import

/// A quad (4 vertices, 2 triangles, normals +z) in z = 0.
const QUAD: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];
const QUAD_UV0: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
const QUAD_UV1: [[f32; 2]; 4] = [[0.1, 0.2], [0.4, 0.2], [0.4, 0.5], [0.1, 0.5]];

/// Which texture coordinate sets a primitive of [`quad_file`] has.
#[derive(Clone, Copy)]
struct Sets {
    uv0: bool,
    uv1: bool,
}

/// A `.glb` with node "Obj" (translation (1, 2, 3), scale 2; one quad primitive per entry of
/// `prims`, material 0: factor (0.2, 0.4, 0.6)) and node "Env" (a quad, material 0).
fn quad_file(prims: &[Sets]) -> Vec<u8> {
    let mut b = Builder::new();
    let pos = b.positions(&QUAD);
    let nor = b.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let uv0 = b.vec2(&QUAD_UV0);
    let uv1 = b.vec2(&QUAD_UV1);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let primitives: Vec<Value> = prims
        .iter()
        .map(|s| {
            let mut attributes = json!({"POSITION": pos, "NORMAL": nor});
            if s.uv0 {
                attributes["TEXCOORD_0"] = json!(uv0);
            }
            if s.uv1 {
                attributes["TEXCOORD_1"] = json!(uv1);
            }
            json!({"attributes": attributes, "indices": idx, "material": 0})
        })
        .collect();
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "Obj", "mesh": 0, "translation": [1, 2, 3], "scale": [2, 2, 2]},
            {"name": "Env", "mesh": 1, "translation": [0, 0, -5]},
        ],
        "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0.0,
            "baseColorFactor": [0.2, 0.4, 0.6, 1.0]}}],
        "meshes": [
            {"primitives": primitives},
            {"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nor}, "indices": idx,
                             "material": 0}]},
        ],
    }))
}

/// Includes `file` with `objects = ["Obj"]`, rotated 90° about z and moved by (10, 0, 0).
fn include_quad(d: &Path, file: &[u8]) -> Scene {
    write(d, "q.glb", file);
    let text = r#"
[[gltf]]
path = "q.glb"
transform = { translate = [10.0, 0.0, 0.0], rotate = [0.0, 0.0, 90.0] }
objects = ["Obj"]

[bake]
epsilon = 0.01
"#;
    scene_in(d, text).unwrap()
}

fn uv_vec(uvs: &[[f32; 2]]) -> Vec<Vec2> {
    uvs.iter().map(|&uv| Vec2::from_array(uv)).collect()
}

#[test]
fn a_named_gltf_node_becomes_a_mesh_object_in_world_space() {
    let d = dir("named");
    let scene = include_quad(
        &d,
        &quad_file(&[Sets {
            uv0: true,
            uv1: true,
        }]),
    );
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(o.name, "Obj");
    assert!(o.patches.is_empty() && o.object_patches.is_empty());
    let source = o.mesh.as_ref().expect("a mesh object");
    assert_eq!(source.mesh.positions.len(), 4);
    assert_eq!(source.mesh.triangles.len(), 2);
    // Vertex 1 = (1, 0, 0): node ×2 then +(1, 2, 3) → (3, 2, 3); include Rz90 → (−2, 3, 3),
    // then +(10, 0, 0) → (8, 3, 3).
    assert!(
        close(source.mesh.positions[1], Vec3::new(8.0, 3.0, 3.0), 1e-5),
        "{}",
        source.mesh.positions[1]
    );
    // Vertex 2 = (1, 1, 0) → (3, 4, 3) → (−4, 3, 3) → (6, 3, 3).
    assert!(close(
        source.mesh.positions[2],
        Vec3::new(6.0, 3.0, 3.0),
        1e-5
    ));
    for n in &source.mesh.normals {
        assert!(close(*n, Vec3::Z, 1e-5), "{n}");
    }
    // The lightmap set first, then the texture set, as read (no node transform on uvs).
    let sources: Vec<UvSource> = source.uv_sets.iter().map(|s| s.0).collect();
    assert_eq!(sources, [UvSource::Lightmap, UvSource::Texture]);
    assert_eq!(source.uv_sets[0].1, uv_vec(&QUAD_UV1));
    assert_eq!(source.uv_sets[1].1, uv_vec(&QUAD_UV0));
    // Base colour: the factor (linear in glTF).
    assert!(
        close(o.base_color, Vec3::new(0.2, 0.4, 0.6), 1e-6),
        "{}",
        o.base_color
    );
    assert_eq!(
        scene.materials[o.material as usize].mean_albedo(),
        o.base_color
    );
    // The other node stays environment geometry: one shape, (0, 0, −5) + quad, then include.
    assert_eq!(scene.shapes.len(), 1);
    let shape = &scene.shapes[0].mesh;
    // Vertex 1 = (1, 0, −5) → Rz90 (0, 1, −5) → (10, 1, −5).
    assert!(close(shape.positions[1], Vec3::new(10.0, 1.0, -5.0), 1e-5));
    // The object is in the ray-traced scene once, as itself.
    let instances = oslf_trace::bvh::scene_instances(&scene, true, 1e-3);
    assert_eq!(instances.len(), 2);
    assert_eq!(instances[1].object, 0);
    assert_eq!(instances[1].mesh.positions, source.mesh.positions);
}

#[test]
fn uv_sets_follow_the_texture_coordinates_present() {
    let d = dir("sets");
    // TEXCOORD_0 only: the texture set alone.
    let scene = include_quad(
        &d,
        &quad_file(&[Sets {
            uv0: true,
            uv1: false,
        }]),
    );
    let source = scene.objects[0].mesh.as_ref().unwrap();
    assert_eq!(source.uv_sets.len(), 1);
    assert_eq!(source.uv_sets[0].0, UvSource::Texture);
    assert_eq!(source.uv_sets[0].1, uv_vec(&QUAD_UV0));
    // None: no candidate set.
    let scene = include_quad(
        &d,
        &quad_file(&[Sets {
            uv0: false,
            uv1: false,
        }]),
    );
    assert!(scene.objects[0].mesh.as_ref().unwrap().uv_sets.is_empty());
    // TEXCOORD_1 only: the lightmap set alone.
    let scene = include_quad(
        &d,
        &quad_file(&[Sets {
            uv0: false,
            uv1: true,
        }]),
    );
    let sets = &scene.objects[0].mesh.as_ref().unwrap().uv_sets;
    assert_eq!(sets.len(), 1);
    assert_eq!(sets[0].0, UvSource::Lightmap);
}

#[test]
fn a_primitive_without_the_lightmap_set_drops_it_for_the_whole_object() {
    let d = dir("drop");
    let scene = include_quad(
        &d,
        &quad_file(&[
            Sets {
                uv0: true,
                uv1: true,
            },
            Sets {
                uv0: true,
                uv1: false,
            },
        ]),
    );
    let source = scene.objects[0].mesh.as_ref().unwrap();
    // Both primitives merged into one mesh.
    assert_eq!(source.mesh.positions.len(), 8);
    assert_eq!(source.mesh.triangles.len(), 4);
    assert_eq!(source.mesh.triangles[2], [4, 5, 6]);
    assert_eq!(source.uv_sets.len(), 1);
    assert_eq!(source.uv_sets[0].0, UvSource::Texture);
    let both: Vec<Vec2> = uv_vec(&QUAD_UV0).into_iter().cycle().take(8).collect();
    assert_eq!(source.uv_sets[0].1, both);
    // The lightmap set of the second primitive alone is not enough either.
    let scene = include_quad(
        &d,
        &quad_file(&[
            Sets {
                uv0: false,
                uv1: false,
            },
            Sets {
                uv0: true,
                uv1: true,
            },
        ]),
    );
    assert!(scene.objects[0].mesh.as_ref().unwrap().uv_sets.is_empty());
}

#[test]
fn the_base_colour_of_a_textured_object_is_the_mean_albedo() {
    // A 2×2 sRGB texture times a factor.
    let texels: [u8; 12] = [200, 30, 90, 10, 250, 128, 64, 64, 64, 255, 0, 170];
    let mut b = Builder::new();
    let png = b.png(2, 2, &texels);
    let pos = b.positions(&QUAD);
    let nor = b.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let uv0 = b.vec2(&QUAD_UV0);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let file = b.glb(json!({
        "nodes": [{"name": "Obj", "mesh": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0.0,
            "baseColorFactor": [0.5, 1.0, 0.25, 1.0],
            "baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nor,
            "TEXCOORD_0": uv0}, "indices": idx, "material": 0}]}],
    }));
    let d = dir("textured");
    let scene = include_quad(&d, &file);
    let factor = Vec3::new(0.5, 1.0, 0.25);
    let mut mean = Vec3::ZERO;
    for t in texels.chunks_exact(3) {
        mean += Vec3::new(
            srgb_to_linear(f32::from(t[0]) / 255.0),
            srgb_to_linear(f32::from(t[1]) / 255.0),
            srgb_to_linear(f32::from(t[2]) / 255.0),
        );
    }
    let expected = factor * mean / 4.0;
    let got = scene.objects[0].base_color;
    assert!(close(got, expected, 2e-3), "{got} vs {expected}");
}

/// A primitive without `NORMAL` is flat shaded, which splits its vertices (three per
/// triangle): the object's texture coordinates must follow that split.
#[test]
fn an_indexed_object_without_normals_keeps_its_texture_coordinates() {
    let mut b = Builder::new();
    let pos = b.positions(&QUAD);
    let uv0 = b.vec2(&QUAD_UV0);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let file = b.glb(json!({
        "nodes": [{"name": "Obj", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv0},
            "indices": idx}]}],
    }));
    let d = dir("flat");
    let scene = include_quad(&d, &file);
    let source = scene.objects[0].mesh.as_ref().unwrap();
    let n = source.mesh.positions.len();
    assert_eq!(source.uv_sets.len(), 1);
    let uvs = &source.uv_sets[0].1;
    assert_eq!(uvs.len(), n, "one uv per vertex of the (split) mesh");
    // Each vertex keeps its own uv: the quad's uv is its (x, y) before the transforms.
    for (t, tri) in source.mesh.triangles.iter().enumerate() {
        for &v in tri {
            let p = source.mesh.positions[v as usize];
            let uv = uvs[v as usize];
            // Rz90 then +(10, 0, 0): object (x, y, 0) is at (10 − y, x, 0).
            let back = Vec2::new(p.y, 10.0 - p.x);
            assert!((back - uv).length() < 1e-5, "triangle {t}: {p} has uv {uv}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Errors

#[test]
fn objects_naming_no_node_is_an_error_naming_file_and_node() {
    let d = dir("nope");
    write(
        &d,
        "q.glb",
        &quad_file(&[Sets {
            uv0: true,
            uv1: false,
        }]),
    );
    let text = r#"
[[gltf]]
path = "q.glb"
objects = ["Obj", "Nope"]
"#;
    let e = scene_in(&d, text).unwrap_err().to_string();
    assert!(e.contains("q.glb"), "{e}");
    assert!(e.contains("\"Nope\""), "{e}");
    assert!(!e.contains("\"Obj\""), "{e}");
}

/// Asserts a located error at `line`:`column` containing `needle`.
fn assert_located(d: &Path, text: &str, line: usize, column: usize, needle: &str) {
    match scene_in(d, text) {
        Err(BakeError::Parse {
            path,
            line: l,
            column: c,
            message,
        }) => {
            assert_eq!(path, d.join("scene.toml"));
            assert!(message.contains(needle), "{message:?} lacks {needle:?}");
            assert_eq!((l, c), (line, column), "{message}");
        }
        Err(other) => panic!("expected a located error, got {other}"),
        Ok(_) => panic!("expected an error for:\n{text}"),
    }
}

#[test]
fn an_object_needs_exactly_one_of_patches_and_mesh() {
    let d = dir("one-of");
    write(&d, "ball.obj", sphere_obj(Vec3::ZERO, 1.0, 0).as_bytes());
    let both = r#"[environment]
uniform = [1.0, 1.0, 1.0]

[[object]]
patches = "newell-teapot"
mesh = "ball.obj"
material = { color = [0.5, 0.5, 0.5] }
"#;
    assert_located(&d, both, 4, 1, "exactly one of `patches`");
    let neither = r#"[environment]
uniform = [1.0, 1.0, 1.0]

[[object]]
name = "nothing"
material = { color = [0.5, 0.5, 0.5] }
"#;
    assert_located(&d, neither, 4, 1, "exactly one of `patches`");
    let select = r#"[[object]]
mesh = "ball.obj"
select = [0, 4]
material = { color = [0.5, 0.5, 0.5] }
"#;
    assert_located(&d, select, 3, 10, "`select`");
    // A missing OBJ is located at its path.
    let missing = r#"[[object]]
mesh = "gone.obj"
material = { color = [0.5, 0.5, 0.5] }
"#;
    assert_located(&d, missing, 2, 8, "file not found");
}

// ---------------------------------------------------------------------------------------------
// 3. A .glb given as the scene

#[test]
fn a_glb_scene_bakes_its_marked_nodes() {
    let d = dir("glb-scene");
    // Two nodes: "Marked" (extras oslf: true), "Plain" (extras without oslf).
    let mut b = Builder::new();
    let pos = b.positions(&QUAD);
    let nor = b.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let idx = b.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let prim = json!({"attributes": {"POSITION": pos, "NORMAL": nor}, "indices": idx});
    let doc = |marked: bool| {
        json!({
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {"name": "Marked", "mesh": 0, "translation": [0, 1, 0],
                 "extras": {"oslf": marked, "note": "x"}},
                {"name": "Plain", "mesh": 0, "extras": {"other": true}},
            ],
            "meshes": [{"primitives": [prim.clone()]}],
        })
    };
    let path = write(&d, "s.glb", &b.glb(doc(true)));
    let scene = Scene::load(&path, None).unwrap();
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    assert_eq!(o.name, "Marked");
    let mesh = &o.mesh.as_ref().unwrap().mesh;
    // glTF Y-up to Z-up (90° about x): (x, y, z) → (x, −z, y); vertex 2 = (1, 1, 0) + (0, 1, 0).
    assert!(
        close(mesh.positions[2], Vec3::new(1.0, 0.0, 2.0), 1e-5),
        "{}",
        mesh.positions[2]
    );
    assert!(close(mesh.normals[0], Vec3::new(0.0, -1.0, 0.0), 1e-5));
    assert_eq!(scene.shapes.len(), 1);
    assert!(scene.preset.is_none());

    // A preset is refused.
    let e = Scene::load(&path, Some("thesis")).unwrap_err().to_string();
    assert!(e.contains("no presets"), "{e}");
    assert!(e.contains("\"thesis\""), "{e}");

    // "oslf": false marks nothing: refused, saying so.
    let path = write(&d, "none.glb", &b.glb(doc(false)));
    let e = Scene::load(&path, None).unwrap_err().to_string();
    assert!(e.contains("none.glb"), "{e}");
    assert!(e.contains("no node is marked"), "{e}");

    // Included from a TOML scene, the mark alone does not make an object.
    write(&d, "marked.glb", &b.glb(doc(true)));
    let text = r#"
[[object]]
mesh = "ball.obj"
material = { color = [0.5, 0.5, 0.5] }

[[gltf]]
path = "marked.glb"
"#;
    write(
        &d,
        "ball.obj",
        sphere_obj(Vec3::new(5.0, 0.0, 0.0), 1.0, 1).as_bytes(),
    );
    let scene = scene_in(&d, text).unwrap();
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.shapes.len(), 2);
}

// ---------------------------------------------------------------------------------------------
// 4. OBJ mesh objects

#[test]
fn an_obj_mesh_object_is_transformed_with_its_uvs() {
    let d = dir("obj");
    let with_vt = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                   vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                   f 1/1 2/2 3/3 4/4\n";
    let without = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    for (file, has_uvs) in [(with_vt, true), (without, false)] {
        write(&d, "quad.obj", file.as_bytes());
        let text = r#"
[[object]]
name = "Quad"
mesh = "quad.obj"
transform = { translate = [0.0, 0.0, 2.0], rotate = [90.0, 0.0, 0.0], scale = 2.0 }
material = { color = [0.1, 0.2, 0.3] }

[bake]
epsilon = 0.01
sample_count = 30
sample_map_resolution = 8
"#;
        let scene = scene_in(&d, text).unwrap();
        let o = &scene.objects[0];
        assert_eq!(o.name, "Quad");
        assert_eq!(o.base_color, Vec3::new(0.1, 0.2, 0.3));
        let source = o.mesh.as_ref().unwrap();
        let m = &source.mesh;
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
        // ×2, then 90° about x ((x, y, z) → (x, −z, y)), then +(0, 0, 2).
        let expected = [
            ([0.0, 0.0], Vec3::new(0.0, 0.0, 2.0)),
            ([1.0, 0.0], Vec3::new(2.0, 0.0, 2.0)),
            ([1.0, 1.0], Vec3::new(2.0, 0.0, 4.0)),
            ([0.0, 1.0], Vec3::new(0.0, 0.0, 4.0)),
        ];
        for (uv, p) in expected {
            let v = m
                .positions
                .iter()
                .position(|q| close(*q, p, 1e-5))
                .unwrap_or_else(|| panic!("no vertex at {p}: {:?}", m.positions));
            assert!(close(m.normals[v], Vec3::new(0.0, -1.0, 0.0), 1e-5));
            if has_uvs {
                assert_eq!(source.uv_sets.len(), 1);
                assert_eq!(source.uv_sets[0].0, UvSource::Texture);
                assert_eq!(source.uv_sets[0].1[v], Vec2::from_array(uv));
            }
        }
        // Area 4: the transform's scale applies.
        assert!((m.area() - 4.0).abs() < 1e-5);
        // The atlas uses the file's uvs when it has them, else its own charts.
        let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
        let atlas = surfaces.atlas(0).unwrap();
        let want = if has_uvs {
            UvSource::Texture
        } else {
            UvSource::Charts
        };
        assert_eq!(atlas.source, want);
        assert_eq!(surfaces.map_count(), atlas.grid * atlas.grid);
    }
}

// ---------------------------------------------------------------------------------------------
// 5. The bake

#[test]
fn a_mesh_object_bakes_to_a_consistent_store() {
    let d = dir("bake");
    let scene = ball_scene(&d);
    let output = d.join("ball.oslf");
    let report = bake_to(&scene, &output);
    assert!(report.finished);
    let store = Store::open(&output).unwrap();
    let meta = store.meta();

    // (a) the object record.
    assert_eq!(meta.objects.len(), 1);
    let info = &meta.objects[0];
    assert_eq!(info.name, "Ball");
    assert_eq!(info.first_patch, 0);
    let mesh = info.mesh.as_ref().expect("a mesh record");
    let k = mesh.atlas_grid;
    assert!(k >= 1);
    assert_eq!(k * k, info.patch_count);
    assert_eq!(store.header().patch_count, u64::from(info.patch_count));
    assert_eq!(meta.map_count(), info.patch_count as usize);
    assert!(meta.patches.is_empty());
    assert!(meta.patches_of(0).is_empty());
    assert_eq!(info.transform, glam::Mat4::IDENTITY.to_cols_array_2d());
    assert_eq!(info.base_color, [0.7, 0.5, 0.3]);
    assert_eq!(mesh.triangles.len(), 320);
    assert_eq!(mesh.positions.len(), mesh.normals.len());
    assert_eq!(mesh.positions.len(), mesh.uvs.len());
    assert!(mesh
        .uvs
        .iter()
        .all(|uv| (0.0..=1.0).contains(&uv[0]) && (0.0..=1.0).contains(&uv[1])));
    for n in &mesh.normals {
        assert!((Vec3::from_array(*n).length() - 1.0).abs() < 1e-3);
    }
    // The stored mesh is the scene's (world space): every stored vertex lies on the sphere.
    for p in &mesh.positions {
        let r = (Vec3::from_array(*p) - Vec3::new(0.0, 0.0, 1.0)).length();
        assert!((r - 0.5).abs() < 1e-5, "{p:?}");
    }

    // The atlas the bake used, rebuilt.
    let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
    let atlas = surfaces.atlas(0).unwrap();
    assert_eq!(atlas.grid, k);
    assert_eq!(atlas.source, UvSource::Charts);
    let m = scene.bake.sample_map_resolution;
    let spacing = (surfaces.area() / (0.866_025_4 * 60.0)).sqrt();
    let texel = spacing / ATLAS_TEXELS_PER_SPACING;

    // Sample points: on their map, ε above the mesh along their face's geometric normal.
    let eps = scene.bake.epsilon;
    let source = &scene.objects[0].mesh.as_ref().unwrap().mesh;
    let points = store.sample_points();
    assert_eq!(points.len(), report.sample_points);
    assert!(points.len() >= 30, "{} points", points.len());
    assert_eq!(store.cube_count() as usize, points.len() + 1);
    for (i, p) in points.iter().enumerate() {
        assert_eq!(p.object, 0);
        assert!(
            p.patch < info.first_patch + info.patch_count,
            "point {i}: {p:?}"
        );
        assert!(
            p.uv.iter().all(|u| (0.0..=1.0).contains(u)),
            "point {i}: {p:?}"
        );
        let position = Vec3::from_array(p.position);
        let normal = Vec3::from_array(p.normal);
        assert!((normal.length() - 1.0).abs() < 1e-4);
        // Its base point is on the mesh; the normal is the face normal there, outwards.
        let base = position - normal * eps;
        let (on, _) = distance_to_mesh(base, source);
        assert!(on < 1e-3 * eps, "point {i}: base {on} off the mesh");
        // (On an edge, the face of either side.)
        let own_face = source.triangles.iter().any(|t| {
            let [a, b, c] = t.map(|v| source.positions[v as usize]);
            let ng = (b - a).cross(c - a).normalize();
            (closest_on_triangle(base, a, b, c) - base).length() < 1e-3 * eps
                && normal.dot(ng) > 1.0 - 1e-4
        });
        assert!(
            own_face,
            "point {i}: {normal} is not the normal of a face at {base}"
        );
        let outward = (base - Vec3::new(0.0, 0.0, 1.0)).normalize();
        assert!(normal.dot(outward) > 0.95, "point {i}");
        // So it lies ε from the mesh (a smooth-normal offset would come closer).
        let (dist, _) = distance_to_mesh(position, source);
        assert!(
            (dist - eps).abs() <= eps * 1e-3,
            "point {i}: {dist} from the mesh, ε = {eps}"
        );
        // (patch, uv) names the texel of the atlas that stands for its base point.
        let page = p.patch - info.first_patch;
        let (x, y) = atlas.page_texel(p.uv);
        let t = atlas
            .texel(page, x, y)
            .unwrap_or_else(|| panic!("point {i}: its texel ({page}, {x}, {y}) is empty"));
        let (at, _) = atlas.sample_surface(t.triangle, t.bary);
        assert!(
            (at - base).length() < 2.0 * texel,
            "point {i}: its texel is {} away (texel {texel})",
            (at - base).length()
        );
    }

    // (b) every used texel found a point; unused texels hold none.
    let cos_phi = scene.bake.phi_samplemap_deg.to_radians().cos();
    let maps = surfaces.maps();
    assert_eq!(maps.len(), info.patch_count as usize);
    let (mut used, mut short, mut unused) = (0u64, 0u64, 0u64);
    for (map, domain) in maps.iter().enumerate() {
        assert_eq!(domain.object(), 0);
        let view = store.sample_map(map as u32).unwrap();
        assert_eq!(view.resolution(), m);
        for y in 0..m {
            for x in 0..m {
                let entries = view.get(x, y).unwrap();
                match domain.texel(x, y, m) {
                    None => {
                        unused += 1;
                        assert_eq!(entries, [INVALID_INDEX; 4], "map {map} texel ({x}, {y})");
                    }
                    Some((surface, normal)) => {
                        used += 1;
                        assert_ne!(entries[0], INVALID_INDEX, "map {map} texel ({x}, {y})");
                        if entries[3] == INVALID_INDEX {
                            short += 1;
                        }
                        for &e in entries.iter().filter(|&&e| e != INVALID_INDEX) {
                            let s = Vec3::from_array(points[e as usize].position);
                            // Eq. 3.10: within φ_samplemap of the texel's normal.
                            let to = s - surface;
                            assert!(normal.dot(to) > cos_phi * to.length() * 0.999);
                        }
                    }
                }
            }
        }
    }
    assert!(used > 0 && unused > 0, "used {used}, unused {unused}");
    assert_eq!(
        used + unused,
        u64::from(info.patch_count) * u64::from(m * m)
    );
    // (c) the statistics count used texels only.
    assert_eq!(report.sample_maps.texels, used);
    assert_eq!(report.sample_maps.short, short);
    // No used texel is empty (asserted above).
    assert_eq!(report.sample_maps.empty, 0);
}

#[test]
fn mesh_bakes_are_deterministic_across_thread_counts() {
    let d = dir("determinism");
    let scene = ball_scene(&d);
    let a = d.join("a.oslf");
    let b = d.join("b.oslf");
    let c = d.join("c.oslf");
    bake_to(&scene, &a);
    bake_to(&scene, &b);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let report = pool.install(|| bake_to(&scene, &c));
    assert!(report.finished);
    let (a, b, c) = (
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        std::fs::read(&c).unwrap(),
    );
    assert!(a == b, "two bakes differ");
    assert!(a == c, "a one-thread bake differs from the default pool's");
}

/// One flat 2×2 bicubic patch in z = 0 (the patch file format of tests/ground_truth.rs).
fn flat_patch_file() -> String {
    let mut text = String::from("1\n");
    text += &(1..=16)
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",");
    text += "\n16\n";
    for i in 0..4 {
        for j in 0..4 {
            text += &format!(
                "{},{},0\n",
                -1.0 + 2.0 * i as f32 / 3.0,
                -1.0 + 2.0 * j as f32 / 3.0
            );
        }
    }
    text
}

/// A Bézier object, then a mesh object: the patch's map first, then the pages.
#[test]
fn a_bezier_then_a_mesh_object_bake_together_in_object_order() {
    mixed_bake(false);
}

/// A mesh object, then a Bézier object: the pages first, then the patch's map.
#[test]
fn a_mesh_then_a_bezier_object_bake_together_in_object_order() {
    mixed_bake(true);
}

/// A Bézier object and a mesh object in one scene: each object's maps are its own range,
/// patches for the Bézier, pages for the mesh, in object order.
fn mixed_bake(mesh_first: bool) {
    let d = dir(if mesh_first {
        "mixed-mesh-first"
    } else {
        "mixed"
    });
    write(&d, "flat.txt", flat_patch_file().as_bytes());
    write(
        &d,
        "ball.obj",
        sphere_obj(Vec3::new(0.0, 0.0, 1.0), 0.5, 1).as_bytes(),
    );
    let patch = r#"
[[object]]
name = "flat"
patches = "flat.txt"
material = { color = [0.4, 0.4, 0.4] }
"#;
    let ball = r#"
[[object]]
name = "ball"
mesh = "ball.obj"
material = { color = [0.6, 0.3, 0.2] }
"#;
    let objects = if mesh_first {
        format!("{ball}{patch}")
    } else {
        format!("{patch}{ball}")
    };
    let text = format!("[environment]\nuniform = [1.0, 1.0, 1.0]\n{objects}{TINY_BAKE}");
    let scene = scene_in(&d, &text).unwrap();
    let (bezier, mesh) = if mesh_first { (1, 0) } else { (0, 1) };
    assert_eq!(scene.objects[bezier].name, "flat");
    assert_eq!(scene.objects[mesh].name, "ball");
    let output = d.join("mixed.oslf");
    let report = bake_to(&scene, &output);
    let store = Store::open(&output).unwrap();
    let meta = store.meta();
    assert_eq!(meta.objects.len(), 2);
    let b = &meta.objects[bezier];
    let m = &meta.objects[mesh];
    assert!(b.mesh.is_none());
    assert_eq!(b.patch_count, 1);
    let k = m.mesh.as_ref().unwrap().atlas_grid;
    assert_eq!(m.patch_count, k * k);
    if mesh_first {
        assert_eq!((m.first_patch, b.first_patch), (0, k * k));
    } else {
        assert_eq!((b.first_patch, m.first_patch), (0, 1));
    }
    assert_eq!(store.header().patch_count, u64::from(1 + k * k));
    assert_eq!(meta.map_count(), (1 + k * k) as usize);
    assert_eq!(meta.patches.len(), 1);
    assert_eq!(meta.patches_of(bezier).len(), 1);
    assert!(meta.patches_of(mesh).is_empty());
    assert_eq!(
        meta.patches_of(bezier)[0].control_points,
        scene.objects[bezier].object_patches[0]
            .cp
            .map(|c| c.to_array())
    );
    // Every point lies in its object's map range, and both objects have points.
    let mut counts = [0usize; 2];
    for p in store.sample_points() {
        let o = &meta.objects[p.object as usize];
        assert!(
            (o.first_patch..o.first_patch + o.patch_count).contains(&p.patch),
            "{p:?} outside object {}'s maps",
            p.object
        );
        counts[p.object as usize] += 1;
        let z = p.position[2];
        if p.object as usize == bezier {
            assert!((z.abs() - scene.bake.epsilon).abs() < 1e-4, "{p:?}");
        } else {
            let source = &scene.objects[mesh].mesh.as_ref().unwrap().mesh;
            let base =
                Vec3::from_array(p.position) - Vec3::from_array(p.normal) * scene.bake.epsilon;
            let (on, _) = distance_to_mesh(base, source);
            assert!(on < 1e-3 * scene.bake.epsilon, "{p:?}: {on} off the mesh");
        }
    }
    assert!(counts[0] > 0 && counts[1] > 0, "{counts:?}");
    // The Bézier map's texels are all used; statistics cover patch and used pages.
    let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
    let res = scene.bake.sample_map_resolution;
    let used: u64 = surfaces
        .maps()
        .iter()
        .map(|dm| {
            (0..res * res)
                .filter(|i| dm.texel(i % res, i / res, res).is_some())
                .count() as u64
        })
        .sum();
    assert_eq!(report.sample_maps.texels, used);
    assert!(used > u64::from(res * res));
}

// ---------------------------------------------------------------------------------------------
// 6. Ground truth

#[test]
fn the_mirror_term_of_a_mesh_sphere_in_a_uniform_sky_is_the_sky() {
    const L: [f32; 3] = [0.5, 0.6, 0.8];
    let d = dir("truth");
    let radius = 1.0f32;
    write(
        &d,
        "ball.glb",
        &sphere_glb("Ball", Vec3::ZERO, radius, 3, [0.5, 0.5, 0.5], None),
    );
    let distance = 5.0f32;
    let vfov = 30.0f32;
    let text = format!(
        r#"
[camera]
position = [0.0, -{distance}, 0.0]
target = [0.0, 0.0, 0.0]
vfov = {vfov}

[environment]
uniform = {L:?}

[[gltf]]
path = "ball.glb"
objects = ["Ball"]

[bake]
epsilon = 0.01
"#
    );
    let scene = scene_in(&d, &text).unwrap();
    assert!(scene.shapes.is_empty());
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let (w, h) = (64u32, 64u32);
    let settings = TruthSettings {
        width: w,
        height: h,
        spp: 2,
        seed: 7,
    };
    let image = truth.render(Term::Mirror, &settings).unwrap();
    let mut covered = 0usize;
    let mut wrong = Vec::new();
    let mut under = 0usize;
    for (i, p) in image.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let hit = truth.primary_hit(x, y, w, h);
        assert_eq!(hit.is_some(), p[3] == 1.0, "pixel ({x}, {y})");
        if let Some((ray, hit)) = hit {
            covered += 1;
            // The mirror direction about the smooth normal (Eq. 2.4). Near the silhouette it
            // can point below the facet it leaves (the smooth normal leans away from the
            // facet's): that ray sees the sphere itself, not the sky, so such pixels are only
            // counted (and must be few, and at the silhouette).
            let view = -ray.dir;
            let n = hit.shading_normal;
            let r = 2.0 * n.dot(view) * n - view;
            let ng = hit.geometric_normal * hit.geometric_normal.dot(view).signum();
            if r.dot(ng) <= 1e-4 {
                under += 1;
                assert!(n.dot(view) < 0.3, "pixel ({x}, {y}): n·v = {}", n.dot(view));
                continue;
            }
            if (0..3).any(|k| (p[k] / L[k] - 1.0).abs() >= 1e-3) {
                wrong.push((x, y, *p));
            }
            assert_eq!(image.base_color[i], Vec3::splat(0.5));
        } else {
            assert_eq!(*p, [0.0; 4]);
        }
    }
    assert!(
        under * 100 < covered,
        "{under} of {covered} reflect below their facet"
    );
    assert!(
        wrong.is_empty(),
        "{} of {covered} object pixels are not the sky; the first: {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(4)]
    );
    // The projected disc: angular radius asin(r/D), a circle of radius tan(α) in the image
    // plane, whose pixels are 2·tan(vfov/2)/h wide.
    let alpha = (radius / distance).asin();
    let pixel = 2.0 * (0.5 * vfov.to_radians()).tan() / h as f32;
    let expected = std::f32::consts::PI * (alpha.tan() / pixel).powi(2);
    let ratio = covered as f32 / expected;
    assert!(
        (ratio - 1.0).abs() < 0.04,
        "{covered} pixels covered, {expected} expected"
    );
    // The disc is centred.
    let (mut sx, mut sy) = (0f64, 0f64);
    for (i, p) in image.pixels.iter().enumerate() {
        if p[3] == 1.0 {
            sx += f64::from(i as u32 % w) + 0.5;
            sy += f64::from(i as u32 / w) + 0.5;
        }
    }
    let (cx, cy) = (sx / covered as f64, sy / covered as f64);
    assert!(
        (cx - 32.0).abs() < 0.5 && (cy - 32.0).abs() < 0.5,
        "({cx}, {cy})"
    );
}

/// The scene hash a store records covers the files the scene includes: the same files give
/// the same hash, an edited OBJ or glTF include (or its external buffer) a different one.
#[test]
fn the_scene_hash_covers_the_included_files() {
    let d = dir("hash");
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    write(&d, "quad.obj", quad.as_bytes());
    let text = r#"
[[object]]
mesh = "quad.obj"
material = { color = [0.5, 0.5, 0.5] }
"#;
    let first = scene_in(&d, text).unwrap().hash;
    assert_eq!(scene_in(&d, text).unwrap().hash, first, "deterministic");
    write(&d, "quad.obj", format!("{quad}# edited\n").as_bytes());
    let edited = scene_in(&d, text).unwrap().hash;
    assert_ne!(edited, first, "an edited OBJ is a different scene");

    // A .gltf with an external buffer: editing the buffer alone changes the hash.
    let mut b = Builder::new();
    let (dirs, faces) = icosphere(0);
    let positions: Vec<[f32; 3]> = dirs.iter().map(|p| (*p * 0.5).to_array()).collect();
    let pos = b.positions(&positions);
    let idx = b.indices_u32(&faces.concat());
    let doc = json!({
        "nodes": [{"name": "Ico", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
    });
    let (gltf, bin) = b.gltf_external(doc, "ico.bin");
    write(&d, "ico.gltf", &gltf);
    write(&d, "ico.bin", &bin);
    let text = r#"
[[gltf]]
path = "ico.gltf"
objects = ["Ico"]
"#;
    let before = scene_in(&d, text).unwrap().hash;
    let mut moved = bin.clone();
    // The first vertex's x coordinate (the positions accessor starts the buffer).
    moved[0..4].copy_from_slice(&0.4f32.to_le_bytes());
    write(&d, "ico.bin", &moved);
    let after = scene_in(&d, text).unwrap().hash;
    assert_ne!(
        before, after,
        "an edited external buffer is a different scene"
    );
}
