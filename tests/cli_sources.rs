//! `oslf render`'s reflection sources and accuracy switches: `--source oslf|env|parallax`,
//! `--proxy-box`, `--no-depth`, `--glossy-filter` (the pbr mode's split-sum baseline too); and
//! what a store without a distance channel gets (a plain warning, `--strict` fails, parallax
//! needs a given box).

use crate::common;

use std::path::{Path, PathBuf};

use common::{oslf, read_exr, runtime_fixture};

/// Renders `store` at 64×48 into `dir/name.exr` with `extra` flags: (success, stderr, path).
fn render(store: &Path, dir: &Path, name: &str, extra: &[&str]) -> (bool, String, PathBuf) {
    let out = dir.join(format!("{name}.exr"));
    let run = oslf("render")
        .arg(store)
        .arg("-o")
        .arg(&out)
        .args(["--width", "64", "--height", "48", "--background", "none"])
        .args(extra)
        .output()
        .unwrap();
    (
        run.status.success(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
        out,
    )
}

#[test]
fn every_source_and_switch_renders_and_changes_the_image() {
    let store = runtime_fixture::store_path();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut images = Vec::new();
    for (name, flags) in [
        ("oslf", vec!["--mode", "mirror"]),
        ("plain", vec!["--mode", "mirror", "--no-depth"]),
        ("env", vec!["--mode", "mirror", "--source", "env"]),
        ("parallax", vec!["--mode", "mirror", "--source", "parallax"]),
        (
            "parallax-box",
            vec![
                "--mode",
                "mirror",
                "--source",
                "parallax",
                "--proxy-box",
                "-6,-6,-1,6,6,8",
            ],
        ),
        ("glossy-mip", vec!["--mode", "glossy", "-M", "4"]),
        (
            "glossy-point",
            vec!["--mode", "glossy", "-M", "4", "--glossy-filter", "point"],
        ),
        (
            "pbr-env",
            vec![
                "--mode",
                "pbr",
                "--roughness",
                "0.4",
                "--source",
                "env",
                "-M",
                "16",
            ],
        ),
        (
            "pbr-split-sum",
            vec![
                "--mode",
                "pbr",
                "--roughness",
                "0.4",
                "--source",
                "env",
                "--glossy-filter",
                "split-sum",
            ],
        ),
    ] {
        let (ok, e, out) = render(&store, dir, name, &flags);
        assert!(ok, "{name}: {e}");
        assert!(!e.contains("warning"), "{name}: {e}");
        let (_, px) = read_exr(&out);
        assert!(px.iter().flatten().all(|v| v.is_finite()), "{name}");
        images.push((name, px));
    }
    let differ = |a: usize, b: usize| {
        let (na, pa) = &images[a];
        let (nb, pb) = &images[b];
        assert!(pa != pb, "{na} and {nb} render the same image");
    };
    differ(0, 1); // depth correction
    differ(2, 3); // parallax correction
    differ(3, 4); // the given box is used
    differ(5, 6); // filtered importance sampling
    differ(7, 8); // the split-sum baseline is not the Monte Carlo one
}

#[test]
fn bad_source_flags_are_named() {
    let store = runtime_fixture::store_path();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for (flags, expect) in [
        (vec!["--source", "probe"], "unknown source \"probe\""),
        (vec!["--proxy-box", "1,2,3"], "is not a box"),
        (vec!["--proxy-box", "1,2,3,0,5,6"], "min < max"),
        (vec!["--glossy-filter", "box"], "unknown glossy filter"),
        (
            vec!["--mode", "pbr", "--glossy-filter", "split-sum"],
            "needs mode pbr and source env or parallax",
        ),
        (
            vec![
                "--mode",
                "glossy",
                "--source",
                "env",
                "--glossy-filter",
                "split-sum",
            ],
            "needs mode pbr and source env or parallax",
        ),
        (
            vec!["--envmap", "--source", "parallax"],
            "cannot be used with",
        ),
    ] {
        let (ok, e, _) = render(&store, dir, "bad", &flags);
        assert!(!ok, "{flags:?} must fail");
        assert!(e.contains(expect), "{flags:?}: {e}");
    }
}

#[test]
fn a_store_without_distances_says_so_and_parallax_needs_a_box() {
    let store = runtime_fixture::store_path_without_distances();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (ok, e, out) = render(&store, dir, "default", &["--mode", "mirror"]);
    assert!(ok, "{e}");
    assert!(
        e.contains("warning:") && e.contains("no distance channel") && e.contains("--no-depth"),
        "{e}"
    );
    assert!(out.exists());
    let (ok, e, out) = render(&store, dir, "strict", &["--mode", "mirror", "--strict"]);
    assert!(
        !ok && e.contains("--strict") && e.contains("no distance channel"),
        "{e}"
    );
    assert!(!out.exists());
    let (ok, e, _) = render(
        &store,
        dir,
        "plain",
        &["--mode", "mirror", "--no-depth", "--strict"],
    );
    assert!(ok && !e.contains("warning"), "{e}");
    let (ok, e, _) = render(&store, dir, "parallax", &["--source", "parallax"]);
    assert!(
        !ok && e.contains("no distance channel") && e.contains("--proxy-box"),
        "{e}"
    );
    let (ok, e, _) = render(
        &store,
        dir,
        "parallax-box",
        &[
            "--source",
            "parallax",
            "--proxy-box",
            "-6,-6,-1,6,6,8",
            "--strict",
        ],
    );
    assert!(ok, "{e}");
}
