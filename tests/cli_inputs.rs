//! Inputs without bounds and their messages, as the user sees them: files that are
//! not regular files are refused at once, naming what they are, and an error's cause prints
//! once.

use crate::common;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{oslf, LID_SCENE};

/// Runs `command`, killing it (and failing the test) if it takes longer than 60 s: a read
/// blocked on a FIFO or filling memory from a device must fail the test, not hang it.
fn run_within_deadline(mut command: Command) -> Output {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("{command:?} ran for more than 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// The stderr of a command that must fail.
fn failure(command: Command) -> String {
    let out = run_within_deadline(command);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "succeeded: {stderr}");
    stderr
}

fn bake(scene: &Path, dir: &Path) -> Command {
    let mut c = oslf("bake");
    c.arg(scene).arg("-o").arg(dir.join("out.oslf")).arg("-q");
    c
}

#[test]
fn a_missing_file_prints_its_cause_once() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let os = "No such file or directory (os error 2)";
    let missing_store = dir.join("missing.oslf");
    let missing_exr = dir.join("missing.exr");
    let mut commands = vec![bake(&dir.join("missing.toml"), dir)];
    for sub in ["store info", "store verify"] {
        let mut c = oslf(sub);
        c.arg(&missing_store);
        commands.push(c);
    }
    let mut c = oslf("compare");
    c.arg(&missing_exr).arg(&missing_exr);
    commands.push(c);
    for command in commands {
        let what = format!("{command:?}");
        let e = failure(command);
        assert_eq!(e.matches(os).count(), 1, "{what}: {e}");
        assert!(e.contains("missing."), "{what}: {e}");
    }
}

#[test]
fn devices_fifos_and_directories_are_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // The scene itself: /dev/zero used to be read until memory ran out, a FIFO blocked.
    let e = failure(bake(Path::new("/dev/zero"), dir));
    assert!(
        e.contains("not a regular file: /dev/zero (a character device)"),
        "{e}"
    );
    let fifo = dir.join("scene.toml");
    let status = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(status.success());
    let e = failure(bake(&fifo, dir));
    assert!(e.contains("scene.toml (a FIFO)"), "{e}");
    // A mesh path that is a directory: named as such, not "file not found".
    std::fs::create_dir(dir.join("mesh.obj")).unwrap();
    let scene = dir.join("lid.toml");
    std::fs::write(
        &scene,
        format!(
            "{LID_SCENE}\n[[mesh]]\npath = \"mesh.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"
        ),
    )
    .unwrap();
    let e = failure(bake(&scene, dir));
    assert!(e.contains("lid.toml:"), "{e}");
    assert!(e.contains("mesh.obj (a directory)"), "{e}");
    assert!(!e.contains("not found"), "{e}");
}
