//! Vertex normals of mesh objects and `[[mesh]]` shapes: the crease-angle default for OBJ files
//! without `vn`, flat normals for glTF primitives without `NORMAL`, the scene file's `normals`
//! key (which overrides a file's own normals), its located errors, and what the scene records
//! for the bake summary.

use crate::gltf_builder;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;
use gltf_builder::Builder;
use oslf_geometry::mesh::Mesh;
use oslf_scene::normals::{NormalRule, DEFAULT_CREASE_DEG};
use oslf_scene::scene::Scene;
use oslf_scene::BakeError;
use serde_json::json;

// ---------------------------------------------------------------------------------------------
// Helpers

/// A fresh directory for one test, under Cargo's target tmp; the next run replaces it.
fn dir(test: &str) -> PathBuf {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "normals/{test}-{}",
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Parses `text` as the scene file `dir/scene.toml`.
fn scene_in(dir: &Path, text: &str) -> Result<Scene, BakeError> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path, None)
}

/// A scene whose one OSLF object is the OBJ `file`, with `extra` keys on the object.
fn obj_scene(d: &Path, file: &str, extra: &str) -> Scene {
    let text = format!(
        "[[object]]\nname = \"it\"\nmesh = \"{file}\"\n{extra}\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"
    );
    scene_in(d, &text).unwrap_or_else(|e| panic!("{e}"))
}

fn object_mesh(scene: &Scene) -> &Mesh {
    &scene.objects[0].mesh.as_ref().unwrap().mesh
}

