//! The `oslf bake` command: a small bake end to end, and bad input.

use crate::common;

use std::os::unix::fs::FileTypeExt;
use std::path::Path;

use common::{oslf, LID_SCENE as SCENE};

#[test]
fn bakes_a_store_with_summary_preview_and_json_report() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
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
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
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
    // The error is located at the bad value's line and column.
    let line = 1 + SCENE
        .lines()
        .position(|l| l == "sample_count = 12")
        .unwrap();
    assert!(
        stderr.contains(&format!("{}:{line}:16", scene.display())),
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
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
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

/// `oslf bake SCENE -o OUT ARGS...` in `dir`, with no preview and no progress bar.
fn bake_in(dir: &std::path::Path, scene_text: &str, args: &[&str]) -> std::process::Output {
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, scene_text).unwrap();
    oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("lid.oslf"))
        .args(["-q", "--preview", "none"])
        .args(args)
        .output()
        .unwrap()
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `placement = "adaptive"` from the CLI: the bake captures its pilot cubes (half the 12
/// points asked, at least 16), counts them on the summary's `time` line and in the JSON
/// report, and places the points asked; the same scene and seed give the same store bytes
/// again. A placement it does not know is a located error naming the three.
#[test]
fn adaptive_placement_captures_pilot_cubes_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let text = format!("{SCENE}placement = \"adaptive\"\n");
    let mut stores = Vec::new();
    for run in 0..2 {
        let report = dir.join(format!("report{run}.json"));
        let out = bake_in(dir, &text, &["--report-json", report.to_str().unwrap()]);
        assert!(out.status.success(), "{}", stderr(&out));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(report["pilot_cubes"], 16, "{report}");
        assert_eq!(report["points_placed"], 12, "{report}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains(" (16 pilot cubes)"), "{stdout}");
        stores.push(std::fs::read(dir.join("lid.oslf")).unwrap());
    }
    assert!(
        stores[0] == stores[1],
        "the same scene and seed gave other bytes"
    );

    let out = bake_in(dir, &format!("{SCENE}placement = \"error\"\n"), &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(
        e.contains("lid.toml:") && e.contains("\"uniform\", \"parallax\" or \"adaptive\""),
        "{e}"
    );
}

/// A partial file whose fixed sections were never completely written (the bake was killed
/// while creating it) holds no cube maps: `--resume` says so in one line and starts over.
#[test]
fn resume_of_a_partial_killed_during_create_starts_over() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let partial = dir.join("lid.oslf.partial");
    for keep in [0u64, 100, 300] {
        let out = bake_in(dir, SCENE, &["--max-cubes", "1"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let len = std::fs::metadata(&partial).unwrap().len();
        assert!(keep < len);
        std::fs::OpenOptions::new()
            .write(true)
            .open(&partial)
            .unwrap()
            .set_len(keep)
            .unwrap();
        let out = bake_in(dir, SCENE, &["--resume"]);
        let err = stderr(&out);
        assert!(out.status.success(), "{err}");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{err}");
        assert!(
            lines[0].starts_with(&format!(
                "{} was never completely created (it has {keep} bytes, less than ",
                partial.display()
            )) && lines[0]
                .ends_with("): it holds no finished cube maps, so the bake starts from scratch"),
            "{err}"
        );
        assert!(!partial.exists());
        let out = oslf("store verify")
            .arg(dir.join("lid.oslf"))
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        std::fs::remove_file(dir.join("lid.oslf")).unwrap();
    }
}

/// A partial file with finished cube maps from other settings is kept, and `--resume` names
/// each setting that differs, both values, and what to do.
#[test]
fn resume_with_other_settings_names_each_setting() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let text = format!(
        "{SCENE}\n[presets.seed9]\nseed = 9\n\n[presets.res4]\ncube_resolution = 4\nseed = 9\n\n[presets.raw]\ndenoise = false\n"
    );
    let out = bake_in(dir, &text, &["--max-cubes", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let partial = dir.join("lid.oslf.partial");
    let before = std::fs::read(&partial).unwrap();
    let hint = "; bake without --resume to start over, or pass the settings it was started with";
    for (preset, differences) in [
        ("seed9", "seed 0 (this bake: 9)"),
        (
            "res4",
            "seed 0 (this bake: 9), cube_resolution 2 (this bake: 4)",
        ),
        // Presets that differ only in how the cubes are filtered (the store records it).
        ("raw", "denoise true (this bake: false)"),
    ] {
        let out = bake_in(dir, &text, &["--resume", "-p", preset]);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert_eq!(
            err.trim_end(),
            format!(
                "error: cannot resume {}: it was started with different settings: {differences}{hint}",
                partial.display()
            )
        );
        assert_eq!(
            std::fs::read(&partial).unwrap(),
            before,
            "the partial file is kept"
        );
    }
    // The settings it was started with continue it.
    let out = bake_in(dir, &text, &["--resume"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("(2 recovered from the interrupted bake)")
    );
}

/// Outputs that cannot be created fail at once, naming the path, before any slow work: no
/// store is written (and no sample maps computed) when only the report or preview is bad.
#[test]
fn unwritable_outputs_fail_before_the_bake() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let run = |args: &[&str]| {
        let out = oslf("bake")
            .arg(&scene)
            .args(["-q"])
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success());
        stderr(&out)
    };
    let err = run(&["-o", "/nonexistent/dir/x.oslf"]);
    assert_eq!(
        err.trim_end(),
        "error: cannot write the store /nonexistent/dir/x.oslf: the directory /nonexistent/dir does not exist"
    );
    let out = dir.join("lid.oslf");
    let o = out.to_str().unwrap();
    let err = run(&["-o", o, "--report-json", "/nonexistent/r.json"]);
    assert_eq!(
        err.trim_end(),
        "error: cannot write the --report-json file /nonexistent/r.json: the directory /nonexistent does not exist"
    );
    let err = run(&["-o", o, "--preview", "/nonexistent/p/preview.png"]);
    assert_eq!(
        err.trim_end(),
        "error: cannot write the preview /nonexistent/p/preview.png: the directory /nonexistent/p does not exist"
    );
    let d = dir.to_str().unwrap();
    let err = run(&["-o", d]);
    assert_eq!(
        err.trim_end(),
        format!("error: --output {d}: exists and is not a regular file (a directory); outputs are written to new or regular files only, and this one is left as it is")
    );
    // A device is not replaced by the store (the rename would replace the device node).
    let err = run(&["-o", "/dev/null"]);
    assert_eq!(
        err.trim_end(),
        "error: --output /dev/null: exists and is not a regular file (a character device); outputs are written to new or regular files only, and this one is left as it is"
    );
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    assert!(!Path::new("/dev/null.partial").exists());
    assert!(!out.exists());
    assert!(!dir.join("lid.oslf.partial").exists());
    assert_eq!(
        std::fs::read_dir(dir).unwrap().count(),
        1,
        "only the scene, no probe files"
    );
}

#[test]
fn preflight_refuses_a_bake_too_slow_for_its_limit_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("slow.toml");
    // 65 536 paths per texel of 200 cube maps of 128² on one thread: weeks by any estimate
    // (the optimistic end is what is checked against the 12 h limit).
    std::fs::write(
        &scene,
        SCENE
            .replace("samples_per_texel = 1", "samples_per_texel = 65536")
            .replace("cube_resolution = 2", "cube_resolution = 128")
            .replace("sample_count = 12", "sample_count = 200"),
    )
    .unwrap();
    let out = dir.join("slow.oslf");
    let run = |extra: &[&str]| {
        oslf("bake")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["-j", "1", "--preview", "none"])
            .args(extra)
            .output()
            .unwrap()
    };
    let r = run(&[]);
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        e.contains("estimate: peak memory")
            && e.contains("the bake would take")
            && e.contains("lower samples_per_texel")
            && e.contains("--max-hours"),
        "{e}"
    );
    assert!(!out.exists() && !dir.join("slow.oslf.partial").exists());
    let r = run(&["--max-hours=-1"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--max-hours -1"));
}

/// examples/can.toml has no `[bake]`: the bake says what it chose and why, in the scene's
/// units with the digits a 66 mm can needs, on stderr and in the JSON report.
#[test]
fn a_scene_without_bake_settings_says_what_it_chose() {
    let (out, report) = bake_example_quickly("can");
    let stderr = String::from_utf8_lossy(&out.stderr);
    for key in [
        "chosen: epsilon = 0.00",
        "chosen: object \"Can\": sample_spacing = 0.00",
        "chosen: placement = \"parallax\": the points crowd where what they see is near",
        "chosen: near_surface = \"lower\": a point that ε brings near another surface",
        "chosen: cube_resolution = 16",
        "chosen: samples_per_texel = 16",
    ] {
        assert!(stderr.contains(key), "no {key:?} in:\n{stderr}");
    }
    // ε of about a millimetre, with two significant digits.
    let eps_line = stderr
        .lines()
        .find(|l| l.starts_with("chosen: epsilon"))
        .unwrap();
    let value: f64 = eps_line["chosen: epsilon = ".len()..]
        .split(':')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((5e-4..5e-3).contains(&value), "{eps_line}");
    let chosen = report["chosen"].as_array().unwrap();
    assert_eq!(chosen.len(), 6, "{chosen:?}");
    assert!(chosen[0].as_str().unwrap().starts_with("epsilon = "));
    // The can stands on the table: the points by its base are lowered, not removed.
    assert!(report["points_lowered"].as_u64().unwrap() > 0, "{report}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(" of them lowered nearer their surface than ε, near another"),
        "{stdout}"
    );
    // The texels without a point lie under the can's base on the table, where no view
    // reaches: counted, not warned about.
    let empty = report["sample_maps"]["empty"].as_u64().unwrap();
    assert!(empty > 0, "{report}");
    assert_eq!(report["coverage"][0]["unseen_empty"], empty, "{report}");
    assert!(!stderr.contains("have no visible sample point"), "{stderr}");
}

/// examples/part.toml: a hard-surface part (flat faces, hard edges, no texture coordinates)
/// with no `[bake]`. Its polished steel asks for 64² cubes; the bake lays out an atlas of its
/// own; its flat bottom lies on the table top, inside the top's slab, where no view reaches:
/// counted, not warned about.
#[test]
fn a_hard_surface_part_resting_flat_bakes_without_bake_settings() {
    let (out, report) = bake_example_quickly("part");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stderr.contains("chosen: cube_resolution = 64"), "{stderr}");
    assert!(stdout.contains("atlas          \"Part\": "), "{stdout}");
    let empty = report["sample_maps"]["empty"].as_u64().unwrap();
    let texels = report["sample_maps"]["texels"].as_u64().unwrap();
    // The bottom: a fifth of the part's area.
    assert!(empty * 10 > texels, "{report}");
    assert_eq!(report["coverage"][0]["unseen_empty"], empty, "{report}");
    assert!(!stderr.contains("have no visible sample point"), "{stderr}");
}

/// Bakes `examples/NAME.toml` as it is, but one cube map only, on the CPU, with its JSON
/// report: the bake's output and the report.
fn bake_example_quickly(name: &str) -> (std::process::Output, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/{name}.toml"));
    let out = oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join(format!("{name}.oslf")))
        .args([
            "--max-cubes",
            "1",
            "--preview",
            "none",
            "--device",
            "cpu",
            "--report-json",
        ])
        .arg(dir.join("report.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    (out, report)
}
