//! `oslf render` says exactly what fell back and why, and `--strict` turns any fallback into a
//! failure that writes nothing: a budget too small for the frame, a damaged environment cube.

use crate::common;

use common::{oslf, runtime_fixture};

fn render(store: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> (bool, String) {
    let run = oslf("render")
        .arg(store)
        .arg("-o")
        .arg(out)
        .args(["--width", "64", "--height", "48"])
        .args(extra)
        .output()
        .unwrap();
    (
        run.status.success(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

#[test]
fn a_budget_too_small_for_the_frame_is_reported_and_strict_fails() {
    let store = runtime_fixture::store_path();
    let dir = store.parent().unwrap().join("fallback-budget");
    std::fs::create_dir_all(&dir).unwrap();

    // The whole working set fits: an exact image, no warning, also under --strict.
    let exact = dir.join("exact.exr");
    let (ok, e) = render(&store, &exact, &["--strict"]);
    assert!(ok && !e.contains("warning"), "{e}");
    assert!(exact.exists());

    // One slot (the pinned environment cube's) cannot hold the frame's cube maps.
    let small = dir.join("small.exr");
    let (ok, e) = render(&store, &small, &["--cache-slots", "1"]);
    assert!(ok, "{e}");
    assert!(
        e.contains("warning:")
            && e.contains("fell back")
            && e.contains("cannot hold the frame's working set")
            && e.contains("--cache-slots"),
        "{e}"
    );
    assert!(small.exists());

    let strict = dir.join("strict.exr");
    let (ok, e) = render(&store, &strict, &["--cache-slots", "1", "--strict"]);
    assert!(!ok, "--strict must fail");
    assert!(e.contains("degraded") && e.contains("--strict"), "{e}");
    assert!(!strict.exists() && !strict.with_extension("png").exists());
}

#[test]
fn a_damaged_environment_cube_is_named_and_strict_fails() {
    let path = runtime_fixture::store_path();
    let store = oslf_format::Store::open(&path).unwrap();
    let env = store
        .env_cube_index()
        .expect("the fixture has an environment cube");
    let mut bytes = std::fs::read(&path).unwrap();
    for face in 0..6 {
        let e = store.face_entry(env, face).unwrap();
        bytes[e.offset as usize + (e.compressed_size as usize) / 2] ^= 0x5a;
    }
    let dir = path.parent().unwrap().join("fallback-env");
    std::fs::create_dir_all(&dir).unwrap();
    let damaged = dir.join("damaged-env.oslf");
    std::fs::write(&damaged, &bytes).unwrap();

    let (ok, e) = render(&damaged, &dir.join("lenient.exr"), &[]);
    assert!(ok, "{e}");
    assert!(
        e.contains(&format!("the environment cube (cube {env})"))
            && e.contains("cannot be decoded"),
        "{e}"
    );
    assert!(!e.contains("(that sample point fell back)"), "{e}");

    let strict = dir.join("strict.exr");
    let (ok, e) = render(&damaged, &strict, &["--strict"]);
    assert!(!ok && e.contains("the environment cube"), "{e}");
    assert!(!strict.exists());
}

#[test]
fn a_frame_larger_than_memory_is_refused_before_any_work() {
    // 16384² (the largest texture lavapipe allows) needs about 35 GB: more than the CI
    // machine's 24 GB, so the render must stop at once with the flags to change.
    let store = runtime_fixture::store_path();
    let out = store.with_file_name("huge.exr");
    let run = oslf("render")
        .arg(&store)
        .arg("-o")
        .arg(&out)
        .args(["--width", "16384", "--height", "16384"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        e.contains("a 16384x16384 frame needs about") && e.contains("lower --width and --height"),
        "{e}"
    );
    assert!(!out.exists());
}
