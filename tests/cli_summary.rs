//! The bake summary explains itself (issue 28): per object, where and why sample-map texels
//! are short, and (JSON) the same in `--report-json`.

mod common;

use std::path::Path;

use common::oslf;

/// The unit cube [0, 1]³ without normals: 8 vertices, 6 quads wound outwards.
const BOX_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// The box resting on a slab (its bottom in the slab's top plane), with `bake` settings.
fn scene(dir: &Path, bake: &str) -> std::path::PathBuf {
    std::fs::write(dir.join("box.obj"), BOX_OBJ).unwrap();
    let text = format!(
        r#"
[environment]
uniform = [1.0, 1.0, 1.0]

[[box]]
size = [6.0, 6.0, 0.2]
transform = {{ translate = [0.0, 0.0, -0.1] }}
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
    // The next line: the bottom, facing down at z = 0, in contact with the slab, harmless.
    let place = lines[at + 1];
    assert!(place.starts_with("               "), "{stdout}");
    for part in [
        "texels facing down (−z) at x ",
        "z = 0.00",
        "all empty",
        "within ε of [[box]] 0",
        "harmless where unseen",
    ] {
        assert!(place.contains(part), "{part:?} not in {place:?}\n{stdout}");
    }
    let c = &json["coverage"][0];
    assert_eq!(c["object"], "box", "{json}");
    assert!(c["short"].as_u64().unwrap() > 0, "{json}");
    assert_eq!(c["short"], json["sample_maps"]["short"], "{json}");
    assert_eq!(c["texels"], json["sample_maps"]["texels"], "{json}");
    let p = &c["places"][0];
    assert_eq!(p["cause"], "contact", "{json}");
    assert_eq!(p["surface"], "[[box]] 0", "{json}");
    assert_eq!(p["facing"], "-z", "{json}");
    assert_eq!(p["min"][2], 0.0, "{json}");
    assert!(p["remedy"].as_str().unwrap().contains("epsilon"), "{json}");
}
