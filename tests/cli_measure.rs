//! The measurement commands end to end on a toy scene (lavapipe in CI; GPU tests fail, never
//! skip, without an adapter): `oslf tables` and `oslf sweep` run, their CSV, JSON and Markdown
//! agree, and bad input is a clear error.

use crate::common;

use common::oslf;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use oslf_bake::bake::{bake, BakeOptions};
use oslf_scene::scene::Scene;

/// The teapot test scene (tests/fixtures/teapot.toml) at toy resolutions, and a preset with
/// finer cube maps.
const SCENE: &str = concat!(
    include_str!("fixtures/teapot.toml"),
    r#"
[bake]
epsilon = 0.1
sample_count = 80
cube_resolution = 8
sample_map_resolution = 16
samples_per_texel = 1
bounces = 1
seed = 3

[presets.fine]
cube_resolution = 16
"#
);

struct Fixture {
    dir: PathBuf,
    scene: PathBuf,
    coarse: PathBuf,
    fine: PathBuf,
}

/// The scene and two stores (8² and 16² cube maps), baked once.
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        // Under Cargo's target tmp, replaced by the next run: the stores outlive the tests
        // that share them (statics are never dropped).
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_measure");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, SCENE).unwrap();
        let mut out = Vec::new();
        for (preset, name) in [(None, "coarse.oslf"), (Some("fine"), "fine.oslf")] {
            let s = Scene::load(&scene, preset).unwrap();
            let output = dir.join(name);
            bake(
                &s,
                &BakeOptions {
                    output: output.clone(),
                    resume: false,
                    progress: None,
                    cube_limit: None,
                    refuse_empty_texels: false,
                    device: None,
                },
            )
            .unwrap();
            out.push(output);
        }
        Fixture {
            dir,
            scene,
            fine: out.pop().unwrap(),
            coarse: out.pop().unwrap(),
        }
    })
}

