//! A triangle-mesh OSLF object end to end through the command line: an OBJ sphere without
//! texture coordinates baked (`[[object]] mesh = …`), described by `oslf store info`, rendered
//! in every mode, and its mirror term compared with `oslf truth`: the light field beats the
//! environment map, as it does for patches.

use crate::common;

use std::fmt::Write as _;
use std::path::Path;

use common::{oslf, read_exr, run_ok};

/// A UV-less sphere of `radius` as Wavefront OBJ text (positions, normals, faces `v//vn`),
/// `rings` × `segments` quads, counter-clockwise seen from outside.
fn sphere_obj(radius: f32, rings: u32, segments: u32) -> String {
    let mut text = String::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            let n = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            writeln!(
                text,
                "v {} {} {}\nvn {} {} {}",
                n[0] * radius,
                n[1] * radius,
                n[2] * radius,
                n[0],
                n[1],
                n[2]
            )
            .unwrap();
        }
    }
    let id = |r: u32, s: u32| r * segments + s % segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (id(r, s), id(r + 1, s), id(r + 1, s + 1), id(r, s + 1));
            if r > 0 {
                writeln!(text, "f {a}//{a} {b}//{b} {d}//{d}").unwrap();
            }
            if r + 1 < rings {
                writeln!(text, "f {b}//{b} {c}//{c} {d}//{d}").unwrap();
            }
        }
    }
    text
}

/// The sphere floating over a checkered floor beside a red box, so that reflections depend
/// on the position on the sphere.
const SCENE: &str = r#"
[camera]
position = [3.2, -2.4, 2.2]
target = [0.0, 0.0, 1.0]
vfov = 35.0

[environment]
uniform = [0.6, 0.7, 0.9]

[[point_light]]
position = [2.0, -2.0, 4.0]
intensity = [20.0, 20.0, 20.0]

[[object]]
name = "ball"
mesh = "ball.obj"
transform = { translate = [0.0, 0.0, 1.0] }
material = { color = [0.7, 0.7, 0.7] }

[[plane]]
size = [8.0, 8.0]
material = { checker = { a = [0.9, 0.9, 0.9], b = [0.1, 0.1, 0.1], scale = 2.0 } }

[[box]]
size = [0.6, 0.6, 1.6]
transform = { translate = [0.0, 1.4, 0.8] }
material = { color = [0.8, 0.1, 0.1] }

[bake]
epsilon = 0.05
sample_count = 160
cube_resolution = 16
sample_map_resolution = 32
samples_per_texel = 4
bounces = 1
"#;

/// RMSE of RGB between `a` and `b` over `a`'s object mask.
fn rmse(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let (mut sum, mut n) = (0f64, 0usize);
    for (p, q) in a.iter().zip(b) {
        if p[3] > 0.5 {
            for k in 0..3 {
                sum += f64::from(p[k] - q[k]).powi(2);
            }
            n += 3;
        }
    }
    assert!(n > 300, "the object covers {} pixels", n / 3);
    (sum / n as f64).sqrt()
}

fn render(store: &Path, out: &Path, flags: &[&str]) -> Vec<[f32; 4]> {
    run_ok(
        oslf("render")
            .arg(store)
            .arg("-o")
            .arg(out)
            .args(["--width", "96", "--height", "72", "--background", "none"])
            .args(flags),
    );
    read_exr(out).1
}

#[test]
fn an_obj_mesh_object_bakes_renders_and_beats_the_environment_map() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("ball.obj"), sphere_obj(0.5, 12, 24)).unwrap();
    let scene = dir.join("ball.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let store = dir.join("ball.oslf");
    let summary =
        run_ok(
            oslf("bake")
                .arg(&scene)
                .arg("-o")
                .arg(&store)
                .args(["--preview", "none", "-q"]),
        );
    // The OBJ has no texture coordinates: the summary says how the atlas was laid out.
    assert!(
        summary.contains("atlas          \"ball\": ")
            && summary.contains(" charts of its own; the surface covers "),
        "{summary}"
    );

    let info = run_ok(oslf("store").args(["info", "--json"]).arg(&store));
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    let object = &info["objects"][0];
    assert_eq!(object["name"], "ball", "{info}");
    assert_eq!(object["kind"], "mesh", "{info}");
    assert_eq!(object["triangles"], 12 * 24 * 2 - 2 * 24, "{info}");

    // Every mode renders finite pixels on the object.
    for mode in ["recon", "mirror", "recon-mirror", "glossy", "recon-glossy"] {
        let px = render(&store, &dir.join(format!("{mode}.exr")), &["--mode", mode]);
        let object: Vec<_> = px.iter().filter(|p| p[3] > 0.5).collect();
        assert!(object.len() > 300, "{mode}: {} object pixels", object.len());
        assert!(
            object.iter().all(|p| p.iter().all(|v| v.is_finite())),
            "{mode}"
        );
        assert!(
            object.iter().any(|p| p[0] + p[1] + p[2] > 0.01),
            "{mode}: the object is black"
        );
    }

    let (e_oslf, e_env) = mirror_errors(dir, &scene, &store);
    assert!(
        e_oslf < 0.8 * e_env,
        "mirror RMSE: OSLF {e_oslf:.4}, environment map {e_env:.4}"
    );
}

