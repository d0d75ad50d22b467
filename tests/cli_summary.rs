//! The bake summary explains itself: per object, where and why sample-map texels
//! are short; how noisy the cube maps are and, when it shows, what to raise at what cost; and
//! (JSON) the same in `--report-json`.

use crate::common;

use std::path::Path;

use common::oslf;

/// The unit cube [0, 1]³ without normals: 8 vertices, 6 quads wound outwards.
const BOX_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// A wide slab whose top is the box's bottom plane: the box rests on it.
const RESTING: &str = "size = [6.0, 6.0, 0.2]\ntransform = { translate = [0.0, 0.0, -0.1] }";

/// A slab of the box's footprint, its top ε/2 under the box: the box hovers over it, and views
/// from the side reach the edges of its bottom.
const HOVERING: &str = "size = [1.0, 1.0, 0.2]\ntransform = { translate = [0.0, 0.0, -0.125] }";

/// The box resting on a slab (its bottom in the slab's top plane) under a low sun, with
/// `bake` settings.
fn scene(dir: &Path, bake: &str) -> std::path::PathBuf {
    scene_over(dir, RESTING, bake)
}

/// The box over `slab` (the slab's `size` and `transform`) under a low sun, with `bake`
/// settings.
fn scene_over(dir: &Path, slab: &str, bake: &str) -> std::path::PathBuf {
    std::fs::write(dir.join("box.obj"), BOX_OBJ).unwrap();
    let text = format!(
        r#"
[environment]
uniform = [0.3, 0.4, 0.6]

[[directional_light]]
direction = [0.5, -0.3, 0.4]
irradiance = [4.0, 4.0, 4.0]

[[box]]
{slab}
material = {{ color = [0.5, 0.5, 0.5] }}

[[object]]
name = "box"
mesh = "box.obj"
normals = "flat"
transform = {{ translate = [-0.5, -0.5, 0.0] }}
material = {{ color = [0.5, 0.5, 0.5] }}

[bake]
epsilon = 0.05
{bake}
"#
    );
    let path = dir.join("box.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Bakes `scene`; its stdout and the `--report-json` it wrote.
fn bake(scene: &Path, dir: &Path) -> (String, serde_json::Value) {
    let report = dir.join("report.json");
    let out = oslf("bake")
        .arg(scene)
        .arg("-o")
        .arg(dir.join("box.oslf"))
        .args(["--preview", "none", "-q", "--report-json"])
        .arg(&report)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    (stdout, json)
}

#[test]
fn the_summary_says_where_and_why_an_objects_texels_are_short() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let path = scene(
        dir,
        "sample_count = 400\nsample_map_resolution = 32\ncube_resolution = 2\nsamples_per_texel = 1",
    );
    let (stdout, json) = bake(&path, dir);
    let lines: Vec<&str> = stdout.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("coverage       object \"box\": "))
        .unwrap_or_else(|| panic!("no coverage line:\n{stdout}"));
    assert!(
        lines[at].contains("texels") && lines[at].contains("with fewer than four points"),
        "{stdout}"
    );
    // Every empty texel is the bottom's, which no view reaches.
    assert!(
        lines[at].ends_with(", all where no view reaches"),
        "{stdout}"
    );
    // The next line: the bottom, facing down at z = 0, in contact with the slab and enclosed
    // by it.
    let place = lines[at + 1];
    assert!(place.starts_with("               "), "{stdout}");
    for part in [
        "texels facing down (−z) at x ",
        "z = 0.00",
        "all empty",
        "within ε of [[box]] 0, enclosed",
        "no view reaches them: nothing is lost",
    ] {
        assert!(place.contains(part), "{part:?} not in {place:?}\n{stdout}");
    }
    let c = &json["coverage"][0];
    assert_eq!(c["object"], "box", "{json}");
    assert!(c["short"].as_u64().unwrap() > 0, "{json}");
    assert_eq!(c["short"], json["sample_maps"]["short"], "{json}");
    assert_eq!(c["texels"], json["sample_maps"]["texels"], "{json}");
    let p = &c["places"][0];
    assert_eq!(p["cause"], "unseen", "{json}");
    assert_eq!(p["surface"], "[[box]] 0", "{json}");
    assert_eq!(p["facing"], "-z", "{json}");
    assert_eq!(p["min"][2], 0.0, "{json}");
    assert_eq!(c["unseen_empty"], c["empty"], "{json}");
}

