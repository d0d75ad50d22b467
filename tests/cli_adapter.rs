//! The GPU adapter as a user meets it: no stray `error:` lines from layers or backends the
//! program does not use.

use crate::common;

use common::{oslf, runtime_fixture};

#[test]
fn a_headless_render_without_a_desktop_prints_no_stray_errors() {
    let store = runtime_fixture::store_path();
    let out = store.with_file_name("no-desktop.exr");
    let run = oslf("render")
        .arg(&store)
        .arg("-o")
        .arg(&out)
        .args(["--width", "64", "--height", "48"])
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        !stderr.lines().any(|l| l.starts_with("error:")),
        "stray error lines:\n{stderr}"
    );
    assert!(out.exists());
}
