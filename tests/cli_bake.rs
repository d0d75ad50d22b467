//! The `oslf bake` command: a small bake end to end, and bad input.

mod common;

use common::oslf;


fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("oslf-bake-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SCENE: &str = r#"
[camera]
position = [6.0, -6.0, 4.0]
target = [0.0, 0.0, 1.0]

[environment.sky]
sun_direction = [0.6, -0.4, 0.7]
sun_irradiance = [5.0, 5.0, 5.0]

[[object]]
patches = "newell-teapot"
select = [20, 28]
material = { color = [0.1, 0.4, 0.1] }

[bake]
sample_count = 12
cube_resolution = 2
sample_map_resolution = 4
samples_per_texel = 1
"#;

#[test]
fn bakes_a_store_with_summary_preview_and_json_report() {
    let dir = temp_dir("ok");
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let out = oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("lid.oslf"))
        .args(["--preview-spp", "1", "-q", "--report-json"])
        .arg(dir.join("report.json"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in [
        "sample points",
        "Mrays/s",
        "bytes per cube-map texel",
        "fewer than four",
    ] {
        assert!(
            stdout.contains(needle),
            "summary lacks {needle:?}:\n{stdout}"
        );
    }
    assert!(dir.join("lid.oslf").exists());
    assert!(dir.join("lid.oslf.preview.png").exists());
    assert!(dir.join("lid.oslf.preview.exr").exists());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["finished"], true);
    assert!(report["sample_points"].as_u64().unwrap() > 0);
}

#[test]
fn a_bad_scene_fails_with_a_located_message() {
    let dir = temp_dir("bad");
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        SCENE.replace("sample_count = 12", "sample_count = -3"),
    )
    .unwrap();
    let out = oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("bad.oslf"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("{}:16:16", scene.display())),
        "{stderr}"
    );
    assert!(!dir.join("bad.oslf").exists());
}

#[test]
fn a_missing_scene_file_is_named() {
    let out = oslf("bake")
        .arg("/nonexistent/scene.toml")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("/nonexistent/scene.toml"), "{stderr}");
}

#[test]
fn oslf_truth_writes_every_mode_and_checks_the_store() {
    let dir = temp_dir("truth");
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let bake = oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("lid.oslf"))
        .args(["--preview", "none", "-q"])
        .output()
        .unwrap();
    assert!(bake.status.success());
    let truth = |extra: &[&str]| {
        oslf("truth")
            .arg(&scene)
            .args(["--width", "40", "--height", "30", "--spp", "2", "-q", "-o"])
            .arg(dir.join("t"))
            .args(extra)
            .output()
            .unwrap()
    };
    let out = truth(&[
        "--modes",
        "recon,mirror,recon-mirror,glossy,recon-glossy",
        "--store",
        dir.join("lid.oslf").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for m in ["recon", "mirror", "recon-mirror", "glossy", "recon-glossy"] {
        for ext in ["exr", "png"] {
            assert!(dir.join(format!("t-{m}.{ext}")).exists(), "t-{m}.{ext}");
        }
    }
    let e = truth(&["--modes", "mirror,shiny"]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("unknown mode \"shiny\""));
    // A store baked from a different scene file is refused.
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        SCENE.replace("sample_count = 12", "sample_count = 13"),
    )
    .unwrap();
    let e = oslf("truth")
        .arg(&other)
        .args(["--store", dir.join("lid.oslf").to_str().unwrap(), "-q"])
        .output()
        .unwrap();
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("was not baked from"));
    let e = truth(&["--nu=-1", "--modes", "glossy"]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("n_u"));
}
