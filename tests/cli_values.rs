//! Values that would make nonsense with exit 0 are refused (flags and scene settings), or, for
//! a bake whose sample maps have empty texels, warned about and refused under `--strict`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{oslf, LID_SCENE};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Bakes the lid scene (`extra` appended to its `[bake]` table) into `dir`; the store's path.
fn bake(dir: &Path, extra: &str, args: &[&str]) -> (PathBuf, Output) {
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, format!("{LID_SCENE}{extra}")).unwrap();
    let store = dir.join("lid.oslf");
    let out = oslf("bake")
        .arg(&scene)
        .args(["-q", "--preview", "none", "-o"])
        .arg(&store)
        .args(args)
        .output()
        .unwrap();
    (store, out)
}

#[test]
fn exposures_fields_of_view_and_thread_counts_that_make_nonsense_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (store, out) = bake(tmp.path(), "", &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let image = tmp.path().join("x.exr");
    let render = |args: &[&str]| {
        let o = oslf("render")
            .arg(&store)
            .args(["--width", "8", "--height", "8", "-o"])
            .arg(&image)
            .args(args)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?} accepted");
        stderr(&o)
    };
    // Beyond 1e-6..=1e6 every pixel is black or white: refused, and said so.
    for e in [
        "NaN", "-1", "0", "inf", "1e30", "3e38", "1e-30", "2e6", "9e-7",
    ] {
        let err = render(&["--exposure", e]);
        assert!(
            err.contains("is not an exposure between 1e-6 and 1e6"),
            "{err}"
        );
    }
    for v in ["1e-30", "0.05", "179.5"] {
        let err = render(&["--vfov", v]);
        assert!(err.contains("must be within 0.1 to 179 degrees"), "{err}");
    }
    assert!(!image.exists());
    let cores = std::thread::available_parallelism().unwrap().get();
    let too_many = (4 * cores + 1).to_string();
    let o = oslf("store convert")
        .arg(&store)
        .arg(tmp.path().join("c.oslf"))
        .args(["--encoding", "bc6h", "-j", &too_many])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains(&format!("--threads {too_many} is more than {}", 4 * cores)),
        "{err}"
    );
    let o = oslf("bake")
        .arg(tmp.path().join("lid.toml"))
        .args(["-q", "-j", "100000", "-o"])
        .arg(tmp.path().join("other.oslf"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--threads 100000 is more than"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_epsilon_larger_than_the_object_is_refused_where_it_is_set() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = LID_SCENE.replace("epsilon = 0.1\n", "epsilon = 1e30\n");
    assert_ne!(scene, LID_SCENE);
    let dir = tmp.path();
    std::fs::write(dir.join("lid.toml"), &scene).unwrap();
    let store = dir.join("lid.oslf");
    let out = oslf("bake")
        .arg(dir.join("lid.toml"))
        .args(["-q", "--preview", "none", "-o"])
        .arg(&store)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("lid.toml:") && err.contains("is too large for object"),
        "{err}"
    );
    assert!(!store.exists());
}

#[test]
fn empty_sample_map_texels_are_warned_about_and_refused_under_strict() {
    let tmp = tempfile::tempdir().unwrap();
    // One sample point: most texels see none.
    let scene = LID_SCENE.replace("sample_count = 12\n", "sample_count = 1\n");
    assert_ne!(scene, LID_SCENE);
    let dir = tmp.path();
    std::fs::write(dir.join("one.toml"), &scene).unwrap();
    let run = |strict: bool| {
        let mut c = oslf("bake");
        c.arg(dir.join("one.toml"))
            .args(["-q", "--preview", "none", "-o"])
            .arg(dir.join("one.oslf"));
        if strict {
            c.arg("--strict");
        }
        c.output().unwrap()
    };
    let o = run(true);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("have no visible sample point") && err.contains("(--strict)"),
        "{err}"
    );
    assert!(!dir.join("one.oslf").exists() && !dir.join("one.oslf.partial").exists());
    let o = run(false);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: ") && stderr(&o).contains("have no visible sample point"),
        "{}",
        stderr(&o)
    );
    // A scene whose sample maps are full bakes under --strict, without the warning.
    let (_, o) = bake(dir, "", &["--strict"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}
