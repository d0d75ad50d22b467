//! Per-object sample density: `[[object]] sample_spacing` gives a small object beside a large
//! one sample points (and atlas texels) at its own scale, while `[bake]`'s density keeps
//! covering the other objects; the preflight counts the same points. `[[gltf]] sample_spacing`
//! does the same for the include's objects.

use crate::gltf_builder;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use oslf_bake::preflight::estimate;
use oslf_bake::sample_points::{self, Surfaces};
use oslf_scene::scene::Scene;
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_scene::BakeError;
use oslf_trace::bvh::TriangleScene;
use serde_json::json;

/// A fresh directory for one test, under Cargo's target tmp; the next run replaces it.
fn dir(test: &str) -> PathBuf {
    let d =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("object_spacing/{test}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An icosphere OBJ (no normals, no uvs) of `radius` at `x` on the x axis.
fn sphere_obj(radius: f32, x: f32) -> String {
    let m = oslf_geometry::mesh::Mesh::icosphere(2);
    let mut text = String::new();
    for p in &m.positions {
        let p = *p * radius;
        writeln!(text, "v {} {} {}", p.x + x, p.y, p.z).unwrap();
    }
    for t in &m.triangles {
        writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    text
}

/// A large ball (radius 1) and a small one (radius 0.1) beside it; `small` holds extra keys of
/// the small one.
fn scene(d: &Path, small: &str) -> Result<Scene, BakeError> {
    std::fs::write(d.join("big.obj"), sphere_obj(1.0, 0.0)).unwrap();
    std::fs::write(d.join("small.obj"), sphere_obj(0.1, 3.0)).unwrap();
    let text = format!(
        r#"
[environment]
uniform = [1.0, 1.0, 1.0]

[[object]]
name = "big"
mesh = "big.obj"
material = {{ color = [0.5, 0.5, 0.5] }}

[[object]]
name = "small"
mesh = "small.obj"
{small}
material = {{ color = [0.5, 0.5, 0.5] }}

[bake]
epsilon = 0.005
sample_count = 200
sample_map_resolution = 64
"#
    );
    let path = d.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path, None)
}

/// Sample points placed on each of the two objects.
fn points_per_object(scene: &Scene) -> [usize; 2] {
    let settings = &scene.bake;
    let geometry = TriangleScene::build(oslf_trace::bvh::scene_instances(
        scene,
        true,
        settings.epsilon * TESSELLATION_ERROR,
    ))
    .unwrap();
    let surfaces = Surfaces::new(&scene.objects, settings).unwrap();
    let placement = sample_points::place(&surfaces, settings, &geometry).unwrap();
    let mut counts = [0; 2];
    for p in &placement.points {
        counts[p.object as usize] += 1;
    }
    counts
}

#[test]
fn a_small_object_with_its_own_spacing_gets_enough_points() {
    let d = dir("small");
    // Without its own spacing the small ball gets its share of the area: 1 % of 200 points.
    let shared = scene(&d, "").unwrap();
    let [big, small] = points_per_object(&shared);
    assert!(small <= 6, "{big} {small}");
    // With sample_spacing = 0.04 it gets its area over (√3/2)·0.04²: about 80 points, and the
    // big ball keeps sample_count = 200 for itself.
    let own = scene(&d, "sample_spacing = 0.04").unwrap();
    assert_eq!(own.objects[1].sample_spacing, Some(0.04));
    let area = own.objects[1].mesh.as_ref().unwrap().mesh.area() as f32;
    let expected = (area / (0.866_025_4 * 0.04 * 0.04)).ceil() as usize;
    assert!((70..=90).contains(&expected), "{expected}");
    let [big, small] = points_per_object(&own);
    assert!(
        small >= expected * 9 / 10 && small <= expected,
        "{small} of {expected}"
    );
    assert!((180..=200).contains(&big), "{big}");
    // The preflight counts the same request: 200 shared points plus the small ball's.
    assert_eq!(estimate(&own, 1).sample_points.0, 200 + expected as u64);
    // The small ball's atlas texel follows its spacing.
    let surfaces = Surfaces::new(&own.objects, &own.bake).unwrap();
    assert!((surfaces.spacing(1) - 0.04).abs() < 1e-7);
    let shared_spacing = surfaces.spacing(0);
    assert!(shared_spacing > 0.1, "{shared_spacing}");
}

#[test]
fn a_bad_object_spacing_is_a_located_error() {
    let d = dir("errors");
    match scene(&d, "sample_spacing = -1.0") {
        Err(BakeError::Parse {
            line,
            column,
            message,
            ..
        }) => {
            assert_eq!((line, column), (13, 18), "{message}");
            assert!(
                message.contains("-1 must be a finite number > 0"),
                "{message}"
            );
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
}

/// A `.glb` of one node "Small": the small ball of [`sphere_obj`] (flat normals).
fn small_glb() -> Vec<u8> {
    let m = oslf_geometry::mesh::Mesh::icosphere(2);
    let positions: Vec<[f32; 3]> = m
        .positions
        .iter()
        .map(|p| [0.1 * p.x + 3.0, 0.1 * p.y, 0.1 * p.z])
        .collect();
    let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    let mut b = gltf_builder::Builder::new();
    let pos = b.positions(&positions);
    let idx = b.indices_u32(&indices);
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Small", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
    }))
}

#[test]
fn a_gltf_include_gives_its_objects_their_spacing() {
    let d = dir("gltf");
    std::fs::write(d.join("big.obj"), sphere_obj(1.0, 0.0)).unwrap();
    std::fs::write(d.join("small.glb"), small_glb()).unwrap();
    let text = |extra: &str| {
        format!(
            "[[object]]\nname = \"big\"\nmesh = \"big.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\n\
             [[gltf]]\npath = \"small.glb\"\nobjects = [\"Small\"]\n{extra}\n\n\
             [bake]\nepsilon = 0.005\nsample_count = 200\nsample_map_resolution = 64\n"
        )
    };
    let path = d.join("scene.toml");
    std::fs::write(&path, text("")).unwrap();
    let shared = Scene::load(&path, None).unwrap();
    assert_eq!(shared.objects[1].sample_spacing, None);
    assert!(points_per_object(&shared)[1] <= 6);
    std::fs::write(&path, text("sample_spacing = 0.04")).unwrap();
    let own = Scene::load(&path, None).unwrap();
    assert_eq!(own.objects[1].sample_spacing, Some(0.04));
    let [big, small] = points_per_object(&own);
    assert!(small >= 70, "{small}");
    assert!((180..=200).contains(&big), "{big}");
}