/// The unit face normal of triangle `t`.
fn face_normal(m: &Mesh, t: &[u32; 3]) -> Vec3 {
    let [a, b, c] = m.corners(t).unwrap();
    (b - a).cross(c - a).normalize()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// The unit cube [0, 1]³: 8 vertices, 6 quads wound outwards; with `vn` face normals if asked.
fn box_obj(with_normals: bool) -> String {
    let mut text = String::new();
    for i in 0..8 {
        writeln!(text, "v {} {} {}", i & 1, (i >> 1) & 1, (i >> 2) & 1).unwrap();
    }
    // Each face: its corners (1-based, counter-clockwise seen from outside) and its normal.
    let faces = [
        ([1, 3, 4, 2], [0, 0, -1]),
        ([5, 6, 8, 7], [0, 0, 1]),
        ([1, 2, 6, 5], [0, -1, 0]),
        ([3, 7, 8, 4], [0, 1, 0]),
        ([1, 5, 7, 3], [-1, 0, 0]),
        ([2, 4, 8, 6], [1, 0, 0]),
    ];
    if with_normals {
        for (_, n) in &faces {
            writeln!(text, "vn {} {} {}", n[0], n[1], n[2]).unwrap();
        }
    }
    for (k, (corners, _)) in faces.iter().enumerate() {
        let refs: Vec<String> = corners
            .iter()
            .map(|c| {
                if with_normals {
                    format!("{c}//{}", k + 1)
                } else {
                    c.to_string()
                }
            })
            .collect();
        writeln!(text, "f {}", refs.join(" ")).unwrap();
    }
    text
}

/// Asserts every triangle corner's normal is its face normal (flat faces).
fn assert_flat(m: &Mesh) {
    for t in &m.triangles {
        let n = face_normal(m, t);
        for &v in t {
            assert!(
                close(m.normals[v as usize], n),
                "{} vs face {n}",
                m.normals[v as usize]
            );
        }
    }
}

/// Asserts every vertex normal of the unit cube points along its corner's diagonal.
fn assert_box_smooth(m: &Mesh) {
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let diagonal = (*p - Vec3::splat(0.5)).normalize();
        assert!(close(*n, diagonal), "at {p}: {n}, expected {diagonal}");
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
fn a_box_obj_without_normals_gets_flat_faces_with_split_corners() {
    let d = dir("box");
    std::fs::write(d.join("box.obj"), box_obj(false)).unwrap();
    let scene = obj_scene(&d, "box.obj", "");
    let m = object_mesh(&scene);
    assert_eq!(m.triangles.len(), 12);
    assert_flat(m);
    // Each corner of the box is split into one vertex per face: 6 faces × 4 corners.
    assert_eq!(m.positions.len(), 24);
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(
        used.rule,
        Some(NormalRule::Crease {
            crease_deg: DEFAULT_CREASE_DEG
        })
    );
    assert_eq!(used.reason, "box.obj has no normals; the default for OBJ");
    assert_eq!(
        used.to_string(),
        "crease 30° (box.obj has no normals; the default for OBJ)"
    );
}

#[test]
fn a_box_obj_asked_to_be_smooth_shares_averaged_normals() {
    let d = dir("box-smooth");
    std::fs::write(d.join("box.obj"), box_obj(false)).unwrap();
    let scene = obj_scene(&d, "box.obj", "normals = \"smooth\"");
    let m = object_mesh(&scene);
    assert_eq!(m.positions.len(), 8);
    assert_box_smooth(m);
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(used.rule, Some(NormalRule::Smooth));
    assert_eq!(
        used.reason,
        "asked for in the scene file; box.obj has no normals"
    );
    // Flat splits every triangle corner.
    let scene = obj_scene(&d, "box.obj", "normals = \"flat\"");
    let m = object_mesh(&scene);
    assert_eq!(m.positions.len(), 36);
    assert_flat(m);
    // A crease angle above 90° smooths the box's edges too.
    let scene = obj_scene(&d, "box.obj", "normals = { crease_deg = 91.0 }");
    assert_box_smooth(object_mesh(&scene));
    assert_eq!(
        scene.objects[0].normals.as_ref().unwrap().rule,
        Some(NormalRule::Crease { crease_deg: 91.0 })
    );
}

#[test]
fn an_obj_keeps_its_vn_normals_unless_the_scene_asks_for_others() {
    let d = dir("box-vn");
    std::fs::write(d.join("box.obj"), box_obj(true)).unwrap();
    let scene = obj_scene(&d, "box.obj", "");
    assert_flat(object_mesh(&scene));
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(used.rule, None);
    assert_eq!(used.to_string(), "from the file (box.obj's vn normals)");
    // An explicit key overrides the file's normals, and says so.
    let scene = obj_scene(&d, "box.obj", "normals = \"smooth\"");
    assert_box_smooth(object_mesh(&scene));
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(used.rule, Some(NormalRule::Smooth));
    assert_eq!(
        used.reason,
        "asked for in the scene file; replaces box.obj's vn normals"
    );
}

/// A closed cylinder of radius 1 and height 1 about +z: `segments` side quads and two
/// `segments`-gon caps, no normals.
fn cylinder_obj(segments: u32) -> String {
    let mut text = String::new();
    for z in [0, 1] {
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            writeln!(text, "v {} {} {z}", phi.cos(), phi.sin()).unwrap();
        }
    }
    let (bottom, top) = (
        |s: u32| s % segments + 1,
        |s: u32| s % segments + 1 + segments,
    );
    for s in 0..segments {
        let (a, b, c, d) = (bottom(s), bottom(s + 1), top(s + 1), top(s));
        writeln!(text, "f {a} {b} {c} {d}").unwrap();
    }
    let cap = |ids: Vec<u32>| ids.iter().map(u32::to_string).collect::<Vec<_>>().join(" ");
    writeln!(text, "f {}", cap((0..segments).rev().map(bottom).collect())).unwrap();
    writeln!(text, "f {}", cap((0..segments).map(top).collect())).unwrap();
    text
}

#[test]
fn a_cylinder_obj_gets_smooth_sides_and_sharp_caps_by_default() {
    let d = dir("cylinder");
    std::fs::write(d.join("cyl.obj"), cylinder_obj(16)).unwrap();
    // Adjacent sides meet at 22.5°: smooth under the default 30° crease, sharp under 20°.
    for (extra, smooth_sides) in [("", true), ("normals = { crease_deg = 20.0 }", false)] {
        let scene = obj_scene(&d, "cyl.obj", extra);
        let m = object_mesh(&scene);
        assert_eq!(m.triangles.len(), 2 * 16 + 2 * 14);
        let (mut sides, mut caps) = (0, 0);
        for t in &m.triangles {
            let face = face_normal(m, t);
            for &v in t {
                let (p, n) = (m.positions[v as usize], m.normals[v as usize]);
                if face.z.abs() > 0.5 {
                    // A cap: sharp against the sides, so its own normal everywhere.
                    caps += 1;
                    assert!(close(n, face), "{extra:?}: cap corner at {p}: {n}");
                } else if smooth_sides {
                    sides += 1;
                    let radial = Vec3::new(p.x, p.y, 0.0).normalize();
                    assert!(close(n, radial), "{extra:?}: side corner at {p}: {n}");
                } else {
                    sides += 1;
                    assert!(close(n, face), "{extra:?}: side corner at {p}: {n}");
                }
            }
        }
        assert_eq!((sides, caps), (3 * 32, 3 * 28));
        // Smooth sides share one vertex per rim position; the caps have their own.
        let expected = if smooth_sides { 32 + 32 } else { 16 * 4 + 32 };
        assert_eq!(m.positions.len(), expected, "{extra:?}");
    }
}

#[test]
fn an_environment_mesh_follows_the_same_rule() {
    let d = dir("env-mesh");
    std::fs::write(d.join("box.obj"), box_obj(false)).unwrap();
    let object =
        "[[object]]\npatches = \"newell-teapot\"\nmaterial = { color = [0.5, 0.5, 0.5] }\n";
    let scene = scene_in(
        &d,
        &format!(
            "{object}[[mesh]]\npath = \"box.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"
        ),
    )
    .unwrap();
    assert_flat(&scene.shapes[0].mesh);
    let scene = scene_in(
        &d,
        &format!("{object}[[mesh]]\npath = \"box.obj\"\nnormals = \"smooth\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"),
    )
    .unwrap();
    assert_box_smooth(&scene.shapes[0].mesh);
    // Patch objects record no normals rule: theirs are exact.
    assert!(scene.objects[0].normals.is_none());
}

// ---------------------------------------------------------------------------------------------
// glTF

/// A `.glb` of one node "Box": the unit cube, 8 shared vertices, 12 triangles; with `NORMAL`
/// (pointing along each corner's diagonal) if asked.
fn box_glb(with_normals: bool) -> Vec<u8> {
    let positions: Vec<[f32; 3]> = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    #[rustfmt::skip]
    let indices: Vec<u32> = vec![
        0, 2, 3, 0, 3, 1,  4, 5, 7, 4, 7, 6,  0, 1, 5, 0, 5, 4,
        2, 6, 7, 2, 7, 3,  0, 4, 6, 0, 6, 2,  1, 3, 7, 1, 7, 5,
    ];
    let mut b = Builder::new();
    let pos = b.positions(&positions);
    let idx = b.indices_u32(&indices);
    let mut attributes = json!({"POSITION": pos});
    if with_normals {
        let normals: Vec<[f32; 3]> = positions
            .iter()
            .map(|p| {
                (Vec3::from_array(*p) - Vec3::splat(0.5))
                    .normalize()
                    .to_array()
            })
            .collect();
        attributes["NORMAL"] = json!(b.vec3(&normals));
    }
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Box", "mesh": 0}],
        "meshes": [{"name": "Cube", "primitives": [{"attributes": attributes, "indices": idx}]}],
    }))
}

