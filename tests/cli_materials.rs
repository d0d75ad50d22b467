//! An OSLF object's own material end to end: `[[object]] material = { color, metallic,
//! roughness }` is recorded in the store (format version 7), `oslf store info` shows it,
//! `oslf render` draws such a store in the pbr mode by default with the object's factors (the
//! flags override them), and `oslf truth -m pbr` renders the object with them.

use crate::common;

use std::path::Path;

use common::{oslf, read_exr, run_ok};

/// The lid scene with a brushed-metal lid: metallic 1, roughness 0.4.
fn scene(dir: &Path) -> std::path::PathBuf {
    let text = common::LID_SCENE.replace(
        "material = { color = [0.1, 0.4, 0.1] }",
        "material = { color = [0.9, 0.6, 0.3], metallic = 1.0, roughness = 0.4 }",
    );
    assert!(
        text.contains("metallic"),
        "the fixture's object material moved"
    );
    let path = dir.join("lid.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn an_objects_material_reaches_the_store_the_renderer_and_the_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = scene(dir);
    let store = dir.join("lid.oslf");
    run_ok(
        oslf("bake")
            .arg(&scene)
            .arg("-o")
            .arg(&store)
            .args(["-q", "--preview", "none"]),
    );
    let info: serde_json::Value =
        serde_json::from_str(&run_ok(oslf("store info").arg(&store).arg("--json"))).unwrap();
    let material = &info["objects"][0]["material"];
    assert_eq!(material["model"], "metallic-roughness", "{info}");
    assert_eq!(material["metallic"], 1.0, "{info}");
    assert!(
        (material["roughness"].as_f64().unwrap() - 0.4).abs() < 1e-6,
        "{info}"
    );
    let text = run_ok(oslf("store info").arg(&store));
    assert!(
        text.contains(
            "material: metallic-roughness, base colour [0.9, 0.6, 0.3], metallic 1, roughness 0.4"
        ),
        "{text}"
    );

    // Without --mode: pbr with the object's factors; the same image as the factors given.
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(format!("{name}.exr"));
        let summary = run_ok(
            oslf("render")
                .arg(&store)
                .args(["--width", "48", "--height", "36", "-M", "8", "-o"])
                .arg(&out)
                .args(extra),
        );
        (summary, read_exr(&out).1)
    };
    let (summary, own) = render("own", &[]);
    assert!(summary.contains("mode           pbr (the default for this store), objects with a metallic-roughness material in the store shaded with it"), "{summary}");
    let (_, given) = render(
        "given",
        &["--mode", "pbr", "--metallic", "1", "--roughness", "0.4"],
    );
    let (_, other) = render(
        "other",
        &["--mode", "pbr", "--metallic", "0", "--roughness", "0.9"],
    );
    assert_eq!(own, given, "the store's factors are the flags' 1 and 0.4");
    assert_ne!(own, other, "the flags override the store's factors");

    // The truth likewise.
    let truth = |prefix: &str, extra: &[&str]| {
        run_ok(
            oslf("truth")
                .arg(&scene)
                .args([
                    "-m", "pbr", "--spp", "4", "--width", "24", "--height", "18", "-q", "-o",
                ])
                .arg(dir.join(prefix))
                .args(extra),
        );
        read_exr(&dir.join(format!("{prefix}-pbr.exr"))).1
    };
    let own = truth("t-own", &[]);
    assert_eq!(
        own,
        truth("t-given", &["--metallic", "1", "--roughness", "0.4"])
    );
    assert_ne!(
        own,
        truth("t-other", &["--metallic", "0", "--roughness", "0.9"])
    );
    assert!(
        own.iter().any(|p| p[3] == 1.0 && p[0] > 0.0),
        "the object is missing or black"
    );
}