fn run(sub: &str, args: &[&str]) -> (bool, String, String) {
    let o = oslf(sub).args(args).output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn tables_reproduce_the_thesis_layout_with_consistent_outputs() {
    let f = fixture();
    let out = f.dir.join("tables");
    let (ok, stdout, stderr) = run(
        "tables",
        &[
            s(&f.scene),
            "--store",
            s(&f.fine),
            "--store",
            s(&f.coarse),
            "--spp",
            "4",
            "--width",
            "96",
            "--height",
            "64",
            "--glossy-m",
            "4,8",
            "--lobes",
            "10:10,10:300",
            "--frames",
            "1",
            "-o",
            s(&out),
            "-q",
        ],
    );
    assert!(ok, "{stderr}");
    for t in ["Table 6.1", "Table 6.2", "Ashikhmin–Shirley"] {
        assert!(stdout.contains(t), "{stdout}");
    }
    let csv = std::fs::read_to_string(out.join("tables.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Per store: 1 recon + 2 baselines + 11 blends, plain and depth-corrected; AS: 2 lobes × 2 M
    // × 6 methods on the finer store.
    assert_eq!(rows.len(), 2 * 25 + 24, "{csv}");
    for method in ["Parallax", "B^n N=4 depth"] {
        assert_eq!(
            rows.iter().filter(|r| r[3] == method).count(),
            2,
            "{method}"
        );
    }
    assert_eq!(rows.iter().filter(|r| r[0] == "6.1").count(), 2);
    assert_eq!(
        rows.iter().filter(|r| r[0] == "AS" && r[2] == "16").count(),
        24
    );
    for r in &rows {
        let l: f64 = r[13].parse().unwrap();
        let ms: f64 = r[20].parse().unwrap();
        assert!(l.is_finite() && l >= 0.0 && ms > 0.0, "{r:?}");
        assert!(
            r[12].parse::<u64>().unwrap() > 100,
            "too few pixels compared: {r:?}"
        );
    }
    // The environment map's ratio to itself is 1, and JSON holds the same records.
    assert!(stdout.contains("EnvMap") && stdout.contains("1.000"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tables.json")).unwrap()).unwrap();
    let recs = json.as_array().unwrap();
    assert_eq!(recs.len(), rows.len());
    let l0 = recs[0]["judgement"]["metrics"]["rmse_lab"][0]
        .as_f64()
        .unwrap();
    assert!((l0 - rows[0][13].parse::<f64>().unwrap()).abs() < 1e-4);
    assert!(std::fs::read_to_string(out.join("tables.md"))
        .unwrap()
        .contains("| method |"));
    assert!(out.join("truth-mirror.exr").exists() && out.join("truth-glossy-10-300.exr").exists());
}

#[test]
fn sweep_writes_rows_front_and_plot() {
    let f = fixture();
    let out = f.dir.join("sweep");
    let args = [
        s(&f.scene),
        "--vary",
        "cube_resolution=4",
        "--vary",
        "device=gpu",
        "--vary",
        "blend=distance,envmap",
        "--spp",
        "4",
        "--width",
        "96",
        "--height",
        "64",
        "--frames",
        "1",
        "-o",
        s(&out),
        "-q",
    ];
    let (ok, stdout, stderr) = run("sweep", &args);
    assert!(ok, "{stderr}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    // 3 stores × 3 runtime settings.
    assert_eq!(lines.len(), 1 + 9, "{csv}");
    assert!(lines[1].starts_with("defaults,"));
    assert!(csv.contains("\"cube_resolution=4, blend=envmap\""));
    // Each row names what captured its store: the CPU by default (auto on lavapipe), the
    // GPU where the variation asks for it.
    for l in &lines[1..] {
        let on_gpu = l.contains("device=gpu");
        assert_eq!(l.contains(",\"GPU "), on_gpu, "{l}");
        assert_eq!(l.contains(",CPU ("), !on_gpu, "{l}");
    }
    // The two Pareto fronts (frame time, bake time, the last two columns) hold a row each.
    for back in [2, 1] {
        let column: Vec<&str> = lines[1..]
            .iter()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                f[f.len() - back]
            })
            .collect();
        assert!(
            column.iter().all(|c| ["yes", "no", "–"].contains(c)),
            "{csv}"
        );
        assert!(column.contains(&"yes"), "{csv}");
    }
    assert!(stdout.contains("Sensitivity") && stdout.contains("Pareto front"));
    let png = image::open(out.join("tradeoff.png")).unwrap();
    assert_eq!((png.width(), png.height()), (1500, 640));
    assert!(std::fs::read_to_string(out.join("tradeoff.svg"))
        .unwrap()
        .contains("Pareto front"));
    // A second run reuses the stores (same settings) and gives the same errors.
    let (ok, _, stderr) = run("sweep", &args);
    assert!(ok, "{stderr}");
    let csv2 = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    // RMSE L*, counted from the end (labels may hold quoted commas): nine columns follow it.
    let err = |c: &str| -> Vec<String> {
        c.lines()
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                f[f.len() - 10].to_string()
            })
            .collect()
    };
    assert_eq!(err(&csv), err(&csv2));
}

#[test]
fn bad_input_is_a_clear_error() {
    let f = fixture();
    let tables = "tables";
    let sweep = "sweep";
    // A store from another scene.
    let other = f.dir.join("other.toml");
    std::fs::write(&other, SCENE.replace("seed = 3", "seed = 4")).unwrap();
    let (ok, _, e) = run(tables, &[s(&other), "--store", s(&f.coarse), "-q"]);
    assert!(!ok && e.contains("was not baked from"), "{e}");
    let (ok, _, e) = run(sweep, &[s(&f.scene), "--device", "tpu", "-q"]);
    assert!(!ok && e.contains("unknown device \"tpu\""), "{e}");
    let (ok, _, e) = run(sweep, &[s(&f.scene), "--vary", "colour=1", "-q"]);
    assert!(!ok && e.contains("unknown key \"colour\""), "{e}");
    let (ok, _, e) = run(sweep, &[s(&f.scene), "--vary", "epsilon=-1", "-q"]);
    assert!(!ok && e.contains("epsilon"), "{e}");
    // An ε the bake cannot honour for this object is refused before anything is baked.
    let (ok, _, e) = run(
        sweep,
        &[
            s(&f.scene),
            "--vary",
            "epsilon=0.0001",
            "-o",
            s(&f.dir.join("bad")),
            "-q",
        ],
    );
    assert!(!ok && e.contains("too small"), "{e}");
    assert!(!f.dir.join("bad/stores/defaults.oslf").exists());
    let (ok, _, e) = run(tables, &[s(&f.scene), "--store", "/nonexistent.oslf", "-q"]);
    assert!(!ok && e.contains("/nonexistent.oslf"), "{e}");
}