fn gltf_scene(d: &Path, extra: &str) -> Scene {
    let text = format!("[[gltf]]\npath = \"box.glb\"\nobjects = [\"Box\"]\n{extra}\n");
    scene_in(d, &text).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_gltf_primitive_without_normal_is_flat_unless_asked() {
    let d = dir("gltf");
    std::fs::write(d.join("box.glb"), box_glb(false)).unwrap();
    let scene = gltf_scene(&d, "");
    let m = object_mesh(&scene);
    assert_flat(m);
    assert_eq!(m.positions.len(), 36);
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(used.rule, Some(NormalRule::Flat));
    assert_eq!(
        used.to_string(),
        "flat (box.glb meshes[0] \"Cube\" primitive 0 has no NORMAL; the glTF default)"
    );
    // Asked for smooth normals: shared, averaged.
    let scene = gltf_scene(&d, "normals = \"smooth\"");
    let m = object_mesh(&scene);
    assert_eq!(m.positions.len(), 8);
    assert_box_smooth(m);
    // The default crease angle keeps the box's edges sharp, its faces flat.
    let scene = gltf_scene(&d, "normals = { crease_deg = 30.0 }");
    let m = object_mesh(&scene);
    assert_eq!(m.positions.len(), 24);
    assert_flat(m);
    assert_eq!(
        scene.objects[0].normals.as_ref().unwrap().to_string(),
        "crease 30° (asked for in the scene file; box.glb meshes[0] \"Cube\" primitive 0 has no NORMAL)"
    );
}

#[test]
fn a_gltf_primitive_keeps_its_normal_unless_asked() {
    let d = dir("gltf-normal");
    std::fs::write(d.join("box.glb"), box_glb(true)).unwrap();
    let scene = gltf_scene(&d, "");
    assert_box_smooth(object_mesh(&scene));
    let used = scene.objects[0].normals.as_ref().unwrap();
    assert_eq!(used.rule, None);
    assert_eq!(
        used.to_string(),
        "from the file (box.glb meshes[0] \"Cube\" primitive 0 has NORMAL)"
    );
    let scene = gltf_scene(&d, "normals = \"flat\"");
    assert_flat(object_mesh(&scene));
    assert_eq!(
        scene.objects[0].normals.as_ref().unwrap().reason,
        "asked for in the scene file; replaces the NORMAL box.glb meshes[0] \"Cube\" primitive 0 has"
    );
}

// ---------------------------------------------------------------------------------------------
// Errors

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
fn bad_normals_keys_are_located_errors() {
    let d = dir("errors");
    std::fs::write(d.join("box.obj"), box_obj(false)).unwrap();
    std::fs::write(d.join("box.glb"), box_glb(false)).unwrap();
    let object = |normals: &str| {
        format!("[[object]]\nmesh = \"box.obj\"\nnormals = {normals}\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n")
    };
    assert_located(
        &d,
        &object("{ crease_deg = 200 }"),
        3,
        26,
        "200 must be an angle in degrees within [0, 180]",
    );
    assert_located(
        &d,
        &object("{ crease_deg = -1.0 }"),
        3,
        26,
        "within [0, 180]",
    );
    assert_located(
        &d,
        &object("\"smoth\""),
        3,
        11,
        "unknown normals \"smoth\" (expected \"smooth\", \"flat\" or { crease_deg = DEGREES })",
    );
    assert_located(
        &d,
        &object("{ crease = 30 }"),
        3,
        13,
        "unknown field `crease`",
    );
    assert_located(&d, &object("30"), 3, 11, "normals = \"smooth\"");
    let patches = "[[object]]\npatches = \"newell-teapot\"\nnormals = \"flat\"\nmaterial = { color = [0.5, 0.5, 0.5] }\n";
    assert_located(&d, patches, 3, 11, "Bézier patches have exact ones");
    let gltf =
        "[[gltf]]\npath = \"box.glb\"\nobjects = [\"Box\"]\nnormals = { crease_deg = 181 }\n";
    assert_located(&d, gltf, 4, 26, "within [0, 180]");
    let mesh = "[[object]]\npatches = \"newell-teapot\"\nmaterial = { color = [0.5, 0.5, 0.5] }\n[[mesh]]\npath = \"box.obj\"\nnormals = \"round\"\nmaterial = { color = [0.5, 0.5, 0.5] }\n";
    assert_located(&d, mesh, 6, 11, "unknown normals \"round\"");
}