/// RMSE of the mirror term against `oslf truth` (16 spp, 96×72, from the scene's camera) for
/// the light field and for the environment map: `(oslf, env)`. Asserts that the rasterized
/// and the ray-traced object cover the same pixels.
fn mirror_errors(dir: &Path, scene: &Path, store: &Path) -> (f64, f64) {
    run_ok(
        oslf("truth")
            .arg(scene)
            .arg("--store")
            .arg(store)
            .args([
                "-m", "mirror", "--spp", "16", "--width", "96", "--height", "72",
            ])
            .args(["-q", "-o"])
            .arg(dir.join("truth")),
    );
    let truth = read_exr(&dir.join("truth-mirror.exr")).1;
    let oslf_px = render(store, &dir.join("oslf.exr"), &["--mode", "mirror"]);
    let env_px = render(
        store,
        &dir.join("env.exr"),
        &["--mode", "mirror", "--source", "env"],
    );
    // The rasterized mesh and the ray-traced mesh cover the same pixels.
    let mask = |px: &[[f32; 4]]| px.iter().filter(|p| p[3] > 0.5).count();
    let (a, b) = (mask(&truth), mask(&oslf_px));
    assert!(
        a.abs_diff(b) * 50 < a,
        "object pixels: truth {a}, render {b}"
    );
    (rmse(&truth, &oslf_px), rmse(&truth, &env_px))
}

/// The unit cube as OBJ text without normals: 8 vertices, 6 quads wound outwards.
const BOX_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

#[test]
fn the_bake_summary_says_which_normals_each_mesh_object_got() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("box.obj"), BOX_OBJ).unwrap();
    let scene = dir.join("box.toml");
    let text = |normals: &str| {
        format!(
            r#"
[environment]
uniform = [1.0, 1.0, 1.0]

[[object]]
name = "box"
mesh = "box.obj"
{normals}
material = {{ color = [0.5, 0.5, 0.5] }}

[bake]
epsilon = 0.02
sample_count = 12
cube_resolution = 2
sample_map_resolution = 4
samples_per_texel = 1
"#
        )
    };
    for (i, (normals, line, rule)) in [
        (
            "",
            "normals        object \"box\": crease 30° (box.obj has no normals; the default for OBJ)",
            serde_json::json!({"crease": {"crease_deg": 30.0}}),
        ),
        (
            "normals = \"smooth\"",
            "normals        object \"box\": smooth (asked for in the scene file; box.obj has no normals)",
            serde_json::json!("smooth"),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        std::fs::write(&scene, text(normals)).unwrap();
        let report = dir.join("report.json");
        let summary = run_ok(oslf("bake")
            .arg(&scene)
            .arg("-o")
            .arg(dir.join(format!("box{i}.oslf")))
            .args(["--preview", "none", "-q", "--report-json"])
            .arg(&report));
        assert!(
            summary.lines().any(|l| l == line),
            "no line {line:?} in:\n{summary}"
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(json["normals"][0]["object"], "box", "{json}");
        assert_eq!(json["normals"][0]["rule"], rule, "{json}");
    }
}

#[test]
fn a_box_without_normals_keeps_its_points_and_mirrors_with_flat_faces() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("box.obj"), BOX_OBJ).unwrap();
    // The ball's scene with the box in its place: a 0.9 m cube, turned so that three faces
    // show, floating 0.6 m over the floor.
    let text = SCENE.replace(
        "mesh = \"ball.obj\"\ntransform = { translate = [0.0, 0.0, 1.0] }",
        "mesh = \"box.obj\"\ntransform = { translate = [-0.3, -0.8, 0.6], rotate = [0.0, 0.0, 20.0], scale = 0.9 }",
    );
    assert_ne!(text, SCENE);
    let scene = dir.join("box.toml");
    std::fs::write(&scene, text).unwrap();
    let store = dir.join("box.oslf");
    let report = dir.join("report.json");
    run_ok(
        oslf("bake")
            .arg(&scene)
            .arg("-o")
            .arg(&store)
            .args(["--preview", "none", "-q", "--report-json"])
            .arg(&report),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let placed = json["points_placed"].as_u64().unwrap();
    let lost = json["points_removed_close"].as_u64().unwrap()
        + json["points_removed_inside"].as_u64().unwrap();
    assert!(placed >= 100 && lost * 20 <= placed, "{json}");

    // Flat faces: a smoothed box would reflect the scene bent round its edges, unlike the
    // truth, which traces the box's own flat faces. The error is in the ball's band.
    let (e_oslf, e_env) = mirror_errors(dir, &scene, &store);
    assert!(
        e_oslf < 0.8 * e_env,
        "mirror RMSE: OSLF {e_oslf:.4}, environment map {e_env:.4}"
    );
}