#[test]
fn the_summary_says_how_noisy_the_cubes_are_and_what_to_raise_at_what_cost() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let settings = |spp: u32| {
        format!(
            "sample_count = 24\nsample_map_resolution = 8\ncube_resolution = 8\nsamples_per_texel = {spp}\nbounces = 1"
        )
    };
    let (stdout, json) = bake(&scene(dir, &settings(4)), dir);
    let noise = stdout
        .lines()
        .find(|l| l.starts_with("noise          ±"))
        .unwrap_or_else(|| panic!("no noise line:\n{stdout}"));
    // Denoised by default: the line says the error is the capture's, before the filter.
    assert!(
        noise.contains("(4 samples per texel), before denoising: above 5.0%; the filter"),
        "{stdout}"
    );
    assert_eq!(json["noise"]["denoised"], true, "{json}");
    let hint = stdout
        .lines()
        .find(|l| l.starts_with("hint           raise samples_per_texel to "))
        .unwrap_or_else(|| panic!("no hint line:\n{stdout}"));
    assert!(
        hint.contains("to halve the noise")
            && hint.contains("4× as long")
            && hint.contains("by the preflight's estimate"),
        "{hint}"
    );
    let n = &json["noise"];
    assert_eq!(n["samples_per_texel"], 4, "{json}");
    assert!(n["relative_error"].as_f64().unwrap() > 0.05, "{json}");
    let more = n["suggestion"]["samples_per_texel"].as_u64().unwrap();
    assert_eq!(more, 16, "{json}");
    assert!(hint.contains(&format!("to {more} ")), "{hint}");
    assert!(
        n["suggestion"]["capture_seconds"][1].as_f64().unwrap() > 0.0,
        "{json}"
    );

    // Enough samples: a noise line without a hint.
    let (stdout, json) = bake(&scene(dir, &settings(256)), dir);
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("noise          ±") && l.contains("below the 5.0% that shows")),
        "{stdout}"
    );
    assert!(!stdout.contains("hint "), "{stdout}");
    assert!(json["noise"]["suggestion"].is_null(), "{json}");

    // Without the filter the cubes keep their speckle, and the line says so.
    let raw = format!("{}\ndenoise = false", settings(4));
    let (stdout, json) = bake(&scene(dir, &raw), dir);
    assert!(
        stdout.lines().any(|l| l.starts_with("noise          ±")
            && l.contains("(4 samples per texel): above 5.0%, it shows as speckle")),
        "{stdout}"
    );
    assert_eq!(json["noise"]["denoised"], false, "{json}");
}

#[test]
fn strict_refusal_says_where_the_empty_texels_are_and_why() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let settings =
        "sample_count = 400\nsample_map_resolution = 32\ncube_resolution = 2\nsamples_per_texel = 1";
    let run = |path: &Path, strict: bool| {
        let mut c = oslf("bake");
        c.arg(path)
            .arg("-o")
            .arg(dir.join("strict.oslf"))
            .args(["--preview", "none", "-q"]);
        if strict {
            c.arg("--strict");
        }
        c.output().unwrap()
    };
    // Hovering: the edges of the bottom are empty and seen from the side.
    let out = run(&scene_over(dir, HOVERING, settings), true);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    for part in [
        "have no visible sample point",
        "; where: object \"box\": ",
        "texels facing down (−z) at x ",
        "within ε of [[box]] 0; harmless where unseen",
        "(--strict)",
    ] {
        assert!(err.contains(part), "{part:?} not in {err}");
    }
    // Without --strict the bake warns, counting the bottom's middle apart.
    let out = run(&scene_over(dir, HOVERING, settings), false);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: ") && err.contains("more where no view reaches)"),
        "{err}"
    );
    // Resting: every empty texel is under the box, where no view reaches; --strict bakes it
    // without a warning.
    let out = run(&scene(dir, settings), true);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("warning"), "{err}");
}
